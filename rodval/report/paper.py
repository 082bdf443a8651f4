"""The paper's reproduction written out: Table 1 beside rodval (CSV, markdown), Fig. 3
(chain configurations) and the exudyn cross-check (CSV, markdown)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from rodval.analysis.reproduce import (
    FORMULATIONS,
    QUANTITY_ORDER,
    REPRODUCTION_SETTINGS,
    column_errors,
    compare_table1,
    run_paper_models,
)
from rodval.core.out_paths import write_file
from rodval.core.scene import TABLE1_TIMES, paper_scene
from rodval.core.trajectory import Trajectory
from rodval.report.figures import plot_configurations
from rodval.report.markdown import to_markdown


def table1_markdown(
    table: pd.DataFrame, errors: pd.DataFrame, coefficients: str, stats: dict[str, dict[str, Any]]
) -> str:
    """Markdown: for each quantity and time, the published P/R values beside rodval's, the
    column errors and the runs."""
    s = REPRODUCTION_SETTINGS
    lines = [
        f"# Table 1 of the paper beside rodval (coefficients: `{coefficients}`)",
        "",
        "P = full model (3n ODEs), R = reduced model (n ODEs). Paper example, n = 8, "
        f"integrated with {s.method}, rtol = {s.rtol:g}, atol = {s.atol:g}.",
        "",
    ]
    wide = table.pivot_table(
        index=["quantity", "t", "k"],
        columns="formulation",
        values=["published", "rodval"],
        sort=False,
    )
    for q in QUANTITY_ORDER:
        part = wide.loc[[q]].reset_index()
        frame = pd.DataFrame(
            {
                "t, s": part["t"],
                "k": part["k"],
                "P published": part[("published", "P")],
                "P rodval": part[("rodval", "P")],
                "R published": part[("published", "R")],
                "R rodval": part[("rodval", "R")],
            }
        )
        lines += [f"## {q}", "", to_markdown(frame, ".6g")]
    err = errors.pivot_table(
        index=["quantity", "formulation"], columns="t", values="error", sort=False
    )
    err.columns = [f"t = {t:g} s" for t in err.columns]
    lines += [
        "## Column errors",
        "",
        "max over k of |rodval - published| / max over k of |published|.",
        "",
        to_markdown(err.reset_index(), ".2e"),
    ]
    runs = pd.DataFrame(
        [
            {"formulation": f, "status": st["message"], "nfev": st["nfev"], "wall, s": st["wall_s"]}
            for f, st in stats.items()
        ]
    )
    lines += ["## Runs", "", to_markdown(runs, ".3f")]
    return "\n".join(lines)


def crosscheck_markdown(table: pd.DataFrame, exudyn: Trajectory) -> str:
    """Markdown of the cross-check table (``rodval.analysis.crosscheck``)."""
    return (
        "# Cross-check against the independent exudyn beam model\n\n"
        "Paper example, rods 2, 4, 6, 8 at t = 0.5, 1, 1.5, 2 s. phi, alpha, beta: max |gap| "
        "(rad); dphi: max |gap| / the reference column's max |value|.\n\n"
        + to_markdown(table, ".2e")
        + f"\nexudyn settings: {exudyn.settings}, options: {exudyn.options}; solve wall "
        f"time {exudyn.stats.wall_s:.2f} s.\n"
    )


def reproduce_paper(out: Path | str, coefficients: str = "printed") -> pd.DataFrame:
    """Write table1.csv, table1.md and configurations.png to ``out``; return column errors."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    trajs = run_paper_models(coefficients)
    table = compare_table1(trajs)
    errors = column_errors(table)
    write_file(out / "table1.csv", table.to_csv(index=False))
    stats = {f: t.stats.as_dict() for f, t in trajs.items()}
    write_file(out / "table1.md", table1_markdown(table, errors, coefficients, stats))
    scene = paper_scene(times=TABLE1_TIMES)
    plot_configurations(
        {
            f"{FORMULATIONS[f]} (P)" if f == "P" else f"{FORMULATIONS[f]} (R)": t
            for f, t in trajs.items()
        },
        TABLE1_TIMES,
        scene.chain.l,
        out / "configurations.png",
        title=f"Paper example, n = 8 (coefficients: {coefficients})",
    )
    return errors
