"""The output folder of one run (``rodval simulate``): ``trajectory.csv`` (tidy t, quantity,
k, value) and ``run.json`` (the complete resolved scene, model, options, integrator settings as
used, how the run ended, its events and provenance, and the size and SHA-256 of
trajectory.csv). ``read_run`` is the inverse of ``write_run``: a run folder is enough to
compare runs or to rerun one exactly. It refuses a trajectory.csv that is not the one its run
wrote (cut short, edited, damaged), naming the file and what is wrong."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import pandas as pd

from rodval.core.checks import check_keys
from rodval.core.provenance import provenance
from rodval.core.scene import Scene
from rodval.core.scene_file import scene_to_dict
from rodval.core.trajectory import SolverStats, Trajectory

RUN_KEYS = ("scene", "model", "options", "settings", "stats")
#: The type of each of them (a run.json whose keys have other types is refused).
RUN_KEY_TYPES = {"scene": dict, "model": str, "options": dict, "settings": dict, "stats": dict}
#: run.json's record of trajectory.csv: {"bytes": size, "sha256": hex digest}.
DIGEST_KEY = "trajectory_csv"
#: The keys a run.json may hold besides ``RUN_KEYS``.
OPTIONAL_KEYS = ("events", "provenance", DIGEST_KEY)


def file_digest(data: bytes) -> dict[str, Any]:
    """Size (bytes) and SHA-256 (hex) of a file's content, as run.json records them."""
    return {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}


def check_digest(path: Path, recorded: Any) -> None:
    """ValueError naming ``path`` unless its content has the size and SHA-256 ``recorded``."""
    check_keys(recorded, ("bytes", "sha256"), f"run.json key {DIGEST_KEY!r}")
    have = file_digest(path.read_bytes())
    if have["bytes"] != recorded.get("bytes"):
        raise ValueError(
            f"{path}: damaged: {have['bytes']} bytes, but run.json records "
            f"{recorded.get('bytes')} (the file was cut short or changed)"
        )
    if have["sha256"] != recorded.get("sha256"):
        raise ValueError(
            f"{path}: damaged: its SHA-256 differs from the one run.json records "
            "(the file was edited or damaged)"
        )


def write_run(traj: Trajectory, scene: Scene, out: Path) -> None:
    """Write ``out/trajectory.csv`` and ``out/run.json`` (which records the csv's digest)."""
    out.mkdir(parents=True, exist_ok=True)
    table = traj.to_frame().to_csv(index=False).encode()
    (out / "trajectory.csv").write_bytes(table)
    record = {
        "scene": scene_to_dict(scene),
        "model": traj.model,
        "options": traj.options,
        "settings": traj.settings,
        "stats": traj.stats.as_dict(),
        "events": traj.events,
        "provenance": provenance(),
        DIGEST_KEY: file_digest(table),
    }
    (out / "run.json").write_text(json.dumps(record, indent=2, default=str))


def read_run_record(path: Path) -> dict[str, Any]:
    """The run.json at ``path`` (ValueError naming the file when it is not one)."""
    if not path.is_file():
        raise ValueError(f"{path} does not exist")
    try:
        rec = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: damaged or not a run.json (not valid JSON: {exc})") from None
    missing = [k for k in RUN_KEYS if not isinstance(rec, dict) or k not in rec]
    if missing:
        raise ValueError(f"{path}: not a run.json of rodval simulate (no {missing[0]!r})")
    check_keys(rec, (*RUN_KEYS, *OPTIONAL_KEYS), str(path))
    for key, kind in RUN_KEY_TYPES.items():
        if not isinstance(rec[key], kind):
            raise ValueError(
                f"{path}: key {key!r} must be a {'table' if kind is dict else 'string'}, "
                f"got {rec[key]!r:.60}"
            )
    events = rec.get("events", [])
    if not isinstance(events, list) or not all(isinstance(e, dict) for e in events):
        raise ValueError(f"{path}: key 'events' must be a list of tables, got {events!r:.60}")
    return rec


def read_run(folder: Path) -> Trajectory:
    """The trajectory of a run folder written by ``write_run``, with its stats, settings,
    options and events. ValueError naming the file when trajectory.csv is not the one its
    run.json records (folders written before the digest was recorded are read unchecked)."""
    rec = read_run_record(folder / "run.json")
    path = folder / "trajectory.csv"
    if not path.is_file():
        raise ValueError(f"{path} does not exist")
    if DIGEST_KEY in rec:
        check_digest(path, rec[DIGEST_KEY])
    try:
        frame = pd.read_csv(path)
        traj = Trajectory.from_frame(frame, rec["model"], rec["scene"].get("name", "scene"))
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, KeyError, ValueError) as exc:
        raise ValueError(f"{path}: not a trajectory table of rodval simulate ({exc})") from None
    stats = {k: v for k, v in rec["stats"].items() if k != "success"}
    try:
        traj.stats = SolverStats(**stats)
    except TypeError as exc:
        raise ValueError(f"{folder / 'run.json'}: key 'stats': {exc}") from None
    traj.settings, traj.options = dict(rec["settings"]), dict(rec["options"])
    traj.events = list(rec.get("events", []))
    return traj
