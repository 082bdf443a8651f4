"""rodval's compiled integrators: whole runs in one compiled loop (``settings.COMPILED_METHODS``).

They take a system's ``CompiledForm`` (its own jitted right-hand side and arrays) and import
no model. ``run_compiled`` is called by the driver (``rodval.solvers.driver``);
``integrate_compiled`` runs ``rodval.solvers.dop853.run`` once (to the end or an event).
"""

from __future__ import annotations

import math
import time
from typing import Any, NamedTuple

import numpy as np

from rodval.core.settings import AUTO, IntegratorSettings
from rodval.core.status import (
    STATUS_BUDGET,
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_FAILED,
    STATUS_WALL,
    exception_line,
    numerical_failure,
    update_status,
)
from rodval.core.trajectory import SolverStats
from rodval.solvers import budget, dop853, progress, stiffness
from rodval.solvers.audit import PowerLedger
from rodval.solvers.budget import EVENT, Settings
from rodval.solvers.dop853 import DOP853_STEPPER, loop
from rodval.solvers.dop853_events import no_events
from rodval.solvers.events import apply_hit
from rodval.solvers.guard import GuardSpec, diverged_message, new_monitor, verdict
from rodval.solvers.outputs import Outputs
from rodval.solvers.signature import Arr, Form
from rodval.solvers.system import CompiledForm, OdeSystem


def verdict_message(code: int, mon: np.ndarray, t: float, spec: GuardSpec) -> tuple[int, str]:
    """Status and message of a compiled run that ended with ``code`` at t (s), the start of
    the last step; the guard's verdicts (``rodval.solvers.guard.verdict``) at its end."""
    if code == budget.STEP_TOO_SMALL:
        return STATUS_FAILED, "Required step size is less than spacing between numbers."
    if code == budget.NON_FINITE:
        return STATUS_DIVERGED, diverged_message(t)
    judged = verdict(code, mon, t + mon[1], spec)
    if judged is None:
        raise ValueError(f"unknown return code {code} of the compiled loop")
    return judged


#: Codes of the budgets: status and the setting named in the message.
_BUDGETS = {
    budget.BUDGET: (STATUS_BUDGET, "max_evaluations"),
    budget.WALL: (STATUS_WALL, "max_wall_s"),
}


#: The compiled loop's stepper for each method that runs on it.
_STEPPERS = {
    "DOP853-numba": dop853.DOP853_STEPPER,
    "Radau-numba": dop853.RADAU_STEPPER,
    AUTO: dop853.SWITCHING_STEPPER,
}


def switch_record(sw: np.ndarray) -> dict[str, Any] | None:
    """``SolverStats.switch`` from the switching state (``stiffness.new_state``): None when
    "auto" never left DOP853."""
    if np.isnan(sw[stiffness.T_FIRST]):
        return None
    t, h, rho = sw[stiffness.T_SWITCH], sw[stiffness.H_SWITCH], sw[stiffness.RHO]
    explicit, implicit = sw[stiffness.RATE_EXPLICIT], sw[stiffness.RATE_IMPLICIT]
    ended = "Radau-numba" if sw[stiffness.IMPLICIT] == 1.0 else "DOP853-numba"
    reason = (
        f"DOP853's steps spent on the fastest mode at t = {t:.6g} s: h rho = {h * rho:.3g} > "
        f"{stiffness.STIFF_H_RHO:g} on {stiffness.STIFF_STEPS} steps (h = {h:.3g} s, "
        f"spectral radius {rho:.4g} 1/s; stability limit h rho = "
        f"{stiffness.STABILITY_IMAG:.3g}), {explicit:.4g} evaluations per simulated second"
    )
    if not np.isnan(implicit):
        reason += f"; Radau IIA {implicit:.4g} per simulated second"
    reason += f"; ended on {ended}"
    return {
        "to": "Radau-numba",
        "first_t": float(sw[stiffness.T_FIRST]),
        "switches": int(sw[stiffness.SWITCHES]),
        "failed_trials": int(sw[stiffness.FAILED]),
        "t": float(t),
        "h": float(h),
        "spectral_radius": float(rho),
        "explicit_cost_per_s": float(explicit),
        "implicit_cost_per_s": None if np.isnan(implicit) else float(implicit),
        "ended_on": ended,
        "reason": reason,
    }


def held_by(switch: dict[str, Any] | None, remaining: float, used: int) -> str:
    """ "; its steps were held by a vibration of ... rad/s (... Hz) ..." for a run whose steps
    the stiffness test found limited by its fastest mode (``switch``: ``switch_record``), with
    the evaluations the ``remaining`` horizon (s) would take at the cheaper method's rate and
    the budget that would reach t_end: the ``used`` evaluations plus those, with a quarter
    more for the rate's change along the way, in two significant digits; "" otherwise."""
    if switch is None:
        return ""
    rho = switch["spectral_radius"]
    rates = [r for r in (switch["explicit_cost_per_s"], switch["implicit_cost_per_s"]) if r]
    more = min(rates) * remaining
    return (
        f"; its steps were held by a vibration of {rho:.4g} rad/s ({rho / (2 * np.pi):.4g} Hz, "
        f"the spectral radius at t = {switch['t']:.6g} s): about {more:.2g} more evaluations "
        f"to t_end at {min(rates):.3g} per simulated second (max_evaluations = "
        f"{float(f'{used + 1.25 * more:.2g}'):.2g} would reach it, command line "
        "--max-evaluations)"
    )


def atol_vector(system: OdeSystem, settings: IntegratorSettings) -> float | np.ndarray:
    """The absolute tolerance of each state component (rad, rad/s, m, m/s): ``settings.atol``
    (a float) for "uniform" error control or a system without bending coordinates
    (``OdeSystem.bending_mask`` None or empty); for "per-block" (``IntegratorSettings``) the
    coordinates (the first half of [q; q']) max(atol, rtol x 1) and their rates max(atol,
    rtol x block_frequency), the bending block's (``bending_mask``) times bending_scale."""
    mask = system.bending_mask()
    if settings.error_control == "uniform" or mask is None or not mask.any():
        return settings.atol
    half = mask.size // 2
    scale = np.where(mask, settings.bending_scale, 1.0)
    scale[half:] *= settings.block_frequency
    return np.maximum(settings.atol, settings.rtol * scale)


class Controls(NamedTuple):
    """The settings of one ``integrate_compiled`` run."""

    rtol: float  #: relative tolerance
    #: absolute tolerance: one for every coordinate, or one per coordinate (N,), e.g.
    #: ``rodval.solvers.compiled.atol_vector``'s
    atol: float | Arr
    max_step: float  #: s
    first_step: float | None  #: s; None: selected (``dop853._initial_step``)
    max_nfev: int  #: the evaluation budget
    deadline: float = math.inf  #: a ``time.perf_counter()`` value (s)
    reporting: bool = False  #: report progress (``rodval.solvers.progress``)
    audit: bool = False  #: integrate the load and damper powers (the energy audit)
    #: ``DOP853_STEPPER``, ``RADAU_STEPPER`` or ``SWITCHING_STEPPER``, see ``dop853.run``
    stepper: int = DOP853_STEPPER


class Carry(NamedTuple):
    """What a run continued after an event carries on from the last (updated in place)."""

    monitor: Arr | None  #: the guard's (``guard_step``); None: a new one
    total: Arr  #: the audit's running [W_ext, D] (J)
    switch: Arr  #: the switching stepper's state (``stiffness.new_state``)


class CompiledRun(NamedTuple):
    """What ``integrate_compiled`` returns."""

    n_out: int  #: output times written
    nfev: int  #: right-hand-side evaluations
    nsteps: int  #: accepted steps
    code: int  #: how the loop ended (OK, STEP_TOO_SMALL, ..., EVENT)
    t: float  #: time reached (s): the event's time for EVENT
    monitor: Arr  #: the guard's figures (``guard_step``)
    work: Arr  #: the audit's [W_ext, D] (J) at the output times written, (n_out, 2)
    event: int  #: the event's index (EVENT), else -1
    y: Arr  #: the state at the event (before its jump; EVENT), else empty
    #: the switching stepper's state (``stiffness.new_state``; carried over restarts)
    switch: Arr


def start_monitor(form: CompiledForm, t: float, y: Arr, guard: GuardSpec) -> Arr:
    """The guard's monitor for a run of ``form`` from (t, y): the load power there in it
    when the guard checks energy (``rodval.solvers.guard.new_monitor``)."""
    if form.mechanics is None or not guard.checks_energy:
        return new_monitor()
    mech = np.zeros(3)
    form.mechanics(t, np.array(y, float), form.P, form.S, form.M, form.L, mech)
    return new_monitor(mech[1])


def packed(form: CompiledForm) -> Form:
    """``form`` as the compiled integrators take it (``signature.FORM_TYPE``); without
    mechanics its right-hand side stands in for them (never called: no energy check, no
    audit), without events ``no_events``."""
    mechanics = form.mechanics if form.mechanics is not None else form.rhs
    events = form.events if form.events is not None else no_events
    return (form.P, form.S, form.M, form.L, form.E, form.directions, form.rhs, mechanics, events)


def _settings(form: CompiledForm, y0: Arr, controls: Controls, guard: GuardSpec) -> Settings:
    """The loop's ``budget.Settings`` for ``controls`` and ``guard`` (its energy check off
    without ``form.mechanics``)."""
    g = guard.as_array()
    if form.mechanics is None:
        g[2] = math.inf
        if controls.audit:
            raise ValueError("an energy audit needs the compiled form's mechanics")
    first = -1.0 if controls.first_step is None else controls.first_step
    atol = np.array(np.broadcast_to(np.asarray(controls.atol, float), y0.shape))
    values = (controls.rtol, atol.max(), controls.max_step, first, controls.max_nfev)
    more = (controls.deadline, controls.stepper, controls.reporting)
    return np.array(values + more, float), atol, g


def integrate_compiled(
    form: CompiledForm,
    y0: Arr,
    edges: Arr,
    times: Arr,
    Y: Arr,
    controls: Controls,
    guard: GuardSpec,
    carry: Carry | None = None,
) -> CompiledRun:
    """Run ``dop853.run`` on a CompiledForm from (edges[0], y0) (see there; without
    ``form.mechanics`` there is no blow-up check and no audit), the states at ``times``
    into Y (len(times), N). A run continued after an event passes the guard's monitor, the
    audit's running total and the switching state on (``carry``, updated in place); new ones
    start from (edges[0], y0)."""
    y0 = np.array(y0, float)
    settings = _settings(form, y0, controls, guard)
    carry = carry or Carry(None, np.zeros(2), stiffness.new_state())
    mon = carry.monitor
    mon = start_monitor(form, float(edges[0]), y0, guard) if mon is None else mon
    W = np.zeros((len(times) if controls.audit else 0, 2))
    hit = np.zeros(y0.size + 1)
    kernels = packed(form)
    n_out, nfev, nsteps, code, t = loop()(
        kernels[:6],
        *kernels[6:],
        y0,
        np.array(edges, float),
        settings,
        (np.array(times, float), Y, W),
        (mon, carry.total, hit, carry.switch),
    )
    event = int(hit[0]) if code == EVENT else -1
    y_event = hit[1:].copy() if code == EVENT else np.zeros(0)
    return CompiledRun(
        int(n_out),
        int(nfev),
        int(nsteps),
        int(code),
        float(t),
        mon,
        W[:n_out],
        event,
        y_event,
        carry.switch,
    )


def run_compiled(
    system: OdeSystem,
    y0: np.ndarray,
    edges: np.ndarray,
    settings: IntegratorSettings,
    guard: GuardSpec,
    out: Outputs,
    stats: SolverStats,
    ledger: PowerLedger | None = None,
    events: list[dict[str, Any]] | None = None,
) -> None:
    """Integrate ``system`` (its ``compiled()`` form) over [edges[0], edges[-1]] restarting at
    each interior edge (the scene's breakpoints) and after each event, writing states at the
    output and lock-window probe times into ``out``; fills ``stats`` (status, message,
    t_reached, nfev, nsteps). The divergence guard ``guard`` runs inside
    the loop, with the verdicts and messages of ``rodval.solvers.guard``; with a ``ledger``
    the energy audit too (its records become the loop's running W_ext, D). Events are
    located inside the loop; each one's jump is the system's (``events.apply_hit``, as on
    the scipy path), its record appended to ``events``; the loop goes on in the new mode.
    The stepper: ``_STEPPERS[settings.method]`` (its switches in ``stats.switch``)."""
    W = np.zeros((out.times.size, 2))
    deadline = time.perf_counter() + settings.max_wall_s
    t, y = float(edges[0]), np.array(y0, float)
    carry = Carry(None, np.zeros(2), stiffness.new_state())
    atol = atol_vector(system, settings)
    while True:
        form = system.compiled()
        assert form is not None  # choose_method took the compiled path for this system
        times = out.remaining()
        buffer = np.empty((times.size, y.size))
        controls = Controls(
            settings.rtol,
            atol,
            settings.max_step,
            settings.first_step,
            settings.max_evaluations - stats.nfev,
            deadline,
            progress.reporting(),
            ledger is not None,
            _STEPPERS[settings.method],
        )
        segments = np.concatenate([[t], edges[edges > t]])
        try:
            res = integrate_compiled(form, y, segments, times, buffer, controls, guard, carry)
        except Exception as exc:  # noqa: BLE001 - e.g. a singular mass matrix: reported as data
            # raised by a model's kernel: the loop's time is lost, t_reached stays at its start
            update_status(
                stats, *(numerical_failure(exc, t) or (STATUS_ERROR, exception_line(exc)))
            )
            stats.t_reached = t
            break
        n_out = out.n
        written = out.write(buffer[: res.n_out])
        if ledger is not None:
            W[n_out : out.n] = res.work[written]
        # a restart goes on with the guard's monitor and the stepper the run ended with
        carry = Carry(res.monitor, carry.total, res.switch)
        stats.nfev += res.nfev
        stats.nsteps += res.nsteps
        stats.t_reached = t = res.t
        stats.switch = switch_record(res.switch)
        if res.code != budget.EVENT:
            _ending(res, settings, guard, stats, float(edges[-1]))
            break
        y = _event(system, res, carry.total, events, out)
    if ledger is not None:
        ledger.replace(W[: out.n])


def _event(
    system: OdeSystem,
    res: CompiledRun,
    total: np.ndarray,
    events: list[dict[str, Any]] | None,
    out: Outputs,
) -> np.ndarray:
    """The located event of ``res``: the system's jump (its state returned), the impact's
    kinetic energy loss booked as dissipated energy of the audit (``total``), the record
    appended to ``events`` and given to the lock windows."""
    y, record, lost = apply_hit(system, res.event, res.t, res.y)
    total[1] += lost
    if events is not None:
        events.append(record)
    if out.windows is not None:
        out.windows.event(record)
    return y


def _ending(
    res: CompiledRun,
    settings: IntegratorSettings,
    guard: GuardSpec,
    stats: SolverStats,
    t_end: float,
) -> None:
    """Status and message of a compiled run that ended with ``res.code`` (not an event). A
    budget spent on a stiff vibration (``stats.switch``) says which and what the rest of the
    horizon would cost (``held_by``)."""
    if res.code in _BUDGETS:
        code, setting = _BUDGETS[res.code]
        held = held_by(stats.switch, t_end - res.t, stats.nfev)
        update_status(stats, code, settings.budget_message(setting, res.t) + held)
    elif res.code != budget.OK:
        update_status(stats, *verdict_message(res.code, res.monitor, res.t, guard))
