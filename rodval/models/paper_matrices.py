"""The paper's matrices (equations (9)-(10) of Russkikh 2022, restated in shared/paper/model.md).

Generalized coordinates q = [phi; alpha; beta] (3n), see ``rodval.core.scene`` for conventions.
Kinetic energy T = 1/2 q'^T M(phi) q' to first order in the bending coordinates; potential
Pi = 1/2 q^T K q; dissipation 1/2 q'^T C q'. The equations of motion of the full model are

    M(phi) q'' + h(phi, phi', alpha', beta') + C q' + K q = [Q(phi, t); 0; 0]

with the convective (gyroscopic/centrifugal) vector

    h_phi   = G_pp phi'^2 + 2 G_pa (phi' * alpha') + 2 G_pb (phi' * beta')
    h_alpha = G_ap phi'^2,     h_beta = G_bp phi'^2

where squares and products of vectors are element-wise. Blocks with c_kj = cos(phi_k - phi_j),
s_kj = sin(phi_k - phi_j), M_k = sum_{i>=k}(mu_i + m_i l_i) - m_k l_k/2, w_k = m_k l_k^2/12:

    M_pp[k,j] = l_k l_j c_kj M_max(k,j)  (k != j),   l_k^2 (M_k - m_k l_k/2) + m_k l_k^3/3 (k = j)
    G_pp[k,j] = l_k l_j s_kj M_max(k,j)
    M_pa[k,j] = w_j l_k c_kj (k < j),  m_k l_k^3/30 (k = j);   M_pb = -M_pa off-diagonal, -m_k l_k^3/20
    G_pa[k,j] = w_j l_k s_kj (k < j);                          G_pb = -G_pa
    M_ap = M_pa^T, M_bp = M_pb^T (printed coefficients); G_ap[k,j] = w_k l_j s_kj (k > j), G_bp = -G_ap
    M_aa = M_bb = diag(m l^3/105),  M_ab = M_ba = diag(-m l^3/140)

Coefficient variants
--------------------
``printed`` (default): the coefficients above, which follow from the kinematics; M is
symmetric positive definite.
``published``: the bending rows carry half of the diagonal phi-coupling (M_ap diagonal
m l^3/60, M_bp diagonal -m l^3/40) while the phi rows keep m l^3/30, -m l^3/20. This
non-symmetric matrix reproduces the alpha/beta values published in the paper's Table 1 and is
kept only to document that erratum (see model.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodval.core.scene import Chain

VARIANTS = ("printed", "published")


@dataclass(frozen=True, eq=False)
class ChainConstants:
    """Angle-independent arrays of a chain, computed once per scene."""

    n: int
    l: np.ndarray
    outer_mass: np.ndarray  # M_k (kg)
    pp_scale: np.ndarray  # l_k l_j M_max(k,j), (n, n)
    pp_diag: np.ndarray  # diagonal of M_pp (kg m^2)
    w_upper: np.ndarray  # w_j l_k for k < j, else 0 (kg m^2), (n, n)
    pa_diag: np.ndarray  # m l^3/30 in phi rows
    pb_diag: np.ndarray  # -m l^3/20 in phi rows
    ap_diag: np.ndarray  # bending-row diagonal coupling (variant dependent)
    bp_diag: np.ndarray
    aa_diag: np.ndarray  # m l^3/105
    ab_diag: np.ndarray  # -m l^3/140


def chain_constants(chain: Chain, variant: str = "printed") -> ChainConstants:
    """Precompute everything in M and G that does not depend on the angles."""
    if variant not in VARIANTS:
        raise ValueError(f"coefficients must be one of {VARIANTS}, got {variant!r}")
    l, m, mu = chain.l, chain.m, chain.mu
    n = chain.n
    rod_mass = m * l
    outer = np.cumsum((mu + rod_mass)[::-1])[::-1] - rod_mass / 2.0
    idx = np.arange(n)
    kmax = np.maximum.outer(idx, idx)
    pp_scale = np.outer(l, l) * outer[kmax]
    pp_diag = l**2 * (outer - rod_mass / 2.0) + m * l**3 / 3.0
    w = m * l**2 / 12.0
    w_upper = np.triu(np.outer(l, w), k=1)  # [k, j] = l_k w_j for k < j
    ml3 = m * l**3
    half = 0.5 if variant == "published" else 1.0
    return ChainConstants(
        n=n,
        l=l,
        outer_mass=outer,
        pp_scale=pp_scale,
        pp_diag=pp_diag,
        w_upper=w_upper,
        pa_diag=ml3 / 30.0,
        pb_diag=-ml3 / 20.0,
        ap_diag=half * ml3 / 30.0,
        bp_diag=-half * ml3 / 20.0,
        aa_diag=ml3 / 105.0,
        ab_diag=-ml3 / 140.0,
    )


def angle_differences(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """c_kj = cos(phi_k - phi_j), s_kj = sin(phi_k - phi_j) as (n, n) arrays."""
    c, s = np.cos(phi), np.sin(phi)
    return np.outer(c, c) + np.outer(s, s), np.outer(s, c) - np.outer(c, s)


def mass_matrix(cc: ChainConstants, phi: np.ndarray) -> np.ndarray:
    """Full-model mass matrix M(phi), (3n, 3n), ordering [phi; alpha; beta]."""
    return assemble_mass(cc, angle_differences(phi)[0])


def assemble_mass(cc: ChainConstants, ckj: np.ndarray) -> np.ndarray:
    """M from precomputed c_kj = cos(phi_k - phi_j)."""
    n = cc.n
    M_pp = cc.pp_scale * ckj
    np.fill_diagonal(M_pp, cc.pp_diag)
    U = cc.w_upper * ckj
    M = np.zeros((3 * n, 3 * n))
    p, a, b = slice(0, n), slice(n, 2 * n), slice(2 * n, 3 * n)
    d = np.arange(n)
    M[p, p] = M_pp
    M[p, a] = U
    M[p, b] = -U
    M[a, p] = U.T
    M[b, p] = -U.T
    M[d, n + d] = cc.pa_diag
    M[d, 2 * n + d] = cc.pb_diag
    M[n + d, d] = cc.ap_diag
    M[2 * n + d, d] = cc.bp_diag
    M[n + d, n + d] = cc.aa_diag
    M[2 * n + d, 2 * n + d] = cc.aa_diag
    M[n + d, 2 * n + d] = cc.ab_diag
    M[2 * n + d, n + d] = cc.ab_diag
    return M


def convective_terms(
    cc: ChainConstants,
    skj: np.ndarray,
    dphi: np.ndarray,
    dalpha: np.ndarray | None = None,
    dbeta: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Convective vector h = (h_phi, h_gamma) with h_gamma = [h_alpha; h_beta], from
    precomputed s_kj = sin(phi_k - phi_j).

    ``dalpha``/``dbeta`` = None means they are dropped (reduced model): h_phi = G_pp phi'^2.
    """
    G_pp = cc.pp_scale * skj
    G_pa = cc.w_upper * skj
    w2 = dphi * dphi
    h_phi = G_pp @ w2
    if dalpha is not None:
        h_phi += 2.0 * (G_pa @ (dphi * (dalpha - dbeta)))
    h_alpha = -(G_pa.T @ w2)  # G_ap[k,j] = w_k l_j s_kj (k > j) = -G_pa[j,k]
    return h_phi, np.concatenate([h_alpha, -h_alpha])


def angle_jacobian(scale: np.ndarray, dtrig: np.ndarray, u: np.ndarray) -> np.ndarray:
    """d(X u)/dphi for X[k,j] = scale[k,j] trig(phi_k - phi_j) and a fixed vector u, given
    dtrig[k,j] = trig'(phi_k - phi_j) (cos -> -s_kj, sin -> c_kj):
    d(X u)_k/dphi_i = delta_ki (X' u)_k - X'_ki u_i with X' = scale * dtrig, (n, n)."""
    Xp = scale * dtrig
    return np.diag(Xp @ u) - Xp * u


def hinge_matrix(n: int) -> np.ndarray:
    """A with hinge angles D = A q: D_i = (phi_i + alpha_i) - (phi_{i-1} + beta_{i-1}), (n, 3n).

    Hinge 0 measures rod 1's root tangent from the x axis (phi_0 = beta_0 = 0).
    """
    A = np.zeros((n, 3 * n))
    i = np.arange(n)
    A[i, i] = 1.0
    A[i, n + i] = 1.0
    A[i[1:], i[:-1]] = -1.0
    A[i[1:], 2 * n + i[:-1]] = -1.0
    return A


def stiffness_matrix(chain: Chain) -> np.ndarray:
    """K = Hessian of Pi (3n, 3n): hinge springs A^T diag(kappa) A plus bending blocks
    (4 EI/l) [[1, 1/2], [1/2, 1]] on (alpha_k, beta_k)."""
    n = chain.n
    A = hinge_matrix(n)
    K = A.T @ (chain.kappa[:, None] * A)
    kb = 4.0 * chain.EI / chain.l
    d = np.arange(n)
    K[n + d, n + d] += kb
    K[2 * n + d, 2 * n + d] += kb
    K[n + d, 2 * n + d] += kb / 2.0
    K[2 * n + d, n + d] += kb / 2.0
    return K


def damping_matrix(chain: Chain) -> np.ndarray:
    """C = Hessian of the dissipation function, A^T diag(nu) A (3n, 3n)."""
    A = hinge_matrix(chain.n)
    return A.T @ (chain.nu[:, None] * A)


def generalized_forces(
    l: np.ndarray, phi: np.ndarray, SX: np.ndarray, SY: np.ndarray
) -> np.ndarray:
    """Q_k = l_k (cos phi_k SY_k - sin phi_k SX_k), SX_k = sum_{j>=k} X_j (N m)."""
    return l * (np.cos(phi) * SY - np.sin(phi) * SX)


def node_positions(l: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates x_k, y_k (m), k = 0..n, along the last axis; phi may be (..., n)."""
    x = np.cumsum(l * np.cos(phi), axis=-1)
    y = np.cumsum(l * np.sin(phi), axis=-1)
    zero = np.zeros(phi.shape[:-1] + (1,))
    return np.concatenate([zero, x], axis=-1), np.concatenate([zero, y], axis=-1)
