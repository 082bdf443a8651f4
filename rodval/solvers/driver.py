"""ODE driver: integrates an ``OdeSystem`` over [0, t_end] and observes it at the output times.

Small parts, each in its own place (docs/architecture.md, "The driver in parts"):

* what a run records, set up once (``_Plan``) from what the scene asks and the system declares,
  and the method (``choose_method``): "auto" takes the compiled DOP853 when the system's compiled
  form can do what is asked (its mechanics for an energy audit, its event functions for a system
  with events), scipy's DOP853 otherwise; the compiled loop of "auto" switches to its Radau IIA
  when the steps are limited by stability (``settings.AUTO``);
* stepping: a scipy ``OdeSolver`` across the scene's load breakpoints (``_ScipyRun``), or a
  compiled loop (``rodval.solvers.compiled``); each path's ending is a value, applied once;
* budgets and non-finite derivatives, checked on every evaluation, including those of rejected
  step attempts (so a NaN step size never loops): an explicit Runge-Kutta method rejects a
  non-finite attempt and cuts its step (a stiff transient), and the run ends as diverged when
  the attempts stay non-finite down to the smallest step; the other methods stop at once;
* after every accepted step: events (``rodval.solvers.events``: crossing located, state jump
  applied, step restarted), the divergence guard (``rodval.solvers.guard``), the energy audit
  (``rodval.solvers.audit``) on the dense output, read on the audit grid as the momentum's;
* observation at the output times reached; the run's peaks (``SolverStats.peaks``) on the
  peak grid and the lock windows' probes of the dense output (``outputs.PeakGrid``).

Dense output is formed only on steps that contain output times, events, or when the scene asks
for "energy". A failure ends the run early with a status, a message and the time reached; the
output times reached so far are kept.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.integrate

from rodval.core.quantities import PEAK_QUANTITIES
from rodval.core.scene import Scene
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
from rodval.core.trajectory import SolverStats, Trajectory, finish
from rodval.core.validity import SMALL_BENDING_RAD, momentum_point
from rodval.solvers.audit import (
    PowerLedger,
    audit_quantities,
    energy_residual,
    momentum_residual,
)
from rodval.solvers.events import EventMonitor, apply_hit
from rodval.solvers.guard import DivergenceGuard, Verdict
from rodval.solvers.limits import MAX_IMPLICIT_SIZE
from rodval.solvers.outputs import AuditGrid, LockWindows, Outputs, PeakGrid
from rodval.solvers.progress import report
from rodval.solvers.system import CompiledForm, Observed, OdeSystem

#: scipy methods that reject a step attempt whose error norm is not finite and cut the step.
_REJECTS_NON_FINITE = ("RK23", "RK45", "DOP853")


class _Stop(Exception):
    """Ends a scipy run from inside the right-hand side: ``code`` (a status), message."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code


def choose_method(
    system: OdeSystem, settings: IntegratorSettings, audit: bool
) -> tuple[str, CompiledForm | None]:
    """The method that will run and the system's compiled form it runs (None on scipy),
    built once: ``audit`` when the run audits energy. ValueError (before any work) when a
    compiled method is asked for what it cannot do."""
    events = bool(system.event_functions())
    form = system.compiled()
    if settings.method == AUTO:
        if (
            form is not None
            and (form.mechanics is not None or not audit)
            and (form.events is not None or not events)
        ):
            return "DOP853-numba", form
        return "DOP853", None
    if not settings.compiled:
        return settings.method, None
    if form is None:
        raise ValueError(
            f"method {settings.method!r} needs a system with a compiled form "
            "(native models with kernel='numba' and loads built from rodval's "
            "load laws: pulse/constant/ramp/harmonic/tabulated, not plain "
            "callables); use a scipy method or 'auto'"
        )
    if audit and form.mechanics is None:
        raise ValueError(
            f"method {settings.method!r} cannot audit energy for this system (its "
            "compiled form has no mechanics); use a scipy method or 'auto'"
        )
    if settings.method == "Radau-numba" and system.y0.size > MAX_IMPLICIT_SIZE:
        raise ValueError(
            f"method 'Radau-numba' factorizes dense N x N matrices (O(N^3)): this system "
            f"has N = {system.y0.size} states, allowed N <= {MAX_IMPLICIT_SIZE}; use "
            "'auto' or 'DOP853-numba'"
        )
    if events and form.events is None:
        raise ValueError(
            f"method {settings.method!r} cannot handle this system's events (its "
            "compiled form has no event functions); use a scipy method or 'auto'"
        )
    return settings.method, form


def segment_edges(scene: Scene) -> np.ndarray:
    """0, the load breakpoints, and the end: t_end, or the last output time when it lies
    beyond t_end by round-off (the Scene accepts it, so it is reached and returned)."""
    end = max(scene.t_end, float(scene.times[-1]))
    return np.concatenate([[0.0], scene.breakpoints, [end]])


class _ScipyRun:
    """One run on a scipy OdeSolver with evaluation and wall budgets, events, guard and audit."""

    def __init__(
        self,
        system: OdeSystem,
        settings: IntegratorSettings,
        plan: _Plan,
        stats: SolverStats,
        guard: DivergenceGuard,
    ):
        self.system, self.settings, self.stats, self.guard = system, settings, stats, guard
        self.out, self.ledger = plan.out, plan.ledger
        method = plan.method
        self.cls = getattr(scipy.integrate, method)  # one of SCIPY_METHODS
        self.nfev = 0
        #: event records (plain dicts) in time order
        self.events: list[dict[str, Any]] = []
        self.deadline = time.perf_counter() + settings.max_wall_s
        self.extra: dict[str, Any] = {}
        if settings.implicit and system.has_jacobian:
            self.extra["jac"] = self.jac
        if settings.first_step is not None:
            self.extra["first_step"] = settings.first_step
        #: scipy's explicit Runge-Kutta methods reject an attempt whose error norm is not
        #: finite and cut the step (as the compiled loop does): they are given the attempt's
        #: non-finite values; the other methods stop at the first one
        self.rejects_non_finite = method in _REJECTS_NON_FINITE
        #: the message of the last evaluation if it was not finite (None after a finite one)
        self.non_finite: str | None = None
        #: set before a solver starts: its first evaluation is at the accepted state, where a
        #: non-finite value is a divergence for every method
        self.at_start = False

    def fun(self, t: float, y: np.ndarray) -> np.ndarray:
        self.nfev += 1
        if self.nfev > self.settings.max_evaluations:
            raise _Stop(STATUS_BUDGET, self.settings.budget_message("max_evaluations", t))
        if time.perf_counter() > self.deadline:
            raise _Stop(STATUS_WALL, self.settings.budget_message("max_wall_s", t))
        start, self.at_start = self.at_start, False
        # scipy's finite-difference Jacobian (Radau, BDF) hands in strided columns
        y = np.ascontiguousarray(y)
        if not np.all(np.isfinite(y)):
            return self._non_finite(
                y, f"diverged: non-finite state in a step attempt at t = {t:.6g} s", start
            )
        try:
            f = self.system.rhs(t, y)
        except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
            raise _Stop(*_failure(exc, t)) from exc
        if not np.all(np.isfinite(f)):
            return self._non_finite(f, f"diverged: non-finite derivative at t = {t:.6g} s", start)
        self.non_finite = None
        return f

    def _non_finite(self, values: np.ndarray, message: str, start: bool) -> np.ndarray:
        """A non-finite evaluation: infinite values for a method that rejects the attempt
        (``rejects_non_finite``; the run ends as diverged with ``message`` if the attempts
        stay non-finite down to the smallest step), else, or at the accepted state a solver
        starts from (``start``), the run stops here as diverged."""
        if not self.rejects_non_finite or start:
            raise _Stop(STATUS_DIVERGED, message)
        self.non_finite = message
        return np.full_like(values, np.inf, dtype=float)

    def jac(self, t: float, y: np.ndarray) -> np.ndarray:
        """The system's Jacobian for implicit methods; a non-finite one stops the run as
        diverged (scipy's LU refused it with "array must not contain infs or NaNs")."""
        try:
            J = self.system.jacobian(t, np.ascontiguousarray(y))
        except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
            raise _Stop(*_failure(exc, t)) from exc
        if not np.all(np.isfinite(J)):
            raise _Stop(STATUS_DIVERGED, f"diverged: non-finite Jacobian at t = {t:.6g} s")
        return J

    def run(self, y: np.ndarray, edges: np.ndarray) -> tuple[float, Verdict | None]:
        """Integrate from edges[0]; returns the time reached and the ending (status, message)
        that stopped the run, None when it reached the last edge."""
        events = EventMonitor(self.system, float(edges[0]), y)
        t_now = float(edges[0])
        for a, b in zip(edges[:-1], edges[1:]):
            t_start = float(a)
            while t_start < b:
                y, t_now, t_start, ending = self._segment(y, t_start, float(b), events)
                if ending is not None:
                    return t_now, ending
        return t_now, None

    def _segment(
        self, y: np.ndarray, a: float, b: float, events: EventMonitor
    ) -> tuple[np.ndarray, float, float, Verdict | None]:
        """Step from a towards b; returns (state, time reached, where to restart, ending): b
        at the segment's end, the event time after a jump; the ending that stopped the run,
        else None."""
        s = self.settings
        self.at_start = True
        try:  # scipy evaluates fun (and may choose the first step) while it is set up
            solver = self.cls(
                self.fun, a, y, b, rtol=s.rtol, atol=s.atol, max_step=s.max_step, **self.extra
            )
        except Exception as exc:  # a _Stop, or e.g. a singular iteration matrix
            self.stats.nfev = self.nfev
            return y, a, b, _ending(exc, a)
        t_now, ending = a, None
        try:
            while ending is None and solver.status == "running":
                ending = self._step(solver)
                if ending is None:
                    t_now, jumped = self._accepted(solver, events)
                    if jumped is not None:
                        self._count(solver)
                        return jumped, t_now, t_now, None
        except Exception as exc:  # a _Stop, or e.g. a singular iteration matrix
            ending = _ending(exc, solver.t)
        self._count(solver)
        return solver.y.copy(), t_now, b, ending

    def _step(self, solver: Any) -> Verdict | None:
        """One step of ``solver``: the ending when it failed (diverged when its attempts
        stayed non-finite down to the smallest step) or when the divergence guard stops the
        run on the step it accepted, else None."""
        with np.errstate(invalid="ignore", over="ignore"):  # non-finite attempts
            msg = solver.step()
        self.stats.nsteps += 1
        if solver.status == "failed":
            if self.non_finite:
                return STATUS_DIVERGED, self.non_finite
            return STATUS_FAILED, f"{msg} (t = {solver.t:.6g} s)"
        return self.guard.check(solver.t_old, solver.t, solver.y)

    def _accepted(self, solver: Any, events: EventMonitor) -> tuple[float, np.ndarray | None]:
        """The step ``solver`` accepted, up to its first event if one crossed: the states at
        the output times in it, the audit's step, progress. Returns the time it reached and,
        after an event, the state after the system's jump (None without one)."""
        t0, t1 = solver.t_old, solver.t
        hit = (
            events.first_crossing(t0, t1, solver.y, solver.dense_output())
            if events.active
            else None
        )
        t_end = hit[1] if hit else t1
        pending = self.out.upto(t_end)
        if pending.size or self.ledger or hit:
            # each state of the (N, k) dense output one contiguous column (Fortran order):
            # the audit's states[:, i] go to compiled kernels, which take no strided array
            dense = _fortran(solver.dense_output())
            own = self.out.write(dense(pending).T) if pending.size else np.zeros(0, bool)
            if self.ledger:
                self.ledger.step(dense, t0, t_end, pending[own])
        report(t_end)
        if not hit:
            return t_end, None
        index, t_event = hit
        y_new, record, lost = apply_hit(self.system, index, t_event, solver.dense_output()(t_event))
        self.events.append(record)
        if self.out.windows is not None:
            self.out.windows.event(record)
        if self.ledger:  # an impact's kinetic energy loss is dissipated energy
            self.ledger.total = self.ledger.total + np.array([0.0, lost])
        events.reset(t_event, y_new)
        return t_event, y_new

    def _count(self, solver: Any) -> None:
        # plain ints: LSODA reports numpy int32 counters, which JSON cannot hold
        self.stats.nfev = self.nfev
        self.stats.njev += int(solver.njev)
        self.stats.nlu += int(solver.nlu)


def _fortran(dense: Callable[[Any], np.ndarray]) -> Callable[[Any], np.ndarray]:
    """A step's dense output with its (N, k) states in Fortran order."""
    return lambda ts: np.asfortranarray(dense(ts))


#: numpy's refusal of a non-finite matrix (``asarray_chkfinite``, scipy's LU): inside a step it
#: means the iteration matrix overflowed (Radau with phi = 1e200: a step size of 0).
_NON_FINITE_MATRIX = "array must not contain infs or NaNs"


def _ending(exc: Exception, t: float) -> Verdict:
    """The ending (status, message) of a scipy run stopped at time t (s) by ``exc``: a
    ``_Stop``'s own, or a numerical failure's, a non-finite matrix refused by scipy's linear
    algebra included; any other exception raised by scipy's solver propagates (the run's
    outer handler reports it)."""
    if isinstance(exc, _Stop):
        return exc.code, str(exc)
    if isinstance(exc, ValueError) and _NON_FINITE_MATRIX in str(exc):
        return STATUS_DIVERGED, f"diverged: non-finite iteration matrix at t = {t:.6g} s"
    verdict = numerical_failure(exc, t)
    if verdict is None:
        raise exc
    return verdict


def _failure(exc: Exception, t: float) -> tuple[int, str]:
    """(status, message) of an exception raised at time t (s) inside a run: a numerical
    failure (``rodval.core.status.numerical_failure``) or a model error."""
    return numerical_failure(exc, t) or (STATUS_ERROR, exception_line(exc))


def _finite_prefix(
    times: np.ndarray, observed: Observed, stats: SolverStats
) -> tuple[np.ndarray, Observed]:
    """The output times up to the first one where an observed value is not finite: a run
    never returns NaN; it is a divergence, where that ending wins (``update_status``: over a
    success, a budget or a plain failure; the time reached is then the last finite one)."""
    bad = [
        int(np.argmax(~np.isfinite(v).all(axis=1)))
        for v, _ in observed.values()
        if not np.isfinite(v).all()
    ]
    if not bad:
        return times, observed
    cut = min(bad)
    message = f"diverged: non-finite outputs at t = {times[cut]:.6g} s"
    update_status(stats, STATUS_DIVERGED, message, float(times[cut - 1]) if cut else 0.0)
    return times[:cut], {q: (v[:cut], k) for q, (v, k) in observed.items()}


def _bending_validity(
    system: OdeSystem, times: np.ndarray, Y: np.ndarray, observed: Observed, stats: SolverStats
) -> None:
    """``stats.max_bending`` and ``stats.small_bending`` from the observed alpha, beta, or
    from the system when the scene did not ask for them."""
    if "alpha" in observed and "beta" in observed:
        values = [observed["alpha"][0], observed["beta"][0]]
        largest = max((float(np.max(np.abs(v))) for v in values if v.size), default=None)
    else:
        try:
            largest = system.max_bending(times, Y) if times.size else None
        except Exception:  # noqa: BLE001 - a measure of validity must not fail the run
            largest = None
    if largest is not None:
        stats.max_bending = largest
        stats.small_bending = bool(largest <= SMALL_BENDING_RAD)


def _momentum_audit(system: OdeSystem, Y: np.ndarray, stats: SolverStats) -> None:
    """``stats.momentum_residual`` from the states ``Y`` on the audit grid reached
    (``outputs.AuditGrid``: the same whatever the output times)."""
    if not len(Y):
        return
    try:
        stats.momentum_residual = momentum_residual(*system.momentum_audit_rows(Y))
    except Exception:  # noqa: BLE001 - a measure of validity must not fail the run
        stats.momentum_residual = None


def _observe(
    system: OdeSystem, out: Outputs, ledger: PowerLedger | None, stats: SolverStats
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """The output times the run reached, their states and the observed quantities (the
    energy audit's at the output times with a ``ledger``, and its residual into ``stats``,
    ``audit.energy_residual``, read on the audit grid, the same whatever the output times:
    E as ``observe`` reports it, ``OdeSystem.energy_history``, O(n) per grid time); a failed
    observation sets the run's status and message and observes nothing."""
    rows, on_grid = out.scene_rows(), out.audit_rows()
    reached, Y = out.times[rows], out.Y[rows]
    try:
        observed = system.observe(reached, Y) if rows.size else {}
        if ledger and rows.size:
            W, D = ledger.series()
            E0 = system.energy(0.0, system.y0)
            observed.update(audit_quantities(observed["energy"][0][:, 0], E0, W[rows], D[rows]))
            E = np.asarray(system.energy_history(out.times[on_grid], out.Y[on_grid]), float)
            stats.energy_residual = energy_residual(E, E0, W[on_grid], D[on_grid])
    except Exception as exc:  # noqa: BLE001
        observed = {}
        status, message = _failure(exc, stats.t_reached)
        update_status(stats, status, f"observation failed: {message}")
    return reached, Y, observed


def _read_peaks(
    peaks: PeakGrid, system: OdeSystem, events: list[dict[str, Any]], stats: SolverStats
) -> None:
    """``stats.peaks`` from the peak grid's states up to the time reached (``PeakGrid.read``);
    a failed reading sets the run's status and message (a peak is never silently missing)."""
    try:
        stats.peaks = peaks.read(system, stats.t_reached, events)
    except Exception as exc:  # noqa: BLE001 - reported as the run's failure
        status, message = _failure(exc, stats.t_reached)
        update_status(stats, status, f"reading the peaks failed: {message}")


@dataclass
class _Plan:
    """What one run records, from what the scene asks and the system declares (``has_energy``,
    ``has_momentum``, its compiled form): the method and its compiled form (None on scipy),
    the recorded states (``out``: output times, audit grid, peak grid, lock windows), the
    energy ledger (None: no energy audit) and whether momentum is audited."""

    method: str
    form: CompiledForm | None
    out: Outputs
    ledger: PowerLedger | None
    momentum: bool

    @classmethod
    def of(cls, system: OdeSystem, scene: Scene, settings: IntegratorSettings) -> _Plan:
        audit = system.has_energy and scene.wants("energy")
        momentum = system.has_momentum and momentum_point(scene) is not None
        peaks = scene.wants(*PEAK_QUANTITIES)
        method, form = choose_method(system, settings, audit)
        out = Outputs(
            np.asarray(scene.times),
            system.y0.size,
            LockWindows(system),
            AuditGrid(scene.t_end) if audit or momentum else None,
            PeakGrid(scene.t_end, system.y0.size) if peaks else None,
        )
        return cls(method, form, out, PowerLedger(system.power) if audit else None, momentum)


def _run(
    system: OdeSystem, scene: Scene, settings: IntegratorSettings, plan: _Plan, stats: SolverStats
) -> list[dict[str, Any]]:
    """Integrate from y0 (its states at t = 0 recorded first) in the compiled loop or on scipy;
    returns its events. The ending and time reached go into ``stats``; never raises."""
    y = system.y0.astype(float).copy()
    out, ledger = plan.out, plan.ledger
    events: list[dict[str, Any]] = []
    t_now, ending = 0.0, None
    try:
        guard = DivergenceGuard(system, settings, scene.t_end, y)
        own = out.write(np.repeat(y[None, :], out.upto(0.0).size, axis=0))
        if ledger:  # one record per recorded time at t = 0 (not per probe there)
            for _ in range(int(np.count_nonzero(own))):
                ledger.record()
        if plan.form is not None:
            from rodval.solvers.compiled import run_compiled  # loads the compiled loop once

            edges = segment_edges(scene)
            run_compiled(system, y, edges, settings, guard.spec, out, stats, ledger, events)
            t_now = stats.t_reached
        else:
            scipy_run = _ScipyRun(system, settings, plan, stats, guard)
            t_now, ending = scipy_run.run(y, segment_edges(scene))
            events = scipy_run.events
    except Exception as exc:  # noqa: BLE001 - e.g. the model's energy at y0: a run never raises
        ending = _failure(exc, t_now)
    if ending is not None:
        update_status(stats, *ending)
    stats.t_reached = float(t_now)
    return events


def integrate(
    system: OdeSystem,
    scene: Scene,
    settings: IntegratorSettings,
    *,
    model: str,
    options: dict[str, Any] | None = None,
) -> Trajectory:
    """Integrate ``system`` over [0, scene.t_end] and observe it at ``scene.times``.

    Never raises for a failed run: status, message and time reached are in ``stats``; a bad
    request (a compiled method for a system without compiled form) is a ValueError.
    """
    system.reset()
    plan = _Plan.of(system, scene, settings)
    stats = SolverStats()
    start = time.perf_counter()
    events = _run(system, scene, settings, plan, stats)
    out = plan.out
    if out.windows is not None:
        out.windows.close()
    reached, Y, observed = _observe(system, out, plan.ledger, stats)
    reached, observed = _finite_prefix(reached, observed, stats)
    _bending_validity(system, reached, Y[: reached.size], observed, stats)
    if plan.momentum:
        _momentum_audit(system, out.Y[out.audit_rows()], stats)
    if out.peaks is not None and observed:
        _read_peaks(out.peaks, system, events, stats)
    stats.wall_s = time.perf_counter() - start
    return finish(
        stats,
        model=model,
        scene_name=scene.name,
        times=reached,
        observed=observed,
        # the method that ran, and the one asked for (a rerun asks for it again)
        settings={**settings.as_dict(), "method": plan.method, "requested_method": settings.method},
        options=options,
        events=events,
    )
