"""Return codes and the evaluation and wall-clock budgets of the compiled loop
(``rodval.solvers.dop853.run``), shared by its steppers (DOP853 and ``rodval.solvers.radau``).
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit, objmode

from rodval.solvers import guard as _guard
from rodval.solvers.progress import report
from rodval.solvers.signature import Arr

#: Return codes of the compiled loop: the guard's (``rodval.solvers.guard.guard_step``) and
#: the loop's own.
OK, BLOWUP, STALLED = _guard.OK, _guard.BLOWUP, _guard.STALLED
STEP_TOO_SMALL, NON_FINITE, BUDGET, WALL, EVENT = 1, 2, 3, 6, 7

#: The compiled loop's settings (``rodval.solvers.dop853.run``), one tuple of float arrays:
#: (controls: [rtol, atol, max_step (s), first_step (s), max_nfev, deadline (s), stepper,
#: reporting (1/0)], atol: each coordinate's absolute tolerance, guard:
#: ``GuardSpec.as_array()``).
Settings = tuple[Arr, Arr, Arr]

#: The most evaluations between two reads of the clock for the wall-clock budget: the read
#: costs about one evaluation of the smallest system, so this keeps it below 1 % of a run.
WALL_CHECK_EVALUATIONS = 100
#: The work (s) between two reads of the clock once evaluations are dear: fewer evaluations
#: than WALL_CHECK_EVALUATIONS go between them, as many as took this long between the last
#: two reads, and at least one, so a run overshoots its deadline by at most the larger of this
#: and one step (at n = 1e6 one evaluation takes about a second: 100 of them overshot a 3 s
#: budget by 43 s). A read then costs at most ~1e-4 of the run.
READ_INTERVAL_S = 0.01


@njit(cache=True)
def _now_ns() -> int:
    """``time.perf_counter_ns()`` (ns; the clock of ``time.perf_counter``), read from inside
    the compiled loop."""
    with objmode(now="int64"):
        now = time.perf_counter_ns()
    return now


@njit(cache=True)
def _report_and_now_ns(t: float) -> int:
    """Tell the progress reporter (``rodval.solvers.progress``) that the run reached t (s),
    then read the clock (ns, ``_now_ns``); one call back into Python."""
    with objmode(now="int64"):
        report(t)
        now = time.perf_counter_ns()
    return now


@njit(cache=True)
def counters() -> Arr:
    """The loop's counters: [evaluations used, the count at the next read of the clock, the
    count at the last read, the last read's clock (ns, ``_now_ns``; now: the run's start)]."""
    cnt = np.zeros(4, np.int64)
    cnt[3] = _now_ns()
    return cnt


@njit(cache=True, inline="always")
def read_interval(evaluations: int, elapsed_ns: int) -> int:
    """Evaluations until the next read of the clock, after ``evaluations`` took ``elapsed_ns``
    (ns) since the last: those that take READ_INTERVAL_S at that pace, from 1 to
    WALL_CHECK_EVALUATIONS."""
    if elapsed_ns <= 0:
        return WALL_CHECK_EVALUATIONS
    paced = evaluations * (READ_INTERVAL_S * 1e9) / elapsed_ns
    return max(1, min(WALL_CHECK_EVALUATIONS, int(paced)))


@njit(cache=True, inline="always")
def exhausted(controls: Arr, cnt: Arr, t: float) -> int:
    """``BUDGET`` once cnt[0] evaluations reach controls[4] (max_nfev), ``WALL`` once the
    clock passes controls[5] (a ``time.perf_counter()`` deadline, s; read when cnt[0] reaches
    cnt[1], the next read ``read_interval`` evaluations later, reporting t (s) to the progress
    reporter if controls[7] (reporting) is 1; ``cnt``: ``counters``), else ``OK``."""
    if cnt[0] >= controls[4]:
        return BUDGET
    reporting = controls[7] != 0.0
    if (controls[5] < np.inf or reporting) and cnt[0] >= cnt[1]:
        now = _report_and_now_ns(t) if reporting else _now_ns()
        cnt[1] = cnt[0] + read_interval(cnt[0] - cnt[2], now - cnt[3])
        cnt[2] = cnt[0]
        cnt[3] = now
        if now * 1e-9 > controls[5]:
            return WALL
    return OK


@njit(cache=True, inline="always")
def smallest_step(t: float) -> float:
    """The smallest step (s) either stepper attempts from t (s): 10 ulp of t (scipy's rule)."""
    return float(10.0 * (np.nextafter(t, np.inf) - t))


@njit(cache=True, inline="always")
def next_attempt(
    t: float, t_bound: float, h_abs: float, min_step: float, finite: bool, controls: Arr, cnt: Arr
) -> tuple[int, float]:
    """Before a step attempt of h_abs (s) from t (s): (``STEP_TOO_SMALL``, or
    ``NON_FINITE`` when the last attempt was not ``finite``) below min_step (s), the
    budgets' codes (``exhausted``), else (``OK``, the attempt's end min(t + h_abs, t_bound))."""
    if h_abs < min_step:
        return (STEP_TOO_SMALL if finite else NON_FINITE), t
    code = exhausted(controls, cnt, t)
    if code != OK:
        return code, t
    return OK, min(t + h_abs, t_bound)
