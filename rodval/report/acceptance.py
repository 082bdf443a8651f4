"""A study's acceptance criteria (``rodval.study.acceptance``) evaluated on its saved tables:
one check per case, bounded pair and quantity (and per model run when every run must be
valid), the breaches as one line each, and a JUnit XML report that CI systems display (one
test case per check, a ``<failure>`` exactly where a bound broke).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

#: The metrics an acceptance bound may limit (columns of discrepancies.csv); the study file's
#: [[acceptance.bound]] tables are checked in ``rodval.study.acceptance``.
BOUND_METRICS = ("max_abs", "rms")


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


def acceptance_checks(meta: dict[str, Any], tables: dict[str, pd.DataFrame]) -> list[Check]:
    """The checks of the study's ``[acceptance]`` (none without it), in case order. A bound
    breaks when its comparison was not made (status other than "ok") or a bounded metric
    exceeds it; a run breaks ``valid = true`` when its verdict is invalid."""
    spec = meta.get("acceptance")
    if not spec:
        return []
    ref = meta["reference"]
    disc, runtime = tables["discrepancies"], tables["runtime"]
    index = {(str(r["case"]), r["model"], r["quantity"]): r for _, r in disc.iterrows()}
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
    broke) in one ``<testsuite>`` named ``suite``."""
    failures = sum(not c.held for c in checks)
    root = ET.Element("testsuites", name=JUNIT_NAME, tests=str(len(checks)), failures=str(failures))
    ts = ET.SubElement(
        root, "testsuite", name=suite, tests=str(len(checks)), failures=str(failures)
    )
    for c in checks:
        tc = ET.SubElement(ts, "testcase", classname=c.classname, name=c.name)
        if not c.held:
            ET.SubElement(tc, "failure", message=c.failure).text = c.failure
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
    return path


def gate(out: Path, junit: Path | None = None) -> list[str]:
    """Evaluate the acceptance of the study in ``out`` (its study.json and checked tables);
    write ``junit`` when given (also without an [acceptance] table: then it has no test
    cases). Returns the breach lines (empty: the study passes)."""
    import json

    from rodval.report.tables import read_tables

    meta = json.loads((Path(out) / "study.json").read_text())
    checks = acceptance_checks(meta, read_tables(out))
    if junit is not None:
        write_junit(checks, junit, str(meta.get("name", "study")))
    return breach_lines(checks)


def acceptance_section(meta: dict[str, Any], tables: dict[str, pd.DataFrame]) -> list[str]:
    """The report's "Acceptance" section: the number of checks, how many broke, and each
    breach (nothing without an [acceptance] table)."""
    checks = acceptance_checks(meta, tables)
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
