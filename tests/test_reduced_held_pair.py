"""The reduced model's held pair rings in the pair's first bending mode (docs/deployment_native.md,
"The held pair's ring in the reduced model"): with hinge 1 held, the reduced model's second
mode is the full model's first bending mode of the pair, seen through the quasi-static
condensation: the static deflection shape's stiffness with the mass M_r = M_pp + G^T M_gp (G:
the static deflection per unit chord angle), which leaves out the static shape's M_pg G and
G^T M_gg G, so it is the kinetic energy of no shape and its frequency no Rayleigh quotient. It
lies above the full model's (three shapes per rod, converged to 4e-4 at this mode: p = 1 gives
276.67 rad/s, p = 3 275.61) by a factor fixed by the geometry, the same at every EI (both
frequencies scale as sqrt(EI)). An exact constraint on the chords would delete this mode,
which every elastic model has."""

import numpy as np
import pytest
import scipy.linalg

import rodval
from rodval.core.scene import Chain, InitialState, Latch, Scene
from rodval.models.assembly.paper_matrices import hinge_matrix
from rodval.models.observation.held import held_reduced
from rodval.models.observation.linear_modes import linear_system


def held_pair(EI: float) -> Scene:
    """Two rods (l = 1.5 m, m = 3 kg/m, mu = 0.5 kg), hinge springs 50 N m/rad, hinge 1 held
    straight, at rest."""
    chain = Chain.uniform(2, l=1.5, m=3.0, EI=EI, mu=0.5, kappa=[50.0, 50.0], nu=0.0)
    return Scene(
        chain=chain, latches=(Latch(1, 0.0, held=True),), initial=InitialState(phi=[0.0, 0.0])
    )


def ratio(EI: float) -> float:
    scene = held_pair(EI)
    reduced = rodval.modes(scene, "reduced").omega
    full = rodval.modes(scene, "full", shapes=3).omega
    assert reduced.size == 2  # the pair's rigid swing on hinge 0 and the ring
    # the swing on hinge 0: the models differ only by the bending's share of its spring,
    # kappa_0 l / EI = 7.5e-4 at EI 1e5 (measured 4.7e-6)
    assert reduced[0] == pytest.approx(full[0], rel=50.0 * 1.5 / EI)
    return float(reduced[1] / full[1])


def test_the_held_pairs_ring_is_its_first_bending_mode_at_every_EI():
    """Measured 1.08514 at EI 1e5 and 1e7 (299.07 / 275.61 and 2990.46 / 2755.81 rad/s); the
    two ratios agree to the eigen-solves' round-off times the swing's coupling (the hinge-0
    spring, 50 N m/rad, is 1e-3 .. 1e-5 of the pair's bending stiffness): 1e-4."""
    soft, stiff = ratio(1e5), ratio(1e7)
    # above the mode because the condensation leaves kinetic energy out (next test), not by
    # Rayleigh's principle: M_r is the kinetic energy of no shape
    assert 1.0 < soft < 1.1
    assert stiff == pytest.approx(soft, abs=1e-4)
    assert np.isfinite(soft)


def ring(K: np.ndarray, M: np.ndarray) -> tuple[float, np.ndarray]:
    """The held pair's ring: the larger of the pencil (K, M)'s two frequencies (rad/s) and its
    unit vector of chord angles."""
    lam, X = scipy.linalg.eig(K, M)
    i = int(np.argmax(lam.real))
    return float(np.sqrt(lam[i].real)), X[:, i].real


@pytest.mark.parametrize("EI", [1e5, 1e7])
def test_the_reduced_ring_is_the_quasi_static_condensation_not_a_rayleigh_quotient(EI):
    """What 1.0851 is (docs/deployment_native.md): the reduced model's held pair is the full
    model's (M, K) condensed on the static deflection shape T = [I; G] (G: the bending per unit
    chord angle, phi'' = 0) with the stiffness T^T K T but the mass M_pp + G^T M_gp, not the
    shape's kinetic energy T^T M T. The Rayleigh-Ritz estimate on T (the Rayleigh quotient of
    the static deflection shape) is 1.01234 x the full model's mode (three shapes), above it
    and above the one-shape mode as Rayleigh-Ritz must be; the reduced ring is 1.0719 x that
    estimate, its mass on the ring 0.8383 of the shape's kinetic energy. Measured 1.012343,
    1.07190 and 0.83830 at EI 1e5 (the same to 2e-6 at 1e7): the bounds are half a unit of
    the last printed digit; the condensation's pieces agree to the round-off of a 6 x 6 solve
    (1e-12 of the largest entry)."""
    scene = held_pair(EI)
    M, C, K = linear_system(scene.chain, "full")
    n, p, g = 2, slice(0, 2), slice(2, 6)
    M_r, _, K_r, gamma = held_reduced((M, C, K), hinge_matrix(n)[[1]], n)
    G = np.column_stack([gamma(e, 0.0) for e in np.eye(n)])  # static deflection per unit phi
    T = np.vstack([np.eye(n), G])
    assert np.abs(M_r - (M[p, p] + G.T @ M[g, p])).max() <= 1e-12 * np.abs(M).max()
    assert np.abs(K_r - T.T @ K @ T).max() <= 1e-12 * np.abs(K).max()
    reduced = rodval.modes(scene, "reduced").omega[1]
    full1 = rodval.modes(scene, "full").omega[1]
    full3 = rodval.modes(scene, "full", shapes=3).omega[1]
    omega_r, x = ring(K_r, M_r)
    assert omega_r == pytest.approx(reduced, rel=1e-10)
    rayleigh_ritz = ring(T.T @ K @ T, T.T @ M @ T)[0]
    assert rayleigh_ritz > full1 > full3  # Rayleigh-Ritz: each richer space lies lower
    assert rayleigh_ritz / full3 == pytest.approx(1.01234, abs=5e-6)
    assert reduced / rayleigh_ritz == pytest.approx(1.0719, abs=5e-5)
    # on the ring's chord angles M_r carries less than the shape's kinetic energy, by what it
    # leaves out (M_pg G + G^T M_gg G; measured 1.999 against 2.384 kg m^2)
    assert (x @ M_r @ x) / (x @ T.T @ M @ T @ x) == pytest.approx(0.8383, abs=5e-5)
