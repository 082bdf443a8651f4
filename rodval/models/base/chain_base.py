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
  T_0 (lambda_0: hinge 0's multiplier when held); their power F_d . v_0 + m_1 theta' is the
  drive's, booked as external in the energy audit.

V is the ladder's (``ladder.ladder_constants``) with ``BODY_ROWS`` rows appended: the body's
mass (kg) and inertia (kg m^2) (zero for a prescribed base), the hinge offset h (m) and the
chain's mass M (kg), each the same in every column. Cost per evaluation O(n p^2): three ladder
solves for a free body, one for a prescribed motion (m more with m hinges held).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.core.loads import load_sums
from rodval.core.motion import motion_at
from rodval.models.assembly.kernels import V_KAPPA, V_L, V_NU, V_OUTER, V_REST, load_power, rhs_head
from rodval.models.base.free_base import body_accelerations
from rodval.models.hinge_items.deployment import hinge_events, locked_head, superpose, unit_moment
from rodval.models.kinematics.ladder_kernels import (
    BLOCK_A,
    bending_sums,
    ladder_damper_power,
    ladder_forces,
    ladder_kinetic,
    ladder_solve,
    ladder_unit_responses,
    shape_count,
    shape_dot,
    shape_row,
)

#: Rows appended to the ladder's V: body mass, body inertia, hinge offset x, y, chain mass.
BODY_ROWS = 5
BODY_MASS, BODY_INERTIA, OFFSET_X, OFFSET_Y, CHAIN_MASS = range(BODY_ROWS)


@njit(cache=True, inline="always")
def body_value(V, i):
    """Body row ``i`` (``BODY_MASS`` ..) of V."""
    return V[V.shape[0] - BODY_ROWS + i, 0]


@njit(cache=True)
def chain_size(V):
    """(n, p + 1, N): rods, shapes per rod and chain coordinates of V's rung."""
    n = V.shape[1]
    P1 = shape_count(V)
    return n, P1, n * (P1 + 1)


@njit(cache=True)
def offset_vector(V, th):
    """rho = R(theta) h (m): node 0 from the body's centre."""
    c, s = np.cos(th), np.sin(th)
    hx, hy = body_value(V, OFFSET_X), body_value(V, OFFSET_Y)
    return c * hx - s * hy, s * hx + c * hy


@njit(cache=True)
def first_moments(V, g):
    """A_k = a_k . g_k (kg m per unit of g) of every rod, (n,); O(n p)."""
    P1, n = g.shape
    A = np.empty(n)
    for k in range(n):
        A[k] = shape_dot(V, P1, BLOCK_A, k, g)
    return A


@njit(cache=True)
def field_forces(V, c, s, Am, gx, gy, fp, fg):
    """[fp; fg] += J_S^T (gx, gy) (N m for a field in m/s^2), O(n p)."""
    l, outer = V[V_L], V[V_OUTER]
    P1 = fg.shape[0]
    for k in range(c.shape[0]):
        ng = c[k] * gy - s[k] * gx
        eg = c[k] * gx + s[k] * gy
        fp[k] += l[k] * outer[k] * ng - Am[k] * eg
        for i in range(P1):
            fg[i, k] += V[shape_row(P1, BLOCK_A, i, 0), k] * ng


@njit(cache=True)
def first_moment_rate(V, c, s, Am, xp, xg):
    """J_S x (kg m/s for rates x = [xp; xg]), O(n p)."""
    l, outer = V[V_L], V[V_OUTER]
    P1 = xg.shape[0]
    sx = 0.0
    sy = 0.0
    for k in range(c.shape[0]):
        a = l[k] * outer[k] * xp[k] + shape_dot(V, P1, BLOCK_A, k, xg)  # along n_k
        b = -Am[k] * xp[k]  # along e_k
        sx += b * c[k] - a * s[k]
        sy += b * s[k] + a * c[k]
    return sx, sy


@njit(cache=True)
def first_moment_quadratic(V, c, s, Am, dAm, dphi):
    """s_2 = S'' - J_S q'' (kg m/s^2), O(n) (module docstring)."""
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
def chain_parts(V, q, dq):
    """(c, s, g, Aex, Pg, Am, dAm) of the chain at [q; q'] (N each): the chords' cosines and
    sines, the bending coordinates (p+1, n), the kinematics' bending sums (``bending_sums``:
    zero with first-order kinematics), the bending first moments A and their rates; O(n p^2)."""
    n, P1, N = chain_size(V)
    c = np.cos(q[:n])
    s = np.sin(q[:n])
    g = q[n:N].reshape((P1, n))
    Aex, Pg = bending_sums(V, g)
    return c, s, g, Aex, Pg, first_moments(V, g), first_moments(V, dq[n:N].reshape((P1, n)))


@njit(cache=True)
def chain_forces(V, yc, c, s, Aex, Pg, has_load, SX, SY, damped, th, dth):
    """(fp (n), fg (p+1, n)): the pinned ladder's forces at the chain state yc with hinge 0
    measured from the attitude theta (rate theta'). O(n p^2)."""
    n, P1, N = chain_size(V)
    fp = np.empty(n)
    fg = np.empty((P1, n))
    ladder_forces(V, yc, c, s, Aex, Pg, has_load, SX, SY, damped, fp, fg)
    shift = V[V_KAPPA, 0] * th + (V[V_NU, 0] * dth if damped else 0.0)
    fp[0] += shift  # -kappa_0 (D_0 - theta - rest) on phi_1 and alpha_1
    fg[0, 0] += shift
    return fp, fg


@njit(cache=True)
def hinge0_moment(V, D, rate, damped):
    """T_0 (N m): hinge 0's moment on the body, kappa_0 (D_0 - rest_0) + nu_0 dD_0/dt (acting
    stops in V's kappa, nu, rest)."""
    T = V[V_KAPPA, 0] * (D - V[V_REST, 0])
    if damped:
        T += V[V_NU, 0] * rate
    return T


# ---------------------------------------------------------------------------- free body
@njit(cache=True)
def chain_state(y, N):
    """[q; q'] of the chain (2N) from a free body's state [Q; Q'] (2 (N + 3))."""
    NQ = N + 3
    yc = np.empty(2 * N)
    for i in range(N):  # loops: a slice assignment compiles numba's shape check
        yc[i] = y[i]
        yc[N + i] = y[NQ + i]
    return yc


@njit(cache=True)
def field_responses(V, c, s, g, Aex, Pg, Am, G):
    """G[j] = M_c^-1 J_S^T e_j (j = x, y; N each) and K = J_S G (2 x 2, kg); O(n p^2)."""
    n, P1, N = chain_size(V)
    K = np.empty((2, 2))
    fp = np.empty(n)
    fg = np.empty((P1, n))
    for j in range(2):
        fp[:] = 0.0
        fg[:] = 0.0
        field_forces(V, c, s, Am, 1.0 - j, float(j), fp, fg)
        ladder_solve(V, Aex, Pg, g, c, s, fp, fg, G[j])
        kx, ky = first_moment_rate(V, c, s, Am, G[j, :n], G[j, n:].reshape((P1, n)))
        K[0, j] = kx
        K[1, j] = ky
    return K


@njit(cache=True)
def body_solve(V, parts, th, G, K, fp, fg, rb, out):
    """x = M_tot^-1 [fp; fg; rb] (the bordered mass matrix of chain and body) into ``out`` (N +
    3): q'' then (a_c (m/s^2), theta'' (rad/s^2)); ``parts`` from ``chain_parts``. O(n p^2)."""
    c, s, g, Aex, Pg, Am, _ = parts
    n, P1, N = chain_size(V)
    u = out[:N]
    ladder_solve(V, Aex, Pg, g, c, s, fp, fg, u)
    jx, jy = first_moment_rate(V, c, s, Am, u[:n], u[n:].reshape((P1, n)))
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
def free_accel(V, y, has_load, SX, SY, damped, out):
    """Q'' (N + 3) of a ladder rung on a free body at y = [Q; Q'] into ``out``; SX, SY the
    load suffix sums (N). O(n p^2): three ladder solves."""
    n, P1, N = chain_size(V)
    NQ = N + 3
    yc = chain_state(y, N)
    parts = chain_parts(V, yc[:N], yc[N:])
    c, s, g, Aex, Pg, Am, dAm = parts
    th, dth = y[N + 2], y[NQ + N + 2]
    fp, fg = chain_forces(V, yc, c, s, Aex, Pg, has_load, SX, SY, damped, th, dth)
    rx, ry = offset_vector(V, th)
    w2 = dth * dth
    field_forces(V, c, s, Am, w2 * rx, w2 * ry, fp, fg)  # a_0's -theta'^2 rho part
    Fx = SX[0] if has_load else 0.0
    Fy = SY[0] if has_load else 0.0
    qx, qy = first_moment_quadratic(V, c, s, Am, dAm, yc[N : N + n])
    mch = body_value(V, CHAIN_MASS)
    T0 = hinge0_moment(V, y[0] + y[n] - th, y[NQ] + y[NQ + n] - dth, damped)
    rb = np.array(
        [
            Fx - qx + mch * w2 * rx,
            Fy - qy + mch * w2 * ry,
            T0 - ry * (Fx - qx) + rx * (Fy - qy),
        ]
    )
    G = np.empty((2, N))
    K = field_responses(V, c, s, g, Aex, Pg, Am, G)
    body_solve(V, parts, th, G, K, fp, fg, rb, out)


@njit(cache=True)
def free_unit_responses(V, q, locks, U):
    """U[j] = M_tot^-1 a_k (N + 3) for k = locks[j] (hinge 0's row has -1 at theta); only
    the positions Q of ``q`` are read. O(n p^2) per hinge."""
    n, P1, N = chain_size(V)
    parts = chain_parts(V, q[:N], q[:N])
    c, s, g, Aex, Pg, Am, _ = parts
    G = np.empty((2, N))
    K = field_responses(V, c, s, g, Aex, Pg, Am, G)
    fp = np.empty(n)
    fg = np.empty((P1, n))
    rb = np.zeros(3)
    for j in range(locks.shape[0]):
        fp[:] = 0.0
        fg[:] = 0.0
        unit_moment(locks[j], fp, fg[0], fg[1])
        rb[2] = -1.0 if locks[j] == 0 else 0.0
        body_solve(V, parts, q[N + 2], G, K, fp, fg, rb, U[j])


@njit(cache=True)
def free_accel_locked(V, y, has_load, SX, SY, damped, locks, out, lam):
    """Q'' with the hinges ``locks`` held (multipliers into ``lam``, N m); O(n p^2 m)."""
    n, P1, N = chain_size(V)
    free_accel(V, y, has_load, SX, SY, damped, out)
    m = locks.shape[0]
    if m == 0:
        return
    U = np.empty((m, N + 3))
    free_unit_responses(V, y, locks, U)
    superpose(out, U, locks, n, lam, N + 2)


@njit(cache=True)
def free_rhs(t, y, P, S, M, L, out):
    """y' of a ladder rung on a free body (compiled integrators' right-hand side)."""
    n = P.shape[1]
    SX = np.empty(n)
    SY = np.empty(n)
    has_load = rhs_head(t, y, L, SX, SY, out)
    free_accel(P, y, has_load, SX, SY, S[0] != 0.0, out[y.shape[0] // 2 :])


@njit(cache=True)
def held(S):
    """The hinges held by a compiled form's S (``deployment.lock_scalars``), or none for the
    unlocked flags [damped]: a prescribed base's right-hand side serves both modes (its held
    hinges' rows read theta'' from the state, so one kernel holds any set)."""
    m = int(S[1]) if S.shape[0] > 1 else 0
    locks = np.empty(m, np.int64)
    for j in range(m):
        locks[j] = int(S[2 + j])
    return locks


@njit(cache=True)
def free_rhs_locked(t, y, P, S, M, L, out):
    """y' with the hinges of S held; O(n p^2 m)."""
    SX, SY, has_load, locks, lam = locked_head(t, y, P, S, L, out)
    free_accel_locked(P, y, has_load, SX, SY, S[0] != 0.0, locks, out[y.shape[0] // 2 :], lam)


@njit(cache=True)
def free_hinge_events(t, y, P, S, M, L, E, out):
    """Latch and stop events g = D_k - angle, hinge 0 from the body's attitude; O(rows)."""
    n, P1, N = chain_size(P)
    hinge_events(y[:n], y[n : 2 * n], y[2 * n : 3 * n], E, out, y[N + 2])


@njit(cache=True)
def free_root_rates(V, y):
    """(v_0x, v_0y (m/s), S'_x, S'_y (kg m/s)) of a free body's state; O(n p)."""
    n, P1, N = chain_size(V)
    NQ = N + 3
    yc = chain_state(y, N)
    c, s, g, Aex, Pg, Am, dAm = chain_parts(V, yc[:N], yc[N:])
    jx, jy = first_moment_rate(V, c, s, Am, yc[N : N + n], yc[N + n :].reshape((P1, n)))
    rx, ry = offset_vector(V, y[N + 2])
    dth = y[NQ + N + 2]
    return y[NQ + N] - dth * ry, y[NQ + N + 1] + dth * rx, jx, jy


@njit(cache=True)
def free_momentum(V, y):
    """P = m_b v_c + M v_0 + S' (N s): the whole system's linear momentum; O(n p)."""
    v0x, v0y, jx, jy = free_root_rates(V, y)
    mb, mch = body_value(V, BODY_MASS), body_value(V, CHAIN_MASS)
    return mb * y[-3] + mch * v0x + jx, mb * y[-2] + mch * v0y + jy


@njit(cache=True)
def moving_mechanics(t, yc, V, S, L, v0x, v0y, jx, jy, dth, out):
    """(T, P_ext, P_diss) of a ladder chain whose node 0 moves at v_0 (m/s) into out[:3]: the
    chain's T with node 0 at rest (``ladder_kinetic``) + 1/2 M |v_0|^2 + v_0 . S' (J), the
    loads' power on the chain and on node 0's motion (W), the dampers' power with hinge 0's
    rate from the body's theta' (W). O(n p^2)."""
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
def free_mechanics(t, y, P, S, M, L, out):
    """(T, P_ext, P_diss) of a ladder rung on a free body into out[:3] (``moving_mechanics``
    plus the body's 1/2 m_b |v_c|^2 + 1/2 J theta'^2). O(n p^2)."""
    n, P1, N = chain_size(P)
    NQ = N + 3
    v0x, v0y, jx, jy = free_root_rates(P, y)
    dth = y[NQ + N + 2]
    moving_mechanics(t, chain_state(y, N), P, S, L, v0x, v0y, jx, jy, dth, out)
    vc2 = y[NQ + N] ** 2 + y[NQ + N + 1] ** 2
    out[0] += 0.5 * (body_value(P, BODY_MASS) * vc2 + body_value(P, BODY_INERTIA) * dth * dth)


# ---------------------------------------------------------------------- prescribed motion
@njit(cache=True)
def prescribed_accel(V, y, mo, has_load, SX, SY, damped, out):
    """Q'' (N + 3) of a ladder rung on a prescribed base at y = [Q; Q'] into ``out``: the
    body's accelerations are the laws' (``mo``: ``loads.motion_at`` at t), the chain's solve
    M_c q'' = f_c - J_S^T a_0 with a_0 = a_c + theta'' rho_perp - theta'^2 rho (theta, theta'
    from the state, which follows the laws). O(n p^2): one ladder solve."""
    n, P1, N = chain_size(V)
    NQ = N + 3
    yc = chain_state(y, N)
    c, s, g, Aex, Pg, Am, _ = chain_parts(V, yc[:N], yc[N:])
    th, dth, ddth = y[N + 2], y[NQ + N + 2], mo[2, 2]
    fp, fg = chain_forces(V, yc, c, s, Aex, Pg, has_load, SX, SY, damped, th, dth)
    rx, ry = offset_vector(V, th)
    ax = mo[0, 2] - ddth * ry - dth * dth * rx
    ay = mo[1, 2] + ddth * rx - dth * dth * ry
    field_forces(V, c, s, Am, -ax, -ay, fp, fg)
    ladder_solve(V, Aex, Pg, g, c, s, fp, fg, out[:N])
    out[N] = mo[0, 2]
    out[N + 1] = mo[1, 2]
    out[N + 2] = ddth


@njit(cache=True)
def prescribed_unit_responses(V, q, locks, U):
    """U[j] = M_c^-1 a_k (N + 3, the body's entries zero: its motion is prescribed) for k =
    locks[j]; only the positions are read. O(n p^2) per hinge."""
    n, P1, N = chain_size(V)
    Uc = np.empty((locks.shape[0], N))
    ladder_unit_responses(V, q[:N], locks, Uc)
    U[:, :] = 0.0
    for j in range(Uc.shape[0]):
        for i in range(N):
            U[j, i] = Uc[j, i]


@njit(cache=True)
def prescribed_accel_locked(V, y, mo, has_load, SX, SY, damped, locks, out, lam):
    """Q'' with the hinges ``locks`` held into ``out``, multipliers (N m) into ``lam``; hinge
    0's row has -1 at theta, whose acceleration is the law's, so it holds D_0 = phi_1 +
    alpha_1 - theta(t). O(n p^2 m)."""
    n, P1, N = chain_size(V)
    prescribed_accel(V, y, mo, has_load, SX, SY, damped, out)
    m = locks.shape[0]
    if m == 0:
        return
    U = np.empty((m, N + 3))
    prescribed_unit_responses(V, y, locks, U)
    superpose(out, U, locks, n, lam, N + 2)


@njit(cache=True)
def prescribed_rhs(t, y, P, S, M, L, out):
    """y' of a ladder rung on a prescribed base (its laws in M[0]); the held hinges of S."""
    n = P.shape[1]
    SX = np.empty(n)
    SY = np.empty(n)
    has_load = rhs_head(t, y, L, SX, SY, out)
    locks = held(S)
    lam = np.empty(locks.shape[0])
    mo = motion_at(M[0], t)
    half = y.shape[0] // 2
    prescribed_accel_locked(P, y, mo, has_load, SX, SY, S[0] != 0.0, locks, out[half:], lam)


@njit(cache=True)
def drive(V, y, mo, S, L, t):
    """(F_dx, F_dy (N), m_1 (N m)): the base's force on the chain at node 0, F_d = M a_0 + S''
    - F, and the moment it passes through hinge 0, m_1 = lambda_0 - T_0, in the mode of S (its
    held hinges). O(n p^2 m)."""
    n, P1, N = chain_size(V)
    NQ = N + 3
    SX = np.empty(n)
    SY = np.empty(n)
    has_load = load_sums(L, t, SX, SY)
    if not has_load:
        SX[:] = 0.0
        SY[:] = 0.0
    damped = S[0] != 0.0
    locks = held(S)
    lam = np.zeros(locks.shape[0])
    acc = np.empty(N + 3)
    prescribed_accel_locked(V, y, mo, has_load, SX, SY, damped, locks, acc, lam)
    yc = chain_state(y, N)
    c, s, g, Aex, Pg, Am, dAm = chain_parts(V, yc[:N], yc[N:])
    jx, jy = first_moment_rate(V, c, s, Am, acc[:n], acc[n:N].reshape((P1, n)))
    qx, qy = first_moment_quadratic(V, c, s, Am, dAm, yc[N : N + n])
    th, dth, ddth = y[N + 2], y[NQ + N + 2], mo[2, 2]
    rx, ry = offset_vector(V, th)
    mch = body_value(V, CHAIN_MASS)
    Fx = mch * (mo[0, 2] - ddth * ry - dth * dth * rx) + jx + qx - SX[0]
    Fy = mch * (mo[1, 2] + ddth * rx - dth * dth * ry) + jy + qy - SY[0]
    m1 = -hinge0_moment(V, y[0] + y[n] - th, y[NQ] + y[NQ + n] - dth, damped)
    for j in range(locks.shape[0]):
        if locks[j] == 0:
            m1 += lam[j]
    return Fx, Fy, m1


@njit(cache=True)
def prescribed_mechanics(t, y, P, S, M, L, out):
    """(T, P_ext, P_diss) of a ladder rung on a prescribed base into out[:3]
    (``free_mechanics`` with a massless body); P_ext includes the drive's power F_d . v_0 +
    m_1 theta' (``drive``). O(n p^2 m)."""
    free_mechanics(t, y, P, S, M, L, out)
    n, P1, N = chain_size(P)
    Fx, Fy, m1 = drive(P, y, motion_at(M[0], t), S, L, t)
    v0x, v0y, jx, jy = free_root_rates(P, y)
    out[1] += Fx * v0x + Fy * v0y + m1 * y[-1]
