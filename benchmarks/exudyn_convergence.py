"""Convergence of the exudyn reference model on the paper example (n = 8, 0..2 s).

Sweeps one discretization option at a time around the defaults (elements per rod, step, EA,
Newton absolute tolerance per EA, solver) and compares each run against the native full model
(printed coefficients, DOP853 rtol 1e-10, atol 1e-12) at t = 0.5, 1, 1.5, 2 s on rods 2, 4, 6, 8.
Errors: phi, alpha, beta in rad (max abs); dphi relative to the column's max |value| of the
native run. Also compares the native ``published`` variant against the native printed one.

    PYTHONPATH=$PWD python benchmarks/exudyn_convergence.py --out results/exudyn_convergence

writes ``convergence.csv`` and ``convergence.md`` in --out.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import pandas as pd

from reference_models.exudyn_chain import DEFAULTS
from rodval import TABLE1_TIMES, paper_scene, simulate
from rodval.analysis.crosscheck import TABLE1_RODS as RODS
from rodval.analysis.crosscheck import table1_gaps as errors

SWEEPS = {
    "elements": [1, 2, 3, 4, 6, 8],
    "step": [1e-3, 5e-4, 2e-4, 1e-4, 5e-5],
    "EA": [1e8, 1e9, 1e10, 1e11],
    "newton_atol_per_EA": [1e-16, 1e-14, 1e-12],
    "solver": ["generalized-alpha", "trapezoidal"],
}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=pathlib.Path, required=True, help="output folder")
    ap.add_argument("--quick", action="store_true", help="only the coarse end of each sweep")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    scene = paper_scene(times=TABLE1_TIMES)
    t0 = time.perf_counter()
    ref = simulate(scene, "full", rtol=1e-10, atol=1e-12)
    native_s = time.perf_counter() - t0
    published = simulate(scene, "full", rtol=1e-10, atol=1e-12, coefficients="published")
    rows = [
        {
            "run": "native published",
            "option": "coefficients",
            "value": "published",
            "status": published.stats.status,
            "wall_s": published.stats.wall_s,
            **errors(published, ref),
        }
    ]
    default = simulate(scene, "exudyn")
    rows += [
        {
            "run": f"exudyn defaults vs native {name}",
            "option": "-",
            "value": "-",
            "status": default.stats.status,
            "wall_s": default.stats.wall_s,
            **errors(default, other),
        }
        for name, other in (("printed", ref), ("published", published))
    ]
    for option, values in SWEEPS.items():
        for value in values[:2] if args.quick else values:
            tr = simulate(scene, "exudyn", **{option: value})
            row = {
                "run": "exudyn",
                "option": option,
                "value": value,
                "status": tr.stats.status,
                "wall_s": tr.stats.wall_s,
                "newton_iterations": tr.stats.nfev,
            }
            row.update(errors(tr, ref) if tr.success else {"message": tr.stats.message})
            rows.append(row)
            print(row, flush=True)
    table = pd.DataFrame(rows)
    table.to_csv(args.out / "convergence.csv", index=False)
    header = (
        f"# exudyn convergence on the paper example\n\nReference: native full model, printed "
        f"coefficients, DOP853 rtol 1e-10 atol 1e-12 ({native_s:.2f} s). Defaults: {DEFAULTS}.\n"
        f"Errors at t = {TABLE1_TIMES} s on rods {RODS}: phi, alpha, beta max abs (rad); dphi "
        f"relative to the column's max |value|. One option varied at a time.\n\n"
    )
    (args.out / "convergence.md").write_text(
        header + table.to_markdown(index=False, floatfmt=".3g") + "\n"
    )


if __name__ == "__main__":
    main()
