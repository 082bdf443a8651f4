"""Running one case: in this process (``run_case``) or isolated in a child process
(``run_case_isolated``) that can be stopped at a time limit and whose crash (even a segfault
in a compiled library) is recorded instead of taking the study down.

The child is ``python -m rodval.study.worker``: it reads a case payload (JSON, see
``Case.payload``) on stdin and prints one JSON line per model run as soon as it finishes, so
runs finished before a timeout or crash are kept.
"""
from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from typing import Any, Iterator

import numpy as np

from ..models import get_model
from ..scene_file import scene_from_dict
from ..settings import IntegratorSettings
from ..trajectory import (STATUS_CRASHED, STATUS_ERROR, STATUS_TIMEOUT, SolverStats,
                          Trajectory)

_LIVE: set[subprocess.Popen] = set()
_LIVE_LOCK = threading.Lock()


def failed_run(model: dict, scene_name: str, status: int, message: str) -> dict[str, Any]:
    """A run record for a model that produced nothing (error before integration, timeout...)."""
    traj = Trajectory(model=model["model"], scene_name=scene_name, times=np.zeros(0), values={},
                      k_index={}, stats=SolverStats(status=status, message=message),
                      settings={**model["settings"], **model["options"]})
    return {"label": model["label"], "setup_s": 0.0, "trajectory": traj.to_dict()}


def iter_case(payload: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """Run every model of a case in turn, yielding one run record per model.

    A model that raises (including "not available") yields a failed run with status
    ``model error``; the next model still runs.
    """
    scene = scene_from_dict(payload["scene"], where=payload["where"])
    for model in payload["models"]:
        start = time.perf_counter()
        try:
            m = get_model(model["model"], **model["options"])
            traj = m.simulate(scene, IntegratorSettings(**model["settings"]))
        except Exception as exc:  # noqa: BLE001 - a failure is data
            yield failed_run(model, scene.name, STATUS_ERROR, f"{type(exc).__name__}: {exc}")
            continue
        total = time.perf_counter() - start
        yield {"label": model["label"], "setup_s": max(total - traj.stats.wall_s, 0.0),
               "trajectory": traj.to_dict()}


def run_case(payload: dict[str, Any]) -> list[dict[str, Any]]:
    """Run a case in this process (no time limit, no crash isolation)."""
    return list(iter_case(payload))


def complete_runs(payload: dict, runs: list[dict], status: int, message: str) -> list[dict]:
    done = {r["label"] for r in runs}
    name = payload["scene"].get("name", payload["case"])
    return runs + [failed_run(m, name, status, message)
                   for m in payload["models"] if m["label"] not in done]


def run_case_isolated(payload: dict[str, Any], timeout: float | None = None) -> list[dict[str, Any]]:
    """Run a case in a child process; after ``timeout`` seconds (None: no limit) the child is
    killed and the models it had not finished are recorded with status ``timeout``."""
    proc = subprocess.Popen([sys.executable, "-m", "rodval.study.worker"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    with _LIVE_LOCK:
        _LIVE.add(proc)
    timed_out = False
    try:
        try:
            out, err = proc.communicate(json.dumps(payload), timeout=timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
            proc.kill()
            out, err = proc.communicate()
    finally:
        with _LIVE_LOCK:
            _LIVE.discard(proc)
    runs = []
    for line in out.splitlines():
        try:
            runs.append(json.loads(line))
        except json.JSONDecodeError:
            break  # a line cut short by the kill
    if timed_out:
        return complete_runs(payload, runs, STATUS_TIMEOUT, f"case exceeded its time limit of {timeout:g} s")
    if proc.returncode != 0 or len(runs) < len(payload["models"]):
        tail = " | ".join(err.strip().splitlines()[-2:]) or "no message"
        return complete_runs(payload, runs, STATUS_CRASHED,
                         f"worker exited with code {proc.returncode}: {tail}")
    return runs


def kill_live_workers() -> None:
    """Kill the child processes of this process's running cases (on interrupt)."""
    with _LIVE_LOCK:
        procs = list(_LIVE)
    for p in procs:
        p.kill()


def main() -> int:
    payload = json.loads(sys.stdin.read())
    for run in iter_case(payload):
        sys.stdout.write(json.dumps(run) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
