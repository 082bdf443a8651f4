"""The bounds of a chain's data (SI units): every number a scene gives for the chain, its hinge
items or its base is finite and, where it must be positive, within [MIN_POSITIVE,
MAX_MAGNITUDE]; each check a one-line ValueError naming the value and the allowed range."""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

#: Allowed magnitudes of the chain's data (SI units): |value| <= MAX_MAGNITUDE, and the
#: strictly positive ones (l, m, EI) >= MIN_POSITIVE. The models form products and quotients
#: of several parameters (frequencies EI / (m l^4), kappa / (m l^3), inertias m l^3); beyond
#: these bounds they leave the range where float64 arithmetic means anything and the runs
#: failed at t = 0 with messages naming no parameter (m = 1e-200: ZeroDivisionError in the
#: full model; kappa = 1e25 or EI = 1e-15: LinAlgError in the reduced model). No physical rod
#: chain is near them: 1e12 N m^2 is a rigid limit already (a bridge girder is ~1e11).
MAX_MAGNITUDE = 1e12
MIN_POSITIVE = 1e-12


def as_rod_array(name: str, value: Any, n: int, *, positive: bool | None) -> np.ndarray:
    """A length-n float array from a scalar or sequence of real numbers; ``positive``: True
    for > 0, False for >= 0 (both with bounded magnitudes: ``MAX_MAGNITUDE``,
    ``MIN_POSITIVE``), None for any finite value (angles, initial state)."""
    items = value if isinstance(value, (list, tuple)) else [value]
    if any(isinstance(v, (bool, np.bool_, str, bytes, dict, list, tuple)) for v in items):
        raw = np.asarray(None)  # a boolean, text or nested list among the numbers: refused
    else:
        raw = np.asarray(value)
    if raw.dtype.kind not in "iuf":  # strings, booleans, complex, objects: refused
        raise ValueError(
            f"{name} must be a real number or a list of n = {n} real numbers, got {value!r}"
        )
    arr = raw.astype(float)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have length n = {n}, got shape {arr.shape}")
    check_bounds(name, arr, positive)
    arr.setflags(write=False)
    return arr


def check_bounds(name: str, arr: np.ndarray, positive: bool | None) -> None:
    """The bounds of the chain's data on a float array: finite; ``positive`` True: in
    [MIN_POSITIVE, MAX_MAGNITUDE], False: in [0, MAX_MAGNITUDE], None: any finite value.
    ValueError naming ``name`` and the allowed range."""
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    if positive is True and np.any(arr <= 0):
        raise ValueError(f"{name} must be > 0 (allowed range (0, inf)), got {arr.tolist()}")
    if positive is False and np.any(arr < 0):
        raise ValueError(f"{name} must be >= 0 (allowed range [0, inf)), got {arr.tolist()}")
    lo = MIN_POSITIVE if positive is True else 0.0
    if positive is not None and np.any(np.abs(arr) > MAX_MAGNITUDE) or np.any(np.abs(arr) < lo):
        bad = float(arr[(np.abs(arr) > MAX_MAGNITUDE) | (np.abs(arr) < lo)][0])
        allowed = (
            f"[{MIN_POSITIVE:g}, {MAX_MAGNITUDE:g}]" if positive else f"[0, {MAX_MAGNITUDE:g}]"
        )
        raise ValueError(
            f"{name} must lie in {allowed} (SI units; beyond that the models' arithmetic "
            f"overflows or underflows), got {bad:g}"
        )


def bounded_number(name: str, value: Any, *, positive: bool | None) -> float:
    """A real number within the chain's bounds (``check_bounds``); ``name`` with its unit."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a real number, got {value!r}")
    v = float(value)
    check_bounds(name, np.array([v]), positive)
    return v
