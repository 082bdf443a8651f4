"""Motors and rate dampers (issue 55): a moment across a hinge, applied by every model through
the one load table (components 2 and 3, ``rodval.core.loads``), its power booked as external
work. Closed forms on one pinned rod without springs (I = m l^3/3 + mu l^2 about the pin):

* constant torque T: H_0(t) = T t in every model (no other moment about the pin), and phi(t)
  = T t^2 / (2 I) where the chord turns as a rigid body (rigid; reduced, whose chord obeys
  I phi'' = T when kappa = 0, its bending being quasi-static);
* torque-speed motor M = T_s (1 - w / w_0): w(t) = w_0 (1 - exp(-t / tau)), tau = I w_0 / T_s,
  its work int M w dt = I w^2 / 2;
* rate damper -c w from w(0) = w_i: w(t) = w_i exp(-c t / I), its work I (w^2 - w_i^2) / 2.

Bounds: the compiled DOP853 at rtol 1e-12 carries ~1e-11 relative global error on these
smooth one-degree-of-freedom solutions (phi is a polynomial of degree 2 for a constant torque:
round-off only), so 1e-9 keeps two orders of room; the audit's work is a Gauss quadrature of
the power on each step's dense output (exact to the dense output's order), 1e-8 likewise.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scenes import motor_wing

from rodval import Chain, InitialState, Motor, RateDamper, Scene, simulate
from rodval.core.scene_file import scene_from_dict

L, MASS, TIP = 1.2, 2.0, 0.5  # m, kg/m, kg
INERTIA = MASS * L**3 / 3.0 + TIP * L**2  # kg m^2 about the pin
TIGHT = dict(method="DOP853-numba", rtol=1e-12, atol=1e-14)
RIGID_CHORD = ["rigid", "reduced"]
EVERY_NATIVE = [("full", "first-order"), ("full", "exact"), ("reduced", None), ("rigid", None)]


def one_rod(EI: float = 1e5, dphi: float = 0.0, t_end: float = 1.0, **items) -> Scene:
    """One pinned rod (l = L, m = MASS, tip mass TIP) without hinge spring or damper."""
    return Scene(
        Chain.uniform(1, l=L, m=MASS, mu=TIP, EI=EI, kappa=0.0, nu=0.0),
        t_end=t_end,
        times=np.linspace(0.0, t_end, 11),
        initial=InitialState(dphi=[dphi]),
        outputs=("phi", "dphi", "angular_momentum", "hinge_moment", "energy"),
        **items,
    )


def _run(scene: Scene, model: str, kinematics: str | None = None, **settings):
    options = {} if kinematics is None else {"kinematics": kinematics}
    traj = simulate(scene, model, **{**TIGHT, **settings}, **options)
    assert traj.stats.status == 0, traj.stats.message
    return traj


CONSTANT = dict(motors=(Motor(0, torque={"type": "constant", "value": 3.0}),))


@pytest.mark.parametrize("model", RIGID_CHORD)
def test_a_constant_torque_turns_the_chord_as_a_rigid_body(model):
    traj = _run(one_rod(**CONSTANT), model)
    t = traj.times
    expected = 3.0 * t**2 / (2.0 * INERTIA)
    np.testing.assert_allclose(traj["phi"][:, 0], expected, rtol=1e-9, atol=1e-12)
    # the hinge moment is the motor's, with the sign of a resisting spring
    np.testing.assert_allclose(traj["hinge_moment"][:, 0], -3.0, rtol=1e-12)


@pytest.mark.parametrize("model,kinematics", EVERY_NATIVE)
def test_a_constant_torque_gives_the_angular_momentum_T_t(model, kinematics):
    """H_0 = T t exactly in every model, the flexible ones too (the rod bends under the root
    moment, so only the rigid-chord models give phi = T t^2 / (2 I))."""
    traj = _run(one_rod(**CONSTANT), model, kinematics)
    H0 = traj["angular_momentum"][:, 0]
    np.testing.assert_allclose(H0, 3.0 * traj.times, rtol=0, atol=1e-9 * 3.0)


def test_the_full_model_turns_as_a_rigid_body_as_EI_grows():
    """The full model's chord leaves T t^2/(2 I) by the root moment's bending, ~ T / EI: a
    hundredfold stiffer rod parts a hundredfold less (the ratio within a factor 2)."""
    dev = []  # 2.4e-5 and 2.3e-7 rad over 0.2 s, far above rtol 1e-10's error (~1e-11 rad)
    for EI in (1e4, 1e6):
        scene = one_rod(EI=EI, t_end=0.2, **CONSTANT)
        traj = _run(scene, "full", "first-order", rtol=1e-10, atol=1e-12)
        rigid = 3.0 * traj.times**2 / (2.0 * INERTIA)
        dev.append(np.max(np.abs(traj["phi"][:, 0] - rigid)))
    assert dev[0] > 1e-6, dev  # the flexible rod does part
    assert 0.5e-2 < dev[1] / dev[0] < 2e-2, dev


STALL, NO_LOAD = 2.0, 1.5  # N m, rad/s
LINE = dict(motors=(Motor(0, stall_torque=STALL, no_load_speed=NO_LOAD),))


@pytest.mark.parametrize("model", RIGID_CHORD)
def test_a_torque_speed_motor_books_its_work_as_external(model):
    traj = _run(one_rod(t_end=3.0, **LINE), model)
    t = traj.times
    tau = INERTIA * NO_LOAD / STALL
    w = NO_LOAD * (1.0 - np.exp(-t / tau))
    np.testing.assert_allclose(traj["dphi"][:, 0], w, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(traj["work"][:, 0], 0.5 * INERTIA * w**2, rtol=1e-8, atol=1e-12)
    assert np.max(np.abs(traj["dissipated"][:, 0])) == 0.0  # no damper: nothing dissipated


@pytest.mark.parametrize("model", RIGID_CHORD)
def test_a_rate_damper_brakes_one_rod_exponentially(model):
    c, w_i = 0.8, 2.5  # N m s/rad, rad/s
    traj = _run(one_rod(dphi=w_i, t_end=2.0, rate_dampers=(RateDamper(0, damping=c),)), model)
    w = w_i * np.exp(-c * traj.times / INERTIA)
    np.testing.assert_allclose(traj["dphi"][:, 0], w, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(
        traj["work"][:, 0], 0.5 * INERTIA * (w**2 - w_i**2), rtol=1e-8, atol=1e-12
    )


def test_a_rate_damper_drives_towards_its_set_rate():
    """-c (w - w_s) from rest: w(t) = w_s (1 - exp(-c t / I))."""
    c, w_s = 1.5, 0.7
    scene = one_rod(t_end=2.0, rate_dampers=(RateDamper(0, damping=c, rate=w_s),))
    traj = _run(scene, "rigid")
    w = w_s * (1.0 - np.exp(-c * traj.times / INERTIA))
    np.testing.assert_allclose(traj["dphi"][:, 0], w, rtol=1e-9, atol=1e-12)


def test_the_scipy_path_applies_the_same_moments():
    """The closed forms (``HingeTorque.moment``) on the scipy path give the compiled rows'
    trajectory (RK45 at rtol 1e-12: ~1e-10 apart)."""
    scene = one_rod(t_end=1.0, **LINE)
    compiled = _run(scene, "reduced")
    scipy = _run(scene, "reduced", method="RK45")
    np.testing.assert_allclose(scipy["phi"], compiled["phi"], rtol=1e-8, atol=1e-10)


#: The energy balance each model keeps (docs/stability.md, "What residual each model has"):
#: exact for the rigid chain and the exact kinematics (the integration error, ~1e-11 at rtol
#: 1e-11, bounded at 1e-8); the first-order full model and the reduced one carry their
#: model's residual (5e-5 to 3e-3 on the paper chain): on this wing 3.4e-4 and 6.3e-4 with
#: the motors, 3.0e-3 and 2.7e-5 deployed by springs instead (the reduced model books a
#: moment's power on its chord rates, as its dampers, and its quasi-static bending energy
#: moves with the torque-speed motor's moment).
BALANCE = {("full", "first-order"): 1e-3, ("full", "exact"): 1e-8, ("reduced", None): 1e-3,
           ("rigid", None): 1e-8}  # fmt: skip


@pytest.mark.parametrize("model,kinematics", EVERY_NATIVE)
def test_motors_deploy_the_latched_wing_and_the_audit_books_their_work(model, kinematics):
    """Both motors drive their hinges to the latches; the energy balance E - E(0) - W + D
    closes as the model's own balance allows (``BALANCE``), the motors' work booked as
    external and the locks' plastic losses as dissipation."""
    traj = _run(motor_wing(), model, kinematics, rtol=1e-11, atol=1e-13)
    locks = [e for e in traj.events if "latch" in e["label"]]
    assert sorted(e["label"] for e in locks) == ["latch hinge 1", "latch hinge 2"]
    assert all(0.5 < e["t"] < 2.5 for e in locks), [(e["label"], e["t"]) for e in locks]
    work = traj["work"][-1, 0]
    assert work > 1.0  # J: the motors do real work
    assert traj.stats.energy_residual <= BALANCE[model, kinematics], traj.stats.energy_residual


def test_motor_tables_round_trip_and_bad_ones_are_named():
    doc = {
        "based_on": "paper",
        "motors": [
            {"hinge": 0, "torque": {"type": "ramp", "value": 2.0, "t_on": 0.0, "t_full": 0.2}},
            {"hinge": 1, "stall_torque": 3.0, "no_load_speed": 0.5},
        ],
        "rate_dampers": [{"hinge": 2, "damping": 4.0, "rate": 0.1}],
    }
    scene = scene_from_dict(doc, "f.toml")
    assert [m.as_dict() for m in scene.motors] == doc["motors"]
    assert [d.as_dict() for d in scene.rate_dampers] == doc["rate_dampers"]
    assert 0.2 in scene.breakpoints  # the ramp's kink
    for bad, words in [
        ({"hinge": 0}, "got neither"),
        ({"hinge": 0, "stall_torque": 1.0}, "go together"),
        ({"hinge": 0, "torque": {"type": "pulse", "value": 1.0}}, "type one of constant"),
        ({"hinge": 0, "torque": {"type": "constant", "value": "x"}}, "value must be"),
        ({"hinge": 0, "stall_torque": -1.0, "no_load_speed": 1.0}, "stall_torque must be"),
    ]:
        with pytest.raises(ValueError, match=words):
            scene_from_dict({"based_on": "paper", "motors": [bad]}, "f.toml")
    with pytest.raises(ValueError, match=r"rate_dampers.0.damping': is missing"):
        scene_from_dict({"based_on": "paper", "rate_dampers": [{"hinge": 0}]}, "f.toml")


def test_a_motor_law_and_its_rows_agree():
    """The closed form and the compiled rows are one law (``hinge_torques`` evaluates the
    rows as the kernels do)."""
    from rodval.core.load_table import applied_torques, hinge_torques, load_table

    items = (
        Motor(0, torque={"type": "harmonic", "value": 2.0, "omega": 3.0, "phase": 0.1}),
        Motor(1, stall_torque=3.0, no_load_speed=0.5),
        RateDamper(1, damping=4.0, rate=0.2),
    )
    table = load_table((), [r for item in items for r in item.rows()])
    rates = np.array([0.3, -0.4])
    for t in np.linspace(0.0, 2.0, 7):
        T, C = hinge_torques(table, t, 2)
        expected = np.zeros(2)
        for item in items:
            expected[item.hinge] += item.moment(t, rates[item.hinge])
        np.testing.assert_allclose(applied_torques(T, C, rates), expected, rtol=1e-14, atol=0)
    assert math.isclose(items[1].moment(0.0, 0.5), 0.0)  # none at the no-load speed


def test_full_and_exudyn_lock_the_motor_wing_within_a_millisecond():
    """The independent exudyn model (its motors are torsional connectors whose user law is the
    item's closed form, reference_models/exudyn_build.py) locks both hinges of the motor wing
    within 1 ms of the full model (measured: 0.10 and 0.15 ms at 4 elements, 2e-4 s steps; a
    step of 1e-4 s halves both, exudyn's lock being first order in its step)."""
    scene = motor_wing(t_end=1.5, num=31)
    full = simulate(scene, "full")
    exudyn = simulate(scene, "exudyn", elements=4, step=2e-4)
    assert full.stats.status == 0 and exudyn.stats.status == 0
    times = [{e["label"]: e["t"] for e in traj.events} for traj in (full, exudyn)]
    assert set(times[0]) == set(times[1]) == {"latch hinge 1", "latch hinge 2"}
    for label, t in times[0].items():
        assert abs(times[1][label] - t) < 1e-3, (label, t, times[1][label])


def test_modes_of_a_scene_with_torque_items_are_refused_not_built_without_them():
    """A motor's moment would load the equilibrium and a rate coefficient damp the modes:
    rather than leave them out silently, every model's modes refuse the scene in one line."""
    from rodval.models.registry import get_model

    scene = one_rod(**LINE)
    for model in ("full", "reduced", "exudyn"):
        with pytest.raises(ValueError, match=r"modes of a scene with motors are not built"):
            get_model(model).modes(scene)


def test_the_shipped_motor_wing_deploys(tmp_path):
    """studies/scenes/wing_motors.toml: both latches lock, the run valid."""
    from rodval.core.scene_file import load_scene

    scene = load_scene(Path(__file__).resolve().parents[1] / "studies/scenes/wing_motors.toml")
    traj = simulate(scene, "reduced")
    assert traj.stats.status == 0, traj.stats.message
    assert {e["label"] for e in traj.events} == {"latch hinge 1", "latch hinge 2"}
