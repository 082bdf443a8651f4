"""The 6-panel latched wing on the user's 800 kg spacecraft body over 10 s (issue 40): the body's
attitude theta(t) of the native full model on three rungs (first-order p = 1, the paper's;
exact p = 1; exact p = 3) against exudyn at two refinements (2 elements per rod and 2e-4 s,
4 elements and 1e-4 s), with each run's momentum residual and verdict.

The gap is max_t |theta - theta_ref| / max_t |theta_ref| with the refined exudyn run as the
reference; exudyn's own change between its two refinements is printed beside it.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/free_body_wing.py [--t-end 10]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from exudyn_speed import wing_scene
from momentum_audit import BODY

from rodval.models import simulate

RUNS = (
    ("exudyn", {"elements": 4, "step": 1e-4}),
    ("exudyn", {"elements": 2, "step": 2e-4}),
    ("full", {}),
    ("full", {"kinematics": "exact"}),
    ("full", {"kinematics": "exact", "shapes": 3}),
)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--t-end", type=float, default=10.0)
    args = parser.parse_args()
    scene = wing_scene(args.t_end).with_(base=BODY, outputs=("phi", "base"))
    ref = None
    print(f"wing on the 800 kg body, t_end = {args.t_end} s")
    print(
        "| model | options | wall (s) | theta(t_end) (rad) | max gap / max |theta_ref| "
        "| momentum residual | verdict |"
    )
    print("|---|---|---|---|---|---|---|")
    for model, options in RUNS:
        start = time.perf_counter()
        tr = simulate(scene, model, **options)
        wall = time.perf_counter() - start
        theta = tr["base_attitude"][:, 0]
        if ref is None:
            ref = theta
        m = min(ref.size, theta.size)
        gap = np.abs(theta[:m] - ref[:m]).max() / np.abs(ref).max()
        st = tr.stats
        verdict = "valid" if st.valid else "INVALID" if st.valid is False else "-"
        label = ", ".join(f"{k} = {v}" for k, v in options.items()) or "paper rung"
        res = "-" if st.momentum_residual is None else f"{st.momentum_residual:.2g}"
        print(
            f"| {model} | {label} | {wall:.1f} | {theta[-1]:.6f} | {gap:.2e} | {res} | "
            f"{verdict}: {st.message[:40]} |"
        )


if __name__ == "__main__":
    main()
