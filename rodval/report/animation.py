"""Animations of runs: the chain's motion as a GIF or MP4, several runs overlaid, the time, the
locks and the stop contacts marked (``rodval animate``).

Drawn on matplotlib's ``Figure`` without pyplot (no backend is selected) and written with
matplotlib's animation writers: ``PillowWriter`` for .gif (Pillow comes with matplotlib),
``FFMpegWriter`` for .mp4 (needs the ``ffmpeg`` program).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib import animation
from matplotlib.figure import Figure

from rodval.core.base import PINNED, Base, rotate
from rodval.core.trajectory import Trajectory
from rodval.report.figures import MODEL_COLOURS

#: Output formats and their writers.
FORMATS = (".gif", ".mp4")
#: Largest frame count and frame rate accepted (a long run is subsampled to ``frames``).
MAX_FRAMES = 5000
MAX_FPS = 120


@dataclass(frozen=True)
class Animated:
    """What was written: the file, the frame count, the frame times (s) and the events marked
    (run label, t (s), event label)."""

    path: Path
    frames: int
    times: np.ndarray
    events: tuple[tuple[str, float, str], ...]


def node_history(
    traj: Trajectory, l: np.ndarray, base: Base = PINNED
) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (m), each (nt, n + 1): x, y if the run recorded them, else the chord
    polygon from phi and the rod lengths ``l`` hung from node 0: the origin for a pinned
    ``base``, r_0 = r_c + R(theta) h for a free one (from the run's base_position and
    base_attitude, output "base"). ValueError when the outputs cannot place the chain, and
    for a run with a free base's outputs given a pinned ``base``: a free base is never drawn
    pinned. O(nt n)."""
    if "x" in traj.values and "y" in traj.values:
        return traj.values["x"], traj.values["y"]
    if "phi" not in traj.values:
        raise ValueError(
            f"run {traj.model!r} has neither x, y nor phi among its outputs: nothing to draw"
        )
    phi = traj.values["phi"]
    if base.free:
        missing = [q for q in ("base_position", "base_attitude") if q not in traj.values]
        if missing:
            raise ValueError(
                f"run {traj.model!r} has a free base but neither x, y nor {', '.join(missing)} "
                "(output 'base') among its outputs, so the chain cannot be drawn where the "
                "body moved; rerun it with outputs x, y or 'base'"
            )
        root = traj.values["base_position"] + rotate(
            traj.values["base_attitude"][:, 0], np.asarray(base.hinge_offset, float)
        )
    elif "base_position" in traj.values:
        raise ValueError(
            f"run {traj.model!r} has a free base's outputs (base_position) but was given a "
            "pinned base: a free base is never drawn pinned; pass the run's scene base"
        )
    else:
        root = np.zeros((phi.shape[0], 2))
    x0, y0 = root[:, :1], root[:, 1:2]
    return (
        np.hstack([x0, x0 + np.cumsum(l * np.cos(phi), axis=1)]),
        np.hstack([y0, y0 + np.cumsum(l * np.sin(phi), axis=1)]),
    )


def _count(times: np.ndarray) -> str:
    span = f" {times[0]:g}..{times[-1]:g} s" if times.size else ""
    return f"{times.size} output time{'s' if times.size != 1 else ''}{span}"


def shared_times(runs: Mapping[str, Trajectory]) -> np.ndarray:
    """The output times (s) every run has (equal within 1e-12 s), in order: a run is drawn
    only at times it has (a failed run, which ends early, ends the animation). ValueError
    naming each run's output times when they share fewer than two."""
    shared = np.asarray(next(iter(runs.values())).times, float)
    for traj in runs.values():
        times = np.asarray(traj.times, float)
        if times.size == 0:
            shared = times
            break
        i = np.searchsorted(times, shared)
        lo, hi = np.clip(i - 1, 0, times.size - 1), np.clip(i, 0, times.size - 1)
        near = np.minimum(np.abs(times[lo] - shared), np.abs(times[hi] - shared))
        shared = shared[near <= 1e-12]
    if shared.size < 2 and len(runs) == 1:
        label, traj = next(iter(runs.items()))
        raise ValueError(f"run {label} has {_count(traj.times)}: an animation needs at least 2")
    if shared.size < 2:
        each = "; ".join(f"{k}: {_count(t.times)}" for k, t in runs.items())
        raise ValueError(
            f"the runs share {shared.size} output time{'s' if shared.size != 1 else ''} "
            f"({each}); an animation draws each run only at times it has and needs at least 2 "
            "common ones: rerun them with the same --times"
        )
    return shared


def frame_times(runs: Mapping[str, Trajectory], frames: int) -> np.ndarray:
    """Up to ``frames`` times (s), evenly spaced over the output times all runs share
    (``shared_times``)."""
    shared = shared_times(runs)
    if shared.size <= frames:
        return shared
    return shared[np.unique(np.linspace(0, shared.size - 1, frames).round().astype(int))]


def _event_marks(traj: Trajectory) -> list[tuple[float, int, str]]:
    """(t, node, text) of a run's events: latches and stop contacts at their hinge's node."""
    marks = []
    for ev in traj.events:
        hinge = ev.get("hinge")
        if isinstance(hinge, (int, np.integer)) and "t" in ev:
            marks.append((float(ev["t"]), int(hinge), str(ev.get("label", "event"))))
    return sorted(marks)


def _writer(path: Path, fps: int) -> animation.AbstractMovieWriter:
    if path.suffix == ".gif":
        return animation.PillowWriter(fps=fps)
    if not animation.writers.is_available("ffmpeg"):
        raise ValueError(f"--out {path}: .mp4 needs the ffmpeg program on PATH; write a .gif")
    return animation.FFMpegWriter(fps=fps)


def _check_request(path: Path, runs: Mapping[str, Trajectory], fps: int, frames: int) -> Path:
    """``path`` when the animation can be made, else ValueError naming what is wrong."""
    if path.suffix not in FORMATS:
        raise ValueError(f"--out must end in one of {FORMATS}, got {path.name!r}")
    if not runs:
        raise ValueError("runs: give at least one run to animate")
    if not (isinstance(fps, int) and 1 <= fps <= MAX_FPS):
        raise ValueError(f"fps must be an integer in [1, {MAX_FPS}], got {fps!r}")
    if not (isinstance(frames, int) and 2 <= frames <= MAX_FRAMES):
        raise ValueError(f"frames must be an integer in [2, {MAX_FRAMES}], got {frames!r}")
    if any(t.times.size == 0 for t in runs.values()):
        raise ValueError("a run has no output times: nothing to animate")
    return path


def animate_runs(
    runs: Mapping[str, Trajectory],
    lengths: Mapping[str, np.ndarray],
    path: Path | str,
    *,
    fps: int = 20,
    frames: int = 200,
    title: str = "",
    bases: Mapping[str, Base] | None = None,
) -> Animated:
    """Write the runs' motion to ``path`` (.gif or .mp4): every run's chain in its own colour,
    one frame per frame time (``frame_times``), the time in the title, each latch drawn as a
    red square on its hinge node from its lock time on and each stop contact as an orange
    diamond at its time, the events so far listed in the corner. ``lengths``: rod lengths (m)
    per run label; ``bases``: each run's base (default pinned: the pin drawn at the origin; a
    free base's chain hangs from its node 0, ``node_history``). Each run is drawn only at
    output times it has: the frames are the times all runs share (``shared_times``).
    Cost O(frames x (n + events)) drawing."""
    path = _check_request(Path(path), runs, fps, frames)
    writer = _writer(path, fps)
    times = frame_times(runs, frames)
    base = {k: (bases or {}).get(k, PINNED) for k in runs}
    nodes = {k: node_history(t, np.asarray(lengths[k], float), base[k]) for k, t in runs.items()}
    # every frame time is an output time of every run (within 1e-12 s): its own row
    index = {k: np.searchsorted(t.times, times - 1e-12) for k, t in runs.items()}
    marks = {k: _event_marks(t) for k, t in runs.items()}
    fig = Figure(figsize=(6.4, 5.2))
    ax = fig.add_subplot()
    allx = np.concatenate([x.ravel() for x, _ in nodes.values()])
    ally = np.concatenate([y.ravel() for _, y in nodes.values()])
    pad = 0.05 * max(float(np.ptp(allx)), float(np.ptp(ally)), 1e-9)
    ax.set_xlim(allx.min() - pad, allx.max() + pad)
    ax.set_ylim(ally.min() - pad, ally.max() + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.grid(alpha=0.3)
    if any(not b.free for b in base.values()):
        ax.plot([0], [0], "k^", ms=9)  # the pin of the pinned runs
    lines = {
        k: ax.plot(
            [], [], "-o", color=MODEL_COLOURS[i % len(MODEL_COLOURS)], ms=3, lw=1.6, label=k
        )[0]
        for i, k in enumerate(runs)
    }
    locks = {k: ax.plot([], [], "s", color="red", ms=8, mfc="none", mew=2)[0] for k in runs}
    stops = {k: ax.plot([], [], "D", color="orange", ms=7, mfc="none", mew=1.5)[0] for k in runs}
    ax.legend(loc="upper right", fontsize=7)
    note = ax.text(0.01, 0.01, "", transform=ax.transAxes, fontsize=7, va="bottom")
    head = ax.set_title("")
    step = float(np.median(np.diff(times))) if times.size > 1 else 0.0

    def draw(i: int) -> None:
        t = times[i]
        text = []
        for k in runs:
            x, y = nodes[k][0][index[k][i]], nodes[k][1][index[k][i]]
            lines[k].set_data(x, y)
            done = [(te, node, lab) for te, node, lab in marks[k] if te <= t + 1e-12]
            latched = [node for _, node, lab in done if "latch" in lab]
            recent = [node for te, node, lab in done if "latch" not in lab and t - te <= step]
            locks[k].set_data(x[latched], y[latched])
            stops[k].set_data(x[recent], y[recent])
            text += [f"{k}: {lab} at {te:.3f} s" for te, _, lab in done[-4:]]
        note.set_text("\n".join(text))
        head.set_text(f"{title + ': ' if title else ''}t = {t:.3f} s")

    with writer.saving(fig, str(path), dpi=90):
        for i in range(times.size):
            draw(i)
            writer.grab_frame()
    events = tuple((k, te, lab) for k in runs for te, _, lab in marks[k] if te <= times[-1])
    return Animated(path, int(times.size), times, events)
