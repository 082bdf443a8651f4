"""Compiled kernels of the rigid chain (``rodval.models.systems.chain_system.RigidSystem``):
the ladder's kernels (``ladder_kernels``) on the rigid constants (``ladder.rigid_constants``:
zero bending mobility, the limit EI -> inf of every rung), run on the rigid state.

The rigid state is y = [phi (n); body (b); phi' (n); body' (b)] (b = 0 on a pinned base, the
free body's x_c, y_c, theta otherwise): n + b coordinates, the ODE the integrator sees. Each
kernel here places it into the ladder's layout [phi; alpha; beta; body; rates] with the
bending coordinates zero (``to_ladder``), runs the ladder's kernel, and takes the rigid
coordinates back (``from_ladder``). With zero mobility the ladder's bending accelerations are
exactly 0, so the bending coordinates the ladder sees stay zero, and nothing of the rigid
chain's equations is written twice: M_pp(phi) phi'' = Q - G_pp phi'^2 - A^T (kappa (D - rest)
+ nu D' - Tq), D_k = phi_k - phi_{k-1} (Tq: the motors' and rate dampers' moments, N m, at
the chord rates D'), with every lock, stop and base of the ladder.
Cost: the ladder's O(n) evaluation on 3 n coordinates plus two copies of the state.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.models.assembly.kernels import Arr, Loads
from rodval.models.hinge_items.deployment import Ints, hinge_events
from rodval.models.kinematics.ladder_kernels import (
    ladder_accel,
    ladder_accel_locked,
    ladder_mechanics,
    ladder_rhs_locked,
    ladder_unit_responses,
)


@njit(cache=True)
def to_ladder(y: Arr, n: int) -> Arr:
    """The ladder's state [phi; 0 (2 n); body; phi'; 0 (2 n); body'] of a rigid state y =
    [phi; body; phi'; body'] (``n`` rods, ``b`` = len(y) / 2 - n body coordinates)."""
    half = y.shape[0] // 2
    N = half + 2 * n
    z = np.zeros(2 * N)
    z[:n] = y[:n]
    z[3 * n : N] = y[n:half]
    z[N : N + n] = y[half : half + n]
    z[N + 3 * n :] = y[half + n :]
    return z


@njit(cache=True)
def positions_to_ladder(q: Arr, n: int) -> Arr:
    """The ladder's coordinates [phi; 0 (2 n); body] of rigid coordinates q = [phi; body]."""
    z = np.zeros(q.shape[0] + 2 * n)
    z[:n] = q[:n]
    z[3 * n :] = q[n:]
    return z


@njit(cache=True)
def from_ladder(z: Arr, n: int, out: Arr) -> None:
    """out = [z_phi; z_body] (rigid coordinates) of a ladder coordinate vector z = [phi;
    alpha; beta; body] (its bending part dropped: zero for the rigid constants)."""
    out[:n] = z[:n]
    out[n:] = z[3 * n :]


@njit(cache=True)
def state_from_ladder(z: Arr, n: int, out: Arr) -> None:
    """out = the rigid state of a ladder state (``from_ladder`` on each half)."""
    N = z.shape[0] // 2
    half = out.shape[0] // 2
    from_ladder(z[:N], n, out[:half])
    from_ladder(z[N:], n, out[half:])


@njit(cache=True)
def rigid_accel(V: Arr, y: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """phi'' (n) of the pinned rigid chain at y = [phi; phi'] into ``out`` (``ladder_accel``
    on ``rigid_constants``; ``loads``: ``kernels.Loads``, Tq the hinge moments, N m, at the
    chord rates, empty for none); O(n)."""
    n = V.shape[1]
    acc = np.empty(3 * n)
    ladder_accel(V, to_ladder(y, n), loads, damped, acc)
    out[:] = acc[:n]


@njit(cache=True)
def rigid_unit_responses(V: Arr, q: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M_pp(phi)^-1 a_{locks[j]} (n each, a_k = dD_k/dphi); only phi = q[:n] is read.
    O(n) per hinge."""
    n = V.shape[1]
    Uz = np.empty((locks.shape[0], 3 * n))
    ladder_unit_responses(V, positions_to_ladder(q[:n], n), locks, Uz)
    for j in range(locks.shape[0]):
        U[j, :] = Uz[j, :n]


@njit(cache=True)
def rigid_accel_locked(
    V: Arr, y: Arr, loads: Loads, damped: bool, locks: Ints, out: Arr, lam: Arr
) -> None:
    """phi'' (n) with the hinges ``locks`` held (D_k'' = 0) into ``out``, their multipliers
    (N m) into ``lam`` (``ladder_accel_locked``, ``loads`` with the hinge moments); O(n m)."""
    n = V.shape[1]
    acc = np.empty(3 * n)
    ladder_accel_locked(V, to_ladder(y, n), loads, damped, locks, acc, lam)
    out[:] = acc[:n]


@njit(cache=True)
def rigid_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the pinned rigid chain (compiled integrators' right-hand side) with the hinges
    of S held, if any (``deployment.lock_scalars``; S = [damped]: none):
    ``ladder_rhs_locked`` on the ladder's state, its hinge moments on the chord rates
    phi'_k - phi'_{k-1}; with no hinge held it is ``ladder_rhs``'s arithmetic. O(n m)."""
    z = to_ladder(y, P.shape[1])
    dz = np.empty_like(z)
    ladder_rhs_locked(t, z, P, S, M, L, dz)
    state_from_ladder(dz, P.shape[1], out)


#: The right-hand side with hinges held: ``rigid_rhs``, which reads them from S.
rigid_rhs_locked = rigid_rhs


@njit(cache=True)
def rigid_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) of the pinned rigid chain into out[:3] (``ladder_mechanics``): T =
    1/2 phi'^T M_pp phi' (J), the loads' and hinge moments' power (W), the hinge dampers' sum
    nu (dD/dt)^2 (W)."""
    ladder_mechanics(t, to_ladder(y, P.shape[1]), P, S, M, L, out)


@njit(cache=True)
def rigid_hinge_events(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, E: Arr, out: Arr) -> None:
    """Latch and stop events g = D_k - angle, D_k = phi_k - phi_{k-1} (rad); O(rows)."""
    n = P.shape[1]
    zero = np.zeros(n)
    hinge_events(y[:n], zero, zero, E, out)
