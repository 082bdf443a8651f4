"""The ``angular_momentum`` output (k = 0: about the root node, k = 1: about the centre of
mass; N m s) in every model: the native closed form against independent quadrature, its
conservation where the equations have the rotational symmetry, the full model's documented
defect where they do not, and the three models side by side on the paper example."""

import kinematics as kin
import numpy as np
import pytest

from rodval import Chain, paper_scene, simulate
from rodval.analysis.metrics import relative_error
from rodval.core.scene import InitialState, Scene
from rodval.models.assembly import paper_matrices as pm
from rodval.models.presets.full import FullModel
from rodval.models.presets.reduced import ReducedModel


def random_chain(rng, n, free_root=True) -> Chain:
    kappa = rng.uniform(5.0, 50.0, n)
    nu = rng.uniform(0.0, 0.5, n)
    if free_root:
        kappa[0] = nu[0] = 0.0
    return Chain(
        l=rng.uniform(0.5, 2.0, n),
        m=rng.uniform(0.5, 3.0, n),
        EI=rng.uniform(1e3, 1e4, n),
        mu=rng.uniform(0.0, 2.0, n),
        kappa=kappa,
        nu=nu,
    )


@pytest.mark.parametrize("n", [1, 3, 6])
def test_native_rows_equal_independent_quadrature(n):
    """The closed form (paper_matrices.angular_momentum) against Gauss quadrature of
    r x r_t dm over the complex-step kinematics of model.md (tests/kinematics.py). Both are
    exact for these polynomial integrands; the bound is round-off on sums of ~10 n terms of
    size |H| (1e-12 relative)."""
    rng = np.random.default_rng(n)
    chain = random_chain(rng, n)
    for _ in range(5):
        phi, dphi, da, db = (rng.uniform(-2, 2, n) for _ in range(4))
        got = pm.angular_momentum(chain, phi, dphi, da, db)
        v = np.concatenate([dphi, da, db])
        want = kin.momenta(np.concatenate([phi, np.zeros(2 * n)]), v, chain.l, chain.m, chain.mu)
        scale = np.max(np.abs(want)) + 1e-300
        assert np.max(np.abs(got - np.array(want))) <= 1e-12 * scale


def free_chain_scene(n=8, t_end=4.0) -> Scene:
    """The paper's chain with its root hinge free (kappa_0 = nu_0 = 0), no loads, set
    spinning with unequal rates from a bent configuration."""
    chain = paper_scene().chain
    kappa, nu = chain.kappa.copy(), chain.nu.copy()
    kappa[0] = nu[0] = 0.0
    rng = np.random.default_rng(3)
    return Scene(
        chain=Chain(l=chain.l, m=chain.m, EI=chain.EI, mu=chain.mu, kappa=kappa, nu=nu),
        t_end=t_end,
        times=np.linspace(0.0, t_end, 41),
        initial=InitialState(
            phi=list(0.3 * rng.standard_normal(n)), dphi=list(0.5 + 0.3 * rng.standard_normal(n))
        ),
        outputs=("phi", "angular_momentum"),
    )


def test_reduced_free_run_keeps_angular_momentum_about_the_root():
    """No moment about the pinned root: H_0 is constant. The reduced model's equations are
    invariant under a rigid rotation of the whole chain, so its H_0 moves only by the
    integrator's error: at rtol 1e-12 the global error over 4 s stays near 1e-11, two orders
    under the 1e-9 bound. H_c is not constant (the root reaction has a moment about the
    centre of mass): it must vary, or the k = 1 row would be a copy of k = 0."""
    traj = simulate(free_chain_scene(), "reduced", rtol=1e-12, atol=1e-14)
    assert traj.stats.status == 0, traj.stats.message
    H = traj["angular_momentum"]
    assert H.shape == (41, 2)
    assert np.max(np.abs(H[:, 0] - H[0, 0])) <= 1e-9 * abs(H[0, 0])
    assert np.ptp(H[:, 1]) > 1e-3 * abs(H[0, 1])


def convective_defect(chain: Chain, phi, dphi, dalpha, dbeta) -> float:
    """R = sum_{k<j} w_j l_k sin(phi_k - phi_j) (phi_k' + phi_j') (alpha_j' - beta_j'),
    w_j = m_j l_j^2 / 12: the full model's phi rows sum to d H_0/dt + R (shared/paper/
    model.md's convective terms 2 G_pa (phi' * alpha') are not d/dt of M_pa alpha' minus the
    Lagrangian's dT/dphi; derivation in docs/quantities.md)."""
    w = chain.m * chain.l**2 / 12.0
    s = np.sin(phi[:, None] - phi[None, :])
    upper = np.triu(np.ones((phi.size, phi.size)), 1)
    terms = upper * (chain.l[:, None] * w[None, :]) * s * (dphi[:, None] + dphi[None, :])
    return float(np.sum(terms * (dalpha - dbeta)[None, :]))


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_rate_of_angular_momentum_along_the_models_own_equations(model):
    """d H_0/dt along the model's right-hand side (complex-step derivative of the closed form,
    exact to round-off) on random states of random chains, root free, no loads: zero for the
    reduced model, -R (convective_defect) for the full model. Bound: round-off of the
    right-hand side's solve, 1e-9 of the largest term."""
    rng = np.random.default_rng(11)
    for n in (2, 4, 7):
        chain = random_chain(rng, n)
        scene = Scene(chain=chain, t_end=1.0, times=[0.0, 1.0])
        cls = FullModel if model == "full" else ReducedModel
        system = cls(kernel="numpy").system(scene)
        for _ in range(3):
            if model == "full":
                y = np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-0.01, 0.01, 2 * n)])
                y = np.concatenate([y, rng.uniform(-2, 2, n), rng.uniform(-20, 20, 2 * n)])
                q, v = y[: 3 * n], y[3 * n :]
            else:
                y = np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)])
                q = np.concatenate([y[:n], np.zeros(2 * n)])
                v = np.concatenate([y[n:], np.zeros(2 * n)])
            dy = system.rhs(0.0, y)
            dq, dv = (
                (dy[: 3 * n], dy[3 * n :])
                if model == "full"
                else (
                    np.concatenate([dy[:n], np.zeros(2 * n)]),
                    np.concatenate([dy[n:], np.zeros(2 * n)]),
                )
            )
            h = 1e-30
            qc, vc = q + 1j * h * dq, v + 1j * h * dv
            H = pm.angular_momentum(chain, qc[:n], vc[:n], vc[n : 2 * n], vc[2 * n :])
            rate = H[0].imag / h
            R = convective_defect(chain, q[:n], v[:n], v[n : 2 * n], v[2 * n :])
            scale = np.max(np.abs(pm.rod_momenta(chain, q[:n], v[:n], v[n : 2 * n], v[2 * n :])[1]))
            scale *= np.max(np.abs(v)) + np.max(np.abs(dv)) / (np.max(np.abs(v)) + 1e-300)
            assert abs(rate + R) <= 1e-9 * scale, (n, rate, R)
            if model == "full":
                assert abs(R) > 1e-6 * scale  # the defect is really there on these states


def test_exudyn_rows_equal_the_native_ones_on_a_rigid_rotation():
    """At t = 0 the beam starts as the straight chain in a rigid rotation (no bending): its
    field is exactly the native one, so the beam's quadrature (5 Gauss points per element,
    exact for its degree-6 integrand) gives the native rows to round-off of the stored
    coordinates (1e-10 relative)."""
    scene = free_chain_scene(n=8, t_end=0.01)
    phi0 = np.zeros(8)
    scene = Scene(
        chain=scene.chain,
        t_end=0.01,
        times=[0.0, 0.01],
        initial=InitialState(phi=list(phi0), dphi=[0.7] * 8),
        outputs=("angular_momentum",),
    )
    ex = simulate(scene, "exudyn", elements=2, step=1e-3)
    assert ex.stats.status == 0, ex.stats.message
    native = pm.angular_momentum(scene.chain, phi0, np.full(8, 0.7), np.zeros(8), np.zeros(8))
    got = ex["angular_momentum"][0]
    assert np.max(np.abs(got - native)) <= 1e-10 * np.max(np.abs(native))


def test_three_models_agree_on_angular_momentum_within_their_phi_agreement():
    """The paper example (root hinge with kappa_0, the load pulse: H_0 is not conserved), 41
    output times: for every pair of models, the root row's max_rel (analysis.metrics) is no
    larger than phi's. Measured: reduced/full 9.0e-5 vs 1.3e-3, exudyn/full 6.4e-5 vs
    3.9e-4, exudyn/reduced 2.8e-5 vs 1.7e-3 (docs/quantities.md)."""
    scene = paper_scene(times=np.linspace(0.0, 2.0, 41), outputs=("phi", "angular_momentum"))
    runs = {
        "full": simulate(scene, "full", rtol=1e-10, atol=1e-12),
        "reduced": simulate(scene, "reduced", rtol=1e-10, atol=1e-12),
        "exudyn": simulate(scene, "exudyn", elements=2, step=2e-4),
    }
    for name, traj in runs.items():
        assert traj.stats.status == 0, (name, traj.stats.message)
        assert list(traj.k_index["angular_momentum"]) == [0, 1]
    for a, b in (("reduced", "full"), ("exudyn", "full"), ("exudyn", "reduced")):
        phi_gap = relative_error(runs[a]["phi"], runs[b]["phi"], "column").max()
        H_gap = relative_error(runs[a]["angular_momentum"], runs[b]["angular_momentum"], "column")
        assert H_gap[0] <= phi_gap, (a, b, H_gap, phi_gap)
