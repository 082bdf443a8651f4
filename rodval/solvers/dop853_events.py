"""Events on the compiled DOP853 loop's dense output (``rodval.solvers.dop853``): the 7th-order
interpolant, the crossing test and the location of a crossing by Brent's method, with the
scipy path's rule and tolerances (``rodval.solvers.events``: ``crosses``, ``time_tolerance``,
``ROOT_RTOL``; scipy's brentq ``maxiter``), so both paths find the same events.

The interpolant's coefficients F are those of ``dop853._dense_coefficients``.
"""

from __future__ import annotations

from numba import njit

from rodval.solvers.events import ROOT_RTOL, crosses, time_tolerance
from rodval.solvers.signature import EVENTS_SIGNATURE, Arr, Form, events_at

#: A step's dense output as the event location reads it: (F: the interpolant's
#: coefficients, y: the state at the step's start, t: its start (s), h: its length (s)).
Dense = tuple[Arr, Arr, float, float]

#: Iterations of the event location (scipy's brentq ``maxiter``).
ROOT_MAXITER = 100


@njit(cache=True, inline="always", error_model="numpy")
def interpolate(F: Arr, y: Arr, x: float, out: Arr) -> None:
    """The state at the fraction x of the step (the interpolant with coefficients F) into
    out. O(N)."""
    for q in range(y.shape[0]):
        acc = 0.0
        for i in range(7):
            acc += F[6 - i, q]
            acc *= x if i % 2 == 0 else 1.0 - x
        out[q] = acc + y[q]


@njit(cache=True, inline="always", error_model="numpy")
def _event_value(form: Form, dense: Dense, s: float, i: int, tmp: Arr, g: Arr) -> float:
    """g_i at time s (s) of the step [t, t + h], on its ``dense`` output. One ``events``
    call."""
    F, y, t, h = dense
    interpolate(F, y, (s - t) / h, tmp)
    events_at(form, s, tmp, g)
    return float(g[i])


@njit(cache=True, error_model="numpy")
def brent(
    form: Form,
    dense: Dense,
    i: int,
    a: float,
    b: float,
    fa: float,
    fb: float,
    scratch: tuple[Arr, Arr],
) -> float:
    """The root of g_i in [a, b] (fa, fb: its values there, of opposite signs) on the step's
    ``dense`` output (t, h: its start and length): scipy's brentq (Brent 1973, as in scipy's
    ``brentq.c``) to ``xtol = time_tolerance(t + h)`` and ``rtol = ROOT_RTOL``, the scipy
    path's tolerances. ``scratch``: (tmp (N,), g (events,))."""
    tmp, g = scratch
    xtol = time_tolerance(dense[2] + dense[3])
    xpre, xcur, fpre, fcur = a, b, fa, fb
    xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    for _ in range(ROOT_MAXITER):
        if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = 0.5 * (xtol + ROOT_RTOL * abs(xcur))
        sbis = 0.5 * (xblk - xcur)
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)  # secant
            else:  # inverse quadratic interpolation
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre, scur = scur, stry
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0.0 else -delta)
        fcur = _event_value(form, dense, xcur, i, tmp, g)
    return xcur


@njit(cache=True, error_model="numpy")
def locate(
    form: Form,
    F: Arr,
    y: Arr,
    t: float,
    t_new: float,
    values: tuple[Arr, Arr],
    scratch: tuple[Arr, Arr],
) -> tuple[int, float]:
    """(index, time) of the earliest event crossing in (t, t_new] (-1, t_new: none), each
    crossing located by ``brent`` on the dense output (F, y) (``rodval.solvers.events``: the
    scipy path's rule); ``values``: the events' (g_old, g_new) at t and t_new, against the
    form's directions; ``scratch``: as ``brent``'s. O(iterations x events) event
    evaluations, on steps with a crossing only."""
    g_old, g_new = values
    tmp, g = scratch
    directions = form[5]
    dense = (F, y, t, t_new - t)
    best, t_best = -1, t_new
    for i in range(g_old.shape[0]):
        if not crosses(g_old[i], g_new[i], directions[i]):
            continue
        if g_new[i] == 0.0:
            t_root = t_new
        else:
            fa = _event_value(form, dense, t, i, tmp, g)
            fb = _event_value(form, dense, t_new, i, tmp, g)
            if (fa < 0.0) == (fb < 0.0) and fa != 0.0 and fb != 0.0:
                t_root = t_new  # the interpolant's ends round to one side: the step's end
            else:
                t_root = brent(form, dense, i, t, t_new, fa, fb, scratch)
        if best < 0 or t_root < t_best:
            best, t_best = i, t_root
    return best, t_best


@njit(cache=True, error_model="numpy")
def any_crossing(g_old: Arr, g_new: Arr, directions: Arr) -> bool:
    """Whether any event crosses between the values g_old and g_new (``crosses``). O(events)."""
    for i in range(g_old.shape[0]):
        if crosses(g_old[i], g_new[i], directions[i]):
            return True
    return False


@njit(EVENTS_SIGNATURE, cache=True)
def no_events(t: float, y: Arr, P: Arr, S: Arr, M: Arr, L: Arr, E: Arr, out: Arr) -> None:
    """The event function of a form without events (E has no rows: nothing to write)."""
    return
