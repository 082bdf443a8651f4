"""The output folder of one run (``rodval simulate``): ``trajectory.csv`` (tidy t, quantity,
k, value) and ``run.json`` (the complete resolved scene, model, options, integrator settings as
used, how the run ended, its events and provenance). ``read_run`` is the inverse of
``write_run``: a run folder is enough to compare runs or to rerun one exactly."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd

from rodval.core.provenance import provenance
from rodval.core.scene import Scene
from rodval.core.scene_file import scene_to_dict
from rodval.core.trajectory import SolverStats, Trajectory

RUN_KEYS = ("scene", "model", "options", "settings", "stats")


def write_run(traj: Trajectory, scene: Scene, out: Path) -> None:
    """Write ``out/trajectory.csv`` and ``out/run.json``."""
    out.mkdir(parents=True, exist_ok=True)
    traj.to_frame().to_csv(out / "trajectory.csv", index=False)
    record = {
        "scene": scene_to_dict(scene),
        "model": traj.model,
        "options": traj.options,
        "settings": traj.settings,
        "stats": traj.stats.as_dict(),
        "events": traj.events,
        "provenance": provenance(),
    }
    (out / "run.json").write_text(json.dumps(record, indent=2, default=str))


def read_run_record(path: Path) -> dict[str, Any]:
    """The run.json at ``path`` (ValueError naming the file when it is not one)."""
    if not path.is_file():
        raise ValueError(f"{path} does not exist")
    try:
        rec = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not a readable run.json ({exc})") from None
    missing = [k for k in RUN_KEYS if not isinstance(rec, dict) or k not in rec]
    if missing:
        raise ValueError(f"{path}: not a run.json of rodval simulate (no {missing[0]!r})")
    return rec


def read_run(folder: Path) -> Trajectory:
    """The trajectory of a run folder written by ``write_run``, with its stats, settings,
    options and events."""
    rec = read_run_record(folder / "run.json")
    path = folder / "trajectory.csv"
    try:
        frame = pd.read_csv(path)
        traj = Trajectory.from_frame(frame, rec["model"], rec["scene"].get("name", "scene"))
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, KeyError, ValueError) as exc:
        raise ValueError(f"{path}: not a trajectory table of rodval simulate ({exc})") from None
    stats = {k: v for k, v in rec["stats"].items() if k != "success"}
    traj.stats = SolverStats(**stats)
    traj.settings, traj.options = dict(rec["settings"]), dict(rec["options"])
    traj.events = list(rec.get("events", []))
    return traj
