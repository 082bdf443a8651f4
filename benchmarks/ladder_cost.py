"""Cost of one right-hand-side evaluation on the model ladder against n and p, as ratios to
the paper's kernel (shapes = 1, first-order) in the same run (docs/model.md, "The model
ladder": O(n p^2) per evaluation).

    PYTHONPATH=. python benchmarks/ladder_cost.py

Prints, per n, the paper kernel's microseconds per evaluation and every rung's ratio to it;
the last column is the exact rung's cost per rod at the largest p over the smallest n's (flat
when the cost is linear in n).
"""

from __future__ import annotations

import timeit

import numpy as np

from rodval.core.scene import Chain, Scene
from rodval.models.presets.full import FullModel

RUNGS = [(1, "exact"), (2, "exact"), (3, "exact"), (4, "exact"), (4, "first-order")]
SIZES = (8, 64, 512, 4096)


def per_call(system, y, repeat=7) -> float:
    """Best-of-``repeat`` seconds per rhs call (enough calls for ~0.1 s per sample)."""
    calls = max(1, int(0.1 / max(timeit.timeit(lambda: system.rhs(0.0, y), number=1), 1e-7)))
    return min(timeit.repeat(lambda: system.rhs(0.0, y), number=calls, repeat=repeat)) / calls


def main() -> None:
    rng = np.random.default_rng(0)
    header = ["n", "paper (us)"] + [f"p={p} {k}" for p, k in RUNGS] + ["per-rod p=4 exact vs n=8"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---:|" * len(header))
    base_per_rod = None
    for n in SIZES:
        scene = Scene(
            chain=Chain.uniform(n, l=2.0, m=3.0, mu=3.0, EI=1e5, kappa=100.0, nu=0.01), t_end=1.0
        )
        paper = FullModel().system(scene)
        t0 = per_call(paper, paper.y0 + 1e-2 * rng.standard_normal(paper.y0.size))
        row = [str(n), f"{t0 * 1e6:.1f}"]
        last = 0.0
        for p, kin in RUNGS:
            system = FullModel(shapes=p, kinematics=kin).system(scene)
            t = per_call(system, system.y0 + 1e-2 * rng.standard_normal(system.y0.size))
            row.append(f"{t / t0:.2f}")
            if (p, kin) == (4, "exact"):
                last = t / n
        base_per_rod = base_per_rod or last
        row.append(f"{last / base_per_rod:.2f}")
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
