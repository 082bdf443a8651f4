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
    check_names,
    latch_hinges,
    lock_list,
    never_locked,
)
from rodval.analysis.metrics import left_out_quantities
from rodval.core.validity import ENERGY_RESIDUAL_BOUND, SMALL_BENDING_RAD
from rodval.report.acceptance import acceptance_checks
from rodval.report.figures import speedups
from rodval.report.markdown import to_markdown
from rodval.report.sample_stats import PERCENTILES, spread
from rodval.report.sensitivity import design_values
from rodval.report.study_answer import WORST_CASES, agreement_lines, answer_section, first_of
from rodval.report.tables import drop_study_constants


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


# ---- the answer the report opens with (a one-model study's verdict) ----------------------


def opening_section(
    meta: dict[str, Any],
    tables: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    peaks: pd.DataFrame,
) -> list[str]:
    """The report's opening, its answer (markdown lines): with two or more models, each
    against the reference (``answer_section``); with one, its verdict: the acceptance gate's
    (``_gate_sentence``), how the runs ended and whether they deployed (``_runs_sentence``),
    and the design quantities (``rodval.report.sensitivity.design_values``: lock time, lock
    impulse and peak hinge moment per hinge, a free base's attitude at t_end) over the cases:
    min, PERCENTILES, max and the worst case (``_quantities_lines``; ``peaks``: the report's
    peak hinge moments, ``rodval.report.study_report.peak_hinge_moments``); nothing in it
    compares models. When the study runs the one model's twin ([agreement.twin]), the one
    comparison there is follows: how long the twin agrees with it."""
    if len(meta["models"]) > 1:
        return answer_section(meta, tables, events)
    label = meta["models"][0]["label"]
    runtime = tables["runtime"][tables["runtime"]["model"] == label]
    values = design_values({**tables, "events": events, "peaks": peaks})
    values = values[values["model"] == label]
    mine = peaks[peaks["model"] == label] if "model" in peaks else peaks
    twin = agreement_lines(meta, tables, events)
    return [
        "## Answer\n",
        _gate_sentence(meta, tables, events),
        _runs_sentence(label, runtime, latch_hinges(tables["cases"]), events, values),
        *_quantities_lines(values, mine, runtime["case"].astype(str).tolist()),
        *([f"### `{label}` against its twin run\n"] if twin else []),
        *twin,
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
        f"`{what}` in {len(where)} of {len(cases)} cases ({first_of(where, 3)})"
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
        text += f"; failed: {first_of(failed)}"
    invalid = runtime[runtime["valid"].astype(str) == "False"] if "valid" in runtime else ok[:0]
    why = [f"`{c}` ({check_names(w)})" for c, w in zip(invalid["case"], invalid["invalid_because"])]
    text += f"; {len(invalid)} invalid: {first_of(why)}" if why else "; none invalid"
    latched = [c for c in runtime["case"] if latches.get(c)]
    if latched:
        missed = {c: never_locked(latches[c], lock_list(events, c, label)) for c in latched}
        undeployed = [f"`{c}` ({m} never locked within its run)" for c, m in missed.items() if m]
        text += (
            f"; deployed (every latch locked) in {len(latched) - len(undeployed)} of {len(latched)}"
        )
        if undeployed:
            text += f", not deployed in {first_of(undeployed)}"
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
