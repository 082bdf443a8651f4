"""Cost of the chain engine's combinations, as ratios in one run (issue 40):

1. per right-hand-side evaluation, best of 7, against the paper preset's kernel on the same
   chain (pinned, first-order, p = 1): the base (pinned, free, prescribed) x kinematics x p, on
   a chain of n = 8 and 512 rods (O(n p^2): the ratio is flat in n);
2. end to end on the user's 6-panel wing (``exudyn_speed.wing_scene``, 2 s, pinned): the
   exact p = 3 rung's wall time against the paper preset's, with the evaluations each took
   (a rung with more shapes has faster bending modes, so an explicit method takes more steps).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/chain_engine_cost.py
"""

from __future__ import annotations

import time
import timeit

import numpy as np
from exudyn_speed import wing_scene

from rodval.core.base import Base, Motion
from rodval.core.scene import Chain, Scene
from rodval.models import simulate
from rodval.models.presets.full import FullModel

BASES = {
    "pinned": Base(),
    "free": Base(kind="free", mass=800.0, inertia=533.0, hinge_offset=(1.0, 0.0)),
    "prescribed": Base(kind="prescribed", motion={"attitude": Motion("spin_up", (1.0, 5.0))}),
}
RUNGS = [("first-order", 1), ("exact", 1), ("exact", 3)]


def per_call(system, y, repeat: int = 7) -> float:
    """Best-of-``repeat`` seconds per rhs call (enough calls for ~0.1 s per sample)."""
    calls = max(1, int(0.1 / max(timeit.timeit(lambda: system.rhs(0.0, y), number=1), 1e-7)))
    return min(timeit.repeat(lambda: system.rhs(0.0, y), number=calls, repeat=repeat)) / calls


def evaluation_table() -> None:
    rng = np.random.default_rng(0)
    head = ["n", "paper preset (us)"] + [f"{b}, {k}, p = {p}" for b in BASES for k, p in RUNGS]
    print("| " + " | ".join(head) + " |")
    print("|" + "---:|" * len(head))
    for n in (8, 512):
        chain = Chain.uniform(n, l=2.0, m=3.0, mu=3.0, EI=1e5, kappa=100.0, nu=0.01)
        cells = []
        paper = None
        for base in BASES.values():
            scene = Scene(chain=chain, t_end=1.0, base=base)
            for kinematics, p in RUNGS:
                system = FullModel(shapes=p, kinematics=kinematics).system(scene)
                y = system.y0 + 1e-2 * rng.standard_normal(system.y0.size)
                cost = per_call(system, y)
                if paper is None:
                    paper = cost
                cells.append(f"{cost / paper:.2f}")
        print(f"| {n} | {paper * 1e6:.1f} | " + " | ".join(cells) + " |")


def wing_table() -> None:
    scene = wing_scene(2.0)
    print("\n| wing (2 s, pinned) | wall (s) | evaluations | ratio to the paper preset |")
    print("|---|---:|---:|---:|")
    first = None
    for label, options in (
        ("paper preset", {}),
        ("exact, p = 1", {"kinematics": "exact"}),
        ("exact, p = 3", {"kinematics": "exact", "shapes": 3}),
    ):
        start = time.perf_counter()
        tr = simulate(scene, "full", **options)
        wall = time.perf_counter() - start
        first = wall if first is None else first
        print(f"| {label} | {wall:.2f} | {tr.stats.nfev} | {wall / first:.2f} |")


if __name__ == "__main__":
    evaluation_table()
    wing_table()
