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
    """

    method: str = "DOP853"
    rtol: float = 1e-8
    atol: float = 1e-10
    max_step: float = math.inf
    first_step: float | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {self.method!r}")
        for name in ("rtol", "atol", "max_step"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v) or v <= 0:
                raise ValueError(f"{name} must be a number > 0, got {v!r}")
        if self.rtol >= 1:
            raise ValueError(f"rtol must be in (0, 1), got {self.rtol!r}")
        if self.first_step is not None and not (self.first_step > 0 and math.isfinite(self.first_step)):
            raise ValueError(f"first_step must be a finite number > 0 or None, got {self.first_step!r}")

    @property
    def compiled(self) -> bool:
        return self.method in COMPILED_METHODS

    @property
    def implicit(self) -> bool:
        return self.method in IMPLICIT_METHODS

    def as_dict(self) -> dict:
        return asdict(self)
