"""The study report: ``OUT/report.md`` and ``OUT/figures/*.png`` rebuilt from the saved tables
(``cases.csv``, ``trajectories.csv``, ``discrepancies.csv``, ``runtime.csv``) and the study's
``study.json`` / ``provenance.json``; nothing is recomputed."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rodval.core.trajectory import Trajectory
from rodval.report.figures import (
    plot_configurations,
    plot_discrepancy_vs,
    plot_runtime_vs,
    plot_speedup_vs,
    plot_time_histories,
    speedups,
)
from rodval.report.markdown import to_markdown
from rodval.report.tables import axis_columns, read_tables, trajectory_samples


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


def _case_figures(
    out: Path, fig_dir: Path, meta: dict, tables: dict[str, pd.DataFrame]
) -> list[str]:
    rep, lines = meta["report"], []
    traj, cases = tables["trajectories"], tables["cases"]
    labels = [m["label"] for m in meta["models"]]
    for cid in rep["cases"]:
        sub = traj[traj["case"] == cid]
        row = cases[cases["case"] == cid].iloc[0]
        n, horizon, l = int(row["n"]), float(row["horizon"]), np.asarray(json.loads(row["l"]))
        trajs = {
            lab: Trajectory.from_frame(sub[sub["model"] == lab], lab, cid)
            for lab in labels
            if (sub["model"] == lab).any()
        }
        lines.append(f"### Case `{cid}` (n = {n}, horizon = {horizon:g} s)\n")
        if not trajs:
            lines.append("_No model produced output for this case._\n")
            continue
        rods = sorted(
            {n if r == "last" else int(r) for r in rep["rods"] if r == "last" or int(r) <= n}
        )
        qs = [q for q in rep["quantities"] if (sub["quantity"] == q).any()]
        slug = cid.replace(",", "_").replace("=", "")
        hist = plot_time_histories(
            trajs, qs, rods, fig_dir / f"history_{slug}.png", title=f"case {cid}: all models"
        )
        lines.append(f"![time histories, case {cid}](figures/{hist.name})\n")
        if "phi" in qs or (sub["quantity"] == "phi").any():
            out_t = np.unique(sub["t"].to_numpy())
            want = rep["times"] or [horizon * f for f in (0.25, 0.5, 0.75, 1.0)]
            snapped = sorted(
                {float(out_t[np.abs(out_t - t).argmin()]) for t in want if t <= horizon}
            )
            conf = plot_configurations(
                trajs,
                snapped,
                l,
                fig_dir / f"configurations_{slug}.png",
                title=f"case {cid}: chain at t = " + ", ".join(f"{t:.4g}" for t in snapped) + " s",
            )
            lines.append(f"![configurations, case {cid}](figures/{conf.name})\n")
    samples = trajectory_samples(traj, meta, cases)
    if not samples.empty:
        lines += ["Values at the report times (rad, rad/s):\n", to_markdown(samples, ".6g")]
    return lines


def _stability_map(runtime: pd.DataFrame, params: list[str]) -> list[str]:
    """Case x model: how each run ended, its cost and (when audited) its energy residual."""

    def cell(row) -> str:
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


def _summary_tables(meta: dict, tables: dict[str, pd.DataFrame], params: list[str]) -> list[str]:
    # a union of grids ([[grid]]) leaves some parameters unset in some cases
    disc, runtime = (
        tables[k].fillna({p: "-" for p in params}) for k in ("discrepancies", "runtime")
    )
    ref = meta["reference"]
    lines = []
    failed = runtime[runtime["status"] != "success"]
    lines.append(
        f"## Outcome\n\n{runtime['case'].nunique()} cases, {len(runtime)} model runs, "
        f"{len(failed)} failed.\n"
    )
    if not failed.empty:
        lines += [
            "Failed runs:\n",
            to_markdown(failed[["case", "model", "status", "t_reached", "message"]]),
        ]
    lines.append(f"## Discrepancies against `{ref}`\n")
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
        wide = ok.pivot_table(
            index=["case", *params], columns="quantity", values=["max_abs", "max_rel"], sort=False
        )
        wide.columns = [f"{q} {m}" for m, q in wide.columns]
        order = [f"{q} {m}" for q in dict.fromkeys(ok["quantity"]) for m in ("max_abs", "max_rel")]
        lines.append(to_markdown(wide[order].reset_index()))
    lines.append("## Run time\n")
    lines.append(
        "Integration wall time in s (without model set-up); speed-up = wall time of "
        f"`{ref}` / wall time of the model.\n"
    )
    ok = runtime[runtime["status"] == "success"]
    wall = ok.pivot_table(index=["case", *params], columns="model", values="wall_s", sort=False)
    speed = speedups(runtime, ref, params)
    if not speed.empty:
        sp = speed.pivot_table(
            index=["case", *params], columns="model", values="speedup", sort=False
        )
        wall = wall.join(sp.add_prefix("speed-up "))
    lines.append("Failed runs are left out.\n")
    lines.append(to_markdown(wall.reset_index()))
    if not failed.empty or (
        "energy_residual" in runtime and runtime["energy_residual"].notna().any()
    ):
        lines += _stability_map(runtime, params)
    return lines


def _param_figures(
    fig_dir: Path, meta: dict, tables: dict[str, pd.DataFrame], params: list[str]
) -> list[str]:
    labels = [m["label"] for m in meta["models"]]
    ref, lines = meta["reference"], []
    speed = speedups(tables["runtime"], ref, params)
    for x in varying_params(tables["cases"], params):
        others = [p for p in varying_params(tables["cases"], params) if p != x]
        logx = (
            x != "horizon"
            and tables["cases"][x].min() > 0
            and tables["cases"][x].max() / tables["cases"][x].min() >= 8
        )
        d = plot_discrepancy_vs(
            tables["discrepancies"],
            x,
            others,
            labels,
            fig_dir / f"discrepancy_vs_{x}.png",
            logx=logx,
        )
        r = plot_runtime_vs(
            tables["runtime"], x, others, labels, fig_dir / f"runtime_vs_{x}.png", logx=logx
        )
        lines += [
            f"### Against {x}\n",
            f"![discrepancy against {x}](figures/{d.name})\n",
            f"![run time against {x}](figures/{r.name})\n",
        ]
        if not speed.empty:
            s = plot_speedup_vs(
                speed, x, others, labels, ref, fig_dir / f"speedup_vs_{x}.png", logx=logx
            )
            lines.append(f"![speed-up against {x}](figures/{s.name})\n")
    return lines


def _header(meta: dict, prov: dict) -> list[str]:
    models = pd.DataFrame(
        [
            {
                "label": m["label"],
                "model": m["model"],
                "options": json.dumps(m["options"]) if m["options"] else "",
                "method": m["settings"]["method"],
                "rtol": m["settings"]["rtol"],
                "atol": m["settings"]["atol"],
            }
            for m in meta["models"]
        ]
    )
    mach = prov["machine"]
    pkgs = ", ".join(f"{k} {v}" for k, v in prov["packages"].items() if v)
    axes = "; ".join(f"`{p}` = {v}" for p, v in meta["axes"].items()) or "none (one case)"
    return [
        f"# Study `{meta['name']}`\n",
        f"{meta['description']}\n" if meta["description"] else "",
        f"Study file: `{meta['source']}` (copied to `study.toml`). Grid: {axes}. "
        f"Reference model: `{meta['reference']}`.\n",
        "Models:\n",
        to_markdown(models),
        f"Machine: {mach['processor']}, {mach['cpu_count']} cores, {mach['platform']}, "
        f"Python {mach['python']}. Packages: {pkgs}.\n",
    ]


def _read_json(path: Path, keys: tuple[str, ...]) -> dict[str, Any]:
    """A JSON object with ``keys``; ValueError naming the file otherwise."""
    if not path.is_file():
        raise ValueError(f"{path.parent} is not a study folder: {path.name} is missing")
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: unreadable ({type(exc).__name__}: {exc})") from None
    if not isinstance(doc, dict) or any(k not in doc for k in keys):
        missing = next((k for k in keys if not isinstance(doc, dict) or k not in doc), "")
        raise ValueError(f"{path}: key {missing!r} is missing")
    return doc


def build_report(out: str | Path) -> Path:
    """Write ``out/report.md`` and ``out/figures/`` from the saved tables; returns the path."""
    out = Path(out)
    meta: dict[str, Any] = _read_json(
        out / "study.json", ("name", "models", "reference", "labels", "axes", "report")
    )
    prov = _read_json(out / "provenance.json", ("machine", "packages"))
    tables = read_tables(out)
    params = ["n", "horizon", *axis_columns(meta).values()]
    fig_dir = out / "figures"
    fig_dir.mkdir(exist_ok=True)
    lines = _header(meta, prov)
    lines += _summary_tables(meta, tables, params)
    figs = _param_figures(fig_dir, meta, tables, params)
    if figs:
        lines += ["## Discrepancy, run time and speed-up against the grid parameters\n", *figs]
    lines += ["## Time histories and configurations\n", *_case_figures(out, fig_dir, meta, tables)]
    path = out / "report.md"
    path.write_text("\n".join(x for x in lines if x))
    return path
