"""How to integrate: the integrator, its tolerances and budgets (independent of scene and model).

This module is the one source of defaults for the Python API, the CLI and study files
(``DEFAULTS``): every surface builds an ``IntegratorSettings`` and never repeats a value.
"""

from __future__ import annotations

import math
import numbers
import sys
from dataclasses import asdict, dataclass, fields
from typing import Any

from rodval.core.checks import check_number

#: scipy.integrate.solve_ivp methods; implicit ones use the model's Jacobian where it has one.
SCIPY_METHODS = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")
#: rodval's compiled integrators (``rodval.solvers.compiled``): the whole run in one compiled
#: loop, for systems that have a compiled form (native models, tabulated load laws).
COMPILED_METHODS = ("DOP853-numba", "Radau-numba")
#: "auto": the compiled DOP853 when the model and scene have a compiled form (events and the
#: energy audit run inside the compiled loop), scipy's DOP853 otherwise. The compiled DOP853
#: of "auto" goes on with the compiled Radau IIA once Hairer's stiffness test finds its steps
#: limited by stability (``rodval.solvers.dop853.SWITCHING_STEPPER``; stiff panels, locked
#: hinges); "DOP853-numba" asked by name never switches. The Trajectory records the method
#: that ran, and ``stats.switch`` where and why it switched.
AUTO = "auto"
#: Every method name accepted by IntegratorSettings (simulate, CLI, studies).
METHODS = (AUTO,) + SCIPY_METHODS + COMPILED_METHODS
IMPLICIT_METHODS = ("Radau", "BDF", "LSODA")
#: The smallest relative tolerance the integrators honour: 100 machine epsilons (scipy's
#: solve_ivp raises any smaller rtol to it; below it no step can meet the tolerance).
MIN_RTOL = 100 * sys.float_info.epsilon
#: The allowed rtol, for messages.
RTOL_RANGE = (
    f"a number in (0, 1), at least {MIN_RTOL:.3g} (> 0 is not enough: the integrators cannot "
    "honour less than 100 machine epsilons)"
)
#: How the compiled loop's error norm weighs the state (``IntegratorSettings.error_control``).
ERROR_CONTROLS = ("uniform", "per-block")

#: Largest count (evaluations, steps) a setting may ask for: 2**53, exact as a double and far
#: inside the compiled loop's int64 counters (a larger one failed at run time with numba's
#: "No matching definition" or OverflowError).
MAX_COUNT = 2**53
#: The allowed counts, for messages.
COUNT_RANGE = f"an integer in [1, {MAX_COUNT}]"


#: Each number setting's range, checked once (``check_number``'s keywords; ``allowed`` words
#: it for a number out of range, a value that is no real number is told "a real number ...",
#: ``rodval.core.checks.describe_range``).
NUMBER_BOUNDS: dict[str, dict[str, Any]] = {
    "rtol": {"low": MIN_RTOL, "high": 1, "high_open": True, "allowed": RTOL_RANGE},
    "atol": {"low": 0, "low_open": True, "finite": True, "allowed": "a finite number > 0"},
    "max_step": {"low": 0, "low_open": True, "allowed": "> 0 (inf: no limit)"},
    "first_step": {
        "low": 0,
        "low_open": True,
        "finite": True,
        "allowed": "a finite number > 0 or None",
    },
    "max_evaluations": {"integer": True, "low": 1, "high": MAX_COUNT, "allowed": COUNT_RANGE},
    "max_wall_s": {"low": 0, "low_open": True, "allowed": "> 0 (inf: no limit)"},
    "blowup_factor": {"low": 1, "low_open": True, "allowed": "> 1 (inf disables)"},
    "min_step_fraction": {"low": 0, "high": 1, "high_open": True, "allowed": "in [0, 1)"},
    "stall_steps": {"integer": True, "low": 1, "high": MAX_COUNT, "allowed": COUNT_RANGE},
    "block_frequency": {
        "low": 0,
        "low_open": True,
        "finite": True,
        "allowed": "a finite frequency > 0 (rad/s)",
    },
    "bending_scale": {"low": 1, "finite": True, "allowed": "a finite number >= 1"},
}


@dataclass(frozen=True)
class IntegratorSettings:
    """Integrator choice for ODE models.

    method : one of ``METHODS``; default "auto" (see ``AUTO``).
    rtol, atol : relative tolerance in [MIN_RTOL, 1) (``MIN_RTOL`` = 2.22e-14: the smallest
        the integrators honour) and absolute tolerance > 0, finite (absolute in the state's
        units: rad, rad/s).
    max_step : largest step (s), > 0; inf means unbounded.
    first_step : initial step (s), > 0, or None to let the integrator choose.

    Budgets (each ends the run with its own status, see ``rodval.core.status``):

    max_evaluations : integer >= 1, right-hand-side evaluations a run may use.
    max_wall_s : wall-clock seconds a run may use (> 0), or inf for no limit.

    Divergence detection (``rodval.solvers.guard``):

    blowup_factor : > 1, or inf to disable. The run stops as "energy blow-up" when the
        kinetic energy exceeds ``blowup_factor`` times its physical budget E(0) + W+(t)
        (W+: the positive work of the loads so far). The hinge dampers only remove energy, so
        a valid solution stays within its budget up to the model's own balance residual
        (below 1 % in every case of the stability study); 100x cannot be a solution.
    min_step_fraction, stall_steps : the run stops as "step size collapse" when
        ``stall_steps`` consecutive accepted steps are all shorter than
        ``min_step_fraction * t_end``.

    Error control per coordinate block (the compiled methods and "auto";
    ``rodval.solvers.compiled.atol_vector``):

    error_control : "uniform": every component's absolute tolerance is ``atol``;
        "per-block": a system that names its bending coordinates (``OdeSystem.bending_mask``:
        the full model) has every angle judged on the scale of 1 rad, atol_i = max(atol,
        rtol x 1 rad) (a panel at phi = 0 no stricter than one at pi), and every rate on
        the scale 1 rad x ``block_frequency``, atol_i = max(atol, rtol x block_frequency x
        1 rad/s): a vibration faster than ``block_frequency`` whose angle stays below rtol x
        1 rad is not resolved, and Radau IIA (L-stable) steps over it; the bending block
        (alpha, beta, a rung's bubbles and their rates) on a scale ``bending_scale`` times
        larger. Systems without bending coordinates (reduced, rigid) run as "uniform".
    block_frequency : rad/s, > 0, finite: the per-block rates' frequency scale.
    bending_scale : >= 1, finite: how much larger the bending block's scale is.
    """

    method: str = AUTO
    rtol: float = 1e-8
    atol: float = 1e-10
    max_step: float = math.inf
    first_step: float | None = None
    max_evaluations: int = 2_000_000
    max_wall_s: float = math.inf
    blowup_factor: float = 100.0
    min_step_fraction: float = 1e-9
    stall_steps: int = 1000
    error_control: str = "uniform"
    block_frequency: float = 1e4
    bending_scale: float = 1e4

    def __post_init__(self) -> None:
        if not isinstance(self.method, str) or self.method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {self.method!r}")
        if not isinstance(self.error_control, str) or self.error_control not in ERROR_CONTROLS:
            raise ValueError(
                f"error_control must be one of {ERROR_CONTROLS}, got {self.error_control!r}"
            )
        for name, bounds in NUMBER_BOUNDS.items():
            value = getattr(self, name)
            if value is None and name == "first_step":
                continue
            if not bounds.get("integer") and (
                isinstance(value, bool) or not isinstance(value, numbers.Real)
            ):
                bounds = dict(bounds, allowed=None)  # "... must be a real number ..., got"
            check_number(name, value, **bounds)

    def check_horizon(self, t_end: float) -> None:
        """The settings against a scene's horizon t_end (s), before any work: a first step
        beyond the horizon is refused (scipy failed on it at run time, as a failed run)."""
        if self.first_step is not None and self.first_step > t_end:
            raise ValueError(
                f"first_step must be at most the horizon t_end = {t_end:g} s, got "
                f"{self.first_step:g}"
            )

    @property
    def compiled(self) -> bool:
        return self.method in COMPILED_METHODS

    @property
    def implicit(self) -> bool:
        return self.method in IMPLICIT_METHODS

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def budget_message(self, budget: str, t: float) -> str:
        """The message of a run stopped at time t (s) by its budget ``budget``
        ("max_evaluations" or "max_wall_s"), with the budget's value."""
        if budget == "max_wall_s":
            used = f"wall-clock budget exhausted: max_wall_s = {self.max_wall_s:g} s"
        else:
            used = f"evaluation budget exhausted: max_evaluations = {self.max_evaluations}"
        return f"{used} used (t = {t:.6g} s)"

    def with_(self, **changes: Any) -> IntegratorSettings:
        """A copy with fields replaced (validated again)."""
        return IntegratorSettings(**{**self.as_dict(), **changes})


#: The defaults of every integrator setting (API keywords, CLI options, study files).
DEFAULTS: dict[str, Any] = IntegratorSettings().as_dict()
#: The settings' names (study files' [integrator] keys, simulate keywords).
SETTING_NAMES: tuple[str, ...] = tuple(f.name for f in fields(IntegratorSettings))
