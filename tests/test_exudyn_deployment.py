"""Deployment in the exudyn reference model: hinge rest angles (pre-stress), one-sided limit
stops, latches locked by an activated rotation constraint, and the lock measures (time,
angular impulse, kinetic energy, angular momentum about the root) taken on the beam solution."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scenes import two_rod_latch

from rodval import Chain, InitialState, Scene, simulate
from rodval.core import scene as scene_module
from rodval.core.scene import Latch, Stop

exu = pytest.importorskip("exudyn")
from reference_models.exudyn_chain import ExudynModel  # noqa: E402

pytestmark = pytest.mark.exudyn

EVENT_KEYS = {"t", "label", "hinge", "impulse", "impulse_window", "kinetic_before", "kinetic_after"}


@pytest.fixture
def hinge_quantities(monkeypatch):
    """rodval.core.scene.QUANTITIES does not list "hinge_angle" / "hinge_moment" yet (core is
    not this branch's to edit): allow them for these tests."""
    monkeypatch.setattr(
        scene_module, "QUANTITIES", (*scene_module.QUANTITIES, "hinge_angle", "hinge_moment")
    )


def unfolding_pair(
    t_end=0.5, EI=1e5, num=501, outputs=("phi", "dphi", "hinge_angle", "hinge_moment", "energy")
):
    """Two rods stowed folded back (hinge 1 at pi - 0.05 rad), hinge 0 free, the chain turning
    at 1 rad/s; hinge 1's spring (50 N m/rad, rest angle 0) unfolds it; the latch locks
    hinge 1 straight (angle 0). (``scenes.two_rod_latch`` with this file's horizon and outputs.)"""
    return two_rod_latch(EI, t_end=t_end, num=num, outputs=outputs)


def run(scene, **options):
    options = {"elements": 2, "step": 1e-4, "spectral_radius": 0.0, **options}
    tr = simulate(scene, "exudyn", **options)
    assert tr.success, tr.stats.message
    return tr


def test_rest_angle_is_the_springs_relaxed_angle():
    """One stiff rod on a hinge-0 spring with rest angle 0.3 rad, released at rest from
    phi = 0, no damping: it swings between 0 and 2 x 0.3 rad about the rest angle."""
    chain = Chain.uniform(1, l=1.0, m=2.0, EI=1e7, mu=0.0, kappa=40.0, nu=0.0, rest_angle=0.3)
    scene = Scene(chain=chain, t_end=1.0, times=np.linspace(0, 1.0, 1001), outputs=("phi",))
    phi = run(scene, elements=1, step=5e-4)["phi"][:, 0]
    period = 2 * math.pi / math.sqrt(40.0 / (2.0 / 3.0))
    assert period < 1.0
    assert phi.max() == pytest.approx(0.6, abs=2e-3)
    assert phi.min() == pytest.approx(0.0, abs=2e-3)


def test_stop_limits_the_hinge_and_conserves_energy():
    """The same rod driven towards rest angle 1 rad hits an upper stop at 0.4 rad (stiffness
    1e4 N m/rad, no damping): it penetrates by about sqrt(2 W / k) with W the spring work
    up to the stop, bounces back, and the total energy (spring, stop, beam) is conserved."""
    kappa, rest, angle, k_stop = 20.0, 1.0, 0.4, 1e4
    chain = Chain.uniform(1, l=1.0, m=2.0, EI=1e7, mu=0.0, kappa=kappa, nu=0.0, rest_angle=rest)
    scene = Scene(
        chain=chain,
        t_end=0.8,
        times=np.linspace(0, 0.8, 1601),
        outputs=("phi", "energy"),
        stops=(Stop(0, angle, "upper", stiffness=k_stop),),
    )
    tr = run(scene, elements=1, step=1e-4)
    phi, energy = tr["phi"][:, 0], tr["energy"][:, 0]
    work = 0.5 * kappa * (rest**2 - (rest - angle) ** 2)
    assert phi.max() - angle == pytest.approx(math.sqrt(2 * work / k_stop), rel=0.05)
    assert phi[-1] < angle  # bounced back
    assert np.ptp(energy) < 2e-3 * energy[0]


def test_latch_lock_measured_on_the_beam_solution(hinge_quantities):
    """Two-rod pre-stressed latch: one lock, bracketed within the step where the joint was
    switched on; D stays at the latch angle afterwards; the relative rate is killed; kinetic
    energy is lost; the angular momentum about the root (hinge 0 free, no loads) is
    continuous through the lock to 1e-5 of the outboard angular impulse."""
    tr = run(unfolding_pair())
    assert len(tr.events) == 1
    ev = tr.events[0]
    assert EVENT_KEYS <= set(ev)
    assert ev["label"] == "latch hinge 1" and ev["hinge"] == 1
    assert ev["t_activated"] <= ev["t"] <= ev["t_activated"] + 2 * ev["step"]
    assert ev["window_closed"]
    # the latch stops D decreasing: its impulse on rod 2 is counter-clockwise (positive)
    assert ev["impulse"] > 1.0
    assert ev["kinetic_after"] < ev["kinetic_before"]
    H0 = ev["angular_momentum_root_before"]
    assert abs(H0) > 1.0
    assert abs(ev["angular_momentum_root_jump"]) < 1e-5 * ev["impulse"]
    D = tr["hinge_angle"][:, 1]
    after = tr.times > ev["t_activated"] + 3 * ev["step"]
    assert np.abs(D[after]).max() < 1e-9
    before = tr.times < ev["t"]
    assert D[before].min() > 0
    assert D[0] == pytest.approx(math.pi - 0.05, abs=1e-9)
    # the chord rates equalize on average after the lock (elastic vibration remains)
    dphi = tr["dphi"]
    late = tr.times > ev["t"] + 0.05
    assert abs(np.mean(dphi[late, 1] - dphi[late, 0])) < 0.05 * abs(ev["chord_rate_before"])
    # hinge moment before the lock: the spring law kappa (D - rest); after it, the beam's
    # root bending moment, whose largest value in the lock window is recorded
    M = tr["hinge_moment"][:, 1]
    assert M[0] == pytest.approx(50.0 * (math.pi - 0.05), rel=1e-9)
    window = (tr.times > ev["t_activated"]) & (tr.times < ev["t"] + ev["impulse_window"])
    assert ev["peak_moment"] >= 0.9 * np.abs(M[window]).max() > 0


def test_latch_measures_converge_with_step(hinge_quantities):
    """Halving exudyn's step (1e-4 -> 5e-5 s) moves the lock time by less than 5e-5 s and the
    lock impulse by less than 2e-3 (measured: 1.7e-5 s, 4.6e-4; from 2e-4 s: 1.7e-5 s,
    9.1e-4); the angular momentum about the root jumps by less at the finer step (second
    order: 1.1e-4, 2.8e-5, 5.3e-6 N m s at 2e-4, 1e-4, 5e-5 s). The run goes past the lock
    window (22.8 ms at EI = 1e5)."""
    a = run(unfolding_pair(t_end=0.44, num=45), step=1e-4).events[0]
    b = run(unfolding_pair(t_end=0.44, num=45), step=5e-5).events[0]
    assert a["window_closed"] and b["window_closed"]
    assert abs(a["t"] - b["t"]) < 5e-5
    assert a["impulse"] == pytest.approx(b["impulse"], rel=2e-3)
    jump_a, jump_b = (abs(e["angular_momentum_root_jump"]) for e in (a, b))
    assert jump_b < 0.5 * jump_a


def test_latch_measures_converge_with_elements(hinge_quantities):
    """2 -> 4 elements per rod: lock time within 5e-5 s, impulse within 1 % (measured:
    1.2e-5 s, 0.25 %)."""
    a = run(unfolding_pair(t_end=0.44, num=45), elements=2).events[0]
    b = run(unfolding_pair(t_end=0.44, num=45), elements=4).events[0]
    assert abs(a["t"] - b["t"]) < 5e-5
    assert a["impulse"] == pytest.approx(b["impulse"], rel=0.01)


def test_stiff_rods_lock_with_the_rigid_plastic_impulse(hinge_quantities):
    """In the rigid-panel limit the latch's measured impulse is the plastic impact of two rigid
    links (pinned root, hinge 0 free): S = -w / (v^T M^-1 v), v = (-1, 1), w the relative chord
    rate before the lock, M the links' mass matrix at the straight configuration. EI = 1e6 N m^2:
    within 1 % (measured 0.29 %; 0.33 % with 4 elements); the lock window is the locked pair's
    first bending period, 7.2 ms."""
    l, m, mu = 1.5, 3.0, 0.5
    ev = run(unfolding_pair(t_end=0.42, num=43, EI=1e6)).events[0]
    M11 = m * l**3 / 3 + (m * l + 2 * mu) * l**2
    M22 = m * l**3 / 3 + mu * l**2
    M12 = l * l * (m * l / 2 + mu)
    v = np.array([-1.0, 1.0])
    rigid = -ev["chord_rate_before"] / (v @ np.linalg.inv([[M11, M12], [M12, M22]]) @ v)
    assert ev["impulse"] == pytest.approx(rigid, rel=0.01)
    assert ev["impulse_window"] == pytest.approx(7.21e-3, rel=1e-3)
    assert ev["window_closed"]


def test_default_options_run_a_latch_scene_with_spectral_radius_zero():
    """exudyn's defaults work with latches (issue 19): spectral_radius "auto" is 0 for a
    scene with latches and 0.9 without, and the run records the value it used; the lock is
    the one the explicit setting gives (same options, the same numbers to round-off)."""
    scene = unfolding_pair(t_end=0.45, num=10, outputs=("phi",))
    auto = simulate(scene, "exudyn")
    assert auto.success, auto.stats.message
    assert auto.settings["spectral_radius"] == 0.0 and auto.options["spectral_radius"] == "auto"
    explicit = simulate(scene, "exudyn", spectral_radius=0.0)
    assert [ev["label"] for ev in auto.events] == ["latch hinge 1"]
    assert auto.events[0]["t"] == explicit.events[0]["t"]
    np.testing.assert_array_equal(auto.values["phi"], explicit.values["phi"])
    free = dataclasses.replace(scene, latches=())
    assert simulate(free, "exudyn").settings["spectral_radius"] == 0.9


@pytest.mark.parametrize(
    "options, match",
    [({"solver": "trapezoidal"}, "generalized-alpha"), ({"spectral_radius": 0.9}, "spectral")],
)
def test_latch_scene_refused_before_any_work(options, match):
    scene = unfolding_pair(t_end=0.1, num=3, outputs=("phi",))
    with pytest.raises(ValueError, match=match):
        ExudynModel(**options).simulate(scene)


@pytest.mark.parametrize(
    "latch, match",
    [
        (Latch(1, math.pi - 0.05), "at or beyond"),
        (Latch(1, 0.0, direction=1), "direction"),
        (Latch(2, 0.0), "0..n-1"),
    ],
)
def test_bad_latches_refused_by_the_scene(latch, match):
    with pytest.raises(ValueError, match=match):
        unfolding_pair(outputs=("phi",)).with_(latches=(latch,))


def synthetic_record(case: str, events: dict[str, list[dict]]):
    """A CaseRecord whose runs carry the given events (label -> events), no values."""
    from rodval.core.trajectory import SolverStats, Trajectory
    from rodval.study.records import CaseRecord, RunRecord

    runs = [
        RunRecord(
            label, 0.0, Trajectory(label, case, np.zeros(0), {}, {}, SolverStats(), events=ev)
        )
        for label, ev in events.items()
    ]
    scene = {"chain": {"l": [1.0, 1.0]}, "t_end": 1.0}
    return CaseRecord(case, "f", {}, scene, "exudyn", runs, [])


NATIVE_EVENT = {
    "t": 0.4041,
    "label": "latch hinge 1",
    "hinge": 1,
    "impulse": 22.9,
    "impulse_window": 2.3e-3,
    "kinetic_before": 242.8,
    "kinetic_after": 1.0,
}


def test_events_table_and_discrepancies_with_native_records():
    """The events table takes the native models' records (keys t, label, hinge,
    impulse, impulse_window, kinetic_before, kinetic_after) and exudyn's (more keys) side by side;
    the discrepancies pair them by case and label."""
    from rodval.report.study_report import event_discrepancies
    from rodval.study.tables import EVENT_COLUMNS, events_table

    exudyn_event = {**NATIVE_EVENT, "t": 0.4040, "impulse": 23.0, "peak_moment": 6e3}
    rec = synthetic_record(
        "base", {"exudyn": [exudyn_event], "full": [NATIVE_EVENT], "reduced": []}
    )
    table = events_table([rec], {})
    assert list(table.columns[: 4 + len(EVENT_COLUMNS)]) == [
        "case",
        "n",
        "horizon",
        "model",
        *EVENT_COLUMNS,
    ]
    assert "peak_moment" in table
    assert table["energy_lost"].tolist() == pytest.approx([241.8, 241.8])
    disc = event_discrepancies(table, "exudyn")
    row = disc.iloc[0]
    assert row["model"] == "full" and row["label"] == "latch hinge 1"
    assert row["dt"] == pytest.approx(1e-4)
    assert row["impulse_rel"] == pytest.approx(0.1 / 23.0)


def test_stop_contacts_are_events_in_exudyn_as_in_the_native_models():
    """exudyn records each stop contact as the native models do ("stop hinge k on" / "off",
    hinge, active), found between recorded states and located by linear interpolation:
    a rod turning at 2 rad/s reaches its stop at 0.5 rad at t = 0.25 s exactly (located
    within 1e-5 s: the O(h^2) interpolation over a quarter of a 2e-4 s step, measured
    2.5e-6); it leaves the stop when the full model says, within 1e-4 s (measured 4e-6)."""
    chain = Chain.uniform(1, l=1.0, m=1.0, EI=1e5, mu=0.5, kappa=0.0, nu=0.0)
    scene = Scene(
        chain=chain,
        t_end=0.6,
        times=np.linspace(0.0, 0.6, 61),
        initial=InitialState(dphi=[2.0]),
        stops=(Stop(0, 0.5, "upper", stiffness=2e3),),
        outputs=("phi",),
    )
    ex, full = simulate(scene, "exudyn"), simulate(scene, "full")
    labels = ["stop hinge 0 on", "stop hinge 0 off"]
    assert [ev["label"] for ev in ex.events] == [ev["label"] for ev in full.events] == labels
    assert [ev["active"] for ev in ex.events] == [True, False]
    assert ex.events[0]["t"] == pytest.approx(0.25, abs=1e-5)
    assert ex.events[1]["t"] == pytest.approx(full.events[1]["t"], abs=1e-4)


def test_report_renders_the_deployment_section(tmp_path):
    """A tiny study run by the native reduced models, with an events.csv of native-style
    records added: the report gains the deployment section (events, discrepancies, residual
    vibration) and the deployment figure."""
    from study_helpers import write_study

    from rodval.report.study_report import build_report
    from rodval.study import load_study, run_study
    from rodval.study.tables import events_table

    path = write_study(tmp_path, grid="scene.t_end = [0.1]")
    out = tmp_path / "out"
    run_study(load_study(path), out, workers=1, progress=False)
    cases = sorted(p.stem for p in (out / "cases").glob("*.json"))
    recs = [
        synthetic_record(
            c,
            {
                "reduced": [{**NATIVE_EVENT, "t": 0.05}],
                "published": [{**NATIVE_EVENT, "t": 0.052, "impulse": 23.4}],
            },
        )
        for c in cases
    ]
    events_table(recs, {}).to_csv(out / "events.csv", index=False)
    text = build_report(out).read_text()
    assert "## Deployment: locks, impulses and residual vibration" in text
    assert "Lock discrepancies against `reduced`" in text
    assert "Residual vibration after the last lock" in text
    assert list((out / "figures").glob("deployment_*.png"))
