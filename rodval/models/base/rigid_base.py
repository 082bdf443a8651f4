"""Compiled kernels of the rigid chain on a moving base: ``chain_base``'s free-body and
prescribed-motion kernels on the rigid constants (``ladder.rigid_constants`` with
``free_base.BODY_ROWS`` appended), run on the rigid state [phi; x_c, y_c, theta; phi'; rates]
(n + 3 coordinates) through ``rigid_kernels.to_ladder`` / ``state_from_ladder``: the body's
equations of docs/base.md with the rods' bending first moments A_k = 0, written once, in
``chain_base``. O(n) per evaluation (three ladder solves for a free body, one for a prescribed
motion, m more with m hinges held).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.models.assembly.kernels import Arr, Loads, Pair
from rodval.models.base import chain_base as cb
from rodval.models.hinge_items.deployment import Ints
from rodval.models.kinematics.rigid_kernels import (
    from_ladder,
    positions_to_ladder,
    state_from_ladder,
    to_ladder,
)


@njit(cache=True)
def free_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the rigid chain on a free body (``chain_base.free_rhs``)."""
    z = to_ladder(y, P.shape[1])
    dz = np.empty_like(z)
    cb.free_rhs(t, z, P, S, M, L, dz)
    state_from_ladder(dz, P.shape[1], out)


@njit(cache=True)
def free_rhs_locked(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' on a free body with the hinges of S held (``chain_base.free_rhs_locked``)."""
    z = to_ladder(y, P.shape[1])
    dz = np.empty_like(z)
    cb.free_rhs_locked(t, z, P, S, M, L, dz)
    state_from_ladder(dz, P.shape[1], out)


@njit(cache=True)
def prescribed_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' on a prescribed base, its laws in M[0] (``chain_base.prescribed_rhs``)."""
    z = to_ladder(y, P.shape[1])
    dz = np.empty_like(z)
    cb.prescribed_rhs(t, z, P, S, M, L, dz)
    state_from_ladder(dz, P.shape[1], out)


@njit(cache=True)
def free_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) on a free body (``chain_base.free_mechanics``)."""
    cb.free_mechanics(t, to_ladder(y, P.shape[1]), P, S, M, L, out)


@njit(cache=True)
def prescribed_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext with the drive's power, P_diss) on a prescribed base
    (``chain_base.prescribed_mechanics``)."""
    cb.prescribed_mechanics(t, to_ladder(y, P.shape[1]), P, S, M, L, out)


@njit(cache=True)
def free_hinge_events(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, E: Arr, out: Arr) -> None:
    """g = D_k - angle, hinge 0 from the body's attitude (``chain_base.free_hinge_events``)."""
    cb.free_hinge_events(t, to_ladder(y, P.shape[1]), P, S, M, L, E, out)


@njit(cache=True)
def free_momentum(V: Arr, y: Arr) -> tuple[float, float]:
    """The whole system's linear momentum (N s) (``chain_base.free_momentum``)."""
    px, py = cb.free_momentum(V, to_ladder(y, V.shape[1]))
    return px, py


@njit(cache=True)
def free_accel(V: Arr, y: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """Q'' (n + 3) on a free body (``chain_base.free_accel``; ``loads`` the
    ``kernels.Loads``, Tq the hinge moments, N m, at the chord rates)."""
    n = V.shape[1]
    z = to_ladder(y, n)
    acc = np.empty(z.shape[0] // 2)
    cb.free_accel(V, z, loads, damped, acc)
    from_ladder(acc, n, out)


@njit(cache=True)
def free_accel_locked(
    V: Arr, y: Arr, loads: Loads, damped: bool, locks: Ints, out: Arr, lam: Arr
) -> None:
    """Q'' (n + 3) on a free body with ``locks`` held (``chain_base.free_accel_locked``)."""
    n = V.shape[1]
    z = to_ladder(y, n)
    acc = np.empty(z.shape[0] // 2)
    cb.free_accel_locked(V, z, loads, damped, locks, acc, lam)
    from_ladder(acc, n, out)


@njit(cache=True)
def free_unit_responses(V: Arr, q: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M_tot^-1 a_k (n + 3) for k = locks[j] (``chain_base.free_unit_responses``)."""
    n = V.shape[1]
    z = positions_to_ladder(q[: U.shape[1]], n)
    Uz = np.empty((locks.shape[0], z.shape[0]))
    cb.free_unit_responses(V, z, locks, Uz)
    for j in range(locks.shape[0]):
        from_ladder(Uz[j], n, U[j])


@njit(cache=True)
def prescribed_unit_responses(V: Arr, q: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M_c^-1 a_k (n + 3, the body's entries zero) (``chain_base``'s)."""
    n = V.shape[1]
    z = positions_to_ladder(q[: U.shape[1]], n)
    Uz = np.empty((locks.shape[0], z.shape[0]))
    cb.prescribed_unit_responses(V, z, locks, Uz)
    for j in range(locks.shape[0]):
        from_ladder(Uz[j], n, U[j])


@njit(cache=True)
def prescribed_accel_locked(
    V: Arr, y: Arr, mo: Arr, loads: Loads, damped: bool, locks: Ints, out: Pair
) -> None:
    """Q'' (n + 3) on a prescribed base with ``locks`` held and their multipliers into out =
    (Q'', lam) (``chain_base``'s)."""
    n = V.shape[1]
    z = to_ladder(y, n)
    acc = np.empty(z.shape[0] // 2)
    cb.prescribed_accel_locked(V, z, mo, loads, damped, locks, (acc, out[1]))
    from_ladder(acc, n, out[0])


@njit(cache=True)
def drive(V: Arr, y: Arr, mo: Arr, S: Arr, L: Arr, t: float) -> tuple[float, float, float]:
    """(F_dx, F_dy (N), m_1 (N m)) of the base on the chain (``chain_base.drive``)."""
    Fx, Fy, m1 = cb.drive(V, to_ladder(y, V.shape[1]), mo, S, L, t)
    return Fx, Fy, m1
