"""Figures shared by the reproduction and study reports (matplotlib, Agg backend)."""
from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .trajectory import Trajectory  # noqa: E402

LINESTYLES = ("-", "--", ":", "-.")


def chain_nodes(traj: Trajectory, t: float, l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (m) at output time t, from x/y if recorded, else from phi and lengths."""
    i = int(np.argmin(np.abs(traj.times - t)))
    if abs(traj.times[i] - t) > 1e-9:
        raise ValueError(f"t = {t} s is not an output time of trajectory {traj.model!r}")
    if "x" in traj.values and "y" in traj.values:
        return traj.values["x"][i], traj.values["y"][i]
    phi = traj.values["phi"][i]
    return (np.concatenate([[0.0], np.cumsum(l * np.cos(phi))]),
            np.concatenate([[0.0], np.cumsum(l * np.sin(phi))]))


def _min_height(ax, ratio: float) -> None:
    """Widen the y limits to at least ``ratio`` of the x span (a nearly straight chain would
    otherwise be drawn as a sliver)."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    need = ratio * (x1 - x0)
    if y1 - y0 < need:
        mid = 0.5 * (y0 + y1)
        ax.set_ylim(mid - need / 2, mid + need / 2)


def plot_configurations(trajectories: Mapping[str, Trajectory], times: Sequence[float],
                        l: np.ndarray, path: Path | str, title: str = "") -> Path:
    """Chain configurations at ``times`` (one colour per time), one line style per model.

    Like Fig. 3 of the paper: the chord polygon through the nodes, root at the origin.
    """
    fig, ax = plt.subplots(figsize=(7, 6))
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(times)))
    for (label, traj), ls in zip(trajectories.items(), LINESTYLES * 4):
        for t, c in zip(times, colours):
            if not np.any(np.abs(traj.times - t) < 1e-9):
                continue  # a failed run may not have reached t
            x, y = chain_nodes(traj, t, l)
            ax.plot(x, y, ls, color=c, marker="o", ms=3,
                    label=f"{label}, t = {t:.4g} s")
    ax.plot([0], [0], "k^", ms=10)
    _min_height(ax, 0.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=1 + len(trajectories) * len(times) // 12,
              loc="upper left", bbox_to_anchor=(1.02, 1.0))
    if title:
        ax.set_title(title)
    path = Path(path)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def model_styles(labels: Sequence[str]) -> dict[str, dict]:
    """One colour and line style per model label, the same in every figure of a report."""
    colours = plt.cm.tab10.colors
    return {lab: {"color": colours[i % len(colours)], "ls": LINESTYLES[i % len(LINESTYLES)]}
            for i, lab in enumerate(labels)}


QUANTITY_UNITS = {"phi": "rad", "dphi": "rad/s", "alpha": "rad", "beta": "rad", "x": "m",
                  "y": "m", "kinetic": "J", "potential": "J", "energy": "J"}


def plot_time_histories(trajectories: Mapping[str, Trajectory], quantities: Sequence[str],
                        rods: Sequence[int], path: Path | str, title: str = "") -> Path:
    """Time histories of ``quantities`` (rows) for rods ``rods`` (columns), every model
    overlaid; a model that lacks a quantity or rod (or failed early) draws what it has."""
    styles = model_styles(list(trajectories))
    fig, axes = plt.subplots(len(quantities), len(rods), figsize=(4.2 * len(rods), 2.4 * len(quantities)),
                             sharex=True, squeeze=False)
    for r, q in enumerate(quantities):
        for c, k in enumerate(rods):
            ax = axes[r, c]
            for label, traj in trajectories.items():
                if q not in traj.values or k not in traj.k_index[q]:
                    continue
                j = int(np.flatnonzero(traj.k_index[q] == k)[0])
                ax.plot(traj.times, traj.values[q][:, j], label=label, lw=1.2, **styles[label])
            ax.set_ylabel(f"{q}_{k}, {QUANTITY_UNITS.get(q, '')}")
            ax.grid(alpha=0.3)
            if r == len(quantities) - 1:
                ax.set_xlabel("t, s")
    axes[0, 0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
