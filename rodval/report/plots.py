"""Figures drawn from the study tables: discrepancy, run time and speed-up against a case
parameter (n, horizon or any numeric grid axis). One panel per quantity, one line per model
and combination of the other parameters."""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd
from matplotlib import ticker

from ..figures import QUANTITY_UNITS, model_styles, plt


def _label(model: str, others: Sequence[str], key: tuple) -> str:
    parts = [f"{o}={v:g}" if isinstance(v, (int, float, np.number)) else f"{o}={v}"
             for o, v in zip(others, key)]
    return ", ".join([model, *parts])


def _lines(ax, df: pd.DataFrame, x: str, y: str, others: Sequence[str], styles: dict,
           logx: bool, logy: bool = True) -> None:
    """One line per model and combination of ``others``; log scales where the data allow."""
    markers = "os^dvP*X"
    df = df[np.isfinite(df[y]) & (df[y] > 0 if logy else True)]
    if logx and (df[x] > 0).all() and not df.empty:
        ax.set_xscale("log")
        ax.set_xticks(sorted(df[x].unique()))           # label the grid values themselves
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_locator(ticker.NullLocator())
    if logy and not df.empty:
        ax.set_yscale("log")
    for model, part in df.groupby("model", sort=False):
        groups = part.groupby(list(others), sort=True) if others else [((), part)]
        for i, (key, sub) in enumerate(groups):
            key = key if isinstance(key, tuple) else (key,)
            sub = sub.sort_values(x)
            ax.plot(sub[x], sub[y], marker=markers[i % len(markers)], ms=4, lw=1,
                    color=styles[model]["color"], ls=styles[model]["ls"],
                    label=_label(str(model), others, key))


def _finish(fig, axes, path: Path, title: str) -> Path:
    axes[0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_discrepancy_vs(disc: pd.DataFrame, x: str, others: Sequence[str], models: Sequence[str],
                        path: Path, metric: str = "max_abs", logx: bool = False) -> Path:
    """``metric`` of every compared quantity against ``x`` (log y); rows with status "ok" only."""
    ok = disc[disc["status"] == "ok"]
    quantities = list(dict.fromkeys(ok["quantity"]))
    ncol = min(2, max(len(quantities), 1))
    nrow = max(1, -(-len(quantities) // ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 3.3 * nrow), squeeze=False)
    axes = axes.ravel()
    for ax in axes[len(quantities):]:
        ax.set_visible(False)
    styles = model_styles(models)
    for ax, q in zip(axes, quantities):
        _lines(ax, ok[ok["quantity"] == q], x, metric, others, styles, logx)
        ax.set_title(f"{q}, {QUANTITY_UNITS.get(q, '')}")
        ax.set_xlabel(x)
        ax.set_ylabel(metric)
        ax.grid(alpha=0.3, which="both")
    return _finish(fig, axes, path, f"Discrepancy ({metric}) against {x}")


def plot_runtime_vs(runtime: pd.DataFrame, x: str, others: Sequence[str], models: Sequence[str],
                    path: Path, logx: bool = True) -> Path:
    """Integration wall time of successful runs against ``x`` (log-log)."""
    ok = runtime[runtime["status"] == "success"]
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    _lines(ax, ok, x, "wall_s", others, model_styles(models), logx)
    ax.set_xlabel(x)
    ax.set_ylabel("integration wall time, s")
    ax.grid(alpha=0.3, which="both")
    return _finish(fig, [ax], path, f"Run time against {x}")


def speedups(runtime: pd.DataFrame, reference: str, params: Sequence[str]) -> pd.DataFrame:
    """wall_s(reference) / wall_s(model) per case for every other model whose run and the
    reference's run both succeeded: columns case, params..., model, speedup."""
    ok = runtime[runtime["status"] == "success"]
    wide = ok.pivot_table(index=["case", *params], columns="model", values="wall_s", sort=False)
    if reference not in wide.columns:
        return pd.DataFrame(columns=["case", *params, "model", "speedup"])
    ratio = (1.0 / wide.drop(columns=reference)).mul(wide[reference], axis=0)
    long = ratio.reset_index().melt(id_vars=["case", *params], var_name="model", value_name="speedup")
    return long.dropna(subset=["speedup"])


def plot_speedup_vs(speed: pd.DataFrame, x: str, others: Sequence[str], models: Sequence[str],
                    reference: str, path: Path, logx: bool = True) -> Path:
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    _lines(ax, speed, x, "speedup", others, model_styles(models), logx)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel(x)
    ax.set_ylabel(f"speed-up: wall time of {reference} / of model")
    ax.grid(alpha=0.3, which="both")
    return _finish(fig, [ax], path, f"Speed-up relative to {reference} against {x}")
