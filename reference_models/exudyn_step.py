"""The exudyn model's ``step = "auto"`` (its default): the fixed step chosen by what the run
needs, by attempts.

1. **A-priori step** (``a_priori_step``): the shortest lock window the scene's latches can
   open (``rodval.mechanics.lock_window.lock_window`` of each armed latch with only the latches
   held from the start held: the smallest locked segment, so the shortest window; a later
   lock's segment is longer and so is its window) over ``MIN_WINDOW_STEPS`` = 20 steps,
   rounded down to two significant digits, capped by ``STEP_CAP_S`` = 2e-4 s (the fixed
   default before ``"auto"``: converged on the paper's chain, docs/reference_model.md).
2. **Attempt** at that step (a fixed-step run, exactly as a float ``step`` runs), then
   **judge** it (``judge``): every lock window must hold at least ``MIN_WINDOW_STEPS`` steps
   (the records' ``window_steps``), the energy residual must be within the model's bound
   (``rodval.core.validity.ENERGY_RESIDUAL_BOUND``, where the run is audited: the scene asks
   for "energy"), and no rod may turn by more than ``max_rotation_per_step`` in one step (a run
   the guard stopped as under-resolved).
3. **Refine** (``next_step``): a broken check halves the step (a lock window or the rotation
   by as many halvings as its measured shortfall needs at once), at most
   ``MAX_REFINEMENTS`` times in all (down to the a-priori step / 16), each further attempt
   refused before it starts when it would not fit the budgets
   (``exudyn_budget.refinement_refusal``: memory, the steps of a run without a wall-clock
   budget, what the attempts before it left of ``max_wall_s``, which covers them all).
   Refining stops, saying why, when the run ended for a reason a smaller step does not
   address (divergence, blow-up, an error, the wall clock) or when the energy residual did
   not fall by ``ENERGY_MIN_FALL`` over a halving (the residual is then the elements', not the
   step's: the fix is more elements).

The last attempt is the run returned; its settings record ``step_auto`` (``AutoStep.record``:
the a-priori step and why, every attempt's step, fewest lock-window steps, energy residual,
status and wall time, the step chosen, whether it met every check, and the note), and the
note goes into ``SolverStats.notes``: why the final step was chosen, or that no step within
the limits met the checks (never silently).
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rodval.core.scene import Scene
from rodval.core.status import STATUS_FAILED, STATUS_SUCCESS
from rodval.core.trajectory import Trajectory
from rodval.mechanics.lock_window import MIN_WINDOW_STEPS, lock_window

#: The option value that chooses the step by attempts.
AUTO = "auto"
#: The largest fixed step accepted (s).
MAX_STEP_S = 0.1
#: The a-priori step's cap (s): the fixed default before ``"auto"``, converged on the paper's
#: chain (2e-4 -> 5e-5 s moves phi by 1.4e-5 rad; docs/reference_model.md).
STEP_CAP_S = 2e-4
#: Halvings ``"auto"`` may make below the a-priori step (its smallest step is the a-priori
#: step / 2**MAX_REFINEMENTS = / 16); the attempts together cost at most 31x the first.
MAX_REFINEMENTS = 4
#: The factor by which the energy residual must fall over a halving for the step to count as
#: its cause: generalized-alpha's numerical dissipation falls by 2 to 4 over a halving
#: (first to second order; 4 elements on studies/deployment.toml: 0.0128 -> 0.0056, 2.3x),
#: while at 2 elements there the residual is the elements' (0.231 -> 0.233 at 2e-4 -> 1e-4 s).
ENERGY_MIN_FALL = 1.2
#: The fix of an energy balance the step does not close (``next_step``).
ELEMENTS_FIX = "more elements (exudyn option elements; the residual did not fall with the step)"


def check_step(step: Any) -> float | str:
    """``step`` as ``"auto"`` or a float in (0, ``MAX_STEP_S``] s; ValueError naming ``step``
    and the allowed values otherwise (bools, other text, non-finite numbers)."""
    if isinstance(step, str) and step == AUTO:
        return AUTO
    value = float(step) if isinstance(step, numbers.Real) and not isinstance(step, bool) else None
    if value is None or not math.isfinite(value) or not 0 < value <= MAX_STEP_S:
        raise ValueError(
            f'step must be "{AUTO}" or a number in (0, {MAX_STEP_S:g}] s, got {step!r}'
        )
    return value


def _floor2(x: float) -> float:
    """``x`` > 0 rounded down to two significant digits (a step written as it ran)."""
    scale = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.floor(x / scale * (1 + 1e-12)) * scale


def a_priori_step(scene: Scene, cap: float = STEP_CAP_S) -> tuple[float, str]:
    """(step in s, why): the shortest lock window of the scene's armed latches (each with the
    latches held from the start held) over ``MIN_WINDOW_STEPS``, rounded down to two
    significant digits, at most ``cap`` (s), and at most t_end."""
    held = [latch.hinge for latch in scene.latches if latch.held]
    windows = [lock_window(scene.chain, latch, held) for latch in scene.latches if not latch.held]
    why = f"the cap {cap:g} s"
    step = cap
    if windows:
        shortest = min(windows)
        # strictly below w / 20, so that the run's step (t_end over whole steps) leaves no
        # window at 19.999... steps
        resolved = _floor2(shortest / MIN_WINDOW_STEPS * (1 - 1e-9))
        if resolved < cap:
            step = resolved
            why = (
                f"the shortest lock window, {shortest:.3g} s, over {MIN_WINDOW_STEPS} steps "
                "(rounded down)"
            )
        else:
            why += (
                f"; the shortest lock window, {shortest:.3g} s, holds "
                f"{shortest / cap:.3g} steps of it"
            )
    else:
        why += " (no lock windows)"
    if step > scene.t_end:
        step, why = scene.t_end, "the horizon t_end (shorter than " + why + ")"
    return step, why


@dataclass
class Attempt:
    """One fixed-step run of ``"auto"``, judged: ``step`` (s, as requested), ``step_used``
    (s, t_end / its equal steps), how it ended, its fewest lock-window steps (None without
    lock windows), energy residual (None where not audited), largest rotation per step
    (rad), wall time from build to observation (s), the broken checks (``needs``) and the
    factor by which the step must fall at least to meet them (1: none broken); whether the
    guard stopped it as under-resolved (a rod turned too far in a step)."""

    step: float
    step_used: float | None
    status: int
    message: str
    t_reached: float
    window_steps_min: float | None
    energy_residual: float | None
    rotation_seen: float | None
    wall_s: float
    needs: list[str] = field(default_factory=list)
    factor: float = 1.0
    under_resolved: bool = False

    @property
    def stopped(self) -> bool:
        """The run ended for a reason a smaller step does not address (not finished, and not
        stopped by the rotation-per-step bound)."""
        return self.status != STATUS_SUCCESS and not self.under_resolved

    def as_dict(self) -> dict[str, Any]:
        return {
            "step": self.step,
            "step_used": self.step_used,
            "status": int(self.status),
            "t_reached": self.t_reached,
            "window_steps_min": self.window_steps_min,
            "energy_residual": self.energy_residual,
            "max_rotation_per_step_seen": self.rotation_seen,
            "wall_s": self.wall_s,
            "needs": list(self.needs),
        }


def judge(
    step: float, trajectory: Trajectory, energy_bound: float, max_rotation: float, wall_s: float
) -> Attempt:
    """The attempt at ``step`` (s) that gave ``trajectory``: its figures and the checks
    ``"auto"`` holds it to (see the module docstring), with ``energy_bound`` (relative) and
    ``max_rotation`` (rad per step) the model's."""
    stats, settings = trajectory.stats, trajectory.settings
    windows = [
        float(ev["window_steps"])
        for ev in trajectory.events
        if isinstance(ev.get("window_steps"), (int, float))
    ]
    seen = settings.get("max_rotation_per_step_seen")
    attempt = Attempt(
        step=step,
        step_used=settings.get("step_used"),
        status=int(stats.status),
        message=stats.message,
        t_reached=float(stats.t_reached),
        window_steps_min=min(windows) if windows else None,
        energy_residual=stats.energy_residual,
        rotation_seen=seen,
        wall_s=wall_s,
    )
    factors = [1.0]
    fewest = attempt.window_steps_min
    if fewest is not None and fewest < MIN_WINDOW_STEPS:
        attempt.needs.append(f"a lock window holds {fewest:.3g} steps (< {MIN_WINDOW_STEPS})")
        factors.append(MIN_WINDOW_STEPS / max(fewest, 1e-300))
    if stats.status == STATUS_FAILED and seen is not None and seen > max_rotation:
        attempt.needs.append(f"a rod turned {seen:.3g} rad in one step (> {max_rotation:g})")
        attempt.under_resolved = True
        factors.append(seen / max_rotation)
    residual = stats.energy_residual
    if residual is not None and not residual <= energy_bound:
        attempt.needs.append(f"the energy residual {residual:.3g} > {energy_bound:g}")
        factors.append(2.0)
    attempt.factor = max(factors)
    return attempt


def next_step(attempts: list[Attempt], smallest: float) -> tuple[float | None, str, str]:
    """(step, why, fix): the step (s) of the next attempt after ``attempts`` (the last broke
    a check), or None and why refining stops: the last run ended for another reason, its
    energy residual did not fall by ``ENERGY_MIN_FALL`` over the last halving (``fix``:
    ``ELEMENTS_FIX``, else ""), or the step its shortfall needs is below ``smallest`` (s)."""
    last = attempts[-1]
    if last.stopped:
        return (
            None,
            f"its run ended before t_end: {last.message} (a smaller step is not tried)",
            "",
        )
    before = attempts[-2] if len(attempts) > 1 else None
    if (
        before is not None
        and last.energy_residual is not None
        and before.energy_residual is not None
        and last.energy_residual > 0
        and before.energy_residual / last.energy_residual < ENERGY_MIN_FALL
        and any("energy" in n for n in last.needs)
    ):
        return (
            None,
            f"the energy residual does not fall with the step ({before.energy_residual:.3g} "
            f"at {before.step:.3g} s, {last.energy_residual:.3g} at {last.step:.3g} s): it is "
            f"the beam's discretization's, not the step's; fix: {ELEMENTS_FIX}",
            ELEMENTS_FIX,
        )
    halvings = max(1, math.ceil(math.log2(last.factor) - 1e-9))
    step = last.step / 2**halvings
    if step < smallest * (1 - 1e-9):
        return (
            None,
            f"it would need a step of {last.step / last.factor:.3g} s or smaller, below the "
            f'smallest "auto" tries ({smallest:.3g} s, the a-priori step halved '
            f"{MAX_REFINEMENTS} times); give step explicitly",
            "",
        )
    return step, "", ""


@dataclass
class AutoStep:
    """The attempts of one ``"auto"`` run and their outcome (``run_auto``)."""

    a_priori: float
    why: str
    attempts: list[Attempt] = field(default_factory=list)
    #: why refining stopped short of meeting the checks ("" when it met them)
    stop: str = ""
    #: the fix of a broken energy balance the step does not close ("" when none is known)
    energy_fix: str = ""

    @property
    def met(self) -> bool:
        return bool(self.attempts) and not self.attempts[-1].needs and not self.attempts[-1].stopped

    def note(self) -> str:
        """One sentence for ``SolverStats.notes``: the step that ran and why it was chosen, or
        that no step within the limits met the checks and why refining stopped."""
        last = self.attempts[-1]
        tried = ", ".join(f"{a.step:.3g}" for a in self.attempts)
        head = (
            f'step = "{AUTO}" ran {last.step:.3g} s (attempts at {tried} s; a-priori step: '
            f"{self.why})"
        )
        if self.met:
            checks = []
            if last.window_steps_min is not None:
                checks.append(
                    f"every lock window holds >= {MIN_WINDOW_STEPS} steps "
                    f"(fewest {last.window_steps_min:.3g})"
                )
            if last.energy_residual is not None:
                checks.append(f"the energy residual is {last.energy_residual:.3g} (within bound)")
            else:
                checks.append("the energy is not audited (outputs without 'energy')")
            return f"{head}: the first step at which {' and '.join(checks)}"
        if last.stopped:
            return f"{head}: {self.stop}"
        return (
            f"{head}: no step within its limits met its checks, at the last "
            f"{'; '.join(last.needs)}; {self.stop}"
        )

    def record(self) -> dict[str, Any]:
        """The ``step_auto`` entry of the trajectory's settings (run.json)."""
        return {
            "a_priori": self.a_priori,
            "a_priori_why": self.why,
            "smallest": self.a_priori / 2**MAX_REFINEMENTS,
            "attempts": [a.as_dict() for a in self.attempts],
            "chosen": self.attempts[-1].step,
            "met": self.met,
            "energy_fix": self.energy_fix,
            "note": self.note(),
        }


def run_auto(
    scene: Scene,
    run_at: Callable[[float], Trajectory],
    refusal: Callable[[float, float], str | None],
    bounds: tuple[float, float],
) -> tuple[Trajectory, AutoStep]:
    """The ``"auto"`` run of ``scene``: ``run_at(step)`` runs one fixed-step attempt,
    ``refusal(step, predicted_wall_s)`` says why a further attempt would not fit the budgets
    (None: it fits), ``bounds`` = (energy residual bound, max rotation per step in rad).
    Returns the last attempt's trajectory and the attempts (see the module docstring)."""
    step, why = a_priori_step(scene)
    auto = AutoStep(step, why)
    smallest = step / 2**MAX_REFINEMENTS
    while True:
        start = time.perf_counter()
        trajectory = run_at(step)
        wall = time.perf_counter() - start
        attempt = judge(step, trajectory, *bounds, wall)
        auto.attempts.append(attempt)
        if not attempt.needs and not attempt.stopped:
            break
        nxt, auto.stop, auto.energy_fix = next_step(auto.attempts, smallest)
        if nxt is None:
            break
        refused = refusal(nxt, wall * step / nxt)
        if refused is not None:
            auto.stop = f"the attempt at {nxt:.3g} s was not run: {refused}"
            break
        step = nxt
    return trajectory, auto
