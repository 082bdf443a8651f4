"""The reduced model's right-hand side and bending recovery in O(n) time and memory.

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

Unknowns, 7 per rod, ordered rod by rod as (S_k,x  S_k,y  alpha_k  P_k,x  P_k,y  x_k  beta_k);
equations per rod in the row order

    P_k - P_{k-1} - l_{k-1} e_{k-1} x_{k-1} = 0   (2 rows; P_0 = 0)
    alpha row k,  phi row k,
    S_k - S_{k+1} - M_k l_k e_k x_k = 0           (2 rows; S_{n-1} = M l e x at the tip)
    beta row k.

With this order every row touches only its own rod and the two neighbours, and the 7n x 7n
matrix is banded with kl = 4 sub- and ku = 6 super-diagonals. It is solved by Gaussian
elimination with partial pivoting on the band (LAPACK gbtf2/gbtrs style, the right-hand side
eliminated on the fly; U then has kl + ku super-diagonals). Rows and columns are equilibrated
by constant powers of two (Ruiz scaling of the angle-independent coefficient magnitudes,
computed once in ``banded_constants``), which changes no value in exact arithmetic and makes
the pivot choice independent of units. Its determinant is +-det(B) det(M_r), so the
banded system is regular exactly when the dense reduced one is.

Cost: O(n) time and memory per evaluation (about 7n x 15 doubles of band storage and ~600 n
flops), no n x n array anywhere. phi'' and gamma come out of the same solve, so the bending
recovery is the same routine.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import (V_KAPPA, V_KB, V_L, V_NU, V_OUTER, V_PPDIAG, V_W, _gpp_times,
                      _hinge_forces, _upper_t_times)

# Rows of Cst: the first rows are laid out like kernels.V (so that the kernels' O(n) helpers
# read them), then the bending-row diagonals and the equilibration scales.
_BASE = max(V_L, V_OUTER, V_PPDIAG, V_W, V_KAPPA, V_NU, V_KB) + 1
C_AP, C_BP = _BASE, _BASE + 1
#: first of 7 rows of row scales (one per local equation) and of 7 rows of column scales
C_RSCALE = _BASE + 2
C_CSCALE = C_RSCALE + 7
N_CST = C_CSCALE + 7

#: unknowns per rod and their local order
NB = 7
U_SX, U_SY, U_A, U_PX, U_PY, U_X, U_B = range(NB)
#: equations per rod and their local order
E_PX, E_PY, E_AL, E_PHI, E_SX, E_SY, E_BE = range(NB)
#: sub- and super-diagonals of the banded matrix (before pivoting)
KL, KU = 4, 6
#: band storage width: row i keeps columns i - KL .. i + KL + KU (room for pivoting fill)
W = 2 * KL + KU + 1


@njit(cache=True, inline="always")
def _put(A, Cst, i, j, v):
    """A[i, j] = R_i v C_j in row-relative band storage (column j at offset j - i + KL)."""
    A[i, j - i + KL] = v * Cst[C_RSCALE + i % NB, i // NB] * Cst[C_CSCALE + j % NB, j // NB]


@njit(cache=True)
def _fill_rod(Cst, k, c, s, A):
    """Write the 7 equation rows of rod k (rows 7k .. 7k+6) into the band storage ``A``,
    equilibrated; c, s = cos, sin of phi. The rows are zeroed first."""
    n = Cst.shape[1]
    r0 = NB * k
    for i in range(r0, r0 + NB):
        for o in range(W):
            A[i, o] = 0.0
    l, outer, w = Cst[V_L, k], Cst[V_OUTER, k], Cst[V_W, k]
    kap, kb = Cst[V_KAPPA, k], Cst[V_KB, k]
    kap_next = Cst[V_KAPPA, k + 1] if k + 1 < n else 0.0
    ck, sk = c[k], s[k]
    here = NB * k
    prev = here - NB
    nxt = here + NB
    # prefix sums: P_k - P_{k-1} - l_{k-1} e_{k-1} x_{k-1} = 0
    _put(A, Cst, r0 + E_PX, here + U_PX, 1.0)
    _put(A, Cst, r0 + E_PY, here + U_PY, 1.0)
    if k > 0:
        lp = Cst[V_L, k - 1]
        _put(A, Cst, r0 + E_PX, prev + U_PX, -1.0)
        _put(A, Cst, r0 + E_PY, prev + U_PY, -1.0)
        _put(A, Cst, r0 + E_PX, prev + U_X, -lp * c[k - 1])
        _put(A, Cst, r0 + E_PY, prev + U_X, -lp * s[k - 1])
    # alpha row: w e.P + ap x + kappa_k (alpha_k - beta_{k-1}) + kb (alpha + beta/2)
    row = r0 + E_AL
    _put(A, Cst, row, here + U_PX, w * ck)
    _put(A, Cst, row, here + U_PY, w * sk)
    _put(A, Cst, row, here + U_X, Cst[C_AP, k])
    _put(A, Cst, row, here + U_A, kap + kb)
    _put(A, Cst, row, here + U_B, 0.5 * kb)
    if k > 0:
        _put(A, Cst, row, prev + U_B, -kap)
    # phi row: pp x + l M e.P + l e.S_{k+1} + (K_pg gamma)_k
    row = r0 + E_PHI
    _put(A, Cst, row, here + U_X, Cst[V_PPDIAG, k])
    _put(A, Cst, row, here + U_PX, l * outer * ck)
    _put(A, Cst, row, here + U_PY, l * outer * sk)
    _put(A, Cst, row, here + U_A, kap)
    _put(A, Cst, row, here + U_B, kap_next)
    if k > 0:
        _put(A, Cst, row, prev + U_B, -kap)
    if k + 1 < n:
        _put(A, Cst, row, nxt + U_SX, l * ck)
        _put(A, Cst, row, nxt + U_SY, l * sk)
        _put(A, Cst, row, nxt + U_A, -kap_next)
    # suffix sums: S_k - S_{k+1} - M_k l_k e_k x_k = 0
    _put(A, Cst, r0 + E_SX, here + U_SX, 1.0)
    _put(A, Cst, r0 + E_SY, here + U_SY, 1.0)
    _put(A, Cst, r0 + E_SX, here + U_X, -outer * l * ck)
    _put(A, Cst, r0 + E_SY, here + U_X, -outer * l * sk)
    if k + 1 < n:
        _put(A, Cst, r0 + E_SX, nxt + U_SX, -1.0)
        _put(A, Cst, r0 + E_SY, nxt + U_SY, -1.0)
    # beta row: -w e.P + bp x + kappa_{k+1} (beta_k - alpha_{k+1}) + kb (alpha/2 + beta)
    row = r0 + E_BE
    _put(A, Cst, row, here + U_PX, -w * ck)
    _put(A, Cst, row, here + U_PY, -w * sk)
    _put(A, Cst, row, here + U_X, Cst[C_BP, k])
    _put(A, Cst, row, here + U_A, 0.5 * kb)
    _put(A, Cst, row, here + U_B, kb + kap_next)
    if k + 1 < n:
        _put(A, Cst, row, nxt + U_A, -kap_next)


@njit(cache=True)
def _eliminate(A, b, j, N):
    """One column of banded Gaussian elimination with partial pivoting: pivot for column j
    among rows j .. j+KL, swap, and eliminate below; the right-hand side b follows."""
    last = min(N - 1, j + KL)
    p = j
    big = abs(A[j, KL])
    for i in range(j + 1, last + 1):
        v = abs(A[i, j - i + KL])
        if v > big:
            big = v
            p = i
    if p != j:
        for col in range(j, min(N - 1, j + KL + KU) + 1):
            t = A[j, col - j + KL]
            A[j, col - j + KL] = A[p, col - p + KL]
            A[p, col - p + KL] = t
        t = b[j]
        b[j] = b[p]
        b[p] = t
    piv = A[j, KL]
    if piv == 0.0:
        return False
    cmax = min(N - 1, j + KL + KU)
    for i in range(j + 1, last + 1):
        f = A[i, j - i + KL] / piv
        if f != 0.0:
            A[i, j - i + KL] = 0.0
            d = KL - i
            for col in range(j + 1, cmax + 1):
                A[i, col + d] -= f * A[j, col - j + KL]
            b[i] -= f * b[j]
    return True


@njit(cache=True)
def _rhs(Cst, phi, dphi, c, s, has_load, SX, SY, damped, b):
    """The equilibrated right-hand side of the banded system into b (7n):
    r_p = Q - G_pp phi'^2 - C_pp phi' - K_pp phi, r_g = -(G_gp phi'^2 + C_gp phi' + K_gp phi)."""
    n = phi.shape[0]
    fp = np.zeros(n)
    fa = np.zeros(n)
    fb = np.zeros(n)
    zero = np.zeros(n)
    _hinge_forces(Cst, phi, zero, zero, V_KAPPA, fp, fa, fb)       # K_qp phi
    if damped:
        _hinge_forces(Cst, dphi, zero, zero, V_NU, fp, fa, fb)     # C_qp phi'
    for k in range(n):
        fp[k] = -fp[k]
        fa[k] = -fa[k]
        fb[k] = -fb[k]
    w2 = dphi * dphi
    _gpp_times(Cst, c, s, w2, fp)                  # - G_pp phi'^2
    _upper_t_times(Cst, c, s, w2, False, fa, 1.0)  # - G_ap phi'^2 = + G_pa^T phi'^2
    _upper_t_times(Cst, c, s, w2, False, fb, -1.0)  # - G_bp phi'^2 = - G_pa^T phi'^2
    if has_load:
        l = Cst[V_L]
        for k in range(n):
            fp[k] += l[k] * (c[k] * SY[k] - s[k] * SX[k])
    for k in range(n):
        r0 = NB * k
        for e in range(NB):
            b[r0 + e] = 0.0
        b[r0 + E_AL] = fa[k] * Cst[C_RSCALE + E_AL, k]
        b[r0 + E_PHI] = fp[k] * Cst[C_RSCALE + E_PHI, k]
        b[r0 + E_BE] = fb[k] * Cst[C_RSCALE + E_BE, k]


@njit(cache=True)
def reduced_solve(Cst, phi, dphi, has_load, SX, SY, damped, ddphi_out, gamma_out):
    """phi'' (rad/s^2, n) into ``ddphi_out`` and gamma = [alpha; beta] (rad, 2n) into
    ``gamma_out`` of the reduced model at state (phi, phi'), by one banded LU solve of the
    unreduced system (module docstring). ``Cst`` from ``banded_constants``; SX, SY are the
    load suffix sums (N, see kernels.load_sums), used when ``has_load``; ``damped`` adds the
    hinge dampers. O(n) time and memory per evaluation. Returns False if a pivot is exactly
    zero (singular system; outputs then hold NaN)."""
    n = phi.shape[0]
    N = NB * n
    c = np.cos(phi)
    s = np.sin(phi)
    b = np.empty(N)
    _rhs(Cst, phi, dphi, c, s, has_load, SX, SY, damped, b)
    A = np.empty((N, W))
    _fill_rod(Cst, 0, c, s, A)
    ok = True
    for k in range(n):
        if k + 1 < n:
            _fill_rod(Cst, k + 1, c, s, A)   # rows 7k+7.. are reached from column 7k+3 on
        for j in range(NB * k, NB * k + NB):
            if not _eliminate(A, b, j, N):
                ok = False
                break
        if not ok:
            break
    if not ok:
        ddphi_out[:] = np.nan
        gamma_out[:] = np.nan
        return False
    # back substitution with U (KL + KU super-diagonals), then undo the column scaling
    for i in range(N - 1, -1, -1):
        acc = b[i]
        d = KL - i
        for col in range(i + 1, min(N - 1, i + KL + KU) + 1):
            acc -= A[i, col + d] * b[col]
        b[i] = acc / A[i, KL]
    for k in range(n):
        r0 = NB * k
        ddphi_out[k] = b[r0 + U_X] * Cst[C_CSCALE + U_X, k]
        gamma_out[k] = b[r0 + U_A] * Cst[C_CSCALE + U_A, k]
        gamma_out[n + k] = b[r0 + U_B] * Cst[C_CSCALE + U_B, k]
    return True


@njit(cache=True)
def reduced_accel_banded(Cst, phi, dphi, has_load, SX, SY, damped, out):
    """phi'' of the reduced model into ``out`` (the argument list of kernels.reduced_accel
    with ``Cst`` in place of (V, Mt)); O(n) time and memory."""
    gamma = np.empty(2 * phi.shape[0])
    reduced_solve(Cst, phi, dphi, has_load, SX, SY, damped, out, gamma)


@njit(cache=True)
def _magnitudes(Cst):
    """Angle-independent coefficient magnitudes |A| of the banded matrix (c = s = 1,
    unit scales), in band storage."""
    n = Cst.shape[1]
    one = np.ones(n)
    A = np.empty((NB * n, W))
    for k in range(n):
        _fill_rod(Cst, k, one, one, A)
    return np.abs(A)


@njit(cache=True)
def _ruiz(T, rs, cs, sweeps):
    """Ruiz equilibration of the band magnitudes T (modified in place): after the sweeps
    every row and column of diag(rs) |A| diag(cs) has its largest entry close to 1."""
    N = T.shape[0]
    rmax = np.empty(N)
    cmax = np.empty(N)
    for _ in range(sweeps):
        cmax[:] = 0.0
        for i in range(N):
            rmax[i] = 0.0
            for o in range(T.shape[1]):
                v = T[i, o]
                if v > rmax[i]:
                    rmax[i] = v
                j = i - KL + o
                if v > 0.0 and v > cmax[j]:
                    cmax[j] = v
        for i in range(N):
            fr = 1.0 / np.sqrt(rmax[i]) if rmax[i] > 0.0 else 1.0
            fc = 1.0 / np.sqrt(cmax[i]) if cmax[i] > 0.0 else 1.0
            rs[i] *= fr
            cs[i] *= fc
        for i in range(N):
            fr = 1.0 / np.sqrt(rmax[i]) if rmax[i] > 0.0 else 1.0
            for o in range(T.shape[1]):
                j = i - KL + o
                if T[i, o] > 0.0:
                    T[i, o] *= fr / np.sqrt(cmax[j])


def banded_constants(cc, chain) -> np.ndarray:
    """Every angle-independent per-rod constant of ``reduced_solve`` as a float64 array
    (N_CST, n); ``cc = paper_matrices.chain_constants(chain, variant)``. O(n).

    Rows: the kernels.V layout (l (m), outer mass M_k (kg), M_pp diagonal (kg m^2),
    w = m l^2/12 (kg m), kappa (N m/rad), nu (N m s/rad), 4 EI/l (N m)), then the bending-row
    diagonals ap, bp (kg m^2; the only difference between the "printed" and "published"
    variants), then 7 row and 7 column equilibration scales (powers of two, per rod)."""
    n = chain.n
    Cst = np.zeros((N_CST, n))
    Cst[V_L] = cc.l
    Cst[V_OUTER] = cc.outer_mass
    Cst[V_PPDIAG] = cc.pp_diag
    Cst[V_W] = chain.m * chain.l**2 / 12.0
    Cst[V_KAPPA] = chain.kappa
    Cst[V_NU] = chain.nu
    Cst[V_KB] = 4.0 * chain.EI / chain.l
    Cst[C_AP] = cc.ap_diag
    Cst[C_BP] = cc.bp_diag
    Cst[C_RSCALE:] = 1.0
    rs = np.ones(NB * n)
    cs = np.ones(NB * n)
    _ruiz(_magnitudes(Cst), rs, cs, 20)
    pow2 = lambda v: np.exp2(np.round(np.log2(v)))        # exact scaling: no rounding
    Cst[C_RSCALE:C_RSCALE + NB] = pow2(rs).reshape(n, NB).T
    Cst[C_CSCALE:C_CSCALE + NB] = pow2(cs).reshape(n, NB).T
    return np.ascontiguousarray(Cst)


def bending_at(Cst: np.ndarray, phi: np.ndarray, dphi: np.ndarray, sums, damped: bool
               ) -> tuple[np.ndarray, np.ndarray]:
    """(phi'', gamma) at one state, ``sums`` = LoadSet.suffix_sums(t) (None: no load).
    The O(n) replacement of ReducedSystem.recover_bending (which returns gamma)."""
    n = phi.shape[0]
    phi = np.ascontiguousarray(phi, dtype=np.float64)
    dphi = np.ascontiguousarray(dphi, dtype=np.float64)
    if sums is None:
        SX = SY = np.zeros(n)
    else:
        SX, SY = (np.ascontiguousarray(v, dtype=np.float64) for v in sums)
    ddphi, gamma = np.empty(n), np.empty(2 * n)
    reduced_solve(Cst, phi, dphi, sums is not None, SX, SY, bool(damped), ddphi, gamma)
    return ddphi, gamma
