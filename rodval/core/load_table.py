"""The compiled load table: the rows the compiled kernels read the scene's nodal forces and
hinge moments from, and their evaluation inside the kernels (``load_sums``, ``hinge_torques``).

Compiled load table: one row per (node, component, law piece), columns ``LOAD_COLUMNS``:
node (0-based), component (``COMP_*``: 0 = X, 1 = Y of a nodal force in N; 2 = a moment in N m
across hinge ``node`` (0-based hinge index), positive driving its angle D up; 3 = a rate
coefficient in N m s/rad across hinge ``node``: the moment -value dD/dt), law code, t0, t1 (s),
right_closed (1: active on [t0, t1], 0: on [t0, t1)), p0, p1, p2 (the law's parameters, see
``LAW_*``), track_end. Hinge rows come from the hinge items that apply torque (motors, rate
dampers: ``rodval.core.hinges.HingeTorque``); ``load_sums`` reads the nodal rows,
``hinge_torques`` the hinge rows.
A track is a run of consecutive rows whose intervals are sorted and disjoint (the pieces of a
tabulated history), so at most one of them acts at any t; ``track_end`` is the index of the
row after the row's track. ``load_sums`` finds a track's acting row by bisection: an
evaluation costs O(tracks x log rows), not O(rows) (a 200,001-sample history made every
evaluation scan 400,000 rows).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import njit

LOAD_COLUMNS = (
    "node",
    "component",
    "law",
    "t0",
    "t1",
    "right_closed",
    "p0",
    "p1",
    "p2",
    "track_end",
)
_TRACK_END = LOAD_COLUMNS.index("track_end")
#: Compiled load-table components: a nodal force's X, Y (N); a hinge's moment (N m) and rate
#: coefficient (N m s/rad).
COMP_X, COMP_Y, COMP_MOMENT, COMP_RATE = 0, 1, 2, 3
_COMPONENT = LOAD_COLUMNS.index("component")
#: Compiled law codes: value(t) on the row's interval.
LAW_CONSTANT = 0  # p0
LAW_RAISED_COSINE = 1  # p0 (1/2 - 1/2 cos(p1 t))
LAW_LINEAR = 2  # p0 + p1 (t - t0)
LAW_HARMONIC = 3  # p0 sin(p1 t + p2)

Row = tuple[int, float, float, bool, float, float, float]  # law, t0, t1, closed, p0, p1, p2


def load_table(
    loads: Sequence[Any], hinge_rows: Sequence[tuple[float, ...]] = ()
) -> np.ndarray | None:
    """The compiled load table (rows x ``LOAD_COLUMNS``) of ``loads`` (``NodalForce``s, each
    giving its ``rows()``) and the hinge items' ``hinge_rows``
    (``rodval.core.hinges.HingeTorque.rows``, after the nodal rows), or None when a load is
    a plain callable."""
    rows: list[tuple[float, ...]] = []
    for f in loads:
        r = f.rows()
        if r is None:
            return None
        rows += r
    rows += hinge_rows
    table = np.array(rows, dtype=np.float64).reshape(-1, len(LOAD_COLUMNS) - 1)
    return np.ascontiguousarray(np.column_stack([table, _track_ends(table)]))


def _track_ends(table: np.ndarray) -> np.ndarray:
    """For each row of a load table (without its last column), the index of the row after
    its track: a row continues the previous row's track when it starts after that row's
    interval ends (or where it ends, if that row is right-open) and both are nodal or both
    hinge rows. O(rows)."""
    t0, t1, closed = table[:, 3], table[:, 4], table[:, 5]
    follows = (t1[:-1] < t0[1:]) | ((t1[:-1] == t0[1:]) & (closed[:-1] == 0.0))
    hinge = table[:, _COMPONENT] >= COMP_MOMENT  # a track is all nodal or all hinge rows
    follows &= hinge[:-1] == hinge[1:]
    starts = np.concatenate([[0], np.flatnonzero(~follows) + 1]).astype(np.int64)
    ends = np.append(starts[1:], len(table))
    return np.repeat(ends, ends - starts).astype(np.float64)


@njit(cache=True)
def _track_row(L: np.ndarray, start: int, end: int, t: float) -> int:
    """The row of the track ``start:end`` of ``L`` with the latest start t0 <= t (``start``
    when there is none): the only row of the track that may act at t. O(log(end - start))."""
    lo, hi = start, end
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if L[mid, 3] <= t:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True, inline="always")
def _acts(L: np.ndarray, r: int, t: float) -> bool:
    """Whether row ``r`` of a load table acts at t (inside its interval)."""
    t0, t1 = L[r, 3], L[r, 4]
    return not (t < t0 or t > t1 or (t == t1 and L[r, 5] == 0.0))


@njit(cache=True, inline="always")
def _law_value(L: np.ndarray, r: int, t: float) -> float:
    """The value at t of row ``r``'s law (``LAW_*``), on its interval."""
    law = L[r, 2]
    if law == LAW_RAISED_COSINE:
        return float(L[r, 6] * (0.5 - 0.5 * math.cos(L[r, 7] * t)))
    if law == LAW_LINEAR:
        return float(L[r, 6] + L[r, 7] * (t - L[r, 3]))
    if law == LAW_HARMONIC:
        return float(L[r, 6] * math.sin(L[r, 7] * t + L[r, 8]))
    return float(L[r, 6])


@njit(cache=True)
def hinge_torques(L: np.ndarray, t: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(T, C) at t from the hinge rows of the load table ``L``: T_k (N m) the moments laws
    apply across hinge k (positive driving D_k up), C_k (N m s/rad) the rate coefficients
    (the moment -C_k dD_k/dt); both empty (length 0) when no hinge row acts at t, so a
    kernel skips them (``applied_torques``). O(tracks x log rows + n)."""
    T = np.empty(0)
    C = np.empty(0)
    end = 0
    while end < L.shape[0]:
        start, end = end, int(L[end, _TRACK_END])
        if L[start, 1] < COMP_MOMENT:
            continue
        r = _track_row(L, start, end, t)
        if not _acts(L, r, t):
            continue
        if T.shape[0] == 0:
            T = np.zeros(n)
            C = np.zeros(n)
        if L[r, 1] == COMP_MOMENT:
            T[int(L[r, 0])] += _law_value(L, r, t)
        else:
            C[int(L[r, 0])] += _law_value(L, r, t)
    return T, C


@njit(cache=True)
def applied_torques(T: np.ndarray, C: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """The hinge moments T_k - C_k dD_k/dt (N m; positive driving D_k up) from
    ``hinge_torques``'s (T, C) and the hinge rates (rad/s) as the model measures them; T is
    overwritten and returned (empty stays empty). O(n)."""
    for k in range(T.shape[0]):
        T[k] -= C[k] * rates[k]
    return T


@njit(cache=True)
def load_sums(L: np.ndarray, t: float, SX: np.ndarray, SY: np.ndarray) -> bool:
    """Suffix sums SX_k = sum_{j>=k} X_j, SY_k (N) at t from the load table ``L``; returns
    False (and leaves SX, SY untouched) when no row acts at t. O(tracks x log rows + n); the
    acting rows are summed in table order."""
    n = SX.shape[0]
    active = False
    end = 0
    while end < L.shape[0]:
        start, end = end, int(L[end, _TRACK_END])
        if L[start, 1] >= COMP_MOMENT:  # a hinge track (``hinge_torques``)
            continue
        r = _track_row(L, start, end, t)
        if not _acts(L, r, t):
            continue
        if not active:
            SX[:] = 0.0
            SY[:] = 0.0
            active = True
        value = _law_value(L, r, t)
        if L[r, 1] == 0:
            SX[int(L[r, 0])] += value
        else:
            SY[int(L[r, 0])] += value
    if active:
        for k in range(n - 2, -1, -1):
            SX[k] += SX[k + 1]
            SY[k] += SY[k + 1]
    return active
