"""Every figure of rodval: chain configurations, time histories, study figures (discrepancy,
run time and speed-up against a grid parameter) and work-precision plots.

Figures are drawn on ``matplotlib.figure.Figure`` objects and saved as PNG directly, without
pyplot: no GUI backend is ever selected, whatever the machine, and nothing happens at import.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
from matplotlib import colormaps, ticker
from matplotlib.axes import Axes
from matplotlib.colors import TABLEAU_COLORS
from matplotlib.figure import Figure
from matplotlib.typing import ColorType

from rodval.analysis.metrics import pareto_front
from rodval.core.base import rotate
from rodval.core.modes import Modes
from rodval.core.out_paths import write_figure
from rodval.core.scene import UNITS
from rodval.core.trajectory import Trajectory
from rodval.models.registry import integrated_models


def _figure(nrows: int = 1, ncols: int = 1, **kw: Any) -> tuple[Figure, Any]:
    """A new figure and its axes (``Figure.subplots`` arguments)."""
    figsize = kw.pop("figsize", None)
    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kw)


LINESTYLES = ("-", "--", ":", "-.")
#: One colour per model, in order, in every figure and animation (matplotlib's tab10 palette).
MODEL_COLOURS: tuple[ColorType, ...] = tuple(TABLEAU_COLORS.values())
#: Widest average glyph width of the default font, in units of the font size (DejaVu Sans:
#: ~0.55 for lower case, ~0.64 for digits and capitals), and the part of the figure's width a
#: title may take.
GLYPH_WIDTH = 0.66
TITLE_SHARE = 0.92


def fit_title(text: str, width_in: float, fontsize: float) -> str:
    """``text`` wrapped on word boundaries into lines that fit ``width_in`` inches at
    ``fontsize`` points (``GLYPH_WIDTH`` per character, 72 points per inch, ``TITLE_SHARE`` of
    the width): a title never
    runs past its figure's edges; a word longer than a line is broken."""
    per_line = max(int(TITLE_SHARE * width_in * 72 / (GLYPH_WIDTH * fontsize)), 10)
    return "\n".join(textwrap.wrap(text, per_line, break_long_words=True)) if text else text


def _title_size(which: Literal["figure.titlesize", "axes.titlesize"] = "figure.titlesize") -> float:
    """The font size (points) of the figure's or an axes' title in the current rcParams."""
    from matplotlib import rcParams
    from matplotlib.font_manager import FontProperties

    return FontProperties(size=rcParams[which]).get_size_in_points()


def moving_base(traj: Trajectory) -> bool:
    """Whether the run's outputs say its base moves (a free or prescribed body: output
    "base", base_position)."""
    return "base_position" in traj.values


def drawable(traj: Trajectory, moving: bool = False) -> bool:
    """Whether the run's outputs place its chain: x, y, or phi hung from the pin at the
    origin (not for a moving base, ``moving`` or told by its outputs, whose node 0 is not
    at the origin)."""
    has_xy = "x" in traj.values and "y" in traj.values
    return has_xy or ("phi" in traj.values and not (moving or moving_base(traj)))


def body_outline(
    centre: np.ndarray, attitude: np.ndarray, half: float
) -> tuple[np.ndarray, np.ndarray]:
    """A body drawn as a square of half side ``half`` (m) about its centre (nt, 2), turned
    by its attitude (nt,): the closed outline's x, y (m), each (nt, 5)."""
    corners = half * np.array([[1, 1], [-1, 1], [-1, -1], [1, -1], [1, 1]], float)
    turned = rotate(np.asarray(attitude)[:, None], corners[None, :, :])
    return centre[:, None, 0] + turned[..., 0], centre[:, None, 1] + turned[..., 1]


def _output_row(traj: Trajectory, t: float) -> int:
    """The index of output time ``t`` (s) in the run; ValueError when it has none there."""
    i = int(np.argmin(np.abs(traj.times - t)))
    if abs(traj.times[i] - t) > 1e-9:
        raise ValueError(f"t = {t} s is not an output time of trajectory {traj.model!r}")
    return i


def body_at(traj: Trajectory, t: float, l: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The outline (x, y, m) of a moving base's body at output time ``t`` (s): a square
    about its centre of mass (base_position), turned by base_attitude, node 0 (x, y) on its
    edge (half side |r_0 - r_c|, at least 5 % of the chain's length ``l`` so that it
    shows); None when the outputs do not hold the pose and node 0."""
    need = ("base_position", "base_attitude", "x", "y")
    if not all(q in traj.values for q in need):
        return None
    i = _output_row(traj, t)
    centre = np.asarray(traj.values["base_position"][i : i + 1], float).reshape(1, 2)
    node0 = np.array([traj.values["x"][i][0], traj.values["y"][i][0]], float)
    half = max(float(np.hypot(*(node0 - centre[0]))), 0.05 * float(np.sum(l)))
    bx, by = body_outline(centre, np.asarray(traj.values["base_attitude"][i], float)[:1], half)
    return bx[0], by[0]


def chain_nodes(
    traj: Trajectory, t: float, l: np.ndarray, moving: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (m) at output time t, from x/y if recorded, else from phi and lengths
    hung from the pin at the origin; ValueError for a moving base (``moving``, or told by
    the run's outputs) without x, y: its node 0 is not at the origin (``drawable``)."""
    i = _output_row(traj, t)
    if "x" in traj.values and "y" in traj.values:
        return traj.values["x"][i], traj.values["y"][i]
    if not drawable(traj, moving):
        raise ValueError(
            f"run {traj.model!r} has a moving base but no x, y among its outputs: its chain "
            "cannot be placed"
        )
    phi = traj.values["phi"][i]
    return (
        np.concatenate([[0.0], np.cumsum(l * np.cos(phi))]),
        np.concatenate([[0.0], np.cumsum(l * np.sin(phi))]),
    )


def _min_height(ax: Axes, ratio: float) -> None:
    """Widen the y limits to at least ``ratio`` of the x span (a nearly straight chain would
    otherwise be drawn as a sliver)."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    need = ratio * (x1 - x0)
    if y1 - y0 < need:
        mid = 0.5 * (y0 + y1)
        ax.set_ylim(mid - need / 2, mid + need / 2)


def plot_configurations(
    trajectories: Mapping[str, Trajectory],
    times: Sequence[float],
    l: np.ndarray,
    path: Path | str,
    title: str = "",
    moving: bool = False,
) -> Path:
    """Chain configurations at ``times`` (one colour per time), one line style per model.

    Like Fig. 3 of the paper: the chord polygon through the nodes, root at the pin at the
    origin; a moving base's chain where its outputs x, y put it, its body drawn as a square
    at its pose (``body_at``), no pin (``moving``: the runs' base moves, whatever their
    outputs say). Every run must be ``drawable``.
    """
    fig, ax = _figure(figsize=(7, 6))
    colours = colormaps["viridis"](np.linspace(0, 0.9, len(times)))
    for traj, ls in zip(trajectories.values(), LINESTYLES * 4):
        for t, c in zip(times, colours):
            if not np.any(np.abs(traj.times - t) < 1e-9):
                continue  # a failed run may not have reached t
            x, y = chain_nodes(traj, t, l, moving)
            ax.plot(x, y, ls, color=c, marker="o", ms=3)
            body = body_at(traj, t, l)
            if body is not None:
                ax.plot(*body, ls, color=c, lw=1.5)
    if not moving and any(not moving_base(traj) for traj in trajectories.values()):
        ax.plot([0], [0], "k^", ms=10)  # the pin of the pinned runs
    _min_height(ax, 0.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.grid(alpha=0.3)
    # two compact legends: colour = time, line style = model (not one entry per pair)
    from matplotlib.lines import Line2D

    by_time = [Line2D([], [], color=c, marker="o", ms=3) for c in colours]
    by_model = [Line2D([], [], color="k", ls=ls) for _, ls in zip(trajectories, LINESTYLES * 4)]
    first = ax.legend(
        by_time,
        [f"t = {t:.4g} s" for t in times],
        fontsize=7,
        loc="upper left",
        title="time",
        title_fontsize=7,
    )
    ax.add_artist(first)
    ax.legend(
        by_model, list(trajectories), fontsize=7, loc="lower right", title="model", title_fontsize=7
    )
    if title:
        ax.set_title(fit_title(title, fig.get_figwidth(), _title_size("axes.titlesize")))
    path = Path(path)
    write_figure(fig, path, dpi=120, bbox_inches="tight")
    return path


def model_styles(labels: Sequence[str], drawn: Sequence[Any] = ()) -> dict[str, dict[str, Any]]:
    """One colour and line style per run label, the same in every figure of a report: the
    study's model ``labels`` in order, then every other label of the runs ``drawn`` (a
    reference's twin run, "full twin"), in their order."""
    labels = list(dict.fromkeys([*labels, *map(str, drawn)]))
    return {
        lab: {
            "color": MODEL_COLOURS[i % len(MODEL_COLOURS)],
            "ls": LINESTYLES[i % len(LINESTYLES)],
        }
        for i, lab in enumerate(labels)
    }


def plot_time_histories(
    trajectories: Mapping[str, Trajectory],
    quantities: Sequence[str],
    rods: Sequence[int],
    path: Path | str,
    title: str = "",
) -> Path:
    """Time histories of ``quantities`` (rows) for rods ``rods`` (columns), every model
    overlaid; a model that lacks a quantity or rod (or failed early) draws what it has."""
    styles = model_styles(list(trajectories))
    fig, axes = _figure(
        len(quantities),
        len(rods),
        figsize=(4.2 * len(rods), 2.4 * len(quantities)),
        sharex=True,
        squeeze=False,
    )
    for r, q in enumerate(quantities):
        for c, k in enumerate(rods):
            ax = axes[r, c]
            for label, traj in trajectories.items():
                if q not in traj.values or k not in traj.k_index[q]:
                    continue
                j = int(np.flatnonzero(traj.k_index[q] == k)[0])
                ax.plot(traj.times, traj.values[q][:, j], label=label, lw=1.2, **styles[label])
            ax.set_ylabel(f"{q}_{k}, {UNITS.get(q, '')}")
            ax.grid(alpha=0.3)
            if r == len(quantities) - 1:
                ax.set_xlabel("t, s")
    axes[0, 0].legend(fontsize=8)
    return _save(fig, path, title)


def _label(model: str, others: Sequence[str], key: tuple[Any, ...]) -> str:
    parts = [
        f"{o}={v:g}" if isinstance(v, (int, float, np.number)) else f"{o}={v}"
        for o, v in zip(others, key)
    ]
    return ", ".join([model, *parts])


def _lines(
    ax: Axes,
    df: pd.DataFrame,
    x: str,
    y: str,
    others: Sequence[str],
    styles: dict[str, dict[str, Any]],
    logx: bool,
    logy: bool = True,
) -> None:
    """One line per model and combination of ``others``; log scales where the data allow."""
    markers = "os^dvP*X"
    df = df[np.isfinite(df[y]) & (df[y] > 0 if logy else True)]
    if logx and (df[x] > 0).all() and not df.empty:
        ax.set_xscale("log")
        ax.set_xticks(sorted(df[x].unique()))  # label the grid values themselves
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_locator(ticker.NullLocator())
    elif not df.empty and df[x].nunique() <= 12:
        ax.set_xticks(sorted(df[x].unique()))  # the grid values (integers for n)
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    if logy and not df.empty:
        ax.set_yscale("log")
    for model, part in df.groupby("model", sort=False):
        groups = part.groupby(list(others), sort=True) if others else [((), part)]
        for i, (key, sub) in enumerate(groups):
            key = key if isinstance(key, tuple) else (key,)
            sub = sub.sort_values(x)
            ax.plot(
                sub[x],
                sub[y],
                marker=markers[i % len(markers)],
                ms=4,
                lw=1,
                color=styles[model]["color"],
                ls=styles[model]["ls"],
                label=_label(str(model), others, key),
            )


def axis_label(x: str) -> str:
    """The axis label of a study parameter: its name in the study file, with its unit."""
    return {"n": "n (rods)", "horizon": "horizon t_end, s"}.get(x, x)


def _save(fig: Figure, path: Path | str, title: str = "") -> Path:
    """Title, tight layout and the PNG (110 dpi): the end of every report figure."""
    if title:
        fig.suptitle(fit_title(title, fig.get_figwidth(), _title_size()))
    fig.tight_layout()
    path = Path(path)
    write_figure(fig, path, dpi=110)
    return path


def _finish(fig: Figure, axes: Sequence[Axes] | np.ndarray, path: Path, title: str) -> Path:
    handles, _ = axes[0].get_legend_handles_labels()
    if handles:  # no line when no run succeeded or was compared: the figure says so
        axes[0].legend(fontsize=7, ncol=2 if len(handles) > 6 else 1)
    else:
        axes[0].text(
            0.5, 0.5, "nothing to draw (see Outcome)", transform=axes[0].transAxes, ha="center"
        )
    return _save(fig, path, title)


def plot_discrepancy_vs(
    disc: pd.DataFrame,
    x: str,
    others: Sequence[str],
    models: Sequence[str],
    path: Path,
    metric: str = "max_abs",
    logx: bool = False,
) -> Path:
    """``metric`` of every compared quantity against ``x`` (log y); rows with status "ok" only."""
    ok = disc[disc["status"] == "ok"]
    quantities = list(dict.fromkeys(ok["quantity"]))
    ncol = min(2, max(len(quantities), 1))
    nrow = max(1, -(-len(quantities) // ncol))
    fig, axes = _figure(nrow, ncol, figsize=(5.2 * ncol, 3.3 * nrow), squeeze=False)
    axes = axes.ravel()
    for ax in axes[len(quantities) :]:
        ax.set_visible(False)
    styles = model_styles(models, ok["model"])
    for ax, q in zip(axes, quantities):
        _lines(ax, ok[ok["quantity"] == q], x, metric, others, styles, logx)
        ax.set_title(f"{q}, {UNITS.get(q, '')}")
        ax.set_xlabel(axis_label(x))
        ax.set_ylabel(metric)
        ax.grid(alpha=0.3, which="both")
    return _finish(fig, axes, path, f"Discrepancy ({metric}) against {x}")


def plot_runtime_vs(
    runtime: pd.DataFrame,
    x: str,
    others: Sequence[str],
    models: Sequence[str],
    path: Path,
    logx: bool = True,
) -> Path:
    """Integration wall time of successful runs against ``x`` (log-log)."""
    ok = runtime[runtime["status"] == "success"]
    fig, ax = _figure(figsize=(6.5, 4.5))
    _lines(ax, ok, x, "wall_s", others, model_styles(models, ok["model"]), logx)
    ax.set_xlabel(axis_label(x))
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
    long = ratio.reset_index().melt(
        id_vars=["case", *params], var_name="model", value_name="speedup"
    )
    return long.dropna(subset=["speedup"])


def plot_speedup_vs(
    speed: pd.DataFrame,
    x: str,
    others: Sequence[str],
    models: Sequence[str],
    reference: str,
    path: Path,
    logx: bool = True,
) -> Path:
    fig, ax = _figure(figsize=(6.5, 4.5))
    _lines(ax, speed, x, "speedup", others, model_styles(models, speed["model"]), logx)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel(axis_label(x))
    ax.set_ylabel(f"speed-up: wall time of {reference} / of model")
    ax.grid(alpha=0.3, which="both")
    return _finish(fig, [ax], path, f"Speed-up relative to {reference} against {x}")


def plot_work_precision(
    frame: pd.DataFrame, out_dir: Path, quantities: Sequence[str] = ("phi", "dphi", "alpha", "beta")
) -> list[Path]:
    """One figure per model and x axis (wall, nfev): error against cost per quantity, one
    line per method/kernel, and the monotone front over all of them. Returns the paths."""
    paths = []
    integrated = integrated_models()  # their cost counts RHS evaluations, others' Newton steps
    for model, part in frame.groupby("model"):
        for xcol, xlabel in (
            ("wall_s", "wall time (s)"),
            ("nfev", "RHS evaluations" if model in integrated else "Newton iterations"),
        ):
            qs = [q for q in quantities if f"max_{q}" in part and part[f"max_{q}"].notna().any()]
            fig, axes = _figure(1, len(qs), figsize=(4.2 * len(qs), 3.8), squeeze=False)
            for ax, q in zip(axes[0], qs):
                for (method, kernel), line in part.groupby(["method", "kernel"]):
                    line = line.sort_values(["rtol", "step"], ascending=False)  # loosest first
                    label = method + (f" ({kernel})" if kernel == "numpy" else "")
                    ax.loglog(line[xcol], line[f"max_{q}"], "o-", ms=3, label=label)
                x, y = part[xcol].to_numpy(float), part[f"max_{q}"].to_numpy(float)
                f = pareto_front(x, y)
                ax.loglog(x[f], y[f], "k--", lw=1.2, label="front")
                ax.set_xlabel(xlabel)
                ax.set_ylabel(f"max rel. error {q}")
                ax.set_title(f"{model}: {q}")
                ax.grid(True, which="both", alpha=0.3)
            axes[0][0].legend(fontsize=7)
            fig.tight_layout()
            path = out_dir / f"wp_{model}_{'wall' if xcol == 'wall_s' else 'nfev'}.png"
            write_figure(fig, path, dpi=110)
            paths.append(path)
    return paths


def drawn_modes(m: Modes, count: int = 4) -> Modes:
    """The modes ``plot_modes`` draws: the first ``count`` flexible modes (a free base's
    rigid modes, ``Modes.flexible``, left out: they move the chain as a body), numbered from
    1 as the files and ``--count`` number them."""
    flex = m.flexible()
    return flex.rows(slice(0, min(count, flex.count)))


def plot_modes(m: Modes, path: Path, title: str = "", count: int = 4) -> Path:
    """The first ``count`` flexible mode shapes (``drawn_modes``) drawn on the chain: the
    configuration in metres, each normalized shape (largest node displacement 1) drawn at
    0.15 of the chain's span, which the legend states (shapes have no unit of their own;
    hinge angles are in modes.csv). A free base's rigid modes are named in the title."""
    rigid = m.rigid
    m = drawn_modes(m, count)
    k = m.count
    x0, y0 = m.node_positions()
    span = max(np.ptp(x0), np.ptp(y0), float(np.sum(m.l)) * 0.2)
    amp = 0.15 * span
    fig, axes = _figure(k, 1, figsize=(7, 1.9 * k + 0.6), squeeze=False, sharex=True)
    for i, ax in enumerate(axes[:, 0]):
        ax.plot(x0, y0, "-o", color="0.7", ms=3, lw=1, label="configuration")
        ax.plot(
            x0 + amp * m.dx[i],
            y0 + amp * m.dy[i],
            "-o",
            color="C0",
            ms=3,
            lw=1.5,
            label=f"normalized shape (largest node displacement drawn as {amp:.3g} m)",
        )
        ys = np.concatenate([y0, y0 + amp * m.dy[i]])
        pad = 0.1 * max(np.ptp(ys), amp)
        ax.set_ylim(ys.min() - pad, ys.max() + pad)
        ax.set_ylabel("y (m)")
        ax.set_title(f"mode {i + 1}: {m.omega[i]:.4g} rad/s ({m.f_hz[i]:.4g} Hz)", fontsize=9)
    axes[-1, 0].set_xlabel("x (m)")
    axes[0, 0].legend(fontsize=7, loc="upper left")
    if rigid:
        title = f"{title}{'; ' if title else ''}flexible modes ({rigid} rigid modes not drawn)"
    if title:
        fig.suptitle(fit_title(title, fig.get_figwidth(), 10), fontsize=10)
    fig.tight_layout()
    write_figure(fig, path, dpi=110)
    return path


def plot_deployment(
    trajectories: Mapping[str, Trajectory],
    events: pd.DataFrame,
    times: Sequence[float],
    l: np.ndarray,
    path: Path | str,
    title: str = "",
    moving: bool = False,
) -> Path:
    """A deployment: one panel per model with the chain at ``times`` (the deployment
    sequence, light to dark), and below them the tip's y (m) against time, every model
    overlaid, with each model's lock times (``events``: columns model, t, label) as dotted
    vertical lines in its colour. A moving base is drawn as in ``plot_configurations``."""
    styles = model_styles(list(trajectories))
    ncol = max(len(trajectories), 1)
    fig = Figure(figsize=(4.0 * ncol, 7.5))
    grid = fig.add_gridspec(2, ncol, height_ratios=[1.4, 1.0])
    colours = colormaps["viridis"](np.linspace(0.0, 0.9, max(len(times), 1)))
    for c, (label, traj) in enumerate(trajectories.items()):
        ax = fig.add_subplot(grid[0, c])
        for t, col in zip(times, colours):
            if not np.any(np.abs(traj.times - t) < 1e-9):
                continue
            x, y = chain_nodes(traj, t, l, moving)
            ax.plot(x, y, "-", color=col, marker="o", ms=2.5, lw=1.2, label=f"t = {t:.3g} s")
            body = body_at(traj, t, l)
            if body is not None:
                ax.plot(*body, "-", color=col, lw=1.2)
        if not (moving or moving_base(traj)):
            ax.plot([0], [0], "k^", ms=8)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(label)
        ax.set_xlabel("x, m")
        ax.grid(alpha=0.3)
        if c == 0:
            ax.set_ylabel("y, m")
            ax.legend(fontsize=6, loc="best")
    ax = fig.add_subplot(grid[1, :])
    for label, traj in trajectories.items():
        x_tip = None
        if "y" in traj.values:
            x_tip = traj.values["y"][:, -1]
        elif "phi" in traj.values:
            x_tip = np.sum(l * np.sin(traj.values["phi"]), axis=1)
        if x_tip is not None:
            ax.plot(traj.times, x_tip, lw=1.1, label=label, **styles[label])
        if not events.empty and "model" in events:
            for t in events.loc[events["model"] == label, "t"]:
                ax.axvline(float(t), color=styles[label]["color"], ls=":", lw=0.9)
    ax.set_xlabel("t, s")
    ax.set_ylabel("tip y, m")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path, title)


def plot_scale(frame: pd.DataFrame, speedup: pd.DataFrame | None, path: Path) -> Path:
    """Wall time over 0..2 s, RHS cost and (if given) the equal-accuracy speed-up against n,
    log-log (``rodval bench scale``)."""
    speedup = speedup if speedup is not None and len(speedup) else None
    panels = 3 if speedup is not None else 2
    fig = Figure(figsize=(4.4 * panels, 3.8))
    axes = fig.subplots(1, panels)
    for model, part in frame.groupby("model", sort=False):
        axes[0].loglog(part.n, part.wall_s, "o-", ms=3, label=model)
        axes[1].loglog(part.n, part.rhs_random_s, "o-", ms=3, label=f"{model}, random state")
        axes[1].loglog(part.n, part.rhs_run_s, "x--", ms=4, label=f"{model}, state at t = 0.5 s")
    axes[0].set_ylabel("wall time over 0..2 s (s)")
    axes[1].set_ylabel("compiled RHS, s per evaluation")
    if speedup is not None:
        axes[2].semilogx(speedup.n, speedup["full/reduced"], "o-", ms=3)
        axes[2].axhline(1.0, color="k", lw=0.8)
        axes[2].set_ylabel("full / reduced wall time, phi error <= 1e-6")
    for ax in axes:
        ax.set_xlabel("rods n")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    write_figure(fig, path, dpi=110)
    return path
