"""The study's tables, built from the saved case records (pandas; written as CSV and markdown).

* ``cases``: case, n, horizon (s), one column per grid axis, l (rod lengths, JSON), fingerprint.
* ``trajectories``: tidy case, model, t (s), quantity, k, value (rad, rad/s, m or J).
* ``discrepancies``: case, n, horizon, axes, model, reference, quantity, max_abs, rms,
  final_abs, max_rel, k_at_max, t_at_max (see ``rodval.compare``), status.
* ``runtime``: case, n, horizon, axes, model, method, rtol, atol, max_step, wall_s
  (integration, s), setup_s (model set-up, s), nfev, njev, nlu, nsteps, t_reached (s),
  status, message.

``provenance.json`` (machine and package versions) and ``study.json`` lie beside them.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd

from ..compare import METRICS
from ..trajectory import STATUS_MESSAGES, Trajectory
from .runner import load_records

TABLES = ("cases", "trajectories", "discrepancies", "runtime")
FIXED = ("case", "n", "horizon", "model", "reference", "quantity", "method", "rtol", "atol",
         "max_step", "wall_s", "setup_s", "nfev", "njev", "nlu", "nsteps", "t_reached",
         "status", "message", "t", "k", "value", "l", "fingerprint", *METRICS)


def axis_columns(meta: dict[str, Any]) -> dict[str, str]:
    """Case parameter label -> table column. scene.n and scene.t_end are the n and horizon
    columns already; a label clashing with a fixed column keeps its full grid path."""
    cols = {}
    for path, label in meta["labels"].items():
        if path in ("scene.n", "scene.t_end"):
            continue
        cols[label] = path if label in FIXED else label
    return cols


def _case_columns(rec: dict, axes: dict[str, str]) -> dict[str, Any]:
    return {"case": rec["case"], "n": rec["n"], "horizon": rec["horizon"],
            **{col: rec["params"].get(label) for label, col in axes.items()}}


def cases_table(records: list[dict], axes: dict[str, str]) -> pd.DataFrame:
    return pd.DataFrame([{**_case_columns(r, axes), "l": json.dumps(r["l"]),
                          "fingerprint": r["fingerprint"]} for r in records])


def trajectories_table(records: list[dict]) -> pd.DataFrame:
    parts = []
    for rec in records:
        for run in rec["runs"]:
            frame = Trajectory.from_dict(run["trajectory"]).to_frame()
            frame.insert(0, "model", run["label"])
            frame.insert(0, "case", rec["case"])
            parts.append(frame)
    cols = ["case", "model", "t", "quantity", "k", "value"]
    return pd.concat(parts, ignore_index=True)[cols] if parts else pd.DataFrame(columns=cols)


def discrepancies_table(records: list[dict], axes: dict[str, str]) -> pd.DataFrame:
    rows = [{**_case_columns(rec, axes), **row} for rec in records for row in rec["discrepancies"]]
    cols = [*_case_columns(records[0], axes), "model", "reference", "quantity", *METRICS, "status"] \
        if records else []
    return pd.DataFrame(rows).reindex(columns=cols)


def runtime_table(records: list[dict], axes: dict[str, str]) -> pd.DataFrame:
    rows = []
    for rec in records:
        for run in rec["runs"]:
            tr = run["trajectory"]
            st, se = tr["stats"], tr["settings"]
            rows.append({**_case_columns(rec, axes), "model": run["label"],
                         "method": se.get("method"), "rtol": se.get("rtol"),
                         "atol": se.get("atol"), "max_step": se.get("max_step"),
                         "wall_s": st["wall_s"], "setup_s": run["setup_s"], "nfev": st["nfev"],
                         "njev": st["njev"], "nlu": st["nlu"], "nsteps": st["nsteps"],
                         "t_reached": st["t_reached"],
                         "energy_residual": st.get("energy_residual"),
                         "status": STATUS_MESSAGES[st["status"]],
                         "message": st["message"]})
    return pd.DataFrame(rows)


def to_markdown(df: pd.DataFrame, floatfmt: str = ".3g") -> str:
    """A GitHub pipe table ("|" inside cells escaped)."""
    if df.empty:
        return "_(no rows)_\n"
    safe = df.copy()
    for col in safe.columns:
        if safe[col].dtype == object:
            safe[col] = safe[col].map(lambda v: str(v).replace("|", "\\|") if isinstance(v, str) else v)
    return safe.to_markdown(index=False, tablefmt="pipe", floatfmt=floatfmt) + "\n"


def trajectory_samples(traj: pd.DataFrame, meta: dict[str, Any], cases: pd.DataFrame) -> pd.DataFrame:
    """The report cases' values at the report times (nearest output time) for the report rods
    and quantities, one column per model: a small table like the paper's Table 1."""
    rep = meta["report"]
    parts = []
    for cid in rep["cases"]:
        sub = traj[traj["case"] == cid]
        if sub.empty:
            continue
        horizon = float(cases.loc[cases["case"] == cid, "horizon"].iloc[0])
        n = int(cases.loc[cases["case"] == cid, "n"].iloc[0])
        rods = sorted({n if r == "last" else int(r) for r in rep["rods"] if r == "last" or int(r) <= n})
        want = rep["times"] or [horizon * f for f in (0.25, 0.5, 0.75, 1.0)]
        out_times = sub["t"].unique()
        snapped = sorted({float(out_times[abs(out_times - t).argmin()]) for t in want if t <= horizon})
        pick = sub[sub["t"].isin(snapped) & sub["k"].isin(rods) & sub["quantity"].isin(rep["quantities"])]
        wide = pick.pivot_table(index=["quantity", "k", "t"], columns="model", values="value",
                                sort=False).reset_index()
        wide.insert(0, "case", cid)
        parts.append(wide)
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


def build_tables(out: str | Path) -> dict[str, pd.DataFrame]:
    """All tables of the study in ``out`` from its case records."""
    out = Path(out)
    meta = json.loads((out / "study.json").read_text())
    records = load_records(out, [c["id"] for c in meta["cases"]])
    axes = axis_columns(meta)
    return {"cases": cases_table(records, axes), "trajectories": trajectories_table(records),
            "discrepancies": discrepancies_table(records, axes),
            "runtime": runtime_table(records, axes)}


def write_tables(out: str | Path) -> dict[str, pd.DataFrame]:
    """Write ``<table>.csv`` for every table and ``<table>.md`` for the readable ones."""
    out = Path(out)
    tables = build_tables(out)
    for name, df in tables.items():
        df.to_csv(out / f"{name}.csv", index=False)
    meta = json.loads((out / "study.json").read_text())
    (out / "discrepancies.md").write_text(to_markdown(tables["discrepancies"]))
    (out / "runtime.md").write_text(to_markdown(tables["runtime"]))
    (out / "trajectories.md").write_text(
        to_markdown(trajectory_samples(tables["trajectories"], meta, tables["cases"]), ".6g"))
    return tables
