"""State events on the scipy path: detect a crossing over an accepted step, locate it on the
step's dense output, and hand it to the system (which returns the state after its jump).

A crossing of event i over the step [t0, t1] is a sign change of g_i between the step's ends
in the event's direction, starting from a non-zero value (a system that has just jumped onto
g_i = 0 does not fire again at once). When several events cross in one step, the earliest
located one is taken; the step is cut there and the integrator restarts after the jump.
Location: Brent's method on g_i(t, dense(t)), to ``time_tolerance(t)``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import brentq

from rodval.solvers.system import EventSpec, OdeSystem

Dense = Callable[[float], np.ndarray]


def time_tolerance(t: float) -> float:
    """Absolute tolerance (s) of a located event time: 4 ulp-scale of t, at least 1e-13 s."""
    return max(1e-13, 8.0 * np.finfo(float).eps * abs(t))


def _crosses(g0: float, g1: float, direction: int) -> bool:
    if g0 == 0.0 or not np.isfinite(g0) or not np.isfinite(g1):
        return False
    if direction > 0:
        return g0 < 0.0 <= g1
    if direction < 0:
        return g0 > 0.0 >= g1
    return (g0 < 0.0 <= g1) or (g0 > 0.0 >= g1)


class EventMonitor:
    """The current mode's events of ``system`` and their values at the last step end."""

    def __init__(self, system: OdeSystem, t: float, y: np.ndarray):
        self.system = system
        self.reset(t, y)

    def reset(self, t: float, y: np.ndarray) -> None:
        """Re-read the system's events (after a jump its mode may have changed)."""
        self.specs: tuple[EventSpec, ...] = tuple(self.system.event_functions())
        self.values = [float(e.g(t, y)) for e in self.specs]

    @property
    def active(self) -> bool:
        return bool(self.specs)

    def first_crossing(
        self, t0: float, t1: float, y1: np.ndarray, dense: Dense
    ) -> tuple[int, float] | None:
        """(event index, located time) of the earliest crossing in (t0, t1], or None; updates
        the stored values to the step end when there is none."""
        new = [float(e.g(t1, y1)) for e in self.specs]
        found: tuple[int, float] | None = None
        for i, (e, g0, g1) in enumerate(zip(self.specs, self.values, new)):
            if not _crosses(g0, g1, e.direction):
                continue
            if g1 == 0.0:
                t_root = t1
            else:
                t_root = brentq(
                    lambda s, g=e.g: g(s, dense(s)),
                    t0,
                    t1,
                    xtol=time_tolerance(t1),
                    rtol=4 * np.finfo(float).eps,
                )
            if found is None or t_root < found[1]:
                found = (i, t_root)
        if found is None:
            self.values = new
        return found
