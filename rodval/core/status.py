"""How a run ended: status codes shared by every model, the driver, studies and reports.

0 and -1 follow scipy's OdeResult; the others are rodval's. A failure is data: a run never
raises for a failed integration, it ends with one of these codes, a message and the time reached.
"""

from __future__ import annotations

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
