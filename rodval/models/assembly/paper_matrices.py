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
from functools import cached_property
from typing import Any, cast

import numpy as np
from scipy.linalg import solveh_banded

from rodval.core.checks import check_choice
from rodval.core.scene import Chain, hinge_angles

VARIANTS = ("printed", "published")
#: The coefficient variant every model and analysis uses unless told otherwise.
DEFAULT_VARIANT = VARIANTS[0]


@dataclass(frozen=True, eq=False)
class ChainConstants:
    """Angle-independent arrays of a chain, computed once per scene: per-rod vectors (O(n));
    the two n x n scales of the dense reference (``pp_scale``, ``w_upper``) only when asked
    for (the O(n) kernels never ask)."""

    n: int
    l: np.ndarray
    w: np.ndarray  # m l^2 / 12 (kg m)
    outer_mass: np.ndarray  # M_k (kg)
    pp_diag: np.ndarray  # diagonal of M_pp (kg m^2)
    pa_diag: np.ndarray  # m l^3/30 in phi rows
    pb_diag: np.ndarray  # -m l^3/20 in phi rows
    ap_diag: np.ndarray  # bending-row diagonal coupling (variant dependent)
    bp_diag: np.ndarray
    aa_diag: np.ndarray  # m l^3/105
    ab_diag: np.ndarray  # -m l^3/140

    @cached_property
    def pp_scale(self) -> np.ndarray:
        """l_k l_j M_max(k,j), (n, n): O(n^2) memory, for the dense reference only."""
        idx = np.arange(self.n)
        return np.asarray(np.outer(self.l, self.l) * self.outer_mass[np.maximum.outer(idx, idx)])

    @cached_property
    def w_upper(self) -> np.ndarray:
        """w_j l_k for k < j, else 0 (kg m^2), (n, n): for the dense reference only."""
        return np.triu(np.outer(self.l, self.w), k=1)


def chain_constants(chain: Chain, variant: str = DEFAULT_VARIANT) -> ChainConstants:
    """Precompute everything in M and G that does not depend on the angles (O(n))."""
    check_choice("coefficients", variant, VARIANTS)
    l, m, mu = chain.l, chain.m, chain.mu
    rod_mass = m * l
    outer = np.cumsum((mu + rod_mass)[::-1])[::-1] - rod_mass / 2.0
    ml3 = m * l**3
    half = 0.5 if variant == "published" else 1.0
    return ChainConstants(
        n=chain.n,
        l=l,
        w=m * l**2 / 12.0,
        outer_mass=outer,
        pp_diag=l**2 * (outer - rod_mass / 2.0) + ml3 / 3.0,
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
    return np.asarray(np.diag(Xp @ u) - Xp * u)


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


def rate_damping_matrix(torques: Any, t: float, n: int) -> np.ndarray | None:
    """A^T diag(c) A (N m s, 3n x 3n): the hinge torque items' rate coefficients c_k =
    -dTq_k/d(dD_k/dt) at t on q' (every law is affine in the rate: c = M(t, 0) - M(t, 1)),
    for the analytic Jacobians; None without items (``rodval.core.hinges.HingeTorque``)."""
    if not torques:
        return None
    c = np.zeros(n)
    for item in torques:
        c[item.hinge] += item.moment(t, 0.0) - item.moment(t, 1.0)
    A = hinge_matrix(n)
    damping: np.ndarray = A.T @ (c[:, None] * A)
    return damping


def bending_blocks(coefficient: np.ndarray, l: np.ndarray, n: int) -> np.ndarray:
    """(4 c/l) [[1, 1/2], [1/2, 1]] on each rod's (alpha_k, beta_k) (3n, 3n; zero elsewhere):
    the cubic shape's integral of c kappa_b^2 over the rod, 1/2 x^T B x = (2 c/l)(a^2 + a b +
    b^2). c = EI gives the bending stiffness (N m), c = bending_damping the Kelvin-Voigt
    damping (N m s) on the bending rates."""
    B = np.zeros((3 * n, 3 * n))
    kb = 4.0 * coefficient / l
    d = np.arange(n)
    B[n + d, n + d] = kb
    B[2 * n + d, 2 * n + d] = kb
    B[n + d, 2 * n + d] = kb / 2.0
    B[2 * n + d, n + d] = kb / 2.0
    return B


def stiffness_matrix(chain: Chain) -> np.ndarray:
    """K = Hessian of Pi (3n, 3n): hinge springs A^T diag(kappa) A plus bending blocks
    (4 EI/l) [[1, 1/2], [1/2, 1]] on (alpha_k, beta_k)."""
    A = hinge_matrix(chain.n)
    return np.asarray(A.T @ (chain.kappa[:, None] * A) + bending_blocks(chain.EI, chain.l, chain.n))


def rest_forces(chain: Chain) -> np.ndarray:
    """A^T (kappa * rest_angle) (N m, 3n): with it the spring forces are K q - A^T kappa rest,
    the gradient of 1/2 sum kappa_k (D_k - rest_k)^2."""
    t = chain.kappa * chain.rest_angle
    f = np.zeros(3 * chain.n)
    f[: chain.n] += t
    f[chain.n : 2 * chain.n] += t
    f[: chain.n - 1] -= t[1:]
    f[2 * chain.n : 3 * chain.n - 1] -= t[1:]
    return f


def potential_energy(
    chain: Chain, phi: np.ndarray, alpha: np.ndarray, beta: np.ndarray, attitude: Any = None
) -> np.ndarray:
    """Pi = hinge_energy + bending_energy (J), per row of (..., n) arrays, O(n)."""
    hinge = hinge_energy(chain, phi, alpha, beta, attitude)
    return cast(np.ndarray, hinge + bending_energy(chain, alpha, beta))


def hinge_energy(
    chain: Chain, phi: np.ndarray, alpha: np.ndarray, beta: np.ndarray, attitude: Any = None
) -> np.ndarray:
    """1/2 sum_k kappa_k (D_k - rest_k)^2 (J): the hinge springs, per row, O(n); ``attitude``
    a free base's theta (rad), hinge 0's reference (``hinge_angles``)."""
    D = hinge_angles(phi, alpha, beta, attitude) - chain.rest_angle
    return cast(np.ndarray, 0.5 * np.sum(chain.kappa * D * D, axis=-1))  # a float for one row


def bending_energy(chain: Chain, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """1/2 sum_k (4 EI_k/l_k)(a^2 + a b + b^2) (J): the rods' bending, per row, O(n)."""
    kb = 4.0 * chain.EI / chain.l
    return cast(
        np.ndarray, 0.5 * np.sum(kb * (alpha * alpha + alpha * beta + beta * beta), axis=-1)
    )


def quasi_static_bending(chain: Chain, phi: np.ndarray) -> np.ndarray:
    """gamma = [alpha; beta] (rad) minimising Pi at fixed phi: B gamma = A_g^T kappa rest -
    K_gp phi with B = K_gg, which is tridiagonal in the order (alpha_1, beta_1, alpha_2, ...)
    and positive definite (EI > 0); O(n) by a banded Cholesky solve."""
    n = chain.n
    kappa, kb = chain.kappa, 4.0 * chain.EI / chain.l
    dphi = phi - np.concatenate([[0.0], phi[:-1]]) - chain.rest_angle  # D_i at gamma = 0
    kap_next = np.concatenate([kappa[1:], [0.0]])
    diag = np.empty(2 * n)
    diag[0::2] = kb + kappa
    diag[1::2] = kb + kap_next
    off = np.empty(2 * n)  # upper diagonal: (alpha_i, beta_i) = kb/2, (beta_i, alpha_i+1) = -kappa
    off[0] = 0.0
    off[1::2] = kb / 2.0
    off[2::2] = -kappa[1:]
    rhs = np.empty(2 * n)
    rhs[0::2] = -kappa * dphi
    rhs[1::2] = np.concatenate([kappa[1:] * dphi[1:], [0.0]])
    x = solveh_banded(np.vstack([off, diag]), rhs)
    return np.concatenate([x[0::2], x[1::2]])


def damper_power(
    chain: Chain, dphi: np.ndarray, dalpha: np.ndarray, dbeta: np.ndarray, attitude_rate: Any = None
) -> float:
    """P_diss = q'^T C q' = sum_k nu_k (dD_k/dt)^2 + sum_k (4 c_k/l_k)(a'^2 + a' b' + b'^2)
    >= 0 (W; c = bending_damping, a', b' the bending rates alpha'_k, beta'_k; hinge 0's rate
    from a free base's ``attitude_rate``, rad/s), O(n)."""
    rates = hinge_angles(dphi, dalpha, dbeta, attitude_rate)
    cb = 4.0 * chain.bending_damping / chain.l
    bending = cb * (dalpha * dalpha + dalpha * dbeta + dbeta * dbeta)
    return float(np.sum(chain.nu * rates * rates) + np.sum(bending))


def damping_matrix(chain: Chain) -> np.ndarray:
    """C = Hessian of the dissipation function (3n, 3n): the hinge dampers A^T diag(nu) A plus
    the rods' Kelvin-Voigt blocks (4 c/l) [[1, 1/2], [1/2, 1]] on (alpha'_k, beta'_k)."""
    A = hinge_matrix(chain.n)
    return np.asarray(
        A.T @ (chain.nu[:, None] * A) + bending_blocks(chain.bending_damping, chain.l, chain.n)
    )


def generalized_forces(
    l: np.ndarray, phi: np.ndarray, SX: np.ndarray, SY: np.ndarray
) -> np.ndarray:
    """Q_k = l_k (cos phi_k SY_k - sin phi_k SX_k), SX_k = sum_{j>=k} X_j (N m)."""
    return np.asarray(l * (np.cos(phi) * SY - np.sin(phi) * SX))


def node_positions(l: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates x_k, y_k (m), k = 0..n, along the last axis; phi may be (..., n)."""
    x = np.cumsum(l * np.cos(phi), axis=-1)
    y = np.cumsum(l * np.sin(phi), axis=-1)
    zero = np.zeros(phi.shape[:-1] + (1,))
    return np.concatenate([zero, x], axis=-1), np.concatenate([zero, y], axis=-1)


def rod_momenta(
    chain: Chain, phi: np.ndarray, dphi: np.ndarray, dalpha: np.ndarray, dbeta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Momenta of each rod k with its far node's point mass, in the models' velocity field:
    points on the chord r = r_{k-1} + s e_k moving with v = v_{k-1} + (s phi_k' + eta') n_k
    (first order in the bending rates, as in the kinetic energy; zero bending rates for the
    reduced model). Closed-form integrals over s (int sigma = l^2/12, int tau = -l^2/12,
    int s sigma = l^3/30, int s tau = -l^3/20). Arrays (..., n); O(n) per state.

    Returns the linear momentum p (..., n, 2) (N s), the angular momentum about node 0 (the
    origin) h (..., n) (N m s, counter-clockwise positive) and the first mass moment about
    node 0 (..., n, 2) (kg m). With rod data only, sum_k h is the model's own generalized
    momentum of a rigid rotation of the whole chain, d T / d theta'."""
    l, m, mu = chain.l, chain.m, chain.mu
    c, s = np.cos(phi), np.sin(phi)
    e = np.stack([c, s], axis=-1)
    nk = np.stack([-s, c], axis=-1)
    x, y = node_positions(l, phi)
    r = np.stack([x, y], axis=-1)  # (..., n+1, 2)
    v = np.concatenate(
        [np.zeros(phi.shape[:-1] + (1, 2)), np.cumsum((l * dphi)[..., None] * nk, axis=-2)],
        axis=-2,
    )
    r0, v0, r1, v1 = r[..., :-1, :], v[..., :-1, :], r[..., 1:, :], v[..., 1:, :]

    def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])

    ml, ml2 = m * l, m * l * l
    swing = ml2 * dphi / 2.0 + ml2 * (dalpha - dbeta) / 12.0  # int (s phi' + eta') m ds
    p = ml[:, None] * v0 + swing[..., None] * nk + mu[:, None] * v1
    h = (
        ml * cross(r0, v0)
        + ml2 / 2.0 * cross(e, v0)
        + np.sum(r0 * e, axis=-1) * swing
        + ml2 * l * (dphi / 3.0 + dalpha / 30.0 - dbeta / 20.0)
        + mu * cross(r1, v1)
    )
    first = ml[:, None] * r0 + (ml2 / 2.0)[:, None] * e + mu[:, None] * r1
    return p, h, first


def angular_momentum(
    chain: Chain, phi: np.ndarray, dphi: np.ndarray, dalpha: np.ndarray, dbeta: np.ndarray
) -> np.ndarray:
    """The ``angular_momentum`` rows (..., 2) (N m s, counter-clockwise positive): k = 0 about
    the root node (the origin), H_0 = sum int r x v dm; k = 1 about the chain's centre of mass,
    H_c = H_0 - S x P / M (S the first mass moment, P the linear momentum, M the total mass),
    in the velocity field of ``rod_momenta``. O(n) per state."""
    return angular_momentum_rows(*rod_momenta(chain, phi, dphi, dalpha, dbeta), chain)


def angular_momentum_rows(
    p: np.ndarray, h: np.ndarray, first: np.ndarray, chain: Chain
) -> np.ndarray:
    """[H_0, H_c] (..., 2) (N m s) from the rods' momenta p (..., n, 2), their angular momenta
    about node 0 h (..., n) and first mass moments (..., n, 2) (``rod_momenta``): H_0 =
    sum h, H_c = H_0 - S x P / M."""
    P, S, H0 = p.sum(axis=-2), first.sum(axis=-2), h.sum(axis=-1)
    total = float(np.sum(chain.m * chain.l + chain.mu))
    Hc = H0 - (S[..., 0] * P[..., 1] - S[..., 1] * P[..., 0]) / total
    return np.stack([H0, Hc], axis=-1)
