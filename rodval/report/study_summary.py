"""The study report's summary sections, from the saved tables: the Answer it opens with
(``opening_section``): in a study that compares models, each model's verdict, agreement
horizon, parting lock and its measured cause, worst lock gaps and run time
(``answer_section``, ``rodval.analysis.agreement``; the reference's verdict in one sentence
for the study); in a study of one model, its verdict (``verdict_section``: the acceptance
gate, which requirement broke in which cases, how the runs ended and deployed, the design
quantities per hinge over the cases with their worst case), nothing compared; then the
Outcome (runs, failures, invalid runs, comparisons made and not made, by reason), the
Discrepancies against the reference, the Run time with speed-ups, and the Stability map."""

from __future__ import annotations

from typing import Any

import pandas as pd

from rodval.analysis.agreement import (
    AgreementSettings,
    agreement_table,
    check_names,
    latch_hinges,
    lock_list,
    never_locked,
    twin_label,
)
from rodval.analysis.metrics import left_out_quantities
from rodval.core.validity import ENERGY_RESIDUAL_BOUND, SMALL_BENDING_RAD
from rodval.report.acceptance import acceptance_checks
from rodval.report.figures import speedups
from rodval.report.markdown import to_markdown
from rodval.report.sample_stats import PERCENTILES, spread
from rodval.report.sensitivity import design_values
from rodval.report.tables import drop_constant, drop_study_constants


def left_out_table(traj: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Per case and model: the quantities left out of its comparison with the reference
    because only one of the two runs outputs them (``left_out_quantities``), with why.
    Columns case, model, quantity, why. O(rows of the trajectories table)."""
    have = traj.groupby(["case", "model"], sort=False)["quantity"].unique()
    rows = []
    for (case, model), qs in have.items():
        if model == reference or (case, reference) not in have.index:
            continue
        ref_qs = have[(case, reference)]
        for q in left_out_quantities(qs, ref_qs):
            lacking = model if q in ref_qs else reference
            rows.append(
                {"case": case, "model": model, "quantity": q, "why": f"not output by {lacking}"}
            )
    return pd.DataFrame(rows, columns=["case", "model", "quantity", "why"])


def summary_sections(
    meta: dict[str, Any],
    tables: dict[str, pd.DataFrame],
    params: list[str],
    constants: dict[str, Any] | None = None,
) -> list[str]:
    """Outcome, Discrepancies against the reference, Run time and, when a run failed or was
    audited for energy, the Stability map (markdown lines); ``params``: the cases' parameter
    columns, "-" where a union of grids ([[grid]]) leaves one unset; ``constants``: the
    columns constant over the study, left out of every table (``study_constants``). A
    sampled study's sections give distributions and the worst cases, not per-case rows
    (``_sampled_sections``)."""
    disc, runtime = (
        tables[k].fillna({p: "-" for p in params}) for k in ("discrepancies", "runtime")
    )
    ref = meta["reference"]
    failed = runtime[runtime["status"] != "success"]
    left = left_out_table(tables["trajectories"], ref)
    keep = dict(constants or {})
    one = len(meta["models"]) == 1
    lines = _outcome(disc, runtime, failed, left, keep, sampled=bool(meta.get("sample")), one=one)
    if meta.get("sample"):
        return lines + _sampled_sections(disc, runtime, ref, one)
    lines += _discrepancies(disc, left, ref, len(meta["models"]), params, keep)
    lines += _run_time(runtime, ref, params, keep, one)
    if not failed.empty or (
        "energy_residual" in runtime and runtime["energy_residual"].notna().any()
    ):
        lines += _stability_map(runtime, params, keep)
    return lines


#: How many worst cases a sampled study's report lists per table.
WORST_CASES = 5


def _sampled_sections(
    disc: pd.DataFrame, runtime: pd.DataFrame, ref: str, one: bool = False
) -> list[str]:
    """A sampled study's Discrepancies and Run time: the worst cases of each model and
    quantity (the percentiles are in Sample statistics) and the run time's percentiles per
    model; per-case values stay in discrepancies.csv and runtime.csv. ``one``: the study has
    one model (nothing to compare: said in one line)."""
    ok = disc[disc["status"] == "ok"]
    lines = [_one_model(ref)] if one else [f"## Discrepancies against `{ref}`\n"]
    if not ok.empty:
        idx = ok.groupby(["model", "quantity"], sort=False)["max_abs"].idxmax()
        worst = ok.loc[idx, ["model", "quantity", "case", "max_abs", "max_rel"]]
        lines += [
            "The case of largest `max_abs` per model and quantity (their percentiles over "
            "the samples: Sample statistics; every case: `discrepancies.csv`):\n",
            to_markdown(worst, ".3g"),
        ]
    done = runtime[runtime["status"] == "success"]
    rows = [
        {
            "model": model,
            "runs": len(part),
            **{f"wall_s p{p}": part["wall_s"].quantile(p / 100) for p in (5, 50, 95)},
            "wall_s max": part["wall_s"].max(),
            "slowest case": part.loc[part["wall_s"].idxmax(), "case"],
        }
        for model, part in done.groupby("model", sort=False)
    ]
    if rows:
        lines += [
            "## Run time\n",
            "Integration wall time (s) of the successful runs over the samples (every run: "
            "`runtime.csv`):\n",
            to_markdown(pd.DataFrame(rows), ".3g"),
        ]
    return lines


def _outcome(
    disc: pd.DataFrame,
    runtime: pd.DataFrame,
    failed: pd.DataFrame,
    left: pd.DataFrame,
    constants: dict[str, Any] | None = None,
    sampled: bool = False,
    one: bool = False,
) -> list[str]:
    """The Outcome section: counts of cases, runs, failed and invalid runs and comparisons
    (none counted in a study of ``one`` model), the comparisons not made by reason, the
    failed runs and the invalid runs (of a sampled study: counted by model and reason, the
    first WORST_CASES failed runs listed)."""
    invalid = runtime[runtime["valid"].astype(str) == "False"] if "valid" in runtime else failed[:0]
    not_made = disc[disc["status"] != "ok"]
    compared = (
        ""
        if one
        else f"; {(disc['status'] == 'ok').sum()} comparisons made (case, model, quantity), "
        f"{len(not_made) + len(left)} could not be made"
    )
    lines = [
        f"## Outcome\n\n{runtime['case'].nunique()} cases, {len(runtime)} model runs, "
        f"{len(failed)} failed, {len(invalid)} invalid{compared}.\n"
    ]
    reasons = pd.concat(
        [not_made[["status"]], pd.DataFrame({"status": left["why"]}) if len(left) else None]
    )
    if len(reasons):
        why = (
            reasons.groupby("status", sort=False)
            .size()
            .reset_index(name="comparisons")
            .rename(columns={"status": "reason"})
        )
        lines += ["Comparisons not made, by reason:\n", to_markdown(why)]
    if not failed.empty:
        shown = failed.head(WORST_CASES) if sampled else failed
        more = len(failed) - len(shown)
        lines += [
            "Failed runs"
            + (f" (the first {len(shown)}; {more} more in `runtime.csv`)" if more else "")
            + ":\n",
            to_markdown(
                drop_study_constants(
                    shown[["case", "model", "status", "t_reached", "message"]], constants or {}
                )
            ),
        ]
    lines.append(
        "Validity: a run is invalid when it broke an assumption of its model (small bending, "
        f"largest |alpha|, |beta| <= {SMALL_BENDING_RAD:g} rad, in the paper models; an "
        f"energy-audit residual <= {ENERGY_RESIDUAL_BOUND:g} where audited; see "
        "docs/stability.md), whether or not it reached its end; its results are not those of "
        "the model's premise." + (" Invalid runs:\n" if len(invalid) else "\n")
    )
    if len(invalid) and sampled:
        counts = (
            invalid.assign(check=invalid["invalid_because"].map(check_names))
            .groupby(["model", "check"], sort=False)
            .size()
            .reset_index(name="runs")
        )
        lines.append(to_markdown(counts))
    elif len(invalid):
        cols = ["case", "model", "status", "invalid_because"]
        lines.append(to_markdown(drop_study_constants(invalid[cols], constants or {})))
    return lines


def _discrepancies(
    disc: pd.DataFrame,
    left: pd.DataFrame,
    ref: str,
    models: int,
    params: list[str],
    constants: dict[str, Any] | None = None,
) -> list[str]:
    """The Discrepancies section: per model, max_abs and max_rel of each quantity against
    the reference ``ref`` per case, and the quantities left out of the comparison
    (``models``: how many models the study has)."""
    if models == 1:
        return [_one_model(ref)]
    lines = [
        f"## Discrepancies against `{ref}`\n",
        "Largest absolute difference over all output times and rods (`max_abs`; rad, "
        "rad/s) and the same relative to each reference rod's largest value "
        "(`max_rel`); see `discrepancies.csv` for rms, final value and where the "
        "maximum occurs.\n",
    ]
    for model, part in disc.groupby("model", sort=False):
        ok = part[part["status"] == "ok"]
        lines.append(f"### `{model}` against `{ref}`\n")
        if ok.empty:
            lines.append(f"_No comparison: {part['status'].iloc[0]}._\n")
            continue
        mine = left[left["model"] == model] if len(left) else left
        if len(mine):
            names = ", ".join(
                f"`{q}` ({w})" for q, w in dict.fromkeys(zip(mine["quantity"], mine["why"]))
            )
            lines.append(
                f"_Left out of this comparison: {names}; the other quantities are compared._\n"
            )
        wide = ok.pivot_table(
            index=["case", *params], columns="quantity", values=["max_abs", "max_rel"], sort=False
        )
        wide.columns = [f"{q} {m}" for m, q in wide.columns]
        order = [f"{q} {m}" for q in dict.fromkeys(ok["quantity"]) for m in ("max_abs", "max_rel")]
        # reindex: a quantity whose reference is zero throughout (the work of a scene without
        # loads) has no max_rel, a column pivot_table drops; it stays, blank
        table = wide.reindex(columns=order).reset_index()
        lines.append(to_markdown(drop_study_constants(table, constants or {})))
    return lines


def _one_model(label: str) -> str:
    """The Discrepancies section of a study of one model (``label``)."""
    return f"## Discrepancies\n\nThe study has one model (`{label}`): nothing to compare.\n"


def _run_time(
    runtime: pd.DataFrame,
    ref: str,
    params: list[str],
    constants: dict[str, Any] | None = None,
    one: bool = False,
) -> list[str]:
    """The Run time section: each successful run's integration wall time (s) per case and
    model, and each model's speed-up against the reference ``ref`` (none in a study of
    ``one`` model)."""
    ok = runtime[runtime["status"] == "success"]
    wall = ok.pivot_table(index=["case", *params], columns="model", values="wall_s", sort=False)
    speed = speedups(runtime, ref, params)
    if not speed.empty:
        sp = speed.pivot_table(
            index=["case", *params], columns="model", values="speedup", sort=False
        )
        wall = wall.join(sp.add_prefix("speed-up "))
    return [
        "## Run time\n",
        "Integration wall time in s (without model set-up)"
        + ("" if one else f"; speed-up = wall time of `{ref}` / wall time of the model")
        + ".\n",
        "Failed runs are left out.\n",
        to_markdown(drop_study_constants(wall.reset_index(), constants or {})),
    ]


def _stability_map(
    runtime: pd.DataFrame, params: list[str], constants: dict[str, Any] | None = None
) -> list[str]:
    """Case x model: how each run ended, its cost and (when audited) its energy residual."""

    def cell(row: pd.Series) -> str:
        """One run's cell: status, wall time (s), time reached (s), energy residual."""
        text = f"{row['status']}, {row['wall_s']:.3g} s"
        if row["status"] != "success":
            text += f", t = {row['t_reached']:.3g} s"
        res = row.get("energy_residual")
        if res is not None and pd.notna(res):
            text += f", R = {res:.2g}"
        return text

    grid = runtime.assign(cell=runtime.apply(cell, axis=1)).pivot_table(
        index=["case", *params], columns="model", values="cell", aggfunc="first", sort=False
    )
    return [
        "## Stability map\n",
        "Each run: status, integration wall time, the time reached if it did not finish, "
        "and R = max |E - E(0) - W_ext + D| / max(E, |W_ext|), the energy balance "
        "residual (see docs/stability.md), when the scene asks for energy.\n",
        to_markdown(drop_study_constants(grid.reset_index(), constants or {})),
    ]


# ---- the answer the report opens with ----------------------------------------------------

#: A study of more cases than this (or a sampled one) gets the answer per model over its
#: cases (percentiles and the worst case), not one row per case.
MAX_ANSWER_CASES = 12


def opening_section(
    meta: dict[str, Any],
    tables: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    peaks: pd.DataFrame,
) -> list[str]:
    """The report's opening, its answer (markdown lines): with two or more models, each
    against the reference (``answer_section``); with one, its verdict (``verdict_section``:
    the acceptance gate, the runs, the quantities of interest over the cases; ``peaks``: the
    report's peak hinge moments, ``rodval.report.study_report.peak_hinge_moments``) and,
    when the study runs the model's twin ([agreement.twin]), the one comparison there is:
    how long the twin agrees with it."""
    if len(meta["models"]) > 1:
        return answer_section(meta, tables, events)
    twin = _agreement_lines(meta, tables, events)
    label = meta["models"][0]["label"]
    head = [f"### `{label}` against its twin run\n"] if twin else []
    return [*verdict_section(meta, tables, events, peaks), *head, *twin]


def answer_section(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame
) -> list[str]:
    """The answer of a study that compares models: a paragraph and one short table, model by
    model, from the runs (``rodval.analysis.agreement.agreement_table``): valid or out of
    domain and why, the agreement horizon, the first lock where it parts and the measured
    cause, the worst lock-time and impulse gaps, the run time (markdown lines; none when no
    run is compared with the reference)."""
    lines = _agreement_lines(meta, tables, events)
    return ["## Answer\n", *lines] if lines else []


def _agreement_lines(
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


def _until(row: pd.Series) -> str:
    """Its agreement horizon in words."""
    if row["role"] == "reference":
        return "(reference)"
    if pd.isna(row["compared_to"]):
        return "not compared"
    if pd.isna(row["horizon"]) and row["status"] != "success":
        return f"its failure at t = {row['compared_to']:.4g} s (the run ends there)"
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
                "agrees until": _until(row),
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
        head = f"{name} is {verdict}{_undeployed(row)}; it agrees with `{ref}` until {_until(row)}"
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
        beyond = _beyond(row, _reference_row(table, row, ref))
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
        text += f" ({_first(others)})"
    text += _error_bar(settings)
    missed = [
        f"`{c}` ({m} never locked within its run)"
        for c, m in zip(cases, refs["never_locked"])
        if _filled(m)
    ]
    if missed:
        text += f", not deployed in {len(missed)} of {len(refs)}: {_first(missed)}"
    slow = refs.loc[refs["wall_s"].idxmax()] if refs["wall_s"].notna().any() else None
    if slow is not None:
        text += (
            f" (run time median {refs['wall_s'].median():.3g} s, longest "
            f"{slow['wall_s']:.3g} s in `{slow['case']}`)"
        )
    return text + "."


def _first(items: list[str], shown: int = WORST_CASES) -> str:
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


# ---- the verdict a one-model study opens with ---------------------------------------------


def verdict_section(
    meta: dict[str, Any],
    tables: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    peaks: pd.DataFrame,
) -> list[str]:
    """A one-model study's answer (markdown lines): the acceptance gate's verdict
    (``_gate_sentence``), how the runs ended and whether they deployed (``_runs_sentence``),
    and the design quantities (``rodval.report.sensitivity.design_values``: lock time, lock
    impulse and peak hinge moment per hinge, a free base's attitude at t_end) over the cases:
    min, PERCENTILES, max and the worst case (``_quantities_lines``; ``peaks``: the report's
    peak hinge moments). Nothing in it compares models: there is one."""
    label = meta["models"][0]["label"]
    runtime = tables["runtime"][tables["runtime"]["model"] == label]
    values = design_values({**tables, "events": events, "peaks": peaks})
    values = values[values["model"] == label]
    mine = peaks[peaks["model"] == label] if "model" in peaks else peaks
    return [
        "## Answer\n",
        _gate_sentence(meta, tables, events),
        _runs_sentence(label, runtime, latch_hinges(tables["cases"]), events, values),
        *_quantities_lines(values, mine, runtime["case"].astype(str).tolist()),
    ]


def _gate_sentence(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame
) -> str:
    """The acceptance verdict in one paragraph (``rodval.report.acceptance``): PASSED with
    the number of checks, or FAILED with each broken requirement, the cases it broke in and
    the figure against the bound; without an [acceptance] table, that none was set."""
    if not meta.get("acceptance"):
        return "Acceptance: no [acceptance] in the study, so no gate was set.\n"
    checks = acceptance_checks(meta, tables, events)
    broken = [c for c in checks if not c.held]
    if not broken:
        return f"**Acceptance: PASSED** ({len(checks)} checks of the study's [acceptance]).\n"
    cases = sorted(tables["cases"]["case"].astype(str), key=len, reverse=True)
    by_requirement: dict[str, list[str]] = {}
    for c in broken:
        case = next((k for k in cases if c.name.startswith(f"{k}: ")), "")
        what = c.name.removeprefix(f"{case}: ") if case else c.name
        by_requirement.setdefault(what, []).append(f"`{case}`: {c.failure}" if case else c.failure)
    parts = [
        f"`{what}` in {len(where)} of {len(cases)} cases ({_first(where, 3)})"
        if where[0].startswith("`")
        else f"`{what}` ({where[0]})"
        for what, where in by_requirement.items()
    ]
    return (
        f"**Acceptance: FAILED**, {len(broken)} of {len(checks)} checks broke: "
        f"{'; '.join(parts[:WORST_CASES])}"
        + (f"; {len(parts) - WORST_CASES} more requirements" if len(parts) > WORST_CASES else "")
        + " (every breach: Acceptance below).\n"
    )


def _runs_sentence(
    label: str,
    runtime: pd.DataFrame,
    latches: dict[Any, list[int]],
    events: pd.DataFrame,
    values: pd.DataFrame,
) -> str:
    """How the model's runs (``runtime``: its runtime.csv rows) ended (a failed run named
    with its status, time reached and message), how many are invalid and why, in how many
    cases every latch locked (``latches``: case -> latched hinges) and which latches never
    locked where not, and a free base's attitude at t_end over the cases (``values``)."""
    n = len(runtime)
    ok = runtime[runtime["status"] == "success"]
    text = f"`{label}` over {n} case{'s' if n > 1 else ''}: {len(ok)} of {n} runs reached t_end"
    failed = [
        f"`{r['case']}` ({r['status']} at t = {r['t_reached']:.4g} s: {r['message']})"
        for _, r in runtime[runtime["status"] != "success"].iterrows()
    ]
    if failed:
        text += f"; failed: {_first(failed)}"
    invalid = runtime[runtime["valid"].astype(str) == "False"] if "valid" in runtime else ok[:0]
    why = [f"`{c}` ({check_names(w)})" for c, w in zip(invalid["case"], invalid["invalid_because"])]
    text += f"; {len(invalid)} invalid: {_first(why)}" if why else "; none invalid"
    latched = [c for c in runtime["case"] if latches.get(c)]
    if latched:
        missed = {c: never_locked(latches[c], lock_list(events, c, label)) for c in latched}
        undeployed = [f"`{c}` ({m} never locked within its run)" for c, m in missed.items() if m]
        text += (
            f"; deployed (every latch locked) in {len(latched) - len(undeployed)} of {len(latched)}"
        )
        if undeployed:
            text += f", not deployed in {_first(undeployed)}"
    attitude = values[values["quantity"] == "final_attitude"]
    if not attitude.empty:
        s = spread(attitude["value"], attitude["case"], absolute=True)
        if s["count"]:
            text += (
                f"; the free base's attitude at t_end (rad) {_cell(s, n)}, largest |attitude| "
                f"{_worst_of(s)}"
            )
    return text + ".\n"


#: The opening table's quantities per hinge: (design quantity, column, worst-case column);
#: each shown by its absolute value (no "|" in a column name: it would split the table).
OPENING_QUANTITIES = (
    ("t_lock", "lock time (s)", "latest (case)"),
    ("impulse", "lock impulse, absolute (N m s)", "largest (case)"),
    ("peak_moment", "peak hinge moment (N m)", "highest (case)"),
)


def _quantities_lines(values: pd.DataFrame, peaks: pd.DataFrame, cases: list[str]) -> list[str]:
    """The opening's table: per hinge, each quantity of OPENING_QUANTITIES over the
    ``cases`` (``values``: ``design_values`` of the one model) as min / p5 / p50 / p95 / max
    and its worst case; a hinge whose moment is an impulse at its lock (``peaks``' blank
    peak beside an ``impulse``) says in how many cases; a peak read on the output times only
    (``peaks``' source ``hinge_moment``: runtime.csv recorded none) says so."""
    n = len(cases)
    per_hinge = values[values["quantity"] != "final_attitude"]
    if per_hinge.empty:
        return []
    rows = []
    for k in sorted(set(per_hinge["k"].astype(int))):
        row: dict[str, Any] = {"hinge": k}
        for q, column, worst in OPENING_QUANTITIES:
            part = per_hinge[(per_hinge["quantity"] == q) & (per_hinge["k"] == k)]
            s = spread(part["value"].abs(), part["case"])
            row[column] = _cell(s, n)
            row[worst] = _worst_of(s)
        if "impulse" in peaks:
            mine = peaks[peaks["hinge"] == k]
            dirac = int((mine["peak_moment"].isna() & mine["impulse"].notna()).sum())
            if dirac:
                note = f"impulsive at its lock in {dirac} of {n}"
                cell = row[OPENING_QUANTITIES[2][1]]
                row[OPENING_QUANTITIES[2][1]] = f"{cell}; {note}" if cell else note
        rows.append(row)
    table = pd.DataFrame(rows)
    table = table[[c for c in table.columns if (table[c] != "").any()]]
    if n == 1:
        table = table.drop(columns=[w for _, _, w in OPENING_QUANTITIES if w in table])
    over = (
        "The model's results"
        if n == 1
        else (
            f"Over the {n} cases, per hinge: {SPREAD_NAMES} of each quantity over "
            "the cases that have it (k of N when fewer: a latch that did not lock, a run that "
            "failed) and its worst case (the latest lock, the largest |impulse|, the highest "
            "peak)"
        )
    )
    notes = [
        "the lock time and impulse are events.csv's first lock of the hinge (the impulse "
        "over its lock window, docs/deployment.md)",
        _peak_note(peaks),
    ]
    return [f"{over}; {'; '.join(notes)}:\n", to_markdown(table)]


def _peak_note(peaks: pd.DataFrame) -> str:
    """Where the opening's peak hinge moments come from (``peaks``' ``source``), in words:
    the peak each run recorded between its output times, or, for a run that recorded none,
    the output times' largest |hinge_moment|, said so; and why a locked hinge may have none."""
    source = peaks["source"] if "source" in peaks else pd.Series(dtype=object)
    if source.empty:
        return "no peak hinge moment: `hinge_moment` is not among the [scene] outputs"
    grid = "the largest |hinge_moment| over the output times of trajectories.csv only"
    recorded = "each run's recorded peak (runtime.csv's `peaks`, read between the output times)"
    if (source == "hinge_moment").all():
        text = f"the peak is {grid} (the runs recorded none)"
    elif (source == "hinge_moment").any():
        text = f"the peak is {recorded}, else, for the runs that recorded none, {grid}"
    else:
        text = f"the peak is {recorded}"
    if "impulse" in peaks and peaks["impulse"].notna().any():
        text += (
            "; an ideal latch on rigid chords (the reduced and rigid models) makes a locked "
            "hinge's moment an impulse at the lock: no finite peak"
        )
    return text


#: How ``_cell`` lists a distribution.
SPREAD_NAMES = " / ".join(["min", *(f"p{p}" for p in PERCENTILES), "max"])


def _cell(s: dict[str, Any], cases: int) -> str:
    """A distribution (``spread``) as SPREAD_NAMES say, min / p5 / p50 / p95 / max (the value
    alone when there is one), "k of N" when fewer than the ``cases`` have a value; "" without
    one."""
    if not s["count"]:
        return ""
    if s["count"] == 1:
        return f"{s['max']:.4g}" + ("" if cases == 1 else f" (1 of {cases})")
    figures = [s["min"], *(s[f"p{p}"] for p in PERCENTILES), s["max"]]
    text = " / ".join(f"{v:.4g}" for v in figures)
    return text + (f" ({s['count']} of {cases})" if s["count"] < cases else "")


def _worst_of(s: dict[str, Any]) -> str:
    """A distribution's (``spread``) worst value and its case."""
    return f"{s['worst']:.4g} (`{s['worst_case']}`)" if s["count"] else ""
