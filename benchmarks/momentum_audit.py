"""The angular-momentum audit of every model where momentum is conserved (docs/stability.md,
"Validity"): the residual max |H - H(0)| / max G (``rodval.core.validity.momentum_balance``)
and the verdict, on three scenes without loads:

* latch3: 3 rods, hinge 0 free, two latches (``exudyn_speed.latch3_scene``), 0.8 s;
* wing, free root: the 6-panel latched wing (``exudyn_speed.wing_scene``) with hinge 0's spring
  and damper removed, 2 s;
* wing on a body: the same wing on a free 800 kg body (inertia 533 kg m^2, node 0 at 1 m from
  its centre), 2 s.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/momentum_audit.py [--no-exudyn]
"""

from __future__ import annotations

import sys

from exudyn_speed import latch3_scene, wing_scene

from rodval.core.base import Base
from rodval.core.scene import Scene
from rodval.models import simulate

#: The user's spacecraft body of issue 37: 800 kg, a 2 m cube's inertia, the wing at 1 m.
BODY = Base(kind="free", mass=800.0, inertia=533.0, hinge_offset=(1.0, 0.0))


def scenes() -> dict[str, Scene]:
    wing = wing_scene(2.0)
    free_root = wing.chain.with_(kappa=[0.0] + [50.0] * 5, nu=[0.0] + [0.05] * 5)
    return {
        "latch3": latch3_scene(),
        "wing, free root": wing.with_(chain=free_root),
        "wing on a body": wing.with_(base=BODY, outputs=("phi", "base")),
    }


def main() -> None:
    runs = [("full", {"kinematics": "first-order"}), ("full", {}), ("reduced", {})]
    if "--no-exudyn" not in sys.argv:
        runs.append(("exudyn", {}))
    print("| scene | model | momentum residual | verdict |")
    print("|---|---|---|---|")
    for name, scene in scenes().items():
        for model, options in runs:
            label = model + "".join(f", {k} = {v}" for k, v in options.items())
            try:
                stats = simulate(scene, model, **options).stats
            except ValueError as exc:
                print(f"| {name} | {label} | refused: {str(exc)[:70]}... | |")
                continue
            verdict = "valid" if stats.valid else "INVALID" if stats.valid is False else "-"
            print(f"| {name} | {label} | {stats.momentum_residual:.2g} | {verdict} |")


if __name__ == "__main__":
    main()
