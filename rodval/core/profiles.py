"""Per-rod profiles: a scene file's chain and initial arrays given as a rule instead of a list
of n numbers, so that one scene (or one study grid over ``n``) describes a non-uniform chain of
any length.

A profile is a table with one of three forms (values in the array's own unit):

* ``{first = [a, b], rest = c}``: the first rods take ``first`` (a number or a list), every
  later rod ``rest`` (a root rod and repeated panels: ``EI = {first = [5e4], rest = 1e4}``);
* ``{first = [a], repeat = [p, q]}``: after ``first`` (optional), the pattern ``repeat``
  cyclically (p, q, p, q, ...);
* ``{at = [x0, x1, ...], values = [v0, v1, ...]}``: a function of the rod's position along the
  chain, x_i = (i + 1/2) / n for rod i = 0..n-1 (by index, 0 at the root, 1 at the tip),
  interpolated linearly between the points ``at`` (increasing, in [0, 1]) and held constant
  beyond the first and last.

Resolved to a list of n numbers (O(n)) before the chain checks its values and bounds.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

PROFILE_FORMS = ("rest", "repeat", "at")
PROFILE_KEYS = ("first", "rest", "repeat", "at", "values")


def _numbers(name: str, key: str, value: Any, *, scalar_ok: bool) -> list[float]:
    items = [value] if scalar_ok and not isinstance(value, (list, tuple)) else value
    if (
        not isinstance(items, (list, tuple))
        or not items
        or not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in items)
    ):
        what = (
            "a number or a non-empty list of numbers"
            if scalar_ok
            else "a non-empty list of numbers"
        )
        raise ValueError(f"{name} profile key {key!r} must be {what}, got {value!r}")
    return [float(v) for v in items]


def resolve_profile(name: str, spec: dict[str, Any], n: int) -> list[float]:
    """The n values of the profile ``spec`` of the array ``name`` (see module docstring);
    ValueError naming the array and the key for anything else."""
    unknown = sorted(set(spec) - set(PROFILE_KEYS))
    if unknown:
        raise ValueError(
            f"{name} profile: unknown key {unknown[0]!r} (allowed: {', '.join(PROFILE_KEYS)})"
        )
    forms = [f for f in PROFILE_FORMS if f in spec]
    if len(forms) != 1:
        raise ValueError(
            f"{name} profile needs exactly one of 'rest', 'repeat' or 'at' (with 'values'), "
            f"got {sorted(spec)}"
        )
    if forms[0] == "at":
        if "first" in spec:
            raise ValueError(f"{name} profile: 'first' goes with 'rest' or 'repeat', not 'at'")
        if "values" not in spec:
            raise ValueError(
                f"{name} profile: 'at' needs 'values' (one per point of 'at'), missing"
            )
        at = _numbers(name, "at", spec["at"], scalar_ok=False)
        values = _numbers(name, "values", spec["values"], scalar_ok=False)
        if len(values) != len(at):
            raise ValueError(
                f"{name} profile: 'at' and 'values' must have the same length, got {len(at)} "
                f"and {len(values)}"
            )
        if any(b <= a for a, b in zip(at, at[1:])) or at[0] < 0 or at[-1] > 1:
            raise ValueError(f"{name} profile: 'at' must increase within [0, 1], got {at}")
        x = (np.arange(n) + 0.5) / n
        profile: list[float] = np.interp(x, at, values).tolist()
        return profile
    if "values" in spec:
        raise ValueError(f"{name} profile: 'values' goes with 'at'")
    first = _numbers(name, "first", spec["first"], scalar_ok=True) if "first" in spec else []
    if len(first) > n:
        raise ValueError(f"{name} profile: 'first' has {len(first)} values, more than n = {n}")
    if forms[0] == "rest":
        rest = _numbers(name, "rest", spec["rest"], scalar_ok=True)
        if len(rest) != 1:
            raise ValueError(f"{name} profile key 'rest' must be one number, got {spec['rest']!r}")
        return first + rest * (n - len(first))
    pattern = _numbers(name, "repeat", spec["repeat"], scalar_ok=False)
    return first + [pattern[i % len(pattern)] for i in range(n - len(first))]


def resolve_profiles(table: dict[str, Any], n: int, where: str) -> dict[str, Any]:
    """``table`` (a scene file's [chain] or [initial]) with every profile resolved to n
    numbers; other values are left for the chain to check."""
    try:
        return {k: resolve_profile(k, v, n) if isinstance(v, dict) else v for k, v in table.items()}
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
