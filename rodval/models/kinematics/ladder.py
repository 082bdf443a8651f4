"""The model ladder: the full model with ``shapes = p`` bending shapes per rod
(``rodval.models.kinematics.shapes``) and ``kinematics = "first-order"`` (the paper's: every product of
the bending coordinates g with phi'^2 or phi'' dropped) or ``"exact"`` (the assumed-mode
kinematics r = r_{k-1} + s e_k + eta n_k kept whole in T, the forces and the momenta, so the
model is Lagrangian and conserves energy to the integrator's tolerance). docs/model.md ("The
model ladder") derives it; shapes = 1 with first-order kinematics is the paper's model, which
``FullSystem`` runs unchanged (the ladder is only built for another rung).

Coordinates q = [phi; alpha; beta; g_2; ...; g_p] (each n long), state [q; q'] (2 N, N =
n (p + 2)); a bubble coordinate g_i (i >= 2, m) scales psi_i, which vanishes with its slope at
both rod ends: hinge angles, latches, stops and node positions are the paper's.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from rodval.core.scene import Chain, Scene
from rodval.models.assembly.kernels import V_CB, V_EPS, V_KB, V_PI, V_RHO, V_TAU, V_W, constant_rows
from rodval.models.assembly.paper_matrices import (
    angle_differences,
    chain_constants,
    hinge_matrix,
    mass_matrix,
)
from rodval.models.assembly.paper_matrices import (
    angular_momentum_rows as momentum_rows,
)
from rodval.models.assembly.stacked_system import StackedSystem
from rodval.models.hinge_items import deployment
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
    ladder_accel,
    ladder_accel_locked,
    ladder_damper_power,
    ladder_kinetic,
    ladder_mechanics,
    ladder_rhs,
    ladder_rhs_locked,
    ladder_unit_responses,
)
from rodval.models.kinematics.rungs import check_kinematics, check_rung_options, check_shapes
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
    A = rung_hinge_matrix(n, p)
    K = A.T @ np.diag(chain.nu if damping else chain.kappa) @ A
    B = sh.C if damping else sh.K
    for k in range(n):
        idx = n * (1 + np.arange(P1)) + k
        K[np.ix_(idx, idx)] += B[k]
    return K


def rung_hinge_matrix(n: int, p: int) -> np.ndarray:
    """A (n, N): D = A q, the paper's hinge matrix padded with zeros for the bubbles."""
    A = np.zeros((n, n * (p + 2)))
    A[:, : 3 * n] = hinge_matrix(n)
    return A


def rod_momenta_exact(
    chain: Chain, sh: RodShapes, exact: bool, phi, dphi, g, dg
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


class LadderSystem(StackedSystem):
    """A rung of the ladder other than the paper's (``shapes`` p, ``kinematics``); the
    compiled kernels only (the dense numpy kernel is the paper model's reference)."""

    has_jacobian = False
    accel_kernel = staticmethod(ladder_accel)
    locked_kernel = staticmethod(ladder_accel_locked)
    unit_kernel = staticmethod(ladder_unit_responses)
    compiled_rhs = staticmethod(ladder_rhs)
    compiled_mechanics = staticmethod(ladder_mechanics)
    compiled_rhs_locked = staticmethod(ladder_rhs_locked)
    compiled_events = staticmethod(deployment.full_hinge_events)  # D from [phi; alpha; beta]

    def __init__(self, scene: Scene, coefficients: str, kernel: str, shapes: int, kinematics: str):
        check_rung_options(coefficients, kernel)
        self.p = check_shapes(shapes)
        self.exact = check_kinematics(kinematics) == "exact"
        super().__init__(scene, coefficients, kernel)
        self.Nc = self.n * (self.p + 2)
        self.N = self.Nc + self.body_coordinates
        self.setup_base(scene)
        self.y0 = self.initial_state()
        self.use_kernel()

    def chain_initial_state(self) -> np.ndarray:
        """[q; q'] of the chain at t = 0: the paper's coordinates, the bubbles at rest."""
        i = self.initial
        bubbles = np.zeros(self.n * (self.p - 1))
        return np.concatenate(
            [i["phi"], i["alpha"], i["beta"], bubbles, i["dphi"], i["dalpha"], i["dbeta"], bubbles]
        )

    @cached_property
    def shapes(self) -> RodShapes:
        return shapes_of(self.base_chain, self.p)

    def kernel_constants(self):
        return ladder_constants(self.chain, self.p, self.exact)

    def _split(self, y: np.ndarray):
        """(phi, phi', g (p+1, n), g' (p+1, n)) of one state."""
        n, N, Nc, P1 = self.n, self.N, self.Nc, self.p + 1
        g = y[n:Nc].reshape(P1, n)
        return y[:n], y[N : N + n], g, y[N + n : N + Nc].reshape(P1, n)

    def hinge_rows(self, hinges) -> np.ndarray:
        return rung_hinge_matrix(self.n, self.p)[hinges]

    def kinetic_energy(self, t, y):
        return float(ladder_kinetic(self.V, y))

    def bubble_energy(self, y: np.ndarray) -> float:
        """1/2 sum_i>=2 K_ii g_i^2 (J): the bubbles' bending energy (their stiffness block
        is diagonal and K-orthogonal to the cubic's, whose energy the paper's Pi holds)."""
        g = self._split(y)[2]
        return 0.5 * float(np.sum(self._bubble_stiffness * g[2:] ** 2))

    @cached_property
    def _bubble_stiffness(self) -> np.ndarray:
        """K_ii (N m) of the bubbles i = 2..p, (p - 1, n)."""
        return np.einsum("kii->ik", self.shapes.K)[2:]

    def bubble_energies(self, Y: np.ndarray) -> np.ndarray:
        return np.array([self.bubble_energy(y) for y in Y])

    def energy_rows(self, times, Y):
        kin = np.array([self.kinetic_energy(t, y) for t, y in zip(times, Y)])
        alpha, beta = self.bending(times, Y)[:2]
        return kin, self.potential(self.rigid(Y)[0], alpha, beta) + self.bubble_energies(Y)

    def energy_budget(self, t, y):
        return float(sum(self.energy_rows(np.array([t]), y[None, :]))[0])

    def bending_energy_at(self, t, y):
        return super().bending_energy_at(t, y) + self.bubble_energy(y)

    def damper_power_at(self, y: np.ndarray) -> float:
        return float(ladder_damper_power(self.V, self._flags, y))

    def rod_momenta_at(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        phi, dphi, g, dg = self._split(y)
        return rod_momenta_exact(self.base_chain, self.shapes, self.exact, phi, dphi, g, dg)

    def angular_momentum_rows(self, times, Y):
        return np.array([momentum_rows(*self.rod_momenta_at(y), self.base_chain) for y in Y])
