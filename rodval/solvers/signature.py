"""The numba type of a compiled right-hand side (``CompiledForm.rhs``, ``.mechanics``):
``f(t, y, P, S, M, L, out)`` writing into ``out``. Kept apart from the integrators so that
kernels can declare it without loading the compiled integrator loop."""

from __future__ import annotations

from numba import types

F1 = types.float64[::1]
F2 = types.float64[:, ::1]
F3 = types.float64[:, :, ::1]
RHS_SIGNATURE = types.void(types.float64, F1, F2, F1, F3, F2, F1)
RHS_TYPE = types.FunctionType(RHS_SIGNATURE)
