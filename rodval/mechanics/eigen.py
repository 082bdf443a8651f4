"""Eigenproblems of linear structural dynamics, accurate over the whole spectrum and the same
on every BLAS kernel: the one solver that every model's modal analysis uses (the native
models' ``rodval.models.observation.linear_modes`` and exudyn's ``reference_models.exudyn_modes``).

Why not ``scipy.linalg.eigh(K, M)`` alone
-----------------------------------------
A chain of soft hinges and stiff rods has a spectrum that spans many decades: the paper chain's
full model from omega^2 = 6.1e-3 (0.078 rad/s) to 7.3e6 (a span of 1.2e9), exudyn's beam model
to its axial modes at omega^2 ~ EA / (m le^2) = 2.2e10 (a span of 3.7e12). ``eigh(K, M)``
reduces the pencil with a Cholesky factor of M and returns each eigenvalue with an absolute
error of order eps * omega_max^2: the lowest one keeps only log10(1 / (eps span)) digits
(3-4 for exudyn), and which of them survive depends on the order of the floating-point
operations, i.e. on the BLAS kernel (``OPENBLAS_CORETYPE``).

The inverted pencil ``M x = mu (K - sigma M) x`` (Cholesky factor of K - sigma M,
lam = sigma + 1 / mu) turns that around: its absolute error is of order eps * mu_max, so the
*lowest* eigenvalues are the accurate ones, to about eps * (lam / lam_min) relative. Each
eigenvalue is therefore taken from the solve that carries it best: the inverted pencil below the
geometric mean of the spectrum's ends, the direct one above it (both errors are then at most
about eps * sqrt(span) relative). The shift sigma is 0 when K is positive definite; otherwise
(a free hinge: rigid-body modes; a buckled state) the smallest of -s, -100 s, ... for which
K - sigma M is positive definite, s = 1e-10 max diag(K) / max diag(M); the error this adds to
a zero eigenvalue is about eps |sigma|, and the split is the geometric mean of the shifted
spectrum's ends, lam - sigma (``_from_inverted``). For such a K, eigenvalues below eps lam_max (the
round-off that K's own entries put on a zero mode) are returned as exactly 0; a positive
definite K has no zero modes and none is made (the threshold of 1e-13 lam_max used before
took exudyn's lowest hinge mode, 6.1e-3, for a zero mode at 16 elements per rod).

The damped (quadratic) problem ``(s^2 M + s C + K) x = 0`` is solved the same way, for
z = 1 / (s - sigma_s) of the linearization
``z [x; y] = [[0, I], [-K'^-1 M, -K'^-1 C']] [x; y]`` with C' = C + 2 sigma_s M,
K' = K + sigma_s C + sigma_s^2 M: the low modes (the ones damping ratios are asked of) carry
about eps * |s| / |s_min| relative error.

Digits carried (measured, ``tests/test_eigen.py`` and ``docs/modes.md``): the paper chain's
lowest frequency is the same to 1e-11 relative on the default, Haswell and Prescott kernels in
the native full model and in exudyn (8 elements per rod); the direct solve alone moved exudyn's
by 1.6e-5.

Cost: two dense symmetric eigensolves of size N, O(N^3); the quadratic problem one dense
non-symmetric eigensolve of size 2N, O(N^3).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

#: Shift scale s relative to max diag(K) / max diag(M) for a pencil whose K is not positive
#: definite (see the module docstring); each retry multiplies the shift by SHIFT_GROWTH.
SHIFT_SCALE = 1e-10
SHIFT_GROWTH = 100.0
#: Retries before the pencil is declared not definite (the last shift is -1e20 s).
SHIFT_TRIES = 12
#: When K is singular (it needs a shift), eigenvalues with |lam| <= ZERO_FLOOR max|lam| are its
#: zero modes. K's entries carry round-off of eps |K|, which leaves an exact zero mode at up to
#: about 1e-2 eps lam_max in the chains here (exudyn's pinned rod, 16 elements: lam = -3e-7
#: beside lam_max = 9e10; the native free-root chain: 5.6e-17 beside 1e7); the lowest genuine
#: mode lies above 10 eps lam_max (exudyn's paper-chain hinge mode, EA = 1e10: 6.1e-3 beside
#: 2.3e12). A K that is positive definite beyond that round-off (no shift) has no zero modes,
#: and none is made.
ZERO_FLOOR = np.finfo(float).eps


def _is_definite(A: np.ndarray) -> bool:
    try:
        scipy.linalg.cholesky(A, lower=True)
        return True
    except np.linalg.LinAlgError:
        return False


def _definite_shift(K: np.ndarray, M: np.ndarray) -> float:
    """The shift sigma <= 0 (units of lam) for which K - sigma M is positive definite: 0 if K
    is positive definite beyond its round-off (K - ZERO_FLOOR r M is, r = max diag(K) /
    max diag(M)), else the first of -s, -100 s, ... (s: ``SHIFT_SCALE`` r). A nonzero shift
    marks K as (numerically) singular: its zero modes are then returned as exactly 0."""
    ratio = float(np.max(np.abs(np.diag(K)))) / float(np.max(np.diag(M)))
    if _is_definite(K - ZERO_FLOOR * ratio * M):
        return 0.0
    sigma = -SHIFT_SCALE * ratio
    for _ in range(SHIFT_TRIES):
        if _is_definite(K - sigma * M):
            return sigma
        sigma *= SHIFT_GROWTH
    raise ValueError(
        "the stiffness matrix is not definite even shifted by "
        f"{sigma:.3g} (1/s^2) times the mass matrix: the linearized system is unstable"
    )


def symmetric_pencil(
    K: np.ndarray, M: np.ndarray, *, vectors: bool = True
) -> tuple[np.ndarray, np.ndarray | None]:
    """Eigenvalues lam (ascending, 1/s^2 for stiffness and mass matrices) and M-orthonormal
    eigenvectors (columns, or None) of K x = lam M x; K symmetric, M symmetric positive
    definite, both read from their lower triangles (as ``scipy.linalg.eigh`` does: averaging
    K with its transpose would mix in the upper triangle's round-off, which moves exudyn's
    lowest paper-chain frequency by 9e-9 relative and makes it kernel-dependent). Each
    eigenvalue from the direct or the inverted pencil, whichever carries it better (module
    docstring). Cost O(N^3)."""
    sigma = _definite_shift(K, M)
    if vectors:
        lam_d, X_d = scipy.linalg.eigh(K, M)
        mu, X_i = scipy.linalg.eigh(M, K - sigma * M)
    else:
        lam_d, X_d = scipy.linalg.eigh(K, M, eigvals_only=True), None
        mu, X_i = scipy.linalg.eigh(M, K - sigma * M, eigvals_only=True), None
    # mu > 0 (both sides definite); ascending lam = descending mu
    order = np.argsort(-mu)
    lam_i = sigma + 1.0 / mu[order]
    lam_max = max(abs(lam_d[-1]), abs(lam_i[-1]))
    low = _from_inverted(lam_i, lam_max, sigma)
    lam = _zero_floor(np.where(low, lam_i, lam_d), sigma)
    if X_d is None or X_i is None:
        return np.sort(lam), None
    # the inverted pencil's vectors are normalized in K - sigma M: rescale to x^T M x = 1
    Xi = X_i[:, order]
    Xi = Xi / np.sqrt(np.einsum("ij,ij->j", Xi, M @ Xi))
    X = np.where(low[None, :], Xi, X_d)
    srt = np.argsort(lam, kind="stable")
    return lam[srt], X[:, srt]


def _from_inverted(lam_i: np.ndarray, lam_max: float, sigma: float) -> np.ndarray:
    """Which eigenvalues (ascending ``lam_i``, 1/s^2, from the inverted pencil shifted by
    ``sigma`` <= 0) are taken, with their vectors, from the inverted pencil rather than the
    direct one: the ones it carries better. Its eigenvalues mu = 1 / (lam - sigma) carry an
    absolute error of about eps mu_max, mu_max = 1 / (lam_0 - sigma), so lam an error of
    about eps (lam - sigma)^2 / (lam_0 - sigma); the direct solve's is eps lam_max: the
    inverted one wins for lam - sigma <= sqrt((lam_0 - sigma) lam_max), the split (module
    docstring; with sigma = 0 the geometric mean of the spectrum's ends). A singular K's zero
    modes (lam_0 - sigma = |sigma|) all fall below it, so their vectors are one basis of the
    null space; the split set by a zero mode's own round-off (0 or a few ulps of sigma) fell
    anywhere from 1e-150 to 1e-3, cut a cluster of zero modes in two and mixed vectors of two
    different bases of the null space, not a basis of it (a free base's rigid modes came out
    as two equal vectors, issue 54), and took the lowest genuine modes from the direct
    solve, which carries them to eps lam_max / lam only."""
    shifted = lam_i - sigma
    lam_0 = max(float(shifted[0]), np.finfo(float).tiny)
    low: np.ndarray = shifted <= np.sqrt(lam_0 * lam_max)
    return low


def _zero_floor(lam: np.ndarray, sigma: float) -> np.ndarray:
    """lam with a singular K's zero modes (``ZERO_FLOOR``) set to exactly 0; unchanged when K
    is positive definite (sigma = 0)."""
    if sigma == 0.0 or not lam.size:
        return lam
    return np.where(np.abs(lam) <= ZERO_FLOOR * float(np.max(np.abs(lam))), 0.0, lam)


def angular_frequencies(lam: np.ndarray) -> np.ndarray:
    """omega (rad/s) of eigenvalues lam = omega^2 (1/s^2): sqrt(lam), and -sqrt(-lam) for a
    negative lam (an unstable, e.g. buckled, configuration)."""
    omega: np.ndarray = np.sign(lam) * np.sqrt(np.abs(lam))
    return omega


def quadratic_eigenvalues(
    M: np.ndarray, C: np.ndarray, K: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues s (1/s) and eigenvectors (columns, the displacement part) of
    (s^2 M + s C + K) x = 0, by the shifted inverted linearization (module docstring). Cost
    O(N^3) (one dense eigensolve of size 2N)."""
    N = M.shape[0]
    sigma_lam = _definite_shift(K, M)
    sigma = np.sqrt(-sigma_lam)  # s-plane shift: K' >= K + sigma^2 M > 0 when C >= 0
    Cs = C + 2.0 * sigma * M
    Ks = K + sigma * C + sigma**2 * M
    lu = scipy.linalg.lu_factor(Ks)
    A = np.zeros((2 * N, 2 * N))
    A[:N, N:] = np.eye(N)
    A[N:, :N] = -scipy.linalg.lu_solve(lu, M)
    A[N:, N:] = -scipy.linalg.lu_solve(lu, Cs)
    z, V = scipy.linalg.eig(A)
    finite = np.abs(z) > 0
    s = sigma + 1.0 / z[finite]
    return s, V[:N, finite]


def coordinate_null_space(J: np.ndarray) -> np.ndarray | None:
    """An exact 0/1 basis B (N, N - r) of the null space of constraint rows J (r, N) whose rows
    each fix one coordinate (one nonzero) or make two equal (two opposite nonzeros), e.g.
    pinned and revolute joints on nodal position coordinates; zero rows (inactive joints) are
    skipped. None when a row has another form (the caller then needs a general basis). Unlike
    an SVD basis it does not rotate coordinates into each other, so it keeps a pencil's
    stiffness scales apart and does not depend on the BLAS kernel. Cost O(N r)."""
    N = J.shape[1]
    parent = list(range(N))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    fixed = []
    for row in np.asarray(J, float):
        nz = np.flatnonzero(row)
        if nz.size == 0:
            continue
        if nz.size == 1:
            fixed.append(int(nz[0]))
        elif nz.size == 2 and row[nz[0]] == -row[nz[1]]:
            parent[find(int(nz[1]))] = find(int(nz[0]))
        else:
            return None
    fixed_roots = {find(i) for i in fixed}
    column: dict[int, int] = {}
    B = np.zeros((N, N))
    for i in range(N):
        r = find(i)
        if r in fixed_roots:
            continue
        B[i, column.setdefault(r, len(column))] = 1.0
    return B[:, : len(column)]


def constraint_basis(A: np.ndarray) -> np.ndarray:
    """A basis Z (N, N - m) of the null space of the linear constraints A q = 0 (A: (m, N),
    full row rank), q = Z u: exact where every row has a pivot, a coordinate of its own that
    no other row touches (a held hinge's alpha_k, rod k's root slope: its row is
    phi_k + alpha_k - phi_{k-1} - beta_{k-1}), which is then eliminated, q_pivot =
    -(row's other terms) / A[row, pivot], every other coordinate kept as it is (a 0/1
    column, or one with the row's ratios: no rotation of coordinates into each other, so the
    condensed pencil Z^T K Z, Z^T M Z keeps the stiffness scales apart); otherwise an
    orthonormal basis (``scipy.linalg.null_space``). Cost O(m N) to find the pivots,
    O(N (N - m)) to write Z."""
    A = np.atleast_2d(np.asarray(A, float))
    m, N = A.shape
    nonzero = A != 0
    touched = nonzero.sum(axis=0)
    pivots = []
    for i in range(m):
        own = np.flatnonzero(nonzero[i] & (touched == 1))
        if own.size == 0:
            basis: np.ndarray = scipy.linalg.null_space(A)
            return basis
        pivots.append(int(own[np.argmax(np.abs(A[i, own]))]))
    keep = np.setdiff1d(np.arange(N), pivots)
    Z = np.zeros((N, keep.size))
    Z[keep, np.arange(keep.size)] = 1.0
    for i, p in enumerate(pivots):
        Z[p] = -A[i, keep] / A[i, p]
    return Z
