"""The study report's summary sections, from the saved tables: the Outcome (runs, failures,
invalid runs, comparisons made and not made, by reason), the Discrepancies against the
reference, the Run time with speed-ups, and the Stability map."""

from __future__ import annotations

from typing import Any

import pandas as pd

from rodval.analysis.metrics import left_out_quantities
from rodval.core.validity import ENERGY_RESIDUAL_BOUND, SMALL_BENDING_RAD
from rodval.report.figures import speedups
from rodval.report.markdown import to_markdown


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
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], params: list[str]
) -> list[str]:
    """Outcome, Discrepancies against the reference, Run time and, when a run failed or was
    audited for energy, the Stability map (markdown lines); ``params``: the cases' parameter
    columns, "-" where a union of grids ([[grid]]) leaves one unset."""
    disc, runtime = (
        tables[k].fillna({p: "-" for p in params}) for k in ("discrepancies", "runtime")
    )
    ref = meta["reference"]
    failed = runtime[runtime["status"] != "success"]
    left = left_out_table(tables["trajectories"], ref)
    lines = _outcome(disc, runtime, failed, left)
    lines += _discrepancies(disc, left, ref, len(meta["models"]), params)
    lines += _run_time(runtime, ref, params)
    if not failed.empty or (
        "energy_residual" in runtime and runtime["energy_residual"].notna().any()
    ):
        lines += _stability_map(runtime, params)
    return lines


def _outcome(
    disc: pd.DataFrame, runtime: pd.DataFrame, failed: pd.DataFrame, left: pd.DataFrame
) -> list[str]:
    """The Outcome section: counts of cases, runs, failed and invalid runs and comparisons,
    the comparisons not made by reason, the failed runs and the invalid runs."""
    invalid = runtime[runtime["valid"].astype(str) == "False"] if "valid" in runtime else failed[:0]
    not_made = disc[disc["status"] != "ok"]
    lines = [
        f"## Outcome\n\n{runtime['case'].nunique()} cases, {len(runtime)} model runs, "
        f"{len(failed)} failed, {len(invalid)} invalid; "
        f"{(disc['status'] == 'ok').sum()} comparisons made (case, model, quantity), "
        f"{len(not_made) + len(left)} could not be made.\n"
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
        lines += [
            "Failed runs:\n",
            to_markdown(failed[["case", "model", "status", "t_reached", "message"]]),
        ]
    lines.append(
        "Validity: a run is invalid when it broke an assumption of its model (small bending, "
        f"largest |alpha|, |beta| <= {SMALL_BENDING_RAD:g} rad, in the paper models; an "
        f"energy-audit residual <= {ENERGY_RESIDUAL_BOUND:g} where audited; see "
        "docs/stability.md), whether or not it reached its end; its results are not those of "
        "the model's premise." + (" Invalid runs:\n" if len(invalid) else "\n")
    )
    if len(invalid):
        lines.append(to_markdown(invalid[["case", "model", "status", "invalid_because"]]))
    return lines


def _discrepancies(
    disc: pd.DataFrame, left: pd.DataFrame, ref: str, models: int, params: list[str]
) -> list[str]:
    """The Discrepancies section: per model, max_abs and max_rel of each quantity against
    the reference ``ref`` per case, and the quantities left out of the comparison
    (``models``: how many models the study has)."""
    lines = [f"## Discrepancies against `{ref}`\n"]
    if models == 1:
        lines.append(f"The study has one model (`{ref}`): nothing to compare.\n")
    else:
        lines.append(
            "Largest absolute difference over all output times and rods (`max_abs`; rad, "
            "rad/s) and the same relative to each reference rod's largest value "
            "(`max_rel`); see `discrepancies.csv` for rms, final value and where the "
            "maximum occurs.\n"
        )
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
        lines.append(to_markdown(wide.reindex(columns=order).reset_index()))
    return lines


def _run_time(runtime: pd.DataFrame, ref: str, params: list[str]) -> list[str]:
    """The Run time section: each successful run's integration wall time (s) per case and
    model, and each model's speed-up against the reference ``ref``."""
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
        "Integration wall time in s (without model set-up); speed-up = wall time of "
        f"`{ref}` / wall time of the model.\n",
        "Failed runs are left out.\n",
        to_markdown(wall.reset_index()),
    ]


def _stability_map(runtime: pd.DataFrame, params: list[str]) -> list[str]:
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
        to_markdown(grid.reset_index()),
    ]
