"""The body the chain hangs from (``Scene.base``): a fixed pin (``"pinned"``, the default), a
free-floating rigid body (``"free"``: a spacecraft) or a body whose motion is prescribed
(``"prescribed"``: a hub spun up by a motor; its position and attitude are laws of time,
``Motion``), docs/base.md.

Conventions (with ``rodval.core.scene``'s): the body's centre of mass is at ``position`` (m,
global frame), its attitude theta (rad) is the angle of its body frame from the global x
axis, counter-clockwise positive; node 0 (hinge 0, the root of rod 1) sits at
``hinge_offset`` in the body frame, r_0 = position + R(theta) hinge_offset. Hinge 0's angle
is measured from the body frame: D_0 = phi_1 + alpha_1 - theta (theta = 0 for a pin), so its
spring, damper, rest angle, stops and latch act between the body and rod 1. ``inertia``
(kg m^2) is about the body's centre of mass.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from rodval.core.bounds import check_bounds
from rodval.core.checks import check_choice, check_keys, check_number
from rodval.core.motion import Motion, motion_at, motion_table

#: The kinds of base: a fixed pin at the origin, a free rigid body, a prescribed motion.
BASE_KINDS = ("pinned", "free", "prescribed")
#: Fields that describe a free body (a pinned base takes none of them).
BODY_FIELDS = ("mass", "inertia", "hinge_offset", "position", "velocity", "attitude", "rate")
#: The prescribed coordinates of a base's motion: its centre's x, y (m) and attitude (rad).
MOTION_AXES = ("x", "y", "attitude")


def _vector(name: str, value: Any, unit: str) -> tuple[float, float]:
    """A 2-vector of finite real numbers (ValueError naming ``name`` otherwise)."""
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(
            f"base {name} must be a pair [x, y] of real numbers ({unit}), got {value!r}"
        )
    x, y = (check_number(f"base {name} ({unit})", v, finite=True) for v in value)
    return (x, y)


@dataclass(frozen=True)
class Base:
    """The body node 0 belongs to. ``kind``: "pinned" (node 0 fixed at the origin, no body
    coordinates: every model's equations as without a base) or "free" (a rigid body of
    ``mass`` (kg) and ``inertia`` (kg m^2, about its centre of mass), free in the plane:
    three more coordinates x, y (m) of its centre and theta (rad), with initial ``position``
    (m), ``velocity`` (m/s), ``attitude`` (rad) and ``rate`` (rad/s); node 0 at
    ``hinge_offset`` (m, body frame)). A pinned base refuses every body field."""

    kind: str = "pinned"
    mass: float | None = None
    inertia: float | None = None
    hinge_offset: tuple[float, float] = (0.0, 0.0)
    position: tuple[float, float] = (0.0, 0.0)
    velocity: tuple[float, float] = (0.0, 0.0)
    attitude: float = 0.0
    rate: float = 0.0
    #: a prescribed base's laws (x, y, attitude), ``Motion`` each (a dict of some on input)
    motion: Any = None

    def __post_init__(self) -> None:
        check_choice("base kind", self.kind, BASE_KINDS)
        set_ = object.__setattr__
        if self.kind == "pinned":
            given = [f.name for f in fields(self) if f.name != "kind" and self._given(f.name)]
            if given:
                raise ValueError(
                    f"base {given[0]} describes a free body; a pinned base (kind 'pinned', "
                    "node 0 fixed at the origin) takes none of " + ", ".join(BODY_FIELDS)
                )
            return
        if self.kind == "prescribed":
            self._prescribe()
            return
        if self.motion is not None:
            raise ValueError(
                "base motion prescribes a body's motion; a free base (kind 'free') moves by "
                "its equations (use kind 'prescribed')"
            )
        for name in ("mass", "inertia"):
            value = getattr(self, name)
            if value is None:
                raise ValueError(f"a free base needs its {name} (base.{name})")
            unit = "kg" if name == "mass" else "kg m^2"
            v = check_number(f"base {name} ({unit})", value, low=0.0, low_open=True, finite=True)
            check_bounds(f"base {name} ({unit})", np.array([v]), True)
            set_(self, name, v)
        for name, unit in (("hinge_offset", "m"), ("position", "m"), ("velocity", "m/s")):
            set_(self, name, _vector(name, getattr(self, name), unit))
        for name, unit in (("attitude", "rad"), ("rate", "rad/s")):
            v = check_number(f"base {name} ({unit})", getattr(self, name), finite=True)
            set_(self, name, v)  # finite: within the chain's bounds (check_bounds)

    def _prescribe(self) -> None:
        """Check a prescribed base: its motion laws (``Motion``, by axis) and hinge offset
        only; the body's state at t = 0 comes from the laws."""
        given = [n for n in BODY_FIELDS if n != "hinge_offset" and self._given(n)]
        if given:
            raise ValueError(
                f"base {given[0]}: a prescribed base (kind 'prescribed') takes its position "
                "and attitude from its motion laws (base.motion: x, y, attitude) and its "
                "hinge_offset, none of " + ", ".join(b for b in BODY_FIELDS if b != "hinge_offset")
            )
        object.__setattr__(self, "hinge_offset", _vector("hinge_offset", self.hinge_offset, "m"))
        laws = {} if self.motion is None else self.motion
        if isinstance(laws, tuple) and len(laws) == 3 and all(isinstance(m, Motion) for m in laws):
            return
        if not isinstance(laws, dict):
            raise ValueError(
                f"base motion must map x, y, attitude to Motion laws, got {type(laws).__name__}"
            )
        check_keys(laws, MOTION_AXES, "base motion")
        motion = []
        for axis in MOTION_AXES:
            law = laws.get(axis, Motion())
            if isinstance(law, dict):
                law = Motion.from_dict(law, f"base motion {axis}")
            if not isinstance(law, Motion):
                raise ValueError(
                    f"base motion {axis} must be a rodval Motion, got {type(law).__name__}"
                )
            motion.append(law)
        object.__setattr__(self, "motion", tuple(motion))

    @property
    def prescribed(self) -> bool:
        return self.kind == "prescribed"

    @property
    def moving(self) -> bool:
        """Whether node 0 moves (a free or a prescribed base)."""
        return self.kind != "pinned"

    def motion_table(self) -> np.ndarray:
        """A prescribed base's law table (``motion_table``)."""
        return motion_table(self.motion)

    def state_at(self, t: float) -> tuple[np.ndarray, np.ndarray, float, float]:
        """A prescribed base's (r_c (m), v_c (m/s), theta (rad), theta' (rad/s)) at t."""
        m = motion_at(self.motion_table(), t)
        return m[:2, 0], m[:2, 1], float(m[2, 0]), float(m[2, 1])

    def initial_attitude(self) -> float | None:
        """The body's attitude at t = 0 (rad; None for a pin): hinge 0 is measured from it."""
        if self.prescribed:
            return self.state_at(0.0)[2]
        return self.attitude if self.free else None

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Kinks of a prescribed motion's acceleration (s)."""
        return tuple(b for m in (self.motion or ()) for b in m.breakpoints)

    def _given(self, name: str) -> bool:
        """Whether field ``name`` holds other than its default (by value: an array or list of
        the default's numbers is the default; anything that is no such number is given)."""
        default = next(f.default for f in fields(self) if f.name == name)
        value = getattr(self, name)
        if default is None or value is None:
            return value is not default
        try:
            return not np.array_equal(np.asarray(value, float), np.asarray(default, float))
        except (TypeError, ValueError):
            return True

    @property
    def free(self) -> bool:
        return self.kind == "free"

    def initial_root(self) -> tuple[np.ndarray, np.ndarray]:
        """Node 0's position (m) and velocity (m/s) at t = 0, (2,) each (``root_state``); the
        origin at rest on a pinned base."""
        if self.prescribed:
            return root_state(self, *self.state_at(0.0))
        if not self.free:
            return np.zeros(2), np.zeros(2)
        return root_state(self, self.position, self.velocity, self.attitude, self.rate)

    def inertial(self) -> tuple[float, float]:
        """A free body's mass (kg) and inertia about its centre of mass (kg m^2)."""
        if self.mass is None or self.inertia is None:
            raise ValueError("a pinned base has no mass or inertia (kind 'pinned')")
        return self.mass, self.inertia

    @classmethod
    def from_dict(cls, d: Any, where: str = "[base]") -> Base:
        """A Base from a scene file's ``[base]`` table (unknown keys refused)."""
        check_keys(d, ("kind", *BODY_FIELDS, "motion"), where)
        try:
            values: dict[str, Any] = {
                k: tuple(v) if isinstance(v, list) else v for k, v in d.items()
            }
            return cls(**values)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None

    def as_dict(self) -> dict[str, Any]:
        """The scene-file form (``from_dict`` rebuilds the same base)."""
        if self.prescribed:
            return {
                "kind": self.kind,
                "hinge_offset": list(self.hinge_offset),
                "motion": {a: m.as_dict() for a, m in zip(MOTION_AXES, self.motion)},
            }
        return {
            f.name: list(v) if isinstance(v := getattr(self, f.name), tuple) else v
            for f in fields(self)
            if f.name != "motion"
        }


def rotate(theta: Any, v: np.ndarray) -> np.ndarray:
    """R(theta) v for body-frame vectors v (..., 2) (m), counter-clockwise theta (rad)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def root_state(
    base: Base, position: Any, velocity: Any, attitude: Any, rate: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Node 0's position r_0 = r_c + rho (m) and velocity v_0 = v_c + theta' k x rho (m/s),
    rho = R(theta) hinge_offset, from the body's centre of mass r_c, v_c (..., 2), attitude
    theta (rad) and rate theta' (rad/s) (...); each (..., 2)."""
    rho = rotate(np.asarray(attitude), np.asarray(base.hinge_offset, float))
    perp = np.stack([-rho[..., 1], rho[..., 0]], axis=-1)  # k x rho
    return np.asarray(position) + rho, np.asarray(velocity) + np.asarray(rate)[..., None] * perp


#: The default base: node 0 pinned at the origin.
PINNED = Base()
