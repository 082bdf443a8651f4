"""A user's own scene: the fastest valid method by default, load laws with compiled forms,
traceable runs (rerun from run.json bit for bit), --t-end that keeps the scene's times, and
refusals that list what is allowed."""

import json
import math

import numpy as np
import pandas as pd
import pytest

from rodval import (
    Chain,
    Latch,
    NodalForce,
    Scene,
    constant,
    harmonic,
    paper_scene,
    pulse,
    ramp,
    simulate,
    tabulated,
)
from rodval.cli import main
from rodval.core.load_table import load_sums, load_table
from rodval.core.loads import LoadSet
from rodval.core.scene_file import scene_from_dict, scene_to_dict

BOOM = """
based_on = "paper"
name = "boom"
n = 5
t_end = 0.4
times = [0.1, 0.25, 0.4]

[chain]
l = [1.0, 1.5, 2.0, 1.2, 0.8]
EI = 1e5
mu = [0.5, 0.5, 1.0, 0.5, 2.0]
kappa = [100.0, 5000.0, 100.0, 100.0, 100.0]

[[loads]]
type = "constant"
node = 5
Y = 50.0
"""


@pytest.fixture()
def boom(tmp_path):
    path = tmp_path / "boom.toml"
    path.write_text(BOOM)
    return path


def test_auto_takes_the_compiled_integrator_and_records_it():
    scene = paper_scene(3, t_end=0.3, times=[0.3])
    auto = simulate(scene, "reduced")
    assert auto.settings["method"] == "DOP853-numba" and auto.settings["requested_method"] == "auto"
    explicit = simulate(scene, "reduced", method="DOP853-numba")
    np.testing.assert_array_equal(auto["phi"], explicit["phi"])
    # a plain Python callable has no compiled form: scipy's DOP853 runs, and says so
    callable_load = scene.with_(loads=(NodalForce(3, fy=math.cos),))
    assert simulate(callable_load, "reduced").settings["method"] == "DOP853"
    # the energy audit and events run inside the compiled loop (tests/test_compiled_audit.py,
    # tests/test_compiled_events.py: the same W, D and events as scipy's)
    audited = simulate(scene.with_(outputs=("phi", "energy")), "reduced")
    assert audited.settings["method"] == "DOP853-numba"
    latched = scene.with_(latches=(Latch(1, 0.5),))
    assert simulate(latched, "reduced").settings["method"] == "DOP853-numba"


@pytest.mark.parametrize(
    "make",
    [
        lambda: ramp(2, X=3.0, Y=-7.0, t_on=0.1, t_full=0.4, t_off=0.9),
        lambda: harmonic(3, X=2.0, Y=5.0, omega=7.0, phase=0.3, t_on=0.05, t_off=0.8),
        lambda: tabulated(
            1, t=[0.0, 0.2, 0.5, 0.7], X=[0.0, 4.0, -2.0, 1.0], Y=[1.0, 1.0, 3.0, 0.0]
        ),
        lambda: pulse(3, Xbar=-15.0, Ybar=120.0, T=0.6),
        lambda: constant(2, X=7.0, Y=-3.0, t_on=0.25, t_off=0.6),
    ],
)
def test_compiled_rows_equal_the_closed_forms(make):
    """Every load law's compiled rows evaluate to its closed form, including at its kinks."""
    f = make()
    loads = (f,)
    table = load_table(loads)
    ref_set = LoadSet(loads, 3)
    times = np.concatenate([np.linspace(0, 1.2, 97), f.breakpoints, [f.support[0]]])
    for t in times:
        SX, SY = np.zeros(3), np.zeros(3)
        active = load_sums(table, t, SX, SY)
        ref = ref_set.suffix_sums(t)
        if ref is None:
            assert not active or (np.all(SX == 0) and np.all(SY == 0)), t
            continue
        np.testing.assert_allclose(SX, ref[0], rtol=1e-14, atol=1e-12, err_msg=str(t))
        np.testing.assert_allclose(SY, ref[1], rtol=1e-14, atol=1e-12, err_msg=str(t))


def test_compiled_and_scipy_runs_agree_for_every_load_law():
    loads = (
        ramp(3, Y=40.0, t_on=0.0, t_full=0.2),
        harmonic(2, X=5.0, omega=9.0),
        tabulated(3, t=[0.0, 0.1, 0.3], X=[0.0, 10.0, 0.0]),
    )
    scene = Scene(chain=Chain.uniform(3), loads=loads, t_end=0.4, times=[0.1, 0.2, 0.4])
    assert set(scene.breakpoints) >= {0.1, 0.2, 0.3}
    fast = simulate(scene, "reduced", method="DOP853-numba", rtol=1e-10, atol=1e-12)
    slow = simulate(scene, "reduced", method="DOP853", rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(fast["phi"], slow["phi"], rtol=0, atol=1e-11)


def test_tabulated_history_from_a_csv_file_in_a_scene_file(tmp_path):
    (tmp_path / "force.csv").write_text("t,Y\n0,0\n0.1,20\n0.3,20\n0.35,0\n")
    scene = scene_from_dict(
        {
            "based_on": "paper",
            "n": 2,
            "t_end": 0.4,
            "loads": [{"type": "tabulated", "node": 2, "file": str(tmp_path / "force.csv")}],
        }
    )
    f = scene.loads[0]
    assert f.fy(0.05) == pytest.approx(10.0) and f.fx is None
    assert tuple(scene.breakpoints) == (0.1, 0.3, 0.35)
    assert simulate(scene, "full").success
    (tmp_path / "bad.csv").write_text("time,Y\n0,0\n")
    with pytest.raises(ValueError, match="name the columns t, X, Y"):
        scene_from_dict(
            {
                "based_on": "paper",
                "n": 2,
                "loads": [{"type": "tabulated", "node": 2, "file": str(tmp_path / "bad.csv")}],
            }
        )


def test_a_run_rebuilt_from_its_run_json_reproduces_it_bit_for_bit(boom, tmp_path, capsys):
    assert main(["simulate", str(boom), "--model", "full", "--out", str(tmp_path / "a")]) == 0
    record = json.loads((tmp_path / "a" / "run.json").read_text())
    assert record["scene"]["chain"]["kappa"] == [100.0, 5000.0, 100.0, 100.0, 100.0]
    assert record["scene"]["loads"] == [
        {"type": "constant", "node": 5, "X": 0.0, "Y": 50.0, "t_on": 0.0, "t_off": math.inf}
    ]
    assert record["settings"]["method"] == "DOP853-numba"
    assert main(["simulate", str(tmp_path / "a" / "run.json"), "--out", str(tmp_path / "b")]) == 0
    a = (tmp_path / "a" / "trajectory.csv").read_bytes()
    assert a == (tmp_path / "b" / "trajectory.csv").read_bytes()


def test_resolved_scene_round_trip_is_exact():
    scene = paper_scene(4, times=np.linspace(0, 2, 7)).with_(
        chain=Chain(
            l=[1.0, 2.0, 0.5, 1.5],
            m=[3.0, 1.0, 2.0, 4.0],
            EI=1e4,
            mu=[0, 1, 2, 3],
            kappa=[0.0, 10.0, 20.0, 30.0],
            nu=0.1,
            rest_angle=[0.0, 0.1, -0.2, 0.3],
        )
    )
    again = scene_from_dict(json.loads(json.dumps(scene_to_dict(scene))))
    assert again.chain == scene.chain and np.array_equal(again.times, scene.times)
    assert again.loads[0].params == scene.loads[0].params and again.t_end == scene.t_end


def test_t_end_keeps_the_scenes_own_times(boom, tmp_path):
    assert main(["simulate", str(boom), "--t-end", "0.3", "--out", str(tmp_path / "c")]) == 0
    frame = pd.read_csv(tmp_path / "c" / "trajectory.csv")
    assert sorted(frame["t"].unique()) == [0.1, 0.25]


def test_t_end_before_every_output_time_is_refused(boom, tmp_path, capsys):
    assert main(["simulate", str(boom), "--t-end", "0.05", "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--t-end" in err[0] and "output times" in err[0]


def test_default_output_times_have_no_float_noise():
    times = paper_scene(t_end=2.0).times
    assert [repr(float(t)) for t in times[:4]] == ["0.0", "0.01", "0.02", "0.03"]
    assert repr(float(times[35])) == "0.35" and times[-1] == 2.0


@pytest.mark.parametrize(
    "args, words",
    [
        (["--model", "exudyn", "--method", "Radau"], "method"),
        (["--model", "exudyn", "--rtol", "1e-3"], "rtol"),
        (["--model", "exudyn", "--set", "stepsize=1e-3"], "allowed: elements, step"),
        (["--model", "full", "--set", "speed=3"], "allowed: coefficients, kernel"),
    ],
)
def test_options_a_model_cannot_honour_are_refused(args, words, tmp_path, capsys):
    pytest.importorskip("exudyn")
    code = main(["simulate", "paper", *args, "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (tmp_path / "x").exists()


def test_compare_two_runs(boom, tmp_path, capsys):
    for model in ("full", "reduced"):
        assert main(["simulate", str(boom), "--model", model, "--out", str(tmp_path / model)]) == 0
    assert (
        main(
            [
                "compare",
                str(tmp_path / "reduced"),
                str(tmp_path / "full"),
                "--out",
                str(tmp_path / "cmp"),
            ]
        )
        == 0
    )
    table = pd.read_csv(tmp_path / "cmp" / "discrepancies.csv")
    assert list(table["quantity"]) == ["phi", "dphi", "alpha", "beta"]
    assert (table["max_abs"] < 1e-2).all() and (table["max_abs"] > 0).all()
    assert (tmp_path / "cmp" / "histories.png").stat().st_size > 10_000


def test_runs_report_whether_they_stayed_within_small_bending():
    """Both models rest on small bending angles: every run reports its largest |alpha|,
    |beta| and whether it stayed within SMALL_BENDING_RAD, also when alpha, beta were not
    asked for. At EI = 1e-3 the reduced model returns bending angles of ~1e4 rad: flagged."""
    from rodval.core.validity import SMALL_BENDING_RAD

    scene = paper_scene(times=[0.5, 1.0], outputs=("phi",))
    for model in ("full", "reduced"):
        ok = simulate(scene, model)
        assert ok.stats.small_bending is True and 0 < ok.stats.max_bending < 0.01
    soft = simulate(paper_scene(times=[0.5, 1.0], outputs=("phi",), EI=1e-3), "reduced")
    assert soft.stats.small_bending is False and soft.stats.max_bending > 100 * SMALL_BENDING_RAD
    asked = simulate(paper_scene(times=[0.5, 1.0]), "reduced")
    assert asked.stats.max_bending == pytest.approx(
        max(np.abs(asked["alpha"]).max(), np.abs(asked["beta"]).max())
    )


def test_dense_paths_are_refused_above_the_memory_limit():
    with pytest.raises(ValueError, match="dense matrices.*RODVAL_MAX_MEMORY_GB"):
        simulate(paper_scene(20000, times=[1.0]), "full", method="Radau")
