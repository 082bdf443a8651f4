"""What a study's report draws (the ``[report]`` table): the cases drawn in full, the rods,
the quantities and the configuration times, checked against those cases when the study file
is read (a report never finds out at the end that it asked for a rod beyond a chain)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rodval.core.checks import check_keys
from rodval.core.scene import QUANTITIES, trajectory_quantities
from rodval.study.case import Case
from rodval.study.document import key_error

REPORT_KEYS = {"cases", "rods", "quantities", "times"}
#: The quantities the report draws when [report] does not say (those the cases output).
DEFAULT_REPORT_QUANTITIES = ("phi", "dphi", "alpha", "beta")


@dataclass(frozen=True)
class ReportSpec:
    """What the report draws. ``rods``: rod numbers >= 1 or "last"; ``times``: configuration
    times (s), None for quarters of each case's horizon."""

    cases: tuple[str, ...]
    rods: tuple[int | str, ...] = (1, "last")
    quantities: tuple[str, ...] = DEFAULT_REPORT_QUANTITIES
    times: tuple[float, ...] | None = None

    def as_dict(self) -> dict[str, Any]:
        """The report's choices as plain JSON (study.json)."""
        return {
            "cases": list(self.cases),
            "rods": list(self.rods),
            "quantities": list(self.quantities),
            "times": None if self.times is None else list(self.times),
        }


def report_spec(table: Any, cases: tuple[Case, ...], where: str) -> ReportSpec:
    """The [report] table, checked against the cases it draws (``report.cases``, by default
    the study's most demanding case, most rods x longest horizon, then its first): every rod
    number within every report case's chain, every quantity among every report case's outputs,
    every time within every report case's horizon (s)."""
    table = {} if table is None else table
    check_keys(table, REPORT_KEYS, f"{where}:", path="report")
    drawn = _report_cases(table, cases, where)
    rods = _report_rods(table, drawn, where)
    quantities = _report_quantities(table, drawn, where)
    times = _report_times(table, drawn, where)
    return ReportSpec(
        cases=tuple(c.id for c in drawn),
        rods=tuple(rods),
        quantities=tuple(quantities),
        times=times,
    )


def _report_cases(table: dict[str, Any], cases: tuple[Case, ...], where: str) -> list[Case]:
    """The cases ``report.cases`` names (default: the most demanding case, then the first)."""
    by_id = {c.id: c for c in cases}
    demanding = max(cases, key=lambda c: c.scene.n * c.scene.t_end).id
    ids = table.get("cases", list(dict.fromkeys([demanding, cases[0].id])))
    if not isinstance(ids, list) or any(c not in by_id for c in ids):
        raise key_error(
            where, "report.cases", f"must be a list of case ids from {list(by_id)}, got {ids!r}"
        )
    return [by_id[c] for c in ids]


def _report_rods(table: dict[str, Any], drawn: list[Case], where: str) -> list[int | str]:
    """``report.rods``: rod numbers >= 1 within the shortest report chain, or "last"."""
    rods = table.get("rods", [1, "last"])
    if (
        not isinstance(rods, list)
        or not rods
        or any(
            not (r == "last" or (isinstance(r, int) and not isinstance(r, bool) and r >= 1))
            for r in rods
        )
    ):
        raise key_error(
            where, "report.rods", f'must be a list of rod numbers >= 1 or "last", got {rods!r}'
        )
    shortest = min(drawn, key=lambda c: c.scene.n)
    beyond = [r for r in rods if r != "last" and r > shortest.scene.n]
    if beyond:
        raise key_error(
            where,
            "report.rods",
            f"rod {beyond[0]} is beyond the chain of report case {shortest.id!r} "
            f'(n = {shortest.scene.n}); allowed: 1..{shortest.scene.n} or "last"',
        )
    return rods


def _report_quantities(table: dict[str, Any], drawn: list[Case], where: str) -> list[str]:
    """``report.quantities``: among the outputs of every report case (default: those of
    ``DEFAULT_REPORT_QUANTITIES`` they output, else all they output)."""
    outputs = [  # trajectory quantities: a free base's "base" yields base_attitude, ...
        q
        for q in trajectory_quantities(QUANTITIES)
        if all(q in trajectory_quantities(c.scene.outputs) for c in drawn)
    ]
    quantities = table.get(
        "quantities", [q for q in DEFAULT_REPORT_QUANTITIES if q in outputs] or outputs
    )
    if (
        not isinstance(quantities, list)
        or not quantities
        or any(q not in outputs for q in quantities)
    ):
        raise key_error(
            where,
            "report.quantities",
            f"must be a list of quantities every report case outputs ({', '.join(outputs)}), "
            f"got {quantities!r}",
        )
    return quantities


def _report_times(table: dict[str, Any], drawn: list[Case], where: str) -> tuple[float, ...] | None:
    """``report.times`` (s): within the shortest horizon of the report cases; None when not
    given (quarters of each case's horizon)."""
    times = table.get("times")
    horizon = min(c.scene.t_end for c in drawn)
    if times is not None and (
        not isinstance(times, list)
        or not times
        or any(
            isinstance(t, bool)
            or not isinstance(t, (int, float))
            or not math.isfinite(t)
            or not 0 <= t <= horizon
            for t in times
        )
    ):
        raise key_error(
            where,
            "report.times",
            f"must be a list of times in 0..{horizon:g} s (the shortest horizon of the report "
            f"cases), got {times!r}",
        )
    return None if times is None else tuple(float(t) for t in times)
