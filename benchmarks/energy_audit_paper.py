"""Energy residual of the paper's example with nu = 0 over 10 T (the pulse ends at T = 1 s).

Run:  PYTHONPATH=. python benchmarks/energy_audit_paper.py
Prints, per model and tolerance, E(T), the work W(T), the residual R at T and 10 T and the
scalar max|R| / max(E, W); two tolerances show whether R is integration error or the model's.
"""

from __future__ import annotations

import numpy as np
from tabulate import tabulate

from rodval import paper_scene, simulate


def main() -> None:
    times = np.linspace(0.0, 10.0, 201)
    scene = paper_scene(t_end=10.0, times=times, outputs=("energy",), nu=0.0)
    i_T = int(np.searchsorted(times, 1.0))
    rows = []
    for model in ("full", "reduced"):
        for rtol in (1e-8, 1e-10):
            tr = simulate(scene, model, rtol=rtol, atol=rtol * 1e-2)
            E, W, R = tr["energy"][:, 0], tr["work"][:, 0], tr["energy_residual"][:, 0]
            after = R[i_T:] - R[i_T]
            rows.append(
                [
                    model,
                    rtol,
                    tr.stats.message,
                    E[i_T],
                    W[-1],
                    R[i_T],
                    R[-1],
                    np.max(np.abs(after)) / E[i_T],
                    tr.stats.energy_residual,
                    tr.stats.nfev,
                    tr.stats.wall_s,
                ]
            )
    print(
        tabulate(
            rows,
            headers=[
                "model",
                "rtol",
                "status",
                "E(T) J",
                "W(10T) J",
                "R(T) J",
                "R(10T) J",
                "max|R-R(T)|/E(T), t>T",
                "max|R|/max(E,W)",
                "nfev",
                "wall s",
            ],
            floatfmt=".4g",
        )
    )


if __name__ == "__main__":
    main()
