"""The model ladder: the full model with ``shapes = p`` bending shapes per rod
(``rodval.models.kinematics.shapes``) and ``kinematics = "first-order"`` (the paper's: every product of
the bending coordinates g with phi'^2 or phi'' dropped) or ``"exact"`` (the assumed-mode
kinematics r = r_{k-1} + s e_k + eta n_k kept whole in T, the forces and the momenta, so the
model is Lagrangian and conserves energy to the integrator's tolerance). docs/model.md ("The
model ladder") derives it; shapes = 1 with first-order kinematics is the paper's model, which
``FullSystem`` runs unchanged (the ladder is only built for another rung). Its constants and
dense matrices live here, its system in ``rodval.models.systems.chain_system.LadderSystem``.

Coordinates q = [phi; alpha; beta; g_2; ...; g_p] (each n long), state [q; q'] (2 N, N =
n (p + 2)); a bubble coordinate g_i (i >= 2, m) scales psi_i, which vanishes with its slope at
both rod ends: hinge angles, latches, stops and node positions are the paper's.
"""

from __future__ import annotations

import numpy as np

from rodval.core.scene import Chain
from rodval.models.assembly.kernels import V_CB, V_EPS, V_KB, V_PI, V_RHO, V_TAU, V_W, constant_rows
from rodval.models.assembly.paper_matrices import (
    angle_differences,
    chain_constants,
    hinge_matrix,
    mass_matrix,
)
from rodval.models.kinematics.ladder_kernels import (
    BLOCK_A,
    BLOCK_B,
    BLOCK_C,
    BLOCK_K,
    BLOCK_P,
    BLOCK_PINV,
    LV_EXACT,
    LV_MASS,
    LV_MU,
    LV_P1,
    LV_SHAPES,
)
from rodval.models.kinematics.shapes import RodShapes, rod_shapes


def shapes_of(chain: Chain, p: int) -> RodShapes:
    """The chain's per-rod shape integrals (``shapes.rod_shapes``)."""
    return rod_shapes(p, chain.l, chain.m, chain.EI, chain.bending_damping)


def ladder_constants(chain: Chain, p: int, exact: bool) -> np.ndarray:
    """The kernels' V (``ladder_kernels``): the paper model's rows with V_W = 1, the Schur
    constants a^T P^-1 a, b^T P^-1 a, b^T P^-1 b of the shapes, V_KB = V_CB = 0, then the
    LV_* rows and the shape blocks. O(n p^3) (one small inverse per rod)."""
    n, P1 = chain.n, p + 1
    sh = shapes_of(chain, p)
    Pinv = np.linalg.inv(sh.P)
    Pinv = 0.5 * (Pinv + np.swapaxes(Pinv, 1, 2))
    rows = constant_rows(chain_constants(chain), chain)
    rows[V_W] = np.ones(n)
    rows[V_KB] = np.zeros(n)
    rows[V_CB] = np.zeros(n)
    V = np.zeros((LV_SHAPES + 2 * P1 + 4 * P1 * P1, n))
    V[: len(rows)] = rows
    V[V_EPS] = np.einsum("ki,kij,kj->k", sh.a, Pinv, sh.a)
    V[V_PI] = V[V_RHO] = np.einsum("ki,kij,kj->k", sh.b, Pinv, sh.a)
    V[V_TAU] = np.einsum("ki,kij,kj->k", sh.b, Pinv, sh.b)
    V[LV_MASS] = chain.m * chain.l
    V[LV_MU] = chain.mu
    V[LV_P1] = P1
    V[LV_EXACT] = 1.0 if exact else 0.0
    blocks = {BLOCK_A: sh.a, BLOCK_B: sh.b}
    for block, B in ((BLOCK_P, sh.P), (BLOCK_PINV, Pinv), (BLOCK_K, sh.K), (BLOCK_C, sh.C)):
        blocks[block] = B.reshape(n, P1 * P1)
    start = LV_SHAPES
    for block in sorted(blocks):
        width = blocks[block].shape[1]
        V[start : start + width] = blocks[block].T
        start += width
    return np.ascontiguousarray(V)


def rigid_constants(chain: Chain) -> np.ndarray:
    """The kernels' V of the rigid chain: the paper's rung (``ladder_constants(chain, 1,
    False)``) with zero bending mobility, the limit EI -> inf of every rung. The bending
    blocks (a, b, P, P^-1, K, C) and the Schur constants (V_EPS .. V_TAU) are zero, so
    ``ladder_solve`` leaves the Schur complement M_pp(phi) (the rigid rods' mass matrix with
    their far nodes) and gives every bending acceleration exactly 0: bending coordinates at
    rest stay at rest, D_k = phi_k - phi_{k-1} and the kernels are the rigid chain's.
    ``rigid_kernels`` runs them on the rigid state [phi; phi']. O(n)."""
    V = ladder_constants(chain, 1, False)
    V[[V_EPS, V_PI, V_RHO, V_TAU]] = 0.0
    V[LV_SHAPES:] = 0.0
    return V


def ladder_mass_matrix(chain: Chain, p: int, exact: bool, q: np.ndarray) -> np.ndarray:
    """M(q) (N, N) of a rung, dense (for the modal analysis; O(N^2)): the paper's M(phi) on
    [phi; alpha; beta], the bubbles' couplings (l_j c_kj a_k to the inboard phi_j, b_k to
    phi_k, P_k among the rod's shapes) and, with exact kinematics, g^T P g on the diagonal
    of M_pp and -A_k l_j s_kj (A_k = a_k . g_k) off it (docs/model.md)."""
    n, P1 = chain.n, p + 1
    sh = shapes_of(chain, p)
    N = n * (P1 + 1)
    M = np.zeros((N, N))
    M[: 3 * n, : 3 * n] = mass_matrix(chain_constants(chain), q[:n])
    ckj, skj = angle_differences(q[:n])
    g = q[n:N].reshape(P1, n)
    lower = np.tril(np.ones((n, n)), -1)  # [k, j]: k > j
    for i in range(2, P1):
        cols = slice(n * (1 + i), n * (2 + i))
        # phi_j . g_{k,i}: l_j c_kj a_k,i for j < k; b_k,i for j = k
        M[:n, cols] = (lower * ckj * chain.l[None, :] * sh.a[:, i][:, None]).T
        M[np.arange(n), n * (1 + i) + np.arange(n)] = sh.b[:, i]
        M[cols, :n] = M[:n, cols].T
    for k in range(n):
        idx = n * (1 + np.arange(P1)) + k
        M[np.ix_(idx, idx)] = sh.P[k]
    if exact:
        A = np.einsum("ki,ik->k", sh.a, g)
        off = -lower * A[:, None] * chain.l[None, :] * skj
        M[:n, :n] += off + off.T + np.diag(np.einsum("ik,kij,jk->k", g, sh.P, g))
    return M


def ladder_stiffness(chain: Chain, p: int, damping: bool = False) -> np.ndarray:
    """K (or C with ``damping``), (N, N): the hinges' springs (dampers) on D = A q and every
    rod's shape block K_k (C_k); constant."""
    n, P1 = chain.n, p + 1
    sh = shapes_of(chain, p)
    A = np.zeros((n, n * (p + 2)))  # D = A q: the paper's hinge matrix, no bubbles
    A[:, : 3 * n] = hinge_matrix(n)
    K = A.T @ np.diag(chain.nu if damping else chain.kappa) @ A
    B = sh.C if damping else sh.K
    for k in range(n):
        idx = n * (1 + np.arange(P1)) + k
        K[np.ix_(idx, idx)] += B[k]
    return np.asarray(K)


def rod_momenta_exact(
    chain: Chain,
    sh: RodShapes,
    exact: bool,
    phi: np.ndarray,
    dphi: np.ndarray,
    g: np.ndarray,
    dg: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p (n, 2) N s, h (n,) N m s about node 0, first moment (n, 2) kg m) of each rod with
    its far node in the rung's velocity field: r = r_{k-1} + z_k (s + i eta), z_k = e^{i phi_k}
    (complex plane), with the terms in g dropped for first-order kinematics. O(n p^2)."""
    l, ml = chain.l, chain.m * chain.l
    z = np.exp(1j * phi)
    v_nodes = np.cumsum(1j * l * dphi * z)
    r_nodes = np.cumsum(l * z)
    V = np.concatenate([[0.0], v_nodes[:-1]])
    R = np.concatenate([[0.0], r_nodes[:-1]])
    Ag = np.einsum("ki,ik->k", sh.a, g) if exact else np.zeros_like(phi)
    gPg = np.einsum("ik,kij,jk->k", g, sh.P, g) if exact else np.zeros_like(phi)
    W = dphi * ml * l / 2 + np.einsum("ki,ik->k", sh.a, dg) + 1j * dphi * Ag
    arm = ml * l / 2 + 1j * Ag  # int m (s + i eta) ds
    p = ml * V + 1j * z * W + chain.mu * v_nodes
    first = ml * R + z * arm + chain.mu * r_nodes
    h = (
        ml * np.imag(np.conj(R) * V)
        + np.imag(np.conj(R) * 1j * z * W)
        + np.imag(np.conj(z) * np.conj(arm) * V)
        + dphi * (ml * l * l / 3 + gPg)
        + np.einsum("ki,ik->k", sh.b, dg)
        + chain.mu * np.imag(np.conj(r_nodes) * v_nodes)
    )
    return np.stack([p.real, p.imag], -1), h, np.stack([first.real, first.imag], -1)
