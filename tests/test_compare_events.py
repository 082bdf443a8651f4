"""Lock events in `rodval compare` and the lock records that say when they mean nothing
(issue 37): the side-by-side lock table (printed, events.csv, events.md), overlapping lock
windows and under-resolved exudyn windows marked not comparable, the root's angular momentum
jump blank once hinge 0 is held."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest
from scenes import latch3_toml

from rodval.analysis.events import MIN_WINDOW_STEPS, event_discrepancies, events_frame
from rodval.cli import main
from rodval.report.markdown import to_markdown

# the three-rod latched deployment (benchmarks/exudyn_speed.py latch3_scene)
LATCH3 = latch3_toml(latches=())
LATCHES = latch3_toml(latches=(1, 2))[len(LATCH3) :]
# two rods whose root hinge latches too (after hinge 1): its record's root jump means nothing
ROOT = """
n = 2
t_end = 0.6
times = { num = 31 }
outputs = ["phi"]

[chain]
l = 1.5
m = 3.0
EI = 1e5
mu = 0.5
kappa = [400.0, 50.0]
nu = 0.0
rest_angle = 0.0

[initial]
phi = [-0.5, 0.5]

[[latches]]
hinge = 0
angle = 0.0

[[latches]]
hinge = 1
angle = 0.0
"""


def _simulate(tmp_path, text: str, model: str, name: str, *extra: str):
    scene = tmp_path / f"{name}.toml"
    scene.write_text(text)
    out = tmp_path / name
    assert main(["simulate", str(scene), "--model", model, "--out", str(out), *extra]) == 0
    return out


COLUMNS = [
    "label",
    "t_A",
    "t_B",
    "dt",
    "impulse_A",
    "impulse_B",
    "impulse_rel",
    "impulse_to_rigid_A",
    "impulse_to_rigid_B",
    "not_comparable",
]


def test_compare_prints_and_writes_the_lock_table(tmp_path, capsys):
    a = _simulate(tmp_path, LATCH3 + LATCHES, "full", "A")
    b = _simulate(tmp_path, LATCH3 + LATCHES, "reduced", "B")
    capsys.readouterr()
    out = tmp_path / "cmp"
    assert main(["compare", str(a), str(b), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "Locks: A = " in printed and printed.index("Locks") > printed.index("quantity")
    header = next(x for x in printed.splitlines() if x.split()[:2] == ["label", "t_A"])
    assert header.split() == COLUMNS
    table = pd.read_csv(out / "events.csv")
    assert list(table.columns) == COLUMNS
    assert (out / "events.md").read_text().count("latch hinge") == 2
    ev_a = {e["label"]: e for e in json.loads((a / "run.json").read_text())["events"]}
    ev_b = {e["label"]: e for e in json.loads((b / "run.json").read_text())["events"]}
    assert sorted(table["label"]) == sorted(ev_a) == ["latch hinge 1", "latch hinge 2"]
    for _, row in table.iterrows():
        ea, eb = ev_a[row["label"]], ev_b[row["label"]]
        assert row["dt"] == pytest.approx(ea["t"] - eb["t"], abs=1e-15)
        assert row["impulse_A"] == pytest.approx(ea["impulse"])
        assert row["impulse_rel"] == pytest.approx(
            abs(ea["impulse"] - eb["impulse"]) / abs(eb["impulse"])
        )
        assert row["impulse_to_rigid_B"] == pytest.approx(eb["impulse"] / eb["rigid_impulse"])
        assert f"{row['dt']:.6g}" in printed


def test_compare_lists_a_lock_only_one_run_has_and_no_lock_table_without_locks(tmp_path, capsys):
    a = _simulate(tmp_path, LATCH3 + LATCHES, "reduced", "A")
    b = _simulate(tmp_path, LATCH3 + LATCHES.split("\n\n")[0], "reduced", "B")  # hinge 1 only
    plain = _simulate(tmp_path, LATCH3, "reduced", "plain")
    capsys.readouterr()
    out = tmp_path / "cmp"
    args = ["--allow-different-scenes"]
    assert main(["compare", str(a), str(b), "--out", str(out), *args]) == 0
    table = pd.read_csv(out / "events.csv").set_index("label")
    assert table.loc["latch hinge 2", "not_comparable"] == "only in A (the other run did not lock)"
    assert math.isnan(table.loc["latch hinge 2", "t_B"])
    capsys.readouterr()
    assert main(["compare", str(plain), str(plain), "--out", str(tmp_path / "none")]) == 0
    assert "Locks" not in capsys.readouterr().out
    assert not (tmp_path / "none" / "events.csv").exists()


def _frame(model_events, ref_events):
    return events_frame(
        [({"case": "c", "model": "m"}, model_events), ({"case": "c", "model": "ref"}, ref_events)]
    )


def _ev(t, label, **kw):
    return {
        "t": t,
        "label": label,
        "impulse": 1.0,
        "impulse_window": 0.01,
        "kinetic_before": 10.0,
        **kw,
    }


@pytest.mark.parametrize("side", ["model", "reference"])
def test_a_lock_whose_window_overlaps_another_lock_is_not_comparable(side):
    apart = [_ev(0.1, "latch hinge 1"), _ev(0.3, "latch hinge 2")]
    close = [_ev(0.1, "latch hinge 1"), _ev(0.105, "latch hinge 2")]
    events = _frame(close, apart) if side == "model" else _frame(apart, close)
    why = event_discrepancies(events, "ref").set_index("label")["not_comparable"]
    who = "its" if side == "model" else "the reference's"
    assert why["latch hinge 1"] == (
        f"{who} window overlaps the lock of latch hinge 2 at t = 0.105 s (the impulses are not separable)"
    )
    # the later lock lies inside the earlier's window
    assert why["latch hinge 2"].startswith(
        f"{who} window overlaps the lock of latch hinge 1 at t = 0.1 s"
    )
    assert event_discrepancies(_frame(apart, apart), "ref")["not_comparable"].tolist() == ["", ""]


def test_an_exudyn_window_of_too_few_steps_is_not_comparable():
    native = [_ev(0.1, "latch hinge 1")]
    coarse = [_ev(0.1, "latch hinge 1", window_steps=MIN_WINDOW_STEPS - 8)]
    fine = [_ev(0.1, "latch hinge 1", window_steps=MIN_WINDOW_STEPS + 1)]
    why = event_discrepancies(_frame(native, coarse), "ref")["not_comparable"].iloc[0]
    assert why == "the reference's exudyn's window holds 12 steps (< 20); refine its step"
    why = event_discrepancies(_frame(coarse, native), "ref")["not_comparable"].iloc[0]
    assert why == "exudyn's window holds 12 steps (< 20); refine its step"
    assert event_discrepancies(_frame(native, fine), "ref")["not_comparable"].iloc[0] == ""


@pytest.mark.parametrize("side", ["model", "reference"])
def test_a_lock_without_a_finite_impulse_says_why_its_cells_are_blank(side):
    """Issue 46: a NaN impulse in an (edited) run.json went into events.csv as blank cells
    with an empty not_comparable; the row now says why."""
    good = [_ev(0.1, "latch hinge 1")]
    bad = [_ev(0.1, "latch hinge 1", impulse=math.nan)]
    events = _frame(bad, good) if side == "model" else _frame(good, bad)
    row = event_discrepancies(events, "ref").iloc[0]
    assert math.isnan(row["impulse_rel"])
    who = "its" if side == "model" else "the reference's"
    assert (
        row["not_comparable"] == f"{who} record has no finite lock impulse (a damaged run record)"
    )


def test_the_root_jump_is_blank_once_hinge_0_is_held(tmp_path):
    run = _simulate(tmp_path, ROOT, "full", "R")
    events = json.loads((run / "run.json").read_text())["events"]
    assert [e["label"] for e in events] == ["latch hinge 1", "latch hinge 0"]
    free, held = events
    assert abs(free["angular_momentum_root_jump"]) <= 1e-9 * abs(
        free["angular_momentum_root_before"]
    )
    for key in ("before", "after", "jump"):
        assert held[f"angular_momentum_root_{key}"] is None
    # the report's table shows a blank there, not a number
    from rodval.report.study_report import _blanks

    frame = events_frame([({"case": "c", "model": "full"}, events)])
    frame.to_csv(tmp_path / "events.csv", index=False)
    back = pd.read_csv(tmp_path / "events.csv")[["label", "angular_momentum_root_jump"]]
    md = to_markdown(_blanks(back), ".5g").splitlines()
    row = next(x for x in md if "latch hinge 0" in x)
    assert row.replace(" ", "").endswith("|latchhinge0||")


@pytest.mark.exudyn
def test_exudyn_records_window_steps_and_a_blank_root_jump_once_hinge_0_is_held(tmp_path):
    run = _simulate(tmp_path, ROOT, "exudyn", "X", "--set", "step=1e-3")
    events = json.loads((run / "run.json").read_text())["events"]
    labels = [e["label"] for e in events]
    assert labels == ["latch hinge 1", "latch hinge 0"]
    for ev in events:
        assert ev["window_steps"] == pytest.approx(ev["impulse_window"] / 1e-3)
    assert events[0]["angular_momentum_root_jump"] is not None
    assert all(events[1][f"angular_momentum_root_{k}"] is None for k in ("before", "after", "jump"))
