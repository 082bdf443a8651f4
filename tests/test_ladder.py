"""The model ladder (docs/model.md, "The model ladder"): shapes = p and exact kinematics.

Checks that can fail: an independent Lagrangian (hyper-dual automatic differentiation,
tests/ladder_lagrangian.py), the paper's model as the ladder's first rung, conservation of
energy and angular momentum with exact kinematics, Euler-Bernoulli and polynomial-Ritz limits
of one rod, the paper chain's bending modes against exudyn, and a latch on a ladder rung.
"""

from __future__ import annotations

import numpy as np
import pytest
from ladder_lagrangian import HD, equations, kinetic_energy
from ladder_lagrangian import Chain as IndependentChain

import rodval
from rodval import simulate
from rodval.core.scene import Chain, Latch, Scene
from rodval.models.kinematics.ladder import ladder_constants
from rodval.models.kinematics.ladder_kernels import ladder_accel, ladder_kinetic
from rodval.models.kinematics.shapes import rod_shapes, shape_polynomials
from rodval.models.observation.linear_modes import modes
from rodval.models.presets.full import FullModel, FullSystem
from rodval.models.systems.chain_system import LadderSystem

EPS = np.finfo(float).eps


def random_chain(rng, n):
    return dict(
        l=rng.uniform(0.5, 2.5, n),
        m=rng.uniform(1.0, 4.0, n),
        mu=rng.uniform(0.0, 3.0, n),
        EI=rng.uniform(50.0, 500.0, n),
        kappa=rng.uniform(0.0, 100.0, n),
        nu=rng.uniform(0.0, 2.0, n),
        rest_angle=rng.uniform(-0.5, 0.5, n),
        bending_damping=rng.uniform(0.0, 3.0, n),
    )


def hinge_moment_forces(ref, q, Tq):
    """sum_k Tq_k dD_k/dq_i (N m) for every coordinate i: the generalized forces of moments
    Tq across the hinges, from the reference's hinge angles by dual differentiation."""
    N = q.size
    return np.array(
        [
            sum(Tq[k] * float(D.b) for k, D in enumerate(ref.hinge_angles(HD(q, np.eye(N)[i]))))
            for i in range(N)
        ]
    )


@pytest.mark.parametrize("p", [1, 2, 3, 4])
def test_exact_kinematics_equals_an_independent_lagrangian(p):
    """Random non-uniform chains (n = 3), random states, loads on every node, hinge and rod
    damping and moments across the hinges (motors): the compiled right-hand side against
    Lagrange's equations of the exact T, V and the Rayleigh function by hyper-dual
    differentiation. The residual M_ref q''_kernel - f_ref,
    relative to |f| + |M| |q''|, is a backward error: a stable O(N) solve leaves a few N eps
    (N <= 18 coordinates: ~2e-15), bound 1e-13. The forward error is bounded by cond(M) times
    that (cond(M) up to 1e7 at p = 4: the bubbles' Gram entries are 1e-3 of the cubic's)."""
    rng = np.random.default_rng(100 + p)
    n = 3
    for _ in range(3):
        data = random_chain(rng, n)
        chain = Chain(**data)
        ref = IndependentChain(
            p,
            *(data[k] for k in ("l", "m", "mu", "EI", "kappa", "nu")),
            data["rest_angle"],
            data["bending_damping"],
        )
        V = ladder_constants(chain, p, exact=True)
        N = n * (p + 2)
        q, v = rng.uniform(-1.0, 1.0, N), rng.uniform(-2.0, 2.0, N)
        X, Y = rng.uniform(-5.0, 5.0, n), rng.uniform(-5.0, 5.0, n)
        SX, SY = np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1]
        Tq = rng.uniform(-5.0, 5.0, n)
        acc = np.empty(N)
        y = np.concatenate([q, v])
        ladder_accel(V, y, (True, SX, SY, Tq), True, acc)
        M, f = equations(ref, q, v, X, Y)
        f += hinge_moment_forces(ref, q, Tq)
        scale = np.max(np.abs(f)) + np.max(np.abs(M)) * np.max(np.abs(acc))
        assert np.max(np.abs(M @ acc - f)) / scale < 1e-13
        forward = np.max(np.abs(acc - np.linalg.solve(M, f))) / np.max(np.abs(acc))
        assert forward < 100 * np.linalg.cond(M) * EPS
        assert ladder_kinetic(V, y) == pytest.approx(kinetic_energy(ref, q, v), rel=1e-13)


def test_first_rung_is_the_paper_model():
    """shapes = 1 with first-order kinematics built as a ladder rung gives the paper's
    FullSystem (a different derivation: sweeps of material accelerations against the paper's
    matrices) to round-off: right-hand side, kinetic energy, momenta, damper power."""
    scene = rodval.paper_scene()
    scene = scene.with_(chain=scene.chain.with_(bending_damping=np.full(scene.n, 5.0)))
    paper = FullSystem(scene)
    rung = LadderSystem(scene, "printed", "numba", 1, "first-order")
    rng = np.random.default_rng(7)
    for t in (0.3, 0.8):
        y = paper.y0 + 0.3 * rng.standard_normal(paper.y0.size)
        a, b = paper.rhs(t, y), rung.rhs(t, y)
        assert np.max(np.abs(a - b)) <= 1e-13 * np.max(np.abs(a))
        assert rung.kinetic_energy(t, y) == pytest.approx(paper.kinetic_energy(t, y), rel=1e-13)
        for x, z in zip(paper.rod_momenta_at(y), rung.rod_momenta_at(y)):
            np.testing.assert_allclose(z, x, rtol=1e-13, atol=1e-13 * np.max(np.abs(x)))
        assert rung.power(t, y) == pytest.approx(paper.power(t, y), rel=1e-13)


def test_default_options_run_the_paper_system():
    """The default rung is the paper's FullSystem itself (bit for bit: no ladder code runs)."""
    scene = rodval.paper_scene()
    assert type(FullModel().system(scene)) is FullSystem
    assert FullModel().options()["shapes"] == 1
    assert type(FullModel(shapes=2).system(scene)) is LadderSystem


@pytest.mark.parametrize(
    "options, match",
    [
        ({"shapes": 0}, r"shapes must be an integer in 1\.\.8, got 0"),
        ({"shapes": 2.0}, r"shapes must be an integer in 1\.\.8"),
        ({"shapes": True}, r"shapes must be an integer"),
        ({"kinematics": "second"}, r"kinematics must be one of"),
    ],
)
def test_bad_rung_options(options, match):
    with pytest.raises(ValueError, match=match):
        FullModel(**options)


def test_rung_refuses_what_it_does_not_carry():
    scene = rodval.paper_scene()
    with pytest.raises(ValueError, match="coefficients must be 'printed'"):
        FullModel(coefficients="published", shapes=2).system(scene)
    with pytest.raises(ValueError, match="kernel must be 'numba'"):
        FullModel(kernel="numpy", kinematics="exact").system(scene)
    with pytest.raises(ValueError, match="options of the full model"):
        modes(scene, "reduced", shapes=2)


def test_shapes_vanish_with_their_slope_and_stiffness_is_legendre():
    """Every bubble vanishes with its slope at both ends; the analytic stiffness block equals
    the quadrature of psi_i'' psi_j'' (round-off, 1e-13 of 4 EI / l)."""
    from numpy.polynomial import polynomial as P

    polys = shape_polynomials(6)
    for c in polys[2:]:
        for x in (0.0, 1.0):
            assert abs(P.polyval(x, c)) < 1e-14 and abs(P.polyval(x, P.polyder(c))) < 1e-13
    xg, wg = np.polynomial.legendre.leggauss(12)
    xi, w = (xg + 1) / 2, wg / 2
    D2 = np.array([P.polyval(xi, P.polyder(c, 2)) for c in polys])
    sh = rod_shapes(6, np.array([2.0]), np.array([3.0]), np.array([1e5]), np.array([0.0]))
    np.testing.assert_allclose(sh.K[0], 1e5 / 2.0 * (D2 * w) @ D2.T, atol=1e-13 * 2e5)


def free_paper_chain():
    """The paper chain with no damper and a free root hinge (kappa_0 = 0): after the pulse
    (t >= 1 s) no external moment or work acts."""
    s = rodval.paper_scene()
    kappa = s.chain.kappa.copy()
    kappa[0] = 0.0
    return s.with_(
        chain=s.chain.with_(nu=np.zeros(s.n), kappa=kappa),
        outputs=("phi", "energy", "angular_momentum"),
        times=np.linspace(0.0, 2.0, 401),
    )


def test_exact_kinematics_conserves_energy_and_angular_momentum():
    """Free undamped paper chain after the pulse, rtol 1e-10: exact kinematics keeps E to
    1e-8 and H about the root to 1e-10 relative (both are first integrals of its Lagrangian;
    measured 5e-14 and 2e-14, the integrator's local errors); the paper's first-order
    kinematics drifts E by 2e-4 and H by 2e-5 (a model property, docs/model.md)."""
    scene = free_paper_chain()
    after = scene.times >= 1.0
    drift = {}
    for kin in ("first-order", "exact"):
        tr = simulate(scene, "full", kinematics=kin, rtol=1e-10, atol=1e-12)
        assert tr.stats.status.name == "SUCCESS"
        E, H = tr["energy"][after, 0], tr["angular_momentum"][after, 0]
        drift[kin] = (np.ptp(E) / np.mean(E), np.ptp(H) / np.max(np.abs(H)))
    assert drift["exact"][0] < 1e-8 and drift["exact"][1] < 1e-10
    assert drift["first-order"][0] > 1e-5 and drift["first-order"][1] > 1e-6


BL_CLAMPED = np.array([1.8751040687119611, 4.6940911329741745, 7.8547574382376126])
BL_PINNED = np.array([3.9266023120479219, 7.0685827550723186, 10.210176122813031])


def monomial_ritz(lowest: int, degree: int) -> np.ndarray:
    """(beta l)^2 of the polynomial Ritz space span{x^lowest..x^degree} on a unit beam
    (exact Gram and stiffness integrals): the best any shape basis of that degree can do."""
    import scipy.linalg

    j = np.arange(lowest, degree + 1)
    M = 1.0 / (j[:, None] + j[None, :] + 1.0)
    jj = j * (j - 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        K = np.where(
            (j[:, None] > 1) & (j[None, :] > 1),
            np.outer(jj, jj) / (j[:, None] + j[None, :] - 3.0),
            0.0,
        )
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)
    return np.sqrt(np.clip(lam, 0.0, None))


@pytest.mark.parametrize(
    "name, kappa0, bl", [("clamped", 1e12, BL_CLAMPED), ("pinned", 0.0, BL_PINNED)]
)
def test_one_rod_converges_to_euler_bernoulli(name, kappa0, bl):
    """One rod, clamped-free (hinge spring 1e12 N m/rad: shifts the frequencies by ~1e-7) and
    pinned-free: the first three bending frequencies fall monotonically with p (nested Ritz
    spaces), equal the monomial Ritz of the same polynomial space (degree p + 2) to 1e-6, and
    are within 1e-3 of Euler-Bernoulli at p = 6 (clamped) and p = 7 (pinned). At p = 4 the third
    is 2.5e-2 (clamped) and 5.5e-2 (pinned) high in that space whatever the basis: docs/model.md."""
    EI, m, l = 1e5, 3.0, 2.0
    scene = Scene(chain=Chain.uniform(1, l=l, m=m, mu=0.0, EI=EI, kappa=kappa0, nu=0.0), t_end=1.0)
    exact = bl**2 * np.sqrt(EI / (m * l**4))
    last = None
    for p in range(1, 8):
        w = modes(scene, "full", shapes=p).omega
        # bending modes only: not the pinned rod's rigid rotation (0), not the clamp
        # spring's own mode (~sqrt(1e12 / I) = 3.5e6 rad/s)
        w = w[(w > 1e-3 * exact[0]) & (w < 1e3 * exact[-1])][:3]
        if last is not None:
            k = min(len(w), len(last))
            assert np.all(w[:k] <= last[:k] * (1 + 1e-12))
        last = w
        ritz = monomial_ritz(2 if name == "clamped" else 1, p + 2)
        ritz = ritz[ritz > 1e-3][: len(w)] * np.sqrt(EI / (m * l**4))
        np.testing.assert_allclose(w, ritz, rtol=1e-6)
        if (name, p) in (("clamped", 6), ("pinned", 7)):
            assert np.all(np.abs(w / exact - 1) < 1e-3)


def test_paper_chain_bending_modes_against_exudyn():
    """Paper chain, straight: modes 9-10 (the first rod-bending pair) at p = 3 within 1 % of
    exudyn with 16 elements per rod (measured 3.0e-4, 3.4e-4; p = 1: 11 %). The hinge modes
    1-8 move by up to 3.0e-6 from p = 1, towards exudyn: modes 2-8 within 1e-6 of it at p = 3
    (measured 1.6e-8; p = 1: up to 3.0e-6). Both models' frequencies carry ~1e-8 there
    (docs/modes.md)."""
    from reference_models.exudyn_modes import exudyn_modes

    scene = rodval.paper_scene()
    ex = exudyn_modes(scene, elements=16).omega[:10]
    p1 = modes(scene, "full", count=10).omega
    p3 = modes(scene, "full", shapes=3, count=10).omega
    assert np.all(np.abs(p3[8:] / ex[8:] - 1) < 1e-2)
    assert np.all(np.abs(p1[8:] / ex[8:] - 1) > 0.1)
    # modes 2-8 (mode 1, 0.078 rad/s, keeps ~5 digits in exudyn's 16-element pencil, whose
    # stiffness spans 1e13: docs/modes.md)
    assert np.all(np.abs(p3[1:8] / ex[1:8] - 1) < 1e-6)
    assert np.all(np.abs(p3[1:8] / ex[1:8] - 1) <= np.abs(p1[1:8] / ex[1:8] - 1))
    assert np.max(np.abs(p3[:8] / p1[:8] - 1)) < 1e-5


def latch_scene() -> Scene:
    """Two flexible rods (EI = 2e3 N m^2), free root, spinning; a latch on hinge 1 at -0.3 rad."""
    chain = Chain.uniform(2, l=1.0, m=2.0, mu=0.5, EI=2e3, kappa=0.0, nu=0.0)
    chain = chain.with_(kappa=np.array([0.0, 50.0]), rest_angle=np.array([0.0, 0.0]))
    return Scene(
        chain=chain,
        t_end=0.6,
        initial=rodval.InitialState(phi=np.array([0.0, -1.0]), dphi=np.array([1.0, -1.0])),
        latches=(Latch(hinge=1, angle=-0.3),),
        outputs=("phi", "angular_momentum", "hinge_angle"),
        times=np.linspace(0.0, 0.6, 121),
    )


def test_latch_on_a_ladder_rung_keeps_angular_momentum():
    """Two rods, free root, rung p = 3 with exact kinematics: a latch locks hinge 1 (plastic
    impact, then held); no external moment acts, so the angular momentum about the root is
    kept through the lock and after it (rtol 1e-10: 1e-9 relative)."""
    scene = latch_scene()
    tr = simulate(scene, "full", shapes=3, kinematics="exact", rtol=1e-10, atol=1e-12)
    assert tr.stats.status.name == "SUCCESS"
    locks = [e for e in tr.events if e["label"].startswith("latch")]
    assert len(locks) == 1
    H = tr["angular_momentum"][:, 0]
    assert np.ptp(H) < 1e-9 * np.max(np.abs(H))
    after = tr.times > locks[0]["t"]
    np.testing.assert_allclose(tr["hinge_angle"][after, 1], -0.3, atol=1e-9)
    # the paper's first-order kinematics gains 16 % of H over the same run (docs/model.md)
    first = simulate(scene, "full", kinematics="first-order", rtol=1e-10, atol=1e-12)[
        "angular_momentum"
    ][:, 0]
    assert np.ptp(first) > 0.1 * np.max(np.abs(first))
