"""rodval's compiled integrators: whole runs in one compiled loop (``settings.COMPILED_METHODS``).

They take a system's ``CompiledForm`` (its own jitted right-hand side and arrays) and import
no model. ``run_compiled`` is called by the driver (``rodval.solvers.driver``).
"""

from __future__ import annotations

import time
from typing import Any

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
from rodval.solvers.events import apply_hit
from rodval.solvers.guard import GuardSpec, diverged_message, verdict
from rodval.solvers.system import OdeSystem


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
    system: OdeSystem,
    y0: np.ndarray,
    edges: np.ndarray,
    scene: Scene,
    settings: IntegratorSettings,
    guard: GuardSpec,
    Y: np.ndarray,
    stats: SolverStats,
    ledger: PowerLedger | None = None,
    events: list[dict[str, Any]] | None = None,
) -> int:
    """Integrate ``system`` (its ``compiled()`` form) over [edges[0], edges[-1]] restarting at
    each interior edge (the scene's breakpoints) and after each event, writing states at the
    output times into Y; fills ``stats`` (status, message, t_reached, nfev, nsteps) and
    returns the number of output times reached. The divergence guard ``guard`` runs inside
    the loop, with the verdicts and messages of ``rodval.solvers.guard``; with a ``ledger``
    the energy audit too (its records become the loop's running W_ext, D at the output times
    reached). Events are located inside the loop; each one's jump is the system's
    (``rodval.solvers.events.apply_hit``, as on the scipy path), its record appended to
    ``events``, and the loop continues from there in the system's new mode."""
    times = np.asarray(scene.times, float)
    W = np.zeros((times.size, 2))
    total = np.zeros(2)
    deadline = time.perf_counter() + settings.max_wall_s
    t, y, n_out = float(edges[0]), np.array(y0, float), 0
    monitor = None
    while True:
        form = system.compiled()
        assert form is not None  # choose_method took the compiled path for this system
        try:
            res = dop853.integrate_compiled(
                form,
                y,
                np.concatenate([[t], edges[edges > t]]),
                times[n_out:],
                settings.rtol,
                settings.atol,
                settings.max_step,
                settings.first_step,
                settings.max_evaluations - stats.nfev,
                guard,
                Y[n_out:],
                deadline=deadline,
                reporting=progress.reporting(),
                audit=ledger is not None,
                monitor=monitor,
                total=total,
            )
        except Exception as exc:  # noqa: BLE001 - e.g. a singular mass matrix: reported as data
            # raised by a model's kernel: the loop's time is lost, t_reached stays at its start
            stats.status, stats.message = numerical_failure(exc, t) or (
                STATUS_ERROR,
                f"{type(exc).__name__}: {exc}",
            )
            stats.t_reached = t
            break
        if ledger is not None:
            W[n_out : n_out + res.n_out] = res.work
        n_out += res.n_out
        monitor = res.monitor
        stats.nfev += res.nfev
        stats.nsteps += res.nsteps
        stats.t_reached = t = res.t
        if res.code != dop853.EVENT:
            _ending(res, settings, guard, stats)
            break
        y, record, lost = apply_hit(system, res.event, res.t, res.y)
        total[1] += lost  # an impact's kinetic energy loss is dissipated energy of the audit
        if events is not None:
            events.append(record)
    if ledger is not None:
        ledger.replace(W[:n_out])
    return n_out


def _ending(res: dop853.CompiledRun, settings: IntegratorSettings, guard, stats) -> None:
    """Status and message of a compiled run that ended with ``res.code`` (not an event)."""
    if res.code in _BUDGETS:
        stats.status, budget = _BUDGETS[res.code]
        stats.message = settings.budget_message(budget, res.t)
    elif res.code != dop853.OK:
        stats.status, stats.message = verdict_message(res.code, res.monitor, res.t, guard)
