"""Return codes and the evaluation and wall-clock budgets of the compiled loop
(``rodval.solvers.dop853.run``), shared by its steppers (DOP853 and ``rodval.solvers.radau``).
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit, objmode

from rodval.solvers import guard as _guard
from rodval.solvers.progress import report

#: Return codes of the compiled loop: the guard's (``rodval.solvers.guard.guard_step``) and
#: the loop's own.
OK, BLOWUP, STALLED = _guard.OK, _guard.BLOWUP, _guard.STALLED
STEP_TOO_SMALL, NON_FINITE, BUDGET, WALL, EVENT = 1, 2, 3, 6, 7

#: Evaluations between two reads of the clock for the wall-clock budget: the read costs about
#: one evaluation of the smallest system, so this keeps it below 1 % of a run, and the run
#: overshoots its budget by at most this many evaluations (milliseconds up to n ~ 1e3).
WALL_CHECK_EVALUATIONS = 100


@njit(cache=True)
def _now():
    """``time.perf_counter()`` (s), read from inside the compiled loop."""
    with objmode(now="float64"):
        now = time.perf_counter()
    return now


@njit(cache=True)
def _report_and_now(t):
    """Tell the progress reporter (``rodval.solvers.progress``) that the run reached t (s),
    then read the clock; one call back into Python."""
    with objmode(now="float64"):
        report(t)
        now = time.perf_counter()
    return now


@njit(cache=True, inline="always")
def exhausted(controls, reporting, cnt, t):
    """``BUDGET`` once cnt[0] evaluations reach controls[4] (max_nfev), ``WALL`` once the
    clock passes controls[5] (a ``time.perf_counter()`` deadline, s; read when cnt[0] reaches
    cnt[1], then ``WALL_CHECK_EVALUATIONS`` evaluations later, reporting t (s) to the progress
    reporter if ``reporting``), else ``OK``."""
    if cnt[0] >= controls[4]:
        return BUDGET
    if (controls[5] < np.inf or reporting) and cnt[0] >= cnt[1]:
        cnt[1] = cnt[0] + WALL_CHECK_EVALUATIONS
        now = _report_and_now(t) if reporting else _now()
        if now > controls[5]:
            return WALL
    return OK


@njit(cache=True, inline="always")
def smallest_step(t):
    """The smallest step (s) either stepper attempts from t (s): 10 ulp of t (scipy's rule)."""
    return 10.0 * (np.nextafter(t, np.inf) - t)


@njit(cache=True, inline="always")
def next_attempt(t, t_bound, h_abs, min_step, finite, controls, reporting, cnt):
    """Before a step attempt of h_abs (s) from t (s): (``STEP_TOO_SMALL``, or
    ``NON_FINITE`` when the last attempt was not ``finite``) below min_step (s), the
    budgets' codes (``exhausted``), else (``OK``, the attempt's end min(t + h_abs, t_bound))."""
    if h_abs < min_step:
        return (STEP_TOO_SMALL if finite else NON_FINITE), t
    code = exhausted(controls, reporting, cnt, t)
    if code != OK:
        return code, t
    return OK, min(t + h_abs, t_bound)
