"""How a run ended: status codes shared by every model, the driver, studies and reports.

0 and -1 follow scipy's OdeResult; the others are rodval's. A failure is data: a run never
raises for a failed integration, it ends with one of these codes, a message and the time reached.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

#: How a run ended, as text in files (runtime.csv, reports) and in ``str(Status.X)``.
STATUS_MESSAGES = {
    0: "success",
    -1: "integration failed",
    -2: "model error",
    -3: "diverged (non-finite state)",
    -4: "timeout",
    -5: "worker crashed",
    -6: "diverged (energy blow-up)",
    -7: "stalled (step size collapse)",
    -8: "evaluation budget exhausted",
    -9: "wall-clock budget exhausted",
}


class Status(IntEnum):
    """How a run ended: an int (run.json and case records store the number, scipy's 0 and
    -1 kept) whose ``str`` is the text files and reports show (``STATUS_MESSAGES``), so a
    status reads the same in Python and in runtime.csv."""

    SUCCESS = 0
    FAILED = -1  # the integrator gave up (step size too small, singular matrix, ...)
    ERROR = -2  # the model raised an exception
    DIVERGED = -3  # NaN/inf in the state
    TIMEOUT = -4  # a study runner stopped the run at its time limit
    CRASHED = -5  # the process running the model died (e.g. a segfault in a library)
    BLOWUP = -6  # energy grew beyond settings.blowup_factor x its physical budget
    STALLED = -7  # step size collapsed below settings.min_step_fraction x t_end
    BUDGET = -8  # the run used up its evaluation budget (settings.max_evaluations)
    WALL = -9  # the run used up its wall-clock budget (settings.max_wall_s)

    @property
    def label(self) -> str:
        return STATUS_MESSAGES[int(self)]

    def __str__(self) -> str:
        return self.label


STATUS_SUCCESS = Status.SUCCESS
STATUS_FAILED = Status.FAILED
STATUS_ERROR = Status.ERROR
STATUS_DIVERGED = Status.DIVERGED
STATUS_TIMEOUT = Status.TIMEOUT
STATUS_CRASHED = Status.CRASHED
STATUS_BLOWUP = Status.BLOWUP
STATUS_STALLED = Status.STALLED
STATUS_BUDGET = Status.BUDGET
STATUS_WALL = Status.WALL


def numerical_failure(exc: BaseException, t: float) -> tuple[int, str] | None:
    """(status, message) of a run stopped at time t (s) by ``exc`` when it is a numerical
    failure, None for any other exception (a model error). Arithmetic that left float64 (a
    division by zero, an overflow; huge states) is ``STATUS_DIVERGED``; a matrix that cannot
    be factored (singular, not positive definite; chains at the extremes of their bounds) is
    ``STATUS_FAILED``. The message names the exception and the time."""
    if isinstance(exc, (ZeroDivisionError, OverflowError, FloatingPointError)):
        return STATUS_DIVERGED, f"diverged: {exception_line(exc)} at t = {t:.6g} s"
    if isinstance(exc, np.linalg.LinAlgError):
        return STATUS_FAILED, (
            f"numerical failure: {exception_line(exc)} at t = {t:.6g} s "
            "(a matrix of the model could not be factored)"
        )
    return None


def exception_line(exc: BaseException) -> str:
    """``exc`` as one line for a run's message (run.json, runtime.csv, the status line): its
    type and the first non-empty line of its text, with the count of lines left out (numba's
    typing errors run to 60 lines, which were dumped whole into stdout and run.json)."""
    lines = [x.strip() for x in str(exc).splitlines() if x.strip()]
    head = lines[0] if lines else ""
    more = f" [{len(lines) - 1} more lines not shown]" if len(lines) > 1 else ""
    return f"{type(exc).__name__}: {head}{more}"
