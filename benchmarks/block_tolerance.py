"""Error control per coordinate block against today's uniform atol (issue 49): the 6-panel
latched wing (``exudyn_speed.wing_scene``) at EI {2e4, 1e6, 1e8, 1e9} x bending damping ratio
{0, 1 %}, full model on the defaults ("uniform") and with ``error_control = "per-block"``;
then phi's largest error on the paper example against a tight run (rtol 1e-12, atol 1e-14).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/block_tolerance.py [t_end]
"""

from __future__ import annotations

import sys
import time

import numpy as np
from exudyn_speed import wing_scene

from rodval.core.damping import bending_damping_for_ratio
from rodval.core.scene import paper_scene
from rodval.models import simulate

CONTROLS = ({}, {"error_control": "per-block"})


def wing(EI: float, ratio: float, t_end: float):
    base = wing_scene(t_end)
    chain = base.chain.with_(EI=EI)
    c = bending_damping_for_ratio(ratio, chain.l, chain.m, chain.EI)
    return base.with_(chain=chain.with_(bending_damping=c))


def main(t_end: float = 10.0) -> None:
    print("| EI | ratio | control | reached (s) | wall (s) | evaluations | locks (s) |")
    print("|---|---|---|---|---|---|---|")
    for EI in (2e4, 1e6, 1e8, 1e9):
        for ratio in (0.0, 0.01):
            for kw in CONTROLS:
                start = time.perf_counter()
                tr = simulate(wing(EI, ratio, t_end), "full", **kw)
                wall = time.perf_counter() - start
                locks = ", ".join(f"{ev['t']:.6f}" for ev in tr.events)
                print(
                    f"| {EI:g} | {ratio:g} | {kw.get('error_control', 'uniform')} | "
                    f"{tr.stats.t_reached:.3f} | {wall:.1f} | {tr.stats.nfev} | {locks} |",
                    flush=True,
                )
    scene = paper_scene()
    ref = simulate(scene, "full", rtol=1e-12, atol=1e-14)
    print("\n| paper example | evaluations | max abs phi error (rad) |\n|---|---|---|")
    for kw in CONTROLS:
        tr = simulate(scene, "full", **kw)
        err = float(np.max(np.abs(tr["phi"] - ref["phi"])))
        print(f"| {kw.get('error_control', 'uniform')} | {tr.stats.nfev} | {err:.3g} |")


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 10.0)
