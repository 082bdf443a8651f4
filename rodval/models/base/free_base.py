"""Compiled kernels of the full model on a free base (a rigid body node 0 belongs to; docs/base.md).

Coordinates Q = [phi; alpha; beta; x_c, y_c, theta] (3n + 3): the chain's, then the body's
centre of mass (m) and attitude (rad); state y = [Q; Q'].

Kinetic energy, with r_0 = r_c + R(theta) h (node 0, h = hinge_offset) and rho = R(theta) h,
v_0 = v_c + theta' rho_perp (rho_perp = k x rho = (-rho_y, rho_x)):
T = 1/2 m_b |v_c|^2 + 1/2 J theta'^2 + 1/2 M_ch |v_0|^2 + v_0 . S' + T_chain(q, q'), with S the
chain's first mass moment about node 0, S = sum_k [l_k M_k e_k + w_k (alpha_k - beta_k) n_k]
(M_k = ``outer_mass``, w_k = m_k l_k^2 / 12 = int m sigma ds; e_k, n_k the chord's unit
vectors), J_S = dS/dq, and T_chain the pinned chain's kinetic energy. Lagrange's equations:

* chain: M_c q'' + J_S^T a_0 = f_c (the pinned chain's forces, hinge 0 measured from the body:
  D_0 = phi_1 + alpha_1 - theta; the hinge moments of motors and rate dampers, A^T Tq, with
  their rates a_k q', hinge 0's minus theta'), a_0 = a_c + theta'' rho_perp - theta'^2 rho;
* translation: M_ch a_0 + S'' + m_b a_c = F (the loads' resultant), S'' = J_S q'' + s_2(q, q');
* attitude: J theta'' + rho_perp . (M_ch a_0 + S'') = T_0 + rho_perp . F, T_0 the moment of
  hinge 0 (spring, damper, acting stops, and -Tq_0: a hinge moment's reaction) on the body.

The translation equation is d P / dt = F for P = m_b v_c + M_ch v_0 + S', whatever the chain's
kinematics: the linear momentum is kept exactly. The total mass matrix is bordered,
[[M_c, J_S^T E], [E^T J_S, D]] with E = [I_2, rho_perp]; it is solved by eliminating the chain
(``full_solve``, O(n)): q'' = u - G E x_b with u = M_c^-1 r_c, G = M_c^-1 J_S^T (two more
O(n) solves) and the 3 x 3 Schur complement D - E^T (J_S G) E for the body's x_b. O(n) per
evaluation, three chain solves.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.core.load_table import hinge_torques, load_sums
from rodval.models.assembly.kernels import (
    V_KAPPA,
    V_L,
    V_NU,
    V_OUTER,
    V_REST,
    V_W,
    Arr,
    Loads,
    Pair,
    full_forces,
    full_mechanics,
    full_solve,
    hinge_moments_at,
    rhs_start,
)
from rodval.models.hinge_items.deployment import (
    Ints,
    hinge_events,
    locked_head,
    small_solve,
    superpose,
    unit_moment,
)

#: Rows appended to a chain's V (``kernels.full_constants`` here, the ladder's in
#: ``chain_base``), each the same value in every column: the body's mass (kg), inertia
#: (kg m^2), hinge offset x, y (m, body frame) and the chain's mass (kg).
BODY_ROWS = 5
BODY_MASS, BODY_INERTIA, OFFSET_X, OFFSET_Y, CHAIN_MASS = range(BODY_ROWS)
#: (cos phi, sin phi, alpha - beta) of the chain at q: what its first mass moment reads.
Chords = tuple[Arr, Arr, Arr]


@njit(cache=True, inline="always")
def body_value(V: Arr, i: int) -> float:
    """Body row ``i`` (``BODY_MASS`` ..) of V."""
    return float(V[V.shape[0] - BODY_ROWS + i, 0])


@njit(cache=True)
def offset_vector(V: Arr, th: float) -> tuple[float, float]:
    """rho = R(theta) h (m): node 0 from the body's centre of mass."""
    c, s = np.cos(th), np.sin(th)
    hx, hy = body_value(V, OFFSET_X), body_value(V, OFFSET_Y)
    return c * hx - s * hy, s * hx + c * hy


@njit(cache=True)
def chain_state(y: Arr, N: int) -> Arr:
    """[q; q'] of the chain (2N) from a body's state [Q; Q'] (2 (N + 3))."""
    NQ = N + 3
    yc = np.empty(2 * N)
    for i in range(N):  # loops: a slice assignment compiles numba's shape check
        yc[i] = y[i]
        yc[N + i] = y[NQ + i]
    return yc


@njit(cache=True)
def hinge0_moment(V: Arr, D: float, rate: float, damped: bool, Tq: Arr) -> float:
    """T_0 (N m): hinge 0's moment on the body, kappa_0 (D_0 - rest_0) + nu_0 dD_0/dt - Tq_0,
    D_0 = phi_1 + alpha_1 - theta (acting stops in V's kappa, nu, rest; Tq the hinge moments
    driving D up, ``rhs_torques``, or empty)."""
    T = V[V_KAPPA, 0] * (D - V[V_REST, 0])
    if damped:
        T += V[V_NU, 0] * rate
    if Tq.shape[0] > 0:
        T -= Tq[0]
    return float(T)


@njit(cache=True)
def _chords(V: Arr, q: Arr) -> Chords:
    """(cos phi, sin phi, delta = alpha - beta) of the chain at the positions ``q``."""
    n = V.shape[1]
    return np.cos(q[:n]), np.sin(q[:n]), q[n : 2 * n] - q[2 * n : 3 * n]


@njit(cache=True)
def _field_forces(V: Arr, geo: Chords, gx: float, gy: float, f: Arr) -> None:
    """f += J_S^T g (N m for g in m/s^2: the generalized force of a uniform field), O(n):
    dS/dphi_k = l_k M_k n_k - w_k delta_k e_k, dS/dalpha_k = w_k n_k = -dS/dbeta_k, delta =
    alpha - beta."""
    c, s, delta = geo
    l, outer, w = V[V_L], V[V_OUTER], V[V_W]
    for k in range(c.shape[0]):
        ng = c[k] * gy - s[k] * gx
        eg = c[k] * gx + s[k] * gy
        f[0, k] += l[k] * outer[k] * ng - w[k] * delta[k] * eg
        f[1, k] += w[k] * ng
        f[2, k] -= w[k] * ng


@njit(cache=True)
def _first_moment_rate(V: Arr, geo: Chords, x: Arr) -> tuple[float, float]:
    """J_S x (kg m/s for rates x): the first moment's rate along x = [xp; xa; xb; ..], O(n)."""
    c, s, delta = geo
    n = c.shape[0]
    xp, xa, xb = x[:n], x[n : 2 * n], x[2 * n : 3 * n]
    l, outer, w = V[V_L], V[V_OUTER], V[V_W]
    sx = 0.0
    sy = 0.0
    for k in range(n):
        a = l[k] * outer[k] * xp[k] + w[k] * (xa[k] - xb[k])  # along n_k
        b = -w[k] * delta[k] * xp[k]  # along e_k
        sx += b * c[k] - a * s[k]
        sy += b * s[k] + a * c[k]
    return sx, sy


@njit(cache=True)
def _first_moment_quadratic(V: Arr, geo: Chords, ddelta: Arr, dphi: Arr) -> tuple[float, float]:
    """s_2 = S'' - J_S q'' (kg m/s^2): -l M phi'^2 e - 2 w delta' phi' e - w delta phi'^2 n
    summed over the rods, O(n)."""
    c, s, delta = geo
    l, outer, w = V[V_L], V[V_OUTER], V[V_W]
    sx = 0.0
    sy = 0.0
    for k in range(c.shape[0]):
        w2 = dphi[k] * dphi[k]
        ec = -l[k] * outer[k] * w2 - 2.0 * w[k] * ddelta[k] * dphi[k]
        nc = -w[k] * delta[k] * w2
        sx += ec * c[k] - nc * s[k]
        sy += ec * s[k] + nc * c[k]
    return sx, sy


@njit(cache=True)
def field_responses(V: Arr, geo: Chords, G: Arr) -> Arr:
    """G[j] = M_c^-1 J_S^T e_j (j = x, y; 3n each) and K = J_S G (2 x 2, kg); O(n)."""
    c, s, _ = geo
    f = np.empty((3, c.shape[0]))
    K = np.empty((2, 2))
    for j in range(2):
        f[:] = 0.0
        _field_forces(V, geo, 1.0 - j, float(j), f)
        full_solve(V, c, s, f, G[j])
        kx, ky = _first_moment_rate(V, geo, G[j])
        K[0, j] = kx
        K[1, j] = ky
    return K


@njit(cache=True)
def body_accelerations(
    K: Arr, rx: float, ry: float, mch: float, mb: float, J: float, jx: float, jy: float, rb: Arr
) -> Arr:
    """(a_c (m/s^2, 2), theta'' (rad/s^2)) of the body: the 3 x 3 Schur complement D - E^T K E
    of the bordered mass matrix (E = [I, rho_perp], K = J_S M_c^-1 J_S^T, kg; rho = (rx, ry) m;
    chain mass mch, body mass mb (kg), inertia J (kg m^2)) solved against rb - E^T (jx, jy)
    (rb: the body's forces, N and N m; (jx, jy) = J_S u of the chain's free accelerations u),
    by loops (no BLAS call: the same digits everywhere). Every rung's free body uses it."""
    px, py = -ry, rx  # rho_perp
    mt = mch + mb
    E = np.array([[1.0, 0.0, px], [0.0, 1.0, py]])
    Sig = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            acc = 0.0
            for i in range(2):
                for j in range(2):
                    acc += E[i, a] * K[i, j] * E[j, b]
            Sig[a, b] = -acc
    Sig[0, 0] += mt
    Sig[1, 1] += mt
    Sig[0, 2] += mch * px
    Sig[2, 0] += mch * px
    Sig[1, 2] += mch * py
    Sig[2, 1] += mch * py
    Sig[2, 2] += J + mch * (rx * rx + ry * ry)
    r = np.array([rb[0] - jx, rb[1] - jy, rb[2] - px * jx - py * jy])
    return small_solve(Sig, r)


@njit(cache=True)
def base_solve(V: Arr, geo: Chords, th: float, G: Arr, K: Arr, f: Arr, rb: Arr, out: Arr) -> None:
    """x = M_tot^-1 [f; rb] (the bordered total mass matrix, module docstring; f the chain's
    force rows (3, n)) into ``out`` (3n + 3): q'' then (a_c (m/s^2), theta'' (rad/s^2)). O(n)."""
    c, s, _ = geo
    n = c.shape[0]
    u = out[: 3 * n]
    full_solve(V, c, s, f, u)
    jx, jy = _first_moment_rate(V, geo, u)
    rx, ry = offset_vector(V, th)
    mch, mb, J = body_value(V, CHAIN_MASS), body_value(V, BODY_MASS), body_value(V, BODY_INERTIA)
    xb = body_accelerations(K, rx, ry, mch, mb, J, jx, jy, rb)
    g0 = xb[0] - xb[2] * ry  # a_0 = a_c + theta'' rho_perp, rho_perp = (-ry, rx)
    g1 = xb[1] + xb[2] * rx
    for i in range(3 * n):
        u[i] -= g0 * G[0, i] + g1 * G[1, i]
    for i in range(3):  # a loop: a slice assignment compiles numba's shape check
        out[3 * n + i] = xb[i]


@njit(cache=True)
def base_accel(V: Arr, y: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """Q'' (3n + 3) of the full model on a free base at y = [Q; Q'] into ``out`` (module
    docstring); ``loads`` = (has_load, SX, SY, Tq) (``kernels.Loads``): the load suffix sums
    (N), the hinge moments (N m, ``rhs_torques``: A^T Tq on the chain, -Tq_0 on the body's
    attitude). O(n): three chain solves."""
    has_load, SX, SY, Tq = loads
    n = V.shape[1]
    N = 3 * n + 3
    geo = _chords(V, y)
    ddelta = y[N + n : N + 2 * n] - y[N + 2 * n : N + 3 * n]
    th, dth = y[3 * n + 2], y[N + 3 * n + 2]
    f = np.empty((3, n))
    full_forces(V, chain_state(y, 3 * n), geo[0], geo[1], loads, damped, f)
    shift = V[V_KAPPA, 0] * th + (V[V_NU, 0] * dth if damped else 0.0)
    f[0, 0] += shift  # hinge 0 measured from the body: D_0 - theta
    f[1, 0] += shift
    rx, ry = offset_vector(V, th)
    w2 = dth * dth
    _field_forces(V, geo, w2 * rx, w2 * ry, f)  # a_0's -theta'^2 rho part
    Fx = SX[0] if has_load else 0.0
    Fy = SY[0] if has_load else 0.0
    qx, qy = _first_moment_quadratic(V, geo, ddelta, y[N : N + n])
    mch = body_value(V, CHAIN_MASS)
    tx = Fx - qx + mch * w2 * rx
    ty = Fy - qy + mch * w2 * ry
    T0 = hinge0_moment(V, y[0] + y[n] - th, y[N] + y[N + n] - dth, damped, Tq)
    rb = np.array([tx, ty, T0 - ry * (Fx - qx) + rx * (Fy - qy)])
    G = np.empty((2, 3 * n))
    K = field_responses(V, geo, G)
    base_solve(V, geo, th, G, K, f, rb, out)


@njit(cache=True)
def base_unit_responses(V: Arr, y: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M_tot^-1 a_k^T (3n + 3) for k = locks[j]: a unit moment at hinge k (on the body
    as well for k = 0: its row has -1 at theta). O(n) per hinge."""
    n = V.shape[1]
    geo = _chords(V, y)
    G = np.empty((2, 3 * n))
    K = field_responses(V, geo, G)
    f = np.empty((3, n))
    rb = np.zeros(3)
    for j in range(locks.shape[0]):
        f[:] = 0.0
        unit_moment(locks[j], f)
        rb[2] = -1.0 if locks[j] == 0 else 0.0
        base_solve(V, geo, y[3 * n + 2], G, K, f, rb, U[j])


@njit(cache=True)
def base_accel_locked(
    V: Arr, y: Arr, loads: Loads, damped: bool, locks: Ints, out: Arr, lam: Arr
) -> None:
    """Q'' with the hinges ``locks`` held (multipliers into ``lam``, N m); O(n m)."""
    n = V.shape[1]
    base_accel(V, y, loads, damped, out)
    m = locks.shape[0]
    if m == 0:
        return
    U = np.empty((m, 3 * n + 3))
    base_unit_responses(V, y, locks, U)
    superpose(out, U, locks, n, lam, 3 * n + 2)


@njit(cache=True)
def rhs_torques(t: float, y: Arr, P: Arr, L: Arr) -> Pair:
    """(Tq, rates) at t of a body's state y = [Q; Q'] (the chain's [phi; alpha; beta; ..]
    first in Q, the attitude theta last): the hinge moments of L's hinge rows (N m, positive
    driving D_k up; ``loads.applied_torques``) at the hinge rates a_k Q' (rad/s), hinge 0's
    from the body's theta'; both empty when no hinge row acts at t (``kernels.
    hinge_moments_at`` with hinge 0 from the body). O(n)."""
    half = y.shape[0] // 2
    return hinge_moments_at(L, t, y[half:], P.shape[1], half - 1)


@njit(cache=True)
def base_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the full model on a free base (compiled integrators' right-hand side)."""
    loads = rhs_start(t, y, P, L, out, True)
    base_accel(P, y, loads, S[0] != 0.0, out[3 * P.shape[1] + 3 :])


@njit(cache=True)
def base_rhs_locked(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' with the hinges of S held (``deployment.lock_scalars``); O(n m)."""
    loads, locks, lam = locked_head(t, y, P, S, L, out, True)
    base_accel_locked(P, y, loads, S[0] != 0.0, locks, out[3 * P.shape[1] + 3 :], lam)


@njit(cache=True)
def base_hinge_events(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, E: Arr, out: Arr) -> None:
    """Latch and stop events g = D_k - angle, hinge 0 from the body's attitude; O(rows)."""
    n = P.shape[1]
    hinge_events(y[:n], y[n : 2 * n], y[2 * n : 3 * n], E, out, y[3 * n + 2])


@njit(cache=True)
def _root_rates(V: Arr, y: Arr) -> tuple[float, float, float, float]:
    """(v_0 (m/s), S' (kg m/s)) at y = [Q; Q']: node 0's velocity v_c + theta' k x rho and the
    rate of the chain's first mass moment about it, J_S q'; O(n)."""
    n = V.shape[1]
    v = y[3 * n + 3 :]
    jx, jy = _first_moment_rate(V, _chords(V, y), v)
    rx, ry = offset_vector(V, y[3 * n + 2])
    dth = v[3 * n + 2]
    return v[3 * n] - dth * ry, v[3 * n + 1] + dth * rx, jx, jy


@njit(cache=True)
def momentum(V: Arr, y: Arr) -> tuple[float, float]:
    """P = m_b v_c + M_ch v_0 + S' (N s): the whole system's linear momentum; O(n)."""
    vc = y[-3:-1]  # the body's velocity: Q' ends with x_c', y_c', theta'
    v0x, v0y, jx, jy = _root_rates(V, y)
    mb, mch = body_value(V, BODY_MASS), body_value(V, CHAIN_MASS)
    return mb * vc[0] + mch * v0x + jx, mb * vc[1] + mch * v0y + jy


@njit(cache=True)
def base_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) into out[:3]: T (J) the whole system's kinetic energy (module
    docstring), P_ext = Q . phi' + F . v_0 + sum_k Tq_k dD_k/dt (W), P_diss the dampers' power
    (W), hinge 0's rate from the body. O(n)."""
    n = P.shape[1]
    v = y[3 * n + 3 :]
    full_mechanics(t, chain_state(y, 3 * n), P, S, M, L, out)
    dth = v[3 * n + 2]
    v0x, v0y, jx, jy = _root_rates(P, y)
    mb, mch = body_value(P, BODY_MASS), body_value(P, CHAIN_MASS)
    vc2 = v[3 * n] ** 2 + v[3 * n + 1] ** 2
    out[0] += 0.5 * (
        mb * vc2 + body_value(P, BODY_INERTIA) * dth * dth + mch * (v0x * v0x + v0y * v0y)
    )
    out[0] += v0x * jx + v0y * jy
    SX = np.empty(n)
    SY = np.empty(n)
    if load_sums(L, t, SX, SY):
        out[1] += SX[0] * v0x + SY[0] * v0y
    r = v[0] + v[n]  # hinge 0's rate from a pin, as full_mechanics books it
    T, C = hinge_torques(L, t, n)
    if T.shape[0] > 0:  # hinge 0's moment power from the body in place of the pin's
        out[1] += (T[0] - C[0] * (r - dth)) * (r - dth) - (T[0] - C[0] * r) * r
    if S[0] != 0.0:
        out[2] += P[V_NU, 0] * ((r - dth) ** 2 - r * r)
