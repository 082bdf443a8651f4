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
from typing import Any

import numpy as np
from matplotlib import animation
from matplotlib.figure import Figure

from rodval.core.base import PINNED, Base, rotate
from rodval.core.out_paths import write_with
from rodval.core.trajectory import Trajectory
from rodval.report.figures import MODEL_COLOURS, body_outline

#: Output formats and their writers.
FORMATS = (".gif", ".mp4")
#: Largest frame count and frame rate accepted (a long run is subsampled to ``frames``).
MAX_FRAMES = 5000
MAX_FPS = 120


@dataclass(frozen=True)
class Animated:
    """What was written: the file, the frame count, the frame times (s) and the events marked
    (run label, t (s), event label); ``notes``: what could not be drawn (a free body whose run
    recorded x, y but not its pose, output "base")."""

    path: Path
    frames: int
    times: np.ndarray
    events: tuple[tuple[str, float, str], ...]
    notes: tuple[str, ...] = ()


def body_pose(traj: Trajectory, base: Base) -> tuple[np.ndarray, np.ndarray] | None:
    """The body's centre of mass (m, (nt, 2)) and attitude (rad, (nt,)) at the run's output
    times: from its outputs base_position, base_attitude (output "base") when recorded, else
    for a prescribed base from its motion laws (closed form); None for a pinned base and for
    a free one without those outputs."""
    if not base.moving:
        return None
    if "base_position" in traj.values and "base_attitude" in traj.values:
        return np.asarray(traj.values["base_position"], float), np.asarray(
            traj.values["base_attitude"], float
        )[:, 0]
    if base.prescribed:
        states = [base.state_at(float(t)) for t in traj.times]
        return (
            np.array([s[0] for s in states]).reshape(-1, 2),
            np.array([s[2] for s in states], float),
        )
    return None


def node_history(
    traj: Trajectory, l: np.ndarray, base: Base = PINNED
) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (m), each (nt, n + 1): x, y if the run recorded them, else the chord
    polygon from phi and the rod lengths ``l`` hung from node 0: the origin for a pinned
    ``base``, r_0 = r_c + R(theta) h for a moving one (``body_pose``: a free body's
    base_position and base_attitude, output "base"; a prescribed body's motion laws).
    ValueError when the outputs cannot place the chain (a free base without x, y or "base"),
    and for a run with a moving base's outputs given a pinned ``base``: a moving base is
    never drawn pinned. O(nt n)."""
    if "x" in traj.values and "y" in traj.values:
        return traj.values["x"], traj.values["y"]
    if "phi" not in traj.values:
        raise ValueError(
            f"run {traj.model!r} has neither x, y nor phi among its outputs: nothing to draw"
        )
    phi = traj.values["phi"]
    pose = body_pose(traj, base)
    if base.free and pose is None:
        missing = [q for q in ("base_position", "base_attitude") if q not in traj.values]
        raise ValueError(
            f"run {traj.model!r} has a free base but neither x, y nor {', '.join(missing)} "
            "(output 'base') among its outputs, so the chain cannot be drawn where the "
            "body moved; rerun it with outputs x, y or 'base'"
        )
    if pose is not None:
        root = pose[0] + rotate(pose[1], np.asarray(base.hinge_offset, float))
    elif "base_position" in traj.values:
        raise ValueError(
            f"run {traj.model!r} has a moving base's outputs (base_position) but was given a "
            "pinned base: a moving base is never drawn pinned; pass the run's scene base"
        )
    else:
        root = np.zeros((phi.shape[0], 2))
    x0, y0 = root[:, :1], root[:, 1:2]
    return (
        np.hstack([x0, x0 + np.cumsum(l * np.cos(phi), axis=1)]),
        np.hstack([y0, y0 + np.cumsum(l * np.sin(phi), axis=1)]),
    )


def body_size(base: Base, l: np.ndarray) -> float:
    """Half side (m) of the square drawn for a body: its hinge offset's length (node 0 on
    the square's edge), at least 5 % of the chain's length so that it shows."""
    return max(float(np.hypot(*base.hinge_offset)), 0.05 * float(np.sum(l)))


def run_base(traj: Trajectory) -> Base:
    """The base of the scene a run carries (``Trajectory.scene``: a run of ``rodval.simulate``),
    pinned for a run without one (read from files: its scene is in run.json)."""
    scene = traj.scene
    return scene.base if scene is not None else PINNED


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
    picked: np.ndarray = shared[
        np.unique(np.linspace(0, shared.size - 1, frames).round().astype(int))
    ]
    return picked


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
    diamond at its time, the latest events so far listed beside the drawing, never over it
    (``listed``, ``_side_panel``), a moving base's body as a square in the run's colour at
    its position and attitude (``body_pose``, ``body_size``).
    The missing folders above ``path`` are made; the file is written whole or not at all,
    never through a link (``write_with``). ``lengths``: rod lengths (m)
    per run label; ``bases``: each run's base (default ``run_base``: the base of the scene the
    run carries, else pinned, the pin drawn at the origin; a free base's chain hangs from its
    node 0, ``node_history``). Each run is drawn only at
    output times it has: the frames are the times all runs share (``shared_times``).
    Cost O(frames x (n + events)) drawing."""
    path = _check_request(Path(path), runs, fps, frames)
    writer = _writer(path, fps)
    times = frame_times(runs, frames)
    base = {k: (bases or {}).get(k) or run_base(t) for k, t in runs.items()}
    nodes = {k: node_history(t, np.asarray(lengths[k], float), base[k]) for k, t in runs.items()}
    bodies, notes = _bodies(runs, lengths, base)
    # every frame time is an output time of every run (within 1e-12 s): its own row
    index = {k: np.searchsorted(t.times, times - 1e-12) for k, t in runs.items()}
    marks = {k: _event_marks(t) for k, t in runs.items()}
    fig, ax = _frame_axes([*nodes.values(), *bodies.values()], base)
    lines, locks, body, stops = _artists(ax, list(runs), list(bodies))
    note = _side_panel(fig, ax, len(runs))
    head = ax.set_title("")
    step = float(np.median(np.diff(times))) if times.size > 1 else 0.0

    def draw(i: int) -> None:
        t = times[i]
        text: list[tuple[float, str]] = []
        for k in runs:
            x, y = nodes[k][0][index[k][i]], nodes[k][1][index[k][i]]
            lines[k].set_data(x, y)
            if k in bodies:
                body[k].set_data(bodies[k][0][index[k][i]], bodies[k][1][index[k][i]])
            done = [(te, node, lab) for te, node, lab in marks[k] if te <= t + 1e-12]
            latched = [node for _, node, lab in done if "latch" in lab]
            recent = [node for te, node, lab in done if "latch" not in lab and t - te <= step]
            locks[k].set_data(x[latched], y[latched])
            stops[k].set_data(x[recent], y[recent])
            text += [(te, f"{k}: {lab} at {te:.3f} s") for te, _, lab in done]
        note.set_text("\n".join(listed(text)))
        head.set_text(f"{title + ': ' if title else ''}t = {t:.3f} s")

    def produce(tmp: Path) -> None:
        with writer.saving(fig, str(tmp), dpi=90):
            for i in range(times.size):
                draw(i)
                writer.grab_frame()

    write_with(path, produce)
    events = tuple((k, te, lab) for k in runs for te, _, lab in marks[k] if te <= times[-1])
    return Animated(path, int(times.size), times, events, tuple(notes))


def _artists(ax: Any, runs: list[str], bodies: list[str]) -> tuple[dict[str, Any], ...]:
    """The lines the frames fill, by run label: each run's chain (in its colour), latch marks
    (red squares), body outline (``bodies``: the runs with a moving base's body) and stop
    contacts (orange diamonds)."""
    lines = {
        k: ax.plot(
            [], [], "-o", color=MODEL_COLOURS[i % len(MODEL_COLOURS)], ms=3, lw=1.6, label=k
        )[0]
        for i, k in enumerate(runs)
    }
    locks = {k: ax.plot([], [], "s", color="red", ms=8, mfc="none", mew=2)[0] for k in runs}
    body = {k: ax.plot([], [], "-", color=lines[k].get_color(), lw=2.2)[0] for k in bodies}
    stops = {k: ax.plot([], [], "D", color="orange", ms=7, mfc="none", mew=1.5)[0] for k in runs}
    return lines, locks, body, stops


#: The most events the animation lists at a time (the latest), beside the drawing.
LISTED_EVENTS = 12


def listed(events: list[tuple[float, str]]) -> list[str]:
    """The lines of the event list: the LISTED_EVENTS latest of ``events`` ((t s, text)),
    in time order, the first line saying how many earlier ones are left out."""
    events = sorted(events, key=lambda e: e[0])
    shown = [text for _, text in events[-LISTED_EVENTS:]]
    more = len(events) - len(shown)
    return [f"... {more} earlier", *shown] if more else shown


def _side_panel(fig: Figure, ax: Any, runs: int) -> Any:
    """The legend of the ``runs`` and the event list below it, beside the axes in the
    figure's right part, which the drawing never reaches (the axes end at ``FRAME_RIGHT``
    of the width): the text object the frames fill (at most LISTED_EVENTS + 1 lines,
    ``listed``)."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize=7)
    # the legend takes about 0.04 of the height per run below the axes' top (0.9)
    top = min(0.62, 0.86 - 0.04 * runs)
    return fig.text(FRAME_RIGHT + 0.02, top, "", fontsize=6.5, va="top", ha="left")


#: The right edge of the animation's axes, as a fraction of the figure's width.
FRAME_RIGHT = 0.62


def _frame_axes(
    paths: list[tuple[np.ndarray, np.ndarray]], base: Mapping[str, Base]
) -> tuple[Figure, Any]:
    """The animation's figure and axes: equal scales holding every node and body outline of
    ``paths`` ((x, y) histories) with a 5 % margin, and the pin at the origin when a run is
    pinned."""
    fig = Figure(figsize=(9.0, 5.2))
    ax = fig.add_axes((0.09, 0.1, FRAME_RIGHT - 0.09, 0.8))
    allx = np.concatenate([x.ravel() for x, _ in paths])
    ally = np.concatenate([y.ravel() for _, y in paths])
    pad = 0.05 * max(float(np.ptp(allx)), float(np.ptp(ally)), 1e-9)
    ax.set_xlim(allx.min() - pad, allx.max() + pad)
    ax.set_ylim(ally.min() - pad, ally.max() + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.grid(alpha=0.3)
    if any(not b.moving for b in base.values()):
        ax.plot([0], [0], "k^", ms=9)  # the pin of the pinned runs
    return fig, ax


def _bodies(
    runs: Mapping[str, Trajectory], lengths: Mapping[str, np.ndarray], base: Mapping[str, Base]
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], list[str]]:
    """The outline of each moving base's body at the run's output times (``body_outline``,
    ``body_pose``) by run label, and a note for each free body whose pose the run did not
    record (drawn from its x, y: the chain, not the body)."""
    bodies, notes = {}, []
    for k, traj in runs.items():
        pose = body_pose(traj, base[k])
        if pose is not None:
            half = body_size(base[k], np.asarray(lengths[k], float))
            bodies[k] = body_outline(pose[0], pose[1], half)
        elif base[k].moving:
            notes.append(
                f"run {k}: its free body is not drawn (the run recorded x, y but not the "
                "body's position and attitude, output 'base')"
            )
    return bodies, notes
