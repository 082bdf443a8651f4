"""The numba types of a system's compiled functions (``CompiledForm``):

* ``RHS_TYPE`` (``.rhs``, ``.mechanics``): ``f(t, y, P, S, M, L, out)`` writing into ``out``;
* ``EVENTS_TYPE`` (``.events``): ``g(t, y, P, S, M, L, E, out)`` writing the value of each
  event function (one per row of the model's event table E) into ``out``.

Kept apart from the integrators so that kernels can declare them without loading the compiled
integrator loop. Kernels are decorated without a signature, so importing their module compiles
(or loads from numba's cache) none of them; ``first_class`` compiles the ones a run uses, as
the compiled integrators take them (issue 38: a run compiles what it needs)."""

from __future__ import annotations

from typing import Any

from numba import types

F1 = types.float64[::1]
F2 = types.float64[:, ::1]
F3 = types.float64[:, :, ::1]
RHS_SIGNATURE = types.void(types.float64, F1, F2, F1, F3, F2, F1)
RHS_TYPE = types.FunctionType(RHS_SIGNATURE)
EVENTS_SIGNATURE = types.void(types.float64, F1, F2, F1, F3, F2, F2, F1)
EVENTS_TYPE = types.FunctionType(EVENTS_SIGNATURE)


def first_class(kernel: Any, signature: Any) -> Any:
    """``kernel`` (a numba dispatcher) with ``signature`` compiled, or loaded from numba's
    cache, so that it passes as a first-class function of that type; returned for chaining.
    Cheap once compiled (a dictionary lookup)."""
    kernel.compile(signature)
    return kernel
