"""Cost of one reduced-model right-hand side: the O(n) solves of rodval.models.bending.reduced_banded
against the dense kernels.reduced_accel (O(n^2) assembly + O(n^3) solve, timed for n <= 512).

Columns: "default" = reduced_accel_banded (the sweep, work allocated per call); "sweep+work"
and "band+work" = reduced_solve_work with a work array allocated once (what a compiled
integrator would do), METHOD_SWEEP and METHOD_BAND (banded LU with partial pivoting);
"band diff" = max |phi''_band - phi''_sweep| / max |phi''_sweep| (the banded LU loses digits
on long chains, see tests/test_reduced_banded.py::test_backward_error_on_a_long_chain).

Seconds per evaluation = min over repeats of (timed loop time / evaluations in the loop), at a
random state (phi ~ 1 rad, phi' ~ 1 rad/s), damped, with a load active. Prints a table and
the least-squares log-log exponent of the banded kernel's time against n.

Run: OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/reduced_banded_cost.py [--quick]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rodval.core.scene import Chain
from rodval.models.assembly import kernels
from rodval.models.bending import reduced_banded as rb

SIZES = (8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384, 32768, 65536, 100000)
DENSE_MAX = 512


def chain(n: int) -> Chain:
    rng = np.random.default_rng(n)
    return Chain(
        l=rng.uniform(0.5, 2.5, n),
        m=rng.uniform(1, 4, n),
        EI=rng.uniform(1e3, 1e5, n),
        mu=rng.uniform(0, 3, n),
        kappa=rng.uniform(0, 200, n),
        nu=rng.uniform(0.01, 0.5, n),
    )


def seconds_per_call(f, min_time: float, repeats: int) -> float:
    f()
    reps = 1
    while True:  # loop long enough to time
        t0 = time.perf_counter()
        for _ in range(reps):
            f()
        dt = time.perf_counter() - t0
        if dt >= min_time:
            break
        reps = max(2 * reps, int(reps * 1.2 * min_time / max(dt, 1e-9)))
    best = dt / reps
    for _ in range(repeats - 1):
        t0 = time.perf_counter()
        for _ in range(reps):
            f()
        best = min(best, (time.perf_counter() - t0) / reps)
    return best


def dense_setup(ch: Chain):
    """(V, Mt) of the dense kernel, built through the existing ReducedSystem."""
    from rodval.core.scene import Scene
    from rodval.models.presets.reduced import ReducedSystem

    system = ReducedSystem(Scene(chain=ch, t_end=1.0), "printed", "numba")
    return system.V, system.Mt


def measure(n: int, min_time: float, repeats: int) -> tuple[int, float, float, float]:
    """Time the kernels at n rods, print the table row; (n, default, sweep+work, band+work)."""
    ch = chain(n)
    Cst = rb.banded_constants(None, ch, "printed")
    rng = np.random.default_rng(0)
    phi, dphi = rng.normal(size=n), rng.normal(size=n)
    SX = np.cumsum(rng.normal(size=n)[::-1])[::-1] * 100.0
    SY = np.cumsum(rng.normal(size=n)[::-1])[::-1] * 100.0
    out = np.empty(n)
    t_b = seconds_per_call(
        lambda: rb.reduced_accel_banded(Cst, phi, dphi, True, SX, SY, True, out), min_time, repeats
    )
    work, gamma, dd = np.empty(rb.work_size(n)), np.empty(2 * n), np.empty(n)
    sweep_work = np.empty(rb.sweep_work_size(n))
    t_w = seconds_per_call(
        lambda: rb.reduced_solve_work(
            Cst, phi, dphi, True, SX, SY, True, dd, gamma, sweep_work, rb.METHOD_SWEEP
        ),
        min_time,
        repeats,
    )
    t_band = seconds_per_call(
        lambda: rb.reduced_solve_work(
            Cst, phi, dphi, True, SX, SY, True, dd, gamma, work, rb.METHOD_BAND
        ),
        min_time,
        repeats,
    )
    band_diff = np.max(np.abs(out - dd)) / np.max(np.abs(out))  # |band - sweep| / max|sweep|
    dense = f"{'-':>13} {'-':>13}"
    if n <= DENSE_MAX:
        V, Mt = dense_setup(ch)
        ref = np.empty(n)
        t_d = seconds_per_call(
            lambda: kernels.reduced_accel(V, Mt, phi, dphi, True, SX, SY, True, ref),
            min_time,
            repeats,
        )
        err = np.max(np.abs(out - ref)) / np.max(np.abs(ref))
        assert err < 1e-9, f"banded and dense kernels disagree at n = {n}: {err:.1e}"
        dense = f"{t_d:13.3e} {t_d / t_b:13.1f}"
    print(
        f"{n:7d} {t_b:14.3e} {t_b * 1e6:10.1f} {t_b / n * 1e9:8.0f} {t_w:11.3e} "
        f"{t_band:11.3e} {band_diff:9.1e} {dense}",
        flush=True,
    )
    return n, t_b, t_w, t_band


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shorter timing loops")
    args = ap.parse_args()
    min_time, repeats = (0.05, 3) if args.quick else (0.2, 5)
    rows = []
    print(
        f"{'n':>7} {'default s/eval':>14} {'us/eval':>10} {'ns/rod':>8} {'sweep+work':>11} "
        f"{'band+work':>11} {'band diff':>9} {'dense s/eval':>13} {'dense/default':>13}"
    )
    for n in SIZES:
        rows.append(measure(n, min_time, repeats))
    data = np.array(rows)
    data = data[data[:, 0] >= 64]  # the small chains only show the dense kernel's range
    ns = data[:, 0]
    big = ns >= 1024
    for col, label in ((1, "default"), (2, "sweep+work"), (3, "band+work")):
        ts = data[:, col]
        slope = np.polyfit(np.log(ns), np.log(ts), 1)[0]
        slope_big = np.polyfit(np.log(ns[big]), np.log(ts[big]), 1)[0]
        print(
            f"log-log exponent, {label:>10}: {slope:.3f} (n = {int(ns[0])}..{int(ns[-1])}), "
            f"{slope_big:.3f} (n >= 1024); target <= 1.2"
        )


if __name__ == "__main__":
    main()
