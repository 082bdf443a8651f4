"""Cost of asking for energy: the compiled DOP853 loop auditing W_ext and D inside the loop,
against scipy's DOP853 (the same steps, the audit on the Python side), side by side in one run.

Scene: an 8-rod non-uniform damped wing (rods 0.6-1.2 m, 0.8-2 kg, EI = 2e4 N m^2, hinge
springs and dampers, a pulse at the tip and a constant force mid-span) over 0..3 s, outputs
phi and energy. Prints per model: the method "auto" chose, wall seconds (best of repeats,
after a warm-up run that compiles) with and without "energy" among the outputs, evaluations,
the ratio scipy / compiled and the audit residual of both (equal to round-off).

Run: OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/compiled_audit_cost.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rodval import Chain, Scene, constant, pulse, simulate

CHAIN = Chain(
    l=[1.2, 0.8, 1.0, 0.6, 0.9, 1.1, 0.7, 1.0],
    m=[2.0, 1.5, 1.0, 1.2, 0.8, 1.4, 0.9, 1.1],
    EI=2e4,
    mu=[0, 1.0, 0, 0.5, 0.3, 0, 0.2, 0.4],
    kappa=[0, 80, 40, 60, 20, 50, 30, 40],
    nu=[0, 0.4, 0.2, 0.1, 0.3, 0.2, 0.1, 0.2],
)
SCENE = Scene(
    chain=CHAIN,
    loads=(pulse(8, T=1.0), constant(4, X=5.0, Y=-8.0)),
    t_end=3.0,
    times=np.linspace(0, 3.0, 61),
    outputs=("phi", "energy"),
)


def best(model: str, method: str, repeats: int, scene: Scene = SCENE):
    """(best wall s, trajectory) of ``repeats`` runs after one warm-up."""
    simulate(scene, model, method=method)
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        tr = simulate(scene, model, method=method)
        runs.append((time.perf_counter() - start, tr))
    return min(runs, key=lambda r: r[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    for model in ("full", "reduced"):
        chosen = simulate(SCENE, model).settings["method"]
        tc, fast = best(model, "auto", args.repeats)
        ts, ref = best(model, "DOP853", args.repeats)
        t0, _ = best(model, "auto", args.repeats, SCENE.with_(outputs=("phi",)))
        gap = abs(fast.stats.energy_residual - ref.stats.energy_residual)
        print(
            f"{model:8s} auto -> {chosen}: with energy {tc:.4f} s ({fast.stats.nfev} evals), "
            f"without {t0:.4f} s (energy costs {tc / t0:.2f}x); scipy DOP853 with energy "
            f"{ts:.4f} s ({ref.stats.nfev} evals), {ts / tc:.1f}x the compiled; residual "
            f"{fast.stats.energy_residual:.10e} vs {ref.stats.energy_residual:.10e} "
            f"(|difference| {gap:.1e})"
        )


if __name__ == "__main__":
    main()
