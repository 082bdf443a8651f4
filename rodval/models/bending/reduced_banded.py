"""The reduced model's right-hand side and bending recovery in O(n) time and memory.

API: ``banded_constants`` (once per chain), ``reduced_solve`` (phi'' and gamma at a state
y = [phi; phi'] into out = (phi'', gamma)), ``reduced_solve_work`` (the same with a reusable
work array and a method choice), ``reduced_accel`` (phi'' only, the argument list of
``kernels.full_accel`` with Cst in place of V), ``bending_at`` (Python convenience). Each
takes the ``kernels.Loads`` (has_load, SX, SY, Tq): the load suffix sums and the hinge moments
``Tq`` (N m, empty for none; ``kernels`` module docstring), whose generalized force A^T Tq
joins the right-hand sides r_p, r_g.

The dense route (``kernels.reduced_accel``, ``ReducedSystem.recover_bending``) eliminates the
bending angles first, M_r = M_pp - K_pg B^-1 M_gp, which is a dense n x n matrix (O(n^2) to
assemble, O(n^3) to solve). Here the elimination is not done: the *unreduced* algebraic system
in x = phi'' (rad/s^2) and gamma = [alpha; beta] (rad),

    phi rows      M_pp x + K_pg gamma = r_p,   r_p = Q - G_pp phi'^2 - C_pp phi' - K_pp phi  (N m)
    bending rows  M_gp x + B gamma    = r_g,   r_g = -(G_gp phi'^2 + C_gp phi' + K_gp phi)   (N m)

(B = K_gg, constant and positive definite since EI > 0; eliminating gamma gives back the
reduced equations of ``reduced.py``, whose matrix M_r is the Schur complement of B), is made
banded by adding the running sums of the dense products as unknowns. With
e_k = (cos phi_k, sin phi_k) and rods k = 0..n-1 (0-based):

    P_k = sum_{j<k} l_j e_j x_j          (m/s^2, prefix *excluding* k, P_0 = 0)
    S_k = sum_{j>=k} M_j l_j e_j x_j     (N, suffix *including* k, S_n = 0; M_k = outer_mass)

    (M_pp x)_k = pp_k x_k + l_k M_k e_k . P_k + l_k e_k . S_{k+1}
    (M_ap x)_k =  w_k e_k . P_k + ap_k x_k,   (M_bp x)_k = -w_k e_k . P_k + bp_k x_k
    (w_k = m_k l_k^2 / 12; ap, bp are the variant's bending-row diagonals)

K_pg and B come from the hinge angles D_k = phi_k + alpha_k - phi_{k-1} - beta_{k-1} and the
per-rod blocks (4 EI_k / l_k) [[1, 1/2], [1/2, 1]]:

    (K_pg gamma)_k = kappa_k (alpha_k - beta_{k-1}) - kappa_{k+1} (alpha_{k+1} - beta_k)
    (B gamma)_alpha_k = kappa_k (alpha_k - beta_{k-1}) + kb_k (alpha_k + beta_k / 2)
    (B gamma)_beta_k  = kappa_{k+1} (beta_k - alpha_{k+1}) + kb_k (alpha_k / 2 + beta_k)

Two O(n) eliminations of this system are implemented; ``reduced_solve`` uses the sweep and
falls back to the banded LU if the sweep meets an exactly zero local pivot (METHOD_AUTO).

Sweep (tip to root, then root to tip; the default, about 6x faster). The rods k..n-1 interact
with the rods before them only through z_k = (P_k, beta_{k-1}) (3 numbers; beta_{-1} = 0).
Going from the tip (S_n = 0, kappa_n = 0) to the root, each rod's three rows (phi, alpha,
beta) are written in its own unknowns u_k = (x_k, alpha_k, beta_k), with the tail relation of
rod k+1, S_{k+1} = F z_{k+1} + f and alpha_{k+1} = G . z_{k+1} + g, and z_{k+1} =
(P_k + l_k e_k x_k, beta_k) substituted; that 3 x 3 system (all rows in N m) is solved by
Gaussian elimination with partial pivoting for u_k = T_k z_k + t_k, and S_k = S_{k+1} +
M_k l_k e_k x_k gives rod k's tail relation. Then z_0 = 0 and u_k, z_{k+1} follow rod by rod.
This is block elimination of the banded system below in the order tip to root (like the
articulated-body algorithm of multibody dynamics); each local 3 x 3 matrix is the Schur
complement of the sub-chain k..n-1, itself a chain of the same model.

Banded LU (METHOD_BAND): the fallback, in ``rodval.models.bending.reduced_band_lu``.

Cost: O(n) time and memory per evaluation, no n x n array anywhere: the sweep ~250 flops and
19 doubles per rod, the banded LU ~800 flops and ~90 doubles per rod (U factor 7n x 11). phi''
and gamma come out of the same solve, so the bending recovery is the same routine. Rods at
rest near the root cost only the forces and a comparison each: the sweep stops where the
rest of the chain's solution is exactly 0 (``solve_sweep``), the usual case on a long chain
driven near its tip (at n = 1e5, ~120 rods move within 2 s of the paper's pulse).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from rodval.models.assembly.kernels import (
    V_KAPPA,
    V_KB,
    V_L,
    V_NU,
    V_OUTER,
    V_PPDIAG,
    V_REST,
    V_W,
    Arr,
    Loads,
    Pair,
    constant_rows,
    hinge_moments_into,
    rhs_head,
)
from rodval.models.assembly.paper_matrices import DEFAULT_VARIANT, chain_constants
from rodval.models.bending import reduced_band_lu as lu


@njit(cache=True)
def reduced_forces(Cst: Arr, y: Arr, geo: Pair, loads: Loads, damped: bool, f: Arr) -> None:
    """Right-hand sides (N m) at y = [phi; phi'] into the rows f (3, n): f[0] = r_p = Q - G_pp
    phi'^2 - C_pp phi' - K_pp phi, f[1] = r_alpha, f[2] = r_beta, with r_g = -(G_gp phi'^2 +
    C_gp phi' + K_gp phi) (C only when ``damped``), plus A^T Tq; ``loads`` = (has_load, SX,
    SY, Tq) (``kernels.Loads``: Tq the hinge moments, N m, empty: none). geo = (cos phi, sin
    phi).

    One pass root to tip (the hinge springs and dampers, kernels.hinge_forces with alpha =
    beta = 0; the prefix sums of G_pp and G_pa^T, kernels.gpp_times and upper_t_times) and
    one back (the suffix sums of G_pp, the load), each sum in the order of those kernels.
    O(n)."""
    c, s = geo
    has_load, SX, SY, Tq = loads
    n = Cst.shape[1]
    phi, dphi = y[:n], y[n:]
    fp, fa, fb = f[0], f[1], f[2]
    l, outer, w = Cst[V_L], Cst[V_OUTER], Cst[V_W]
    kap, nu, rest = Cst[V_KAPPA], Cst[V_NU], Cst[V_REST]
    # hinge k: D_k = phi_k - phi_{k-1} - rest_k, torque T_k = kappa_k D_k (Tv: nu_k D_k')
    T_next = kap[0] * (phi[0] - rest[0])
    Tv_next = nu[0] * dphi[0] if damped else 0.0
    pc = 0.0  # sum_{j<k} l_j c_j phi_j'^2 (G_pp's and G_pa^T's prefix sums alike)
    ps = 0.0
    for k in range(n):
        T, Tv = T_next, Tv_next
        p = T
        a = T
        b = 0.0
        if k + 1 < n:
            T_next = kap[k + 1] * ((phi[k + 1] - phi[k]) - rest[k + 1])
            p -= T_next
            b -= T_next
        if damped:
            p += Tv
            a += Tv
            if k + 1 < n:
                Tv_next = nu[k + 1] * (dphi[k + 1] - dphi[k])
                p -= Tv_next
                b -= Tv_next
        x = dphi[k] * dphi[k]
        fp[k] = -p - l[k] * outer[k] * (s[k] * pc - c[k] * ps)  # - G_pp phi'^2, j < k
        g = w[k] * (c[k] * ps - s[k] * pc)
        fa[k] = -a + g  # - G_ap phi'^2 = + G_pa^T phi'^2
        fb[k] = -b + -g  # - G_bp phi'^2 = - G_pa^T phi'^2
        pc += l[k] * c[k] * x
        ps += l[k] * s[k] * x
    sc = 0.0
    ss = 0.0
    for k in range(n - 1, -1, -1):  # - G_pp phi'^2, j > k (weight M_j); then the load
        fp[k] -= l[k] * (s[k] * sc - c[k] * ss)
        x = dphi[k] * dphi[k]
        sc += outer[k] * l[k] * c[k] * x
        ss += outer[k] * l[k] * s[k] * x
        if has_load:
            fp[k] += l[k] * (c[k] * SY[k] - s[k] * SX[k])
    hinge_moments_into(Tq, f)


#: Magnitudes below this are set to zero in the sweep (physical units: N, rad, rad/s^2). Far
#: below any round-off of the values they are added to, and far above the subnormal range
#: (< 2.2e-308): on a long chain the coefficients of the tail relation and the solution decay
#: geometrically towards the root and would otherwise sit at subnormals, where every x86
#: operation takes a ~100-cycle microcode assist (5x slower runs at n = 8192,
#: benchmarks/subnormal_cost.py).
TINY = 1e-250


@njit(cache=True, inline="always")
def _flush(v: float) -> float:
    return 0.0 if abs(v) < TINY else v


@njit(cache=True, inline="always")
def _local_system(Cst: Arr, k: int, c: Arr, s: Arr, f: Arr, F: Arr, G: Arr, L: Arr, R: Arr) -> None:
    """Rod k's phi, alpha, beta rows as L u = R [P; beta_{k-1}; 1], u = (x_k, alpha_k,
    beta_k), with S_{k+1}, alpha_{k+1} from the tail relation (F, G) of rod k+1 and
    z_{k+1} = (P_k + l e x_k, beta_k) substituted (all rows in N m). O(1)."""
    l, M, w = Cst[V_L, k], Cst[V_OUTER, k], Cst[V_W, k]
    kap, kb = Cst[V_KAPPA, k], Cst[V_KB, k]
    kapn = Cst[V_KAPPA, k + 1] if k + 1 < c.shape[0] else 0.0
    ex, ey = c[k], s[k]
    Fe0 = F[0, 0] * ex + F[0, 1] * ey  # F_P e
    Fe1 = F[1, 0] * ex + F[1, 1] * ey
    FTe0 = F[0, 0] * ex + F[1, 0] * ey  # F_P^T e
    FTe1 = F[0, 1] * ex + F[1, 1] * ey
    eFe = ex * Fe0 + ey * Fe1
    eFb = ex * F[0, 2] + ey * F[1, 2]
    ef = ex * F[0, 3] + ey * F[1, 3]
    Ge = G[0] * ex + G[1] * ey
    L[0, 0] = Cst[V_PPDIAG, k] + l * l * eFe - kapn * l * Ge
    L[0, 1] = kap
    L[0, 2] = l * eFb + kapn * (1.0 - G[2])
    R[0, 0] = kapn * G[0] - l * (M * ex + FTe0)
    R[0, 1] = kapn * G[1] - l * (M * ey + FTe1)
    R[0, 2] = kap
    R[0, 3] = f[0, k] - l * ef + kapn * G[3]
    L[1, 0] = Cst[lu.C_AP, k]
    L[1, 1] = kap + kb
    L[1, 2] = 0.5 * kb
    R[1, 0] = -w * ex
    R[1, 1] = -w * ey
    R[1, 2] = kap
    R[1, 3] = f[1, k]
    L[2, 0] = Cst[lu.C_BP, k] - kapn * l * Ge
    L[2, 1] = 0.5 * kb
    L[2, 2] = kb + kapn * (1.0 - G[2])
    R[2, 0] = w * ex + kapn * G[0]
    R[2, 1] = w * ey + kapn * G[1]
    R[2, 2] = 0.0
    R[2, 3] = f[2, k] + kapn * G[3]


@njit(cache=True, inline="always")
def _solve_local(L: Arr, R: Arr, Tk: Arr) -> bool:
    """Tk = L^-1 R by 3 x 3 Gaussian elimination with partial pivoting (L, R overwritten);
    False if a pivot is zero. O(1)."""
    for j in range(3):
        p = j
        big = abs(L[j, j])
        for i in range(j + 1, 3):
            if abs(L[i, j]) > big:
                big = abs(L[i, j])
                p = i
        if big == 0.0:
            return False
        if p != j:
            for q in range(3):
                t = L[j, q]
                L[j, q] = L[p, q]
                L[p, q] = t
            for q in range(4):
                t = R[j, q]
                R[j, q] = R[p, q]
                R[p, q] = t
        for i in range(j + 1, 3):
            f = L[i, j] / L[j, j]
            for q in range(j + 1, 3):
                L[i, q] -= f * L[j, q]
            for q in range(4):
                R[i, q] -= f * R[j, q]
    for j in range(2, -1, -1):
        for q in range(4):
            acc = R[j, q]
            for i in range(j + 1, 3):
                acc -= L[j, i] * Tk[i, q]
            Tk[j, q] = _flush(acc / L[j, j])
    return True


@njit(cache=True, inline="always")
def _tail_relation(Cst: Arr, k: int, c: Arr, s: Arr, Tk: Arr, F: Arr, G: Arr) -> None:
    """Rod k's tail relation from rod k+1's (F, G updated in place): S_k = S_{k+1} + M l e x_k
    = [F_P | 0 | f] + F_b (x) T_k[2] + (l F_P e + M l e) (x) T_k[0]; alpha_k = T_k[1]. O(1)."""
    l, M = Cst[V_L, k], Cst[V_OUTER, k]
    ex, ey = c[k], s[k]
    v0 = l * (F[0, 0] * ex + F[0, 1] * ey + M * ex)
    v1 = l * (F[1, 0] * ex + F[1, 1] * ey + M * ey)
    Fb0 = F[0, 2]
    Fb1 = F[1, 2]
    F[0, 2] = 0.0
    F[1, 2] = 0.0
    for q in range(4):
        F[0, q] = _flush(F[0, q] + Fb0 * Tk[2, q] + v0 * Tk[0, q])
        F[1, q] = _flush(F[1, q] + Fb1 * Tk[2, q] + v1 * Tk[0, q])
        G[q] = Tk[1, q]


@njit(cache=True, inline="always")
def _quiet_below(Cst: Arr, k: int, c: Arr, s: Arr, f: Arr, f0: float, f1: float) -> int:
    """The highest rod j <= k whose local system has a nonzero constant column R[:, 3] when
    the tail's constant part is f = (f0, f1) (N) and its alpha part G[3] is 0, or -1 when rods
    0..k have none (_local_system: R[:, 3] = (fp - l e.f, fa, fb); the same expression, so the
    test is exact). O(k - j)."""
    l = Cst[V_L]
    j = k
    while j >= 0:
        if f[1, j] != 0.0 or f[2, j] != 0.0 or f[0, j] != l[j] * (c[j] * f0 + s[j] * f1):
            return j
        j -= 1
    return -1


@njit(cache=True, inline="always")
def _root_to_tip(Cst: Arr, c: Arr, s: Arr, T: Arr, quiet: int, out: Pair) -> bool:
    """u_k = 0 for the quiet rods k <= ``quiet`` (solve_sweep); then z = 0, u_k = T_k [z_k;
    1], z_{k+1} = (P_k + l_k e_k x_k, beta_k), rod by rod into out = (phi'', gamma); False if
    a value is not finite. O(n)."""
    n = c.shape[0]
    ddphi_out, gamma_out = out
    for k in range(quiet + 1):
        ddphi_out[k] = 0.0
        gamma_out[k] = 0.0
        gamma_out[n + k] = 0.0
    P0 = 0.0
    P1 = 0.0
    bprev = 0.0
    for k in range(quiet + 1, n):
        x = _flush(T[k, 0, 0] * P0 + T[k, 0, 1] * P1 + T[k, 0, 2] * bprev + T[k, 0, 3])
        a = _flush(T[k, 1, 0] * P0 + T[k, 1, 1] * P1 + T[k, 1, 2] * bprev + T[k, 1, 3])
        bb = _flush(T[k, 2, 0] * P0 + T[k, 2, 1] * P1 + T[k, 2, 2] * bprev + T[k, 2, 3])
        if not (np.isfinite(x) and np.isfinite(a) and np.isfinite(bb)):
            return False
        ddphi_out[k] = x
        gamma_out[k] = a
        gamma_out[n + k] = bb
        l = Cst[V_L, k]
        P0 += l * c[k] * x
        P1 += l * s[k] * x
        bprev = bb
    return True


@njit(cache=True)
def solve_sweep(Cst: Arr, c: Arr, s: Arr, f: Arr, T: Arr, out: Pair) -> bool:
    """The tip-to-root elimination (module docstring, "sweep") of the right-hand sides f (3,
    n), then root to tip into out = (phi'', gamma). T (n x 3 x 4): work storage for u_k =
    T_k[:, :3] z_k + T_k[:, 3]. False if a local pivot is zero or a result is not finite.
    O(n): ~250 flops per rod.

    The quiet root part: once the constant parts of rods 0..k (T_k[:, 3], from R[:, 3]) are
    all exactly zero, z_0 = 0 gives u_j = 0 and z_{j+1} = 0 rod by rod up to k, whatever the
    T_j[:, :3]; the tip-to-root pass stops there (``_quiet_below`` checks the rods below it,
    each rod at most once per evaluation) and rods 0..k get 0. This is the same result as the
    full pass to the last bit (up to the sign of zeros): on a long chain driven near its tip
    the motion decays geometrically towards the root (the sweep flushes values below TINY),
    and the rods at rest there cost nothing. Not checked for them: a zero local pivot, which
    the full pass would hand to the banded LU (a singular sub-chain at rest)."""
    n = c.shape[0]
    F = np.zeros((2, 4))  # tail relation of rod k+1: S_{k+1} = F[:, :3] z_{k+1} + F[:, 3]
    G = np.zeros(4)  #                           alpha_{k+1} = G[:3] . z_{k+1} + G[3]
    L = np.empty((3, 3))
    R = np.empty((3, 4))
    quiet = -1
    unchecked = n  # rods >= unchecked were checked for the current (F[:, 3], G[3])
    for k in range(n - 1, -1, -1):
        if k < unchecked and G[3] == 0.0:
            j = _quiet_below(Cst, k, c, s, f, F[0, 3], F[1, 3])
            if j < 0:
                quiet = k
                break
            unchecked = j  # rods j+1..k keep F[:, 3], G[3]: no check until rod j is passed
        _local_system(Cst, k, c, s, f, F, G, L, R)
        if not _solve_local(L, R, T[k]):
            return False
        _tail_relation(Cst, k, c, s, T[k], F, G)
    return _root_to_tip(Cst, c, s, T, quiet, out)


#: ``method`` of reduced_solve_work
METHOD_AUTO, METHOD_BAND, METHOD_SWEEP = 0, 1, 2


@njit(cache=True)
def reduced_solve(Cst: Arr, y: Arr, loads: Loads, damped: bool, out: Pair) -> bool:
    """phi'' (rad/s^2, n) and gamma = [alpha; beta] (rad, 2n) into out = (phi'', gamma) of
    the reduced model at state y = [phi; phi'] (module docstring: the sweep, with the banded
    LU as fallback). ``Cst`` from ``banded_constants``; ``loads`` = (has_load, SX, SY, Tq)
    (``kernels.Loads``: the load suffix sums (N, load_table.load_sums), the hinge moments
    (N m, empty: none)); ``damped`` adds the hinge dampers. O(n) time and memory per
    evaluation. Returns False if the system is singular (outputs then hold NaN)."""
    work = np.empty(sweep_work_size(Cst.shape[1]))  # the fallback allocates its own
    return reduced_solve_work(Cst, y, loads, damped, out, work, METHOD_AUTO)


@njit(cache=True)
def work_size(n: int) -> int:
    """Length of a float64 work array of ``reduced_solve_work`` that serves every method for
    n rods: 7n scratch, then the larger of the sweep's T (12n) and the banded LU's U
    (7n x 11), right-hand side (7n + 10) and ring of active rows."""
    return 7 * n + max(12 * n, lu.band_size(n))


@njit(cache=True)
def sweep_work_size(n: int) -> int:
    """Length of a work array that serves METHOD_SWEEP (19n); with METHOD_AUTO the rare
    fallback to the banded LU then allocates what it needs."""
    return 19 * n


@njit(cache=True)
def reduced_solve_work(
    Cst: Arr, y: Arr, loads: Loads, damped: bool, out: Pair, work: Arr, method: int
) -> bool:
    """``reduced_solve`` with a caller-provided float64 work array of length >= work_size(n),
    or >= sweep_work_size(n) (then the banded LU, if used, allocates its part), so that a
    caller that evaluates many times, such as an integrator, allocates it once; and a
    ``method``: METHOD_AUTO (the sweep; the banded LU if the sweep meets a zero local pivot
    or a non-finite value), METHOD_BAND or METHOD_SWEEP (one of them only)."""
    n = Cst.shape[1]
    phi = y[:n]
    c = work[:n]
    s = work[n : 2 * n]
    for k in range(n):
        p = phi[k]
        if p == 0.0:  # cos(+-0) = 1, sin(+-0) = +-0 exactly: the rods at rest cost no call
            c[k] = 1.0
            s[k] = p
        else:
            c[k] = np.cos(p)
            s[k] = np.sin(p)
    f = work[2 * n : 5 * n].reshape((3, n))
    reduced_forces(Cst, y, (c, s), loads, damped, f)
    rest = work[7 * n :]
    if method != METHOD_BAND:
        if solve_sweep(Cst, c, s, f, rest[: 12 * n].reshape((n, 3, 4)), out):
            return True
    if method != METHOD_SWEEP:
        if rest.shape[0] < lu.band_size(n):
            rest = np.empty(lu.band_size(n))
        if lu.solve_band(Cst, c, s, f, rest, out):
            return True
    out[0][:] = np.nan
    out[1][:] = np.nan
    return False


def banded_constants(cc: Any, chain: Any, variant: str = DEFAULT_VARIANT) -> Arr:
    """Every angle-independent per-rod constant of ``reduced_solve`` as a float64 array
    (N_CST, n); ``cc = paper_matrices.chain_constants(chain, variant)``, or None to compute
    the per-rod constants here for ``variant``. O(n) time and memory.

    Rows: the kernels.V layout (l (m), outer mass M_k (kg), M_pp diagonal (kg m^2),
    w = m l^2/12 (kg m), kappa (N m/rad), nu (N m s/rad), 4 EI/l (N m)), then the bending-row
    diagonals ap, bp (kg m^2; the only difference between the "printed" and "published"
    variants), then the banded LU's equilibration: its flag (C_EQUIL) and 7 row and 7 column
    scales per rod, left at 1 here; the banded LU writes them on its first use
    (``reduced_band_lu.equilibrate``), since the sweep, the default, does not read them."""
    n = chain.n
    if cc is None:
        cc = chain_constants(chain, variant)
    Cst = np.empty((lu.N_CST, n))
    rows = constant_rows(cc, chain)
    for i in range(lu.N_V_ROWS):  # row by row: no (N_V_ROWS, n) temporary
        Cst[i] = rows[i]
    Cst[lu.C_AP] = cc.ap_diag
    Cst[lu.C_BP] = cc.bp_diag
    Cst[lu.C_EQUIL] = 0.0
    Cst[lu.C_RSCALE :] = 1.0
    return Cst


def bending_at(
    Cst: np.ndarray,
    phi: np.ndarray,
    dphi: np.ndarray,
    loads: Loads,
    damped: bool,
    method: int = METHOD_AUTO,
) -> Pair:
    """(phi'', gamma) at one state, ``loads`` = (has_load, SX, SY, Tq) (``kernels.Loads``:
    the load suffix sums, N, and the hinge moments, N m, length 0: none). The O(n) replacement
    of ReducedSystem.recover_bending (which returns gamma)."""
    n = phi.shape[0]
    phi = np.ascontiguousarray(phi, dtype=np.float64)
    dphi = np.ascontiguousarray(dphi, dtype=np.float64)
    SX, SY, Tq = (np.ascontiguousarray(v, dtype=np.float64) for v in loads[1:])
    ddphi, gamma = np.empty(n), np.empty(2 * n)
    work = np.empty(sweep_work_size(n))  # the banded LU, if needed, allocates its own
    y = np.concatenate((phi, dphi))
    packed = (bool(loads[0]), SX, SY, Tq)
    reduced_solve_work(Cst, y, packed, bool(damped), (ddphi, gamma), work, method)
    return ddphi, gamma


@njit(cache=True)
def reduced_accel(Cst: Arr, y: Arr, loads: Loads, damped: bool, out: Arr) -> None:
    """phi'' at y = [phi; phi'] into ``out`` (the argument convention of
    ``kernels.full_accel``); O(n) time and memory."""
    reduced_solve(Cst, y, loads, damped, (out, np.empty(2 * Cst.shape[1])))


@njit(cache=True)
def rhs_work_size(n: int) -> int:
    """Length of ``reduced_rhs``'s work space: load sums (2n), gamma (2n), the sweep (19n),
    and one slot for the largest |gamma| seen (``track_bending``)."""
    return 4 * n + sweep_work_size(n) + 1


@njit(cache=True)
def track_bending(gamma: Arr, seen: float) -> float:
    """max(seen, max |gamma|): the largest bending angle (rad) met by the solves of a run."""
    for v in gamma:
        if abs(v) > seen:
            seen = abs(v)
    return seen


@njit(cache=True, inline="always")
def rhs_work(t: float, y: Arr, M: Arr, L: Arr, out: Arr) -> tuple[Loads, Arr, Arr]:
    """The start of the reduced model's compiled right-hand sides (``rhs_head``: the hinge
    moments at the chord rates) on the work space M[0, 0] (``rhs_work_size``): (the
    ``Loads``, gamma, the solve's work). O(n)."""
    half = y.shape[0] // 2
    work = M[0, 0]
    loads = rhs_head(t, y, L, (work[:half], work[half : 2 * half]), out)
    return loads, work[2 * half : 4 * half], work[4 * half : work.shape[0] - 1]


@njit(cache=True)
def reduced_rhs(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, out: Arr) -> None:
    """y' of the reduced model (compiled integrators' right-hand side, loads and hinge moments
    from table L, the moments at the chord rates); O(n) time and memory per evaluation, no
    allocation without hinge moments: ``M[0, 0]`` is its work space (``rhs_work_size``;
    ``ReducedSystem.compiled_scratch``), whose last slot keeps the largest |alpha|, |beta| of
    the solves (the run's small-bending check, at no extra solve)."""
    loads, gamma, work = rhs_work(t, y, M, L, out)
    sol = (out[y.shape[0] // 2 :], gamma)
    reduced_solve_work(P, y, loads, S[0] != 0.0, sol, work, METHOD_AUTO)
    M[0, 0, -1] = track_bending(gamma, M[0, 0, -1])
