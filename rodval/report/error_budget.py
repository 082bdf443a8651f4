"""The model error budget: each case group's gap to the reference split into what the full
model's ladder rungs (docs/model.md, "The model ladder") attribute to the first-order
kinematics, to the bending shapes and, when the study varies the base kind, to the base.

``split_gaps`` is the one definition of the split (the study report and
``benchmarks/model_error_budget.py`` both call it); ``error_budget`` reads a study's rungs from
its description (study.json: the models, their options, each case's grid values) and its gaps
from the discrepancies table, and returns the split, or None when the study does not run the
rungs the split needs (first-order p = 1, exact p = 1 and an exact p > 1).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import pandas as pd

from rodval.core.scene import UNITS
from rodval.models.kinematics.rungs import KINEMATICS, PAPER_RUNG
from rodval.report.tables import axis_columns

FIRST_ORDER, EXACT = KINEMATICS
#: The registry name of the model whose rungs the split reads.
LADDER_MODEL = "full"
#: Columns of the table ``split_gaps`` returns beyond the group's, in order: the base kind
#: (when given), quantity, unit, then one ``gap KIN p=P`` column per rung and these parts.
PARTS = ("kinematics", "shapes", "base", "remainder")
#: Why the base part is blank.
NO_BASE_AXIS = "the study does not vary the base kind"
NO_PINNED = "no pinned case with the same parameters"
NO_KIND = "the case does not set its base kind"


def rung_name(kinematics: str, shapes: int) -> str:
    """A rung's gap column: ``gap first-order p=1``."""
    return f"gap {kinematics} p={shapes}"


def ladder_p_max(rungs: Sequence[tuple[str, int]] | set[tuple[str, int]]) -> int | None:
    """The highest exact p the split compares against when ``rungs`` (kinematics, shapes)
    hold first-order p = 1, exact p = 1 and at least one exact p > 1; None otherwise."""
    have = set(rungs)
    exact = [p for kin, p in have if kin == EXACT and p > 1]
    if (FIRST_ORDER, 1) not in have or (EXACT, 1) not in have or not exact:
        return None
    return max(exact)


def _pinned_gaps(
    table: dict[tuple[Any, ...], dict[tuple[str, int], float]],
    keys: list[str],
    match: list[int],
    top: tuple[str, int],
) -> dict[tuple[Any, ...], float]:
    """The pinned cases' gap on the rung ``top``, by their key without the base columns."""
    kind_at = keys.index("base_kind")
    pinned: dict[tuple[Any, ...], float] = {}
    for key, row in table.items():
        if key[kind_at] == "pinned":
            pinned.setdefault(tuple(key[i] for i in match), row.get(top, math.nan))
    return pinned


def _base_part(
    key: tuple[Any, ...],
    keys: list[str],
    match: list[int],
    pinned: dict[tuple[Any, ...], float] | None,
    last: float,
) -> tuple[float, str]:
    """(base part, the reason it is blank or ""): 0 on a pinned row, the gap ``last`` less its
    pinned counterpart's on another base (``split_gaps``); blank when the gaps' base kind does
    not vary (``pinned`` None)."""
    if pinned is None:
        return math.nan, NO_BASE_AXIS
    kind = key[keys.index("base_kind")]
    counterpart = tuple(key[i] for i in match)
    if kind == "pinned":
        return 0.0, ""
    if kind in (None, "-"):
        return math.nan, NO_KIND
    if counterpart in pinned:
        return last - pinned[counterpart], ""
    return math.nan, NO_PINNED


def split_gaps(
    gaps: pd.DataFrame, by: Sequence[str] = (), base_columns: Sequence[str] = ()
) -> pd.DataFrame | None:
    """The error budget of each case group and quantity, from the rungs' gaps.

    ``gaps``: one row per case group, rung and quantity: the columns ``by`` (the group: its
    scene and parameters, the rungs' own options excluded), ``kinematics`` ("first-order" or
    "exact"), ``shapes`` (p), ``quantity`` and ``gap`` (the rung's largest |model -
    reference| over the compared times and rods, in the quantity's unit: rad for phi, alpha,
    beta, rad/s for dphi; NaN where the comparison was not made), and optionally
    ``base_kind`` ("pinned", "free", "prescribed"; None where not known). ``base_columns``:
    the columns of ``by`` that describe the base body (mass, inertia, ...), ignored when a
    free case looks for its pinned counterpart (the first duplicate row counts).

    Returns None when the rungs are not all there (first-order p = 1, exact p = 1 and an
    exact p > 1; p_max below is the highest exact p of the table), else one row per group
    (and base kind) and quantity: ``by``, ``base_kind``, ``quantity``, ``unit``, the gap of
    every rung (``gap KIN p=P``, first-order rungs first, then by p), ``p_max`` and, in the
    quantity's unit,

    * ``kinematics`` = gap(first-order, 1) - gap(exact, 1): what the paper's first-order
      kinematics costs;
    * ``shapes`` = gap(exact, 1) - gap(exact, p_max): what one cubic shape per rod costs;
    * ``base`` = gap(exact, p_max) - gap_pinned(exact, p_max), on the same rung, against the
      pinned case of the same group (the ``base_columns`` aside): what the free (or
      prescribed) base adds to the gap no rung closes; 0 on a pinned row; blank (NaN, with
      the reason in ``base_note``) when the gaps have no ``base_kind`` varying over pinned
      and another kind, or the row has no pinned counterpart;
    * ``remainder`` = gap(exact, p_max) - base (gap(exact, p_max) itself when ``base`` is
      blank): the reference's own discretization error plus what no rung carries (the
      inextensible chord: no axial shortening from bending, no stretch).

    The parts add up: kinematics + shapes + (base) + remainder = gap(first-order, 1). A
    negative part means the rungs' errors cancel: e.g. shapes < 0 when exact p = 1 lies
    closer to the reference than exact p_max because its shape error partly offsets what no
    rung carries (or the reference's own error), not that more shapes make the model worse.
    The parts are differences of distances to the reference (each gap is a largest absolute
    difference), with no sign of their own. O(rows of ``gaps``)."""
    rung_list = _rungs(gaps)
    p_max = ladder_p_max(rung_list)
    if p_max is None:
        return None
    with_kind = "base_kind" in gaps.columns
    kinds = set(gaps["base_kind"].dropna()) if with_kind else set()
    base_varies = "pinned" in kinds and len(kinds) > 1
    keys = [*by, *(["base_kind"] if with_kind else []), "quantity"]
    table = _gap_table(gaps, keys)
    top = (EXACT, p_max)
    match = [i for i, c in enumerate(keys) if c not in base_columns and c != "base_kind"]
    pinned = _pinned_gaps(table, keys, match, top) if base_varies else None
    out = []
    for key, row in table.items():
        gap = {r: row.get(r, math.nan) for r in rung_list}
        base, note = _base_part(key, keys, match, pinned, gap[top])
        out.append(
            {
                **dict(zip(keys, key)),
                "unit": UNITS.get(str(key[-1]), ""),
                **{rung_name(*r): gap[r] for r in rung_list},
                "p_max": p_max,
                **_parts(gap, top, base),
                "base_note": note,
            }
        )
    frame, lead = pd.DataFrame(out), [*keys[:-1], "quantity", "unit"]
    return frame[[*lead, *(c for c in frame.columns if c not in lead)]]


def _rungs(gaps: pd.DataFrame) -> list[tuple[str, int]]:
    """The rungs (kinematics, shapes) of ``gaps``: first-order before exact, then by p."""
    return sorted(
        {(str(k), int(p)) for k, p in zip(gaps["kinematics"], gaps["shapes"])},
        key=lambda r: (KINEMATICS.index(r[0]) if r[0] in KINEMATICS else len(KINEMATICS), r),
    )


def _gap_table(
    gaps: pd.DataFrame, keys: list[str]
) -> dict[tuple[Any, ...], dict[tuple[str, int], float]]:
    """The rungs' gaps by group key (the values of ``keys``), each rung's first row only."""
    table: dict[tuple[Any, ...], dict[tuple[str, int], float]] = {}
    for rec in gaps.to_dict("records"):
        row = table.setdefault(tuple(_key(rec[c]) for c in keys), {})
        row.setdefault((str(rec["kinematics"]), int(rec["shapes"])), float(rec["gap"]))
    return table


def _parts(
    gap: dict[tuple[str, int], float], top: tuple[str, int], base: float
) -> dict[str, float]:
    """One row's parts (``split_gaps``) from its rungs' ``gap``, ``top`` the exact rung of
    p_max and ``base`` its base part (NaN when blank)."""
    first, exact1, last = gap[(FIRST_ORDER, 1)], gap[(EXACT, 1)], gap[top]
    return {
        "kinematics": first - exact1,
        "shapes": exact1 - last,
        "base": base,
        "remainder": last if math.isnan(base) else last - base,
    }


def _key(value: Any) -> Any:
    """A group value as a dict key: NaN (an axis a [[grid]] leaves unset) as "-"."""
    if isinstance(value, float) and math.isnan(value):
        return "-"
    return value


def ran_options(runtime: pd.DataFrame | None) -> dict[tuple[str, str], dict[str, Any]]:
    """(case id, model label) -> the options each run recorded it ran with (runtime.csv's
    ``options`` column, JSON: "auto" options resolved, e.g. the full model's kinematics);
    empty without the column (a table written before it) or ``runtime``."""
    if runtime is None or "options" not in runtime.columns:
        return {}
    out = {}
    for case, label, text in zip(runtime["case"], runtime["model"], runtime["options"]):
        try:
            options = json.loads(text)
        except (TypeError, ValueError):  # a blank cell (NaN): no record of the options
            continue
        if isinstance(options, dict):
            out[(str(case), str(label))] = options
    return out


def ladder_rungs(
    meta: dict[str, Any], ran: dict[tuple[str, str], dict[str, Any]] | None = None
) -> dict[tuple[str, str], tuple[str, int]]:
    """(case id, model label) -> (kinematics, shapes) of every run of the full model but the
    reference's in the study described by ``meta`` (study.json): the options the run
    recorded (``ran``, ``ran_options``: the kinematics that ran, "auto" resolved for the
    case's scene), else the model's options overridden by the case's grid values
    (``models.LABEL.kinematics``, ``.shapes``; one shape per rod where neither says). A run
    whose kinematics is left to "auto" (the default, ``auto_kinematics``: it depends on the
    case's scene) and has no record is no rung."""
    labels, ran = meta.get("labels", {}), ran or {}
    out = {}
    for m in meta["models"]:
        label = m["label"]
        if m["model"] != LADDER_MODEL or label == meta["reference"]:
            continue
        opts = m.get("options", {})
        for case in meta.get("cases", []):
            params = case.get("params", {})
            kin = params.get(labels.get(f"models.{label}.kinematics"), opts.get("kinematics"))
            p = params.get(labels.get(f"models.{label}.shapes"), opts.get("shapes"))
            record = ran.get((str(case["id"]), label), {})
            kin, p = record.get("kinematics", kin), record.get("shapes", p)
            if kin in KINEMATICS:
                out[(str(case["id"]), label)] = (
                    str(kin),
                    int(p if p is not None else PAPER_RUNG[0]),
                )
    return out


def has_ladder(meta: dict[str, Any], runtime: pd.DataFrame | None = None) -> bool:
    """Whether the study described by ``meta`` (and its runs' records, ``runtime``) runs the
    rungs the split needs (first-order p = 1, exact p = 1 and an exact p > 1 of the full
    model, the reference aside)."""
    return ladder_p_max(set(ladder_rungs(meta, ran_options(runtime)).values())) is not None


def _base_paths(meta: dict[str, Any]) -> list[str]:
    """The grid paths that set the base (``scene.base``, ``scene.base.KEY``)."""
    return [p for p in meta.get("labels", {}) if p == "scene.base" or p.startswith("scene.base.")]


def _base_kind(params: dict[str, Any], meta: dict[str, Any]) -> str | None:
    """A case's base kind from its grid values: ``scene.base.kind``, or the kind of a
    ``scene.base`` table ("pinned" when it names none); None when the case sets neither."""
    labels = meta.get("labels", {})
    kind = params.get(labels.get("scene.base.kind"))
    if kind is not None:
        return str(kind)
    table = params.get(labels.get("scene.base"))
    if isinstance(table, dict):
        return str(table.get("kind", "pinned"))
    return None


def error_budget(
    disc: pd.DataFrame, meta: dict[str, Any], runtime: pd.DataFrame | None = None
) -> pd.DataFrame | None:
    """The error budget of a study (``split_gaps``) from its discrepancies table ``disc``
    (``discrepancies.csv``: the gap of a run is its ``max_abs`` against the reference, over
    all output times and rods, where ``status`` is "ok") and its description ``meta``
    (study.json) and the options each run recorded (``runtime``: runtime.csv; which run is
    which rung, ``ladder_rungs``). The group of a case is its n,
    horizon and grid values, the rungs' own axes aside; its base kind (column ``base_kind``,
    when some case sets it) is read from the grid (``scene.base.kind`` or a ``scene.base``
    table). None when the study does not run the
    rungs the split needs (``has_ladder``)."""
    rungs = ladder_rungs(meta, ran_options(runtime))
    if ladder_p_max(set(rungs.values())) is None:
        return None
    axes = axis_columns(meta)
    rung_labels = {
        meta["labels"][p]
        for m in meta["models"]
        for p in (f"models.{m['label']}.kinematics", f"models.{m['label']}.shapes")
        if p in meta["labels"]
    }
    base_labels = {meta["labels"][p] for p in _base_paths(meta)}
    kind_label = meta["labels"].get("scene.base.kind")  # the base_kind column says it
    skip = {*rung_labels, kind_label}
    by = ["n", "horizon", *(col for lab, col in axes.items() if lab not in skip)]
    by = [c for c in by if c in disc.columns]
    base_columns = [axes[lab] for lab in base_labels if lab in axes]
    params = {c["id"]: c.get("params", {}) for c in meta.get("cases", [])}
    kinds = {cid: _base_kind(p, meta) for cid, p in params.items()}
    varies = any(k is not None for k in kinds.values())
    rows = []
    for rec in disc.to_dict("records"):
        rung = rungs.get((str(rec["case"]), str(rec["model"])))
        if rung is None:
            continue
        ok = rec.get("status") == "ok"
        rows.append(
            {
                **{c: rec[c] for c in by},
                **({"base_kind": kinds.get(str(rec["case"]))} if varies else {}),
                "kinematics": rung[0],
                "shapes": rung[1],
                "quantity": rec["quantity"],
                "gap": float(rec["max_abs"]) if ok else math.nan,
            }
        )
    if not rows:
        return None
    return split_gaps(pd.DataFrame(rows), by=by, base_columns=base_columns)
