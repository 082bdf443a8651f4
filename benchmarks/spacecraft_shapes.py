"""The deployed attitude of the six-panel wing on the 800 kg body against the full model's
shapes per rod (docs/deployment.md, "The wing on a spacecraft"): for p = 1, 3, 5 shapes per
rod (kinematics "auto": exact here), the lock times, and the chord angles and the body's
attitude averaged after the last lock (``rodval.analysis.convergence.deployed_mean``, the
definition ``rodval reference`` converges and the study's answer compares).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/spacecraft_shapes.py     # about 3 min
"""

from __future__ import annotations

import time

import numpy as np

from rodval.analysis.convergence import deployed_mean
from rodval.analysis.events import is_lock
from rodval.core.scene_file import load_scene
from rodval.models import simulate

SCENE = "studies/scenes/wing6_spacecraft.toml"


def main() -> None:
    scene = load_scene(SCENE).with_(outputs=("phi", "base"))
    print(
        "| shapes | status | wall (s) | evaluations | locks (hinge: t s) | deployed attitude (rad) |"
    )
    print("|---|---|---|---|---|---|")
    for p in (1, 3, 5):
        start = time.perf_counter()
        tr = simulate(scene, "full", shapes=p, max_evaluations=20_000_000)
        wall = time.perf_counter() - start
        locks = [(ev["label"].split()[-1], ev["t"]) for ev in tr.events if is_lock(ev["label"])]
        since = max(t for _, t in locks)
        attitude = float(np.ravel(deployed_mean(tr.times, tr["base_attitude"], since))[0])
        times = ", ".join(f"{h}: {t:.6f}" for h, t in locks)
        print(
            f"| {p} | {tr.stats.status} | {wall:.1f} | {tr.stats.nfev} | {times} | {attitude:.4f} |"
        )


if __name__ == "__main__":
    main()
