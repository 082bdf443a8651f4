"""A study's acceptance criteria (``rodval.study.acceptance``) evaluated on its saved tables:
one check per case, bounded pair and quantity (and per model run when every run must be
valid), per case and event bound (the locks against the reference's,
``rodval.analysis.events.lock_comparison``), per model for ``all_latched``, per run for the
residuals, per case and absolute requirement of a model's own results
([[acceptance.require]]: every latch locked by a time, a hinge's lock time and |impulse| in
a range from events.csv, the peak |hinge_moment| the run recorded between its output times
(runtime.csv's ``peaks``, ``SolverStats.peaks``) and a quantity's value at t_end from
trajectories.csv; ``_require_checks``; a run that did not reach t_end breaks every
requirement on it, in one line); the breaches as one line each
(``acceptance breached: CASE: MODEL: hinge 2 lock time: t = 0.6312 s > max 0.61 s``), and
a JUnit XML report that CI systems display (one test case per check, a ``<failure>`` exactly
where a bound broke).
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from rodval.analysis.agreement import locked_hinges
from rodval.core.out_paths import write_with

#: The metrics an acceptance bound may limit (columns of discrepancies.csv); the study file's
#: [[acceptance.bound]] tables are checked in ``rodval.study.acceptance``.
BOUND_METRICS = ("max_abs", "rms")
#: The figures an [[acceptance.event]] table may bound: ``lock_time`` (s, max |dt| of the
#: model's locks against the reference's), ``impulse`` (max impulse_rel).
EVENT_METRICS = ("lock_time", "impulse")
#: The [acceptance] table's scalar keys: ``all_latched`` (the fraction of cases in which every
#: latch of the scene locked, per model), ``energy_residual`` and ``momentum_residual`` (the
#: largest |residual| of runtime.csv's column of that name, per run).
SCALAR_KEYS = ("all_latched", "energy_residual", "momentum_residual")
#: What an [[acceptance.require]] table may require of a model's own results (absolute, not
#: against the reference): ``locked_by`` (s, every latch of the scene locked at or before),
#: ``lock_time`` (s, a hinge's lock time in [min, max]), ``impulse`` (N m s, |a hinge's lock
#: impulse| in [min, max]), ``peak_hinge_moment`` (N m, the run's max |hinge_moment|, read
#: between the output times: ``SolverStats.peaks``), ``final`` (a quantity's value at the last
#: output time in [min, max]).
REQUIRE_ITEMS = ("locked_by", "lock_time", "impulse", "peak_hinge_moment", "final")
#: Why a run has no energy residual: it was not audited.
NO_ENERGY_RESIDUAL = (
    'no energy residual recorded (a run audits its energy only with "energy" among the '
    "scene's outputs)"
)
#: Why a run has no momentum residual (runtime.csv's blank): the audit does not apply.
NOT_AUDITED = "momentum is audited on a free base or a free, unloaded root only"


@dataclass(frozen=True)
class Check:
    """One acceptance check: its JUnit class and name, and why it failed ("" if it held)."""

    classname: str
    name: str
    failure: str = ""

    @property
    def held(self) -> bool:
        return not self.failure


def _figure(row: pd.Series, metric: str) -> float:
    value = row.get(metric)
    return math.nan if value is None else float(value)


def acceptance_checks(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame | None = None
) -> list[Check]:
    """The checks of the study's ``[acceptance]`` (none without it), in case order. A bound
    breaks when its comparison was not made (status other than "ok") or a bounded metric
    exceeds it; a run breaks ``valid = true`` when its verdict is invalid. ``events``: the
    study's events.csv (``rodval.report.tables.read_events``; none: no run locked), for the
    event bounds (``_event_checks``) and ``all_latched`` (``_latched_checks``); the residual
    keys are checked per run (``_residual_checks``)."""
    spec = meta.get("acceptance")
    if not spec:
        return []
    if events is None:
        events = pd.DataFrame(columns=["case", "model", "t", "label"])
    ref = meta["reference"]
    disc, runtime = tables["discrepancies"], tables["runtime"]
    index = {(str(r["case"]), r["model"], r["quantity"]): r for _, r in disc.iterrows()}
    comparisons = _lock_comparisons(spec.get("events", []), ref, events)
    own = _own_results(tables, events) if spec.get("requires") else {}
    checks = []
    for case in tables["cases"]["case"].astype(str):
        for b in spec["bounds"]:
            name = f"{case}: {b['model']} vs {ref}: {b['quantity']}"
            row = index.get((case, b["model"], b["quantity"]))
            if row is None or row["status"] != "ok":
                why = "no row" if row is None else row["status"]
                checks.append(Check("acceptance.bounds", name, f"not compared ({why})"))
                continue
            broken = [
                f"{m} = {_figure(row, m):.6g} > {b[m]:g}"
                for m in BOUND_METRICS
                if m in b and not _figure(row, m) <= b[m]
            ]
            checks.append(Check("acceptance.bounds", name, "; ".join(broken)))
        if spec["valid"]:
            for _, run in runtime[runtime["case"].astype(str) == case].iterrows():
                invalid = str(run.get("valid")) == "False"
                why = f"invalid run: {run.get('invalid_because', '')}" if invalid else ""
                checks.append(Check("acceptance.valid", f"{case}: {run['model']} valid", why))
        checks += _event_checks(spec.get("events", []), ref, case, comparisons)
        checks += _residual_checks(spec, case, runtime)
        checks += _require_checks(spec.get("requires", []), case, own)
    if "all_latched" in spec:
        labels = [m["label"] for m in meta["models"]]
        checks += _latched_checks(spec["all_latched"], labels, tables["cases"], events)
    return checks


def _lock_comparisons(
    bounds: list[dict[str, Any]], ref: str, events: pd.DataFrame
) -> dict[str, pd.DataFrame]:
    """Per bounded model, its locks against the reference's (``lock_comparison``), case as
    text."""
    from rodval.analysis.events import lock_comparison

    events = events.assign(case=events["case"].astype(str))
    return {m: lock_comparison(events, m, ref) for m in dict.fromkeys(b["model"] for b in bounds)}


def _event_checks(
    bounds: list[dict[str, Any]], ref: str, case: str, comparisons: dict[str, pd.DataFrame]
) -> list[Check]:
    """One check per event bound in ``case``: a lock only one of the pair has breaks it; a
    lock that is not comparable pointwise is skipped (counted in the check's name); every
    other lock must keep each bound: |dt| <= lock_time (s), impulse_rel <= impulse."""
    checks = []
    for b in bounds:
        comp = comparisons[b["model"]]
        locks = comp[comp["case"] == case]
        why = locks["not_comparable"].fillna("").astype(str)
        missing = locks[why.str.startswith("only in ")]
        skipped = locks[(why != "") & ~why.str.startswith("only in ")]
        kept = locks[why == ""]
        name = f"{case}: {b['model']} vs {ref}"
        if locks.empty:
            name += " (no locks)"
        elif len(skipped) == len(locks):
            name += f" (all {len(skipped)} locks not comparable pointwise: skipped)"
        elif len(skipped):
            s = "s" if len(skipped) > 1 else ""
            name += f" ({len(skipped)} lock{s} not comparable pointwise: skipped)"
        broken = []
        for _, lock in missing.iterrows():
            lacks = ref if str(lock["not_comparable"]) == f"only in {b['model']}" else b["model"]
            broken.append(f"{lock['label']}: no lock in {lacks}")
        for _, lock in kept.iterrows():
            dt, rel = abs(float(lock["dt"])), float(lock["impulse_rel"])
            if "lock_time" in b and not dt <= b["lock_time"]:
                broken.append(f"{lock['label']} lock time |dt| = {dt:.3g} s > {b['lock_time']:g} s")
            if "impulse" in b and not rel <= b["impulse"]:
                broken.append(f"{lock['label']} impulse_rel = {rel:.3g} > {b['impulse']:g}")
        checks.append(Check("acceptance.events", name, "; ".join(broken)))
    return checks


def _residual_checks(spec: dict[str, Any], case: str, runtime: pd.DataFrame) -> list[Check]:
    """One check per run of ``case`` and residual key: |residual| <= the bound. A run without
    an energy residual breaks the bound; a blank momentum residual (or no such column) is
    a run the momentum audit does not apply to: named, not broken."""
    checks = []
    runs = runtime[runtime["case"].astype(str) == case]
    for key in ("energy_residual", "momentum_residual"):
        if key not in spec:
            continue
        bound = spec[key]
        for _, run in runs.iterrows():
            name = f"{case}: {run['model']} {key}"
            value = pd.to_numeric(pd.Series([run.get(key)]), errors="coerce").iloc[0]
            if pd.isna(value):
                if key == "momentum_residual":
                    checks.append(
                        Check("acceptance.residuals", f"{name} (not audited: {NOT_AUDITED})")
                    )
                else:
                    checks.append(Check("acceptance.residuals", name, NO_ENERGY_RESIDUAL))
                continue
            fail = "" if abs(value) <= bound else f"|{key}| = {abs(value):.3g} > {bound:g}"
            checks.append(Check("acceptance.residuals", name, fail))
    return checks


def _own_results(tables: dict[str, pd.DataFrame], events: pd.DataFrame) -> dict[str, Any]:
    """What the requirements read, split by case once (case as text): its cases.csv row,
    its trajectories, its events and its runs' runtime.csv rows by model."""

    def by_case(frame: pd.DataFrame) -> dict[str, pd.DataFrame]:
        return dict(iter(frame.groupby(frame["case"].astype(str), sort=False)))

    empty = pd.DataFrame(columns=["case", "model", "t", "quantity", "k", "value"])
    cases = tables["cases"].assign(case=tables["cases"]["case"].astype(str)).set_index("case")
    runtime = tables["runtime"]
    runs = {(str(r["case"]), str(r["model"])): r for _, r in runtime.iterrows()}
    return {
        "cases": cases,
        "runs": runs,
        "trajectories": by_case(tables.get("trajectories", empty)),
        "events": by_case(events),
        "empty": empty,
        "no_events": events.iloc[0:0],
    }


def _require_checks(requires: list[dict[str, Any]], case: str, own: dict[str, Any]) -> list[Check]:
    """One check per requirement of each [[acceptance.require]] table in ``case`` (classname
    ``acceptance.require``), from the model's own lock events and trajectories (``own``:
    ``_own_results``): locked_by (every latch of the case's latch_hinges), lock_time and
    impulse (the hinge's first lock), peak_hinge_moment (the run's recorded peak,
    ``_peak_check``), final (the value at the case's horizon). A lock, value or time that is
    not there breaks the requirement; a run that did not reach t_end breaks its table in one
    check that says how it ended (``_unfinished``)."""
    if not requires:
        return []
    row = own["cases"].loc[case]
    traj = own["trajectories"].get(case, own["empty"])
    ev = own["events"].get(case, own["no_events"])
    checks = []
    for req in requires:
        model = req["model"]
        head = f"{case}: {model}"
        run = own["runs"].get((case, model))
        stopped = _unfinished(run, float(row["horizon"]))
        if stopped:
            checks.append(Check("acceptance.require", f"{head}: requirements", stopped))
            continue
        locks = _first_locks(ev[ev["model"] == model])
        if "locked_by" in req:
            latched = json.loads(str(row.get("latch_hinges", "[]")))
            checks.append(_locked_by_check(head, req["locked_by"], latched, locks))
        for r in req.get("lock_time", []):
            lock = locks.get(r["hinge"])
            t = math.nan if lock is None else lock[0]
            name = f"{head}: hinge {r['hinge']} lock time"
            checks.append(_range_check(name, "t", t, r, "s", "no lock"))
        for r in req.get("impulse", []):
            lock = locks.get(r["hinge"])
            value = math.nan if lock is None else abs(lock[1])
            name = f"{head}: hinge {r['hinge']} lock impulse"
            absent = (
                "no lock" if lock is None else f"no impulse recorded (lock at t = {lock[0]:.6g} s)"
            )
            checks.append(_range_check(name, "|impulse|", value, r, "N m s", absent))
        mine = traj[traj["model"] == model]
        if "peak_hinge_moment" in req:
            checks.append(_peak_check(head, req["peak_hinge_moment"], run))
        for r in req.get("final", []):
            checks.append(_final_check(head, r, mine, float(row["horizon"])))
    return checks


def _unfinished(run: pd.Series | None, horizon: float) -> str:
    """Why a run's requirements cannot hold (its runtime.csv row ``run``; None: the tables
    have no row for it, nothing to say): it failed or stopped before the case's horizon
    (s). "" for a run that reached t_end."""
    if run is None:
        return ""
    status = str(run.get("status", "success"))
    t = pd.to_numeric(pd.Series([run.get("t_reached")]), errors="coerce").iloc[0]
    short = not pd.isna(t) and float(t) < horizon * (1 - 1e-9)
    if status == "success" and not short:
        return ""
    reached = "unknown" if pd.isna(t) else f"{float(t):.6g} s"
    return (
        f"the run did not reach t_end (status {status}, t reached = {reached} of {horizon:g} s): "
        "no requirement is judged on a partial run"
    )


def _first_locks(events: pd.DataFrame) -> dict[int, tuple[float, float]]:
    """Hinge -> (t s, impulse N m s) of its first lock among one run's ``events``."""
    locks: dict[int, tuple[float, float]] = {}
    for _, e in events.sort_values("t", kind="stable").iterrows():
        for h in locked_hinges(e["label"]):
            impulse = pd.to_numeric(pd.Series([e.get("impulse")]), errors="coerce").iloc[0]
            locks.setdefault(h, (float(e["t"]), float(impulse)))
    return locks


def _range_check(
    name: str, what: str, value: float, r: dict[str, Any], unit: str, absent: str = "no value"
) -> Check:
    """``value`` within r's [min, max]; a value that is not there (nan) breaks it, said by
    ``absent``."""
    bounds = f"[{r.get('min', -math.inf):g}, {r.get('max', math.inf):g}] {unit}"
    if math.isnan(value):
        return Check("acceptance.require", name, f"{absent} (required in {bounds})")
    fail = ""
    if "max" in r and not value <= r["max"]:
        fail = f"{what} = {value:.6g} {unit} > max {r['max']:g} {unit}"
    elif "min" in r and not value >= r["min"]:
        fail = f"{what} = {value:.6g} {unit} < min {r['min']:g} {unit}"
    return Check("acceptance.require", name, fail)


def _locked_by_check(
    head: str, by: float, latched: list[int], locks: dict[int, tuple[float, float]]
) -> Check:
    """Every latched hinge of the case locked at or before ``by`` s."""
    late = []
    for h in sorted(latched):
        if h not in locks:
            late.append(f"hinge {h} never locked")
        elif not locks[h][0] <= by:
            late.append(f"hinge {h} locked at t = {locks[h][0]:.6g} s")
    name = f"{head}: every latch locked by {by:g} s"
    return Check("acceptance.require", name, f"{', '.join(late)} > {by:g} s" if late else "")


def _peak_check(head: str, r: dict[str, Any], run: pd.Series | None) -> Check:
    """The run's peak |hinge_moment| (of r's hinge, or of every hinge) <= max: the peak the
    run recorded between its output times (runtime.csv's ``peaks``: ``SolverStats.peaks``),
    never the output times' own. A run without a recorded peak (a study of an older rodval)
    or whose hinge moment is impulsive at a lock (its entry holds the lock's impulse)
    breaks it, saying so."""
    which = "every hinge" if "hinge" not in r else f"hinge {r['hinge']}"
    name = f"{head}: peak |hinge_moment| ({which})"
    raw = None if run is None else run.get("peaks")
    if raw is None or pd.isna(raw) or "hinge_moment" not in json.loads(str(raw)):
        why = "no peak recorded between the output times (run the study again to record it)"
        return Check("acceptance.require", name, why)
    entries = json.loads(str(raw))["hinge_moment"]
    if "hinge" in r:
        entries = [e for e in entries if int(e["k"]) == r["hinge"]]
    impulsive = [e for e in entries if e.get("impulse") is not None]
    if impulsive:
        e = impulsive[0]
        why = (
            f"hinge {e['k']}'s moment is impulsive at its lock (t = {e['t']:.6g} s, impulse "
            f"{e['impulse']:.6g} N m s): no finite peak; bound its impulse instead"
        )
        return Check("acceptance.require", name, why)
    if not entries or any(e["peak"] is None for e in entries):
        return Check("acceptance.require", name, "no finite hinge_moment recorded")
    at = max(entries, key=lambda e: float(e["peak"]))
    peak = float(at["peak"])
    where = "" if "hinge" in r else f" (hinge {int(at['k'])})"
    fail = (
        ""
        if peak <= r["max"]
        else f"{peak:.6g} N m at t = {float(at['t']):.6g} s{where} > max {r['max']:g} N m"
    )
    return Check("acceptance.require", name, fail)


def _final_check(head: str, r: dict[str, Any], traj: pd.DataFrame, horizon: float) -> Check:
    """The quantity's value at the case's horizon (its last output time) in [min, max]."""
    from rodval.core.scene import UNITS

    q, k = r["quantity"], r["k"]
    rows = traj[(traj["quantity"] == q) & (traj["k"] == k)]
    name = f"{head}: final {q}[{k}]"
    unit = UNITS.get(q, "")
    if rows.empty:
        return Check("acceptance.require", name, f"no {q}[{k}] in the trajectories")
    last = rows.loc[rows["t"].idxmax()]
    if not math.isclose(float(last["t"]), horizon, rel_tol=1e-9, abs_tol=1e-12):
        why = f"the output ends at t = {float(last['t']):.6g} s, not t_end = {horizon:g} s"
        return Check("acceptance.require", name, why)
    return _range_check(name, f"{q}[{k}] at t = {horizon:g} s", float(last["value"]), r, unit)


def _latched_checks(
    fraction: float, labels: list[str], cases: pd.DataFrame, events: pd.DataFrame
) -> list[Check]:
    """One check per model: in at least ``fraction`` of the cases whose scene has latches
    (cases.csv's latch_hinges) every latch locked in that model (its "latch hinge ..."
    events); the failure names the cases where some did not."""
    if "latch_hinges" not in cases:
        return [
            Check("acceptance.events", f"{m}: all latched", "cases.csv has no latch_hinges column")
            for m in labels
        ]
    latched = {
        str(c): set(json.loads(str(h))) if pd.notna(h) else set()
        for c, h in zip(cases["case"], cases["latch_hinges"])
    }
    latched = {c: h for c, h in latched.items() if h}
    ev = events.assign(case=events["case"].astype(str))
    checks = []
    for model in labels:
        name = f"{model}: all latched in >= {fraction:.4g} of the cases"
        if not latched:
            checks.append(Check("acceptance.events", f"{name} (no case has latches)"))
            continue
        own = ev[ev["model"] == model]
        short = []
        for case, hinges in latched.items():
            done = {h for lab in own[own["case"] == case]["label"] for h in locked_hinges(lab)}
            if not hinges <= done:
                short.append(f"{case} (hinge {', '.join(map(str, sorted(hinges - done)))})")
        k = len(latched) - len(short)
        share = k / len(latched)
        fail = (
            ""
            if share >= fraction
            else f"every latch locked in {k} of {len(latched)} cases ({share:.1%}) < {fraction:g}; "
            f"not in case {', '.join(short)}"
        )
        checks.append(Check("acceptance.events", name, fail))
    return checks


def breach_lines(checks: list[Check]) -> list[str]:
    """One line per broken check: case, pair, quantity (or run), the figure and the bound."""
    return [f"acceptance breached: {c.name}: {c.failure}" for c in checks if not c.held]


#: The name of the ``<testsuites>`` element of rodval's JUnit reports: how a later run knows
#: that a file at its --junit path is its own to overwrite (``is_junit_report``).
JUNIT_NAME = "rodval acceptance"


def is_junit_report(path: Path) -> bool:
    """Whether ``path`` is a JUnit report rodval wrote (its root names ``JUNIT_NAME``)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(512)
    except OSError:
        return False
    return head.startswith(b"<?xml") and f'<testsuites name="{JUNIT_NAME}"'.encode() in head


def write_junit(checks: list[Check], path: Path, suite: str) -> Path:
    """A JUnit XML file of ``checks`` (one ``<testcase>`` each, a ``<failure>`` where one
    broke) in one ``<testsuite>`` named ``suite``; the folders above ``path`` are made when
    missing, and the file is never written through a link (``write_with``)."""
    failures = sum(not c.held for c in checks)
    root = ET.Element("testsuites", name=JUNIT_NAME, tests=str(len(checks)), failures=str(failures))
    ts = ET.SubElement(
        root, "testsuite", name=suite, tests=str(len(checks)), failures=str(failures)
    )
    for c in checks:
        tc = ET.SubElement(ts, "testcase", classname=c.classname, name=c.name)
        if not c.held:
            ET.SubElement(tc, "failure", message=c.failure).text = c.failure
    tree = ET.ElementTree(root)
    return write_with(
        Path(path), lambda tmp: tree.write(tmp, encoding="utf-8", xml_declaration=True), "--junit"
    )


def gate(out: Path, junit: Path | None = None) -> list[str]:
    """Evaluate the acceptance of the study in ``out`` (its study.json and checked tables);
    write ``junit`` when given (also without an [acceptance] table: then it has no test
    cases). Returns the breach lines (empty: the study passes)."""
    from rodval.report.tables import read_events, read_tables

    meta = json.loads((Path(out) / "study.json").read_text())
    checks = acceptance_checks(meta, read_tables(out), read_events(Path(out)))
    if junit is not None:
        write_junit(checks, junit, str(meta.get("name", "study")))
    return breach_lines(checks)


def acceptance_section(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame | None = None
) -> list[str]:
    """The report's "Acceptance" section: the number of checks, how many broke, and each
    breach (nothing without an [acceptance] table); ``events``: the study's events.csv."""
    checks = acceptance_checks(meta, tables, events)
    if not meta.get("acceptance"):
        return []
    broken = breach_lines(checks)
    verdict = "PASSED" if not broken else f"FAILED ({len(broken)} of {len(checks)} checks)"
    lines = ["## Acceptance\n", f"{len(checks)} checks of the study's [acceptance]: {verdict}.\n"]
    if broken:
        lines.append(
            "\n".join(f"- {line.removeprefix('acceptance breached: ')}" for line in broken) + "\n"
        )
    return lines
