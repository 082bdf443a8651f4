"""Deployment mechanics of the paper's models: locked hinges (latches) as exact constraints,
their plastic lock impulses, and the helpers the systems' event handling uses (O(n) kernels).

Conventions (docs/deployment_native.md has the derivations):

* A hinge moment lambda_k acting at hinge k is the generalized force a_k lambda_k, a_k = dD_k/dq
  the k-th row of the hinge matrix A (``paper_matrices.hinge_matrix``): +1 on phi_k, alpha_k,
  -1 on phi_{k-1}, beta_{k-1}. ``hinge_moment`` reports moments with the sign of a spring
  (positive when the hinge resists increasing D_k), so a multiplier lambda is reported as
  -lambda.
* Full model: a locked hinge k is the linear constraint a_k^T q = angle_k. Its multiplier
  comes from M q'' = f + A_L^T lambda, A_L q'' = 0, solved by superposition: q'' = u_0 +
  sum_j lambda_j u_j with u_0 = M^-1 f and u_j = M^-1 a_j (m + 1 O(n) solves), then the m x m
  capacitance system (A_L U) lambda = -A_L u_0. An explicit Runge-Kutta method keeps the
  linear invariants a^T q' = 0 and a^T q = angle to round-off (every stage combination of
  states with a^T q'' = 0).
* Reduced model: D_k = a_p^T phi + a_g^T gamma with gamma the quasi-static bending, an
  unknown of the same linear solve as phi''. A locked hinge adds the unknown lambda_k and the
  equation a_g^T gamma = angle_k - a_p^T phi to that solve (the kappa_k -> infinity limit of
  the reduced model); solved again by superposition, m + 1 O(n) sweeps.
* Motors and rate dampers (``Tq``, ``kernels`` module docstring) act in the free
  accelerations u_0 (the reduced model: in the first solve's right-hand sides), before the
  superposition: a held hinge's multiplier holds its motor too.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.linalg import solveh_banded

from rodval.core.scene import Chain
from rodval.models.assembly.kernels import (
    V_L,
    V_OUTER,
    V_PPDIAG,
    Arr,
    Loads,
    Pair,
    add_moment,
    full_accel,
    full_solve,
    generator_solve,
    hinge_of,
    rhs_start,
)
from rodval.models.bending.reduced_band_lu import band_size, solve_band
from rodval.models.bending.reduced_banded import (
    reduced_forces,
    reduced_rhs,
    rhs_work,
    solve_sweep,
    track_bending,
)

#: Hinge indices (int64), as the kernels take them.
Ints = NDArray[np.int64]

#: Another armed latch locks together with the one whose crossing was located when its
#: angle is within this distance (rad) of its latch angle at that time.
SIMULTANEOUS_RAD = 1e-8


@njit(cache=True)
def unit_moment(k: int, f: Arr) -> None:
    """f += a_k (generalized force of a unit moment at hinge k) on the force rows f (phi,
    alpha, beta, ...: ``kernels.full_forces``; ``kernels.add_moment``)."""
    add_moment(k, 1.0, f)


@njit(cache=True)
def small_solve(G: Arr, r: Arr) -> Arr:
    """Solve the small dense system G x = r (Gaussian elimination with partial pivoting);
    G and r are overwritten, the solution is returned."""
    m = r.shape[0]
    for j in range(m):
        p = j
        for i in range(j + 1, m):
            if abs(G[i, j]) > abs(G[p, j]):
                p = i
        if p != j:
            for q in range(m):
                t = G[j, q]
                G[j, q] = G[p, q]
                G[p, q] = t
            t = r[j]
            r[j] = r[p]
            r[p] = t
        for i in range(j + 1, m):
            f = G[i, j] / G[j, j]
            for q in range(j, m):
                G[i, q] -= f * G[j, q]
            r[i] -= f * r[j]
    x = np.empty(m)
    for j in range(m - 1, -1, -1):
        acc = r[j]
        for q in range(j + 1, m):
            acc -= G[j, q] * x[q]
        x[j] = acc / G[j, j]
    return x


@njit(cache=True)
def full_unit_responses(V: Arr, phi: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M(phi)^-1 a_{locks[j]} (3n each), O(n) per hinge."""
    c = np.cos(phi)
    s = np.sin(phi)
    f = np.empty((3, V.shape[1]))
    for j in range(locks.shape[0]):
        f[:] = 0.0
        unit_moment(locks[j], f)
        full_solve(V, c, s, f, U[j])


@njit(cache=True)
def full_accel_locked(
    V: Arr, y: Arr, loads: Loads, damped: bool, locks: Ints, out: Arr, lam: Arr
) -> None:
    """q'' (3n) of the full model with the hinges ``locks`` held (a_k^T q'' = 0) into
    ``out``, their multipliers (N m, generalized force a_k lambda_k) into ``lam``; the
    ``loads`` (``kernels.Loads``: the hinge moments Tq, N m, in the free accelerations).
    O(n m)."""
    full_accel(V, y, loads, damped, out)  # the free accelerations, O(n)
    if locks.shape[0] > 0:
        U = np.empty((locks.shape[0], out.shape[0]))
        full_unit_responses(V, y[: V.shape[1]], locks, U)
        superpose(out, U, locks, V.shape[1], lam)


@njit(cache=True)
def superpose(out: Arr, U: Arr, locks: Ints, n: int, lam: Arr, theta: int = -1) -> None:
    """q'' = u_0 + sum_j lambda_j u_j with the hinges ``locks`` held: ``out`` holds the free
    accelerations u_0 on entry, U[j] = M^-1 a_{locks[j]}; the capacitance system
    (A_L U) lambda = -A_L u_0 (m x m) gives the multipliers (N m) into ``lam``. O(N m + m^3)
    for N coordinates ordered [phi; alpha; beta; ...] (``theta``: see ``kernels.hinge_of``)."""
    m = locks.shape[0]
    G = np.empty((m, m))
    r = np.empty(m)
    for i in range(m):
        r[i] = -hinge_of(out, locks[i], n, theta)
        for j in range(m):
            G[i, j] = hinge_of(U[j], locks[i], n, theta)
    x = small_solve(G, r)
    for j in range(m):
        lam[j] = x[j]
        out += x[j] * U[j]


@njit(cache=True)
def _reduced_linear(Cst: Arr, c: Arr, s: Arr, f: Arr, T: Arr, out: Pair) -> bool:
    """The reduced model's unreduced linear solve for given right-hand sides (the sweep, the
    banded LU as fallback) into out = (phi'', gamma)."""
    if solve_sweep(Cst, c, s, f, T, out):
        return True
    return bool(solve_band(Cst, c, s, f, np.empty(band_size(c.shape[0])), out))


@njit(cache=True)
def reduced_solve_locked(
    Cst: Arr, y: Arr, loads: Loads, damped: bool, held: tuple[Ints, Arr], out: Pair, lam: Arr
) -> bool:
    """phi'' (n) and gamma (2n) into out = (phi'', gamma), the multipliers lambda (m) into
    ``lam`` of the reduced model at y = [phi; phi'] with the hinges held = (locks, angles)
    held at their angles: D_k = a_p^T phi + a_g^T gamma = angle_k exactly (an algebraic
    equation of the solve); the ``loads`` (``kernels.Loads``: the hinge moments Tq, N m, in
    the first solve's right-hand sides). O(n m). False if a solve is singular."""
    locks, angles = held
    ddphi, gamma = out
    n = Cst.shape[1]
    m = locks.shape[0]
    phi = y[:n]
    c = np.cos(phi)
    s = np.sin(phi)
    f = np.empty((3, n))
    reduced_forces(Cst, y, (c, s), loads, damped, f)
    T = np.empty((n, 3, 4))
    if not _reduced_linear(Cst, c, s, f, T, out):
        return False
    if m == 0:
        return True
    X = np.empty((m, n))
    Gm = np.empty((m, 2 * n))
    for j in range(m):
        f[:] = 0.0
        unit_moment(locks[j], f)
        if not _reduced_linear(Cst, c, s, f, T, (X[j], Gm[j])):
            return False
    G = np.empty((m, m))
    r = np.empty(m)
    for i in range(m):
        k = locks[i]
        D = phi[k] + gamma[k]
        if k > 0:
            D -= phi[k - 1] + gamma[n + k - 1]
        r[i] = angles[i] - D
        for j in range(m):
            g = Gm[j, k]
            if k > 0:
                g -= Gm[j, n + k - 1]
            G[i, j] = g
    x = small_solve(G, r)
    for j in range(m):
        lam[j] = x[j]
        ddphi += x[j] * X[j]
        gamma += x[j] * Gm[j]
    return True


@njit(cache=True)
def mpp_solve(V: Arr, phi: Arr, r: Arr, x: Arr) -> None:
    """Solve M_pp(phi) x = r (the rigid chords' mass matrix, the reduced model's kinetic
    metric) in O(n): M_pp = diag(pp) + tril(a b^T) + triu(b e^T) with a_k = e_k' = l_k M_k e_k,
    b_k = l_k e_k (e_k = (cos phi_k, sin phi_k))."""
    n = phi.shape[0]
    a = np.empty((n, 2))
    b = np.empty((n, 2))
    for k in range(n):
        ck = np.cos(phi[k])
        sk = np.sin(phi[k])
        b[k, 0] = V[V_L, k] * ck
        b[k, 1] = V[V_L, k] * sk
        a[k, 0] = V[V_OUTER, k] * b[k, 0]
        a[k, 1] = V[V_OUTER, k] * b[k, 1]
    generator_solve(V[V_PPDIAG], a, b, a, r, x)


def reduced_hinge_gradient(chain: Chain, k: int) -> np.ndarray:
    """c_k = dD_k/dphi of the reduced model's static hinge angle (gamma at its quasi-static
    value B^-1 (rest terms - K_gp phi)): c_k = a_p,k - K_pg B^-1 a_g,k (n), O(n) by the banded
    solve of B. It is also the generalized force on phi of a unit moment at hinge k once the
    bending rows are eliminated statically."""
    n = chain.n
    kappa, kb = chain.kappa, 4.0 * chain.EI / chain.l
    kap_next = np.concatenate([kappa[1:], [0.0]])
    diag = np.empty(2 * n)
    diag[0::2] = kb + kappa
    diag[1::2] = kb + kap_next
    off = np.empty(2 * n)
    off[0] = 0.0
    off[1::2] = kb / 2.0
    off[2::2] = -kappa[1:]
    rhs = np.zeros(2 * n)  # interleaved (alpha_0, beta_0, alpha_1, ...)
    rhs[2 * k] = 1.0
    if k > 0:
        rhs[2 * k - 1] = -1.0
    x = solveh_banded(np.vstack([off, diag]), rhs)
    alpha, beta = x[0::2], x[1::2]
    # (K_pg gamma)_i = kappa_i (alpha_i - beta_{i-1}) - kappa_{i+1} (alpha_{i+1} - beta_i)
    t = kappa * (alpha - np.concatenate([[0.0], beta[:-1]]))
    kpg = t - np.concatenate([t[1:], [0.0]])
    c: np.ndarray = -kpg
    c[k] += 1.0
    if k > 0:
        c[k - 1] -= 1.0
    return c


# ------------------------------------------------------------------ compiled event forms
# A mode with locked hinges runs on the compiled integrators with S = [damped, m, hinges (m),
# angles (m, rad)] (``lock_scalars``); the event table E has one row [hinge, angle (rad)] per
# armed latch or switching stop, g = D_hinge - angle (``rodval.models.hinge_items.events.event_rows``).


def lock_scalars(damped: float, hinges: np.ndarray, angles: np.ndarray) -> Arr:
    """S of a compiled form with the hinges ``hinges`` held at ``angles`` (rad)."""
    m = len(hinges)
    return np.concatenate([[damped, float(m)], np.asarray(hinges, float), angles]).astype(float)


@njit(cache=True)
def held_hinges(S: Arr) -> tuple[Ints, Arr]:
    """(hinges, angles) held, from a compiled form's S (``lock_scalars``); none for the
    unlocked flags [damped]."""
    m = int(S[1]) if S.shape[0] > 1 else 0
    locks = np.empty(m, np.int64)
    for j in range(m):
        locks[j] = int(S[2 + j])
    return locks, S[2 + m : 2 + 2 * m]


@njit(cache=True, inline="always")
def locked_head(
    t: float, y: Arr, P: Arr, S: Arr, L: Arr, out: Arr, moving: bool = False
) -> tuple[Loads, Ints, Arr]:
    """The start of a compiled right-hand side with the hinges of S held (``rhs_start``):
    (loads, locks, lam): the ``kernels.Loads`` at t (``moving``: hinge 0 from a moving base's
    attitude), the held hinges and room for their multipliers. O(n)."""
    loads = rhs_start(t, y, P, L, out, moving)
    locks, _ = held_hinges(S)
    return loads, locks, np.empty(locks.shape[0])


@njit(cache=True)
def full_rhs_locked(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the full model with the hinges of S held (``full_accel_locked``), the hinge
    moments at the rates a_k q' (``kernels.hinge_moments_at``); O(n m)."""
    loads, locks, lam = locked_head(t, y, P, S, L, out)
    full_accel_locked(P, y, loads, S[0] != 0.0, locks, out[3 * P.shape[1] :], lam)


@njit(cache=True)
def reduced_rhs_locked(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the reduced model with the hinges of S held at their angles
    (``reduced_solve_locked``); gamma and the largest |gamma| kept in the work space M[0, 0]
    as ``reduced_banded.reduced_rhs`` does, the hinge moments at the chord rates; a singular
    solve gives NaN (the run ends as diverged). O(n m)."""
    half = y.shape[0] // 2
    loads, gamma, _ = rhs_work(t, y, M, L, out)
    held = held_hinges(S)
    lam = np.empty(held[0].shape[0])
    ddphi = np.empty(half)
    if not reduced_solve_locked(P, y, loads, S[0] != 0.0, held, (ddphi, gamma), lam):
        ddphi[:] = np.nan
    for i in range(half):  # a loop: a slice assignment compiles numba's shape check
        out[half + i] = ddphi[i]
    M[0, 0, -1] = track_bending(gamma, M[0, 0, -1])


@njit(cache=True)
def hinge_events(phi: Arr, alpha: Arr, beta: Arr, E: Arr, out: Arr, attitude: float = 0.0) -> None:
    """out[i] = D_k - angle for the rows [k, angle] of E, D_k = phi_k + alpha_k - phi_{k-1} -
    beta_{k-1} (rad), D_0 from a free base's ``attitude`` (rad; 0 for a pin); O(rows)."""
    for i in range(E.shape[0]):
        k = int(E[i, 0])
        D = phi[k] + alpha[k]
        if k > 0:
            D -= phi[k - 1] + beta[k - 1]
        else:
            D -= attitude
        out[i] = D - E[i, 1]


@njit(cache=True)
def full_hinge_events(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, E: Arr, out: Arr) -> None:
    """The full model's latch and stop events: g = D_k - angle from the state's q; O(rows)."""
    n = P.shape[1]
    hinge_events(y[:n], y[n : 2 * n], y[2 * n : 3 * n], E, out)


@njit(cache=True)
def reduced_hinge_events(
    t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, E: Arr, out: Arr
) -> None:
    """The reduced model's latch and stop events: g = D_k - angle with the quasi-static
    bending gamma of the current mode (one solve of the mode's right-hand side, which leaves
    gamma in M[0, 0]); O(n) (O(n m) with m hinges held)."""
    n = P.shape[1]
    rates = np.empty(y.shape[0])
    if S.shape[0] > 1:
        reduced_rhs_locked(t, y, P, S, M, L, rates)
    else:
        reduced_rhs(t, y, P, S, M, L, rates)
    gamma = M[0, 0][2 * n : 4 * n]
    hinge_events(y[:n], gamma[:n], gamma[n:], E, out)
