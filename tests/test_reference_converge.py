"""rodval reference (issue 47, "A converged reference with an error bar"): the exudyn reference
refined over levels until its quantities of interest settle, with the finest level's error bar
(rodval.analysis.convergence: observed order, Richardson where it shows)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rodval.analysis.convergence import (
    LAST_CHANGE,
    RICHARDSON,
    error_bar,
    estimate,
    estimates,
    finest_error,
    missing_quantity,
    observed_order,
    quantities_of_interest,
    successive_changes,
    unconverged,
    worst_error,
)
from rodval.cli import main

# ------------------------------------------------------------------ the analysis, synthetic


@pytest.mark.parametrize("levels", [3, 4, 5])
def test_a_second_order_sequence_gives_p_2_and_the_richardson_error(levels):
    """q_i = q* + C h_i**2 with h_i = h0 / 2**i: p = 2 and the finest error q_last - q*."""
    exact, C, h = 1.25, 3.0, 0.1 / 2.0 ** np.arange(levels)
    values = list(exact + C * h**2)
    error, p, method = finest_error(successive_changes(values))
    assert method == RICHARDSON
    assert p == pytest.approx(2.0, abs=1e-10)
    assert error == pytest.approx(abs(values[-1] - exact), abs=1e-10)


def test_an_array_quantity_changes_by_its_largest_component():
    h = 0.1 / 2.0 ** np.arange(3)
    values = [
        np.array([[1.0, 2.0], [3.0, 4.0]]) + c * np.array([[1.0, -3.0], [0.5, 2.0]]) for c in h**1
    ]
    found = estimate("phi_times", values)
    assert found.changes == pytest.approx((3 * 0.05, 3 * 0.025))
    assert found.order == pytest.approx(1.0)
    assert found.error == pytest.approx(3 * 0.025 / (2**1 - 1))
    assert found.unit == "rad"


@pytest.mark.parametrize(
    "changes",
    [
        [1e-3, -5e-4],  # oscillating: signs alternate
        [1e-3, 2e-3],  # growing
        [1e-3, 1e-3],  # not shrinking
        [1e-3, 0.0],  # vanished by chance
        [1.0, 1e-3],  # p = 10: a crossing, not a rate
        [0.1, 0.05, 0.0125],  # p = 1 then 2: ratios inconsistent
        [0.1],  # two levels: no ratio
    ],
)
def test_order_not_shown_falls_back_to_the_last_change(changes):
    assert observed_order(changes) is None
    error, p, method = finest_error(changes)
    assert (p, method) == (None, LAST_CHANGE)
    assert error == abs(changes[-1])


TIMES = np.array([0.0, 1.0])


def test_impulses_are_relative_to_the_finest_and_locks_matched_by_label_and_order():
    def level(t1, s1, t2):
        events = [
            {"t": t1, "label": "latch hinge 1", "impulse": s1},
            {"t": 0.5, "label": "stop hinge 2", "impulse": 9.0},  # not a lock
            {"t": t2, "label": "latch hinge 1", "impulse": 1.0},
        ]
        return quantities_of_interest(events, TIMES, np.array([[0.0, 0.1], [0.2, -0.4]]))

    levels = [level(0.30, -10.0, 0.80), level(0.34, -12.0, 0.84), level(0.35, -12.5, 0.85)]
    assert set(levels[0]) == {
        "lock_t[latch hinge 1#1]",
        "lock_impulse[latch hinge 1#1]",
        "lock_t[latch hinge 1#2]",
        "lock_impulse[latch hinge 1#2]",
        "phi_times",
        "phi_deployed[1]",
        "phi_deployed[2]",
    }
    found = {e.name: e for e in estimates(levels)}
    assert found["lock_impulse[latch hinge 1#1]"].changes == pytest.approx((-2 / 12.5, -0.5 / 12.5))
    assert found["lock_t[latch hinge 1#1]"].order == pytest.approx(2.0)
    assert found["lock_t[latch hinge 1#1]"].error == pytest.approx(0.01 / 3)
    assert found["phi_times"].error == 0.0
    bar = error_bar(list(found.values()), phi_scale=0.4)
    assert bar == pytest.approx({"rel": 0.0, "lock_dt": 0.01 / 3, "impulse_rel": 0.04 / 3})
    worst = unconverged(list(found.values()), tol=1e-3)
    assert worst is not None and worst.name == "lock_impulse[latch hinge 1#1]"
    assert unconverged(list(found.values()), tol=0.05) is None


def test_a_lock_one_level_misses_is_named():
    a = quantities_of_interest(
        [{"t": 0.3, "label": "latch hinge 1", "impulse": 1.0}], TIMES, np.zeros((2, 1))
    )
    b = quantities_of_interest([], TIMES, np.zeros((2, 1)))
    assert missing_quantity([a, b]) == "lock_t[latch hinge 1#1] (not at level 1)"
    assert missing_quantity([a, a]) is None


def test_the_error_bar_is_what_a_study_agreement_accepts():
    from rodval.study.case import agreement_spec

    bar = error_bar([estimate("lock_t[latch hinge 1#1]", [0.3, 0.31, 0.3125])], phi_scale=1.0)
    spec = agreement_spec({"reference_error": bar}, "study.toml")
    assert spec["reference_error"] == bar


# ------------------------------------------------------------------------------ the CLI

TINY = """\
n = 2
t_end = 0.1
times = { num = 11 }
outputs = ["phi"]

[chain]
l = 1.0
m = 3.0
EI = 1e4
mu = 0.5
kappa = [0.0, 50.0]
nu = 0.0

[initial]
phi = [0.0, 0.3]
dphi = [0.0, -10.0]

[[latches]]
hinge = 1
angle = 0.0
"""


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


@pytest.mark.exudyn
def test_the_cli_refines_records_every_level_and_the_error_bar(tiny, tmp_path, capsys):
    pytest.importorskip("exudyn")
    out = tmp_path / "ref"
    argv = ["reference", str(tiny), "--converge", "1e-3", "--out", str(out)]
    code = main([*argv, "--elements", "1", "--step", "4e-4", "--levels", "4"])
    printed = capsys.readouterr().out.splitlines()
    record = json.loads((out / "reference.json").read_text())
    table = (out / "levels.csv").read_text().splitlines()
    assert code == (0 if record["converged"] else 1)
    assert record["levels"] == len(table) - 1 >= 3
    assert [line.split(":")[0] for line in printed[: record["levels"]]] == [
        f"level {i}" for i in range(record["levels"])
    ]
    assert table[0].startswith("level,elements,step,wall_s,verdict,lock_t[latch hinge 1#1]")
    assert table[1].startswith("0,1,0.0004,") and table[2].startswith("1,2,0.0002,")
    finest = 2 ** (record["levels"] - 1)
    assert record["finest"] == {"elements": finest, "step": pytest.approx(4e-4 / finest)}
    assert set(record["reference_error"]) == {"rel", "lock_dt", "impulse_rel"}
    assert all(math.isfinite(v) and v >= 0 for v in record["reference_error"].values())
    lock = next(q for q in record["quantities"] if q["name"] == "lock_t[latch hinge 1#1]")
    assert record["reference_error"]["lock_dt"] == lock["error"] > 0
    assert printed[record["levels"]].startswith("error bar (")


@pytest.mark.parametrize(
    "option, value, message",
    [
        ("--converge", "0", "--converge must be a finite number > 0, got '0'"),
        ("--converge", "-1e-3", "--converge must be a finite number > 0, got '-1e-3'"),
        ("--levels", "2", "--levels must be an integer in [3, 8], got '2'"),
        ("--elements", "0", "--elements must be an integer in [1,"),
        ("--step", "nan", "--step must be a finite number > 0, got 'nan'"),
    ],
)
def test_bad_input_is_refused_in_one_line_before_any_work(
    tiny, tmp_path, capsys, option, value, message
):
    out = tmp_path / "ref"
    argv = ["reference", str(tiny), "--converge", "1e-3", "--out", str(out), option, value]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.exudyn
def test_a_level_the_model_refuses_is_named_before_any_level_runs(tiny, tmp_path, capsys):
    pytest.importorskip("exudyn")
    out = tmp_path / "ref"
    code = main(["reference", str(tiny), "--converge", "1e-3", "--out", str(out), "--step", "0.2"])
    err = capsys.readouterr()
    assert code == 2
    assert err.out == ""
    assert err.err.startswith("rodval reference: error: level 0 (elements ")
    assert len(err.err.strip().splitlines()) == 1
    assert not (out / "levels.csv").exists()


def test_the_deployed_state_is_the_mean_after_the_last_lock_not_the_vibrations_phase():
    """Two levels that ring about the same deployed angle 0.5 rad after a lock at 1 s, with a
    phase 1 rad apart: their final angles differ by up to 2 x 0.1 sin(0.5) ~ 0.096 rad, their
    deployed means over 0 .. 20 whole periods by round-off of the trapezoid sum (the mean of a
    sine over whole periods sampled 400 times a period: its trapezoid error is ~1e-15 rad)."""
    t = np.arange(8401) / 400.0  # 0 .. 21 s, 400 samples a period, 1 s on the grid
    omega = 2 * np.pi

    def level(phase):
        ring = np.where(t >= 1.0, 0.5 + 0.1 * np.sin(omega * (t - 1.0) + phase), 3.0 - 2.5 * t)
        events = [{"t": 1.0, "label": "latch hinge 1", "impulse": 2.0}]
        return quantities_of_interest(events, t, ring[:, None], attitude=0.01 * ring)

    a, b = level(0.0), level(1.0)
    assert abs(a["phi_times"][-1, 0] - b["phi_times"][-1, 0]) > 0.05
    assert a["phi_deployed[1]"] == pytest.approx(0.5, abs=1e-12)
    assert abs(a["phi_deployed[1]"] - b["phi_deployed[1]"]) < 1e-12
    assert a["attitude_deployed"] == pytest.approx(0.005, abs=1e-14)
    assert a["attitude_times"].shape == (t.size,)
    found = {e.name: e for e in estimates([a, b, b])}
    assert found["attitude_times"].unit == found["attitude_deployed"].unit == "rad"
    bar = error_bar(list(found.values()), phi_scale=3.0)
    assert bar["rel"] == 0.0  # the finest two levels agree: last change 0, no order
    assert worst_error(list(found.values()), "attitude") == 0.0
    assert worst_error(list(found.values()), "nothing") == 0.0


def test_without_a_lock_the_deployed_state_is_the_whole_horizons_mean():
    t = np.linspace(0.0, 2.0, 5)
    q = quantities_of_interest([], t, np.array([[0.0], [1.0], [2.0], [3.0], [4.0]]))
    assert q["phi_deployed[1]"] == pytest.approx(2.0)
    assert "attitude_times" not in q
