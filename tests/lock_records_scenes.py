"""The latched scenes whose lock records ``tests/test_lock_records_equal.py`` holds to the
records the per-state lock bookkeeping wrote (commit 5627385), and the script that wrote them:

    OMP_NUM_THREADS=1 .venv/bin/python tests/lock_records_scenes.py

writes ``tests/data/lock_records_reference.json`` (every numeric field of every lock record,
per scene and model, as repr'd floats)."""

from __future__ import annotations

import json
import math
import pathlib
import sys

import numpy as np
from scenes import spun_damped_latch, three_rods_loaded

from rodval import simulate
from rodval.bench.fast_path import four_panel_wing
from rodval.bench.stiffness import rigid_latch
from rodval.core.scene import Scene
from rodval.core.settings import IntegratorSettings

REFERENCE = pathlib.Path(__file__).parent / "data" / "lock_records_reference.json"
#: the settings of every run (tight: the step sequence, hence the probe states, is then
#: well away from round-off decisions)
SETTINGS = IntegratorSettings(rtol=1e-8, atol=1e-10)


def scenes() -> dict[str, Scene]:
    """The latched scenes, by name."""
    return {
        "four_panel_wing": four_panel_wing(),
        "rigid_latch": rigid_latch(),
        "spun_damped_latch": spun_damped_latch(),
        "three_rods_loaded": three_rods_loaded(),
    }


#: the models each scene runs on (the full model cannot finish the rigid latch: docs/performance.md)
MODELS = {
    "four_panel_wing": ("reduced", "full"),
    "rigid_latch": ("reduced",),
    "spun_damped_latch": ("reduced", "full"),
    "three_rods_loaded": ("reduced", "full"),
}


def numbers(record: dict) -> dict[str, float | list[float]]:
    """The record's numeric fields (floats and lists of floats; booleans and labels left out)."""
    out: dict[str, float | list[float]] = {}
    for key, value in record.items():
        if isinstance(value, bool) or value is None or isinstance(value, str):
            continue
        if isinstance(value, (int, float)):
            out[key] = float(value)
        elif isinstance(value, (list, tuple)):
            flat = np.asarray(value, dtype=float).ravel()
            out[key] = [float(v) for v in flat]
    return out


def lock_records(scene: Scene, model: str) -> list[dict]:
    """The numeric fields of the run's lock records (events with a lock window)."""
    tr = simulate(scene, model, settings=SETTINGS)
    return [numbers(ev) for ev in tr.events if "impulse_window" in ev]


def write_reference() -> None:
    data = {
        name: {model: lock_records(scene, model) for model in MODELS[name]}
        for name, scene in scenes().items()
    }
    REFERENCE.write_text(json.dumps(data, indent=1) + "\n")
    counts = {k: {m: len(v) for m, v in d.items()} for k, d in data.items()}
    print(f"wrote {REFERENCE}: {counts}", file=sys.stderr)
    assert all(math.isfinite(len(v)) for d in data.values() for v in d.values())


if __name__ == "__main__":
    write_reference()
