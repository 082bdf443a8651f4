"""Running one case in a worker process.

``python -m rodval.study.worker`` is a warm worker: it imports rodval and loads the compiled
kernels and integrator once, then reads case payloads (JSON, one per line, see
``Case.payload``) on stdin and, for each, prints one JSON line per model run as soon as it
finishes and a final ``{"done": CASE}`` line. The parent (``rodval.study.schedule``) kills it
at a case's time limit or when it crashes and starts a fresh one; the runs it had finished
are kept.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Iterator
from typing import Any

from rodval.core.scene import Scene
from rodval.core.scene_file import scene_from_dict
from rodval.core.settings import IntegratorSettings
from rodval.core.status import STATUS_ERROR
from rodval.core.trajectory import SolverStats, Trajectory
from rodval.models.registry import modal_options, simulate


def failed_run(model: dict[str, Any], scene_name: str, status: int, message: str) -> dict[str, Any]:
    """A run record for a model that produced nothing (error before integration, timeout...)."""
    traj = Trajectory.failed(
        model["model"],
        scene_name,
        SolverStats(status=status, message=message),
        settings=model["settings"],
        options=model["options"],
    )
    return {"label": model["label"], "setup_s": 0.0, "trajectory": traj.to_dict()}


def iter_case(payload: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """Run every model of a case in turn, yielding one run record per model.

    Each run goes through ``rodval.models.registry.simulate``, the entry point of
    ``rodval simulate`` (the model's options and memory checked before it runs). A model that
    raises (including "not available") yields a failed run with status ``model error``; the
    next model still runs.
    """
    scene = scene_from_dict(payload["scene"], where=payload["where"])
    for model in payload["models"]:
        start = time.perf_counter()
        try:
            traj = simulate(
                scene,
                model["model"],
                settings=IntegratorSettings(**model["settings"]),
                **model["options"],
            )
        except Exception as exc:  # noqa: BLE001 - a failure is data
            yield failed_run(model, scene.name, STATUS_ERROR, f"{type(exc).__name__}: {exc}")
            continue
        total = time.perf_counter() - start
        run = {
            "label": model["label"],
            "setup_s": max(total - traj.stats.wall_s, 0.0),
            "trajectory": traj.to_dict(),
        }
        if payload.get("modes"):
            run.update(case_modes(scene, model, payload["modes"]))
        yield run


def case_modes(scene: Scene, model: dict[str, Any], spec: dict[str, Any]) -> dict[str, Any]:
    """``{"modes": ...}`` (``Modes.to_dict``) of one model about the study's configuration,
    or ``{"modes_error": message}``: a failed modal analysis never fails the run."""
    from rodval.analysis.modes import model_modes

    try:
        options = modal_options(model["model"], model["options"])
        m = model_modes(
            scene,
            model["model"],
            about=spec["about"],
            count=spec["count"],
            load_at=spec.get("load_at"),
            allow_unbalanced=spec.get("allow_unbalanced", False),
            **options,
        )
    except Exception as exc:  # noqa: BLE001 - a failure is data
        return {"modes_error": f"{type(exc).__name__}: {exc}"}
    return {"modes": m.to_dict()}


def warm_up() -> None:
    """Load what every case needs (compiled kernels and integrator) once per process."""
    from rodval.solvers import dop853  # noqa: F401 - loading it is the point


def main() -> int:
    warm_up()
    sys.stdout.write(json.dumps({"ready": True}) + "\n")
    sys.stdout.flush()
    for line in sys.stdin:
        if not line.strip():
            continue
        payload = json.loads(line)
        for run in iter_case(payload):
            sys.stdout.write(json.dumps(run) + "\n")
            sys.stdout.flush()
        sys.stdout.write(json.dumps({"done": payload["case"]}) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
