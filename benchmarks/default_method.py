"""Is the default method the fastest valid one? For the paper example and a user's 5-rod
non-uniform boom (one stiff hinge, constant tip load), both with the full model over their
horizon: per method, the fastest run over an rtol ladder whose phi error is <= 1e-6 (relative
to the largest |phi|, against a reference of a different method, see rodval.bench), measured
side by side in one process. Prints a markdown table with the default ("auto", i.e.
`rodval simulate` with no method) beside the fastest.

Usage: OMP_NUM_THREADS=1 python benchmarks/default_method.py
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from rodval import Chain, Scene, constant, paper_scene
from rodval.bench.precision import errors, references, timed
from rodval.core.settings import IntegratorSettings
from rodval.report.markdown import to_markdown

METHODS = ("auto", "DOP853-numba", "DOP853", "RK45", "Radau", "LSODA")
RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
TOL = 1e-6
BUDGET_S = 30.0


def boom() -> Scene:
    chain = Chain(
        l=[1.0, 1.5, 2.0, 1.2, 0.8],
        m=3.0,
        EI=1e5,
        mu=[0.5, 0.5, 1.0, 0.5, 2.0],
        kappa=[100.0, 5000.0, 100.0, 100.0, 100.0],
        nu=0.01,
    )
    return Scene(
        chain=chain,
        loads=(constant(5, Y=50.0),),
        t_end=1.0,
        times=np.linspace(0, 1, 21),
        name="boom",
    )


def fastest(scene: Scene, model: str, method: str, refs) -> dict:
    ref = refs.for_method("DOP853" if method == "auto" else method)
    for rtol in RTOLS:
        settings = IntegratorSettings(method=method, rtol=rtol, atol=rtol * 1e-2)
        traj, wall = timed(scene, model, settings, repeats=3)
        err = errors(traj, ref)["max_phi"]
        if err <= TOL:
            return {
                "method": method,
                "ran": traj.settings["method"],
                "rtol": rtol,
                "wall_s": wall,
                "nfev": traj.stats.nfev,
                "phi_error": err,
            }
        if wall > BUDGET_S:
            break
    return {
        "method": method,
        "ran": "",
        "rtol": math.nan,
        "wall_s": math.nan,
        "nfev": math.nan,
        "phi_error": math.nan,
    }


def main() -> None:
    rows = []
    for scene in (paper_scene(times=np.linspace(0, 2, 41)), boom()):
        refs = references(scene, "full")
        for method in METHODS:
            row = {"scene": scene.name, **fastest(scene, "full", method, refs)}
            print(row, flush=True)
            rows.append(row)
    frame = pd.DataFrame(rows)
    best = frame.groupby("scene")["wall_s"].transform("min")
    frame["vs_fastest"] = frame["wall_s"] / best
    print(to_markdown(frame, ".3g"))


if __name__ == "__main__":
    main()
