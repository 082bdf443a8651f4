"""The full model tends to the rigid-panel model as EI grows, where the locks' ring is damped
(docs/model.md, "The rigid model"): the latched three-rod deployment (``exudyn_speed.
latch3_scene``) in the full model (exact kinematics) at EI 1e6 .. 1e9, undamped and with 30 %
bending damping (each rod's first free-free mode), against the rigid model: each lock's time
gap (s) and the largest chord-angle gap (rad).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/rigid_limit.py      # 2-4 min
"""

from __future__ import annotations

import numpy as np
from exudyn_speed import latch3_scene

from rodval import simulate
from rodval.core.damping import bending_damping_for_ratio


def main() -> None:
    scene = latch3_scene()
    rigid = simulate(scene, "rigid", rtol=1e-10, atol=1e-12)
    print("| damping ratio | EI | lock 1 gap (s) | lock 2 gap (s) | max |phi - phi_rigid| (rad) |")
    print("|---|---|---|---|---|")
    for ratio in (0.0, 0.3):
        for EI in (1e6, 1e7, 1e8, 1e9):
            chain = scene.chain.with_(EI=np.full(scene.n, EI))
            c = bending_damping_for_ratio(ratio, chain.l, chain.m, chain.EI)
            chain = chain.with_(bending_damping=np.broadcast_to(c, (scene.n,)).astype(float))
            full = simulate(
                scene.with_(chain=chain), "full", kinematics="exact", max_evaluations=20_000_000
            )
            if not full.success:
                print(f"| {ratio} | {EI:g} | {full.stats.message[:60]} | | |")
                continue
            gaps = [a["t"] - b["t"] for a, b in zip(full.events, rigid.events)]
            worst = float(np.abs(full["phi"] - rigid["phi"]).max())
            print(f"| {ratio} | {EI:g} | {gaps[0]:.2g} | {gaps[1]:.2g} | {worst:.2g} |", flush=True)


if __name__ == "__main__":
    main()
