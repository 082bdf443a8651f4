"""The Answer a study that compares models opens with (``answer_section``): each model's
verdict against the reference, its agreement horizon, parting lock and its measured cause,
worst lock gaps and run time (``rodval.analysis.agreement``), the reference's verdict in one
sentence for the study, and beyond the horizon the deployed state (or the latches that never
locked). ``rodval.report.study_summary.opening_section`` chooses it when a study has two or
more models."""

from __future__ import annotations

from typing import Any

import pandas as pd

from rodval.analysis.agreement import (
    AgreementSettings,
    agreement_table,
    latch_hinges,
    twin_label,
)
from rodval.report.markdown import to_markdown
from rodval.report.tables import drop_constant

#: How many worst cases a sampled study's report lists per table.
WORST_CASES = 5


#: A study of more cases than this (or a sampled one) gets the answer per model over its
#: cases (percentiles and the worst case), not one row per case.
MAX_ANSWER_CASES = 12


def answer_section(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame
) -> list[str]:
    """The answer of a study that compares models: a paragraph and one short table, model by
    model, from the runs (``rodval.analysis.agreement.agreement_table``): valid or out of
    domain and why, the agreement horizon, the first lock where it parts and the measured
    cause, the worst lock-time and impulse gaps, the run time (markdown lines; none when no
    run is compared with the reference)."""
    lines = agreement_lines(meta, tables, events)
    return ["## Answer\n", *lines] if lines else []


def agreement_lines(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame
) -> list[str]:
    """``answer_section``'s lines below its heading; none when the agreement table holds no
    run but the reference's (nothing is compared)."""
    ref = meta["reference"]
    settings = AgreementSettings.from_dict(meta.get("agreement"))
    table = agreement_table(
        tables["trajectories"],
        events,
        tables["runtime"],
        ref,
        settings,
        latch_hinges(tables["cases"]),
    )
    if table.empty or (table["role"] == "reference").all():
        return []
    lines = [_definition(settings, ref)]
    if meta.get("sample") or table["case"].nunique() > MAX_ANSWER_CASES:
        lines += _answer_over_cases(table, ref)
    else:
        lines += [" ".join(_sentences(table, ref, settings)) + "\n"]
        lines.append(
            to_markdown(
                _deployed_shown(drop_constant(_answer_rows(table, settings, ref), ("case",)))
            )
        )
    return lines


def _definition(settings: AgreementSettings, ref: str) -> str:
    """The sentence that states the tolerances the answer uses."""
    bars = [
        f"{name} {value:g}{unit}"
        for name, value, unit in (
            ("scale fraction", settings.reference_rel, ""),
            ("lock time", settings.reference_dt, " s"),
            ("impulse fraction", settings.reference_impulse, ""),
        )
        if value > 0
    ]
    bar = f" plus the reference's own error bar ({', '.join(bars)})" if bars else ""
    twin = settings.twin
    twin_text = (
        f" The twin run `{twin_label(ref)}` is `{ref}` with the initial chord angle of rod "
        f"{twin['rod']} moved by {twin['angle']:g} rad; its horizon is the predictability "
        "horizon."
        if twin
        else " No twin run ([agreement.twin]): whether the motion is predictable is not measured."
    )
    return (
        f"A model agrees with `{ref}` until the first output time where "
        f"max_k |q - q_ref| exceeds {settings.tol:g} x the largest |q_ref| for "
        f"{', '.join(f'`{q}`' for q in settings.quantities)}{bar}; it parts at a lock that it "
        f"lacks, reaches out of order or more than {settings.lock_dt * 1e3:g} ms from the "
        f'reference\'s (docs/deployment.md, "The answer").{twin_text}\n'
    )


def _verdict(row: pd.Series) -> str:
    """A run's verdict in words."""
    if row["status"] != "success":
        return f"failed ({row['status']})"
    if row["out_of_domain"]:
        return f"out of domain: {row['out_of_domain']}"
    return "valid" if row["valid"] is not False else "invalid"


def _until(row: pd.Series, ref_row: pd.Series | None = None) -> str:
    """Its agreement horizon in words; a pair compared only up to where one of its runs
    failed (the run or the reference, ``ref_row``) agrees until that failure, never 'the
    end'."""
    if row["role"] == "reference":
        return "(reference)"
    if pd.isna(row["compared_to"]):
        return "not compared"
    if pd.isna(row["horizon"]) and row["status"] != "success":
        return f"its failure at t = {row['compared_to']:.4g} s (the run ends there)"
    if pd.isna(row["horizon"]) and ref_row is not None and ref_row["status"] != "success":
        return f"the reference's failure at t = {row['compared_to']:.4g} s (compared that far)"
    if pd.isna(row["horizon"]):
        return f"the end ({row['compared_to']:.4g} s)"
    return f"t = {row['horizon']:.4g} s ({row['horizon_quantity']})"


def _ms(dt: float) -> str:
    return f"{dt * 1e3:+.3g} ms"


def _parts(row: pd.Series) -> str:
    """Its parting lock in words."""
    if not row["part_lock"] or pd.isna(row["part_lock"]):
        return "" if row["role"] == "reference" else "none"
    dt = "" if pd.isna(row["part_dt"]) else f", {_ms(row['part_dt'])}"
    return f"{row['part_lock']} ({row['part_why']}{dt})"


def _worst(row: pd.Series) -> tuple[str, str]:
    """Its worst lock-time and impulse gaps in words."""
    dt = "" if pd.isna(row["worst_dt"]) else f"{_ms(row['worst_dt'])} ({row['worst_dt_lock']})"
    imp = (
        ""
        if pd.isna(row["worst_impulse_rel"])
        else f"{row['worst_impulse_rel'] * 100:.3g} % ({row['worst_impulse_lock']})"
    )
    return dt, imp


def _deployed_shown(rows: pd.DataFrame) -> pd.DataFrame:
    """The answer's table without its ``deployed`` column when no run says "no" there (every
    latch locked in every run, or no latches): a column that would only say "yes"."""
    if rows["deployed"].str.startswith("no").any():
        return rows
    return rows.drop(columns="deployed")


def _deployed(row: pd.Series) -> str:
    """Whether the run deployed: "yes" when every latch of its case locked, "no: ..." naming
    those that never locked, "" for a case without latches."""
    missed = row.get("never_locked")
    if not isinstance(missed, str):
        return ""
    return f"no: {missed} never locked" if missed else "yes"


def _undeployed(row: pd.Series) -> str:
    """ ", not deployed: ... never locked within its run" for a run with a latch that never
    locked, else ""."""
    missed = row.get("never_locked")
    if not _filled(missed):
        return ""
    return f", not deployed: {missed} never locked within its run"


def _reference_row(table: pd.DataFrame, row: pd.Series, ref: str) -> pd.Series | None:
    """The reference's row of ``row``'s case in the agreement table (None when it has none)."""
    same = table[(table["case"] == row["case"]) & (table["model"] == ref)]
    return same.iloc[0] if len(same) else None


def _beyond(row: pd.Series, ref_row: pd.Series | None = None) -> str:
    """What stays meaningful beyond the horizon, in words: the lock order, the locks within
    the lock-time bound, the deployed state's gaps against the reference's bands (rad); a
    latch that never locked in the run or in the reference (``ref_row``) makes the state
    after the last lock a partly deployed one, and says so."""
    parts = []
    missed = {
        who: r["never_locked"]
        for who, r in (("this run", row), ("the reference", ref_row))
        if r is not None and _filled(r.get("never_locked"))
    }
    what = "deployed {}" if not missed else "{} after the last lock (not deployed)"
    order = row.get("lock_order")
    if _filled(order):
        parts.append("lock order the same" if order == "same" else f"lock order differs ({order})")
    if _filled(row.get("locks_within")):
        parts.append(f"{row['locks_within']} locks within the lock-time bound")
    for gap, band, name in (
        ("deployed_gap", "deployed_band", what.format("angles")),
        ("attitude_gap", "attitude_band", what.format("attitude")),
    ):
        if pd.notna(row.get(gap)):
            within = (
                f" (band {row[band]:.2g} rad: {'within' if row[gap] <= row[band] else 'outside'})"
                if pd.notna(row.get(band)) and row[band] > 0
                else ""
            )
            parts.append(f"{name} {row[gap]:.2g} rad off{within}")
    if len(set(missed.values())) == 1 and len(missed) == 2:
        parts.append(f"{missed['this run']} never locked in either run")
    elif missed:
        parts.append(", ".join(f"{what} never locked in {who}" for who, what in missed.items()))
    return "; ".join(parts)


def _filled(value: Any) -> bool:
    """Whether a text cell holds text."""
    return isinstance(value, str) and bool(value)


def _answer_rows(table: pd.DataFrame, settings: AgreementSettings, ref: str) -> pd.DataFrame:
    """The short table: one row per case and run."""
    rows = []
    for _, row in table.iterrows():
        dt, imp = _worst(row)
        rows.append(
            {
                "case": row["case"],
                "model": row["model"],
                "verdict": _verdict(row),
                "agrees until": _until(row, _reference_row(table, row, ref)),
                "first lock where it parts": _parts(row),
                "cause": row["cause"] if isinstance(row["cause"], str) else "",
                "worst lock dt": dt,
                "worst impulse gap": imp,
                "deployed": _deployed(row),
                "beyond the horizon": ""
                if row["role"] == "reference"
                else _beyond(row, _reference_row(table, row, ref)),
                "run time": f"{row['wall_s']:.3g} s",
            }
        )
    out = pd.DataFrame(rows)
    if settings.reference_dt > 0 or settings.reference_impulse > 0:
        out["reference error bar"] = (
            f"{settings.reference_dt * 1e3:g} ms, {settings.reference_impulse:.1%}"
        )
    return out


def _sentences(table: pd.DataFrame, ref: str, settings: AgreementSettings) -> list[str]:
    """The opening paragraph's sentences, with the figures: one for the reference (over
    several cases one for the study, ``_reference_sentence``), then one per compared run."""
    many = table["case"].nunique() > 1
    refs = table[table["role"] == "reference"]
    out = [_reference_sentence(refs, settings)] if many and len(refs) else []
    for _, row in table.iterrows():
        name = f"`{row['model']}`" + (f" (case `{row['case']}`)" if many else "")
        verdict = _verdict(row)
        if row["role"] == "reference":
            if not many:
                out.append(
                    f"The reference {name} is {verdict}{_error_bar(settings)}"
                    f"{_undeployed(row)} (run time {row['wall_s']:.3g} s)."
                )
            continue
        ref_row = _reference_row(table, row, ref)
        until = _until(row, ref_row)
        head = f"{name} is {verdict}{_undeployed(row)}; it agrees with `{ref}` until {until}"
        if row["role"] == "twin":
            dt, _ = _worst(row)
            moved = f" and moves the locks by at most {dt}" if dt else ""
            horizon = (
                "it has no predictability horizon within the run"
                if pd.isna(row["horizon"])
                else "that is the predictability horizon"
            )
            out.append(f"{head}: {horizon}{moved}.")
            continue
        parts = _parts(row)
        text = head + (
            f", parts first at {parts}: {row['cause']}" if parts != "none" else ", at every lock"
        )
        dt, imp = _worst(row)
        if dt:
            text += f"; worst lock-time gap {dt}, impulse gap {imp or 'n/a'}"
        beyond = _beyond(row, ref_row)
        if beyond and (parts != "none" or not pd.isna(row["horizon"])):
            text += f"; beyond: {beyond}"
        out.append(f"{text}; run time {row['wall_s']:.3g} s.")
    return out


def _reference_sentence(refs: pd.DataFrame, settings: AgreementSettings) -> str:
    """The reference's one sentence over the cases of its rows ``refs`` (agreement table
    rows, one per case): in how many it is valid (the others named with their verdict), its
    error bar, the cases where it is not deployed and which latches never locked there, its
    median and longest run time."""
    verdicts = [_verdict(row) for _, row in refs.iterrows()]
    cases = refs["case"].astype(str).tolist()
    valid = sum(v == "valid" for v in verdicts)
    others = [f"{v} in `{c}`" for c, v in zip(cases, verdicts) if v != "valid"]
    text = f"The reference `{refs['model'].iloc[0]}` is valid in {valid} of {len(refs)} cases"
    if others:
        text += f" ({first_of(others)})"
    text += _error_bar(settings)
    missed = [
        f"`{c}` ({m} never locked within its run)"
        for c, m in zip(cases, refs["never_locked"])
        if _filled(m)
    ]
    if missed:
        text += f", not deployed in {len(missed)} of {len(refs)}: {first_of(missed)}"
    slow = refs.loc[refs["wall_s"].idxmax()] if refs["wall_s"].notna().any() else None
    if slow is not None:
        text += (
            f" (run time median {refs['wall_s'].median():.3g} s, longest "
            f"{slow['wall_s']:.3g} s in `{slow['case']}`)"
        )
    return text + "."


def first_of(items: list[str], shown: int = WORST_CASES) -> str:
    """The first ``shown`` of ``items`` joined, and how many more there are."""
    more = len(items) - shown
    return ", ".join(items[:shown]) + (f" and {more} more" if more > 0 else "")


def _error_bar(settings: AgreementSettings) -> str:
    """The reference's measured error bar in words (the study's ``[agreement]
    reference_error``), "" when the study gives none."""
    parts = [
        text
        for value, text in (
            (settings.reference_dt, f"its locks to {settings.reference_dt * 1e3:.3g} ms"),
            (settings.reference_impulse, f"their impulses to {settings.reference_impulse:.2%}"),
            (settings.reference_rel, f"the angles to {settings.reference_rel:.2%} of their scale"),
            (
                settings.reference_attitude,
                f"the deployed attitude to {settings.reference_attitude:.2g} rad",
            ),
        )
        if value > 0
    ]
    if not parts:
        return ", its error bar not given ([agreement] reference_error)"
    return ", its error bar measured by refining it ([agreement] reference_error): " + ", ".join(
        parts
    )


def _answer_over_cases(table: pd.DataFrame, ref: str) -> list[str]:
    """The answer of a study of many cases: per run label, over the cases, how many valid,
    the agreement horizon's percentiles and its worst case, how many part at a lock, the
    causes by kind, the worst gaps with their cases, the median run time."""
    rows, sentences = [], []
    for model, part in table.groupby("model", sort=False):
        n = len(part)
        valid = int((part["valid"] == True).sum())  # noqa: E712 - None is not valid
        row: dict[str, Any] = {"model": model, "cases": n, "valid": f"{valid}/{n}"}
        latched = part["never_locked"].map(lambda v: isinstance(v, str))
        deployed = ""
        if latched.any():
            done = int((part.loc[latched, "never_locked"] == "").sum())
            row["deployed"] = f"{done}/{int(latched.sum())}"
            deployed = f", deployed (every latch locked) in {done} of {int(latched.sum())}"
        if (part["role"] != "reference").any():
            h = part["horizon"].fillna(part["compared_to"])
            worst = part.loc[h.idxmin()] if h.notna().any() else None
            row["agrees until p5 / p50 (s)"] = (
                f"{h.quantile(0.05):.4g} / {h.median():.4g}" if h.notna().any() else ""
            )
            row["shortest (case)"] = "" if worst is None else f"{h.min():.4g} s ({worst['case']})"
            parted = part[part["part_lock"].fillna("") != ""]
            row["parts at a lock"] = f"{len(parted)}/{n}"
            kinds = parted["cause"].fillna("").str.split(" \\(|;").str[0].value_counts()
            row["causes"] = ", ".join(f"{k}: {v}" for k, v in kinds.items() if k)
            for col, label, fmt in (
                ("worst_dt", "worst lock dt (case)", _ms),
                ("worst_impulse_rel", "worst impulse gap (case)", lambda x: f"{x:.1%}"),
            ):
                vals = part[col].abs()
                row[label] = (
                    f"{fmt(part.loc[vals.idxmax(), col])} ({part.loc[vals.idxmax(), 'case']})"
                    if vals.notna().any()
                    else ""
                )
        row["run time p50 (s)"] = f"{part['wall_s'].median():.3g}"
        rows.append(row)
        sentences.append(
            f"`{model}`: valid in {valid} of {n} cases{deployed}"
            + (
                f", agrees with `{ref}` until t = {row['shortest (case)']} at the shortest"
                f" (median {row['agrees until p5 / p50 (s)'].split(' / ')[-1]} s), parts at a "
                f"lock in {row['parts at a lock']} cases ({row['causes'] or 'no cause'})."
                if "parts at a lock" in row and row["shortest (case)"]
                else "."
            )
        )
    table = pd.DataFrame(rows).astype(object)
    return [" ".join(sentences) + "\n", to_markdown(table.where(table.notna(), ""))]
