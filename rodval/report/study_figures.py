"""The study report's figures: discrepancy, run time and speed-up against each grid parameter,
and for each report case its time histories, configurations and deployment sequence, drawn
from the saved tables (``rodval.report.figures`` draws them; this module chooses what)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rodval.core.profiles import PROFILE_KEYS
from rodval.core.trajectory import Trajectory
from rodval.report.figures import (
    drawable,
    plot_configurations,
    plot_deployment,
    plot_discrepancy_vs,
    plot_runtime_vs,
    plot_speedup_vs,
    plot_time_histories,
    speedups,
)
from rodval.report.markdown import to_markdown
from rodval.report.tables import (
    QUARTERS,
    axis_columns,
    report_rods,
    snapped_times,
    trajectory_samples,
)


def varying_params(cases: pd.DataFrame, params: list[str]) -> list[str]:
    """Case parameters with more than one value, all numeric and finite: the x axes of the
    figures (an axis such as max_step = [inf, 1e-7] has no place on a plot axis)."""
    return [
        p
        for p in params
        if pd.api.types.is_numeric_dtype(cases[p])
        and cases[p].nunique() > 1
        and np.isfinite(cases[p].to_numpy(float)).all()
    ]


def key_name(path: str, label: str) -> str:
    """The name a figure gives the grid key ``path`` (its table column ``label``): the
    label, extended to the key a list index, "*" or a profile's key (``PROFILE_KEYS``:
    first, rest, ...) belongs to (scene.chain.kappa.first -> kappa.first,
    scene.initial.phi.1 -> phi.1); the label says nothing without it."""
    parts = path.split(".")
    depth = max(len(label.split(".")), 1)
    while depth < len(parts) and (
        parts[-depth].isdigit() or parts[-depth] == "*" or parts[-depth] in PROFILE_KEYS
    ):
        depth += 1
    return ".".join(parts[-depth:]) if path.endswith(label) else label


def axis_names(meta: dict[str, Any]) -> dict[str, str]:
    """Table column -> the name its figures give it (``key_name``), for the grid's axes."""
    columns = axis_columns(meta)
    return {
        columns[label]: key_name(path, label)
        for path, label in meta["labels"].items()
        if label in columns
    }


def figure_slug(cid: str) -> str:
    """A case id as part of a figure's file name: ``n=8,t_end=2`` -> ``n8_t_end2``."""
    return cid.replace(",", "_").replace("=", "")


def param_figures(
    fig_dir: Path, meta: dict[str, Any], tables: dict[str, pd.DataFrame], params: list[str]
) -> list[str]:
    """Per varying parameter (``varying_params``): the discrepancy, run time and speed-up
    figures against it, each line one value of the other parameters (markdown lines)."""
    labels = [m["label"] for m in meta["models"]]
    ref, lines = meta["reference"], []
    names = axis_names(meta)
    speed = speedups(tables["runtime"], ref, params)
    varying = varying_params(tables["cases"], params)
    # each axis under its name (kappa.first, not first): the name is the figures' x label,
    # their legends' and their files'
    tables = {k: tables[k].rename(columns=names) for k in ("cases", "discrepancies", "runtime")}
    speed = speed.rename(columns=names)
    varying = [names.get(p, p) for p in varying]
    for x in varying:
        others = [p for p in varying if p != x]
        logx = (
            x != "horizon"
            and tables["cases"][x].min() > 0
            and tables["cases"][x].max() / tables["cases"][x].min() >= 8
        )
        lines.append(f"### Against {x}\n")
        if not tables["discrepancies"].empty:
            d = plot_discrepancy_vs(
                tables["discrepancies"],
                x,
                others,
                labels,
                fig_dir / f"discrepancy_vs_{x}.png",
                logx=logx,
            )
            lines.append(f"![discrepancy against {x}](figures/{d.name})\n")
        r = plot_runtime_vs(
            tables["runtime"], x, others, labels, fig_dir / f"runtime_vs_{x}.png", logx=logx
        )
        lines.append(f"![run time against {x}](figures/{r.name})\n")
        if not speed.empty:
            s = plot_speedup_vs(
                speed, x, others, labels, ref, fig_dir / f"speedup_vs_{x}.png", logx=logx
            )
            lines.append(f"![speed-up against {x}](figures/{s.name})\n")
    return lines


def _case_runs(sub: pd.DataFrame, labels: list[str], cid: str) -> dict[str, Trajectory]:
    """The runs of case ``cid`` that produced output, by model label, from its rows ``sub`` of
    the trajectories table."""
    return {
        lab: Trajectory.from_frame(sub[sub["model"] == lab], lab, cid)
        for lab in labels
        if (sub["model"] == lab).any()
    }


def case_figures(fig_dir: Path, meta: dict[str, Any], tables: dict[str, pd.DataFrame]) -> list[str]:
    """Per report case: every model's time histories of the report's rods and quantities and
    the chain's configurations at the report times; then the values at the report times
    (markdown lines)."""
    traj, cases = tables["trajectories"], tables["cases"]
    lines = []
    for cid in meta["report"]["cases"]:
        row = cases[cases["case"] == cid].iloc[0]
        lines += _one_case_figures(fig_dir, meta, traj[traj["case"] == cid], row, cid)
    return [*lines, *values_at_report_times(trajectory_samples(traj, meta, cases))]


#: A value table of at most this many rows is printed in the report; a longer one is linked.
INLINE_VALUE_ROWS = 24


def values_at_report_times(samples: pd.DataFrame) -> list[str]:
    """The report cases' values at the report times (``trajectory_samples``): the table itself
    when it has at most INLINE_VALUE_ROWS rows, else a link to ``trajectories.md``, where the
    study writes the same table (``rodval.study.tables.write_tables``), and to
    ``trajectories.csv`` (markdown lines)."""
    if samples.empty:
        return []
    if len(samples) <= INLINE_VALUE_ROWS:
        return ["Values at the report times (rad, rad/s):\n", to_markdown(samples, ".6g")]
    return [
        f"Values at the report times (rad, rad/s; {len(samples)} rows, one column per model): "
        "[`trajectories.md`](trajectories.md); every output time in "
        "[`trajectories.csv`](trajectories.csv).\n"
    ]


def _one_case_figures(
    fig_dir: Path, meta: dict[str, Any], sub: pd.DataFrame, row: pd.Series, cid: str
) -> list[str]:
    """``case_figures`` of the case ``cid`` (``sub``: its trajectories, ``row``: its cases
    row)."""
    rep = meta["report"]
    n, horizon, l = int(row["n"]), float(row["horizon"]), np.asarray(json.loads(row["l"]))
    trajs = _case_runs(sub, [m["label"] for m in meta["models"]], cid)
    lines = [f"### Case `{cid}` (n = {n}, horizon = {horizon:g} s)\n"]
    if not trajs:
        return [*lines, "_No model produced output for this case._\n"]
    rods = report_rods(rep, n)
    qs = [q for q in rep["quantities"] if (sub["quantity"] == q).any()]
    slug = figure_slug(cid)
    hist = plot_time_histories(
        trajs, qs, rods, fig_dir / f"history_{slug}.png", title=f"case {cid}: all models"
    )
    lines.append(f"![time histories, case {cid}](figures/{hist.name})\n")
    moving = _moving(row)
    drawn, lines_not = _drawn(trajs, moving)
    if drawn and ("phi" in qs or (sub["quantity"] == "phi").any()):
        snapped = snapped_times(sub, rep["times"], horizon, QUARTERS)
        conf = plot_configurations(
            drawn,
            snapped,
            l,
            fig_dir / f"configurations_{slug}.png",
            title=f"case {cid}: chain at t = " + ", ".join(f"{t:.4g}" for t in snapped) + " s",
            moving=moving,
        )
        lines.append(f"![configurations, case {cid}](figures/{conf.name})\n")
    return [*lines, *lines_not]


def _moving(row: pd.Series) -> bool:
    """Whether the case's base moves (cases.csv's base_kind; a study of an older rodval
    records none: then only a run's base outputs tell)."""
    kind = row.get("base_kind")
    return isinstance(kind, str) and kind != "pinned"


def _drawn(trajs: dict[str, Trajectory], moving: bool) -> tuple[dict[str, Trajectory], list[str]]:
    """The runs whose chain the outputs place (``drawable``; ``moving``: the case's base
    moves) and a markdown line naming the others (a moving base without outputs x, y),
    none when every run is drawn."""
    drawn = {k: t for k, t in trajs.items() if drawable(t, moving)}
    left = [f"`{k}`" for k in trajs if k not in drawn]
    if not left:
        return drawn, []
    return drawn, [
        f"_Chain not drawn for {', '.join(left)}: a moving base without outputs x, y, whose "
        "node 0 is not at the origin; add x, y to the [scene] outputs._\n"
    ]


def deployment_figures(
    fig_dir: Path, meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame
) -> list[str]:
    """Per report case with chord angles: each model's deployment sequence (the chain at the
    report times, default 0, 1/4 ... of the horizon) and the tip's y with the lock times of
    ``events`` (markdown lines)."""
    traj, cases = tables["trajectories"], tables["cases"]
    labels = [m["label"] for m in meta["models"]]
    lines = []
    for cid in meta["report"]["cases"]:
        sub = traj[traj["case"] == cid]
        if sub.empty or not (sub["quantity"] == "phi").any():
            continue
        row = cases[cases["case"] == cid].iloc[0]
        l = np.asarray(json.loads(row["l"]))
        moving = _moving(row)
        trajs, note = _drawn(_case_runs(sub, labels, cid), moving)
        lines += note
        if not trajs:
            continue
        snapped = snapped_times(
            sub, meta["report"]["times"], float(row["horizon"]), (0.0, *QUARTERS)
        )
        fig = plot_deployment(
            trajs,
            events[events["case"] == cid],
            snapped,
            l,
            fig_dir / f"deployment_{figure_slug(cid)}.png",
            title=f"case {cid}: deployment sequence and tip y (dotted: lock times)",
            moving=moving,
        )
        lines.append(f"![deployment, case {cid}](figures/{fig.name})\n")
    return lines
