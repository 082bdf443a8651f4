"""Compiled (numba) kernels of the paper's models: the full model's right-hand side and the
O(n) helpers both models share (the reduced model's solve is in ``reduced_banded``).

The numpy right-hand sides in ``full.py``/``reduced.py`` are the straightforward dense
reference (``kernel="numpy"``); the kernels compute the same with the chain structure
exploited (``kernel="numba"``, the default):

* every product with an angle-dependent block (M_pp, G_pp, U = M_pa off-diagonal, G_pa and
  their transposes) is O(n): with c_kj = c_k c_j + s_k s_j and s_kj = s_k c_j - c_k s_j the
  sums over j < k or j > k are running (prefix/suffix) sums;
* K q and C q' go through the hinge angles D = A q (A bidiagonal), springs about their rest
  angles, O(n);
* the full model's 3n x 3n solve eliminates the bending coordinates (M_gg is constant and
  2 x 2 block diagonal per rod); the n x n Schur complement S = M_pp - M_pg M_gg^-1 M_gp is
  "diagonal + rank-2 semiseparable": S[k,j] = a_k . b_j (k > j), b_k . e_j (k < j), so its
  LU factors have the same form and the solve is O(n) (a generator-form LU, the recursion used
  by Foreman-Mackey et al. 2017, "celerite", generalised to a non-symmetric matrix for the
  ``published`` coefficients).

Argument conventions: ``full_accel(V, y, loads, damped, out)`` for the
Python-side right-hand side (whose loads may be any callable); ``full_rhs`` and ``*_mechanics``
have the compiled integrators' type ``rodval.solvers.signature.RHS_TYPE`` (loads and hinge
moments from the compiled load table, ``rodval.core.load_table.load_sums`` and ``hinge_torques``,
O(log rows) per evaluation). ``V`` holds rows of length-n vectors (layout ``V_*`` below),
``S = [damped]``. Generalized forces are one array ``f`` of rows (n each): f[0] on phi, then
one row per bending coordinate (alpha, beta). ``loads`` = (has_load, SX, SY, Tq) (``Loads``):
the load suffix sums and the motors' and rate dampers' moments ``Tq`` (N m) across the hinges
(positive driving D_k up), length n, or length 0 for none (then nothing is added:
``hinge_moments_at``); their generalized force A^T Tq is external (``hinge_moments_into``) and
their power sum_k Tq_k dD_k/dt is booked in P_ext.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rodval.core.load_table import applied_torques, hinge_torques, load_sums

#: A float64 array (numba reads no annotation: they are mypy's); two of them, a kernel's outputs.
Arr = NDArray[np.float64]
Pair = tuple[Arr, Arr]
#: The loads a kernel applies, one argument (has_load, SX, SY, Tq): whether a load acts, the
#: load suffix sums SX, SY (N, n each; read only when has_load), the hinge moments Tq (N m, n,
#: or empty for none).
Loads = tuple[bool, Arr, Arr, Arr]

# Rows of V (per-rod vectors). Shared by both models.
V_L, V_OUTER, V_PPDIAG, V_W, V_KAPPA, V_NU, V_KB, V_REST, V_CB = range(9)
# Full model only: Schur-complement constants per rod (see full_constants).
V_PA, V_PB, V_AP, V_BP, V_AA, V_AB, V_EPS, V_PI, V_RHO, V_TAU = range(9, 19)


def constant_rows(cc: Any, chain: Any) -> list[Arr]:
    """The rows V_L .. V_CB shared by every kernel (and by reduced_banded's constants); V_KB
    = 4 EI/l (N m) and V_CB = 4 bending_damping/l (N m s), see paper_matrices.bending_blocks."""
    return [
        cc.l,
        cc.outer_mass,
        cc.pp_diag,
        cc.w,
        chain.kappa,
        chain.nu,
        4.0 * chain.EI / chain.l,
        chain.rest_angle,
        4.0 * chain.bending_damping / chain.l,
    ]


def full_constants(cc: Any, chain: Any) -> Arr:
    """V for the full model: chain vectors plus the per-rod constants of the bending
    elimination. With M_gg,j = [[aa, ab], [ab, aa]], e = (1, -1), p = (pa, pb), a = (ap, bp):
    eps = e^T M_gg^-1 e, pi = p^T M_gg^-1 e, rho = e^T M_gg^-1 a, tau = p^T M_gg^-1 a."""
    aa, ab = cc.aa_diag, cc.ab_diag
    det = aa * aa - ab * ab
    eps = 2.0 / (aa - ab)
    pi = (cc.pa_diag - cc.pb_diag) / (aa - ab)
    rho = (cc.ap_diag - cc.bp_diag) / (aa - ab)
    tau = (
        cc.pa_diag * (aa * cc.ap_diag - ab * cc.bp_diag)
        + cc.pb_diag * (aa * cc.bp_diag - ab * cc.ap_diag)
    ) / det
    rows = constant_rows(cc, chain) + [
        cc.pa_diag,
        cc.pb_diag,
        cc.ap_diag,
        cc.bp_diag,
        aa,
        ab,
        np.broadcast_to(eps, aa.shape),
        pi,
        rho,
        tau,
    ]
    return np.ascontiguousarray(np.vstack(rows), dtype=np.float64)


@njit(cache=True)
def hinge_forces(
    V: Arr, phi: Arr, alpha: Arr, beta: Arr, row: int, out_p: Arr, out_a: Arr, out_b: Arr
) -> None:
    """out += A^T diag(V[row]) (A [phi; alpha; beta] - rest), O(n): hinge springs about
    their rest angles (row V_KAPPA) or dampers (row V_NU: no rest rate)."""
    n = phi.shape[0]
    for i in range(n):
        D = phi[i] + alpha[i]
        if i > 0:
            D -= phi[i - 1] + beta[i - 1]
        if row == V_KAPPA:
            D -= V[V_REST, i]
        T = V[row, i] * D
        out_p[i] += T
        out_a[i] += T
        if i > 0:
            out_p[i - 1] -= T
            out_b[i - 1] -= T


@njit(cache=True)
def add_moment(k: int, T: float, f: Arr) -> None:
    """f += a_k T: the generalized force of a moment T (N m) across hinge k (a_k the k-th row
    of the hinge matrix A: +1 on phi_k, alpha_k, -1 on phi_{k-1}, beta_{k-1}) on the force
    rows f (phi, alpha, beta, ...: ``full_forces``). O(1)."""
    f[0, k] += T
    f[1, k] += T
    if k > 0:
        f[0, k - 1] -= T
        f[2, k - 1] -= T


@njit(cache=True)
def hinge_moments_into(Tq: Arr, f: Arr) -> None:
    """f += A^T Tq (``add_moment`` per hinge): the hinge moments Tq (N m, positive driving
    D_k up; empty: nothing) as external generalized forces on the rows f. O(n)."""
    for k in range(Tq.shape[0]):
        add_moment(k, Tq[k], f)


@njit(cache=True)
def hinge_of(v: Arr, k: int, n: int, theta: int = -1) -> float:
    """a_k . v: hinge k's angle (rad) or rate (rad/s) from v = [phi; alpha; beta; ...]
    (3n or more), or from v = phi (n: the chord angle phi_k - phi_{k-1}, the reduced and
    rigid rungs'); ``theta`` >= 0: the index of a free base's attitude in v, which hinge 0 is
    measured from (``free_base``). O(1)."""
    if v.shape[0] > n:
        r = v[k] + v[n + k]
        if k > 0:
            r -= v[k - 1] + v[2 * n + k - 1]
    else:
        r = v[k]
        if k > 0:
            r -= v[k - 1]
    if k == 0 and theta >= 0:
        r -= v[theta]
    return float(r)


@njit(cache=True)
def hinge_rates(v: Arr, n: int, theta: int = -1) -> Arr:
    """dD_k/dt (rad/s, n) of every hinge from the rates v (``hinge_of``: a_k q' for v =
    q' = [phi'; alpha'; beta'; ...], the chord rates for v = phi'). O(n)."""
    rates = np.empty(n)
    for k in range(n):
        rates[k] = hinge_of(v, k, n, theta)
    return rates


@njit(cache=True)
def hinge_moments_at(L: Arr, t: float, v: Arr, n: int, theta: int = -1) -> Pair:
    """(Tq, rates): the hinge moments Tq (N m, positive driving D_k up) of the load table L's
    hinge rows at t (``hinge_torques``, ``applied_torques``) at the hinge rates (rad/s) from
    the rates v (``hinge_rates``: the full model's a_k q', the reduced model's chord rates;
    ``theta``: a moving base's attitude index in v, ``hinge_of``); both empty when no hinge row
    acts at t (no rate computed). O(n)."""
    T, C = hinge_torques(L, t, n)
    if T.shape[0] == 0:
        return T, T
    rates = hinge_rates(v, n, theta)
    return applied_torques(T, C, rates), rates


@njit(cache=True)
def torque_power(Tq: Arr, rates: Arr) -> float:
    """sum_k Tq_k dD_k/dt (W): the hinge moments' power, external work; 0 for none. O(n)."""
    p = 0.0
    for k in range(Tq.shape[0]):
        p += Tq[k] * rates[k]
    return p


@njit(cache=True)
def gpp_times(V: Arr, c: Arr, s: Arr, x: Arr, out: Arr) -> None:
    """out -= G_pp x, G_pp[k,j] = l_k l_j M_max(k,j) s_kj, O(n)."""
    n = c.shape[0]
    l, outer = V[V_L], V[V_OUTER]
    pc = 0.0
    ps = 0.0
    for k in range(n):  # j < k: weight M_k
        out[k] -= l[k] * outer[k] * (s[k] * pc - c[k] * ps)
        pc += l[k] * c[k] * x[k]
        ps += l[k] * s[k] * x[k]
    sc = 0.0
    ss = 0.0
    for k in range(n - 1, -1, -1):  # j > k: weight M_j
        out[k] -= l[k] * (s[k] * sc - c[k] * ss)
        sc += outer[k] * l[k] * c[k] * x[k]
        ss += outer[k] * l[k] * s[k] * x[k]


@njit(cache=True)
def upper_times(V: Arr, c: Arr, s: Arr, x: Arr, cos_part: bool, out: Arr, sign: float) -> None:
    """out += sign * X x with X[k,j] = l_k w_j (c_kj if cos_part else s_kj) for k < j, O(n)."""
    n = c.shape[0]
    l, w = V[V_L], V[V_W]
    wc = 0.0
    ws = 0.0
    for k in range(n - 1, -1, -1):
        if cos_part:
            out[k] += sign * l[k] * (c[k] * wc + s[k] * ws)
        else:
            out[k] += sign * l[k] * (s[k] * wc - c[k] * ws)
        wc += w[k] * c[k] * x[k]
        ws += w[k] * s[k] * x[k]


@njit(cache=True)
def upper_t_times(V: Arr, c: Arr, s: Arr, x: Arr, cos_part: bool, out: Arr, sign: float) -> None:
    """out += sign * X^T x for the X of ``upper_times``, O(n)."""
    n = c.shape[0]
    l, w = V[V_L], V[V_W]
    lc = 0.0
    ls = 0.0
    for j in range(n):
        if cos_part:
            out[j] += sign * w[j] * (c[j] * lc + s[j] * ls)
        else:
            out[j] += sign * w[j] * (c[j] * ls - s[j] * lc)
        lc += l[j] * c[j] * x[j]
        ls += l[j] * s[j] * x[j]


@njit(cache=True)
def generator_solve(d: Arr, a: Arr, b: Arr, e: Arr, r: Arr, x: Arr) -> None:
    """Solve S x = r for S = diag(d) + tril(a b^T, -1) + triu(b e^T, 1) (2-vectors a_k, b_k,
    e_k per row, (n, 2) arrays): S[k,j] = a_k . b_j (k > j), b_k . e_j (k < j); O(n)."""
    n = d.shape[0]
    # LU with L[k,j] = a_k . W_j, R[j,k] = Z_j . e_k (unit triangular), pivots D_k.
    S00 = 0.0
    S01 = 0.0
    S10 = 0.0
    S11 = 0.0
    f0 = 0.0
    f1 = 0.0
    Z = np.empty((n, 2))
    for k in range(n):
        Se0 = S00 * e[k, 0] + S01 * e[k, 1]
        Se1 = S10 * e[k, 0] + S11 * e[k, 1]
        Sta0 = S00 * a[k, 0] + S10 * a[k, 1]
        Sta1 = S01 * a[k, 0] + S11 * a[k, 1]
        Dk = d[k] - (a[k, 0] * Se0 + a[k, 1] * Se1)
        W0 = (b[k, 0] - Se0) / Dk
        W1 = (b[k, 1] - Se1) / Dk
        Z[k, 0] = (b[k, 0] - Sta0) / Dk
        Z[k, 1] = (b[k, 1] - Sta1) / Dk
        S00 += Dk * W0 * Z[k, 0]
        S01 += Dk * W0 * Z[k, 1]
        S10 += Dk * W1 * Z[k, 0]
        S11 += Dk * W1 * Z[k, 1]
        yk = r[k] - (a[k, 0] * f0 + a[k, 1] * f1)
        f0 += W0 * yk
        f1 += W1 * yk
        x[k] = yk / Dk
    g0 = 0.0
    g1 = 0.0
    for k in range(n - 1, -1, -1):
        x[k] -= Z[k, 0] * g0 + Z[k, 1] * g1
        g0 += e[k, 0] * x[k]
        g1 += e[k, 1] * x[k]


@njit(cache=True)
def schur_generators(V: Arr, c: Arr, s: Arr) -> tuple[Arr, Arr, Arr, Arr]:
    """(d, a, b, e) of the Schur complement S = diag(d) + tril(a b^T) + triu(b e^T) (see
    ``generator_solve``) from the rows V_L, V_OUTER, V_W, V_PPDIAG, V_EPS .. V_TAU; O(n)."""
    n = c.shape[0]
    l, outer, w = V[V_L], V[V_OUTER], V[V_W]
    eps, pi, rho, tau = V[V_EPS], V[V_PI], V[V_RHO], V[V_TAU]
    a = np.empty((n, 2))
    b = np.empty((n, 2))
    e = np.empty((n, 2))
    d = np.empty(n)
    scc = 0.0
    scs = 0.0
    sss = 0.0  # sum_{j>k} w_j^2 eps_j (c c, c s, s s)_j
    for k in range(n - 1, -1, -1):
        g0 = c[k] * scc + s[k] * scs
        g1 = c[k] * scs + s[k] * sss
        base0 = l[k] * (outer[k] * c[k] - g0)
        base1 = l[k] * (outer[k] * s[k] - g1)
        a[k, 0] = base0 - w[k] * pi[k] * c[k]
        a[k, 1] = base1 - w[k] * pi[k] * s[k]
        e[k, 0] = base0 - w[k] * rho[k] * c[k]
        e[k, 1] = base1 - w[k] * rho[k] * s[k]
        b[k, 0] = l[k] * c[k]
        b[k, 1] = l[k] * s[k]
        d[k] = V[V_PPDIAG, k] - l[k] * l[k] * (c[k] * g0 + s[k] * g1) - tau[k]
        we = w[k] * w[k] * eps[k]
        scc += we * c[k] * c[k]
        scs += we * c[k] * s[k]
        sss += we * s[k] * s[k]
    return d, a, b, e


@njit(cache=True)
def full_forces(V: Arr, y: Arr, c: Arr, s: Arr, loads: Loads, damped: bool, f: Arr) -> None:
    """f = [Q; 0; 0] + A^T Tq - h - C q' - K q + A^T kappa rest of the full model (N m) into
    the rows f (3, n) (zeroed here), O(n). C q' (hinge dampers and the rods' bending damping)
    only when ``damped``; ``loads`` = (has_load, SX, SY, Tq) (``Loads``: Tq empty for none;
    module docstring)."""
    has_load, SX, SY, Tq = loads
    n = V.shape[1]
    q, v = y[: 3 * n], y[3 * n :]
    phi, alpha, beta = q[:n], q[n : 2 * n], q[2 * n :]
    dphi, dalpha, dbeta = v[:n], v[n : 2 * n], v[2 * n :]
    f[:] = 0.0
    fp, fa, fb = f[0], f[1], f[2]
    hinge_forces(V, phi, alpha, beta, V_KAPPA, fp, fa, fb)
    if damped:
        hinge_forces(V, dphi, dalpha, dbeta, V_NU, fp, fa, fb)
    kb, cb = V[V_KB], V[V_CB]
    for k in range(n):
        fa[k] += kb[k] * (alpha[k] + 0.5 * beta[k])
        fb[k] += kb[k] * (0.5 * alpha[k] + beta[k])
        if damped and cb[k] != 0.0:
            fa[k] += cb[k] * (dalpha[k] + 0.5 * dbeta[k])
            fb[k] += cb[k] * (0.5 * dalpha[k] + dbeta[k])
        fp[k] = -fp[k]
        fa[k] = -fa[k]
        fb[k] = -fb[k]
    w2 = dphi * dphi
    gpp_times(V, c, s, w2, fp)  # - G_pp phi'^2
    upper_times(V, c, s, dphi * (dalpha - dbeta), False, fp, -2.0)  # - 2 G_pa (...)
    upper_t_times(V, c, s, w2, False, fa, 1.0)  # - h_alpha = + G_pa^T w2
    upper_t_times(V, c, s, w2, False, fb, -1.0)
    if has_load:
        load_moments(V, c, s, SX, SY, fp)
    hinge_moments_into(Tq, f)


@njit(cache=True)
def load_moments(V: Arr, c: Arr, s: Arr, SX: Arr, SY: Arr, fp: Arr) -> None:
    """fp += Q, the loads' generalized forces on phi: Q_k = l_k (c_k SY_k - s_k SX_k) (N m)
    from the load suffix sums SX, SY (N); O(n)."""
    l = V[V_L]
    for k in range(c.shape[0]):
        fp[k] += l[k] * (c[k] * SY[k] - s[k] * SX[k])


@njit(cache=True)
def full_solve(V: Arr, c: Arr, s: Arr, f: Arr, out: Arr) -> None:
    """q'' = M(phi)^-1 f (3n; f the rows (3, n) of ``full_forces``) into ``out``, O(n): the
    bending coordinates are eliminated per rod, the Schur complement S = M_pp - M_pg M_gg^-1
    M_gp (``schur_generators``) is solved in generator form."""
    n = V.shape[1]
    fp, fa, fb = f[0], f[1], f[2]
    # g = M_gg^-1 f_g per rod; r = f_p - M_pg g; S x_p = r; x_g = M_gg^-1 (f_g - M_gp x_p)
    aa, ab = V[V_AA], V[V_AB]
    ga = np.empty(n)
    gb = np.empty(n)
    for k in range(n):
        det = aa[k] * aa[k] - ab[k] * ab[k]
        ga[k] = (aa[k] * fa[k] - ab[k] * fb[k]) / det
        gb[k] = (aa[k] * fb[k] - ab[k] * fa[k]) / det
    r = fp - V[V_PA] * ga - V[V_PB] * gb
    upper_times(V, c, s, ga - gb, True, r, -1.0)
    xp = out[:n]
    d, a, b, e = schur_generators(V, c, s)
    generator_solve(d, a, b, e, r, xp)
    ut = np.zeros(n)
    upper_t_times(V, c, s, xp, True, ut, 1.0)
    for k in range(n):
        ra = fa[k] - ut[k] - V[V_AP, k] * xp[k]
        rb = fb[k] + ut[k] - V[V_BP, k] * xp[k]
        det = aa[k] * aa[k] - ab[k] * ab[k]
        out[n + k] = (aa[k] * ra - ab[k] * rb) / det
        out[2 * n + k] = (aa[k] * rb - ab[k] * ra) / det


@njit(cache=True)
def full_accel(V: Arr, y: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """Accelerations q'' (3n) of the full model at y = [q; q'] into ``out``: M(phi) q'' =
    [Q; 0; 0] + A^T Tq - h - C q' - K q, ``loads`` = (has_load, SX, SY, Tq) (``Loads``: the
    load suffix sums (N) and the hinge moments (N m, empty: none)). O(n) time and memory."""
    n = V.shape[1]
    c = np.cos(y[:n])
    s = np.sin(y[:n])
    f = np.empty((3, n))
    full_forces(V, y, c, s, loads, damped, f)
    full_solve(V, c, s, f, out)


@njit(cache=True, inline="always")
def rhs_head(t: float, y: Arr, L: Arr, sums: Pair, out: Arr, moving: bool = False) -> Loads:
    """The start of a compiled right-hand side y' = [v; a] of a state y = [q; v]: out's first
    half = v, the load suffix sums at t (N) into sums = (SX, SY) (``load_sums``, n each), the
    hinge moments at the state's rates v (``hinge_moments_at``; ``moving``: hinge 0 measured
    from a moving base's attitude, v's last entry). Returns the ``Loads``. O(N)."""
    half = y.shape[0] // 2
    for i in range(half):  # a loop: a slice assignment compiles numba's shape check
        out[i] = y[half + i]
    SX, SY = sums
    has_load = bool(load_sums(L, t, SX, SY))
    Tq = hinge_moments_at(L, t, y[half:], SX.shape[0], half - 1 if moving else -1)[0]
    return has_load, SX, SY, Tq


@njit(cache=True, inline="always")
def rhs_start(t: float, y: Arr, P: Arr, L: Arr, out: Arr, moving: bool = False) -> Loads:
    """``rhs_head`` with the load sums allocated (n each, n = P's columns). O(N)."""
    sums = (np.empty(P.shape[1]), np.empty(P.shape[1]))
    return rhs_head(t, y, L, sums, out, moving)


@njit(cache=True)
def full_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the full model (compiled integrators' right-hand side, loads and hinge moments
    from table L)."""
    full_accel(P, y, rhs_start(t, y, P, L, out), S[0] != 0.0, out[3 * P.shape[1] :])


@njit(cache=True)
def _mpp_quadratic(V: Arr, c: Arr, s: Arr, x: Arr) -> float:
    """x^T M_pp x (kg m^2/s^2 for rates x), O(n): M_pp[k,j] = l_k l_j M_max(k,j) c_kj off the
    diagonal, c_kj = c_k c_j + s_k s_j by prefix sums."""
    n = c.shape[0]
    l, outer, d = V[V_L], V[V_OUTER], V[V_PPDIAG]
    total = 0.0
    pc = 0.0
    ps = 0.0
    for k in range(n):
        total += d[k] * x[k] * x[k] + 2.0 * l[k] * outer[k] * x[k] * (c[k] * pc + s[k] * ps)
        pc += l[k] * c[k] * x[k]
        ps += l[k] * s[k] * x[k]
    return float(total)


@njit(cache=True)
def load_power(V: Arr, c: Arr, s: Arr, dphi: Arr, L: Arr, t: float) -> float:
    """P_ext = Q . phi' (W) with Q_k = l_k (c_k SY_k - s_k SX_k); 0 when no load acts."""
    n = c.shape[0]
    SX = np.empty(n)
    SY = np.empty(n)
    if not load_sums(L, t, SX, SY):
        return 0.0
    l = V[V_L]
    p = 0.0
    for k in range(n):
        p += l[k] * (c[k] * SY[k] - s[k] * SX[k]) * dphi[k]
    return p


@njit(cache=True)
def compiled_damper_power(V: Arr, S: Arr, dphi: Arr, dalpha: Arr, dbeta: Arr) -> float:
    """q'^T C q' = sum_k nu_k (dD_k/dt)^2 + sum_k cb_k (a'^2 + a' b' + b'^2) (W), dD_k/dt =
    phi'_k + alpha'_k - phi'_{k-1} - beta'_{k-1} (the hinge rates,
    ``rodval.core.scene.hinge_angles`` of the rates), cb = 4 bending_damping/l on the bending
    rates a' = alpha'_k, b' = beta'_k (``paper_matrices.damper_power``); 0 unless S[0] (the
    damped flag). O(n)."""
    if S[0] == 0.0:
        return 0.0
    nu, cb = V[V_NU], V[V_CB]
    p = 0.0
    left = 0.0
    for k in range(dphi.shape[0]):
        rate = dphi[k] + dalpha[k] - left
        p += nu[k] * rate * rate
        p += cb[k] * (dalpha[k] * dalpha[k] + dalpha[k] * dbeta[k] + dbeta[k] * dbeta[k])
        left = dphi[k] + dbeta[k]
    return p


@njit(cache=True)
def external_power(V: Arr, c: Arr, s: Arr, v: Arr, L: Arr, t: float) -> float:
    """P_ext (W) at rates v (q' = [phi'; alpha'; beta'], or the reduced model's phi'): the
    loads' power (``load_power``) plus the hinge moments' sum_k Tq_k dD_k/dt
    (``hinge_moments_at``, ``torque_power``; added only when a hinge row acts). O(n)."""
    n = c.shape[0]
    p = load_power(V, c, s, v[:n], L, t)
    Tq, rates = hinge_moments_at(L, t, v, n)
    if Tq.shape[0] > 0:
        p += torque_power(Tq, rates)
    return p


@njit(cache=True)
def full_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) of the full model into out[:3]: T = 1/2 q'^T M q' (J) with the
    kinematic (printed, symmetric) mass matrix, the external power (W: loads and hinge
    moments, ``external_power``) and the damper power
    sum_k nu_k (dD_k/dt)^2 (W; 0 unless S[0], the damped flag). O(n)."""
    n = P.shape[1]
    phi, dphi = y[:n], y[3 * n : 4 * n]
    va, vb = y[4 * n : 5 * n], y[5 * n :]
    c = np.cos(phi)
    s = np.sin(phi)
    u = np.zeros(n)
    upper_times(P, c, s, va - vb, True, u, 1.0)  # U (alpha' - beta')
    aa, ab = P[V_AA], P[V_AB]
    T = _mpp_quadratic(P, c, s, dphi)
    for k in range(n):
        T += 2.0 * dphi[k] * (u[k] + P[V_PA, k] * va[k] + P[V_PB, k] * vb[k])
        T += aa[k] * (va[k] * va[k] + vb[k] * vb[k]) + 2.0 * ab[k] * va[k] * vb[k]
    out[0] = 0.5 * T
    out[1] = external_power(P, c, s, y[3 * n :], L, t)
    out[2] = compiled_damper_power(P, S, dphi, va, vb)


@njit(cache=True)
def reduced_mechanics(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """(T, P_ext, P_diss) of the reduced model into out[:3]: T = 1/2 phi'^T M_pp phi' (J; its
    bending rates are dropped, in its dampers too: P_diss = sum_k nu_k (phi'_k -
    phi'_{k-1})^2, W), the external power (W: loads and hinge moments at the chord rates,
    ``external_power``). O(n)."""
    n = P.shape[1]
    phi, dphi = y[:n], y[n:]
    c = np.cos(phi)
    s = np.sin(phi)
    out[0] = 0.5 * _mpp_quadratic(P, c, s, dphi)
    out[1] = external_power(P, c, s, dphi, L, t)
    zero = np.zeros(n)
    out[2] = compiled_damper_power(P, S, dphi, zero, zero)
