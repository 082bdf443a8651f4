"""A study runner's own cost per case: wall time minus the cases' integration and set-up.

For a study file (e.g. studies/scale_study.toml: 1000 cases of ~1 ms of integration each),
this script

1. runs K cases "cold", one fresh ``python -m rodval.study.worker`` process per case (what the
   old runner did: imports and compiled-kernel loading paid by every case), timing each from
   spawn to exit;
2. runs the whole study with the processes backend (warm workers) at each ``--workers``, or
   with the dask backend on the cluster at ``--scheduler`` (benchmarks/dask_cluster.py),
   through ``rodval.study.run_study`` (no report), timing the case phase and the tables apart;

and prints, per run, the per-case overhead

    overhead per case = (W x case-phase wall - sum over runs of (wall_s + setup_s)) / cases

(W = worker slots; ``wall_s`` integration, ``setup_s`` model construction, from runtime.csv),
i.e. the worker time per case not spent inside the model. Writes overhead.csv and
overhead.md into --out.

Run: OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/study_overhead.py \\
         studies/scale_study.toml --out /tmp/overhead [--workers 1,2] [--cold 20]
     ... --backend dask --scheduler tcp://127.0.0.1:8786 --workers 2   (W = dask threads)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd

from rodval.report.markdown import to_markdown
from rodval.study import load_study, run_study
from rodval.study.tables import write_tables


def cold_case(payload: dict) -> tuple[float, float, int]:
    """(elapsed s from spawn to exit, sum of wall_s + setup_s, runs) of one case in a fresh
    worker process."""
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "rodval.study.worker"],
        input=json.dumps(payload) + "\n",
        capture_output=True,
        text=True,
        check=True,
    )
    elapsed = time.perf_counter() - start
    inside, runs = 0.0, 0
    for line in proc.stdout.splitlines():
        msg = json.loads(line)
        if "label" in msg:
            inside += msg["setup_s"] + msg["trajectory"]["stats"]["wall_s"]
            runs += 1
    return elapsed, inside, runs


def row(label: str, cases: int, slots: int, wall: float, inside: float, tables: float) -> dict:
    return {
        "run": label,
        "cases": cases,
        "worker slots W": slots,
        "case-phase wall (s)": wall,
        "sum wall_s + setup_s (s)": inside,
        "tables (s)": tables,
        "wall per case (ms)": 1e3 * wall / cases,
        "overhead per case (ms)": 1e3 * (slots * wall - inside) / cases,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", type=Path)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts")
    ap.add_argument("--cold", type=int, default=20, help="cases run cold (0: none)")
    ap.add_argument("--backend", choices=("processes", "dask"), default="processes")
    ap.add_argument("--scheduler", help="dask scheduler address (--backend dask)")
    args = ap.parse_args()
    spec = load_study(args.study)
    n = len(spec.cases)
    rows = []
    print(f"{spec.name}: {n} cases; load average {os.getloadavg()}", flush=True)
    if args.cold:
        payloads = [c.payload() for c in spec.cases[: args.cold]]
        cold = [cold_case(p) for p in payloads]
        wall = sum(c[0] for c in cold)
        inside = sum(c[1] for c in cold)
        rows.append(row("cold: fresh process per case", len(cold), 1, wall, inside, 0.0))
        print(rows[-1], flush=True)
    for w in [int(v) for v in args.workers.split(",")]:
        out = args.out / f"{args.backend}_w{w}"
        start = time.perf_counter()
        res = run_study(
            spec,
            out,
            workers=w,
            backend=args.backend,
            scheduler=args.scheduler,
            resume=False,
            progress=False,
            report=False,
            fresh=True,
        )
        total = time.perf_counter() - start
        start = time.perf_counter()
        write_tables(out, spec)  # again, to time the tables apart from the cases
        tables = time.perf_counter() - start
        rt = pd.read_csv(out / "runtime.csv")
        inside = float((rt.wall_s + rt.setup_s).sum())
        label = f"warm: {args.backend}, {w} worker(s)"
        rows.append(row(label, len(res.ran), w, total - tables, inside, tables))
        print(rows[-1], f"failed runs {res.failed_runs}", flush=True)
    frame = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    frame.to_csv(args.out / "overhead.csv", index=False)
    command = " ".join(sys.argv)
    text = [
        f"# Study overhead: {spec.name}",
        "",
        f"Command: `{command}`; load average after: {os.getloadavg()}",
        "",
        to_markdown(frame, ".4g"),
    ]
    (args.out / "overhead.md").write_text("\n".join(text))
    print(to_markdown(frame, ".4g"))


if __name__ == "__main__":
    main()
