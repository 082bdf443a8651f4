"""Deployment in the native models: pre-stressed hinges, latches (plastic lock, then an exact
constraint) and limit stops. Angular momentum and the rigid-limit energy loss are computed
here from the kinematics, not from the models' matrices."""

from functools import partial

import kinematics as kin
import numpy as np
import pytest

from rodval.core.scene import Chain, InitialState, Latch, Scene, Stop
from rodval.core.settings import IntegratorSettings
from rodval.models.presets.full import FullModel, FullSystem
from rodval.models.presets.reduced import ReducedModel, ReducedSystem
from rodval.solvers.driver import integrate

#: the full model on its paper rung (first-order kinematics: the rung these tests measure)
MODELS = {"full": partial(FullModel, kinematics="first-order"), "reduced": ReducedModel}
TIGHT = IntegratorSettings(rtol=1e-10, atol=1e-12)
#: the full model carries the rods' bending modes (~1e3 rad/s at EI = 1e3 here): its runs
#: use a softer EI and rtol 1e-8 to stay within a few seconds
FULL = IntegratorSettings(rtol=1e-8, atol=1e-10)
#: per model: bending stiffness of the two-rod scenes (N m^2) and settings
SETUP = {"full": (1e3, FULL), "reduced": (1e4, TIGHT)}


def two_rods(EI=1e4, t_end=0.8, dphi=(1.0, 1.5), **kw) -> Scene:
    """Root hinge free, hinge 1 pre-stressed towards 0 from D_1 = -2.5 rad, latching at 0."""
    chain = Chain.uniform(2, l=1.0, m=1.0, EI=EI, mu=0.5, kappa=[0.0, 5.0], nu=0.0)
    return Scene(
        chain=chain,
        t_end=t_end,
        times=np.linspace(0.0, t_end, 9),
        initial=InitialState(phi=[0.0, -2.5], dphi=list(dphi)),
        latches=(Latch(1, 0.0),),
        outputs=("phi", "hinge_angle", "hinge_moment"),
        **kw,
    )


def run_capturing(model, scene, settings):
    """Integrate and keep the states just before and after every event."""
    system = model.system(scene)
    jumps = []
    apply = system.apply_event

    def spy(index, t, y):
        y_new, record = apply(index, t, y)
        jumps.append((t, y.copy(), y_new.copy()))
        return y_new, record

    system.apply_event = spy
    traj = integrate(system, scene, settings, model=model.name)
    return system, traj, jumps


def angular_momentum(chain: Chain, state: np.ndarray, full: bool) -> float:
    """H about the pinned root (kg m^2/s) by quadrature over the rods (tests/kinematics.py:
    the models' first-order velocity field, zero bending rates for the reduced model)."""
    n = chain.n
    v = state[3 * n :] if full else np.concatenate([state[n:], np.zeros(2 * n)])
    return kin.momenta(state[:n], v, chain.l, chain.m, chain.mu)[0]


@pytest.mark.parametrize("name", ["reduced", "full"])
def test_lock_conserves_angular_momentum_about_the_root(name):
    model = MODELS[name]()
    EI, settings = SETUP[name]
    sc = two_rods(EI=EI, t_end=0.6)
    system, traj, jumps = run_capturing(model, sc, settings)
    assert traj.stats.status == 0, traj.stats.message
    assert len(traj.events) == 1 and traj.events[0]["label"] == "latch hinge 1"
    t, before, after = jumps[0]
    H0 = angular_momentum(sc.chain, before, system.full)
    H1 = angular_momentum(sc.chain, after, system.full)
    assert abs(H1 - H0) <= 1e-9 * abs(H0)
    ev = traj.events[0]
    assert ev["kinetic_after"] < ev["kinetic_before"]
    # the root reaction impulse is the jump of the whole chain's linear momentum
    assert np.shape(ev["joint_impulses"]) == (2, 2)
    assert ev["root_impulse"] == ev["joint_impulses"][0]
    # the hinge rate is zero after the lock
    assert abs(system.hinge_rates(after)[1]) < 1e-12 * np.max(np.abs(system.hinge_rates(before)))


def test_rigid_limit_energy_loss_matches_closed_form():
    """Reduced model, EI large: the kinetic energy lost at the lock equals that of two rigid
    rods whose relative rate is set to zero conserving the angular momentum about the pin."""
    sc = two_rods(EI=1e9, t_end=0.56)
    system, traj, jumps = run_capturing(ReducedModel(), sc, TIGHT)
    assert traj.stats.status == 0, traj.stats.message
    t, before, after = jumps[0]
    m, l, mu = 1.0, 1.0, 0.5
    theta = before[1] - before[0]  # relative chord angle at the lock (~0)
    w1, w2 = before[2], before[3]
    a = 4 * m * l**3 / 3 + 2 * mu * l**2
    b = (m * l**3 / 2 + mu * l**2) * np.cos(theta)
    c = m * l**3 / 3 + mu * l**2
    T_before = 0.5 * (a * w1**2 + 2 * b * w1 * w2 + c * w2**2)
    H = a * w1 + b * (w1 + w2) + c * w2
    I_locked = a + 2 * b + c  # the pair straightened at the lock angle 0
    lost = T_before - H**2 / (2 * I_locked)
    ev = traj.events[0]
    measured = ev["kinetic_before"] - ev["kinetic_after"]
    assert abs(measured - lost) <= 1e-6 * lost
    assert abs(ev["kinetic_before"] - T_before) <= 1e-9 * T_before


@pytest.mark.parametrize(
    "name,kernel",
    [
        ("reduced", "numba"),
        ("reduced", "numpy"),
        ("full", "numba"),
        pytest.param("full", "numpy", marks=pytest.mark.slow),  # ~30 s: dense Python rhs
    ],
)
def test_locked_hinge_stays_at_its_angle(name, kernel):
    sc = two_rods(EI=SETUP[name][0], t_end=0.7, dphi=(0.0, 0.0))
    traj = MODELS[name](kernel=kernel).simulate(sc, FULL)
    assert traj.stats.status == 0, traj.stats.message
    t_lock = traj.events[0]["t"]
    after = traj.times > t_lock
    assert after.sum() >= 2
    D = traj.values["hinge_angle"][after, 1]
    assert np.max(np.abs(D - 0.0)) < 1e-9
    # the constraint moment holds the pre-stressed spring: sum is finite, the hinge is held
    assert np.all(np.isfinite(traj.values["hinge_moment"]))


def three_rods(EI=1e4, **kw):
    chain = Chain.uniform(3, l=1.0, m=1.0, EI=EI, mu=0.3, kappa=[0.0, 4.0, 6.0], nu=0.0)
    return Scene(
        chain=chain,
        t_end=1.5,
        times=np.linspace(0.0, 1.5, 16),
        initial=InitialState(phi=[0.0, -2.0, -3.5], dphi=[0.5, 0.0, 0.0]),
        latches=(Latch(1, 0.0), Latch(2, 0.0)),
        outputs=("phi", "hinge_angle"),
        **kw,
    )


@pytest.mark.parametrize("name", ["reduced", "full"])
def test_two_latches_lock_at_different_times_and_stay(name):
    EI, settings = SETUP[name]
    sc = three_rods(EI=EI)
    system, traj, jumps = run_capturing(MODELS[name](), sc, settings)
    assert traj.stats.status == 0, traj.stats.message
    assert [e["hinges"] for e in traj.events] in ([[1], [2]], [[2], [1]])
    for (_t, before, after), ev in zip(jumps, traj.events):
        H0 = angular_momentum(sc.chain, before, system.full)
        H1 = angular_momentum(sc.chain, after, system.full)
        assert abs(H1 - H0) <= 1e-9 * max(abs(H0), 1.0)
        assert set(ev["hinges"]) <= set(ev["held_hinges"])
        assert len(ev["angular_impulses"]) == len(ev["held_hinges"])
    t_last = traj.events[-1]["t"]
    D = traj.values["hinge_angle"][traj.times > t_last]
    assert np.max(np.abs(D[:, 1:])) < 1e-9


@pytest.mark.parametrize("system_cls", [ReducedSystem, FullSystem])
@pytest.mark.parametrize("kernel", ["numba", "numpy"])
def test_simultaneous_lock_solves_the_joint_impulse(system_cls, kernel):
    """Both latched hinges at their angles at once: one event locks both; their rates are
    zero after it and the angular momentum is kept."""
    sc = three_rods()
    system = system_cls(sc, kernel=kernel)
    n = 3
    phi = np.array([0.3, 0.3, 0.3])
    rates = np.array([0.4, -1.0, 2.0])
    if system.full:
        y = np.concatenate([phi, np.zeros(2 * n), rates, np.zeros(2 * n)])
    else:
        y = np.concatenate([phi, rates])
    specs = system.event_functions()
    D = system.hinge_angles_at(0.1, y)
    if not system.full:
        # shift phi so that the recovered D_1 = D_2 = 0 (D is phi-differences + bending)
        for _ in range(5):
            y[1] -= D[1]
            y[2] -= D[1] + D[2]
            D = system.hinge_angles_at(0.1, y)
    assert np.max(np.abs(D[1:])) < 1e-9
    y_new, record = system.apply_event(0, 0.1, y)
    assert record.data["hinges"] == [1, 2] and record.label == "latch hinge 1, 2"
    assert len(specs) == 2 and system.event_functions() == ()
    assert np.max(np.abs(system.hinge_rates(y_new)[1:])) < 1e-12
    H0 = angular_momentum(sc.chain, y, system.full)
    H1 = angular_momentum(sc.chain, y_new, system.full)
    assert abs(H1 - H0) <= 1e-9 * abs(H0)
    # the joint impulse takes out at least as much kinetic energy as either lock alone
    T_joint = system.kinetic_energy(0.1, y_new)
    for j in (1, 2):
        alone = system_cls(sc, kernel=kernel)
        hinges = np.array([j])
        y_one, _ = alone.plastic_jump(y, hinges, np.zeros(1))
        assert alone.kinetic_energy(0.1, y_one) >= T_joint


def test_numba_and_numpy_agree_with_rest_angles_stops_and_locks():
    """The compiled O(n) kernels against the dense reference in every mode."""
    rng = np.random.default_rng(3)
    n = 5
    chain = Chain(
        l=rng.uniform(0.5, 2.0, n),
        m=rng.uniform(1, 3, n),
        EI=rng.uniform(1e3, 1e5, n),
        mu=rng.uniform(0, 2, n),
        kappa=rng.uniform(0, 100, n),
        nu=rng.uniform(0, 0.5, n),
        rest_angle=rng.uniform(-1, 1, n),
    )
    sc = Scene(
        chain=chain,
        t_end=1.0,
        initial=InitialState(phi=[0.0, -0.5, -1.0, -1.5, -2.0]),
        latches=(Latch(1, 0.3), Latch(3, 0.2)),
        stops=(Stop(2, 0.1, "upper", 500.0, 2.0), Stop(4, -3.0, "lower", 800.0, 0.0)),
    )
    for cls, width in ((FullSystem, 6), (ReducedSystem, 2)):
        fast, ref = cls(sc, kernel="numba"), cls(sc, kernel="numpy")
        for mode in [
            ((False, False), (), ()),
            ((True, True), (), ()),
            ((True, False), (0,), ()),
            ((False, True), (1, 0), ()),
        ]:
            fast._activate(mode)
            ref._activate(mode)
            for _ in range(3):
                y = rng.normal(scale=1.0, size=width * n)
                a, b = fast.rhs(0.2, y), ref.rhs(0.2, y)
                np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.max(np.abs(b)))
                np.testing.assert_allclose(
                    fast.hinge_angles_at(0.2, y), ref.hinge_angles_at(0.2, y), atol=1e-10
                )
                if mode[1]:
                    la, lb = fast.accel_locked(0.2, y)[1], ref.accel_locked(0.2, y)[1]
                    np.testing.assert_allclose(la, lb, rtol=1e-8, atol=1e-8)
                    h = np.array([sc.latches[j].hinge for j in mode[1]])
                    ya, ma = fast.plastic_jump(y, h, np.array([0.3, 0.2])[list(mode[1])])
                    yb, mb = ref.plastic_jump(y, h, np.array([0.3, 0.2])[list(mode[1])])
                    np.testing.assert_allclose(ya, yb, rtol=0, atol=1e-10 * np.max(np.abs(yb)))


@pytest.mark.parametrize("name", ["reduced", "full"])
def test_prestressed_release_energy_audit_closes(name):
    """No latch, nu = 0: the released spring energy becomes kinetic energy, and the energy
    audit closes to the model's own residual (docs/stability.md): the same at two
    tolerances (a property of the model, not of the integrator), falling as 1/EI."""
    EI = {"full": 1e3, "reduced": 1e4}[name]
    residuals = []
    for rtol in (1e-8, 1e-10) if name == "reduced" else (1e-8,):
        chain = Chain.uniform(3, l=1.0, m=1.0, EI=EI, mu=0.5, kappa=[0.0, 10.0, 10.0], nu=0.0)
        sc = Scene(
            chain=chain,
            t_end=0.5,
            times=np.linspace(0.0, 0.5, 11),
            initial=InitialState(phi=[0.0, -1.0, -2.0]),
            outputs=("phi", "energy"),
        )
        traj = MODELS[name]().simulate(sc, IntegratorSettings(rtol=rtol, atol=rtol * 1e-2))
        assert traj.stats.status == 0, traj.stats.message
        kin, pot = traj.values["kinetic"][:, 0], traj.values["potential"][:, 0]
        assert kin[0] == 0.0 and pot[0] == pytest.approx(10.0, rel=1e-2)  # 2 x 1/2 10 1^2
        assert np.max(kin) > 0.8 * pot[0]
        residuals.append(traj.stats.energy_residual)
    assert max(residuals) < RELEASE_RESIDUAL[name]
    assert max(residuals) <= 1.01 * min(residuals)


#: measured over 0.5 s: full 6.8e-4 (EI = 1e3; 7.7e-5 at 1e4, 9.3e-6 at 1e5), reduced
#: 7.49e-6 at rtol 1e-8 and 1e-10 alike (EI = 1e4; 7.5e-5 at 1e3): both fall as 1/EI
RELEASE_RESIDUAL = {"full": 1e-3, "reduced": 1e-5}


@pytest.mark.parametrize("name", ["reduced", "full"])
def test_stop_bounces_the_hinge_back(name):
    """A free rod swings into an undamped upper stop and comes back at the same speed; the
    contact is two mode switches (on, off) and the audit counts the stop's spring energy."""
    EI, settings = {"reduced": (1e5, TIGHT), "full": (1e3, FULL)}[name]
    chain = Chain.uniform(1, l=1.0, m=1.0, EI=EI, mu=0.5, kappa=0.0, nu=0.0)
    sc = Scene(
        chain=chain,
        t_end=0.6,
        times=np.linspace(0.0, 0.6, 61),
        initial=InitialState(dphi=[2.0]),
        stops=(Stop(0, 0.5, "upper", stiffness=2e3, damping=0.0),),
        outputs=("phi", "dphi", "hinge_angle", "energy"),
    )
    traj = MODELS[name]().simulate(sc, settings)
    assert traj.stats.status == 0, traj.stats.message
    labels = [e["label"] for e in traj.events]
    assert labels == ["stop hinge 0 on", "stop hinge 0 off"]
    assert traj.events[0]["t"] == pytest.approx(0.25, abs=1e-9)  # 0.5 rad at 2 rad/s
    D = traj.values["hinge_angle"][:, 0]
    assert 0.5 < D.max() < 0.6
    # no damping: the rod comes back at its speed (the full model keeps part of the energy
    # in the bending vibration the contact excites, at EI = 1e3 a few per cent)
    rel = {"reduced": 2e-3, "full": 5e-2}[name]
    assert traj.values["dphi"][-1, 0] == pytest.approx(-2.0, rel=rel)
    assert traj.stats.energy_residual < STOP_RESIDUAL[name]


#: measured: reduced 4.1e-4 at EI = 1e5 (4.1e-6 at 1e7: the model's 1/EI residual during
#: the contact, which loads the quasi-static bending), full 1.7e-13 at EI = 1e5
STOP_RESIDUAL = {"reduced": 1e-3, "full": 1e-9}


def test_implicit_method_runs_through_a_lock():
    """Radau (Jacobian by differences while a hinge is held) finds the same lock as DOP853
    and holds the hinge."""
    sc = two_rods(EI=1e4, t_end=0.7, dphi=(0.0, 0.0))
    ref = ReducedModel().simulate(sc, TIGHT)
    rad = ReducedModel().simulate(sc, IntegratorSettings(method="Radau", rtol=1e-10, atol=1e-12))
    assert rad.stats.status == 0, rad.stats.message
    assert rad.events[0]["t"] == pytest.approx(ref.events[0]["t"], abs=1e-7)
    after = rad.times > rad.events[0]["t"]
    assert np.max(np.abs(rad.values["hinge_angle"][after, 1])) < 1e-9


@pytest.mark.parametrize("system_cls,width", [(FullSystem, 6), (ReducedSystem, 2)])
def test_locked_kernels_at_larger_n(system_cls, width):
    """The O(n m) superposition (m + 1 O(n) solves and an m x m capacitance system) against
    the dense constrained reference on a 40-rod chain with 3 held hinges."""
    n = 40
    sc = Scene(
        chain=Chain.uniform(n, rest_angle=0.2),
        t_end=1.0,
        initial=InitialState(phi=np.linspace(0.0, -3.0, n)),
        latches=(Latch(3, 0.5), Latch(17, 0.5), Latch(39, 0.5)),
    )
    fast, ref = system_cls(sc, kernel="numba"), system_cls(sc, kernel="numpy")
    mode = ((), (2, 0, 1), ())
    fast._activate(mode)
    ref._activate(mode)
    y = np.random.default_rng(5).normal(scale=0.5, size=width * n)
    a, b = fast.rhs(0.3, y), ref.rhs(0.3, y)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.max(np.abs(b)))
    np.testing.assert_allclose(
        fast.accel_locked(0.3, y)[1], ref.accel_locked(0.3, y)[1], rtol=1e-7, atol=1e-6
    )
