"""State events: detect a crossing over an accepted step, locate it on the step's dense
output, and hand it to the system (which returns the state after its jump). The scipy path's
loop is here (``EventMonitor``); the compiled DOP853 loop does the same inside its loop
(``rodval.solvers.dop853._locate``) with the same crossing rule and time tolerance, and both
hand a located event to the system through ``apply_hit``.

A crossing of event i over the step [t0, t1] is a sign change of g_i between the step's ends
in the event's direction, starting from a non-zero value (a system that has just jumped onto
g_i = 0 does not fire again at once). When several events cross in one step, the earliest
located one is taken; the step is cut there and the integrator restarts after the jump.
Location: Brent's method on g_i(t, dense(t)), to ``time_tolerance(t1)``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit
from scipy.optimize import brentq

from rodval.solvers.system import EventSpec, OdeSystem

Dense = Callable[[float], np.ndarray]

_EPS = float(np.finfo(float).eps)
#: Relative tolerance of a located event time (scipy's brentq ``rtol``).
ROOT_RTOL = 4 * _EPS


@njit(cache=True)
def time_tolerance(t: float) -> float:
    """Absolute tolerance (s) of a located event time: 8 eps |t|, at least 1e-13 s."""
    return max(1e-13, 8.0 * _EPS * abs(t))


@njit(cache=True)
def crosses(g0: float, g1: float, direction: float) -> bool:
    """Whether g goes from g0 (step start) to g1 (step end) across zero in ``direction``
    (+1 rising, -1 falling, 0 both), starting from a non-zero value."""
    if g0 == 0.0 or not np.isfinite(g0) or not np.isfinite(g1):
        return False
    if direction > 0:
        return g0 < 0.0 <= g1
    if direction < 0:
        return g0 > 0.0 >= g1
    return (g0 < 0.0 <= g1) or (g0 > 0.0 >= g1)


def impact_loss(data: dict[str, Any]) -> float:
    """Energy (J) an event took out at once (its record's ``instant_energy_loss``, E = T + Pi
    before minus after; negative: added): dissipated energy of the energy audit; 0 for an
    event without one."""
    return float(data.get("instant_energy_loss", 0.0))


def apply_hit(
    system: OdeSystem, index: int, t: float, y: np.ndarray
) -> tuple[np.ndarray, dict[str, Any], float]:
    """Event ``index`` of ``system`` located at t (s) in state y: the state after its jump,
    its record (a plain dict) and the kinetic energy it dissipated (J); the system switches
    its mode."""
    y_new, record = system.apply_event(index, t, y)
    return y_new, record.as_dict(), impact_loss(record.data)


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
            if not crosses(g0, g1, float(e.direction)):
                continue
            if g1 == 0.0:
                t_root = t1
            else:
                t_root = brentq(
                    lambda s, g=e.g: g(s, dense(s)),
                    t0,
                    t1,
                    xtol=time_tolerance(t1),
                    rtol=ROOT_RTOL,
                )
            if found is None or t_root < found[1]:
                found = (i, t_root)
        if found is None:
            self.values = new
        return found
