"""Compiled kernels of the model ladder (``rodval.models.kinematics.ladder``): the full model with p + 1
bending shapes per rod (``shapes = p``) and first-order or exact assumed-mode kinematics.

Coordinates q = [phi (n); g_0 (n); g_1 (n); ...; g_p (n)] (g_0 = alpha, g_1 = beta, g_i
component-major, so alpha, beta sit where the paper's model has them), state y = [q; q'],
N = n (p + 2) coordinates. docs/model.md ("The model ladder") derives every term:

* the generalized forces f = [Q; 0] + A^T Tq - dPi/dq - C q' - c(q, q'), where Tq are the
  motors' and rate dampers' moments across the hinges (N m, positive driving D_k up, on the
  rows the hinge springs act on: phi, alpha, beta; at the hinge rates a_k q' the hinge
  dampers see, ``kernels.hinge_moments_at``) and the velocity terms
  c_i = sum int dm (dr/dq_i) . a_v are accumulated along the chain (a_v: the acceleration of
  each material point at q'' = 0; node accelerations by a forward sweep, the inertia of
  everything beyond a node by a backward one): O(n p^2);
* the solve M(q) q'' = f: the bending block of each rod (its Gram matrix P_k, constant) is
  eliminated, leaving the Schur complement of the paper's model with per-rod constants
  a^T P^-1 a, b^T P^-1 a, b^T P^-1 b and, with exact kinematics, its diagonal raised by
  g^T P g and its generators by the rods' bending first moments a . g (the rank-2
  semiseparable form is kept): ``kernels.generator_solve``, O(n p^2).

The rows of V: the paper model's rows V_L .. V_TAU (``kernels``; V_W = 1, V_KB = V_CB = 0:
the shapes' own blocks carry the bending), then the ``LV_*`` rows below and the per-rod shape
blocks (``shape_row``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.models.assembly.kernels import (
    V_KAPPA,
    V_L,
    V_NU,
    Arr,
    Loads,
    compiled_damper_power,
    external_power,
    generator_solve,
    hinge_forces,
    hinge_moments_into,
    load_moments,
    rhs_start,
    schur_generators,
    upper_t_times,
    upper_times,
)
from rodval.models.hinge_items.deployment import Ints, locked_head, superpose, unit_moment

#: Rows after the paper model's 19: rod mass m l (kg), node mass mu (kg), the number of
#: shapes p + 1 and the exact-kinematics flag (the same in every column).
LV_MASS, LV_MU, LV_P1, LV_EXACT = range(19, 23)
#: First row of the shape blocks: a (p+1 rows), b (p+1), then P, P^-1, K, C ((p+1)^2 each,
#: row-major).
LV_SHAPES = 23
BLOCK_A, BLOCK_B, BLOCK_P, BLOCK_PINV, BLOCK_K, BLOCK_C = range(6)
#: The chain at q: (cos phi, sin phi, g (p+1, n), A, Pg (``bending_sums``)); ``ladder_geometry``.
Geometry = tuple[Arr, Arr, Arr, Arr, Arr]


@njit(cache=True, inline="always")
def shape_row(P1: int, block: int, i: int, j: int) -> int:
    """Row of V holding entry (i, j) of a shape block (j = 0 for the vectors a, b)."""
    if block <= BLOCK_B:
        return LV_SHAPES + block * P1 + i
    return LV_SHAPES + 2 * P1 + (block - BLOCK_P) * P1 * P1 + i * P1 + j


@njit(cache=True)
def _quadratic(V: Arr, P1: int, block: int, k: int, x: Arr, z: Arr) -> float:
    """x^T B_k z for the shape block B of rod k."""
    total = 0.0
    for i in range(P1):
        for j in range(P1):
            total += x[i, k] * V[shape_row(P1, block, i, j), k] * z[j, k]
    return float(total)


@njit(cache=True)
def _block_times(V: Arr, P1: int, block: int, k: int, x: Arr, out: Arr, sign: float) -> None:
    """out[:, k] += sign * B_k x[:, k] for a shape block B (``shape_row``)."""
    for i in range(P1):
        acc = 0.0
        for j in range(P1):
            acc += V[shape_row(P1, block, i, j), k] * x[j, k]
        out[i, k] += sign * acc


@njit(cache=True)
def shape_dot(V: Arr, P1: int, block: int, k: int, x: Arr) -> float:
    """v_k . x[:, k] for a shape vector v (a or b) of rod k."""
    total = 0.0
    for i in range(P1):
        total += V[shape_row(P1, block, i, 0), k] * x[i, k]
    return float(total)


@njit(cache=True)
def bending_sums(V: Arr, g: Arr) -> tuple[Arr, Arr]:
    """(A (n,), Pg (p+1, n)): every rod's bending first moment A_k = a_k . g_k (kg m) and
    P_k g_k (kg m^2), the state-dependent part of exact kinematics; zeros with first-order
    kinematics, which drops every term they carry. O(n p^2), once per evaluation."""
    P1, n = g.shape
    A = np.zeros(n)
    Pg = np.zeros((P1, n))
    if V[LV_EXACT, 0] != 0.0:
        for k in range(n):
            A[k] = shape_dot(V, P1, BLOCK_A, k, g)
            _block_times(V, P1, BLOCK_P, k, g, Pg, 1.0)
    return A, Pg


@njit(cache=True)
def ladder_geometry(V: Arr, q: Arr) -> Geometry:
    """(c, s, g, A, Pg) of the ladder at the positions q: the chords' cosines and sines, the
    bending coordinates (p+1, n) and their ``bending_sums``. O(n p^2)."""
    n = V.shape[1]
    P1 = shape_count(V)
    g = q[n : n * (P1 + 1)].reshape((P1, n))
    A, Pg = bending_sums(V, g)
    return np.cos(q[:n]), np.sin(q[:n]), g, A, Pg


@njit(cache=True)
def _velocity_terms(
    V: Arr, c: Arr, s: Arr, phi_rate: Arr, dg: Arr, A: Arr, Pg: Arr, fp: Arr, fg: Arr
) -> None:
    """fp, fg -= c(q, q'), the velocity terms of the ladder (module docstring), O(n p^2);
    A, Pg from ``bending_sums`` (zero for first-order kinematics)."""
    n = c.shape[0]
    P1 = dg.shape[0]
    l, ml, mu = V[V_L], V[LV_MASS], V[LV_MU]
    node = np.empty((n, 2))  # velocity part of the node accelerations A_k
    rod = np.empty((n, 2))  # int over rod k of m a_v ds
    Ax = 0.0
    Ay = 0.0
    for k in range(n):
        w = phi_rate[k]
        h = 0.5 * ml[k] * l[k]  # int m s ds
        Ad = shape_dot(V, P1, BLOCK_A, k, dg)
        ur = c[k] * Ax + s[k] * Ay  # conj(z_k) A_{k-1}
        ui = c[k] * Ay - s[k] * Ax
        own = h * ui - A[k] * ur
        for i in range(P1):
            own += 2.0 * w * dg[i, k] * Pg[i, k]  # 2 phi' g^T P g'
            fg[i, k] -= V[shape_row(P1, BLOCK_A, i, 0), k] * ui - w * w * Pg[i, k]
        fp[k] -= own
        Xr = w * (w * h + 2.0 * Ad)
        Xi = w * w * A[k]
        rod[k, 0] = ml[k] * Ax - (c[k] * Xr - s[k] * Xi)
        rod[k, 1] = ml[k] * Ay - (s[k] * Xr + c[k] * Xi)
        Ax -= l[k] * w * w * c[k]
        Ay -= l[k] * w * w * s[k]
        node[k, 0] = Ax
        node[k, 1] = Ay
    Tx = 0.0  # inertia of everything beyond node j: sum_{k>j} (rod_k + mu_k A_k)
    Ty = 0.0
    for j in range(n - 1, -1, -1):
        Fx = mu[j] * node[j, 0] + Tx
        Fy = mu[j] * node[j, 1] + Ty
        fp[j] -= l[j] * (c[j] * Fy - s[j] * Fx)
        Tx = Fx + rod[j, 0]
        Ty = Fy + rod[j, 1]


@njit(cache=True)
def ladder_forces(V: Arr, y: Arr, geo: Geometry, loads: Loads, damped: bool, f: Arr) -> None:
    """f = [Q; 0] + A^T Tq - dPi/dq - C q' - c(q, q') (N m) into the rows f (p+2, n: phi,
    then g), ``geo`` the ``ladder_geometry`` at q; ``loads`` = (has_load, SX, SY, Tq)
    (``kernels.Loads``), Tq the hinge moments (N m, n, or empty for none) on the rows the
    hinge springs act on (phi, alpha, beta: ``kernels.hinge_moments_into``). O(n p^2)."""
    c, s, g, A, Pg = geo
    has_load, SX, SY, Tq = loads
    n = c.shape[0]
    P1 = g.shape[0]
    N = n * (P1 + 1)
    q, v = y[:N], y[N:]
    dg = v[n:].reshape((P1, n))
    fp, fg = f[0], f[1:]
    f[:] = 0.0
    hinge_forces(V, q[:n], g[0], g[1], V_KAPPA, fp, f[1], f[2])
    if damped:
        hinge_forces(V, v[:n], dg[0], dg[1], V_NU, fp, f[1], f[2])
    for k in range(n):
        _block_times(V, P1, BLOCK_K, k, g, fg, 1.0)
        if damped:
            _block_times(V, P1, BLOCK_C, k, dg, fg, 1.0)
    f *= -1.0
    _velocity_terms(V, c, s, v[:n], dg, A, Pg, fp, fg)
    if has_load:
        load_moments(V, c, s, SX, SY, fp)
    hinge_moments_into(Tq, f)


@njit(cache=True)
def ladder_solve(V: Arr, geo: Geometry, f: Arr, out: Arr) -> None:
    """q'' = M(q)^-1 f (the rows f = [fp; fg]) into ``out`` (N), O(n p^2): per rod x_g = P^-1
    (f_g - M_gp x_p), the Schur complement (``kernels.schur_generators``, with exact
    kinematics raised by g^T P g on the diagonal and by the bending first moment A = a . g in
    the generators: M_pp[k, j] = l_j (l_k M_k c_kj - A_k s_kj), k > j) solved in generator
    form; ``geo`` the ``ladder_geometry`` at q."""
    c, s, g, A, Pg = geo
    fp, fg = f[0], f[1:]
    n = c.shape[0]
    P1 = fg.shape[0]
    G = np.zeros((P1, n))
    r = fp.copy()
    aG = np.empty(n)
    for k in range(n):
        _block_times(V, P1, BLOCK_PINV, k, fg, G, 1.0)
        aG[k] = shape_dot(V, P1, BLOCK_A, k, G)
        r[k] -= shape_dot(V, P1, BLOCK_B, k, G)
    upper_times(V, c, s, aG, True, r, -1.0)  # V_W = 1: sum_{j>k} l_k c_kj a_j . G_j
    d, a, b, e = schur_generators(V, c, s)
    if V[LV_EXACT, 0] != 0.0:
        for k in range(n):
            for i in range(P1):
                d[k] += g[i, k] * Pg[i, k]
            a[k, 0] -= A[k] * s[k]
            a[k, 1] += A[k] * c[k]
            e[k, 0] -= A[k] * s[k]
            e[k, 1] += A[k] * c[k]
    xp = out[:n]
    generator_solve(d, a, b, e, r, xp)
    ut = np.zeros(n)
    upper_t_times(V, c, s, xp, True, ut, 1.0)  # sum_{j<k} l_j c_kj x_j
    rg = np.empty((P1, n))
    for k in range(n):
        for i in range(P1):
            rg[i, k] = (
                fg[i, k]
                - V[shape_row(P1, BLOCK_A, i, 0), k] * ut[k]
                - V[shape_row(P1, BLOCK_B, i, 0), k] * xp[k]
            )
    xg = out[n:].reshape((P1, n))
    xg[:] = 0.0
    for k in range(n):
        _block_times(V, P1, BLOCK_PINV, k, rg, xg, 1.0)


@njit(cache=True)
def shape_count(V: Arr) -> int:
    """p + 1: the shapes per rod of V's rung."""
    return int(V[LV_P1, 0])


@njit(cache=True)
def ladder_accel(V: Arr, y: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """Accelerations q'' (N) of the ladder at y = [q; q'] into ``out``; ``loads`` the load
    suffix sums (N) and the hinge moments (N m, empty for none) (``kernels.Loads``). O(n p^2)
    time, O(n p) memory."""
    geo = ladder_geometry(V, y)
    f = np.empty((shape_count(V) + 1, V.shape[1]))
    ladder_forces(V, y, geo, loads, damped, f)
    ladder_solve(V, geo, f, out)


@njit(cache=True)
def ladder_unit_responses(V: Arr, q: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M(q)^-1 a_{locks[j]} (N each), O(n p^2) per hinge."""
    geo = ladder_geometry(V, q)
    f = np.empty((shape_count(V) + 1, V.shape[1]))
    for j in range(locks.shape[0]):
        f[:] = 0.0
        unit_moment(locks[j], f)
        ladder_solve(V, geo, f, U[j])


@njit(cache=True)
def ladder_accel_locked(
    V: Arr, y: Arr, loads: Loads, damped: bool, locks: Ints, out: Arr, lam: Arr
) -> None:
    """q'' (N) with the hinges ``locks`` held into ``out``, their multipliers (N m) into
    ``lam`` (``deployment.superpose``: the hinge moments Tq act in the free accelerations, so
    a held hinge's multiplier holds its motor too); O(n p^2 m)."""
    ladder_accel(V, y, loads, damped, out)
    if locks.shape[0] > 0:
        U = np.empty((locks.shape[0], out.shape[0]))
        ladder_unit_responses(V, y[: out.shape[0]], locks, U)
        superpose(out, U, locks, V.shape[1], lam)


@njit(cache=True)
def ladder_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the ladder (compiled integrators' right-hand side, loads and hinge moments from
    table L: ``kernels.hinge_moments_at`` on the hinge rates a_k q' its dampers see)."""
    ladder_accel(P, y, rhs_start(t, y, P, L, out), S[0] != 0.0, out[y.shape[0] // 2 :])


@njit(cache=True)
def ladder_rhs_locked(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the ladder with the hinges of S held (``deployment.lock_scalars``)."""
    loads, locks, lam = locked_head(t, y, P, S, L, out)
    ladder_accel_locked(P, y, loads, S[0] != 0.0, locks, out[y.shape[0] // 2 :], lam)


@njit(cache=True)
def ladder_kinetic(V: Arr, y: Arr) -> float:
    """T = 1/2 int |r'|^2 dm + 1/2 sum mu_k |v_k|^2 (J) of the ladder's velocity field
    (first-order kinematics: the terms in g dropped, as in its mass matrix); O(n p^2)."""
    n = V.shape[1]
    P1 = shape_count(V)
    N = n * (P1 + 1)
    q, v = y[:N], y[N:]
    g = q[n:].reshape((P1, n))
    dg = v[n:].reshape((P1, n))
    A, Pg = bending_sums(V, g)
    l, ml, mu = V[V_L], V[LV_MASS], V[LV_MU]
    T = 0.0
    Vx = 0.0  # velocity of node k-1
    Vy = 0.0
    for k in range(n):
        c = np.cos(q[k])
        s = np.sin(q[k])
        w = v[k]
        Wr = w * 0.5 * ml[k] * l[k] + shape_dot(V, P1, BLOCK_A, k, dg)  # int m (s phi' + eta')
        Wi = w * A[k]  # int m eta phi'
        J = w * w * ml[k] * l[k] * l[k] / 3.0 + 2.0 * w * shape_dot(V, P1, BLOCK_B, k, dg)
        J += _quadratic(V, P1, BLOCK_P, k, dg, dg)
        for i in range(P1):
            J += w * w * g[i, k] * Pg[i, k]  # phi'^2 g^T P g (exact kinematics)
        T += 0.5 * ml[k] * (Vx * Vx + Vy * Vy) + 0.5 * J
        T += Vx * -(s * Wr + c * Wi) + Vy * (c * Wr - s * Wi)
        Vx -= l[k] * w * s
        Vy += l[k] * w * c
        T += 0.5 * mu[k] * (Vx * Vx + Vy * Vy)
    return float(T)


@njit(cache=True)
def ladder_damper_power(V: Arr, S: Arr, y: Arr) -> float:
    """The dampers' power (W): the hinges' sum nu (dD/dt)^2 plus every rod's g'^T C g';
    0 unless S[0] (the damped flag). O(n p^2)."""
    n = V.shape[1]
    P1 = shape_count(V)
    v = y[y.shape[0] // 2 :]
    dg = v[n:].reshape((P1, n))
    power = compiled_damper_power(V, S, v[:n], dg[0], dg[1])  # V_CB = 0: the hinges only
    if S[0] != 0.0:
        for k in range(n):
            power += _quadratic(V, P1, BLOCK_C, k, dg, dg)
    return power


@njit(cache=True)
def ladder_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) of the ladder into out[:3]: ``ladder_kinetic`` (J), the external
    power (W: the loads' and the hinge moments' sum Tq_k dD_k/dt, ``kernels.external_power``)
    and the dampers' power: hinges sum nu (dD/dt)^2 plus the rods' g'^T C g' (W; 0 unless
    S[0], the damped flag). O(n p^2)."""
    n = P.shape[1]
    phi, v = y[:n], y[y.shape[0] // 2 :]
    out[0] = ladder_kinetic(P, y)
    out[1] = external_power(P, np.cos(phi), np.sin(phi), v, L, t)
    out[2] = ladder_damper_power(P, S, y)
