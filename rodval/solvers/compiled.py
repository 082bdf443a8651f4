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
    STATUS_BUDGET,
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_FAILED,
    STATUS_WALL,
    numerical_failure,
)
from rodval.core.trajectory import SolverStats
from rodval.solvers import dop853, progress
from rodval.solvers.audit import PowerLedger
from rodval.solvers.guard import GuardSpec, diverged_message, verdict
from rodval.solvers.system import CompiledForm


def verdict_message(code: int, mon: np.ndarray, t: float, spec: GuardSpec) -> tuple[int, str]:
    """Status and message of a compiled run that ended with ``code`` at t (s), the start of
    the last step; the guard's verdicts (``rodval.solvers.guard.verdict``) at its end."""
    if code == dop853.STEP_TOO_SMALL:
        return STATUS_FAILED, "Required step size is less than spacing between numbers."
    if code == dop853.NON_FINITE:
        return STATUS_DIVERGED, diverged_message(t)
    judged = verdict(code, mon, t + mon[1], spec)
    if judged is None:
        raise ValueError(f"unknown return code {code} of the compiled loop")
    return judged


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
    guard: GuardSpec,
    Y: np.ndarray,
    stats: SolverStats,
    ledger: PowerLedger | None = None,
) -> int:
    """Integrate over [edges[0], edges[-1]] restarting at each interior edge (the scene's
    breakpoints), writing states at the output times into Y; fills ``stats`` (status,
    message, t_reached, nfev, nsteps) and returns the number of output times reached.
    The divergence guard ``guard`` runs inside the loop, with the verdicts and messages of
    ``rodval.solvers.guard``; with a ``ledger`` the energy audit too (its records become the
    loop's running W_ext, D at the output times reached)."""
    try:
        n_out, nfev, nsteps, code, t, mon, work = dop853.integrate_compiled(
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
            Y,
            deadline=time.perf_counter() + settings.max_wall_s,
            reporting=progress.reporting(),
            audit=ledger is not None,
        )
    except Exception as exc:  # noqa: BLE001 - e.g. a singular mass matrix: reported as data
        # raised by a model's kernel: the loop's time is lost, t_reached stays at the start
        stats.status, stats.message = numerical_failure(exc, float(edges[0])) or (
            STATUS_ERROR,
            f"{type(exc).__name__}: {exc}",
        )
        return 0
    if ledger is not None:
        ledger.replace(work)
    stats.nfev += nfev
    stats.nsteps += nsteps
    stats.t_reached = t
    if code in _BUDGETS:
        stats.status, budget = _BUDGETS[code]
        stats.message = settings.budget_message(budget, t)
    elif code != dop853.OK:
        stats.status, stats.message = verdict_message(code, mon, t, guard)
    return n_out
