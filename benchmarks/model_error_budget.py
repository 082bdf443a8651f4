"""The model error budget of the paper example: each rung of the full model's ladder against
exudyn refined (docs/model.md, "The model ladder"; the study is studies/model_error_budget.toml).

    PYTHONPATH=. python benchmarks/model_error_budget.py [--elements 4] [--step 5e-5] [--EA 1e11]

Rungs: the paper's (first-order kinematics, p = 1), exact p = 1, exact p = 2..4. For each:
max |phi - phi_ex| over the rods at the Table 1 times, and max |alpha - alpha_ex|,
|beta - beta_ex| at the two of them under load (0.5, 1.0 s: after the load ends the rods ring
at ~430 Hz, undamped, and that ringing's phase is not comparable pointwise between models;
docs/model.md) (rad). The split (``rodval.report.error_budget.split_gaps``, the study report's
Error budget table): kinematics = gap(first-order, 1) - gap(exact, 1); shapes = gap(exact,
1) - gap(exact, 4); what is left at exact p = 4 is exudyn's own discretization and axial
stretch (EA) plus what no rung carries (axial shortening from bending).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

import rodval
from rodval import simulate
from rodval.report.error_budget import split_gaps

RUNGS = [("first-order", 1), ("exact", 1), ("exact", 2), ("exact", 3), ("exact", 4)]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--elements", type=int, default=8)
    ap.add_argument("--step", type=float, default=5e-5)
    ap.add_argument("--EA", type=float, default=1e11)
    args = ap.parse_args()
    scene = rodval.paper_scene()
    scene = scene.with_(outputs=("phi", "alpha", "beta"), times=np.array(rodval.TABLE1_TIMES))
    loaded = scene.times <= 1.0
    t0 = time.perf_counter()
    ex = simulate(scene, "exudyn", elements=args.elements, step=args.step, EA=args.EA)
    print(
        f"exudyn: {args.elements} elements/rod, step {args.step:g} s, EA {args.EA:g} N: "
        f"{ex.stats.status.name}, {time.perf_counter() - t0:.1f} s"
    )
    gaps = {}
    for kin, p in RUNGS:
        tr = simulate(scene, "full", shapes=p, kinematics=kin, rtol=1e-10, atol=1e-12)
        gaps[(kin, p)] = {
            q: float(np.max(np.abs(tr[q] - ex[q])[rows]))
            for q, rows in (("phi", slice(None)), ("alpha", loaded), ("beta", loaded))
        }
    print("\n| rung | phi gap (rad) | alpha gap (rad) | beta gap (rad) |")
    print("|---|---:|---:|---:|")
    for (kin, p), g in gaps.items():
        print(f"| {kin}, p = {p} | {g['phi']:.2e} | {g['alpha']:.2e} | {g['beta']:.2e} |")
    records = [
        {"kinematics": kin, "shapes": p, "quantity": q, "gap": g}
        for (kin, p), by_q in gaps.items()
        for q, g in by_q.items()
    ]
    split = split_gaps(pd.DataFrame(records))
    assert split is not None  # RUNGS holds every rung the split needs
    p_max = int(split["p_max"].iloc[0])
    print(
        "\n| quantity | first-order kinematics costs | one shape costs "
        f"| left at exact p = {p_max} |"
    )
    print("|---|---:|---:|---:|")
    for row in split.itertuples():
        print(f"| {row.quantity} | {row.kinematics:.2e} | {row.shapes:.2e} | {row.remainder:.2e} |")


if __name__ == "__main__":
    main()
