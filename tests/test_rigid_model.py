"""The rigid-panel model (issue 49): the chain of rigid rods, the limit EI -> inf of every rung.
Its lock is the rigid-panel lock of ``rodval.mechanics.rigid`` (computed there from node velocities,
another formulation), its energy is kept between locks and lost at them as rigid-panel theory
says, one rod is the closed-form spring pendulum, a free base keeps its momenta, and the full
model (exact kinematics, damped panels) tends to it as EI grows."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from exudyn_speed import latch3_scene  # noqa: E402

import rodval  # noqa: E402
from rodval import Base, simulate  # noqa: E402
from rodval.cli import main  # noqa: E402
from rodval.core.base import Motion  # noqa: E402
from rodval.core.damping import bending_damping_for_ratio  # noqa: E402
from rodval.core.scene import Chain, InitialState, Scene  # noqa: E402
from rodval.mechanics.rigid import rigid_lock  # noqa: E402
from rodval.models.registry import get_model  # noqa: E402
from rodval.report.tables import read_tables  # noqa: E402

#: rtol = atol = 1e-12 for the conservation tests: DOP853's local error per step is ~1e-12 of
#: the state, ~2e3 steps here, so a conserved quantity drifts by at most ~1e-9 of its scale
#: (measured: energy 1.1e-11, P and H 8e-12, the momentum audit 1.5e-12 relative);
#: the bounds below are that 1e-9.
TIGHT = {"rtol": 1e-12, "atol": 1e-12}
KEPT = 1e-9
BODY = Base(kind="free", mass=800.0, inertia=533.0, hinge_offset=(1.0, 0.0))


def test_the_lock_impulse_is_the_rigid_panel_impulse_of_its_record():
    """The plastic lock in M_pp(phi) against ``rigid_lock`` (a KKT system in the node
    velocities): the same impulse to round-off, at every lock of the latched 3-panel wing."""
    tr = simulate(latch3_scene(), "rigid")
    locks = [e for e in tr.events if "rigid_impulse" in e]
    assert tr.success and sorted(e["hinge"] for e in locks) == [1, 2]
    for e in locks:
        assert abs(e["impulse_instant"] - e["rigid_impulse"]) <= 1e-10 * abs(e["rigid_impulse"])


def test_energy_is_kept_between_locks_and_lost_at_them_as_rigid_panel_theory_says():
    """No damping (nu = 0): E = T + Pi is constant between locks (to KEPT of E) and each lock
    takes out the rigid-panel loss, T- - T+ of ``rigid_lock`` from the same velocities."""
    sc = latch3_scene().with_(outputs=("phi", "energy"), times=np.linspace(0.0, 0.8, 161))
    tr = simulate(sc, "rigid", **TIGHT)
    assert tr.success
    E, t = tr["energy"][:, 0], tr.times
    marks = [0.0] + [e["t"] for e in tr.events] + [sc.t_end + 1.0]
    level = [E[0]] + [e["energy_after"] for e in tr.events]
    for a, b, E0 in zip(marks[:-1], marks[1:], level):
        inside = (t > a) & (t < b)
        assert inside.any()
        assert np.abs(E[inside] - E0).max() <= KEPT * abs(E[0])
    for e in tr.events:  # the record carries the rigid lock of the chords just before it
        theory = e["rigid_kinetic_before"] - e["rigid_kinetic_after"]
        assert theory > 0.0
        assert abs(e["instant_energy_loss"] - theory) <= 1e-10 * e["rigid_kinetic_before"]
        assert abs(e["kinetic_before"] - e["rigid_kinetic_before"]) <= 1e-12 * theory


def test_the_locked_state_is_the_rigid_lock_s_from_the_pre_lock_state():
    """The state just after a lock from ``rigid_lock`` directly (not from the record): the
    kinetic energy after it and the impulse, computed from the pre-lock chord rates."""
    sc = latch3_scene()
    system = get_model("rigid").system(sc)
    seen = []
    apply = system.apply_event

    def spy(index, t, y):
        y_new, record = apply(index, t, y)
        seen.append((y.copy(), y_new.copy(), record.data))
        return y_new, record

    system.apply_event = spy  # type: ignore[method-assign]
    from rodval.solvers.driver import integrate

    integrate(system, sc, rodval.IntegratorSettings(), model="rigid")
    n = sc.n
    y, y_new, data = seen[0]
    lock = rigid_lock(sc.chain, y[:n], y[n:], data["held_hinges"], data["hinge"])
    assert (
        abs(system.kinetic_energy(0.0, y_new) - lock["rigid_kinetic_after"])
        <= 1e-12 * (lock["rigid_kinetic_before"])
    )


def test_one_rod_is_the_spring_pendulum():
    """One rigid rod (l, m per length, far-node mass mu) on a torsional spring kappa and
    damper nu, no gravity: I phi'' = -kappa phi - nu phi', I = m l^3 / 3 + mu l^2, exactly
    linear at any amplitude: phi = phi0 e^(-zeta w t) (cos w_d t + zeta w / w_d sin w_d t)."""
    l, m, mu, kappa, nu, phi0 = 2.0, 3.0, 0.4, 7.0, 0.05, 0.6
    I = m * l**3 / 3.0 + mu * l**2
    w = math.sqrt(kappa / I)
    zeta = nu / (2.0 * math.sqrt(kappa * I))
    wd = w * math.sqrt(1.0 - zeta**2)
    sc = Scene(
        chain=Chain.uniform(1, l=l, m=m, EI=1.0, mu=mu, kappa=kappa, nu=nu),
        t_end=20.0,
        times=np.linspace(0.0, 20.0, 201),
        outputs=("phi",),
        initial=InitialState(phi=[phi0]),
    )
    tr = simulate(sc, "rigid", **TIGHT)
    t = tr.times
    exact = phi0 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))
    assert np.abs(tr["phi"][:, 0] - exact).max() <= 1e-9 * phi0
    # its mode: w and zeta (the rigid modal analysis, another path: the full model's pencil on
    # the rigid basis)
    modes = rodval.modes(sc.with_(initial=InitialState(phi=[0.0])), "rigid")
    assert abs(modes.omega[0] - w) <= 1e-12 * w
    assert abs(modes.damping[0] - zeta) <= 1e-9 * zeta


def test_a_free_800_kg_body_keeps_the_momenta_through_every_lock():
    """The latched wing on an 800 kg body from rest: P = 0 and H = 0 (about the centre of
    mass) for ever, through both locks (internal impulses), to KEPT of the momenta's scale
    (the body's largest |P_body| = m_b |v_c|, equal and opposite to the chain's)."""
    outputs = ("phi", "base", "momentum", "angular_momentum")
    tr = simulate(latch3_scene().with_(base=BODY, outputs=outputs), "rigid", **TIGHT)
    assert tr.success and sorted(e["hinge"] for e in tr.events) == [1, 2]
    scale = 800.0 * np.abs(tr["base_velocity"]).max()
    assert scale > 1.0
    assert np.abs(tr["momentum"]).max() <= KEPT * scale
    spin = 533.0 * np.abs(tr["base_rate"]).max()
    assert np.abs(tr["angular_momentum"][:, 1]).max() <= KEPT * spin
    assert tr.stats.momentum_residual is not None and tr.stats.momentum_residual <= KEPT


def test_a_prescribed_base_runs_follows_its_laws_and_books_the_drive():
    hub = Base(
        kind="prescribed",
        hinge_offset=(0.5, 0.0),
        motion={
            "attitude": Motion("spin_up", (2.0, 1.0)),
            "x": Motion("harmonic", (0.1, 3.0, 0.0)),
        },
    )
    sc = latch3_scene().with_(base=hub, outputs=("phi", "base", "energy", "drive"))
    tr = simulate(sc, "rigid")
    assert tr.success and sorted(e["hinge"] for e in tr.events) == [1, 2]
    for t, theta in zip(tr.times, tr["base_attitude"][:, 0]):
        assert abs(theta - hub.state_at(float(t))[2]) < 1e-8
    assert tr.stats.energy_residual is not None and tr.stats.energy_residual < 1e-6


def test_the_full_model_tends_to_the_rigid_one_on_stiff_damped_panels():
    """The latched 3-panel wing at EI 1e9 with 30 % bending damping (the locks' ring damped
    out: undamped, the full model keeps the ring's energy, which rigid panels lose at the
    lock): measured, lock 1 (hinge 2) 5.5e-9 s and lock 2 (hinge 1) 3.0e-5 s apart, phi
    within 1.8e-4 rad (at EI 1e6..1e8: 8.3e-4, 2.9e-4, 9.4e-5 s for lock 2, EI^-1/2)."""
    sc = latch3_scene()
    ch = sc.chain.with_(EI=np.full(3, 1e9))
    c = bending_damping_for_ratio(0.3, ch.l, ch.m, ch.EI)
    stiff = sc.with_(chain=ch.with_(bending_damping=np.asarray(c, float)))
    full = simulate(stiff, "full", kinematics="exact")
    rigid = simulate(stiff, "rigid", rtol=1e-10, atol=1e-12)
    assert full.success and rigid.success
    times = {e["hinge"]: e["t"] for e in rigid.events}
    assert len(full.events) == len(rigid.events) == 2
    for e in full.events:
        assert abs(e["t"] - times[e["hinge"]]) < 1e-4
    assert np.abs(full["phi"] - rigid["phi"]).max() < 1e-3


def test_the_commands_run_the_rigid_model(tmp_path, capsys):
    """simulate, compare, modes and a study with the rigid model, through rodval.cli.main."""
    scene = Path(__file__).resolve().parents[1] / "studies/scenes/wing_stop_latches.toml"
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["simulate", str(scene), "--model", "rigid", "--out", str(a)]) == 0
    assert main(["simulate", str(scene), "--model", "reduced", "--out", str(b)]) == 0
    assert main(["compare", str(a), str(b), "--out", str(tmp_path / "cmp")]) == 0
    assert "latch hinge 4" in (tmp_path / "cmp" / "events.md").read_text()
    assert main(["modes", "paper", "--model", "rigid", "--out", str(tmp_path / "m")]) == 0
    assert (tmp_path / "m" / "frequencies.csv").exists()
    doc = {
        "study": {"name": "rigid", "reference": "rigid"},
        "scene": {"file": str(scene), "t_end": 1.0, "times": {"num": 11}},
        "models": {"rigid": {}, "reduced": {}},
    }
    run = rodval.run_study(doc, tmp_path / "st", workers=1, progress=False, report=False)
    assert len(run.ran) == 1
    runtime = read_tables(run.out)["runtime"]
    assert set(runtime["model"]) == {"rigid", "reduced"}


@pytest.mark.parametrize(
    "options, match",
    [
        ({"shapes": 2}, "unknown rigid model option 'shapes'"),
        ({"kinematics": "exact"}, "unknown rigid model option 'kinematics'"),
        ({"coefficients": "published"}, "unknown rigid model option 'coefficients'"),
    ],
)
def test_bad_options_are_refused_in_one_line(options, match):
    with pytest.raises(ValueError, match=match) as err:
        simulate(latch3_scene(), "rigid", **options)
    assert "\n" not in str(err.value)


def test_modes_refuse_an_option_and_a_free_base_in_one_line():
    straight = latch3_scene().with_(latches=(), initial=InitialState(phi=[0.0, 0.0, 0.0]))
    assert rodval.modes(straight, "rigid").omega.size == 3
    with pytest.raises(ValueError) as err:
        rodval.modes(straight, "rigid", shapes=2)
    assert "\n" not in str(err.value) and "shapes" in str(err.value)
    with pytest.raises(ValueError, match="free base") as err:
        rodval.modes(straight.with_(base=BODY), "rigid")
    assert "\n" not in str(err.value)


def test_modes_of_a_rigid_chain_with_every_hinge_held_are_refused_in_one_line():
    """Every hinge held: nothing moves, so no modes; one line naming why (it crashed with
    numpy's zero-size error)."""
    from rodval.core.hinges import Latch
    from rodval.core.scene import Chain, Scene

    chain = Chain.uniform(2, l=1.0, m=1.0, EI=1e4)
    scene = Scene(chain=chain, latches=(Latch(0, 0.0, held=True), Latch(1, 0.0, held=True)))
    with pytest.raises(ValueError, match="every hinge is held") as info:
        rodval.modes(scene, "rigid")
    assert "\n" not in str(info.value)
