"""The rods' Kelvin-Voigt bending damping (``Chain.bending_damping``, issue 19): bending moment
EI kappa_b + c dkappa_b/dt, the same law in the full model (damping block (4 c/l)[[1, 1/2],
[1/2, 1]] on the bending rates) and exudyn (``bendingDamping`` of its ANCF cables); the
reduced model states that its quasi-static bending has nothing for it to act on."""

import numpy as np
import pytest

from rodval import simulate
from rodval.bench.stiffness import rigid_latch
from rodval.core.scene import Chain, InitialState, Scene
from rodval.core.settings import IntegratorSettings
from rodval.models import get_model
from rodval.models.presets.full import FullSystem


def proportional_chain(beta: float) -> Chain:
    """Three rods whose damping is beta times their stiffness, hinge by hinge and rod by rod:
    nu = beta kappa, bending_damping = beta EI, so C = beta K in every model."""
    EI, kappa = np.array([1e4, 2e4, 5e3]), np.array([50.0, 80.0, 30.0])
    return Chain.uniform(3, EI=EI, kappa=kappa, nu=beta * kappa, bending_damping=beta * EI, mu=1.0)


@pytest.mark.parametrize(
    "model, bound",
    [
        # the quadratic eigenproblem in double precision, condition ~ omega_max / omega_min
        # = 3e3: 1e-12 measured, bound 1e-9
        ("full", 1e-9),
        # exudyn's K carries eps |K| per entry (docs/modes.md: its hinge frequencies hold
        # 7 digits); 2.5e-9 measured, bound 1e-6
        ("exudyn", 1e-6),
    ],
)
def test_stiffness_proportional_damping_gives_zeta_beta_omega_over_two(model, bound):
    """With C = beta K every mode has zeta = beta omega / 2 exactly (the eigenvalues are
    s = -beta omega^2 / 2 +- i omega sqrt(1 - zeta^2)): a closed form that holds only if the
    bending damping enters each model with the bending stiffness's own block, the hinge
    modes and the bending modes alike."""
    beta = 1e-4
    scene = Scene(chain=proportional_chain(beta), t_end=1.0)
    modes = get_model(model).modes(scene, count=9)
    assert modes.omega.size == 9 and modes.omega[-1] > 100.0  # bending modes included
    expected = beta * modes.omega / 2.0
    np.testing.assert_allclose(modes.damping, expected, rtol=bound)


def test_the_compiled_kernel_equals_the_dense_reference_with_bending_damping():
    """kernels.full_accel (O(n)) against the dense M^-1 (f - C q' ...) on random states of a
    non-uniform chain: the two differ by round-off of the O(n) recursion (2e-16 measured;
    bound 1e-12, well above the LU's growth on these well-conditioned M)."""
    rng = np.random.default_rng(11)
    n = 5
    chain = Chain.uniform(
        n,
        EI=rng.uniform(1e3, 1e4, n),
        bending_damping=rng.uniform(1.0, 5.0, n),
        nu=rng.uniform(0.0, 0.1, n),
    )
    scene = Scene(chain=chain, t_end=1.0)
    fast, dense = FullSystem(scene, kernel="numba"), FullSystem(scene, kernel="numpy")
    for _ in range(5):
        y = rng.normal(size=6 * n)
        a, b = fast.rhs(0.0, y), dense.rhs(0.0, y)
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))


def vibrating_rod(c: float) -> Scene:
    """One rod (1 m, 1 kg/m, EI = 1e4 N m^2, tip mass 0.5 kg) on a hinge spring (kappa =
    1e3 N m/rad), released at rest with a small bending (alpha = 1e-4 rad): a linear
    vibration (the neglected terms are O(alpha^2) = 1e-8 relative) whose energy the
    bending damping c (N m^2 s) takes out."""
    chain = Chain.uniform(1, l=1.0, m=1.0, EI=1e4, mu=0.5, kappa=1e3, nu=0.0, bending_damping=c)
    return Scene(
        chain=chain,
        t_end=0.5,
        times=np.linspace(0.0, 0.5, 101),
        initial=InitialState(alpha=[1e-4]),
        outputs=("phi", "alpha", "energy"),
    )


@pytest.mark.parametrize("method", ["DOP853-numba", "DOP853"])
def test_the_energy_audit_books_the_bending_damping(method):
    """E - E(0) + D = 0 (no load): the dissipated energy is the time integral of the full
    model's q'^T C q' (its bending block included), in the compiled loop and on scipy's
    path. At rtol 1e-10 on a linear vibration the residual is the integration's (1e-10
    relative) plus the O(alpha^2) terms (1e-8): bound 1e-7 of E(0) (measured 5.7e-11 damped,
    5.2e-9 undamped). With c = 0.5 N m^2 s the first bending mode (1277 rad/s, zeta = c
    omega / (2 EI) = 0.031 by the model's modes) keeps 3.7e-5 of E(0) at t_end (bound
    1e-3); undamped, E stays constant."""
    settings = IntegratorSettings(method, rtol=1e-10, atol=1e-14)
    damped = simulate(vibrating_rod(0.5), "full", settings=settings)
    E = damped["energy"][:, 0]
    assert damped.stats.energy_residual < 1e-7
    assert E[-1] < 1e-3 * E[0]
    undamped = simulate(vibrating_rod(0.0), "full", settings=settings)
    E0 = undamped["energy"][:, 0]
    assert np.max(np.abs(E0 - E0[0])) < 1e-7 * E0[0]


def test_the_reduced_model_says_bending_damping_has_no_effect():
    """The reduced model's bending is quasi-static (no bending rates): the same trajectory
    bit for bit with and without bending damping, and a note in the run's stats saying so;
    the full model has no such note."""
    scene = rigid_latch(1e5)
    damped = scene.with_(chain=scene.chain.with_(bending_damping=50.0))
    plain, with_c = simulate(scene, "reduced"), simulate(damped, "reduced")
    np.testing.assert_array_equal(plain["phi"], with_c["phi"])
    assert plain.stats.notes == []
    assert len(with_c.stats.notes) == 1 and "no effect" in with_c.stats.notes[0]
    assert "notes" in with_c.stats.as_dict()
    assert get_model("full").scene_notes(damped) == []


def test_negative_bending_damping_is_refused_naming_the_field():
    with pytest.raises(ValueError, match=r"bending_damping .* must be >= 0 .*\[0, inf\)"):
        Chain.uniform(2, bending_damping=[1.0, -1.0])


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_the_rigid_two_rod_latch_with_damped_rods_runs_on_the_default_method(model):
    """Issue 19: the rigid two-rod latch (EI = 1e9, free root) with bending damping c =
    1200 N m^2 s (the locked chain's first bending mode, 8.2e4 rad/s, then has zeta = c
    omega / (2 EI) = 0.049: it dies out within a few periods) reaches t_end on "auto" in
    both native models (undamped, the full model must resolve the lock's bending vibration
    for the whole run and exhausts its budget: docs/performance.md). Afterwards the hinge
    stays locked and the chain turns as one rigid body about its free root: rate H / I to
    1e-6 (measured 1.6e-8 full, 7e-9 reduced: rtol, plus the O(1/EI) bending)."""
    scene = rigid_latch(1e9)
    scene = scene.with_(chain=scene.chain.with_(bending_damping=1200.0))
    run = simulate(scene, model)
    assert run.success and run.stats.t_reached == scene.t_end
    after = run.times > run.events[0]["t"] + 0.05
    assert np.max(np.abs(run["hinge_angle"][after, 1])) < 1e-12
    H = run["angular_momentum"][:, 0]
    # 1e-8 relative global error at rtol 1e-8 (H is not a linear invariant of the method)
    np.testing.assert_allclose(H, H[0], rtol=1e-7)
    inertia = 2.0**3 / 3.0 + 0.5 * 1.0**2 + 0.5 * 2.0**2
    np.testing.assert_allclose(run["dphi"][after], H[0] / inertia, rtol=1e-6)


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_the_rigid_two_rod_latch_keeps_angular_momentum_to_1e9(model):
    """Issue 19: the same damped rigid latch on the default method keeps the angular momentum
    about its free root to 1e-9 over the whole run once the integrator's global error is below
    it (rtol 1e-10: measured 9.7e-10 full, 2.6e-10 reduced; at the default rtol 1e-8 it is
    1.6e-8 and 2.3e-8, the integration's, while the lock itself moves it by round-off)."""
    scene = rigid_latch(1e9)
    scene = scene.with_(chain=scene.chain.with_(bending_damping=1200.0))
    run = simulate(scene, model, rtol=1e-10, atol=1e-12)
    assert run.success and [ev["label"] for ev in run.events] == ["latch hinge 1"]
    H = run["angular_momentum"][:, 0]
    assert np.max(np.abs(H - H[0])) <= 1e-9 * abs(H[0])
    # the impact itself: round-off of H's few-term sums (measured 2.8e-15, about 13 eps)
    assert abs(run.events[0]["angular_momentum_root_jump"]) <= 1e-13 * abs(H[0])
