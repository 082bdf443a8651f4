"""A reference converged by refinement, and its error bar (``rodval reference``, docs/
reference_model.md, "A converged reference with an error bar").

Level i of a refinement runs the reference with elements E0 * 2**i and step H0 / 2**i: both
halve the discretization's size h_i, so a quantity whose error goes as C h**p changes between
levels by d_i = q_i - q_{i-1} ~ C' h_i**p, and d_{i-1} / d_i ~ 2**p.

The quantities of interest (``quantities_of_interest``), each with its unit:

- ``lock_t[LABEL#j]``: the j-th lock of that label (``Trajectory.events``, matched by label and
  order), its time, s;
- ``lock_impulse[LABEL#j]``: its impulse, relative: changes divided by the finest level's
  |impulse|; only for a lock whose window closed before the run's end (``window_closed``: a
  window the run ended inside holds the impulse over the part reached, not the lock's);
- ``phi_times``: the chord angles at the scene's output times, rad: the change between levels
  is the largest |phi_i - phi_{i-1}| over times and rods (a norm, >= 0);
- ``phi_deployed[k]``: rod k's deployed chord angle, rad: its time mean (trapezoid) over the
  output times from the last lock to the end (the whole horizon without a lock), the state the
  residual vibration rings about. The instantaneous angle at the end is in ``phi_times``; its
  change between levels mostly measures that vibration's phase, which a lock-time error of a
  few ms shifts by a large fraction of a period (docs/reference_model.md);
- with a free base, ``attitude_times``: the body's attitude at the output times (the change: the
  largest over times) and ``attitude_deployed``: its time mean after the last lock, rad.

Per quantity (``estimate``): the changes between successive levels; the observed order
p = log2(|d_{i-1}| / |d_i|) where it shows (``observed_order``: at least three levels, the last
changes of one sign and shrinking, p in [MIN_ORDER, MAX_ORDER], and with four or more levels
the previous ratio's order within ORDER_SPREAD of it); the estimated error of the finest level:
Richardson |d_last| / (2**p - 1) where the order shows, else |d_last| (``method`` says which).

The levels compared (``compared_from``): the finest level and the levels just before it that
finished, are valid by the model's own checks and hold the same quantities (lock alike); a
level left out (failed, INVALID, locking otherwise) ends the run of compared levels, so an
error bar never rests on a change from a level the model itself rejects.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

#: Fewest levels a refinement needs: two changes, one ratio.
MIN_LEVELS = 3
#: The observed orders the Richardson estimate accepts: a smaller one is no convergence, a
#: larger one a change that vanished by chance (a crossing), not an asymptotic rate.
MIN_ORDER = 0.5
MAX_ORDER = 6.0
#: With four or more levels, the two last ratios' orders must agree within this.
ORDER_SPREAD = 0.5
#: The units of the quantity groups (``quantities_of_interest``'s name prefixes).
UNITS = {
    "lock_t": "s",
    "lock_impulse": "relative",
    "phi_times": "rad",
    "phi_deployed": "rad",
    "attitude_times": "rad",
    "attitude_deployed": "rad",
}
RICHARDSON = "richardson"
LAST_CHANGE = "last change"


@dataclass(frozen=True)
class Estimate:
    """One quantity's refinement: its changes between successive levels (in its unit; signed
    for a scalar, a norm for ``phi_times``), the observed order (None where it does not show),
    the estimated error of the finest level and how it was estimated (RICHARDSON or
    LAST_CHANGE)."""

    name: str
    unit: str
    changes: tuple[float, ...]
    order: float | None
    error: float
    method: str


def observed_order(changes: Sequence[float]) -> float | None:
    """p = log2(|d_{-2}| / |d_{-1}|) of the last two changes where the order shows (module
    docstring), else None: fewer than two changes, a zero or non-finite change, changes of
    opposite signs (an oscillating sequence), a change that does not shrink, p outside
    [MIN_ORDER, MAX_ORDER], or, with three changes or more, the previous ratio's order more
    than ORDER_SPREAD away."""
    d = [float(c) for c in changes]
    if len(d) < MIN_LEVELS - 1 or not all(math.isfinite(c) and c != 0 for c in d[-3:]):
        return None
    p = _ratio_order(d[-2], d[-1])
    if p is None:
        return None
    if len(d) >= 3:
        before = _ratio_order(d[-3], d[-2])
        if before is None or abs(before - p) > ORDER_SPREAD:
            return None
    return p


def _ratio_order(coarse: float, fine: float) -> float | None:
    """log2(|coarse| / |fine|) for two changes of one sign, within [MIN_ORDER, MAX_ORDER]."""
    if (coarse > 0) != (fine > 0):
        return None
    p = math.log2(abs(coarse) / abs(fine))
    return p if MIN_ORDER <= p <= MAX_ORDER else None


def finest_error(changes: Sequence[float]) -> tuple[float, float | None, str]:
    """(error, order, method): the estimated error of the finest level, Richardson
    |d_last| / (2**p - 1) where the order p shows (``observed_order``), else |d_last|."""
    if not changes:
        raise ValueError("changes must hold at least one change between levels, got none")
    last = abs(float(changes[-1]))
    p = observed_order(changes)
    if p is None:
        return last, None, LAST_CHANGE
    return last / (2.0**p - 1.0), p, RICHARDSON


def successive_changes(values: Sequence[Any]) -> list[float]:
    """The changes between successive levels' values: q_i - q_{i-1} for scalars, the largest
    |q_i - q_{i-1}| for arrays (one shape at every level; ValueError naming the level
    otherwise)."""
    out = []
    for i in range(1, len(values)):
        a, b = np.asarray(values[i - 1], float), np.asarray(values[i], float)
        if a.shape != b.shape:
            raise ValueError(f"level {i}'s values have shape {b.shape}, level {i - 1}'s {a.shape}")
        out.append(float(b - a) if b.ndim == 0 else float(np.max(np.abs(b - a), initial=0.0)))
    return out


def estimate(name: str, values: Sequence[Any], scale: float = 1.0) -> Estimate:
    """The refinement of quantity ``name`` over its levels' ``values`` (coarse to fine), its
    changes divided by ``scale`` (the finest |impulse| for a relative quantity, else 1)."""
    changes = [c / scale for c in successive_changes(values)]
    error, order, method = finest_error(changes)
    unit = UNITS[name.split("[")[0]]
    return Estimate(name, unit, tuple(changes), order, error, method)


def lock_keys(events: Sequence[Mapping[str, Any]]) -> dict[str, Mapping[str, Any]]:
    """A run's locks keyed "LABEL#j" (the j-th lock of that label, j from 1), in time order."""
    from rodval.analysis.events import is_lock

    seen: dict[str, int] = {}
    out = {}
    for ev in events:
        label = str(ev.get("label"))
        if is_lock(label):
            seen[label] = seen.get(label, 0) + 1
            out[f"{label}#{seen[label]}"] = ev
    return out


def deployed_mean(times: np.ndarray, values: np.ndarray, since: float) -> np.ndarray:
    """The time mean (trapezoid) of ``values`` (times x columns) over the output times at or
    after ``since`` (s): the deployed state after the last lock. With fewer than two such
    times, the values at the last time."""
    times, values = np.asarray(times, float), np.asarray(values, float)
    keep = times >= since
    if keep.sum() < 2:
        return np.asarray(values[-1])
    t, v = times[keep], values[keep]
    dt = np.diff(t).reshape(-1, *([1] * (v.ndim - 1)))
    return np.asarray(np.sum(0.5 * (v[1:] + v[:-1]) * dt, axis=0) / (t[-1] - t[0]))


def quantities_of_interest(
    events: Sequence[Mapping[str, Any]],
    times: np.ndarray,
    phi: np.ndarray,
    attitude: np.ndarray | None = None,
) -> dict[str, Any]:
    """One level's quantities of interest (module docstring) from its lock events, its output
    ``times`` (s), chord angles ``phi`` (times x rods, rad) and, with a free base, the body's
    ``attitude`` (rad, one per time): name -> value (a float, or an array for the ``_times``
    quantities). A lock whose window did not close has its time and no impulse."""
    out: dict[str, Any] = {}
    locks = lock_keys(events)
    for key, ev in locks.items():
        out[f"lock_t[{key}]"] = float(ev["t"])
        if impulse_measured(ev):
            out[f"lock_impulse[{key}]"] = float(ev["impulse"])
    since = max((float(ev["t"]) for ev in locks.values()), default=float(times[0]))
    phi = np.asarray(phi, float)
    out["phi_times"] = phi
    for k, value in enumerate(deployed_mean(times, phi, since), start=1):
        out[f"phi_deployed[{k}]"] = float(value)
    if attitude is not None:
        theta = np.asarray(attitude, float).reshape(-1)
        out["attitude_times"] = theta
        out["attitude_deployed"] = float(deployed_mean(times, theta[:, None], since)[0])
    return out


def qoi_record(qoi: Mapping[str, Any]) -> dict[str, Any]:
    """``quantities_of_interest``'s values as JSON values (arrays as nested lists; JSON keeps
    every digit of a float): the inverse of ``qoi_from_record``."""
    return {name: np.asarray(v).tolist() if is_array(name) else float(v) for name, v in qoi.items()}


def qoi_from_record(record: Mapping[str, Any]) -> dict[str, Any]:
    """The quantities of interest of ``qoi_record``'s JSON values, bit for bit."""
    return {
        name: np.asarray(v, float) if is_array(name) else float(v) for name, v in record.items()
    }


def is_array(name: str) -> bool:
    """Whether quantity ``name`` is an array over the output times (``phi_times``,
    ``attitude_times``) rather than a number."""
    return name.endswith("_times")


def compared_from(levels: Sequence[Mapping[str, Any] | None]) -> int:
    """The first of the levels the error bar compares (module docstring): the finest level and
    those just before it with the same quantities, back to the first level that is None (left
    out: failed or INVALID) or holds other quantities (``missing_quantity``). len(levels) when
    the finest is None: nothing is compared."""
    finest = levels[-1] if levels else None
    if finest is None:
        return len(levels)
    start = len(levels) - 1
    while start > 0:
        level = levels[start - 1]
        if level is None or missing_quantity([level, finest]) is not None:
            break
        start -= 1
    return start


def missing_quantity(
    levels: Sequence[Mapping[str, Any]], numbers: Sequence[int] | None = None
) -> str | None:
    """The first quantity that some level lacks and another holds (a lock one level does not
    reach, a lock window one level closes and another does not), as "NAME (not at level i)"
    (i: the level's place in ``levels``, or its number in ``numbers``), or None when every
    level holds the same ones."""
    names = list(dict.fromkeys(name for level in levels for name in level))
    for name in names:
        for i, level in enumerate(levels):
            if name not in level:
                return f"{name} (not at level {i if numbers is None else numbers[i]})"
    return None


def unmeasured(events: Sequence[Mapping[str, Any]]) -> list[str]:
    """The lock impulses of a run that are no quantity of interest: "lock_impulse[LABEL#j]" of
    each lock whose window the run ended inside (``window_closed`` False)."""
    return [
        f"lock_impulse[{key}]" for key, ev in lock_keys(events).items() if not impulse_measured(ev)
    ]


def impulse_measured(event: Mapping[str, Any]) -> bool:
    """Whether a lock record's impulse is the lock's: its window closed before the run ended
    (``window_closed``; taken as closed when the record has no such key)."""
    return bool(event.get("window_closed", True))


def estimates(levels: Sequence[Mapping[str, Any]]) -> list[Estimate]:
    """Every quantity's refinement over ``levels`` (each ``quantities_of_interest``, coarse to
    fine, the same quantities at each: ``missing_quantity`` None); impulses relative to the
    finest level's |impulse|."""
    out = []
    for name in levels[-1]:
        values = [level[name] for level in levels]
        scale = abs(float(values[-1])) if name.startswith("lock_impulse") else 1.0
        out.append(estimate(name, values, scale if scale > 0 else 1.0))
    return out


def unconverged(found: Sequence[Estimate], tol: float) -> Estimate | None:
    """The quantity with the largest error-to-tol ratio among those whose estimated error is not
    below ``tol`` (in each quantity's unit), or None when every one is below it."""
    over = [e for e in found if not e.error < tol]
    return max(over, key=lambda e: e.error / tol) if over else None


def error_bar(found: Sequence[Estimate], phi_scale: float) -> dict[str, float]:
    """The reference's error bar with the keys of a study's ``[agreement] reference_error``
    (``rodval.study.case.agreement_spec``): ``rel``: the largest angle error (phi_times,
    phi_deployed; rad) over ``phi_scale`` (max |phi| of the finest level, the scale of
    ``rodval.analysis.agreement.gap_series``); ``lock_dt``: the largest lock-time error, s;
    ``impulse_rel``: the largest relative impulse error; with a free base's quantities,
    ``attitude``: the error of the body's deployed attitude (attitude_deployed, rad: the
    band of ``rodval.analysis.agreement``'s ``attitude_gap``; the attitude at the output
    times is in ``group_errors``). 0 for a group with no quantity."""
    angle = max(worst_error(found, "phi_times"), worst_error(found, "phi_deployed"))
    bar = {
        "rel": angle / phi_scale if phi_scale > 0 else 0.0,
        "lock_dt": worst_error(found, "lock_t["),
        "impulse_rel": worst_error(found, "lock_impulse["),
    }
    if any(e.name.startswith("attitude") for e in found):
        bar["attitude"] = worst_error(found, "attitude_deployed")
    return bar


def group_errors(found: Sequence[Estimate]) -> dict[str, float]:
    """The largest estimated error of each group of quantities present (UNITS' names: lock
    times s, impulses relative, angles rad), the figures ``rodval reference`` prints."""
    return {
        group: worst_error(found, group)
        for group in UNITS
        if any(e.name.split("[")[0] == group for e in found)
    }


def worst_error(found: Sequence[Estimate], prefix: str) -> float:
    """The largest estimated error among the quantities whose name starts with ``prefix`` (in
    their unit), 0 when there is none."""
    return max((e.error for e in found if e.name.startswith(prefix)), default=0.0)
