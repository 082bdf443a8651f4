"""The compiled DOP853 loop's own cost per evaluation: rodval.solvers.dop853 run on n
uncoupled harmonic oscillators (a trivial O(n) right-hand side, ~2 ns per rod), 0..2 s, rtol
1e-6, 21 output times, against the same RHS alone in a compiled loop. What is left is the
loop's vector work (stage combinations with temporaries, error norm, dense output).

Run: OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/dop853_loop_cost.py 8 1024 65536 100000
"""

from __future__ import annotations

import sys
import time

import numpy as np
from numba import njit

from rodval.core.load_table import LOAD_COLUMNS
from rodval.solvers import compiled
from rodval.solvers.guard import GuardSpec
from rodval.solvers.signature import RHS_SIGNATURE
from rodval.solvers.system import CompiledForm


@njit(RHS_SIGNATURE, cache=True)
def oscillators(t, y, P, S, M, L, out):
    half = y.shape[0] // 2
    for i in range(half):
        out[i] = y[half + i]
        out[half + i] = -P[0, i] * y[i]


@njit
def rhs_loop(reps, y, P, out):
    empty = np.zeros((0, 0, 0))
    for _ in range(reps):
        oscillators(0.0, y, P, P[0], empty, P, out)


def measure(n: int, repeats: int = 3) -> None:
    P = np.ones((1, n))
    y0 = np.zeros(2 * n)
    y0[:n] = 0.1
    form = CompiledForm(
        oscillators, P, np.zeros(1), np.zeros((0, 0, 0)), np.zeros((0, len(LOAD_COLUMNS)))
    )
    times = np.linspace(0, 2, 21)
    Y = np.empty((21, 2 * n))
    guard = GuardSpec()  # no stall or energy check: the loop alone
    edges = np.array([0.0, 1.0, 2.0])
    best, nfev = np.inf, 0
    for _ in range(repeats):
        start = time.perf_counter()
        controls = compiled.Controls(1e-6, 1e-8, np.inf, None, 10**9)
        nfev = compiled.integrate_compiled(form, y0, edges, times, Y, controls, guard)[1]
        best = min(best, time.perf_counter() - start)
    out = np.empty(2 * n)
    rhs_loop(1, y0, P, out)
    start = time.perf_counter()
    rhs_loop(nfev, y0, P, out)
    rhs = (time.perf_counter() - start) / nfev
    per_eval = best / nfev
    print(
        f"n = {n:6d}: nfev {nfev}, loop {per_eval * 1e6:9.2f} us/eval = "
        f"{per_eval / n * 1e9:6.1f} ns/rod/eval; the RHS alone {rhs / n * 1e9:5.2f} ns/rod",
        flush=True,
    )


if __name__ == "__main__":
    for n in [int(a) for a in sys.argv[1:]] or [8, 1024, 65536, 100000]:
        measure(n)
