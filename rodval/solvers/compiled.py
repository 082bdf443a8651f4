"""rodval's compiled integrators: whole runs in one compiled loop (``settings.COMPILED_METHODS``).

They take a system's ``CompiledForm`` (its own jitted right-hand side and arrays) and import
no model. ``run_compiled`` is called by the driver (``rodval.solvers.driver``).
"""

from __future__ import annotations

import time

import numpy as np

from rodval.core.scene import Scene
from rodval.core.settings import IntegratorSettings
from rodval.core.status import (
    STATUS_BLOWUP,
    STATUS_BUDGET,
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_FAILED,
    STATUS_STALLED,
    STATUS_WALL,
    numerical_failure,
)
from rodval.core.trajectory import SolverStats
from rodval.solvers import dop853, progress
from rodval.solvers.guard import ENERGY_FLOOR_J
from rodval.solvers.system import CompiledForm

_CODES = {
    dop853.STEP_TOO_SMALL: (
        STATUS_FAILED,
        "Required step size is less than spacing between numbers.",
    ),
    dop853.NON_FINITE: (STATUS_DIVERGED, "diverged: non-finite state"),
    dop853.BLOWUP: (
        STATUS_BLOWUP,
        "energy blow-up: kinetic energy > blowup_factor x budget E(0) + W+",
    ),
    dop853.STALLED: (
        STATUS_STALLED,
        "step size collapse: stall_steps consecutive steps shorter than min_step_fraction x t_end",
    ),
}
#: Codes of the budgets: status and the setting named in the message.
_BUDGETS = {
    dop853.BUDGET: (STATUS_BUDGET, "max_evaluations"),
    dop853.WALL: (STATUS_WALL, "max_wall_s"),
}


def run_compiled(
    form: CompiledForm,
    y0: np.ndarray,
    edges: np.ndarray,
    scene: Scene,
    settings: IntegratorSettings,
    energy0: float,
    Y: np.ndarray,
    stats: SolverStats,
) -> int:
    """Integrate over [edges[0], edges[-1]] restarting at each interior edge (the scene's
    breakpoints), writing states at the output times into Y; fills ``stats`` (status,
    message, t_reached, nfev, nsteps) and returns the number of output times reached.
    The divergence guard runs inside the loop, with the verdicts of ``rodval.solvers.guard``
    (``energy0``: the budget's E(0), J)."""
    guard = np.array(
        [settings.min_step_fraction * scene.t_end, settings.blowup_factor, energy0, ENERGY_FLOOR_J]
    )
    try:
        n_out, nfev, nsteps, code, t = dop853.integrate_compiled(
            form,
            y0,
            edges,
            np.asarray(scene.times, float),
            settings.rtol,
            settings.atol,
            settings.max_step,
            settings.first_step,
            settings.max_evaluations,
            guard,
            settings.stall_steps,
            Y,
            deadline=time.perf_counter() + settings.max_wall_s,
            reporting=progress.reporting(),
        )
    except Exception as exc:  # noqa: BLE001 - e.g. a singular mass matrix: reported as data
        # raised by a model's kernel: the loop's time is lost, t_reached stays at the start
        stats.status, stats.message = numerical_failure(exc, float(edges[0])) or (
            STATUS_ERROR,
            f"{type(exc).__name__}: {exc}",
        )
        return 0
    stats.nfev += nfev
    stats.nsteps += nsteps
    stats.t_reached = t
    if code in _BUDGETS:
        stats.status, budget = _BUDGETS[code]
        stats.message = settings.budget_message(budget, t)
    elif code != dop853.OK:
        stats.status, message = _CODES[code]
        stats.message = f"{message} (t = {t:.6g} s)"
    return n_out
