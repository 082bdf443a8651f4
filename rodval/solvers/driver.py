"""ODE driver: integrates an ``OdeSystem`` over [0, t_end] and observes it at the output times.

Small parts, each in its own place:

* method choice (``choose_method``): "auto" takes the compiled DOP853 when the system has a
  compiled form that can do what is asked (its mechanics for an energy audit, its event
  functions for a system with events), scipy's DOP853 otherwise; the compiled loop of "auto"
  switches to its Radau IIA when the steps are limited by stability (``settings.AUTO``);
* stepping: a scipy ``OdeSolver`` across the scene's load breakpoints (``_ScipyRun``), or a
  compiled loop (``rodval.solvers.compiled``);
* budgets and non-finite derivatives, checked on every evaluation, including those of rejected
  step attempts (so a NaN step size never loops): an explicit Runge-Kutta method rejects a
  non-finite attempt and cuts its step (a stiff transient), and the run ends as diverged when
  the attempts stay non-finite down to the smallest step; the other methods stop at once;
* events (``rodval.solvers.events``): crossing located, state jump applied, step restarted;
* divergence guard (``rodval.solvers.guard``) after every accepted step;
* energy audit (``rodval.solvers.audit``) on the dense output of every accepted step, its
  residual read on the audit grid (``audit.audit_times``), as the momentum audit's;
* observation at the output times reached; the run's peaks (``SolverStats.peaks``) on the
  peak grid and the lock windows' probes of the dense output (``outputs.PeakGrid``), not on
  the output times.

Dense output is formed only on steps that contain output times, events, or when the scene asks
for "energy". A failure ends the run early with a status, a message and the time reached; the
output times reached so far are kept.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, Radau

from rodval.core.quantities import PEAK_QUANTITIES
from rodval.core.scene import Scene
from rodval.core.settings import AUTO, COMPILED_METHODS, IntegratorSettings
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
from rodval.solvers.guard import DivergenceGuard
from rodval.solvers.limits import MAX_IMPLICIT_SIZE
from rodval.solvers.outputs import AuditGrid, LockWindows, Outputs, PeakGrid
from rodval.solvers.progress import report
from rodval.solvers.system import OdeSystem

_SOLVERS = {
    "RK23": RK23,
    "RK45": RK45,
    "DOP853": DOP853,
    "Radau": Radau,
    "BDF": BDF,
    "LSODA": LSODA,
}


#: scipy methods that reject a step attempt whose error norm is not finite and cut the step.
_REJECTS_NON_FINITE = ("RK23", "RK45", "DOP853")


def _contiguous_states(dense: Callable[[Any], np.ndarray]) -> Callable[[Any], np.ndarray]:
    """A step's dense output whose states are contiguous arrays: scipy's (N, k) array of
    states at k times made Fortran-ordered, so each state ``states[:, i]`` (the energy
    audit's, ``rodval.solvers.audit.step_integral``) is one contiguous column. A system's
    compiled kernels take contiguous states only (numba's reshape of a strided one is a
    TypingError)."""
    return lambda ts: np.asfortranarray(dense(ts))


class _Stop(Exception):
    """Ends a scipy run from inside the right-hand side: ``code`` (a status), message."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code


def choose_method(system: OdeSystem, scene: Scene, settings: IntegratorSettings) -> str:
    """The method that will run. ValueError (before any work) when a compiled method is asked
    for what it cannot do."""
    audit = scene.wants("energy") and system.has_energy
    events = bool(system.event_functions())
    form = system.compiled()
    if settings.method == AUTO:
        if (
            form is not None
            and (form.mechanics is not None or not audit)
            and (form.events is not None or not events)
        ):
            return "DOP853-numba"
        return "DOP853"
    if settings.compiled:
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
    return settings.method


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
        scene: Scene,
        settings: IntegratorSettings,
        method: str,
        stats: SolverStats,
        out: Outputs,
        ledger: PowerLedger | None,
        guard: DivergenceGuard,
    ):
        self.system, self.scene, self.settings = system, scene, settings
        self.cls = _SOLVERS[method]
        self.stats, self.out, self.ledger, self.guard = stats, out, ledger, guard
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

    def run(self, y: np.ndarray, edges: np.ndarray) -> float:
        """Integrate from edges[0]; returns the time reached."""
        events = EventMonitor(self.system, float(edges[0]), y)
        t_now = float(edges[0])
        for a, b in zip(edges[:-1], edges[1:]):
            t_start = float(a)
            while t_start < b:
                y, t_now, t_start = self._segment(y, t_start, float(b), events)
                if self.stats.status != 0:
                    return t_now
        return t_now

    def _segment(
        self, y: np.ndarray, a: float, b: float, events: EventMonitor
    ) -> tuple[np.ndarray, float, float]:
        """Step from a towards b; returns (state, time reached, where to restart): b at the
        segment's end, the event time after a jump."""
        s = self.settings
        self.at_start = True
        try:  # scipy evaluates fun (and may choose the first step) while it is set up
            solver = self.cls(
                self.fun, a, y, b, rtol=s.rtol, atol=s.atol, max_step=s.max_step, **self.extra
            )
        except _Stop as stop:
            update_status(self.stats, stop.code, str(stop))
            self.stats.nfev = self.nfev
            return y, a, b
        except Exception as exc:  # e.g. a singular iteration matrix while scipy sets up
            update_status(self.stats, *_numerical_or_raise(exc, a))
            self.stats.nfev = self.nfev
            return y, a, b
        t_now = a
        try:
            while solver.status == "running":
                with np.errstate(invalid="ignore", over="ignore"):  # non-finite attempts
                    msg = solver.step()
                self.stats.nsteps += 1
                if solver.status == "failed":
                    if self.non_finite:  # non-finite at every step size: diverged
                        update_status(self.stats, STATUS_DIVERGED, self.non_finite)
                    else:
                        update_status(self.stats, STATUS_FAILED, f"{msg} (t = {solver.t:.6g} s)")
                    break
                verdict = self.guard.check(solver.t_old, solver.t, solver.y)
                if verdict:
                    update_status(self.stats, *verdict)
                    break
                t0, t1 = solver.t_old, solver.t
                hit = (
                    events.first_crossing(t0, t1, solver.y, solver.dense_output())
                    if events.active
                    else None
                )
                t_end = hit[1] if hit else t1
                pending = self.out.upto(t_end)
                if pending.size or self.ledger or hit:
                    dense = _contiguous_states(solver.dense_output())
                    own = self.out.write(dense(pending).T) if pending.size else np.zeros(0, bool)
                    if self.ledger:
                        self.ledger.step(dense, t0, t_end, pending[own])
                t_now = t_end
                report(t_now)
                if hit:
                    index, t_event = hit
                    y_event = solver.dense_output()(t_event)
                    y_new, record, lost = apply_hit(self.system, index, t_event, y_event)
                    self.events.append(record)
                    if self.out.windows is not None:
                        self.out.windows.event(record)
                    if self.ledger:  # an impact's kinetic energy loss is dissipated energy
                        self.ledger.total = self.ledger.total + np.array([0.0, lost])
                    events.reset(t_event, y_new)
                    self._count(solver)
                    return y_new, t_event, t_event
        except _Stop as stop:
            update_status(self.stats, stop.code, str(stop))
        except Exception as exc:  # e.g. a singular iteration matrix inside scipy's step
            update_status(self.stats, *_numerical_or_raise(exc, solver.t))
        self._count(solver)
        return solver.y.copy(), t_now, b

    def _count(self, solver) -> None:
        # plain ints: LSODA reports numpy int32 counters, which JSON cannot hold
        self.stats.nfev = self.nfev
        self.stats.njev += int(solver.njev)
        self.stats.nlu += int(solver.nlu)


def _failure(exc: Exception, t: float) -> tuple[int, str]:
    """(status, message) of an exception raised at time t (s) inside a run: a numerical
    failure (``rodval.core.status.numerical_failure``) or a model error."""
    return numerical_failure(exc, t) or (STATUS_ERROR, exception_line(exc))


#: numpy's refusal of a non-finite matrix (``asarray_chkfinite``, scipy's LU): inside a step it
#: means the iteration matrix overflowed (Radau with phi = 1e200: a step size of 0).
_NON_FINITE_MATRIX = "array must not contain infs or NaNs"


def _numerical_or_raise(exc: Exception, t: float) -> tuple[int, str]:
    """A numerical failure's (status, message) at time t (s), a non-finite matrix refused by
    scipy's linear algebra included; any other exception raised by scipy's solver propagates
    (the run's outer handler reports it)."""
    if isinstance(exc, ValueError) and _NON_FINITE_MATRIX in str(exc):
        return STATUS_DIVERGED, f"diverged: non-finite iteration matrix at t = {t:.6g} s"
    verdict = numerical_failure(exc, t)
    if verdict is None:
        raise exc
    return verdict


def _finite_prefix(times: np.ndarray, observed: dict, stats: SolverStats):
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
    system: OdeSystem, times: np.ndarray, Y: np.ndarray, observed: dict, stats: SolverStats
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


def _audits_momentum(system: OdeSystem, scene: Scene) -> bool:
    """Whether a run audits angular momentum: the scene conserves it (``momentum_point``)
    and the system measures it (``momentum_audit_rows``)."""
    return momentum_point(scene) is not None and hasattr(system, "momentum_audit_rows")


def _momentum_audit(system: OdeSystem, Y: np.ndarray, stats: SolverStats) -> None:
    """``stats.momentum_residual`` from the states ``Y`` on the audit grid reached
    (``outputs.AuditGrid``: the same whatever the output times)."""
    rows = getattr(system, "momentum_audit_rows", None)  # the systems that measure it
    if rows is None or not len(Y):
        return
    try:
        stats.momentum_residual = momentum_residual(*rows(Y))
    except Exception:  # noqa: BLE001 - a measure of validity must not fail the run
        stats.momentum_residual = None


def _energy_audit(
    system: OdeSystem, times: np.ndarray, Y: np.ndarray, W: np.ndarray, D: np.ndarray
) -> float:
    """The scalar energy residual (``audit.energy_residual``) on the audit grid reached:
    E, the energy ``observe`` reports (in the mode in effect at each time), at its ``times``
    (s) and states ``Y`` (``energy_history`` where the system has it: one pass per mode;
    else ``energy`` per state), W, D (J) the ledger's there; the same whatever the output
    times. O(n) per grid time, after the run."""
    history = getattr(system, "energy_history", None)  # the paper systems' batched form
    if history is not None:
        E = np.asarray(history(times, Y), float)
    else:
        E = np.array([system.energy(float(t), y) for t, y in zip(times, Y)])
    return energy_residual(E, system.energy(0.0, system.y0), W, D)


def _observe(
    system: OdeSystem, out: Outputs, ledger: PowerLedger | None, stats: SolverStats
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """The output times the run reached, their states and the observed quantities (the
    energy audit's at the output times with a ``ledger``, and its residual into ``stats``,
    read on the audit grid); a failed observation sets the run's status and message and
    observes nothing."""
    rows, on_grid = out.scene_rows(), out.audit_rows()
    reached, Y = out.times[rows], out.Y[rows]
    try:
        observed = system.observe(reached, Y) if rows.size else {}
        if ledger and rows.size:
            W, D = ledger.series()
            observed.update(
                audit_quantities(
                    observed["energy"][0][:, 0], system.energy(0.0, system.y0), W[rows], D[rows]
                )
            )
            stats.energy_residual = _energy_audit(
                system, out.times[on_grid], out.Y[on_grid], W[on_grid], D[on_grid]
            )
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


def integrate(
    system: OdeSystem,
    scene: Scene,
    settings: IntegratorSettings,
    *,
    model: str,
    options: dict | None = None,
) -> Trajectory:
    """Integrate ``system`` over [0, scene.t_end] and observe it at ``scene.times``.

    Never raises for a failed run: status, message and time reached are in ``stats``; a bad
    request (a compiled method for a system without compiled form) is a ValueError.
    """
    system.reset()
    method = choose_method(system, scene, settings)
    # the method that ran, and the one asked for (a rerun asks for it again)
    ran = {**settings.as_dict(), "method": method, "requested_method": settings.method}
    form = system.compiled() if method in COMPILED_METHODS else None
    if form is not None:
        from rodval.solvers.compiled import run_compiled  # loads the compiled loop once
    times = np.asarray(scene.times)
    windows = LockWindows(system)
    audit = scene.wants("energy") and system.has_energy
    momentum = _audits_momentum(system, scene)
    # the audits' fixed grid, recorded beside the output times
    grid = AuditGrid(scene.t_end) if audit or momentum else None
    # the peaks' grid of the dense output, when the scene outputs a peak quantity
    peaks = PeakGrid(scene.t_end, system.y0.size) if scene.wants(*PEAK_QUANTITIES) else None
    out = Outputs(times, system.y0.size, windows, grid, peaks)
    stats = SolverStats()
    y = system.y0.astype(float).copy()
    ledger = PowerLedger(system.power) if audit else None
    start = time.perf_counter()
    t_now = 0.0
    events: list[dict[str, Any]] = []
    edges = segment_edges(scene)
    try:
        guard = DivergenceGuard(system, settings, scene.t_end, y)
        at_zero = out.upto(0.0)
        own = out.write(np.repeat(y[None, :], at_zero.size, axis=0))
        if ledger:  # one record per recorded time at t = 0 (not per probe there)
            for _ in range(int(np.count_nonzero(own))):
                ledger.record()
        if form is not None:
            run_compiled(system, y, edges, scene, settings, guard.spec, out, stats, ledger, events)
            t_now = stats.t_reached
        else:
            scipy_run = _ScipyRun(system, scene, settings, method, stats, out, ledger, guard)
            t_now = scipy_run.run(y, edges)
            events = scipy_run.events
    except Exception as exc:  # noqa: BLE001 - e.g. the model's energy at y0: a run never raises
        update_status(stats, *_failure(exc, t_now))
    stats.t_reached = float(t_now)
    windows.close()
    reached, Y, observed = _observe(system, out, ledger, stats)
    reached, observed = _finite_prefix(reached, observed, stats)
    _bending_validity(system, reached, Y[: reached.size], observed, stats)
    if momentum:
        _momentum_audit(system, out.Y[out.audit_rows()], stats)
    if peaks is not None and observed:
        _read_peaks(peaks, system, events, stats)
    stats.wall_s = time.perf_counter() - start
    return finish(
        stats,
        model=model,
        scene_name=scene.name,
        times=reached,
        observed=observed,
        settings=ran,
        options=options,
        events=events,
    )
