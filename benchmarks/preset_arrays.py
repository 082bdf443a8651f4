"""Are the paper presets' results bit for bit those of another checkout? (issue 40: the paper's
models as presets of the chain engine, "today's results bit for bit where the arithmetic is
the same").

    PYTHONPATH=$PWD .venv/bin/python benchmarks/preset_arrays.py save NEW.pkl
    (in a worktree of the old commit: PYTHONPATH=OLD python benchmarks/preset_arrays.py save OLD.pkl)
    .venv/bin/python benchmarks/preset_arrays.py compare OLD.pkl NEW.pkl

Runs: the paper example (n = 8) in the full and reduced presets, the latched 3-rod scene
(``exudyn_speed.latch3_scene``) in both, the same on a free 50 kg body (the paper rung's
free-base kernels), the 6-panel wing on the exact p = 3 rung, and the latched 3-rod scene on
a pinned, a free and a prescribed base in the rigid model and on the exact rung (issue 55:
"every earlier result bit for bit"), with each run's lock events and peaks; ``compare`` prints, per run
and output, array_equal or the largest difference.
"""

from __future__ import annotations

import json
import pickle
import sys

import numpy as np
from exudyn_speed import latch3_scene, wing_scene

from rodval import Base, Motion, paper_scene, simulate


def runs() -> dict:
    body = Base(kind="free", mass=50.0, inertia=20.0, hinge_offset=(0.5, 0.0))
    cases = {
        ("paper", "full"): (paper_scene(8), "full", {}),
        ("paper", "reduced"): (paper_scene(8), "reduced", {}),
        ("latch3", "full"): (latch3_scene(), "full", {}),
        ("latch3", "reduced"): (latch3_scene(), "reduced", {}),
        ("latch3 free", "full"): (
            latch3_scene().with_(base=body, outputs=("phi", "base", "momentum")),
            "full",
            {},
        ),
        ("wing", "exact3"): (wing_scene(2.0), "full", {"kinematics": "exact", "shapes": 3}),
    }
    hub = Base(
        kind="prescribed",
        hinge_offset=(0.5, 0.0),
        motion={
            "attitude": Motion("spin_up", (2.0, 1.0)),
            "x": Motion("harmonic", (0.1, 3.0, 0.0)),
        },
    )
    moving = ("phi", "base", "energy", "drive")
    for label, base, outputs in (
        ("pinned", Base(), ("phi", "energy")),
        ("free", body, ("phi", "base", "momentum", "energy")),
        ("prescribed", hub, moving),
    ):
        sc = latch3_scene().with_(base=base, outputs=outputs)
        cases[("latch3 " + label, "rigid")] = (sc, "rigid", {})
        cases[("latch3 " + label, "exact")] = (sc, "full", {"kinematics": "exact"})
    return {key: _arrays(simulate(sc, model, **opts)) for key, (sc, model, opts) in cases.items()}


def _arrays(tr) -> dict:
    """A run's outputs, its lock times and hinges, and its peaks, as arrays."""
    out = {k: np.asarray(v) for k, v in tr.values.items()}
    out["events"] = np.asarray([(e["hinge"], e["t"]) for e in tr.events], dtype=float)
    out["peaks"] = np.asarray(json.dumps(tr.stats.peaks, sort_keys=True, default=repr))
    return out


def compare(old: dict, new: dict) -> None:
    for key, quantities in old.items():
        for q, x in quantities.items():
            y = new.get(key, {}).get(q)
            if y is not None and x.shape == y.shape and np.array_equal(x, y):
                print(key, q, "array_equal")
            elif y is None or x.shape != y.shape:
                print(key, q, "MISSING or other shape")
            else:
                if x.dtype.kind in "US":
                    print(key, q, f"DIFF {x} != {y}")
                    continue
                print(key, q, f"DIFF max {float(np.nanmax(np.abs(x - y))):.3g}")


if __name__ == "__main__":
    if sys.argv[1] == "save":
        with open(sys.argv[2], "wb") as f:
            pickle.dump(runs(), f)
    else:
        with open(sys.argv[2], "rb") as f, open(sys.argv[3], "rb") as g:
            compare(pickle.load(f), pickle.load(g))
