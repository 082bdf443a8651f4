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
                    label=f"{label}, t = {t:g} s")
    ax.plot([0], [0], "k^", ms=10)
    ax.set_aspect("equal")
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    if title:
        ax.set_title(title)
    path = Path(path)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path
