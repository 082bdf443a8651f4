"""The lock impulse (issue 19): one definition in every model, the latch reaction's impulse,
instantaneous part included, averaged over the lock window after the lock
(``rodval.mechanics.lock_window``); the native models measure it on their multiplier and cross-check
it on the outboard angular momentum, exudyn on the angular momentum. In the rigid-panel limit
it must be the plastic impulse of rigid panels, ``rigid_impulse``."""

import dataclasses
import math

import numpy as np
import pytest
from scenes import stiff_damped_latch, two_rod_latch

from rodval import simulate
from rodval.core.scene import Chain, Latch
from rodval.core.scene_file import scene_from_dict, scene_to_dict
from rodval.mechanics.lock_window import first_bending_period, locked_segment, window_nodes


@pytest.mark.parametrize(
    "n, hinge, held, beta_l",
    [
        (3, 1, (), 3.926602312),  # the locked pair, pinned-free, 2 l
        (3, 0, (), 1.875104069),  # rod 1 clamped at a held root, l
        (3, 1, (2,), 3.926602312),  # rods 1-3 through held hinge 2, pinned-free, 3 l
        (3, 2, (0, 1), 1.875104069),  # rods 1-3 clamped at the held root, 3 l
        (4, 2, (), 3.926602312),  # the pair 2-3: hinges 1 and 3 free
        (1000, 1, range(1, 1000), 3.926602312),  # 1000 rods in 128 sections
        (1000, 5, range(1000), 1.875104069),
    ],
)
def test_the_default_window_is_the_locked_segments_euler_bernoulli_period(n, hinge, held, beta_l):
    """Without node masses a locked segment of uniform rods is a uniform beam: pinned-free
    (beta L = 3.9266) or clamped-free at a held root (beta L = 1.8751), L its length. Period
    within 1e-5: 8 Hermite elements per rod of a pair, >= 16 in all (measured <= 2.5e-6, the
    elements' h^4 error); a 1000-rod segment as 128 uniform sections (measured 1e-7 and
    2.4e-6: round-off of a condition number 128^4)."""
    chain = Chain.uniform(n, l=1.5, m=3.0, EI=1e7, mu=0.0)
    rods, _ = locked_segment(n, hinge, held)
    omega = (beta_l / (1.5 * len(rods))) ** 2 * math.sqrt(1e7 / 3.0)
    assert first_bending_period(chain, hinge, held) == pytest.approx(2 * math.pi / omega, rel=1e-5)


def test_the_locked_segment_runs_through_held_hinges_only():
    assert locked_segment(6, 3, [3]) == (range(2, 4), False)
    assert locked_segment(6, 3, [1, 2, 4, 5]) == (range(0, 6), False)
    assert locked_segment(6, 3, [0, 2]) == (range(1, 4), False)  # hinge 1 free: pinned at node 1
    assert locked_segment(6, 1, [0, 1]) == (range(0, 2), True)
    with pytest.raises(ValueError, match="hinge must be 0..5"):
        locked_segment(6, 6, [])


def test_node_masses_lengthen_the_window():
    bare = first_bending_period(Chain.uniform(2, l=1.5, m=3.0, EI=1e7, mu=0.0), 1)
    assert first_bending_period(Chain.uniform(2, l=1.5, m=3.0, EI=1e7, mu=0.5), 1) > bare


def test_the_window_quadrature_is_exact_and_averages_out_the_ring():
    """The taper weights integrate s^j (1 - s/w) exactly for j <= 8 (Gauss-Legendre, 4 nodes
    on 64 panels: round-off, 1e-13 relative); the mean weights sum to 1, and the mean of
    1 - cos(2 pi s / w), the cumulative impulse of an undamped ring of period w, is 1."""
    w = 0.01
    t, taper, mean = window_nodes(1.0, w)
    s = t - 1.0
    for j in range(9):
        exact = w ** (j + 1) * (1 / (j + 1) - 1 / (j + 2))
        assert taper @ s**j == pytest.approx(exact, rel=1e-13)
    assert mean.sum() == pytest.approx(1.0, rel=1e-14)
    assert mean @ (1 - np.cos(2 * math.pi * s / w)) == pytest.approx(1.0, rel=1e-12)


def test_a_latch_window_from_the_scene_is_used_and_bad_ones_are_refused():
    scene = two_rod_latch(1e7).with_(latches=(Latch(1, 0.0, window=0.004),))
    again = scene_from_dict(scene_to_dict(scene))
    assert again.latches[0].window == 0.004
    ev = simulate(again, "reduced").events[0]
    assert ev["impulse_window"] == 0.004
    for bad in (0.0, -1.0, math.nan, math.inf, "1"):
        with pytest.raises(ValueError, match="latch window must be"):
            Latch(1, 0.0, window=bad)


@pytest.mark.parametrize("name", ["full", "reduced"])
def test_the_stiff_damped_two_rod_lock_is_the_rigid_panel_impulse(name):
    """EI = 1e7, zeta = 0.1: the windowed impulse within 1 % of the rigid-panel impulse
    (measured +5e-4 full, +5e-6 reduced: the full model's lock acts on its end tangents, the
    rest of the impulse reaches the chords through the bending within the window); the
    momentum cross-check within 1e-4 of it (measured 1.8e-6 full, 5e-6 reduced: the gap of the
    reduced model's quasi-static hinge moment from its rigid chords' momentum, falling as
    1/EI); the angular momentum about the root through the lock to 1e-9 (the impact is
    internal: round-off of an O(n) solve, measured below 1e-14)."""
    ev = simulate(stiff_damped_latch(), name).events[0]
    assert ev["window_closed"]
    assert ev["impulse"] == pytest.approx(ev["rigid_impulse"], rel=1e-2)
    assert ev["impulse_momentum"] == pytest.approx(ev["impulse"], rel=1e-4)
    H = ev["angular_momentum_root_before"]
    assert abs(ev["angular_momentum_root_jump"]) <= 1e-9 * abs(H)


def test_the_native_models_agree_on_the_lock_impulse():
    """Full and reduced on the stiff damped scene: within 1 % (measured 5e-4)."""
    full, reduced = (simulate(stiff_damped_latch(), m).events[0] for m in ("full", "reduced"))
    assert full["impulse"] == pytest.approx(reduced["impulse"], rel=1e-2)
    # the full model's instantaneous part is its tangents' impact, a small part of the whole
    assert full["impulse_instant"] < 0.01 * full["impulse"]


def test_a_window_the_run_does_not_reach_is_flagged():
    scene = two_rod_latch(1e7).with_(latches=(Latch(1, 0.0, window=0.1),))
    ev = simulate(scene, "full").events[0]
    assert not ev["window_closed"]
    assert ev["t"] + ev["impulse_window"] > scene.t_end


@pytest.mark.exudyn
def test_exudyn_measures_the_same_impulse():
    """exudyn (2 elements per rod, h = 2.5e-5 s, spectral radius 0) on the stiff damped
    scene: within 1 % of its rigid-panel impulse and of the native models' (measured +0.34 %,
    +0.34 %; +1.8 % at h = 1e-4: the window holds 23 steps there, the gap falls with the
    step); the angular momentum about the root across the lock window to 1e-6 (measured
    2.9e-7: generalized-alpha's second-order error in the window's moment integral)."""
    pytest.importorskip("exudyn")
    scene = stiff_damped_latch()
    ex = simulate(scene, "exudyn", elements=2, step=2.5e-5, spectral_radius=0.0).events[0]
    reduced = simulate(scene, "reduced").events[0]
    assert ex["window_closed"]
    assert ex["impulse"] == pytest.approx(ex["rigid_impulse"], rel=1e-2)
    assert ex["impulse"] == pytest.approx(reduced["impulse"], rel=1e-2)
    H = ex["angular_momentum_root_before"]
    assert abs(ex["angular_momentum_root_jump"]) <= 1e-6 * abs(H)


@pytest.mark.slow
@pytest.mark.exudyn
def test_the_shipped_flexible_deployment_compares_like_with_like(tmp_path):
    """studies/deployment.toml (four panels, EI = 5e3; its reference exudyn at 8 elements per
    rod and 2.5e-5 s since issue 47, hinge 3's lock time to 0.16 ms by `rodval reference`):
    the first lock (hinge 3) compares like with like: the full model within 0.3 ms (measured
    -0.19 ms, about the reference's error bar) and 1 % in impulse (0.63 %), the reduced model
    within 1.2 ms (measured +1.07 ms: its quasi-static bending lags; it is out of its domain on
    this scene by its energy balance) and 10 % (5.4 %). (Against the earlier reference, exudyn
    at 4 elements and 1e-4 s, the reduced model's gap was 0.98 ms and a 1 ms bound held both.)
    The later locks the models reach in other states are marked not comparable, with the
    earlier lock's gap as the reason (reduced: hinge 3's 1.07 ms; full at hinge 1: hinge 2's
    1.41 ms), and the report says why."""
    pytest.importorskip("exudyn")
    from pathlib import Path

    from rodval.report.study_report import build_report, event_discrepancies, read_events
    from rodval.study import load_study, run_study

    study = Path(__file__).resolve().parents[1] / "studies" / "deployment.toml"
    out = tmp_path / "out"
    run_study(load_study(study), out, workers=1, progress=False)
    disc = event_discrepancies(read_events(out), "exudyn").set_index(["model", "label"])
    for model, dt, impulse in (("full", 3e-4, 0.01), ("reduced", 1.2e-3, 0.1)):
        first = disc.loc[(model, "latch hinge 3")]
        assert abs(first["dt"]) < dt
        assert first["impulse_rel"] < impulse
        assert first["not_comparable"] == ""
        assert disc.loc[(model, "latch hinge 1"), "not_comparable"] != ""
    assert "after latch hinge 3" in disc.loc[("reduced", "latch hinge 2"), "not_comparable"]
    assert "after latch hinge 2" in disc.loc[("full", "latch hinge 1"), "not_comparable"]
    assert "not_comparable" in build_report(out).read_text()


@pytest.mark.slow
@pytest.mark.exudyn
def test_stiff_damped_deployment_agrees_across_models_and_with_exudyn_refined(tmp_path):
    """studies/deployment_stiff.toml (the four-panel wing at EI = 1e7, bending damping 2500
    N m^2 s: zeta 0.34 / 0.16 / 0.09 on the segments the three locks complete), issue 19: lock
    times within 1 ms (measured <= 0.17 ms), windowed impulses within 2 % (measured <= 1.2 %,
    the reduced model's hinge 1) and final phi within 1e-2 rad (measured <= 3.5e-4) of the
    finest exudyn (8 elements per rod, 2.5e-5 s) for full, reduced and exudyn at 4 elements,
    1e-4 s; and each native
    model's impulse gap to exudyn falls at every lock as exudyn is refined (2, 4, 8 elements;
    measured e.g. full, hinge 3: 0.21, 0.079, 0.021 N m s)."""
    pytest.importorskip("exudyn")
    from pathlib import Path

    import pandas as pd

    from rodval.report.study_report import event_discrepancies, read_events
    from rodval.study import load_study, run_study

    study = Path(__file__).resolve().parents[1] / "studies" / "deployment_stiff.toml"
    out = tmp_path / "out"
    run_study(load_study(study), out, workers=1, progress=False)
    events = read_events(out)
    disc = event_discrepancies(events, "exudyn_fine").set_index(["model", "label"])
    labels = [f"latch hinge {k}" for k in (3, 2, 1)]
    for model in ("full", "reduced", "exudyn"):
        for label in labels:
            assert abs(disc.loc[(model, label), "dt"]) <= 1e-3
            assert disc.loc[(model, label), "impulse_rel"] <= 0.02
            assert disc.loc[(model, label), "not_comparable"] == ""
    final = pd.read_csv(out / "discrepancies.csv").query("quantity == 'phi'")
    assert (final["status"] == "ok").all() and len(final) == 4
    assert (final["final_abs"] <= 1e-2).all()
    impulse = events.set_index(["model", "label"])["impulse"]
    for native in ("full", "reduced"):
        for label in labels:
            gaps = [
                abs(impulse[(native, label)] - impulse[(ex, label)])
                for ex in ("exudyn_coarse", "exudyn", "exudyn_fine")
            ]
            assert gaps[0] > gaps[1] > gaps[2], (native, label, gaps)


def test_the_segment_window_not_the_pairs_makes_later_locks_agree():
    """Why the default window is the locked segment's period: at hinge 1 of the stiff damped
    wing (studies/deployment_stiff.toml) the lock completes the four-panel segment, which
    rings 3.8x lower than the pair (8.74 ms against 2.28 ms). Over the segment's period the
    native models' impulses agree within 1 % (measured 11.27 and 11.22 N m s, 0.4 %); over
    the pair's, most of the segment's ring stays in the mean and they part by more than 50 %
    (measured 10.09 and 19.25 N m s)."""
    from pathlib import Path

    from rodval import load_study

    study = Path(__file__).resolve().parents[1] / "studies" / "deployment_stiff.toml"
    scene = load_study(study).cases[0].scene
    pair = first_bending_period(scene.chain, 1)
    latches = tuple(
        dataclasses.replace(la, window=pair) if la.hinge == 1 else la for la in scene.latches
    )

    def hinge_1(sc, model):
        first = {"kinematics": "first-order"} if model == "full" else {}  # the measured rung
        return next(e for e in simulate(sc, model, **first).events if e["label"] == "latch hinge 1")

    segment = [hinge_1(scene, m) for m in ("full", "reduced")]
    assert segment[0]["impulse_window"] == pytest.approx(3.83 * pair, rel=1e-2)
    assert segment[1]["impulse"] == pytest.approx(segment[0]["impulse"], rel=1e-2)
    paired = [hinge_1(dataclasses.replace(scene, latches=latches), m) for m in ("full", "reduced")]
    assert abs(paired[1]["impulse"] / paired[0]["impulse"] - 1.0) > 0.5
