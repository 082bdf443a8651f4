"""How a run ended: status codes shared by every model, the driver, studies and reports.

0 and -1 follow scipy's OdeResult; the others are rodval's. A failure is data: a run never
raises for a failed integration, it ends with one of these codes, a message and the time reached.
"""

from __future__ import annotations

import numpy as np

STATUS_SUCCESS = 0
STATUS_FAILED = -1  # the integrator gave up (step size too small, singular matrix, ...)
STATUS_ERROR = -2  # the model raised an exception
STATUS_DIVERGED = -3  # NaN/inf in the state
STATUS_TIMEOUT = -4  # a study runner stopped the run at its time limit
STATUS_CRASHED = -5  # the process running the model died (e.g. a segfault in a library)
STATUS_BLOWUP = -6  # energy grew beyond settings.blowup_factor x its physical budget
STATUS_STALLED = -7  # step size collapsed below settings.min_step_fraction x t_end
STATUS_MESSAGES = {
    0: "success",
    -1: "integration failed",
    -2: "model error",
    -3: "diverged (non-finite state)",
    -4: "timeout",
    -5: "worker crashed",
    -6: "diverged (energy blow-up)",
    -7: "stalled (step size collapse)",
}


STATUS_BUDGET = -8  # the run used up its evaluation budget (settings.max_evaluations)
STATUS_WALL = -9  # the run used up its wall-clock budget (settings.max_wall_s)
STATUS_MESSAGES.update({-8: "evaluation budget exhausted", -9: "wall-clock budget exhausted"})


def numerical_failure(exc: BaseException, t: float) -> tuple[int, str] | None:
    """(status, message) of a run stopped at time t (s) by ``exc`` when it is a numerical
    failure, None for any other exception (a model error). Arithmetic that left float64 (a
    division by zero, an overflow; huge states) is ``STATUS_DIVERGED``; a matrix that cannot
    be factored (singular, not positive definite; chains at the extremes of their bounds) is
    ``STATUS_FAILED``. The message names the exception and the time."""
    if isinstance(exc, (ZeroDivisionError, OverflowError, FloatingPointError)):
        return STATUS_DIVERGED, f"diverged: {type(exc).__name__}: {exc} at t = {t:.6g} s"
    if isinstance(exc, np.linalg.LinAlgError):
        return STATUS_FAILED, (
            f"numerical failure: {type(exc).__name__}: {exc} at t = {t:.6g} s "
            "(a matrix of the model could not be factored)"
        )
    return None
