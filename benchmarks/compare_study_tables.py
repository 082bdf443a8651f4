"""Do two runs of the same study (e.g. the processes and the dask backends) give the same
tables? Compares cases.csv, discrepancies.csv, trajectories.csv and runtime.csv of two output
folders row by row (sorted by their keys): every column must be equal, numbers to a relative
1e-12, except the measured times (runtime.csv: wall_s, setup_s), whose medians are printed.

Run: PYTHONPATH=. python benchmarks/compare_study_tables.py DIR_A DIR_B
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

KEYS = {
    "cases": ["case"],
    "discrepancies": ["case", "model", "quantity"],
    "trajectories": ["case", "model", "quantity", "k", "t"],
    "runtime": ["case", "model"],
}
TIMES = ("wall_s", "setup_s")


def compare(a: Path, b: Path) -> list[str]:
    """Differences between the tables of folders a and b (empty: the same)."""
    problems = []
    for name, keys in KEYS.items():
        ta = pd.read_csv(a / f"{name}.csv").sort_values(keys).reset_index(drop=True)
        tb = pd.read_csv(b / f"{name}.csv").sort_values(keys).reset_index(drop=True)
        if ta.shape != tb.shape or list(ta.columns) != list(tb.columns):
            problems.append(f"{name}: shape/columns differ: {ta.shape} vs {tb.shape}")
            continue
        for col in ta.columns:
            if col in TIMES:
                continue
            x, y = ta[col], tb[col]
            if pd.api.types.is_numeric_dtype(x) and pd.api.types.is_numeric_dtype(y):
                xv, yv = x.to_numpy(float), y.to_numpy(float)
                same = (np.isnan(xv) & np.isnan(yv)) | np.isclose(xv, yv, rtol=1e-12, atol=0)
            else:
                same = (x.astype(str) == y.astype(str)).to_numpy()
            if not same.all():
                problems.append(f"{name}.{col}: {int((~same).sum())} of {len(same)} rows differ")
        print(f"{name}: {len(ta)} rows compared", end="")
        if name == "runtime":
            wa, wb = ta.wall_s.median(), tb.wall_s.median()
            sa, sb = ta.setup_s.median(), tb.setup_s.median()
            print(f"; median wall_s {wa:.2e} vs {wb:.2e} s, setup_s {sa:.2e} vs {sb:.2e} s", end="")
        print()
    return problems


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    args = ap.parse_args()
    problems = compare(args.a, args.b)
    for p in problems:
        print("DIFFERENT:", p)
    print("same tables" if not problems else f"{len(problems)} differences")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
