"""Issue 58: a report opens with its verdict, whatever the study.

A one-model study's report opened with the cross-validation preamble ("A model agrees with
`rigid` until ...") about a reference that is the only model, then, over a grid, the
reference's sentence once per case and a table of "(reference)" rows; its acceptance verdict,
lock times and peak moments came dozens of lines later. It now opens with the acceptance
verdict (which requirement broke, in which case), how the runs ended, whether they deployed
and the quantities of interest per hinge over the cases (min, p5, p50, p95, max, the worst
case); nothing in it compares models. A study that compares models still opens with the
agreement answer (tests/test_study_report.py, tests/test_agreement.py), the reference's
sentence once for the study.

The user's study: a 5-panel wing (1 m, 2.5 kg panels on a 0.8 m yoke, preloaded hinge
springs, a latch on every hinge) on a pinned base, the rigid model alone, a 3 x 3 grid of the
panels' spring stiffness and the hinge fittings' mass, and a gate: every run valid, every
latch locked by 1.6 s, hinge 3's lock impulse at most 20 N m s.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from rodval.analysis.agreement import AGREEMENT_COLUMNS, AgreementSettings, latch_hinges
from rodval.report.sample_stats import PERCENTILES
from rodval.report.study_answer import _sentences
from rodval.report.study_report import build_report, peak_hinge_moments
from rodval.report.study_summary import opening_section, summary_sections
from rodval.report.tables import axis_columns, read_events, read_tables, study_constants
from rodval.study import load_study, run_study

WING = (
    """
[study]
name = "wing5"
reference = "rigid"

[scene]
n = 6
t_end = 2.0
times = { num = 101 }
outputs = ["phi", "hinge_moment"]
loads = []

[scene.chain]
l = [0.8, 1.0, 1.0, 1.0, 1.0, 1.0]
m = [1.25, 2.5, 2.5, 2.5, 2.5, 2.5]
EI = 2e4
mu = 0.2
kappa = { first = [100.0, 60.0], rest = 20.0 }
nu = 0.02
rest_angle = [-0.3, -0.3, 0.3, -0.3, 0.3, -0.3]

[scene.initial]
phi = [0.5, 3.5915926535897933, 0.5, 3.5915926535897933, 0.5, 3.5915926535897933]
"""
    + "".join(f"\n[[scene.latches]]\nhinge = {h}\nangle = 0.0\n" for h in range(6))
    + """
[models.rigid]

[grid]
"scene.chain.kappa.rest" = [15.0, 20.0, 25.0]
"scene.chain.mu" = [0.1, 0.2, 0.3]

[acceptance]
valid = true

[[acceptance.require]]
model = "rigid"
locked_by = 1.6
impulse = { hinge = 3, max = 20.0 }
"""
)

#: The lines of report.md that must hold the answer.
HEAD = 20


@pytest.fixture(scope="module")
def wing(tmp_path_factory):
    """The wing study's folder (tables, no report), study.json, tables and events."""
    tmp = tmp_path_factory.mktemp("wing5")
    (tmp / "wing5.toml").write_text(WING)
    out = tmp / "out"
    run_study(load_study(tmp / "wing5.toml"), out, workers=1, progress=False, report=False)
    meta = json.loads((out / "study.json").read_text())
    return out, meta, read_tables(out), read_events(out)


def _head(meta, tables, events) -> list[str]:
    """The report's first HEAD lines as build_report writes them: the title, the opening."""
    peaks = peak_hinge_moments(tables["trajectories"], events, meta["models"], tables["runtime"])
    lines = [f"# Study `{meta['name']}`\n", *opening_section(meta, tables, events, peaks)]
    return "\n".join(x for x in lines if x).splitlines()[:HEAD]


def _first_locks(events: pd.DataFrame, hinge: int) -> pd.DataFrame:
    """Each case's first lock of ``hinge``: case, t, impulse."""
    own = events[events["label"] == f"latch hinge {hinge}"].sort_values("t")
    return own.drop_duplicates("case")[["case", "t", "impulse"]]


def _spread_text(values: np.ndarray) -> str:
    """min / p5 / p50 / p95 / max as the opening writes them (4 digits: what a reader reads)."""
    figures = [values.min(), *(np.percentile(values, p) for p in PERCENTILES), values.max()]
    return " / ".join(f"{v:.4g}" for v in figures)


def test_the_first_lines_give_the_lock_time_percentiles_and_the_latest_case(wing):
    """Hinge 1 (the yoke's: it swings the whole wing) locks last; its lock times over the nine
    cases and the case of the latest are in the first 20 lines."""
    _, meta, tables, events = wing
    head = "\n".join(_head(meta, tables, events))
    locks = _first_locks(events, 1)
    assert len(locks) == 9
    latest = locks.loc[locks["t"].idxmax()]
    row = next(line for line in head.splitlines() if line.startswith("|       1 |"))
    assert _spread_text(locks["t"].to_numpy()) in row
    assert f"{latest['t']:.4g} (`{latest['case']}`)" in row
    assert "## Answer" in head and "min / p5 / p50 / p95 / max" in head


def test_the_first_lines_give_the_peak_moments_or_say_they_are_impulses(wing):
    """The rigid model locks its chords plastically: a hinge that locked has an impulse, not a
    finite peak, and the opening says in how many cases; a hinge that never locked has the
    peak the run recorded between its output times (runtime.csv's ``peaks``)."""
    _, meta, tables, events = wing
    head = "\n".join(_head(meta, tables, events))
    assert "peak hinge moment (N m)" in head
    peaks = peak_hinge_moments(tables["trajectories"], events, meta["models"], tables["runtime"])
    assert set(peaks["source"]) == {"dense output (4000 intervals, lock windows)"}
    for hinge, part in peaks.groupby("hinge"):
        row = next(line for line in head.splitlines() if line.startswith(f"|       {hinge} |"))
        impulsive = int(part["peak_moment"].isna().sum())
        if impulsive:
            assert f"impulsive at its lock in {impulsive} of 9" in row
        finite = part.dropna(subset=["peak_moment"])
        if len(finite):
            top = finite.loc[finite["peak_moment"].idxmax()]
            assert f"{top['peak_moment']:.4g} (`{top['case']}`)" in row


def test_a_failed_gate_names_the_requirement_and_the_cases(wing):
    """The gate fails: hinge 3's lock impulse exceeds 20 N m s; the opening says FAILED, names
    the requirement, in how many cases and which, with the figure against the bound."""
    _, meta, tables, events = wing
    head = _head(meta, tables, events)
    gate = next(line for line in head if "Acceptance" in line)
    assert gate.startswith("**Acceptance: FAILED**")
    hinge3 = _first_locks(events, 3)
    over = hinge3[hinge3["impulse"].abs() > 20.0]
    assert len(over) >= 1
    assert f"`rigid: hinge 3 lock impulse` in {len(over)} of 9 cases" in gate
    order = list(tables["cases"]["case"].astype(str))
    first = over.loc[over["case"].map(order.index).idxmin()]  # the breaches in case order
    assert f"`{first['case']}`: |impulse| = {abs(first['impulse']):.6g} N m s > max 20" in gate


def test_a_passed_gate_says_so_first(wing):
    """With requirements every run meets, the opening's first sentence says PASSED."""
    _, meta, tables, events = wing
    lenient = copy.deepcopy(meta)
    lenient["acceptance"] = {"valid": True, "bounds": [], "events": [], "requires": []}
    head = _head(lenient, tables, events)
    assert head[4] == "**Acceptance: PASSED** (9 checks of the study's [acceptance])."


def test_the_runs_and_their_deployment_are_stated_once(wing):
    """How the runs ended and in how many cases every latch locked; a case where a latch
    never locked is named, with the latch, and not called deployed."""
    _, meta, tables, events = wing
    head = "\n".join(_head(meta, tables, events))
    assert "`rigid` over 9 cases: 9 of 9 runs reached t_end; none invalid" in head
    latched = latch_hinges(tables["cases"])
    done = {
        case: {int(lab.split()[-1]) for lab in part["label"]}
        for case, part in events.groupby("case")
    }
    missing = {c: [h for h in hs if h not in done.get(c, set())] for c, hs in latched.items()}
    missing = {c: hs for c, hs in missing.items() if hs}
    assert f"deployed (every latch locked) in {9 - len(missing)} of 9" in head
    for case, hs in missing.items():
        names = ", ".join(f"latch hinge {h}" for h in hs)
        assert f"`{case}` ({names} never locked within its run)" in head


def test_no_line_of_a_one_model_report_speaks_of_a_reference(wing):
    """Nothing compares models in a one-model study: no reference, no agreement, no speed-up,
    no comparisons counted, no Discrepancies "against" the model itself."""
    _, meta, tables, events = wing
    params = ["n", "horizon", *axis_columns(meta).values()]
    constants = study_constants(tables["cases"], meta["reference"])
    text = "\n".join(
        _head(meta, tables, events) + summary_sections(meta, tables, params, constants)
    )
    for word in ("reference", "agree", "speed-up", "comparisons made", "against `"):
        assert word not in text.lower(), word
    assert "nothing to compare" in text


def test_a_grid_states_the_reference_once():
    """Over a grid the reference's verdict is one sentence for the study (it was one per
    case), naming the cases where it did not deploy."""
    rows = []
    for case, missed in (("a", ""), ("b", "latch hinge 1"), ("c", "")):
        common = {"case": case, "status": "success", "valid": True, "out_of_domain": ""}
        rows.append({**common, "model": "ref", "role": "reference", "never_locked": missed})
        rows.append(
            {
                **common,
                "model": "m",
                "role": "model",
                "never_locked": missed,
                "compared_to": 1.0,
                "part_lock": "",
                "cause": "",
            }
        )
    table = pd.DataFrame(rows).reindex(columns=list(AGREEMENT_COLUMNS)).assign(wall_s=0.5)
    text = " ".join(_sentences(table, "ref", AgreementSettings()))
    assert text.count("The reference") == 1 and text.count("error bar not given") == 1
    assert text.startswith("The reference `ref` is valid in 3 of 3 cases")
    assert "not deployed in 1 of 3: `b` (latch hinge 1 never locked within its run)" in text
    assert text.count("`m` (case") == 3


def test_a_free_base_a_failed_run_and_unrecorded_peaks_are_said():
    """On a free base the opening gives the base's attitude at t_end over the cases with the
    case of the largest |attitude|; a failed run is named with its status, time reached and
    message (its values left out); peaks from a study that recorded none are the output times'
    maximum, and the opening says so."""
    cases = pd.DataFrame(
        {
            "case": ["c1", "c2", "c3"],
            "n": 2,
            "horizon": 1.0,
            "latch_hinges": "[1]",
            "base_kind": "free",
        }
    )
    runtime = pd.DataFrame(
        {
            "case": ["c1", "c2", "c3"],
            "model": "rigid",
            "status": ["success", "success", "wall-clock budget exhausted"],
            "t_reached": [1.0, 1.0, 0.25],
            "message": ["reached t_end", "reached t_end", "max_wall_s = 1 s spent"],
            "valid": [True, True, None],
            "invalid_because": "",
            "wall_s": 0.1,
        }
    )
    traj = pd.DataFrame(
        [
            {"case": c, "model": "rigid", "t": t, "quantity": q, "k": k, "value": v}
            for c, att, moment in (("c1", 0.01, 40.0), ("c2", -0.03, 55.0), ("c3", 0.5, 1e3))
            for t in (0.0, 1.0)
            for q, k, v in (("base_attitude", 0, att * t), ("hinge_moment", 1, moment * t))
        ]
    )
    events = pd.DataFrame(
        {
            "case": ["c1", "c2"],
            "model": "rigid",
            "t": [0.4, 0.6],
            "label": "latch hinge 1",
            "hinge": 1,
            "impulse": [-3.0, -5.0],
        }
    )
    meta = {"name": "free", "models": [{"label": "rigid", "model": "rigid"}], "reference": "rigid"}
    tables = {"cases": cases, "runtime": runtime, "trajectories": traj}
    peaks = peak_hinge_moments(traj, events, meta["models"], runtime)
    text = "\n".join(opening_section(meta, tables, events, peaks))
    assert "`c3` (wall-clock budget exhausted at t = 0.25 s: max_wall_s = 1 s spent)" in text
    assert "the free base's attitude at t_end (rad) -0.03 / " in text
    assert "largest |attitude| -0.03 (`c2`)" in text  # c3 failed: its 0.5 rad left out
    assert "over the output times of trajectories.csv only" in text
    assert "55 (`c2`)" in text and "1000" not in text
    assert "3 / 3.1 / 4 / 4.9 / 5 (2 of 3)" in text and "| 5 (`c2`) " in text  # |impulse|
    assert "not deployed in `c3` (latch hinge 1 never locked within its run)" in text


@pytest.mark.slow  # the whole report with its figures (15 s here); the tests above its parts
def test_report_md_opens_with_the_verdict_and_never_names_a_reference(wing):
    """The written report.md: its first 20 lines hold the gate, the lock-time percentiles and
    the peaks; no line of it speaks of a reference or an agreement."""
    out, *_ = wing
    report = build_report(out).read_text()
    head = "\n".join(report.splitlines()[:HEAD])
    assert "**Acceptance: FAILED**" in head and "`rigid: hinge 3 lock impulse`" in head
    assert "lock time (s)" in head and "peak hinge moment (N m)" in head
    assert "|       5 |" in head  # the last hinge's row
    for word in ("reference", "agree"):
        assert word not in report.lower(), word
