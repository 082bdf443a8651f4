"""Prescribed motions of a base (``rodval.core.base.Base`` of kind "prescribed"): laws of time
f(t) for the body's centre x, y (m) and attitude (rad), twice differentiable, with f' and f''
in closed form. A law's compiled rows are a load law's (``rodval.core.load_table.LOAD_COLUMNS``; the
component is the axis 0, 1, 2 = x, y, attitude) and its values are the load laws' formulas,
evaluated with both derivatives by ``law_motion``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from rodval.core.checks import check_choice, check_keys, check_number, check_type
from rodval.core.load_table import LAW_CONSTANT, LAW_HARMONIC, LAW_LINEAR, LAW_RAISED_COSINE

#: Kane, Ryan and Banerjee's smooth spin-up (on [0, p1)): p0 / p1 (t^2 / 2 + (p1 / 2 pi)^2
#: (cos(2 pi t / p1) - 1)), rate p0 reached at t = p1 with zero acceleration.
LAW_SPIN_UP = 4
#: Motion laws -> (their parameters, law code): f(t) on t >= 0, twice differentiable.
MOTION_LAWS: dict[str, tuple[tuple[str, ...], int]] = {
    "constant": (("value",), LAW_CONSTANT),
    "linear": (("value", "rate"), LAW_LINEAR),
    "harmonic": (("amplitude", "omega", "phase"), LAW_HARMONIC),
    "spin_up": (("rate", "time"), LAW_SPIN_UP),
}


@dataclass(frozen=True)
class Motion:
    """A prescribed coordinate history f(t) of a base (m for x, y; rad for the attitude), twice
    differentiable, with f' and f'' in closed form (``loads.law_motion``, the load laws'
    formulas). ``law`` and its parameters (``MOTION_LAWS``):

    * ``constant``: f = value;
    * ``linear``: f = value + rate t;
    * ``harmonic``: f = amplitude sin(omega t + phase) (omega > 0 in rad/s);
    * ``spin_up``: Kane, Ryan and Banerjee's smooth spin-up to ``rate`` (per s) over ``time``
      T (s): f = rate/T (t^2/2 + (T/2 pi)^2 (cos(2 pi t/T) - 1)) for t < T, rate (t - T/2)
      after; f' and f'' are continuous (f'' = 0 at t = 0 and at T)."""

    law: str = "constant"
    params: tuple[float, ...] = (0.0,)

    def __post_init__(self) -> None:
        check_choice("motion law", self.law, tuple(MOTION_LAWS))
        names = MOTION_LAWS[self.law][0]
        check_type(
            "motion params", self.params, (tuple, list), f"a tuple of numbers ({', '.join(names)})"
        )
        if len(self.params) != len(names):
            raise ValueError(
                f"motion law {self.law!r} takes {len(names)} parameters "
                f"({', '.join(names)}), got {len(self.params)}"
            )
        values = tuple(
            check_number(f"motion {self.law} {name}", v, finite=True)
            for name, v in zip(names, self.params)
        )
        for name in ("omega", "time"):
            if name in names:
                check_number(
                    f"motion {self.law} {name}", values[names.index(name)], low=0.0, low_open=True
                )
        object.__setattr__(self, "params", values)

    @classmethod
    def from_dict(cls, d: Any, where: str) -> Motion:
        """A Motion from a scene file's table ``{law = "spin_up", rate = 4.0, time = 15.0}``."""
        if not isinstance(d, dict) or "law" not in d:
            raise ValueError(f"{where}: a motion needs a 'law' (one of {', '.join(MOTION_LAWS)})")
        law = d["law"]
        check_choice(f"{where} law", law, tuple(MOTION_LAWS))
        names = MOTION_LAWS[law][0]
        check_keys(d, ("law", *names), where)
        missing = [k for k in names if k not in d]
        if missing:
            raise ValueError(f"{where}: motion law {law!r} needs {', '.join(missing)}")
        return cls(law, tuple(d[k] for k in names))

    def as_dict(self) -> dict[str, Any]:
        return {"law": self.law, **dict(zip(MOTION_LAWS[self.law][0], self.params))}

    def rows(self, axis: int) -> list[tuple[float, ...]]:
        """The law's rows of a base-motion table (``load_table.LOAD_COLUMNS``; component = the
        axis 0, 1, 2 = x, y, attitude)."""
        code = MOTION_LAWS[self.law][1]
        p = self.params
        if self.law == "spin_up":
            rate, T = p
            return [
                (0, axis, code, 0.0, T, 0, rate, T, 0.0, 0),
                (0, axis, LAW_LINEAR, T, np.inf, 1, 0.5 * rate * T, rate, 0.0, 0),
            ]
        padded = (*p, 0.0, 0.0, 0.0)[:3]
        return [(0, axis, code, 0.0, np.inf, 1, *padded, 0)]

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Times (s) where f'' has a kink (the spin-up's end)."""
        return (self.params[1],) if self.law == "spin_up" else ()


def motion_table(motion: tuple[Motion, ...]) -> np.ndarray:
    """The base-motion table (rows x ``LOAD_COLUMNS``) of the three axes' laws."""
    rows = [r for axis, m in enumerate(motion) for r in m.rows(axis)]
    return np.ascontiguousarray(np.array(rows, dtype=np.float64))


@njit(cache=True)
def law_motion(L: np.ndarray, r: int, t: float) -> tuple[float, float, float]:
    """(f, f', f'') at t of row ``r`` of a law table (``LOAD_COLUMNS``), on its interval: the
    value in the law's unit and its first and second time derivatives (a prescribed base's
    motion, ``rodval.core.base.Motion``). The values are ``load_sums``' formulas."""
    law, t0 = L[r, 2], L[r, 3]
    p0, p1, p2 = L[r, 6], L[r, 7], L[r, 8]
    if law == LAW_RAISED_COSINE:
        return (
            p0 * (0.5 - 0.5 * math.cos(p1 * t)),
            0.5 * p0 * p1 * math.sin(p1 * t),
            0.5 * p0 * p1 * p1 * math.cos(p1 * t),
        )
    if law == LAW_LINEAR:
        return p0 + p1 * (t - t0), p1, 0.0
    if law == LAW_HARMONIC:
        x = p1 * t + p2
        return p0 * math.sin(x), p0 * p1 * math.cos(x), -p0 * p1 * p1 * math.sin(x)
    if law == LAW_SPIN_UP:
        w = 2.0 * math.pi / p1
        return (
            p0 / p1 * (0.5 * t * t + (math.cos(w * t) - 1.0) / (w * w)),
            p0 / p1 * (t - math.sin(w * t) / w),
            p0 / p1 * (1.0 - math.cos(w * t)),
        )
    return p0, 0.0, 0.0


@njit(cache=True)
def motion_at(table: np.ndarray, t: float) -> np.ndarray:
    """(3, 3) [[x, x', x''], [y, ...], [theta, ...]] (m, m/s, m/s^2; rad, rad/s, rad/s^2) at t
    >= 0 from a base-motion table (``rodval.core.base.motion_table``): each axis's row whose
    interval holds t (``law_motion``); O(rows)."""
    out = np.zeros((3, 3))
    for r in range(table.shape[0]):
        t0, t1 = table[r, 3], table[r, 4]
        if (t0 <= t and t < t1) or (t == t1 and table[r, 5] != 0.0):
            f, df, ddf = law_motion(table, r, t)
            axis = int(table[r, 1])
            out[axis, 0] = f
            out[axis, 1] = df
            out[axis, 2] = ddf
    return out
