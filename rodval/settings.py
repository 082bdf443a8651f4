"""How to integrate: the integrator and its tolerances (independent of scene and model)."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

#: scipy.integrate.solve_ivp methods; implicit ones use the model's Jacobian where it has one.
SCIPY_METHODS = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")
#: rodval's compiled integrators (``rodval.integrators``): the whole run in one compiled loop,
#: for native models with the numba kernel and tabulated (pulse/constant) loads.
COMPILED_METHODS = ("DOP853-numba",)
#: Every method name accepted by IntegratorSettings (simulate, CLI, studies).
METHODS = SCIPY_METHODS + COMPILED_METHODS
IMPLICIT_METHODS = ("Radau", "BDF", "LSODA")


@dataclass(frozen=True)
class IntegratorSettings:
    """Integrator choice for ODE models.

    method : one of ``METHODS`` (scipy's solve_ivp methods, or a ``COMPILED_METHODS`` entry).
    rtol, atol : relative and absolute tolerances, > 0 (absolute in the state's units: rad, rad/s).
    max_step : largest step (s), > 0; inf means unbounded.
    first_step : initial step (s), > 0, or None to let the integrator choose.

    Divergence detection (see ``rodval.divergence``; each stops the run with its own status):

    blowup_factor : > 1, or inf to disable. The run stops as "energy blow-up" when the
        mechanical energy E(t) exceeds ``blowup_factor`` times its physical budget
        E(0) + W+(t) (W+: the positive work of the loads so far). The hinge dampers only remove
        energy, so a valid solution stays within its budget up to the model's own balance
        residual (below 1 % in every case of the stability study); 100x cannot be a solution.
    min_step_fraction, stall_steps : the run stops as "step size collapse" when
        ``stall_steps`` consecutive accepted steps are all shorter than
        ``min_step_fraction * t_end``. Defaults: 1e-9 and 1000.
    """

    method: str = "DOP853"
    rtol: float = 1e-8
    atol: float = 1e-10
    max_step: float = math.inf
    first_step: float | None = None
    blowup_factor: float = 100.0
    min_step_fraction: float = 1e-9
    stall_steps: int = 1000

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {self.method!r}")
        for name in ("rtol", "atol", "max_step"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v) or v <= 0:
                raise ValueError(f"{name} must be a number > 0, got {v!r}")
        if not math.isfinite(self.atol):
            raise ValueError(f"atol must be a finite number > 0, got {self.atol!r}")
        if self.rtol >= 1:
            raise ValueError(f"rtol must be in (0, 1), got {self.rtol!r}")
        if self.first_step is not None and not (self.first_step > 0 and math.isfinite(self.first_step)):
            raise ValueError(f"first_step must be a finite number > 0 or None, got {self.first_step!r}")
        if not (self.blowup_factor > 1):
            raise ValueError(f"blowup_factor must be > 1 (inf disables), got {self.blowup_factor!r}")
        if not (0 <= self.min_step_fraction < 1):
            raise ValueError(f"min_step_fraction must be in [0, 1), got {self.min_step_fraction!r}")
        if isinstance(self.stall_steps, bool) or not isinstance(self.stall_steps, int) \
                or self.stall_steps < 1:
            raise ValueError(f"stall_steps must be an integer >= 1, got {self.stall_steps!r}")

    @property
    def compiled(self) -> bool:
        return self.method in COMPILED_METHODS

    @property
    def implicit(self) -> bool:
        return self.method in IMPLICIT_METHODS

    def as_dict(self) -> dict:
        return asdict(self)
