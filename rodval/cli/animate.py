"""rodval animate RUN [RUN ...] --out FILE.gif|mp4: the chain's motion from run folders of
`rodval simulate`, several runs overlaid, time, locks and stop contacts marked."""

from __future__ import annotations

import argparse
from pathlib import Path

from rodval.cli import SUMMARIES
from rodval.cli.options import positive_int

#: ``rodval animate --help``'s description (argparse rewraps it).
DESCRIPTION = """Write the chain's motion of one or more `rodval simulate` run folders to FILE (.gif
with Pillow, .mp4 with the ffmpeg program), the runs overlaid in one frame each, the time in the
title, each latch marked on its hinge node from its lock on, stop contacts marked at their times.
Nodes from the runs' x, y outputs, else from phi and the rod lengths, hung from the pin at the
origin or, for a free base, from node 0 where the body moved (output 'base'; a free-base run with
neither x, y nor 'base' is refused). Each run is drawn only at output times it has: the frames are
the output times all runs share (a note says so when the runs' times differ; runs sharing fewer than
2 are refused). A free or prescribed base's body is drawn as a square at its position and attitude
(from output 'base', or a prescribed base's laws). The folders above FILE are made when missing;
FILE inside another command's output folder, or a link, is refused before any work."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from rodval.report.animation import MAX_FPS, MAX_FRAMES

    p = sub.add_parser("animate", help=SUMMARIES["animate"], description=DESCRIPTION)
    p.add_argument("runs", metavar="RUN", type=Path, nargs="+", help="run folder(s)")
    p.add_argument("--out", required=True, type=Path, help="FILE.gif or FILE.mp4")
    p.add_argument(
        "--fps",
        type=positive_int("--fps"),
        default=20,
        help=f"frames per second (default 20, at most {MAX_FPS})",
    )
    p.add_argument(
        "--frames",
        type=positive_int("--frames"),
        default=200,
        help=f"most frames, evenly spaced over the output times (default 200, 2..{MAX_FRAMES})",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rodval.core.out_paths import check_output_file, in_command_folder
    from rodval.core.scene_file import scene_from_dict
    from rodval.report.animation import FORMATS, animate_runs, shared_times
    from rodval.report.run_files import read_run, read_run_record

    if args.out.suffix not in FORMATS:
        raise ValueError(f"--out must end in one of {FORMATS}, got {args.out.name!r}")
    # before any work: a place a file can be made (missing folders are), no link, no folder
    # of another command; an existing animation there is replaced
    check_output_file(args.out, "--out", reserved=in_command_folder, ours=lambda p: True)
    runs, lengths, bases = {}, {}, {}
    for folder in args.runs:
        traj = read_run(folder)
        label = f"{folder.name} ({traj.model})"
        if label in runs:
            label = f"{folder} ({traj.model})"
        scene = scene_from_dict(read_run_record(folder / "run.json")["scene"], where=str(folder))
        runs[label], lengths[label], bases[label] = traj, scene.chain.l, scene.base
    try:
        done = animate_runs(runs, lengths, args.out, fps=args.fps, frames=args.frames, bases=bases)
    except ValueError as exc:
        if str(exc).startswith("--out"):
            raise
        raise ValueError(f"{', '.join(map(str, args.runs))}: {exc}") from None
    print(
        f"{done.frames} frames, {len(done.events)} events marked, "
        f"t = {done.times[0]:g}..{done.times[-1]:g} s -> {done.path}"
    )
    for note in done.notes:
        print(f"note: {note}")
    counts = {label: traj.times.size for label, traj in runs.items()}
    if len(set(counts.values())) > 1:
        each = ", ".join(f"{label}: {c}" for label, c in counts.items())
        print(
            f"note: the runs' output times differ ({each} output times): each run is drawn "
            f"only at the {shared_times(runs).size} output times they share"
        )
    return 0
