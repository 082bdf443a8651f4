"""Stability map: which model/integrator completes each stress case, at what cost, with what
energy residual (issue 6). The grid is the one of studies/stability.toml, run here with
``rodval.simulate`` directly, each run in its own process with a wall-time limit.

Run:  PYTHONPATH=. python benchmarks/stability_map.py [--out DIR] [--timeout S] [--workers N]
Writes DIR/stability_map.csv and DIR/stability_map.md (default DIR: results/stability).

Cases (paper chain data unless varied; the paper's pulse, T = 1 s, at the last node, scaled
by ``load``; nu = 0.01 N m s/rad), sized to finish on 2 cores:
  A. n in {8, 32, 128} x kappa in {0, 100, 1e6} N m/rad; EI = 1e5, load 1; 2 T.
  L. n = 8, kappa in {0, 100, 1e6}, load 10 (Xbar = -1500 N, Ybar = 12000 N); 2 T.
  B. n = 8, kappa = 100, EI in {1e3, 1e4, 1e6, 1e7} N m^2 (1e5 is in A); 2 T.
  C. n = 8, paper data: 100 T.
Each case runs with full and reduced, each with DOP853 (explicit) and Radau (implicit), rtol
1e-6, atol 1e-8, outputs phi and energy at 101 times. Each run has a CPU-time budget of
``--timeout`` seconds (RLIMIT_CPU, so the verdict does not depend on the machine's load);
a run that exceeds it is recorded as "timeout". ``cpu_s`` is the run's CPU time.
"""
from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import resource
import signal
import time
from pathlib import Path

import numpy as np
import pandas as pd
from tabulate import tabulate

from rodval import paper_scene, pulse, simulate
from rodval.trajectory import STATUS_MESSAGES

MODELS = (("full", "DOP853"), ("full", "Radau"), ("reduced", "DOP853"), ("reduced", "Radau"))
RTOL, ATOL = 1e-6, 1e-8


def cases() -> list[dict]:
    base = dict(kappa=100.0, EI=1e5, load=1, horizon=2.0)
    out = [dict(base, group="A", n=n, kappa=kappa) for n in (8, 32, 128)
           for kappa in (0.0, 100.0, 1e6)]
    out += [dict(base, group="L", n=8, kappa=kappa, load=10) for kappa in (0.0, 100.0, 1e6)]
    out += [dict(base, group="B", n=8, EI=EI) for EI in (1e3, 1e4, 1e6, 1e7)]
    out += [dict(base, group="C", n=8, horizon=100.0)]
    return out


def scene_of(case: dict):
    n, horizon = case["n"], case["horizon"]
    scene = paper_scene(n, t_end=horizon, times=np.linspace(0.0, horizon, 101),
                        outputs=("phi", "energy"), kappa=case["kappa"], EI=case["EI"])
    return scene.with_(loads=(pulse(n, Xbar=-150.0 * case["load"], Ybar=1200.0 * case["load"]),))


def _run(case: dict, model: str, method: str, conn, budget: float) -> None:
    used = time.process_time()
    resource.setrlimit(resource.RLIMIT_CPU, (int(used + budget) + 1, int(used + budget) + 2))
    tr = simulate(scene_of(case), model, method=method, rtol=RTOL, atol=ATOL)
    st = tr.stats
    E = tr["energy"][:, 0] if "energy" in tr.values else np.zeros(0)
    conn.send({"status": STATUS_MESSAGES[st.status], "t_reached": st.t_reached,
               "cpu_s": time.process_time() - used,
               "nsteps": st.nsteps, "nfev": st.nfev, "wall_s": st.wall_s,
               "energy_residual": st.energy_residual,
               "E_max": float(E.max()) if E.size else np.nan, "message": st.message})


def _key(row: dict) -> tuple:
    return tuple(row[k] for k in ("group", "n", "kappa", "EI", "load", "horizon", "model",
                                  "method"))


def run_all(jobs: list[tuple[dict, str, str]], timeout: float, workers: int,
            log: Path) -> list[dict]:
    """Run the jobs not yet in ``log`` (JSON lines, one finished run each: resumable)."""
    ctx = mp.get_context("fork")
    rows = [json.loads(line) for line in log.read_text().splitlines()] if log.exists() else []
    done = {_key(r) for r in rows}
    pending = [j for j in jobs if _key({**j[0], "model": j[1], "method": j[2]}) not in done]
    active = []
    while pending or active:
        while pending and len(active) < workers:
            case, model, method = pending.pop(0)
            recv, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_run, args=(case, model, method, send, timeout),
                               daemon=True)
            proc.start()
            send.close()
            active.append((proc, recv, time.perf_counter(), case, model, method))
        time.sleep(0.05)
        for item in list(active):
            proc, recv, start, case, model, method = item
            elapsed = time.perf_counter() - start
            row = None
            if recv.poll():
                try:
                    row = recv.recv()
                except EOFError:        # the run died: its exit code says how
                    proc.join()
            if row is not None or proc.is_alive():
                pass
            elif proc.exitcode == -signal.SIGXCPU:
                row = {"status": "timeout", "message": f"CPU budget of {timeout:g} s exceeded"}
            else:
                row = {"status": "worker crashed", "message": f"exit code {proc.exitcode}"}
            if row is None:
                continue
            proc.join()
            active.remove(item)
            rows.append({**case, "model": model, "method": method, "elapsed_s": elapsed, **row})
            with log.open("a") as fh:
                fh.write(json.dumps(rows[-1]) + "\n")
            print(f"{case['group']} n={case['n']} kappa={case['kappa']:g} EI={case['EI']:g} "
                  f"load={case['load']} T={case['horizon']:g} {model}/{method}: {row['status']} "
                  f"R={row.get('energy_residual')} {elapsed:.1f} s", flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/stability"))
    ap.add_argument("--timeout", type=float, default=10.0, help="CPU-time budget per run, s")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    jobs = [(c, m, meth) for c in cases() for m, meth in MODELS]
    start = time.perf_counter()
    args.out.mkdir(parents=True, exist_ok=True)
    rows = run_all(jobs, args.timeout, args.workers, args.out / "runs.jsonl")
    total = time.perf_counter() - start
    df = pd.DataFrame(rows).sort_values(["group", "n", "kappa", "EI", "load", "horizon",
                                         "model", "method"])
    args.out.mkdir(parents=True, exist_ok=True)
    df.to_csv(args.out / "stability_map.csv", index=False)
    cols = ["group", "n", "kappa", "EI", "load", "horizon", "model", "method", "status",
            "t_reached", "nsteps", "nfev", "cpu_s", "energy_residual"]
    table = tabulate(df[cols], headers=cols, tablefmt="pipe", showindex=False, floatfmt=".3g")
    (args.out / "stability_map.md").write_text(
        f"{table}\n\n{len(df)} runs, CPU budget {args.timeout:g} s per run, {args.workers} workers, "
        f"total wall time {total:.0f} s\n")
    print(f"{len(df)} runs in {total:.0f} s -> {args.out}")


if __name__ == "__main__":
    main()
