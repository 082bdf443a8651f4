"""Compiled kernels of the moving bases on every ladder rung (any shapes p, first-order or exact
kinematics, ``ladder_kernels``): a free body (docs/base.md) and a prescribed motion.

The chain is the ladder's, q = [phi; g_0 (= alpha); g_1 (= beta); g_2 ..; g_p] (N = n (p + 2)),
hanging from node 0 at r_0 = r_c + rho, rho = R(theta) h (h: the hinge offset in the body
frame). Its first mass moment about node 0 is, on every rung (the nodes are exact and the
bending first moment A_k = a_k . g_k is linear in g),

    S = sum_k [l_k M_k e_k + A_k n_k]   (M_k = ``outer_mass``; e_k, n_k the chord's unit vectors),

J_S = dS/dq: dS/dphi_k = l_k M_k n_k - A_k e_k, dS/dg_ki = a_ki n_k, and S'' = J_S q'' + s_2 with
s_2 = -sum_k [(l_k M_k phi_k'^2 + 2 A_k' phi_k') e_k + A_k phi_k'^2 n_k]. (On the paper's rung
A_k = w_k (alpha_k - beta_k): ``free_base`` is this module's p = 1, first-order case.)

* **Free body** (state [q; x_c, y_c, theta; q'; ...], 2 (N + 3)): Lagrange's equations are
  ``free_base``'s with the ladder's pinned chain in place of the paper's: M_c q'' + J_S^T a_0 =
  f_c, M a_0 + S'' + m_b a_c = F, J theta'' + rho_perp . (M a_0 + S'') = T_0 + rho_perp . F.
  The chain is eliminated by three O(n p^2) ladder solves and a 3 x 3 Schur complement.
* **Prescribed motion** (a free body's state, the body's accelerations the laws' r_c''(t),
  theta''(t), from the compiled form's M[0], ``rodval.core.base.motion_table``; its x_c, y_c,
  theta follow the laws to the integration's tolerance): M_c q'' = f_c - J_S^T a_0, a_0 = a_c
  + theta'' rho_perp - theta'^2 rho, hinge 0 measured from theta. The base's force on the chain at
  node 0 is F_d = M a_0 + S'' - F, and the moment it passes through hinge 0 is m_1 = lambda_0 -
  T_0 (lambda_0: hinge 0's multiplier when held; T_0 with -Tq_0, a motor's reaction); their
  power F_d . v_0 + m_1 theta' is the drive's, booked as external in the energy audit.

Hinge moments (motors, rate dampers; Tq, N m) act on the chain as A^T Tq (``ladder_forces``)
at the hinge rates a_k q', hinge 0's measured from theta' (``free_base.rhs_torques``); the
body (or the drive) takes hinge 0's reaction -Tq_0, and their power sum_k Tq_k dD_k/dt is
external work in the audit.

V is the ladder's (``ladder.ladder_constants``) with ``free_base.BODY_ROWS`` rows appended: the
body's mass (kg) and inertia (kg m^2) (zero for a prescribed base), the hinge offset h (m) and
the chain's mass M (kg), each the same in every column. Cost per evaluation O(n p^2): three ladder
solves for a free body, one for a prescribed motion (m more with m hinges held).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.core.load_table import load_sums
from rodval.core.motion import motion_at
from rodval.models.assembly.kernels import (
    V_KAPPA,
    V_L,
    V_NU,
    V_OUTER,
    Arr,
    Loads,
    Pair,
    load_power,
    rhs_start,
    torque_power,
)
from rodval.models.base.free_base import (
    BODY_INERTIA,
    BODY_MASS,
    CHAIN_MASS,
    body_accelerations,
    body_value,
    chain_state,
    hinge0_moment,
    offset_vector,
    rhs_torques,
)
from rodval.models.hinge_items.deployment import (
    Ints,
    held_hinges,
    hinge_events,
    locked_head,
    superpose,
    unit_moment,
)
from rodval.models.kinematics.ladder_kernels import (
    BLOCK_A,
    Geometry,
    ladder_damper_power,
    ladder_forces,
    ladder_geometry,
    ladder_kinetic,
    ladder_solve,
    ladder_unit_responses,
    shape_count,
    shape_dot,
    shape_row,
)

#: The chain at [q; q']: its ``ladder_geometry``, the rods' bending first moments A and their
#: rates (``chain_parts``).
Parts = tuple[Geometry, Arr, Arr]


@njit(cache=True)
def chain_size(V: Arr) -> tuple[int, int, int]:
    """(n, p + 1, N): rods, shapes per rod and chain coordinates of V's rung."""
    n = V.shape[1]
    P1 = shape_count(V)
    return n, P1, n * (P1 + 1)


@njit(cache=True)
def first_moments(V: Arr, g: Arr) -> Arr:
    """A_k = a_k . g_k (kg m per unit of g) of every rod, (n,); O(n p)."""
    P1, n = g.shape
    A = np.empty(n)
    for k in range(n):
        A[k] = shape_dot(V, P1, BLOCK_A, k, g)
    return A


@njit(cache=True)
def field_forces(V: Arr, parts: Parts, gx: float, gy: float, f: Arr) -> None:
    """f += J_S^T (gx, gy) on the force rows f (p+2, n) (N m for a field in m/s^2), O(n p)."""
    (c, s, _, _, _), Am, _ = parts
    l, outer = V[V_L], V[V_OUTER]
    P1 = f.shape[0] - 1
    for k in range(c.shape[0]):
        ng = c[k] * gy - s[k] * gx
        eg = c[k] * gx + s[k] * gy
        f[0, k] += l[k] * outer[k] * ng - Am[k] * eg
        for i in range(P1):
            f[1 + i, k] += V[shape_row(P1, BLOCK_A, i, 0), k] * ng


@njit(cache=True)
def first_moment_rate(V: Arr, parts: Parts, x: Arr) -> tuple[float, float]:
    """J_S x (kg m/s for rates x = [xp; xg; ..], N read), O(n p)."""
    (c, s, _, _, _), Am, _ = parts
    n, P1, N = chain_size(V)
    xp, xg = x[:n], x[n:N].reshape((P1, n))
    l, outer = V[V_L], V[V_OUTER]
    sx = 0.0
    sy = 0.0
    for k in range(n):
        a = l[k] * outer[k] * xp[k] + shape_dot(V, P1, BLOCK_A, k, xg)  # along n_k
        b = -Am[k] * xp[k]  # along e_k
        sx += b * c[k] - a * s[k]
        sy += b * s[k] + a * c[k]
    return sx, sy


@njit(cache=True)
def first_moment_quadratic(V: Arr, parts: Parts, dphi: Arr) -> tuple[float, float]:
    """s_2 = S'' - J_S q'' (kg m/s^2), O(n) (module docstring)."""
    (c, s, _, _, _), Am, dAm = parts
    l, outer = V[V_L], V[V_OUTER]
    sx = 0.0
    sy = 0.0
    for k in range(c.shape[0]):
        w2 = dphi[k] * dphi[k]
        ec = -l[k] * outer[k] * w2 - 2.0 * dAm[k] * dphi[k]
        nc = -Am[k] * w2
        sx += ec * c[k] - nc * s[k]
        sy += ec * s[k] + nc * c[k]
    return sx, sy


@njit(cache=True)
def chain_parts(V: Arr, q: Arr, dq: Arr) -> Parts:
    """(geometry, A, A') of the chain at [q; q'] (N each): its ``ladder_geometry`` (zero
    bending sums with first-order kinematics), the bending first moments A and their rates;
    O(n p^2)."""
    n, P1, N = chain_size(V)
    geo = ladder_geometry(V, q)
    return geo, first_moments(V, geo[2]), first_moments(V, dq[n:N].reshape((P1, n)))


@njit(cache=True)
def chain_forces(
    V: Arr, yc: Arr, parts: Parts, loads: Loads, damped: bool, attitude: tuple[float, float]
) -> Arr:
    """The force rows f (p+2, n) of the pinned ladder at the chain state yc with hinge 0
    measured from the ``attitude`` (theta (rad), theta' (rad/s)); ``loads`` the
    ``kernels.Loads``, Tq the hinge moments (N m, ``free_base.rhs_torques``, or empty: A^T Tq
    on the chain). O(n p^2)."""
    n, P1, N = chain_size(V)
    th, dth = attitude
    f = np.empty((P1 + 1, n))
    ladder_forces(V, yc, parts[0], loads, damped, f)
    shift = V[V_KAPPA, 0] * th + (V[V_NU, 0] * dth if damped else 0.0)
    f[0, 0] += shift  # -kappa_0 (D_0 - theta - rest) on phi_1 and alpha_1
    f[1, 0] += shift
    return f


# ---------------------------------------------------------------------------- free body
@njit(cache=True)
def field_responses(V: Arr, parts: Parts, G: Arr) -> Arr:
    """G[j] = M_c^-1 J_S^T e_j (j = x, y; N each) and K = J_S G (2 x 2, kg); O(n p^2)."""
    n, P1, N = chain_size(V)
    K = np.empty((2, 2))
    f = np.empty((P1 + 1, n))
    for j in range(2):
        f[:] = 0.0
        field_forces(V, parts, 1.0 - j, float(j), f)
        ladder_solve(V, parts[0], f, G[j])
        kx, ky = first_moment_rate(V, parts, G[j])
        K[0, j] = kx
        K[1, j] = ky
    return K


@njit(cache=True)
def body_solve(V: Arr, parts: Parts, th: float, G: Arr, K: Arr, f: Arr, rb: Arr, out: Arr) -> None:
    """x = M_tot^-1 [f; rb] (the bordered mass matrix of chain and body) into ``out`` (N + 3):
    q'' then (a_c (m/s^2), theta'' (rad/s^2)); ``parts`` from ``chain_parts``. O(n p^2)."""
    n, P1, N = chain_size(V)
    u = out[:N]
    ladder_solve(V, parts[0], f, u)
    jx, jy = first_moment_rate(V, parts, u)
    rx, ry = offset_vector(V, th)
    mch, mb, J = body_value(V, CHAIN_MASS), body_value(V, BODY_MASS), body_value(V, BODY_INERTIA)
    xb = body_accelerations(K, rx, ry, mch, mb, J, jx, jy, rb)
    g0 = xb[0] - xb[2] * ry  # a_0 = a_c + theta'' rho_perp
    g1 = xb[1] + xb[2] * rx
    for i in range(N):
        u[i] -= g0 * G[0, i] + g1 * G[1, i]
    for i in range(3):
        out[N + i] = xb[i]


@njit(cache=True)
def free_accel(V: Arr, y: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """Q'' (N + 3) of a ladder rung on a free body at y = [Q; Q'] into ``out``; ``loads`` =
    (has_load, SX, SY, Tq) (``kernels.Loads``): the load suffix sums (N), the hinge moments
    (N m, ``free_base.rhs_torques``: A^T Tq on the chain, -Tq_0 on the body's attitude).
    O(n p^2): three ladder solves."""
    has_load, SX, SY, Tq = loads
    n, P1, N = chain_size(V)
    NQ = N + 3
    yc = chain_state(y, N)
    parts = chain_parts(V, yc[:N], yc[N:])
    th, dth = y[N + 2], y[NQ + N + 2]
    f = chain_forces(V, yc, parts, loads, damped, (th, dth))
    rx, ry = offset_vector(V, th)
    w2 = dth * dth
    field_forces(V, parts, w2 * rx, w2 * ry, f)  # a_0's -theta'^2 rho part
    Fx = SX[0] if has_load else 0.0
    Fy = SY[0] if has_load else 0.0
    qx, qy = first_moment_quadratic(V, parts, yc[N : N + n])
    mch = body_value(V, CHAIN_MASS)
    T0 = hinge0_moment(V, y[0] + y[n] - th, y[NQ] + y[NQ + n] - dth, damped, Tq)
    rb = np.array(
        [
            Fx - qx + mch * w2 * rx,
            Fy - qy + mch * w2 * ry,
            T0 - ry * (Fx - qx) + rx * (Fy - qy),
        ]
    )
    G = np.empty((2, N))
    K = field_responses(V, parts, G)
    body_solve(V, parts, th, G, K, f, rb, out)


@njit(cache=True)
def free_unit_responses(V: Arr, q: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M_tot^-1 a_k (N + 3) for k = locks[j] (hinge 0's row has -1 at theta); only
    the positions Q of ``q`` are read. O(n p^2) per hinge."""
    n, P1, N = chain_size(V)
    parts = chain_parts(V, q[:N], q[:N])
    G = np.empty((2, N))
    K = field_responses(V, parts, G)
    f = np.empty((P1 + 1, n))
    rb = np.zeros(3)
    for j in range(locks.shape[0]):
        f[:] = 0.0
        unit_moment(locks[j], f)
        rb[2] = -1.0 if locks[j] == 0 else 0.0
        body_solve(V, parts, q[N + 2], G, K, f, rb, U[j])


@njit(cache=True)
def free_accel_locked(
    V: Arr, y: Arr, loads: Loads, damped: bool, locks: Ints, out: Arr, lam: Arr
) -> None:
    """Q'' with the hinges ``locks`` held (multipliers into ``lam``, N m; the hinge moments
    of ``loads`` act in the free accelerations, so a held hinge's multiplier holds its motor
    too); O(n p^2 m)."""
    free_accel(V, y, loads, damped, out)
    if locks.shape[0] > 0:
        U = np.empty((locks.shape[0], out.shape[0]))
        free_unit_responses(V, y, locks, U)
        superpose(out, U, locks, V.shape[1], lam, out.shape[0] - 1)


@njit(cache=True)
def free_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of a ladder rung on a free body (compiled integrators' right-hand side)."""
    free_accel(P, y, rhs_start(t, y, P, L, out, True), S[0] != 0.0, out[y.shape[0] // 2 :])


@njit(cache=True)
def free_rhs_locked(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' with the hinges of S held; O(n p^2 m)."""
    loads, locks, lam = locked_head(t, y, P, S, L, out, True)
    free_accel_locked(P, y, loads, S[0] != 0.0, locks, out[y.shape[0] // 2 :], lam)


@njit(cache=True)
def free_hinge_events(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, E: Arr, out: Arr) -> None:
    """Latch and stop events g = D_k - angle, hinge 0 from the body's attitude; O(rows)."""
    n, P1, N = chain_size(P)
    hinge_events(y[:n], y[n : 2 * n], y[2 * n : 3 * n], E, out, y[N + 2])


@njit(cache=True)
def free_root_rates(V: Arr, y: Arr) -> tuple[float, float, float, float]:
    """(v_0x, v_0y (m/s), S'_x, S'_y (kg m/s)) of a free body's state; O(n p)."""
    n, P1, N = chain_size(V)
    NQ = N + 3
    yc = chain_state(y, N)
    jx, jy = first_moment_rate(V, chain_parts(V, yc[:N], yc[N:]), yc[N:])
    rx, ry = offset_vector(V, y[N + 2])
    dth = y[NQ + N + 2]
    return y[NQ + N] - dth * ry, y[NQ + N + 1] + dth * rx, jx, jy


@njit(cache=True)
def free_momentum(V: Arr, y: Arr) -> tuple[float, float]:
    """P = m_b v_c + M v_0 + S' (N s): the whole system's linear momentum; O(n p)."""
    v0x, v0y, jx, jy = free_root_rates(V, y)
    mb, mch = body_value(V, BODY_MASS), body_value(V, CHAIN_MASS)
    return mb * y[-3] + mch * v0x + jx, mb * y[-2] + mch * v0y + jy


@njit(cache=True)
def moving_mechanics(
    t: float,
    yc: Arr,
    V: Arr,
    S: Arr,
    L: Arr,
    rates: tuple[float, float, float, float],
    dth: float,
    out: Arr,
) -> None:
    """(T, P_ext, P_diss) of a ladder chain whose node 0 moves into out[:3], ``rates`` =
    (v_0x, v_0y (m/s), S'_x, S'_y (kg m/s)) (``free_root_rates``): the chain's T with node 0
    at rest (``ladder_kinetic``) + 1/2 M |v_0|^2 + v_0 . S' (J), the loads' power on the
    chain and on node 0's motion (W), the dampers' power with hinge 0's rate from the body's
    theta' (W). O(n p^2)."""
    v0x, v0y, jx, jy = rates
    n, P1, N = chain_size(V)
    mch = body_value(V, CHAIN_MASS)
    out[0] = ladder_kinetic(V, yc) + 0.5 * mch * (v0x * v0x + v0y * v0y) + v0x * jx + v0y * jy
    out[1] = load_power(V, np.cos(yc[:n]), np.sin(yc[:n]), yc[N : N + n], L, t)
    SX = np.empty(n)
    SY = np.empty(n)
    if load_sums(L, t, SX, SY):
        out[1] += SX[0] * v0x + SY[0] * v0y
    out[2] = ladder_damper_power(V, S, yc)
    if S[0] != 0.0:
        r = yc[N] + yc[N + n]
        out[2] += V[V_NU, 0] * ((r - dth) ** 2 - r * r)


@njit(cache=True)
def free_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) of a ladder rung on a free body into out[:3] (``moving_mechanics``
    plus the body's 1/2 m_b |v_c|^2 + 1/2 J theta'^2 and the hinge moments' power sum_k Tq_k
    dD_k/dt, hinge 0's rate from the body, W). O(n p^2)."""
    n, P1, N = chain_size(P)
    NQ = N + 3
    dth = y[NQ + N + 2]
    moving_mechanics(t, chain_state(y, N), P, S, L, free_root_rates(P, y), dth, out)
    out[1] += torque_power(*rhs_torques(t, y, P, L))
    vc2 = y[NQ + N] ** 2 + y[NQ + N + 1] ** 2
    out[0] += 0.5 * (body_value(P, BODY_MASS) * vc2 + body_value(P, BODY_INERTIA) * dth * dth)


# ---------------------------------------------------------------------- prescribed motion
@njit(cache=True)
def prescribed_accel(V: Arr, y: Arr, mo: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """Q'' (N + 3) of a ladder rung on a prescribed base at y = [Q; Q'] into ``out``: the
    body's accelerations are the laws' (``mo``: ``loads.motion_at`` at t), the chain's solve
    M_c q'' = f_c - J_S^T a_0 with a_0 = a_c + theta'' rho_perp - theta'^2 rho (theta, theta'
    from the state, which follows the laws; ``loads`` the ``kernels.Loads``, Tq the hinge
    moments, N m, on the chain). O(n p^2): one ladder solve."""
    n, P1, N = chain_size(V)
    NQ = N + 3
    yc = chain_state(y, N)
    parts = chain_parts(V, yc[:N], yc[N:])
    th, dth, ddth = y[N + 2], y[NQ + N + 2], mo[2, 2]
    f = chain_forces(V, yc, parts, loads, damped, (th, dth))
    rx, ry = offset_vector(V, th)
    ax = mo[0, 2] - ddth * ry - dth * dth * rx
    ay = mo[1, 2] + ddth * rx - dth * dth * ry
    field_forces(V, parts, -ax, -ay, f)
    ladder_solve(V, parts[0], f, out[:N])
    out[N] = mo[0, 2]
    out[N + 1] = mo[1, 2]
    out[N + 2] = ddth


@njit(cache=True)
def prescribed_unit_responses(V: Arr, q: Arr, locks: Ints, U: Arr) -> None:
    """U[j] = M_c^-1 a_k (N + 3, the body's entries zero: its motion is prescribed) for k =
    locks[j]; only the positions are read. O(n p^2) per hinge."""
    N = chain_size(V)[2]
    Uc = np.empty((locks.shape[0], N))
    ladder_unit_responses(V, q[:N], locks, Uc)
    U[:, :] = 0.0
    U[:, :N] = Uc


@njit(cache=True)
def prescribed_accel_locked(
    V: Arr, y: Arr, mo: Arr, loads: Loads, damped: bool, locks: Ints, out: Pair
) -> None:
    """Q'' with the hinges ``locks`` held and their multipliers (N m) into out = (Q'', lam);
    hinge 0's row has -1 at theta, whose acceleration is the law's, so it holds D_0 = phi_1 +
    alpha_1 - theta(t). O(n p^2 m)."""
    acc, lam = out
    prescribed_accel(V, y, mo, loads, damped, acc)
    if locks.shape[0] > 0:
        U = np.empty((locks.shape[0], acc.shape[0]))
        prescribed_unit_responses(V, y, locks, U)
        superpose(acc, U, locks, V.shape[1], lam, acc.shape[0] - 1)


@njit(cache=True)
def prescribed_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of a ladder rung on a prescribed base (its laws in M[0]); the held hinges of S."""
    loads = rhs_start(t, y, P, L, out, True)
    locks = held_hinges(S)[0]
    acc = (out[y.shape[0] // 2 :], np.empty(locks.shape[0]))
    prescribed_accel_locked(P, y, motion_at(M[0], t), loads, S[0] != 0.0, locks, acc)


@njit(cache=True)
def drive(V: Arr, y: Arr, mo: Arr, S: Arr, L: Arr, t: float) -> tuple[float, float, float]:
    """(F_dx, F_dy (N), m_1 (N m)): the base's force on the chain at node 0, F_d = M a_0 + S''
    - F, and the moment it passes through hinge 0, m_1 = lambda_0 - T_0 (T_0 with the hinge
    moment's reaction -Tq_0, ``hinge0_moment``), in the mode of S (its held hinges).
    O(n p^2 m)."""
    n, P1, N = chain_size(V)
    NQ = N + 3
    SX = np.zeros(n)  # left zero when no load acts
    SY = np.zeros(n)
    Tq = rhs_torques(t, y, V, L)[0]
    damped = S[0] != 0.0
    locks = held_hinges(S)[0]
    lam = np.zeros(locks.shape[0])
    acc = np.empty(N + 3)
    loads = (bool(load_sums(L, t, SX, SY)), SX, SY, Tq)
    prescribed_accel_locked(V, y, mo, loads, damped, locks, (acc, lam))
    yc = chain_state(y, N)
    parts = chain_parts(V, yc[:N], yc[N:])
    jx, jy = first_moment_rate(V, parts, acc)
    qx, qy = first_moment_quadratic(V, parts, yc[N : N + n])
    th, dth, ddth = y[N + 2], y[NQ + N + 2], mo[2, 2]
    rx, ry = offset_vector(V, th)
    mch = body_value(V, CHAIN_MASS)
    Fx = mch * (mo[0, 2] - ddth * ry - dth * dth * rx) + jx + qx - SX[0]
    Fy = mch * (mo[1, 2] + ddth * rx - dth * dth * ry) + jy + qy - SY[0]
    m1 = -hinge0_moment(V, y[0] + y[n] - th, y[NQ] + y[NQ + n] - dth, damped, Tq)
    for j in range(locks.shape[0]):
        if locks[j] == 0:
            m1 += lam[j]
    return Fx, Fy, m1


@njit(cache=True)
def prescribed_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) of a ladder rung on a prescribed base into out[:3]
    (``free_mechanics`` with a massless body); P_ext includes the drive's power F_d . v_0 +
    m_1 theta' (``drive``). O(n p^2 m)."""
    free_mechanics(t, y, P, S, M, L, out)
    Fx, Fy, m1 = drive(P, y, motion_at(M[0], t), S, L, t)
    v0x, v0y, jx, jy = free_root_rates(P, y)
    out[1] += Fx * v0x + Fy * v0y + m1 * y[-1]
