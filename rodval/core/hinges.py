"""The chain's hinge items: latches (a hinge locks at an angle) and one-sided limit stops, and
the checks a scene makes of them (hinge indices 0..n-1, acting stops, latch angles ahead of
the initial state). Conventions: ``rodval.core.scene``."""

from __future__ import annotations

import numbers
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rodval.core.bounds import bounded_number, check_bounds
from rodval.core.checks import check_number


def _index(name: str, value: Any, n: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(
            f"{name} must be an integer hinge index in 0..n-1 = 0..{n - 1}, got {value!r}"
        )
    index = int(value)
    if not 0 <= index < n:
        raise ValueError(f"{name} must be in 0..n-1 = 0..{n - 1}, got {value}")
    return index


@dataclass(frozen=True)
class Latch:
    """A latch on hinge ``hinge`` (0..n-1): the hinge locks when its angle D reaches
    ``angle`` (rad) moving in ``direction`` (+1: D increasing, -1: decreasing; None: towards
    the angle from the initial state). At the lock the hinge's relative rate drops to zero
    (a plastic impact) and D stays at ``angle`` afterwards. ``window`` (s, > 0): the window
    over which the models measure the lock impulse (None: the first bending period of the
    locked segment, ``rodval.mechanics.lock_window``). ``held``: the hinge is held from t = 0 (a
    clamp, or a joint locked before the run: its initial angle must be ``angle`` and its
    initial rate zero); it never fires an event."""

    hinge: int
    angle: float
    direction: int | None = None
    window: float | None = None
    held: bool = False

    def __post_init__(self) -> None:
        if (
            isinstance(self.hinge, bool)
            or not isinstance(self.hinge, numbers.Integral)
            or self.hinge < 0
        ):
            raise ValueError(f"latch hinge must be an integer >= 0, got {self.hinge!r}")
        check_number("latch angle", self.angle, finite=True, unit="rad")
        if self.direction is not None and (
            isinstance(self.direction, bool)
            or not isinstance(self.direction, numbers.Integral)
            or self.direction not in (1, -1)
        ):
            raise ValueError(
                f"latch direction must be the integer +1 or -1, or omitted (None), "
                f"got {self.direction!r}"
            )
        if self.window is not None:
            check_number("latch window", self.window, low=0.0, low_open=True, finite=True, unit="s")
        if not isinstance(self.held, bool):
            raise ValueError(f"latch held must be true or false, got {self.held!r}")


@dataclass(frozen=True)
class Stop:
    """A limit stop on hinge ``hinge``: a one-sided spring-damper acting beyond ``angle``
    (rad) on the ``side`` "upper" (D > angle) or "lower" (D < angle), with moment
    -stiffness (D - angle) - damping dD/dt there (N m; stiffness > 0 in N m/rad, damping >= 0
    in N m s/rad)."""

    hinge: int
    angle: float
    side: str = "upper"
    stiffness: float = 1e4
    damping: float = 0.0

    def __post_init__(self) -> None:
        if (
            isinstance(self.hinge, bool)
            or not isinstance(self.hinge, numbers.Integral)
            or self.hinge < 0
        ):
            raise ValueError(f"stop hinge must be an integer >= 0, got {self.hinge!r}")
        check_number("stop angle", self.angle, finite=True, unit="rad")
        if self.side not in ("upper", "lower"):
            raise ValueError(f"stop side must be 'upper' or 'lower', got {self.side!r}")
        # an acting stop adds its stiffness to kappa and its damping to nu: the same bounds
        bounded_number("stop stiffness (N m/rad)", self.stiffness, positive=True)
        bounded_number("stop damping (N m s/rad)", self.damping, positive=False)

    def acts(self, D: Any) -> Any:
        """Whether the stop acts at hinge angle(s) ``D`` (rad, a number or an array): D
        beyond ``angle`` on its ``side``, strictly (the one definition every model uses)."""
        return D > self.angle if self.side == "upper" else D < self.angle


def check_acting_stops(chain: Any, stops: tuple[Stop, ...]) -> None:
    """An acting stop adds its stiffness to its hinge's kappa and its damping to nu: the sums
    (all of a hinge's stops acting at once) must stay within the chain's bounds."""
    for field_name, attr, unit in (
        ("kappa", "stiffness", "N m/rad"),
        ("nu", "damping", "N m s/rad"),
    ):
        total = getattr(chain, field_name).copy()
        for st in stops:
            total[st.hinge] += getattr(st, attr)
        for st in stops:
            check_bounds(
                f"stop {attr} + {field_name} of hinge {st.hinge} ({unit})",
                total[st.hinge : st.hinge + 1],
                positive=False,
            )


def hinge_items(label: str, cls: type[Latch] | type[Stop], items: Any, n: int) -> tuple[Any, ...]:
    """The scene's latches or stops (``label``) as a tuple of ``cls`` on hinges 0..n-1."""
    if isinstance(items, (str, bytes, dict)) or not isinstance(items, Iterable):
        raise ValueError(f"{label} must be a sequence of rodval.{cls.__name__}")
    out: tuple[Any, ...] = tuple(items)
    for item in out:
        if not isinstance(item, cls):
            raise ValueError(
                f"{label} must be rodval.{cls.__name__} objects, got {type(item).__name__}"
            )
        _index(f"{label[:-1] if label == 'stops' else 'latch'} hinge", item.hinge, n)
    return out


#: A held latch's hinge must start at its angle (rad) and at rest (rad/s) to this distance: the
#: initial state is on the constraint (round-off of the angles' sums, 1e-12 rad, with room).
HELD_START = 1e-9


def check_latches(latches: tuple[Latch, ...], D0: np.ndarray, rate0: np.ndarray) -> None:
    """At most one latch per hinge, each ahead of its hinge's initial angle D0 (rad) in its
    direction; a held latch's hinge at its angle and at rest (rate0, rad/s)."""
    hinges = [latch.hinge for latch in latches]
    if len(set(hinges)) != len(hinges):
        raise ValueError(f"at most one latch per hinge, got hinges {hinges}")
    for latch in latches:
        d0 = D0[latch.hinge]
        if latch.held:
            if abs(d0 - latch.angle) > HELD_START or abs(rate0[latch.hinge]) > HELD_START:
                raise ValueError(
                    f"held latch on hinge {latch.hinge}: the hinge must start at its angle "
                    f"{latch.angle:.6g} rad and at rest (within {HELD_START:g}), got D = "
                    f"{d0:.6g} rad, dD/dt = {rate0[latch.hinge]:.6g} rad/s"
                )
            continue
        side = np.sign(latch.angle - d0)
        if side == 0 or (latch.direction is not None and side != latch.direction):
            raise ValueError(
                f"latch on hinge {latch.hinge}: the hinge starts at D = {d0:.6g} rad, at or "
                f"beyond its latch angle {latch.angle:.6g} rad"
                + (f" in direction {latch.direction:+d}" if latch.direction else "")
            )
