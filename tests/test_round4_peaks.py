"""Peaks and gates (issue 54, and issue 56's "peaks between outputs"): a peak is the run's, read
between its output times (the native models on their dense output, exudyn on every recorded
step), recorded with its time in ``SolverStats.peaks`` and runtime.csv, and read by the
report's peak table and the acceptance gate; a requirement on a run that did not reach t_end
breaks, and so does a peak gate on a hinge moment that is an impulse at its lock (the rigid
and reduced chords' plastic lock), saying why; a lock time past the horizon is refused when
the study is read; every setting that changes what ran is in runtime.csv and in the
report's Models table.

Each test failed on the code as found (no ``SolverStats.peaks``, the gate read the output
times, a stopped run passed, a lock time past t_end was accepted, runtime.csv had no
error_control) and passes now."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from scenes import two_rod_latch

from rodval import Study, simulate
from rodval.report.acceptance import acceptance_checks, breach_lines, gate
from rodval.study import run_study

#: The scene's outputs: every peak quantity the native models give.
PEAK_OUTPUTS = ("phi", "hinge_moment", "alpha", "beta", "tip_deflection")


def _run(model: str, num: int, **keywords):
    """two_rod_latch(1e5) (the lock at 0.404 s, its window 22.8 ms) with ``num`` output
    times."""
    base = two_rod_latch(1e5)
    scene = base.with_(times=np.linspace(0.0, base.t_end, num), outputs=PEAK_OUTPUTS)
    return simulate(scene, model, **keywords)


def _peaks(traj) -> dict[tuple[str, int], dict]:
    return {(q, e["k"]): e for q, rows in traj.stats.peaks["values"].items() for e in rows}


def test_the_full_models_peak_is_the_runs_whatever_its_output_times():
    """11 output times miss the lock's moment (4923 N m at t = 0.42 s against 6767 N m at
    2001): the recorded peak is the same at both, 6775 N m at 0.4098 s, above both grids'."""
    coarse, fine = _run("full", 11), _run("full", 2001)
    assert coarse.success and fine.success
    a, b = _peaks(coarse), _peaks(fine)
    assert a.keys() == b.keys() and ("tip_deflection", 0) in a and ("alpha", 2) in a
    for key in a:
        # the same steps and the same dense-output times in both runs: equal to round-off;
        # 1e-6 relative is the bound
        assert a[key]["peak"] == pytest.approx(b[key]["peak"], rel=1e-6, abs=1e-12), key
        assert a[key]["t"] == pytest.approx(b[key]["t"], abs=1e-12), key
    peak = a[("hinge_moment", 1)]
    grid = [float(np.max(np.abs(t["hinge_moment"][:, 1]))) for t in (coarse, fine)]
    assert grid[0] < 5000.0 < grid[1] < peak["peak"]
    assert 0.4040 < peak["t"] < 0.4040 + 0.0228  # inside the lock's window


def test_a_rigid_lock_reports_its_impulse_never_a_finite_peak():
    """The rigid (and the reduced model's) chords lock plastically: the hinge moment at the
    lock is an impulse; the run records it (N m s, at the lock's time) and no peak for that
    hinge, the same at 11 and 2001 output times, on the compiled loop ("auto") and on
    scipy's steps."""
    tips = {}
    runs = [("rigid", num, m) for num in (11, 2001) for m in ("auto", "DOP853")]
    for model, num, method in [*runs, ("reduced", 11, "auto"), ("reduced", 2001, "auto")]:
        traj = _run(model, num, method=method)
        assert traj.settings["method"] == {"auto": "DOP853-numba"}.get(method, method)
        (lock,) = traj.events
        entry = _peaks(traj)[("hinge_moment", 1)]
        assert entry["peak"] is None
        assert entry["t"] == lock["t"]
        assert entry["impulse"] == pytest.approx(abs(lock["impulse_instant"]), rel=1e-12)
        assert _peaks(traj)[("hinge_moment", 0)]["peak"] is not None  # no latch on hinge 0
        tips[model, num, method] = _peaks(traj)[("tip_deflection", 0)]["peak"]
    for key in (("rigid", "auto"), ("rigid", "DOP853"), ("reduced", "auto")):
        # the same steps whatever the output times: equal to round-off
        assert tips[key[0], 11, key[1]] == pytest.approx(tips[key[0], 2001, key[1]], rel=1e-6)


def test_exudyn_reads_its_peaks_on_every_recorded_step():
    """exudyn's peak over its recorded steps, the same at 11 and 2001 output times and at
    least the output times' largest |hinge_moment|."""
    pytest.importorskip("exudyn")
    coarse, fine = _run("exudyn", 11, elements=2), _run("exudyn", 2001, elements=2)
    assert coarse.stats.peaks["read_on"] == "every recorded step"
    a, b = _peaks(coarse), _peaks(fine)
    for key in a:
        # the same recorded steps observed alike: equal to round-off
        assert a[key]["peak"] == pytest.approx(b[key]["peak"], rel=1e-6, abs=1e-12), key
    top = float(np.max(np.abs(fine["hinge_moment"][:, 1])))
    # every output time lies on a Hermite interpolant between two recorded steps: the steps'
    # peak is at least the output times' less the interpolant's overshoot (well below 1 %)
    assert a[("hinge_moment", 1)]["peak"] >= 0.99 * top


# ------------------------------------------------------------------ the gate, on its tables


def _tables(peaks: str | None, status: str = "success", t_reached: float = 1.0):
    """One case "c" (horizon 1 s, a latch on hinge 1) run by "full": its 11 output times'
    hinge moments peak at 900 N m; runtime.csv records ``peaks``, ``status``, ``t_reached``."""
    t = np.linspace(0.0, 1.0, 11)
    traj = pd.DataFrame(
        {
            "case": "c",
            "model": "full",
            "t": t,
            "quantity": "hinge_moment",
            "k": 1,
            "value": 900.0 * np.sin(np.pi * t),
        }
    )
    runtime = pd.DataFrame(
        {
            "case": ["c"],
            "model": ["full"],
            "status": [status],
            "t_reached": [t_reached],
            "peaks": [peaks],
        }
    )
    return {
        "cases": pd.DataFrame({"case": ["c"], "horizon": [1.0], "latch_hinges": ["[1]"]}),
        "discrepancies": pd.DataFrame(columns=["case", "model", "quantity", "status"]),
        "runtime": runtime,
        "trajectories": traj,
    }


def _meta(req: dict) -> dict:
    return {
        "reference": "full",
        "models": [{"label": "full", "model": "full"}],
        "acceptance": {"valid": False, "bounds": [], "events": [], "requires": [req]},
    }


RECORDED = json.dumps({"hinge_moment": [{"k": 1, "peak": 1210.0, "t": 0.4098}]})


def test_the_gate_reads_the_runs_peak_not_the_output_times():
    """The output times peak at 900 N m, the run at 1210 N m: a 1000 N m gate breaks."""
    req = {"model": "full", "peak_hinge_moment": {"hinge": 1, "max": 1000.0}}
    checks = acceptance_checks(_meta(req), _tables(RECORDED))
    assert breach_lines(checks) == [
        "acceptance breached: c: full: peak |hinge_moment| (hinge 1): 1210 N m at t = 0.4098 s "
        "> max 1000 N m"
    ]


def test_a_gate_without_a_recorded_peak_or_on_an_impulse_breaks_saying_why():
    req = {"model": "full", "peak_hinge_moment": {"max": 1000.0}}
    (check,) = acceptance_checks(_meta(req), _tables(None))
    assert check.failure.startswith("no peak recorded between the output times")
    impulse = json.dumps({"hinge_moment": [{"k": 1, "peak": None, "t": 0.404, "impulse": 21.98}]})
    (check,) = acceptance_checks(_meta(req), _tables(impulse))
    assert check.failure == (
        "hinge 1's moment is impulsive at its lock (t = 0.404 s, impulse 21.98 N m s): no "
        "finite peak; bound its impulse instead"
    )


def test_a_requirement_on_a_run_that_stopped_early_breaks_in_one_line():
    """The run stopped at 0.002 s of 1 s (its peak, 12 N m, holds the gate): every
    requirement of its table breaks, in one check naming the status and the time reached."""
    req = {"model": "full", "peak_hinge_moment": {"max": 1000.0}, "locked_by": 0.9}
    small = json.dumps({"hinge_moment": [{"k": 1, "peak": 12.0, "t": 0.002}]})
    for status, t in (("evaluation budget exhausted", 0.002), ("integration failed", 0.002)):
        checks = acceptance_checks(_meta(req), _tables(small, status, t))
        assert breach_lines(checks) == [
            f"acceptance breached: c: full: requirements: the run did not reach t_end (status "
            f"{status}, t reached = 0.002 s of 1 s): no requirement is judged on a partial run"
        ]


# ------------------------------------------------------------------ the study file


def _study(acceptance: dict, models: dict | None = None) -> dict:
    """The two-rod latch (two_rod_latch(1e5)) as a study of "full" (and ``models``)."""
    return {
        "study": {"reference": "full"},
        "scene": {
            "n": 2,
            "t_end": 0.42,
            "times": {"num": 11},
            "outputs": ["phi", "hinge_moment"],
            "chain": {"l": 1.5, "m": 3.0, "EI": 1e5, "mu": 0.5, "kappa": [0.0, 50.0], "nu": 0.0},
            "initial": {"phi": [0.0, math.pi - 0.05], "dphi": [1.0, 1.0]},
            "latches": [{"hinge": 1, "angle": 0.0}],
        },
        "models": models or {"full": {}},
        "acceptance": acceptance,
    }


@pytest.mark.parametrize(
    "req, words",
    [
        (
            {"lock_time": {"hinge": 1, "min": 0.4, "max": 0.5}},
            r"key 'acceptance\.require\[0\]\.lock_time\.max': must be <= the cases' horizon "
            r"t_end = 0\.42 s \(a lock after t_end is never seen\), got 0\.5",
        ),
        (
            {"lock_time": {"hinge": 1, "min": 0.6}},
            r"'acceptance\.require\[0\]\.lock_time\.min': must be <= the cases' horizon",
        ),
        (
            {"locked_by": 1.0},
            r"'acceptance\.require\[0\]\.locked_by': must be <= the cases' horizon t_end = 0\.42",
        ),
    ],
)
def test_a_lock_time_past_the_horizon_is_refused_when_the_study_is_read(req, words):
    doc = _study({"require": [{"model": "full", **req}]})
    with pytest.raises(ValueError, match=words) as info:
        Study.from_dict(doc)
    assert "\n" not in str(info.value)


def test_the_study_gates_on_the_runs_peak_and_shows_every_setting_that_ran(tmp_path):
    """The issue's gate end to end: hinge 1's moment peaks at 4923 N m on the 11 output
    times and 6775 N m in the run; a 5000 N m requirement breaks, and on the rigid model
    (an impulse at the lock, no finite peak) it breaks saying why. The per-block run's error
    control is in runtime.csv and in the report's Models table, the models' options
    (kinematics, shapes) beside."""
    gates = [
        {"model": "full", "peak_hinge_moment": {"hinge": 1, "max": 5000.0}},
        {"model": "rigid", "peak_hinge_moment": {"hinge": 1, "max": 5000.0}},
    ]
    models = {"full": {}, "per_block": {"model": "full", "error_control": "per-block"}}
    doc = _study({"require": gates}, {**models, "rigid": {}})
    out = tmp_path / "out"
    run_study(Study.from_dict(doc), out, workers=1, progress=False)
    runtime = pd.read_csv(out / "runtime.csv").set_index("model")
    assert runtime.loc["full", "error_control"] == "uniform"
    assert runtime.loc["per_block", "error_control"] == "per-block"
    options = json.loads(runtime.loc["full", "options"])
    assert "kinematics" in options and "shapes" in options
    peaks = json.loads(runtime.loc["full", "peaks"])["hinge_moment"]
    assert peaks[1]["peak"] > 6700.0 and "dense output" in runtime.loc["full", "peaks_read_on"]
    lines = (out / "report.md").read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("| label"))  # Models
    cells = [c.strip() for c in lines[at].split("|")]
    assert {"error_control", "max_step", "first_step", "options", "method"} <= set(cells)
    row = next(line for line in lines[at:] if line.startswith("| per_block"))
    assert [c.strip() for c in row.split("|")][cells.index("error_control")] == "per-block"
    assert '"kinematics"' in row and '"shapes"' in row
    peak_rows = [x for x in lines if x.startswith("| full") and "| dense output" in x]
    peak_cells = [[c.strip() for c in x.split("|")] for x in peak_rows]
    assert any("6775" in row for row in peak_cells), peak_rows  # the report's peak table
    full, rigid = gate(out)
    assert full.startswith(
        "acceptance breached: base: full: peak |hinge_moment| (hinge 1): 6775.17"
    )
    # the rigid chords' lock is an impulse: refused with the reason, in one line
    assert rigid.startswith(
        "acceptance breached: base: rigid: peak |hinge_moment| (hinge 1): hinge 1's moment is "
        "impulsive at its lock (t = 0.403942 s, impulse 21.98"
    )


def test_the_reports_peak_table_reads_the_runs_peak_and_an_impulse():
    """The Deployment section's peak table: the run's recorded peak (1210 N m at 0.4098 s,
    not the output times' 900 N m), and for rigid's locked hinge its impulse, no peak."""
    from rodval.report.study_report import peak_hinge_moments

    tables = _tables(RECORDED)
    rigid = json.dumps({"hinge_moment": [{"k": 1, "peak": None, "t": 0.404, "impulse": 21.98}]})
    runtime = pd.concat(
        [
            tables["runtime"].assign(peaks_read_on="dense output (4000 intervals, lock windows)"),
            pd.DataFrame({"case": ["c"], "model": ["rigid"], "peaks": [rigid]}),
        ],
        ignore_index=True,
    )
    models = [{"label": "full", "model": "full"}, {"label": "rigid", "model": "rigid"}]
    peaks = peak_hinge_moments(tables["trajectories"], pd.DataFrame(), models, runtime)
    got = {r.model: r for r in peaks.itertuples()}
    assert (got["full"].peak_moment, got["full"].t_peak) == (1210.0, 0.4098)
    assert got["full"].source == "dense output (4000 intervals, lock windows)"
    assert np.isnan(got["rigid"].peak_moment) and got["rigid"].impulse == 21.98
    assert len(peaks) == 2
