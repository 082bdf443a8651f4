"""The reduced model's banded LU solve, the fallback of ``rodval.models.bending.reduced_banded``'s
sweep, and the layout of the per-rod constants both read (``Cst``).

Banded LU (METHOD_BAND; Gaussian elimination with partial pivoting over the whole band).
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
computed once per ``Cst`` by ``equilibrate`` on the banded LU's first use: the sweep, the
default, never reads them), which changes no value in exact arithmetic and makes the pivot
choice independent of units. Its determinant is +-det(B) det(M_r), so the
banded system is regular exactly when the dense reduced one is.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.models.assembly.kernels import (
    V_CB,
    V_KAPPA,
    V_KB,
    V_L,
    V_OUTER,
    V_PPDIAG,
    V_W,
    Arr,
    Pair,
)

# Rows of Cst: the first rows are laid out like kernels.V (so that the kernels' O(n) helpers
# read them), then the bending-row diagonals and the equilibration scales.
#: number of Cst's leading rows laid out like kernels.V (rows 0 .. N_V_ROWS - 1; V_CB the last
#: of ``kernels.constant_rows``)
N_V_ROWS = V_CB + 1
C_AP, C_BP = N_V_ROWS, N_V_ROWS + 1
#: 1.0 once the scales below hold the equilibration (``equilibrate``), 0.0 while they are 1
C_EQUIL = N_V_ROWS + 2
#: first of 7 rows of row scales (one per local equation) and of 7 rows of column scales
C_RSCALE = N_V_ROWS + 3
C_CSCALE = C_RSCALE + 7
N_CST = C_CSCALE + 7
#: Ruiz sweeps of the equilibration: the powers of two stop changing after 15-19 sweeps on the
#: paper chain and on random chains with coefficients spread over 9 decades (n = 3000)
RUIZ_SWEEPS = 20

#: unknowns per rod and their local order
NB = 7
U_SX, U_SY, U_A, U_PX, U_PY, U_X, U_B = range(NB)
#: equations per rod and their local order
E_PX, E_PY, E_AL, E_PHI, E_SX, E_SY, E_BE = range(NB)
#: sub- and super-diagonals of the banded matrix (before pivoting)
KL, KU = 4, 6
#: band storage width: row i keeps columns i - KL .. i + KL + KU (room for pivoting fill)
W = 2 * KL + KU + 1
#: rows of the ring of active rows (a power of two > rows alive at once, 2 NB + KL)
RING = 16
RMASK = RING - 1


@njit(cache=True, inline="always")
def _put(A: Arr, mask: int, i: int, j: int, v: float) -> None:
    """A[i, j] = v in row-relative band storage: row i lives in A[i & mask] (mask = -1: all
    rows; mask = RING - 1: a ring of rows) and keeps column j at offset j - i + KL."""
    A[i & mask, j - i + KL] = v


@njit(cache=True)
def _fill_rod(Cst: Arr, k: int, c: Arr, s: Arr, A: Arr, mask: int) -> None:
    """Write the 7 equation rows of rod k (rows 7k .. 7k+6) into the band storage ``A``,
    equilibrated (entry (i, j) times row scale R_i and column scale C_j); c, s = cos, sin of
    phi. The rows are zeroed first; row i is stored in A[i & mask] (see _put)."""
    n = Cst.shape[1]
    r0 = here = NB * k  # the rod's first row and first column
    prev, nxt = here - NB, here + NB
    for i in range(r0, r0 + NB):
        A[i & mask, :] = 0.0
    R = Cst[C_RSCALE : C_RSCALE + NB, k]  # this rod's row scales
    Ch = Cst[C_CSCALE : C_CSCALE + NB, k]  # column scales: this rod, previous, next
    Cp = Cst[C_CSCALE : C_CSCALE + NB, k - 1] if k > 0 else Ch
    Cn = Cst[C_CSCALE : C_CSCALE + NB, k + 1] if k + 1 < n else Ch
    l, outer, w = Cst[V_L, k], Cst[V_OUTER, k], Cst[V_W, k]
    kap, kb = Cst[V_KAPPA, k], Cst[V_KB, k]
    kap_next = Cst[V_KAPPA, k + 1] if k + 1 < n else 0.0
    ck, sk = c[k], s[k]
    # prefix sums: P_k - P_{k-1} - l_{k-1} e_{k-1} x_{k-1} = 0
    rx, ry = R[E_PX], R[E_PY]
    _put(A, mask, r0 + E_PX, here + U_PX, rx * Ch[U_PX])
    _put(A, mask, r0 + E_PY, here + U_PY, ry * Ch[U_PY])
    if k > 0:
        lp = Cst[V_L, k - 1]
        _put(A, mask, r0 + E_PX, prev + U_PX, -rx * Cp[U_PX])
        _put(A, mask, r0 + E_PY, prev + U_PY, -ry * Cp[U_PY])
        _put(A, mask, r0 + E_PX, prev + U_X, -rx * lp * c[k - 1] * Cp[U_X])
        _put(A, mask, r0 + E_PY, prev + U_X, -ry * lp * s[k - 1] * Cp[U_X])
    # alpha row: w e.P + ap x + kappa_k (alpha_k - beta_{k-1}) + kb (alpha + beta/2)
    row = r0 + E_AL
    r = R[E_AL]
    _put(A, mask, row, here + U_PX, r * w * ck * Ch[U_PX])
    _put(A, mask, row, here + U_PY, r * w * sk * Ch[U_PY])
    _put(A, mask, row, here + U_X, r * Cst[C_AP, k] * Ch[U_X])
    _put(A, mask, row, here + U_A, r * (kap + kb) * Ch[U_A])
    _put(A, mask, row, here + U_B, r * 0.5 * kb * Ch[U_B])
    if k > 0:
        _put(A, mask, row, prev + U_B, -r * kap * Cp[U_B])
    # phi row: pp x + l M e.P + l e.S_{k+1} + (K_pg gamma)_k
    row = r0 + E_PHI
    r = R[E_PHI]
    _put(A, mask, row, here + U_X, r * Cst[V_PPDIAG, k] * Ch[U_X])
    _put(A, mask, row, here + U_PX, r * l * outer * ck * Ch[U_PX])
    _put(A, mask, row, here + U_PY, r * l * outer * sk * Ch[U_PY])
    _put(A, mask, row, here + U_A, r * kap * Ch[U_A])
    _put(A, mask, row, here + U_B, r * kap_next * Ch[U_B])
    if k > 0:
        _put(A, mask, row, prev + U_B, -r * kap * Cp[U_B])
    if k + 1 < n:
        _put(A, mask, row, nxt + U_SX, r * l * ck * Cn[U_SX])
        _put(A, mask, row, nxt + U_SY, r * l * sk * Cn[U_SY])
        _put(A, mask, row, nxt + U_A, -r * kap_next * Cn[U_A])
    # suffix sums: S_k - S_{k+1} - M_k l_k e_k x_k = 0
    rx, ry = R[E_SX], R[E_SY]
    _put(A, mask, r0 + E_SX, here + U_SX, rx * Ch[U_SX])
    _put(A, mask, r0 + E_SY, here + U_SY, ry * Ch[U_SY])
    _put(A, mask, r0 + E_SX, here + U_X, -rx * outer * l * ck * Ch[U_X])
    _put(A, mask, r0 + E_SY, here + U_X, -ry * outer * l * sk * Ch[U_X])
    if k + 1 < n:
        _put(A, mask, r0 + E_SX, nxt + U_SX, -rx * Cn[U_SX])
        _put(A, mask, r0 + E_SY, nxt + U_SY, -ry * Cn[U_SY])
    # beta row: -w e.P + bp x + kappa_{k+1} (beta_k - alpha_{k+1}) + kb (alpha/2 + beta)
    row = r0 + E_BE
    r = R[E_BE]
    _put(A, mask, row, here + U_PX, -r * w * ck * Ch[U_PX])
    _put(A, mask, row, here + U_PY, -r * w * sk * Ch[U_PY])
    _put(A, mask, row, here + U_X, r * Cst[C_BP, k] * Ch[U_X])
    _put(A, mask, row, here + U_A, r * 0.5 * kb * Ch[U_A])
    _put(A, mask, row, here + U_B, r * (kb + kap_next) * Ch[U_B])
    if k + 1 < n:
        _put(A, mask, row, nxt + U_A, -r * kap_next * Cn[U_A])


@njit(cache=True)
def _eliminate(A: Arr, b: Arr, j: int, U: Arr) -> bool:
    """Column j of banded Gaussian elimination with partial pivoting: pivot among rows
    j .. j+KL, swap, eliminate below (the right-hand side b follows), and move the finished
    row j (diagonal and KL + KU super-diagonals) to U[j]. Active rows live in the ring A
    (row i in A[i & RMASK], column c at offset c - i + KL); past the last equation the ring
    holds KL zero rows, so that all loops have fixed trip counts."""
    p = 0
    big = abs(A[j & RMASK, KL])
    for r in range(1, KL + 1):
        v = abs(A[(j + r) & RMASK, KL - r])
        if v > big:
            big = v
            p = r
    if big == 0.0:
        return False
    rj = j & RMASK
    if p != 0:
        rq = (j + p) & RMASK
        for o in range(KL, W):
            t = A[rj, o]
            A[rj, o] = A[rq, o - p]
            A[rq, o - p] = t
        t = b[j]
        b[j] = b[j + p]
        b[j + p] = t
    piv = A[rj, KL]
    bj = b[j]
    for r in range(1, KL + 1):
        ri = (j + r) & RMASK
        f = A[ri, KL - r]
        if f != 0.0:
            f /= piv
            A[ri, KL - r] = 0.0
            for o in range(KL + 1, W):
                A[ri, o - r] -= f * A[rj, o]
            b[j + r] -= f * bj
    for o in range(KL, W):
        U[j, o - KL] = A[rj, o]
    return True


@njit(cache=True)
def solve_band(Cst: Arr, c: Arr, s: Arr, f: Arr, work: Arr, out: Pair) -> bool:
    """The banded LU with partial pivoting (module docstring) of the 7n x 7n system with the
    right-hand sides f (3, n: phi, alpha, beta rows) into out = (phi'', gamma). ``work``
    (>= ``band_size(n)``) holds U (7n x 11), b (7n + 10) and A (RING x W). False if a pivot
    column is exactly zero. Its first call on a ``Cst`` writes the equilibration into it
    (``equilibrate``)."""
    n = c.shape[0]
    N = NB * n
    o1 = N * (KL + KU + 1)
    o2 = o1 + N + KL + KU
    U = work[:o1].reshape((N, KL + KU + 1))
    b = work[o1:o2]
    A = work[o2 : o2 + RING * W].reshape((RING, W))
    ddphi_out, gamma_out = out
    equilibrate(Cst)
    for k in range(n):
        r0 = NB * k
        for e in range(NB):
            b[r0 + e] = 0.0
        b[r0 + E_AL] = f[1, k] * Cst[C_RSCALE + E_AL, k]
        b[r0 + E_PHI] = f[0, k] * Cst[C_RSCALE + E_PHI, k]
        b[r0 + E_BE] = f[2, k] * Cst[C_RSCALE + E_BE, k]
    b[N:] = 0.0  # padding: see _eliminate and the back substitution
    _fill_rod(Cst, 0, c, s, A, RMASK)
    for k in range(n):
        if k + 1 < n:  # rows 7k+7.. are reached from column 7k+3 on
            _fill_rod(Cst, k + 1, c, s, A, RMASK)
        else:  # KL zero rows past the last equation
            for i in range(N, N + KL):
                A[i & RMASK, :] = 0.0
        for j in range(NB * k, NB * k + NB):
            if not _eliminate(A, b, j, U):
                return False
    # back substitution with U (KL + KU super-diagonals), then undo the column scaling
    for i in range(N - 1, -1, -1):
        acc = b[i]
        for o in range(1, KL + KU + 1):  # columns i+1 .. i+KL+KU (b is padded)
            acc -= U[i, o] * b[i + o]
        b[i] = acc / U[i, 0]
    for k in range(n):
        r0 = NB * k
        ddphi_out[k] = b[r0 + U_X] * Cst[C_CSCALE + U_X, k]
        gamma_out[k] = b[r0 + U_A] * Cst[C_CSCALE + U_A, k]
        gamma_out[n + k] = b[r0 + U_B] * Cst[C_CSCALE + U_B, k]
    return True


@njit(cache=True)
def band_size(n: int) -> int:
    """Length (float64 entries) of the banded LU's work storage for n rods: U (7n x (KL + KU +
    1)), b (7n + KL + KU) and the ring A (RING x W), as ``solve_band`` takes them."""
    return NB * n * (KL + KU + 1) + NB * n + KL + KU + RING * W


@njit(cache=True)
def band_magnitudes(Cst: Arr) -> Arr:
    """Angle-independent coefficient magnitudes |A| of the banded matrix (c = s = 1,
    unit scales), in band storage (7n x W). O(n)."""
    n = Cst.shape[1]
    unit = Cst.copy()
    unit[C_RSCALE:] = 1.0
    one = np.ones(n)
    A = np.empty((NB * n, W))
    for k in range(n):
        _fill_rod(unit, k, one, one, A, -1)
    return np.abs(A)


@njit(cache=True)
def ruiz_equilibrate(T: Arr, rs: Arr, cs: Arr, sweeps: int) -> None:
    """Ruiz equilibration of the band magnitudes T (modified in place): after the sweeps
    every row and column of diag(rs) |A| diag(cs) has its largest entry close to 1. Each
    sweep: the row and column maxima, then every nonzero entry divided by the square roots
    of its row's and its column's (one square root per row and column). O(n) per sweep."""
    N = T.shape[0]
    rmax = np.empty(N)
    cmax = np.empty(N)
    rsq = np.empty(N)
    csq = np.empty(N)
    for _ in range(sweeps):
        cmax[:] = 0.0
        for i in range(N):
            rmax[i] = 0.0
            for o in range(T.shape[1]):
                v = T[i, o]
                rmax[i] = max(rmax[i], v)
                j = i - KL + o
                if v > 0.0 and v > cmax[j]:
                    cmax[j] = v
        for i in range(N):
            rsq[i] = np.sqrt(rmax[i])
            csq[i] = np.sqrt(cmax[i])
            fr = 1.0 / rsq[i] if rmax[i] > 0.0 else 1.0
            fc = 1.0 / csq[i] if cmax[i] > 0.0 else 1.0
            rs[i] *= fr
            cs[i] *= fc
        for i in range(N):
            fr = 1.0 / rsq[i] if rmax[i] > 0.0 else 1.0
            for o in range(T.shape[1]):
                if T[i, o] > 0.0:
                    T[i, o] *= fr / csq[i - KL + o]


@njit(cache=True)
def equilibrate(Cst: Arr) -> None:
    """Write the row and column scales of the banded LU into ``Cst`` (rows C_RSCALE ..,
    C_CSCALE ..; C_EQUIL set to 1), unless done: RUIZ_SWEEPS sweeps of Ruiz equilibration of
    the angle-independent magnitudes (``band_magnitudes``), each scale rounded to the nearest
    power of two (exact scaling: no rounding in the solve). Called by ``solve_band`` on its
    first use, so a run whose sweep never falls back pays nothing (``banded_constants``
    leaves the scales at 1). O(n) time, ~120n doubles of work memory while it runs."""
    if Cst[C_EQUIL, 0] != 0.0:
        return
    n = Cst.shape[1]
    rs = np.ones(NB * n)
    cs = np.ones(NB * n)
    ruiz_equilibrate(band_magnitudes(Cst), rs, cs, RUIZ_SWEEPS)
    rs = np.exp2(np.round(np.log2(rs)))
    cs = np.exp2(np.round(np.log2(cs)))
    for k in range(n):
        for e in range(NB):
            Cst[C_RSCALE + e, k] = rs[NB * k + e]
            Cst[C_CSCALE + e, k] = cs[NB * k + e]
    Cst[C_EQUIL, :] = 1.0
