"""The full model's default kinematics (issue 47, "Valid defaults"): ``kinematics = "auto"``
runs the exact kinematics where the scene has latches (held ones included), stops or a moving
base, and the paper's first-order kinematics otherwise (``auto_kinematics``, the one rule);
the run records the kinematics that ran and says in a note that "auto" chose it and why."""

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scenes import latch3_toml

from rodval.cli import main
from rodval.core.base import Base
from rodval.core.hinges import Latch, Stop
from rodval.core.motion import Motion
from rodval.core.scene import InitialState, paper_scene
from rodval.core.validity import MOMENTUM_RESIDUAL_BOUND
from rodval.models import simulate
from rodval.models.kinematics.rungs import auto_kinematics
from rodval.models.presets.full import FullModel
from rodval.models.registry import model_class
from rodval.report.error_budget import error_budget, has_ladder
from rodval.report.run_files import read_run

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from exudyn_speed import latch3_scene, wing_scene  # noqa: E402
from momentum_audit import BODY  # noqa: E402

CHOSEN = 'kinematics "exact" chosen by kinematics = "auto"'
PAPER = 'kinematics = "first-order" (command line: --set kinematics=first-order)'


def stopped_scene():
    """latch3 with one-sided stops (1e5 N m/rad) at 0 in place of its latches."""
    scene = latch3_scene()
    stops = (Stop(1, 0.0, "lower", 1e5), Stop(2, 0.0, "upper", 1e5))
    return scene.with_(latches=(), stops=stops)


def test_the_paper_example_keeps_the_papers_model_bit_for_bit():
    """The paper example (no latches, stops or moving base): "auto" runs the first-order
    kinematics, every array equal to an explicit first-order run's, and says so."""
    scene = paper_scene(8).with_(t_end=0.5, times=np.linspace(0.0, 0.5, 26))
    auto = simulate(scene, "full")
    given = simulate(scene, "full", kinematics="first-order")
    assert auto.options["kinematics"] == "first-order"
    assert set(auto.values) == set(given.values)
    for quantity, values in auto.values.items():
        assert np.array_equal(values, given.values[quantity]), quantity
    assert auto.stats.notes == [
        'kinematics "first-order" (the paper\'s) chosen by kinematics = "auto": the scene '
        "has no latches, stops or moving base"
    ]
    assert given.stats.notes == []


@pytest.mark.parametrize(
    "scene, has",
    [
        (latch3_scene(), "the scene has latches ("),
        (latch3_scene().with_(base=BODY), "the scene has latches and a free base ("),
    ],
    ids=["latch3 pinned", "latch3 on the 800 kg body"],
)
def test_a_latched_scene_runs_exact_and_is_valid_where_first_order_is_not(scene, has):
    """latch3 (benchmarks/exudyn_speed.py) pinned and on the 800 kg body of
    benchmarks/momentum_audit.py: under "auto" the exact kinematics runs, recorded, its
    momentum residual within bound (valid); the explicit first-order run is INVALID by it
    (0.071 and 0.052 measured)."""
    auto = simulate(scene, "full")
    first = simulate(scene, "full", kinematics="first-order")
    assert auto.options["kinematics"] == "exact"
    assert auto.stats.valid is True
    assert auto.stats.momentum_residual < MOMENTUM_RESIDUAL_BOUND
    assert first.options["kinematics"] == "first-order"
    assert first.stats.valid is False
    assert first.stats.momentum_residual > MOMENTUM_RESIDUAL_BOUND
    (note,) = auto.stats.notes
    assert (
        note.startswith(CHOSEN) and has in note and note.endswith(f"{PAPER} for the paper's model")
    )
    assert first.stats.notes == []


def test_a_stopped_scene_runs_exact():
    """Stops in place of latch3's latches: "auto" runs the exact kinematics, which keeps the
    angular momentum to round-off where the first-order one drifts by 3.6e-3."""
    auto = simulate(stopped_scene(), "full")
    first = simulate(stopped_scene(), "full", kinematics="first-order")
    assert auto.options["kinematics"] == "exact"
    assert auto.stats.valid is True
    assert auto.stats.momentum_residual < 1e-8 < 1e-3 < first.stats.momentum_residual
    assert "the scene has stops (" in auto.stats.notes[0]


def test_the_rule_on_held_latches_and_moving_bases():
    """Held latches, a free and a prescribed base make "auto" exact (no run needed: the one
    rule, ``auto_kinematics``); a plain scene stays first-order."""
    wing = wing_scene(0.1)
    held = wing.with_(
        initial=InitialState(phi=[0.0] * 6),
        latches=tuple(Latch(k, 0.0, held=True) for k in range(1, 6)),
    )
    spin = Base(kind="prescribed", motion={"attitude": Motion("linear", (0.0, 1.0))})
    plain = paper_scene(4)
    assert auto_kinematics(held)[0] == "exact"
    assert auto_kinematics(plain.with_(base=BODY))[0] == "exact"
    assert "a prescribed base" in auto_kinematics(plain.with_(base=spin))[1]
    assert auto_kinematics(plain.with_(base=spin))[0] == "exact"
    assert auto_kinematics(plain)[0] == "first-order"
    assert FullModel().system(held).__class__.__name__ == "LadderSystem"


def test_explicit_kinematics_is_honoured():
    """An explicit kinematics runs as given, with no note of "auto"."""
    paper = paper_scene(4).with_(t_end=0.1, times=np.linspace(0.0, 0.1, 3))
    exact = simulate(paper, "full", kinematics="exact")
    first = simulate(latch3_scene(), "full", kinematics="first-order")
    assert exact.options["kinematics"] == "exact" and exact.stats.notes == []
    assert first.options["kinematics"] == "first-order" and first.stats.notes == []
    assert FullModel(kinematics="first-order").for_scene(latch3_scene())[1] == []


@pytest.mark.parametrize(
    "option, text",
    [
        ({"coefficients": "published"}, 'coefficients = "published" (command line: --set '),
        ({"kernel": "numpy"}, 'kernel = "numpy" (command line: --set kernel=numpy)'),
    ],
)
def test_options_of_the_papers_rung_keep_first_order_and_say_so(option, text):
    """The published coefficients or the numpy kernel run on the paper's rung only: "auto"
    keeps first-order on a latched scene (the user's option wins), and the note says so."""
    run = simulate(latch3_scene(), "full", **option)
    assert run.options["kinematics"] == "first-order"
    assert run.stats.valid is False  # the first-order balance at the locks, as given
    (note,) = run.stats.notes
    assert note.startswith('kinematics "first-order" kept by kinematics = "auto" although')
    assert text in note and 'kinematics = "exact" (command line' in note


def test_modes_accept_auto():
    """Modes take ``kinematics = "auto"``, resolved by the same rule: exact on held latches
    (pinned and on a free body), first-order on a plain chain; the same frequencies as the
    explicit rung's."""
    wing = wing_scene(0.1)
    held = wing.with_(
        initial=InitialState(phi=[0.0] * 6),
        latches=tuple(Latch(k, 0.0, held=True) for k in range(1, 6)),
    )
    full = model_class("full")
    for scene in (held, held.with_(base=BODY)):
        auto = full.modes(scene, kinematics="auto", count=4)
        exact = full.modes(scene, kinematics="exact", count=4)
        assert auto.info["kinematics"] == "exact"
        assert np.array_equal(auto.omega, exact.omega)
    plain = full.modes(paper_scene(4), kinematics="auto", count=2)
    assert plain.info["kinematics"] == "first-order"


LATCH3 = latch3_toml()


def test_run_json_records_the_kinematics_that_ran_and_a_rerun_reproduces(tmp_path, capsys):
    """``rodval simulate`` on the latched scene file: run.json holds kinematics "exact" and
    the note (printed too); rerunning run.json runs the same model, the same arrays."""
    scene = tmp_path / "latch3.toml"
    scene.write_text(LATCH3)
    assert main(["simulate", str(scene), "--model", "full", "--out", str(tmp_path / "a")]) == 0
    assert CHOSEN in capsys.readouterr().out
    record = json.loads((tmp_path / "a" / "run.json").read_text())
    assert record["options"]["kinematics"] == "exact"
    assert record["stats"]["notes"][0].startswith(CHOSEN)
    again = tmp_path / "b"
    assert main(["simulate", str(tmp_path / "a" / "run.json"), "--out", str(again)]) == 0
    first, second = read_run(tmp_path / "a"), read_run(again)
    assert second.options["kinematics"] == "exact"
    assert np.array_equal(first["phi"], second["phi"])


def test_the_error_budget_reads_the_kinematics_each_run_ran_with():
    """A study whose "paper" model leaves kinematics to "auto": its rung is the one its runs
    recorded (runtime.csv's options), not a guess; without the record it is no rung."""
    meta = {
        "reference": "exudyn",
        "models": [
            {"label": "paper", "model": "full", "options": {}},
            {"label": "exact1", "model": "full", "options": {"kinematics": "exact"}},
            {"label": "exact2", "model": "full", "options": {"kinematics": "exact", "shapes": 2}},
        ],
        "labels": {},
        "axes": {},
        "cases": [{"id": "base", "params": {}}],
    }
    disc = pd.DataFrame(
        [
            {"case": "base", "n": 2, "horizon": 1.0, "model": m, "reference": "exudyn"}
            | {"quantity": "phi", "max_abs": g, "status": "ok"}
            for m, g in (("paper", 0.75), ("exact1", 0.25), ("exact2", 0.125))
        ]
    )
    ran = {
        "paper": {"kinematics": "first-order", "shapes": 1},
        "exact1": {"kinematics": "exact", "shapes": 1},
        "exact2": {"kinematics": "exact", "shapes": 2},
    }
    runtime = pd.DataFrame(
        [{"case": "base", "model": m, "options": json.dumps(o)} for m, o in ran.items()]
    )
    assert not has_ladder(meta) and error_budget(disc, meta) is None
    assert has_ladder(meta, runtime)
    split = error_budget(disc, meta, runtime)
    assert split is not None and split.iloc[0]["kinematics"] == 0.5
    # a latched case where "auto" ran exact: two exact p = 1 runs, no first-order rung
    ran["paper"] = {"kinematics": "exact", "shapes": 1}
    runtime["options"] = [json.dumps(o) for o in ran.values()]
    assert error_budget(disc, meta, runtime) is None


def test_a_study_case_fingerprints_the_kinematics_auto_resolves_to():
    """A study folder made when the full model's default was first-order must not reuse its
    records for [models.full] without kinematics: the case's fingerprint holds the options
    each model runs with, "auto" resolved (exact on a latched scene, first-order on the
    paper's)."""
    import dataclasses

    from rodval.study.spec import StudySpec

    doc = {
        "study": {"name": "k", "reference": "full"},
        "scene": {"based_on": "paper", "n": 2, "t_end": 0.1},
        "models": {"full": {}},
        "grid": {"scene.latches": [[], [{"hinge": 1, "angle": 0.5}]]},
    }
    plain, latched = StudySpec.from_dict(doc, name="k").cases
    assert plain.ran_options["full"]["kinematics"] == "first-order"
    assert latched.ran_options["full"]["kinematics"] == "exact"
    first_order = {"full": {**latched.ran_options["full"], "kinematics": "first-order"}}
    assert dataclasses.replace(latched, ran_options=first_order).fingerprint != latched.fingerprint
