"""Reproduction of the paper's example: Table 1 side by side with rodval, and Fig. 3.

Error measure of a Table 1 column (one quantity, formulation and time):
max over k of |rodval - published| divided by max over k of |published|.
"""
from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd

from .figures import plot_configurations
from .scene import TABLE1_TIMES, paper_scene
from .settings import IntegratorSettings
from .simulate import simulate
from .trajectory import Trajectory

#: Table 1 formulation letters: P = full ("полная"), R = reduced.
FORMULATIONS = {"P": "full", "R": "reduced"}
QUANTITY_ORDER = ("phi", "dphi", "alpha", "beta")
#: Tight enough that integration error is far below the published digits.
REPRODUCTION_SETTINGS = IntegratorSettings(method="DOP853", rtol=1e-10, atol=1e-12)


def published_table1() -> pd.DataFrame:
    """The published Table 1: columns quantity, k, formulation, t, value."""
    with resources.files("rodval.data").joinpath("table1.csv").open() as fh:
        return pd.read_csv(fh)


def run_paper_models(coefficients: str = "printed",
                     settings: IntegratorSettings = REPRODUCTION_SETTINGS,
                     outputs=("phi", "dphi", "alpha", "beta")) -> dict[str, Trajectory]:
    """Full and reduced models on the paper example at the Table 1 times."""
    scene = paper_scene(times=TABLE1_TIMES, outputs=outputs)
    return {f: simulate(scene, model, settings=settings, coefficients=coefficients)
            for f, model in FORMULATIONS.items()}


def compare_table1(trajectories: dict[str, Trajectory]) -> pd.DataFrame:
    """Published values beside rodval's: quantity, k, formulation, t, rodval, published, diff."""
    pub = published_table1()
    ours = []
    for f, traj in trajectories.items():
        frame = traj.to_frame()
        frame["formulation"] = f
        ours.append(frame)
    ours_df = pd.concat(ours, ignore_index=True).rename(columns={"value": "rodval"})
    ours_df["t"] = ours_df["t"].round(9)
    pub = pub.assign(t=pub["t"].round(9)).rename(columns={"value": "published"})
    table = pub.merge(ours_df, on=["quantity", "k", "formulation", "t"], how="left")
    table["diff"] = table["rodval"] - table["published"]
    table["quantity"] = pd.Categorical(table["quantity"], QUANTITY_ORDER, ordered=True)
    table = table.sort_values(["quantity", "formulation", "t", "k"]).reset_index(drop=True)
    table["quantity"] = table["quantity"].astype(str)
    return table[["quantity", "k", "formulation", "t", "rodval", "published", "diff"]]


def column_errors(table: pd.DataFrame) -> pd.DataFrame:
    """Error measure per (quantity, formulation, t): max_k |diff| / max_k |published|."""
    g = table.assign(abs_diff=table["diff"].abs(), abs_pub=table["published"].abs()) \
             .groupby(["quantity", "formulation", "t"], sort=False)
    err = (g["abs_diff"].max() / g["abs_pub"].max()).rename("error").reset_index()
    return err


def _fmt(v: float) -> str:
    return f"{v:.6g}" if np.isfinite(v) else "—"


def table1_markdown(table: pd.DataFrame, errors: pd.DataFrame, coefficients: str,
                    stats: dict[str, dict]) -> str:
    """Markdown: for each quantity and time, the published P/R values beside rodval's."""
    lines = [f"# Table 1 of the paper beside rodval (coefficients: `{coefficients}`)", "",
             "P = full model (3n ODEs), R = reduced model (n ODEs). Paper example, n = 8, "
             f"integrated with {REPRODUCTION_SETTINGS.method}, rtol = "
             f"{REPRODUCTION_SETTINGS.rtol:g}, atol = {REPRODUCTION_SETTINGS.atol:g}.", ""]
    wide = table.pivot_table(index=["quantity", "t", "k"], columns="formulation",
                             values=["published", "rodval"], sort=False)
    for q in QUANTITY_ORDER:
        lines += [f"## {q}", "",
                  "| t, s | k | P published | P rodval | R published | R rodval |",
                  "|---:|---:|---:|---:|---:|---:|"]
        for (qq, t, k), row in wide.loc[[q]].iterrows():
            lines.append(f"| {t:g} | {k} | {_fmt(row[('published', 'P')])} | "
                         f"{_fmt(row[('rodval', 'P')])} | {_fmt(row[('published', 'R')])} | "
                         f"{_fmt(row[('rodval', 'R')])} |")
        lines.append("")
    lines += ["## Column errors", "",
              "max over k of |rodval - published| / max over k of |published|.", "",
              "| quantity | formulation | " + " | ".join(f"t = {t:g} s" for t in TABLE1_TIMES) + " |",
              "|---|---|" + "---:|" * len(TABLE1_TIMES)]
    for (q, f), grp in errors.groupby(["quantity", "formulation"], sort=False):
        vals = dict(zip(grp["t"].round(9), grp["error"]))
        lines.append(f"| {q} | {f} | " + " | ".join(f"{vals.get(round(t, 9), np.nan):.2e}"
                                                    for t in TABLE1_TIMES) + " |")
    lines += ["", "## Runs", "", "| formulation | status | nfev | wall, s |", "|---|---|---:|---:|"]
    for f, s in stats.items():
        lines.append(f"| {f} | {s['message']} | {s['nfev']} | {s['wall_s']:.3f} |")
    return "\n".join(lines) + "\n"


def reproduce_paper(out: Path | str, coefficients: str = "printed") -> pd.DataFrame:
    """Write table1.csv, table1.md and configurations.png to ``out``; return column errors."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    trajs = run_paper_models(coefficients)
    table = compare_table1(trajs)
    errors = column_errors(table)
    table.to_csv(out / "table1.csv", index=False)
    stats = {f: t.stats.as_dict() for f, t in trajs.items()}
    (out / "table1.md").write_text(table1_markdown(table, errors, coefficients, stats))
    scene = paper_scene(times=TABLE1_TIMES)
    plot_configurations({f"{FORMULATIONS[f]} (P)" if f == "P" else f"{FORMULATIONS[f]} (R)": t
                         for f, t in trajs.items()}, TABLE1_TIMES, scene.chain.l,
                        out / "configurations.png",
                        title=f"Paper example, n = 8 (coefficients: {coefficients})")
    return errors
