"""The exudyn model's budgets: the wall clock of a run (``max_wall_s``, read in its pre-step
function), the number of steps a run without one may plan, and the memory of the steps it
records (exudyn stores every step of the sensors the outputs need).

* Before any work (``check_plan``): a run without a wall-clock budget is refused when its
  t_end / step exceeds ``MAX_STEPS_UNBOUNDED`` or its recorded steps would exceed the memory
  limit of ``rodval.core.resources`` (``RODVAL_MAX_MEMORY_GB``). With a wall-clock budget the
  run is bounded by the clock and allowed.
* During the run (``RunBudget.pre_step``, before every step): the clock, started when the run
  starts (its set-up counts), and the count of recorded steps against the memory bound. Either
  stops exudyn's solver after the coming step (the pre-step function returns False), keeping
  every step computed; the run then ends with the wall-clock status (``STATUS_WALL``, the
  message of ``IntegratorSettings.budget_message``) or as ``STATUS_FAILED`` at the memory
  bound.
* Between the attempts of ``step = "auto"`` (``refinement_refusal``): a further attempt at a
  smaller step is refused before it starts when it would not fit the memory, the steps of a
  run without a wall-clock budget, or what the attempts before it left of the wall-clock
  budget, which covers them all (every attempt's ``RunBudget`` starts from the run's start).
"""

from __future__ import annotations

import math
import time

from rodval.core.resources import ENV_LIMIT, memory_limit_bytes
from rodval.core.settings import IntegratorSettings
from rodval.core.status import STATUS_FAILED, STATUS_WALL

#: Steps (t_end / step) a run without a wall-clock budget may plan: 1e7. A step of the paper
#: chain (8 rods, 2 elements each) costs 100-800 us on the 2-core machine (the guard's check
#: included; more when it is shared), a one-rod chain about half of that, so 1e7 steps run for
#: 15 min to 2 h: beyond that a run is more likely a mistyped t_end or step than meant
#: (t_end = 1e6 s at the default step is 5e9 steps: days). A longer run gives a wall-clock
#: budget (max_wall_s, --max-wall S) and is bounded by it.
MAX_STEPS_UNBOUNDED = 10**7
#: exudyn's largest step count: it converts numberOfSteps to a 32-bit int (5e9 steps ran with
#: a negative step, time going backwards), so no run is given more.
EXUDYN_MAX_STEPS = 2**31 - 1
#: Bytes per recorded double, over the run: exudyn's store of the sensors (1.4x the raw
#: doubles: it grows by blocks), their copy into numpy and the model's records cut to the
#: finite steps; measured 3.1 x 8 bytes per double at the peak of a run (paper chain, 4,000 vs
#: 40,000 steps, with and without the energy audit), rounded up.
BYTES_PER_RECORDED_DOUBLE = 8 * 4


def planned_steps(t_end: float, step: float) -> int:
    """The run's equal steps: ceil(t_end / step) (t_end, step in s), at least 1."""
    return max(1, math.ceil(t_end / step - 1e-9))


def record_bytes(doubles_per_step: int) -> int:
    """Memory (bytes) one recorded step takes over the run, for ``doubles_per_step`` doubles
    stored by the sensors at each step (``BYTES_PER_RECORDED_DOUBLE`` each)."""
    return BYTES_PER_RECORDED_DOUBLE * int(doubles_per_step)


def memory_bound_steps(doubles_per_step: int) -> float:
    """The recorded steps the memory limit allows (inf when the limit is off)."""
    return memory_limit_bytes() / record_bytes(doubles_per_step)


def check_plan(t_end: float, step: float, doubles_per_step: int, max_wall_s: float) -> int:
    """The planned steps of a run over ``t_end`` (s) at ``step`` (s), or ValueError (one line,
    before any work) when the run has no wall-clock budget (``max_wall_s`` = inf) and plans
    more than ``MAX_STEPS_UNBOUNDED`` steps or more than its records fit in memory."""
    steps = planned_steps(t_end, step)
    if math.isfinite(max_wall_s):
        return steps
    if steps > MAX_STEPS_UNBOUNDED:
        raise ValueError(
            f"exudyn: t_end / step = {t_end:g} s / {step:g} s = {steps:.3g} steps, more than "
            f"the {MAX_STEPS_UNBOUNDED:.0e} a run without a wall-clock budget may take; give "
            "a wall-clock budget (max_wall_s, CLI --max-wall S), a larger step, or a shorter "
            "t_end"
        )
    per_step = record_bytes(doubles_per_step)
    if steps > memory_bound_steps(doubles_per_step):
        raise ValueError(
            f"exudyn: t_end / step = {steps} steps recorded at {per_step} bytes each (the "
            f"sensors' {doubles_per_step} doubles a step and their copies) would need about "
            f"{steps * per_step / 1e9:.3g} GB of memory, more than the limit of "
            f"{memory_limit_bytes() / 1e9:.3g} GB ({ENV_LIMIT}); give a larger step or a "
            f"shorter t_end, a wall-clock budget (max_wall_s, CLI --max-wall S: the run stops "
            f"at the memory bound), or raise {ENV_LIMIT}"
        )
    return steps


def refinement_refusal(
    t_end: float,
    step: float,
    doubles_per_step: int,
    max_wall_s: float,
    left_s: float,
    predicted_s: float,
) -> str | None:
    """Why a further attempt of ``step = "auto"`` at ``step`` (s) over ``t_end`` (s) would not
    fit the run's budgets, decided before it starts (None: it fits): more recorded steps than
    the memory limit allows, or, without a wall-clock budget (``max_wall_s`` = inf), more
    than ``MAX_STEPS_UNBOUNDED`` steps (``check_plan``'s message); with one, a predicted wall
    time ``predicted_s`` (s) beyond the ``left_s`` (s) the attempts before it left of it."""
    steps = planned_steps(t_end, step)
    if steps > memory_bound_steps(doubles_per_step):
        return (
            f"its {steps} recorded steps would need about "
            f"{steps * record_bytes(doubles_per_step) / 1e9:.3g} GB of memory, more than the "
            f"limit of {memory_limit_bytes() / 1e9:.3g} GB ({ENV_LIMIT})"
        )
    if not math.isfinite(max_wall_s):
        try:
            check_plan(t_end, step, doubles_per_step, max_wall_s)
        except ValueError as exc:
            return str(exc).removeprefix("exudyn: ")
        return None
    if predicted_s > left_s:
        return (
            f"it would take about {predicted_s:.3g} s and the wall-clock budget (max_wall_s "
            f"{max_wall_s:g} s, every attempt's together) leaves {max(left_s, 0.0):.3g} s"
        )
    return None


class RunBudget:
    """The budgets of one run, checked before every step (exudyn's pre-step function): the
    wall clock from ``start`` (``time.perf_counter()`` s, the start of the run) to
    ``max_wall_s`` (inf: none), and the recorded steps against the memory bound
    (``memory_bound_steps``) and ``EXUDYN_MAX_STEPS``. ``stop`` is then "max_wall_s" or
    "memory"; the solver completes the coming step and stops."""

    def __init__(self, settings: IntegratorSettings, start: float, doubles_per_step: int):
        self.settings = settings
        self.deadline = start + settings.max_wall_s
        self.doubles_per_step = int(doubles_per_step)
        self.max_steps = min(memory_bound_steps(doubles_per_step), EXUDYN_MAX_STEPS - 1)
        self.steps = 0
        self.stop: str | None = None

    def pre_step(self) -> bool:
        """Before a step: whether it may run (False stops the run after it). Costs a clock
        read (~0.1 us) against the step's 100 us or more."""
        if self.stop is not None:
            return False
        self.steps += 1
        if self.steps > self.max_steps:
            self.stop = "memory"
        elif time.perf_counter() > self.deadline:
            self.stop = "max_wall_s"
        return self.stop is None

    def outcome(self, t_reached: float) -> tuple[int, str] | None:
        """(status, message) of a run this budget stopped at ``t_reached`` (s), else None."""
        if self.stop == "max_wall_s":
            return STATUS_WALL, self.settings.budget_message("max_wall_s", t_reached)
        if self.stop == "memory":
            return STATUS_FAILED, self._memory_message(t_reached)
        return None

    def _memory_message(self, t: float) -> str:
        per_step = record_bytes(self.doubles_per_step)
        if self.max_steps >= EXUDYN_MAX_STEPS - 1:
            return f"exudyn's largest run of {EXUDYN_MAX_STEPS} steps reached (t = {t:.6g} s)"
        return (
            f"memory bound reached: {int(self.max_steps)} steps recorded at {per_step} bytes "
            f"each, the limit of {memory_limit_bytes() / 1e9:.3g} GB ({ENV_LIMIT}) "
            f"(t = {t:.6g} s); give a larger step or a shorter t_end, or raise {ENV_LIMIT}"
        )
