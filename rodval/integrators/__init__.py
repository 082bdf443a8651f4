"""rodval's own integrators: whole runs in one compiled loop (see ``settings.COMPILED_METHODS``).

``run_compiled`` is called by ``rodval.integrate.integrate`` for those methods.
"""
from __future__ import annotations

import numpy as np

from ..scene import Scene
from ..settings import IntegratorSettings
from ..trajectory import STATUS_DIVERGED, STATUS_ERROR, STATUS_FAILED, SolverStats
from . import dop853

_CODES = {dop853.STEP_TOO_SMALL: (STATUS_FAILED, "Required step size is less than spacing between numbers."),
          dop853.NON_FINITE: (STATUS_DIVERGED, "non-finite state")}


def compiled_form(system, method: str) -> tuple:
    """The system's compiled form, or ValueError (before any work) when it has none."""
    form = system.compiled() if hasattr(system, "compiled") else None
    if form is None:
        raise ValueError(f"method {method!r} needs a native model (full, reduced) with "
                         "kernel='numba' and pulse/constant loads; use a scipy method otherwise")
    _warm_up(form, system.y0)
    return form


_warm = False


def _warm_up(form: tuple, y0: np.ndarray) -> None:
    """One tiny step, once per process, so that loading (or compiling) the integrator is not
    part of a run's wall time (all systems share one compiled signature)."""
    global _warm
    if not _warm:
        kind, V, Mt, table, damped = form
        dop853.integrate_compiled(kind, V, Mt, table, damped, y0, np.array([0.0, 1e-9]),
                                  np.zeros(0), 1e-6, 1e-9, np.inf, 1e-9, np.empty((0, y0.size)))
        _warm = True


def run_compiled(form: tuple, y0: np.ndarray, scene: Scene, settings: IntegratorSettings,
                 Y: np.ndarray, stats: SolverStats) -> int:
    """Integrate over [0, t_end] across the scene's breakpoints, writing states at the output
    times into Y; fills ``stats`` (status, message, t_reached, nfev, nsteps) and returns the
    number of output times reached."""
    kind, V, Mt, table, damped = form
    edges = np.concatenate([[0.0], scene.breakpoints, [scene.t_end]])
    try:
        n_out, nfev, nsteps, code, t = dop853.integrate_compiled(
            kind, V, Mt, table, damped, y0, edges, np.array(scene.times, float), settings.rtol,
            settings.atol, settings.max_step, settings.first_step, Y)
    except Exception as exc:  # noqa: BLE001 - e.g. a singular mass matrix: reported as data
        stats.status, stats.message = STATUS_ERROR, f"{type(exc).__name__}: {exc}"
        return 0
    stats.nfev, stats.nsteps, stats.t_reached = nfev, nsteps, t
    if code != dop853.OK:
        stats.status, message = _CODES[code]
        stats.message = f"{message} (t = {t:.6g} s)"
    return n_out
