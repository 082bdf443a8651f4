"""The rigid-panel lock (``rodval.mechanics.rigid``, issue 19): the one impulse every model's lock
record carries beside its own, computed from the model's chord angles and rates just before
the lock. Checked against closed forms, an independent dense formulation, the conservation of
angular momentum, and each model's own impulse in the rigid-panel limit."""

import math

import numpy as np
import pytest
from scenes import two_rod_latch

from rodval import simulate
from rodval.core.scene import Chain
from rodval.mechanics.rigid import node_velocities, rigid_lock


def two_link_closed_form(l, m, mu, w):
    """Two rigid links of a straight chain (pinned root, hinge 0 free) locking hinge 1 with
    relative chord rate w: S = -w / (v^T M^-1 v), v = (-1, 1), M the links' mass matrix."""
    M11 = m * l**3 / 3 + (m * l + 2 * mu) * l**2
    M22 = m * l**3 / 3 + mu * l**2
    M12 = l * l * (m * l / 2 + mu)
    v = np.array([-1.0, 1.0])
    return -w / (v @ np.linalg.solve([[M11, M12], [M12, M22]], v))


def test_two_links_match_the_closed_form():
    """To round-off (1e-12 relative: a 6 x 6 sparse solve of O(1) entries)."""
    chain = Chain.uniform(2, l=1.5, m=3.0, mu=0.5)
    dphi = np.array([1.3, -4.0])
    got = rigid_lock(chain, np.array([0.2, 0.2]), dphi, [1], 1)["rigid_impulse"]
    assert got == pytest.approx(two_link_closed_form(1.5, 3.0, 0.5, dphi[1] - dphi[0]), rel=1e-12)


def dense_rigid_lock(chain, phi, dphi, held, hinge):
    """The same impact in chord coordinates, built independently: M = J^T M_pts J from the
    velocities of many sample points of each rod (Gauss quadrature, exact for the quadratic
    integrand) and the point masses; Delta phi' = M^-1 A^T mu, A (phi' + Delta phi') = 0 with
    A's rows e_{h+1} - e_h (hinge 0: e_1). O(n^3); for the test only."""
    n = chain.n
    xg, wg = np.polynomial.legendre.leggauss(3)
    M = np.zeros((n, n))
    for k in range(n):  # Gauss points of rod k, then node k + 1's point mass
        points = [
            (0.5 * (x + 1) * chain.l[k], 0.5 * w * chain.l[k] * chain.m[k]) for x, w in zip(xg, wg)
        ]
        for s, weight in [*points, (chain.l[k], chain.mu[k])]:
            J = np.zeros((2, n))  # d(point velocity)/d(phi')
            for i in range(k):
                J[:, i] = chain.l[i] * np.array([-np.sin(phi[i]), np.cos(phi[i])])
            J[:, k] = s * np.array([-np.sin(phi[k]), np.cos(phi[k])])
            M += weight * J.T @ J
    A = np.zeros((len(held), n))
    for j, h in enumerate(held):
        A[j, h] = 1.0
        if h > 0:
            A[j, h - 1] = -1.0
    Minv_At = np.linalg.solve(M, A.T)
    mu = np.linalg.solve(A @ Minv_At, -(A @ dphi))
    return mu[list(held).index(hinge)], M, dphi + Minv_At @ mu


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_banded_solve_equals_an_independent_dense_impact(seed):
    """Random non-uniform chains, random configurations, several held hinges: impulse equal
    to the dense chord-coordinate impact to 1e-9 relative (both solve well-conditioned
    systems of O(1) entries; the dense one's M is a sum of n Gauss rules); the angular
    momentum about the root 1^T M phi' unchanged when hinge 0 is free (the impulses are
    internal; 1e-12 relative), and the rigid kinetic energies equal 1/2 phi'^T M phi' before
    and after."""
    rng = np.random.default_rng(seed)
    n = 6
    chain = Chain.uniform(
        n, l=rng.uniform(0.5, 2, n), m=rng.uniform(1, 4, n), mu=rng.uniform(0, 2, n)
    )
    phi, dphi = rng.uniform(-3, 3, n), rng.normal(size=n)
    held = [1, 3, 4]
    got = rigid_lock(chain, phi, dphi, held, 3)
    S, M, after = dense_rigid_lock(chain, phi, dphi, held, 3)
    assert got["rigid_impulse"] == pytest.approx(S, rel=1e-9)
    H0, H1 = np.sum(M @ dphi), np.sum(M @ after)
    assert abs(H1 - H0) <= 1e-12 * np.abs(M @ dphi).sum()
    assert got["rigid_kinetic_before"] == pytest.approx(0.5 * dphi @ M @ dphi, rel=1e-12)
    assert got["rigid_kinetic_after"] == pytest.approx(0.5 * after @ M @ after, rel=1e-9)


def test_node_velocities_are_the_chords_turning_about_the_root():
    v = node_velocities(np.array([1.0, 2.0]), np.array([0.0, math.pi / 2]), np.array([1.0, 3.0]))
    np.testing.assert_allclose(v, [[0.0, 1.0], [-6.0, 1.0]], atol=1e-15)


def test_a_hinge_not_held_is_refused():
    with pytest.raises(ValueError, match="hinge 2 must be among the held hinges"):
        rigid_lock(Chain.uniform(3), np.zeros(3), np.ones(3), [1], 2)


def test_every_native_lock_record_carries_the_rigid_impulse():
    """At EI = 1e7 (undamped) the reduced model's lock impulse is the rigid one to 5e-6
    (falling as 1/EI: its hinge rate c_k differs from the chords' by the bending compliance;
    bound 1e-4); the full model's rigid_impulse, from its chords, is within 1e-3 of the
    reduced model's (measured 5e-4: the chord rates carry the full model's bending
    vibration), and its windowed impulse within 1 % of it (measured -0.27 %: undamped, the
    ring of the higher bending modes is not averaged out; tests/test_lock_impulse.py has the
    damped scene). Its instantaneous part acts on the end tangents: 0.17 N m s."""
    scene = two_rod_latch(1e7)
    full, reduced = (simulate(scene, m).events[0] for m in ("full", "reduced"))
    assert reduced["impulse"] == pytest.approx(reduced["rigid_impulse"], rel=1e-4)
    assert full["rigid_impulse"] == pytest.approx(reduced["rigid_impulse"], rel=1e-3)
    assert full["impulse"] == pytest.approx(full["rigid_impulse"], rel=1e-2)
    assert full["impulse_instant"] < 0.01 * full["rigid_impulse"]
    for ev in (full, reduced):
        assert ev["rigid_kinetic_after"] < ev["rigid_kinetic_before"]


@pytest.mark.exudyn
def test_exudyn_lock_records_carry_the_rigid_impulse():
    """exudyn (2 elements per rod, h = 2.5e-5 s, spectral radius 0) at EI = 1e7, undamped:
    its rigid impulse, from its beam's chords one step before the lock, within 1e-3 of the
    reduced model's (measured 1e-5), and its lock impulse within 1 % of it (measured
    +0.15 %)."""
    pytest.importorskip("exudyn")
    scene = two_rod_latch(1e7)
    ex = simulate(scene, "exudyn", elements=2, step=2.5e-5, spectral_radius=0.0).events[0]
    reduced = simulate(scene, "reduced").events[0]
    assert ex["rigid_impulse"] == pytest.approx(reduced["rigid_impulse"], rel=1e-3)
    assert ex["impulse"] == pytest.approx(ex["rigid_impulse"], rel=1e-2)
