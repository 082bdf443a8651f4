"""How a run ended: status codes shared by every model, the driver, studies and reports.

0 and -1 follow scipy's OdeResult; the others are rodval's. A failure is data: a run never
raises for a failed integration, it ends with one of these codes, a message and the time reached.
"""

from __future__ import annotations

from enum import IntEnum
from typing import Protocol

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


#: Which ending wins when two apply to one run, defined once (diffrax's ``update_result``):
#: a status is replaced only by one of higher rank, never by one of equal or lower rank, so
#: among equals the first stays. Ranks, from how little the ending says is wrong with the
#: model to how much: 0 success; 1 a budget spent (wall clock, evaluations, a study's time
#: limit: the run was stopped from outside, its state fine); 2 the integrator gave up; 3 its
#: steps collapsed; 4 the energy blew up; 5 the state left float64 (non-finite); 6 the model
#: (or the process running it) broke. So the guard's verdict replaces the solver failure it
#: caused, a non-finite state replaces a plain failure, and nothing replaces a model error.
PRECEDENCE: dict[Status, int] = {
    Status.SUCCESS: 0,
    Status.WALL: 1,
    Status.BUDGET: 1,
    Status.TIMEOUT: 1,
    Status.FAILED: 2,
    Status.STALLED: 3,
    Status.BLOWUP: 4,
    Status.DIVERGED: 5,
    Status.ERROR: 6,
    Status.CRASHED: 6,
}


def update_result(old: int, new: int) -> Status:
    """The status of a run that ended ``old`` when ``new`` applies too: ``new`` if it ranks
    above ``old`` in ``PRECEDENCE``, else ``old`` (ValueError for a number that is no
    status)."""
    old_s, new_s = Status(old), Status(new)
    return new_s if PRECEDENCE[new_s] > PRECEDENCE[old_s] else old_s


class Outcome(Protocol):
    """What ``update_status`` writes: a run's status, message and time reached (s)."""

    status: int
    message: str
    t_reached: float


def update_status(result: Outcome, code: int, message: str, t: float | None = None) -> bool:
    """Apply the ending ``code`` with its one-line ``message`` (and ``t``, the time reached
    in s, when given) to ``result`` (a ``SolverStats``) when it wins by ``update_result``;
    returns whether it did. The one place a run's status is written."""
    old = Status(result.status)
    if update_result(old, code) == old:
        return False
    result.status, result.message = Status(code), message
    if t is not None:
        result.t_reached = float(t)
    return True


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
