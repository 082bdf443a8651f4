"""How an exudyn run ends: its guard, its status and the output times it keeps, its lock
records, and a prescribed base's unaudited drive (``exudyn_chain.ExudynModel._run_at``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from reference_models.exudyn_beam import Array
from reference_models.exudyn_budget import RunBudget
from reference_models.exudyn_build import BuiltSystem
from reference_models.exudyn_guard import Guard
from reference_models.exudyn_latches import Latches
from reference_models.exudyn_observe import Observed, body_view
from rodval.core.scene import Scene
from rodval.core.status import STATUS_DIVERGED, STATUS_FAILED, update_status
from rodval.core.trajectory import SolverStats

#: What a prescribed base's run leaves unaudited: the drive's work is not measured.
DRIVE_UNAUDITED = ("work", "dissipated", "energy_residual")
#: A lock window's accounts that need the work done on the chain (the drive's included).
DRIVE_WINDOW_KEYS = ("work_window_end", "dissipated_window_end", "energy_residual_window_end")


def run_guard(
    built: BuiltSystem, scene: Scene, E: int, EA: float, factor: float, rotation: float
) -> Guard:
    """The run's ``Guard``. On a prescribed base it sees the massless body (``body_view``:
    the lock records' kinetic energies are the chain's, as the native models') and checks no
    energy budget: its drive's work, which the budget would need, is not measured (the
    non-finite and rotation-per-step checks stay)."""
    return Guard(
        built, body_view(scene), E, EA, factor, rotation, checks_energy=not scene.base.prescribed
    )


def unaudited_drive(
    observed: Observed, events: list[dict[str, Any]]
) -> tuple[None, dict[str, float]]:
    """A prescribed base's run is not audited for energy: its drive's power (the imposed
    coordinates' constraint forces on the chain) is not measured, so the balance's work would
    miss it. The audit's quantities are dropped from ``observed``, and the lock windows' work,
    dissipation and residual from their records (their energies at the window's end stay);
    returns (no residual, no settings entry) as for any unaudited run."""
    for name in DRIVE_UNAUDITED:
        observed.pop(name, None)
    for ev in events:
        for key in DRIVE_WINDOW_KEYS:
            ev.pop(key, None)
    return None, {}


def ended(
    scene: Scene, stats: SolverStats, checks: tuple[Guard, RunBudget], t_rec: Array, diverged: bool
) -> Array:
    """How the run ended (status, message, time reached into ``stats``, each ending through
    ``update_status``'s precedence: the guard's verdict, which stopped the solver and says
    why; a state cut off as non-finite; the budget's stop (``checks`` = (guard, budget)) of
    a run that ended early, or else a plain failure) and the output times it kept."""
    guard, budget = checks
    stats.t_reached = float(t_rec[-1]) if t_rec.size else 0.0
    keep_detected = True
    if guard.verdict is not None:
        status, message, t_detected, keep = guard.verdict
        t = min(stats.t_reached, t_detected) if t_rec.size else 0.0
        if update_status(stats, status, message, t):
            keep_detected = keep
    short = stats.t_reached < scene.t_end * (1 - 1e-9)
    if diverged and guard.verdict is None:
        update_status(stats, STATUS_DIVERGED, f"non-finite state after t = {stats.t_reached:.6g} s")
    if short:
        stopped = budget.outcome(stats.t_reached)
        update_status(stats, *(stopped or (STATUS_FAILED, "solver stopped before t_end")))
    times: Array = np.asarray(scene.times)
    tol = 1e-9 * max(1.0, scene.t_end)
    if not t_rec.size:
        return t_rec
    if keep_detected:
        return times[times <= stats.t_reached + tol]
    return times[times < stats.t_reached - tol]  # the state at the detection time is bad


def lock_records(
    latches: Latches | None,
) -> tuple[list[dict[str, Any]], tuple[dict[int, float], dict[int, float]]]:
    """The lock events in time order and (hinge -> lock time, hinge -> the time its compliant
    latch acts after) (s, ``Latches.engaged``), pending locks closed."""
    if latches is None:
        return [], ({}, {})
    try:
        latches.close()
    except Exception:  # noqa: BLE001 - the pending locks stay unrecorded
        pass
    events = sorted(latches.events, key=lambda ev: ev["t"])
    return events, (dict(latches.lock_times.items()), dict(latches.engaged))


def solver_message(solver: Any, default: str) -> str:
    """exudyn's error string of a failed solve, ``default`` when it gives none."""
    try:
        msg = solver.GetErrorString()
    except Exception:  # noqa: BLE001
        msg = ""
    return msg.strip() or default
