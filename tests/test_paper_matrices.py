"""The analytic blocks of the paper's models against independent kinematics (tests/kinematics.py)."""

import kinematics as kin
import numpy as np
import pytest

from rodval import Chain
from rodval.models.assembly import paper_matrices as pm


@pytest.fixture(params=[1, 2, 4])
def chain(request):
    rng = np.random.default_rng(request.param)
    n = request.param
    return Chain(
        l=rng.uniform(0.5, 3, n),
        m=rng.uniform(1, 5, n),
        EI=rng.uniform(1e3, 1e5, n),
        mu=rng.uniform(0, 4, n),
        kappa=rng.uniform(0, 200, n),
        nu=rng.uniform(0, 1, n),
    )


def random_phi(n, seed=0):
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, n)


def test_printed_mass_matrix_is_symmetric_positive_definite(chain):
    cc = pm.chain_constants(chain)
    for seed in range(5):
        M = pm.mass_matrix(cc, random_phi(chain.n, seed))
        assert np.allclose(M, M.T, rtol=0, atol=1e-14 * np.abs(M).max())
        assert np.linalg.eigvalsh(M).min() > 0


def test_published_variant_differs_only_in_bending_row_diagonal(chain):
    phi = random_phi(chain.n)
    Mp = pm.mass_matrix(pm.chain_constants(chain, "printed"), phi)
    Mq = pm.mass_matrix(pm.chain_constants(chain, "published"), phi)
    n, d = chain.n, np.arange(chain.n)
    diff = Mq - Mp
    expected = np.zeros_like(diff)
    ml3 = chain.m * chain.l**3
    expected[n + d, d] = -ml3 / 60
    expected[2 * n + d, d] = ml3 / 40
    assert np.allclose(diff, expected, rtol=0, atol=1e-12)
    assert not np.allclose(Mq, Mq.T)


def test_mass_matrix_equals_quadrature_of_kinetic_energy(chain):
    n = chain.n
    q = np.concatenate([random_phi(n, 3), np.zeros(2 * n)])
    M_kin = kin.mass_matrix(q, chain.l, chain.m, chain.mu)
    M = pm.mass_matrix(pm.chain_constants(chain), q[:n])
    assert np.allclose(M, M_kin, rtol=1e-7, atol=1e-7 * np.abs(M).max())


def test_convective_terms_equal_lagrange_terms_of_kinetic_energy(chain):
    """At alpha = beta = 0 the first-order model's velocity terms are exactly Lagrange's."""
    n = chain.n
    rng = np.random.default_rng(7)
    q = np.concatenate([random_phi(n, 4), np.zeros(2 * n)])
    v = rng.normal(size=3 * n)
    h_kin = kin.convective(q, v, chain.l, chain.m, chain.mu)
    ckj, skj = pm.angle_differences(q[:n])
    h_phi, h_gamma = pm.convective_terms(
        pm.chain_constants(chain), skj, v[:n], v[n : 2 * n], v[2 * n :]
    )
    h = np.concatenate([h_phi, h_gamma])
    scale = np.abs(kin.mass_matrix(q, chain.l, chain.m, chain.mu)).max() * np.sum(v**2)
    assert np.allclose(h, h_kin, rtol=1e-6, atol=1e-8 * scale)


def test_generalized_forces_equal_virtual_work_of_nodal_forces(chain):
    n = chain.n
    rng = np.random.default_rng(11)
    q = np.concatenate([random_phi(n, 5), rng.normal(scale=1e-2, size=2 * n)])
    X, Y = rng.normal(size=n), rng.normal(size=n)
    _, Jn = kin.jacobians(q, chain.l)  # d node / dq, (n, 2, 3n)
    Q_kin = np.einsum("k,ki->i", X, Jn[:, 0, :]) + np.einsum("k,ki->i", Y, Jn[:, 1, :])
    SX, SY = np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1]
    Q = pm.generalized_forces(chain.l, q[:n], SX, SY)
    assert np.allclose(Q, Q_kin[:n], rtol=1e-8, atol=1e-8)
    assert np.allclose(Q_kin[n:], 0.0, atol=1e-8)  # nodes do not move with bending


def test_stiffness_matrix_is_hessian_of_potential_energy(chain):
    n = chain.n
    K_kin = kin.hessian(lambda q: kin.potential(q, chain.l, chain.EI, chain.kappa), np.zeros(3 * n))
    K = pm.stiffness_matrix(chain)
    assert np.allclose(K, K_kin, rtol=1e-5, atol=1e-5 * np.abs(K).max())


def test_damping_matrix_is_hinge_structure_with_nu(chain):
    C = pm.damping_matrix(chain)
    A = pm.hinge_matrix(chain.n)
    rng = np.random.default_rng(2)
    v = rng.normal(size=3 * chain.n)
    dD = A @ v
    assert np.isclose(0.5 * v @ C @ v, 0.5 * np.sum(chain.nu * dD**2))


def test_node_positions_follow_chords():
    l = np.array([1.0, 2.0, 0.5])
    phi = np.array([0.0, np.pi / 2, np.pi])
    x, y = pm.node_positions(l, phi)
    assert np.allclose(x, [0, 1, 1, 0.5]) and np.allclose(y, [0, 0, 2, 2])


def test_rest_angles_and_quasi_static_bending_against_the_dense_forms():
    """The O(n) potential with hinge rest angles has gradient K q - A^T kappa rest, and the
    O(n) quasi-static bending solves the dense bending rows B gamma = rest_g - K_gp phi."""
    rng = np.random.default_rng(1)
    n = 6
    chain = Chain(
        l=rng.uniform(1, 2, n),
        m=1.0,
        EI=rng.uniform(1e3, 1e4, n),
        mu=0.0,
        kappa=[0, 5, 10, 0, 3, 7],
        nu=0.0,
        rest_angle=rng.normal(size=n),
    )
    K, rest = pm.stiffness_matrix(chain), pm.rest_forces(chain)
    q = rng.normal(size=3 * n)
    h = 1e-2  # Pi is quadratic: central differences are exact up to round-off
    grad = [
        (
            pm.potential_energy(chain, *np.split(q + h * e, 3))
            - pm.potential_energy(chain, *np.split(q - h * e, 3))
        )
        / (2 * h)
        for e in np.eye(3 * n)
    ]
    np.testing.assert_allclose(grad, K @ q - rest, rtol=1e-9, atol=1e-9)
    phi, g, p = q[:n], slice(n, 3 * n), slice(0, n)
    dense = np.linalg.solve(K[g, g], rest[g] - K[g, p] @ phi)
    np.testing.assert_allclose(pm.quasi_static_bending(chain, phi), dense, rtol=1e-12, atol=1e-14)
