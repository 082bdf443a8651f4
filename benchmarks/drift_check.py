"""The drift check of the fast-path table (issue 50): run ``rodval bench fast-path`` afresh (or
read a fresh CSV) and compare it with the recorded table by ratios (``rodval.bench.drift``):
the default method's speed-up over scipy's DOP853 (measured side by side in each run) beyond
the machine's noise, and the default method's evaluation count beyond 2 %. Exit 1 when a
figure drifted, naming it.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/drift_check.py [--fresh FILE.csv] \
        [--recorded benchmarks/recorded/fast_path.csv] [--noise 1.5] [--repeats 2]
"""

from __future__ import annotations

import argparse
import sys

import pandas as pd

from rodval.bench.drift import drift_table, drifted
from rodval.report.markdown import to_markdown

KEYS = ("scene", "feature", "with_feature", "model")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--recorded", default="benchmarks/recorded/fast_path.csv")
    p.add_argument("--fresh", help="a fresh fast_path.csv (default: run the benchmark now)")
    p.add_argument("--noise", type=float, default=1.5)
    p.add_argument("--repeats", type=int, default=2)
    args = p.parse_args()
    recorded = pd.read_csv(args.recorded, comment="#")
    if args.fresh:
        fresh = pd.read_csv(args.fresh, comment="#")
    else:
        from rodval.bench.fast_path import fast_path_rows

        fresh = fast_path_rows(args.repeats, progress=lambda *a: None)
    table = drift_table(recorded, fresh, KEYS, ["speedup"], ["auto_nfev"], noise=args.noise)
    print(to_markdown(table, ".3g"))
    bad = drifted(table)
    for _, row in bad.iterrows():
        name = ", ".join(str(row[k]) for k in KEYS)
        print(
            f"drifted: {name}: {row['figure']} {row['recorded']:.4g} -> {row['fresh']:.4g} "
            f"({row['verdict']}, x{row['factor']:.3g})"
        )
    return 1 if len(bad) else 0


if __name__ == "__main__":
    sys.exit(main())
