"""ODE driver: steps a scipy OdeSolver across the scene's load breakpoints.

Dense output is formed only on steps that contain output times, or on every step when the
scene asks for "energy" (the energy audit integrates the load and damper powers on it, see
``rodval.energy``). A failure (integrator gives up, model raises, non-finite state, energy
blow-up, step size collapse; see ``rodval.divergence``) ends the run early with a status, a
message and the time reached; the output times reached so far are kept.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, Radau

from .integrators import compiled_form, run_compiled
from .divergence import DivergenceGuard
from .energy import PowerLedger, audit_quantities
from .models.base import OdeSystem
from .scene import Scene
from .settings import IntegratorSettings
from .trajectory import STATUS_ERROR, STATUS_FAILED, SolverStats, Trajectory

_SOLVERS = {"RK23": RK23, "RK45": RK45, "DOP853": DOP853, "Radau": Radau, "BDF": BDF,
            "LSODA": LSODA}


class _ModelError(Exception):
    pass


def _segments(scene: Scene) -> list[tuple[float, float]]:
    edges = np.concatenate([[0.0], scene.breakpoints, [scene.t_end]])
    return list(zip(edges[:-1], edges[1:]))


def _add_counts(stats: SolverStats, solver) -> None:
    # plain ints: LSODA reports numpy int32 counters, which JSON case files cannot hold
    stats.nfev += int(solver.nfev)
    stats.njev += int(solver.njev)
    stats.nlu += int(solver.nlu)


def integrate(system: OdeSystem, scene: Scene, settings: IntegratorSettings, *,
              model: str, options: dict | None = None) -> Trajectory:
    """Integrate ``system`` over [0, scene.t_end] and observe it at ``scene.times``."""
    times = np.asarray(scene.times)
    Y = np.empty((times.size, system.y0.size))
    n_out = 0
    stats = SolverStats()
    y = system.y0.astype(float).copy()
    form = compiled_form(system, settings.method) if settings.compiled else None
    solver_cls = _SOLVERS.get(settings.method)
    extra = {}
    if settings.implicit and system.jac is not None:
        extra["jac"] = system.jac
    if settings.first_step is not None:
        extra["first_step"] = settings.first_step

    def fun(t, yy):
        try:
            return system.rhs(t, yy)
        except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
            raise _ModelError(f"{type(exc).__name__}: {exc}") from exc

    audit = scene.wants("energy") and system.power is not None and system.energy is not None
    if audit and form is not None:
        raise ValueError(f"method {settings.method!r} runs in one compiled loop and cannot "
                         "audit energy; use a scipy method (e.g. DOP853) for 'energy' outputs")
    ledger = PowerLedger(system.power) if audit else None
    start = time.perf_counter()
    while n_out < times.size and times[n_out] == 0.0:
        Y[n_out] = y
        n_out += 1
        if ledger:
            ledger.record()
    t_now = 0.0
    solver = None
    try:
        guard = DivergenceGuard(system, settings, scene.t_end, y)
        if form is not None:   # the whole run in one compiled loop (rodval.integrators)
            n_out = run_compiled(form, y, scene, settings, Y, stats)
            t_now = stats.t_reached
        for a, b in (_segments(scene) if form is None else ()):
            solver = solver_cls(fun, a, y, b, rtol=settings.rtol, atol=settings.atol,
                                max_step=settings.max_step, **extra)
            while solver.status == "running":
                msg = solver.step()
                stats.nsteps += 1
                if solver.status == "failed":
                    stats.status, stats.message = STATUS_FAILED, str(msg)
                    break
                verdict = guard.check(solver.t_old, solver.t, solver.y)
                if verdict:
                    stats.status, stats.message = verdict
                    break
                t_now = solver.t
                n_step = int(np.searchsorted(times, solver.t, side="right")) - n_out
                if n_step or ledger:
                    dense = solver.dense_output()
                    Y[n_out:n_out + n_step] = dense(times[n_out:n_out + n_step]).T
                    if ledger:
                        ledger.step(dense, solver.t_old, solver.t, times[n_out:n_out + n_step])
                    n_out += n_step
            if stats.status != 0:
                break
            y = solver.y.copy()
            _add_counts(stats, solver)
            solver = None
    except _ModelError as exc:
        stats.status, stats.message = STATUS_ERROR, str(exc)
    except Exception as exc:  # noqa: BLE001 - e.g. the model's energy at y0: a run never raises
        stats.status, stats.message = STATUS_ERROR, f"{type(exc).__name__}: {exc}"
    if solver is not None:
        _add_counts(stats, solver)
    stats.t_reached = float(t_now)
    if stats.status == 0:
        stats.message = "reached t_end"
    reached = times[:n_out]
    try:
        observed = system.observe(reached, Y[:n_out]) if n_out else {}
        if ledger and n_out:
            audited, stats.energy_residual = audit_quantities(
                observed["energy"][0][:, 0], system.energy(0.0, system.y0), ledger)
            observed.update(audited)
    except Exception as exc:  # noqa: BLE001
        observed = {}
        stats.status, stats.message = STATUS_ERROR, f"observation failed: {type(exc).__name__}: {exc}"
    stats.wall_s = time.perf_counter() - start
    return Trajectory(model=model, scene_name=scene.name, times=reached,
                      values={q: v for q, (v, _) in observed.items()},
                      k_index={q: k for q, (_, k) in observed.items()},
                      stats=stats, settings={**settings.as_dict(), **(options or {})})
