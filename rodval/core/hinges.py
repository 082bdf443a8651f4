"""The chain's hinge items: latches (a hinge locks at an angle), one-sided limit stops, motors
and rate dampers (moments across a hinge, ``HingeTorque``). Each is a class registered by its
scene table's name in ``HINGE_ITEMS`` (as the load laws are in ``LOAD_FACTORIES``) that
declares its keys (``KEYS``: the one list, which ``scene_keys.SCENE_KEYS`` reads), its checks
(``__post_init__``; within a scene, ``check_in``) and its scene-file table (``from_tables``,
``as_dict``); a torque item also its moment, closed form and compiled rows. Conventions:
``rodval.core.scene``."""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, ClassVar, Self

from rodval.core.checks import check_keys, check_number
from rodval.core.keys import BOOLEAN, INTEGER, NUMBER, STRING, Key
from rodval.core.keys import TABLE as TABLE_KIND


def _keys(hinge: str, **more: Key) -> dict[str, Key]:
    """An item's keys: ``hinge`` (its allowed values in words) and ``angle``, both required,
    then the kind's own (``more``)."""
    return {
        "hinge": Key(INTEGER, "", hinge, required=True),
        "angle": Key(NUMBER, "rad", "finite", required=True),
        **more,
    }


def _torque_keys(**more: Key) -> dict[str, Key]:
    """A torque item's keys: ``hinge`` (required), then the kind's own (``more``)."""
    return {"hinge": Key(INTEGER, "", "0..n-1", required=True), **more}


@dataclass(frozen=True)
class HingeItem:
    """A part on hinge ``hinge`` (an integer in 0..n-1). A kind is a frozen dataclass
    subclass that sets ``TABLE``, ``NOUN`` and ``KEYS``, extends ``__post_init__`` and
    ``check_in`` with its own checks, and is listed in ``HINGE_ITEMS``."""

    TABLE: ClassVar[str]  # its scene-file table ([[latches]]), the name of its Scene field
    NOUN: ClassVar[str]  # its name in messages ("latch")
    KEYS: ClassVar[dict[str, Key]]  # its scene-file keys: type, unit, range, required

    hinge: int

    def __post_init__(self) -> None:
        hinge = self.hinge
        if isinstance(hinge, bool) or not isinstance(hinge, numbers.Integral) or hinge < 0:
            raise ValueError(f"{self.NOUN} hinge must be an integer >= 0, got {hinge!r}")

    def as_dict(self) -> dict[str, Any]:
        """Its scene-file table (``from_tables`` rebuilds the item from it)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_tables(cls, doc: dict[str, Any], where: str) -> tuple[Self, ...]:
        """The ``[[TABLE]]`` tables of the scene document ``doc`` (their types already
        checked, ``scene_keys.check_types``) as items; a ValueError naming
        ``<where> [[TABLE]] #<i>`` and the key."""
        out = []
        for i, spec in enumerate(doc.get(cls.TABLE, [])):
            place = f"{where} [[{cls.TABLE}]] #{i + 1}"
            check_keys(spec, cls.KEYS, place)
            try:
                out.append(cls(**spec))
            except ValueError as exc:
                raise ValueError(f"{place}: {exc}") from None
        return tuple(out)

    @classmethod
    def check_in(cls, items: Any, scene: Any) -> tuple[Self, ...]:
        """The ``scene``'s ``items`` of this kind as a tuple: objects of this class on hinges
        0..n-1 (ValueError otherwise); a kind adds its checks against the scene."""
        if isinstance(items, (str, bytes, dict)) or not isinstance(items, Iterable):
            raise ValueError(f"{cls.TABLE} must be a sequence of rodval.{cls.__name__}")
        out = tuple(items)
        for item in out:
            if not isinstance(item, cls):
                raise ValueError(
                    f"{cls.TABLE} must be rodval.{cls.__name__} objects, got {type(item).__name__}"
                )
            if item.hinge >= scene.n:
                raise ValueError(
                    f"{cls.NOUN} hinge must be in 0..n-1 = 0..{scene.n - 1}, got {item.hinge}"
                )
        return out


@dataclass(frozen=True)
class AtAngle(HingeItem):
    """An item acting at the hinge angle ``angle`` (rad, finite): latches and stops."""

    angle: float

    def __post_init__(self) -> None:
        super().__post_init__()
        check_number(f"{self.NOUN} angle", self.angle, finite=True, unit="rad")


def _check_direction(noun: str, direction: Any) -> None:
    """A latch's ``direction``: the integer +1 or -1, or None."""
    if direction is not None and (
        isinstance(direction, bool)
        or not isinstance(direction, numbers.Integral)
        or direction not in (1, -1)
    ):
        raise ValueError(
            f"{noun} direction must be the integer +1 or -1, or omitted (None), got {direction!r}"
        )


def _check_ahead(latch: Any, d0: float) -> None:
    """A latch's hinge starts (at D = ``d0`` rad) short of its angle, in its direction."""
    side = int(latch.angle > d0) - int(latch.angle < d0)
    if side == 0 or (latch.direction is not None and side != latch.direction):
        raise ValueError(
            f"{latch.NOUN} on hinge {latch.hinge}: the hinge starts at D = {d0:.6g} rad, at or "
            f"beyond its latch angle {latch.angle:.6g} rad"
            + (f" in direction {latch.direction:+d}" if latch.direction else "")
        )


#: A held latch's hinge must start at its angle (rad) and at rest (rad/s) to this distance: the
#: initial state is on the constraint (round-off of the angles' sums, 1e-12 rad, with room).
HELD_START = 1e-9


@dataclass(frozen=True)
class Latch(AtAngle):
    """A latch on hinge ``hinge`` (0..n-1): the hinge locks when its angle D reaches
    ``angle`` (rad) moving in ``direction`` (+1: D increasing, -1: decreasing; None: towards
    the angle from the initial state). At the lock the hinge's relative rate drops to zero
    (a plastic impact) and D stays at ``angle`` afterwards. ``window`` (s, > 0): the window
    over which the models measure the lock impulse (None: the first bending period of the
    locked segment, ``rodval.mechanics.lock_window``). ``held``: the hinge is held from t = 0 (a
    clamp, or a joint locked before the run: its initial angle must be ``angle`` and its
    initial rate zero); it never fires an event."""

    TABLE = "latches"
    NOUN = "latch"
    KEYS = _keys(
        "0..n-1, one latch per hinge",
        direction=Key(INTEGER, "", "+1 or -1", none=True),
        window=Key(NUMBER, "s", "> 0, finite", none=True),
        held=Key(BOOLEAN),
    )

    direction: int | None = None
    window: float | None = None
    held: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_direction(self.NOUN, self.direction)
        if self.window is not None:
            check_number("latch window", self.window, low=0.0, low_open=True, finite=True, unit="s")
        if not isinstance(self.held, bool):
            raise ValueError(f"latch held must be true or false, got {self.held!r}")

    def as_dict(self) -> dict[str, Any]:
        """Its table, ``held`` only when true (other scenes' records unchanged)."""
        d = super().as_dict()
        if not self.held:
            del d["held"]
        return d

    @classmethod
    def check_in(cls, items: Any, scene: Any) -> tuple[Self, ...]:
        """At most one latch per hinge, each ahead of its hinge's initial angle (rad) in its
        direction; a held latch's hinge at its angle and at rest."""
        latches = super().check_in(items, scene)
        hinges = [latch.hinge for latch in latches]
        if len(set(hinges)) != len(hinges):
            raise ValueError(f"at most one latch per hinge, got hinges {hinges}")
        if not latches:
            return latches
        D0, rate0 = scene.initial_hinge_angles(), scene.initial_hinge_rates()
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
            _check_ahead(latch, d0)
        return latches


@dataclass(frozen=True)
class Stop(AtAngle):
    """A limit stop on hinge ``hinge``: a one-sided spring-damper acting beyond ``angle``
    (rad) on the ``side`` "upper" (D > angle) or "lower" (D < angle), with moment
    -stiffness (D - angle) - damping dD/dt there (N m; stiffness > 0 in N m/rad, damping >= 0
    in N m s/rad)."""

    TABLE = "stops"
    NOUN = "stop"
    KEYS = _keys(
        "0..n-1",
        side=Key(STRING, "", '`"upper"`, `"lower"`'),
        stiffness=Key(NUMBER, "N m/rad", "> 0, <= 1e12"),
        damping=Key(NUMBER, "N m s/rad", ">= 0, <= 1e12"),
    )

    side: str = "upper"
    stiffness: float = 1e4
    damping: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.side not in ("upper", "lower"):
            raise ValueError(f"stop side must be 'upper' or 'lower', got {self.side!r}")
        from rodval.core.bounds import bounded_number  # numpy: not at import (`rodval --help`)

        # an acting stop adds its stiffness to kappa and its damping to nu: the same bounds
        bounded_number("stop stiffness (N m/rad)", self.stiffness, positive=True)
        bounded_number("stop damping (N m s/rad)", self.damping, positive=False)

    def acts(self, D: Any) -> Any:
        """Whether the stop acts at hinge angle(s) ``D`` (rad, a number or an array): D
        beyond ``angle`` on its ``side``, strictly (the one definition every model uses)."""
        return D > self.angle if self.side == "upper" else D < self.angle

    @classmethod
    def check_in(cls, items: Any, scene: Any) -> tuple[Self, ...]:
        """An acting stop adds its stiffness to its hinge's kappa and its damping to nu: the
        sums (all of a hinge's stops acting at once) must stay within the chain's bounds."""
        from rodval.core.bounds import check_bounds

        stops = super().check_in(items, scene)
        for field_name, attr, unit in (
            ("kappa", "stiffness", "N m/rad"),
            ("nu", "damping", "N m s/rad"),
        ):
            total = getattr(scene.chain, field_name).copy()
            for st in stops:
                total[st.hinge] += getattr(st, attr)
            for st in stops:
                check_bounds(
                    f"stop {attr} + {field_name} of hinge {st.hinge} ({unit})",
                    total[st.hinge : st.hinge + 1],
                    positive=False,
                )
        return stops


@dataclass(frozen=True)
class CompliantLatch(AtAngle):
    """A compliant latch on hinge ``hinge`` (0..n-1): when the hinge angle D reaches ``angle``
    (rad) moving in ``direction`` (+1, -1; None: towards the angle from the initial state) it
    engages, without an impact, and holds the hinge thereafter by a spring-damper about its
    angle with free ``play`` (rad >= 0) on either side: beyond angle + play the moment
    -``stiffness`` (D - angle - play) - ``damping`` dD/dt, below angle - play the same about
    angle - play, none inside (stiffness > 0 in N m/rad, damping >= 0 in N m s/rad). Its two
    sides are the stops ``engaged_stops`` gives, so every model that has stops applies it;
    the ideal ``Latch`` is its limit of infinite stiffness."""

    TABLE = "compliant_latches"
    NOUN = "compliant latch"
    KEYS = _keys(
        "0..n-1, one latch per hinge",
        direction=Key(INTEGER, "", "+1 or -1", none=True),
        stiffness=Key(NUMBER, "N m/rad", "> 0, <= 1e12", required=True),
        damping=Key(NUMBER, "N m s/rad", ">= 0, <= 1e12"),
        play=Key(NUMBER, "rad", ">= 0, finite"),
    )

    direction: int | None = None
    stiffness: float = 1e4
    damping: float = 0.0
    play: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_direction(self.NOUN, self.direction)
        check_number("compliant latch play", self.play, low=0.0, finite=True, unit="rad")
        self.engaged_stops()  # the stops' own checks: stiffness > 0, damping >= 0, bounded

    def engaged_stops(self) -> tuple[Stop, Stop]:
        """The two stops (upper, lower) that hold the hinge once the latch has engaged."""
        return (
            Stop(self.hinge, self.angle + self.play, "upper", self.stiffness, self.damping),
            Stop(self.hinge, self.angle - self.play, "lower", self.stiffness, self.damping),
        )

    @classmethod
    def check_in(cls, items: Any, scene: Any) -> tuple[Self, ...]:
        """At most one latch of either kind per hinge, each ahead of its hinge's initial
        angle (rad) in its direction."""
        latches = super().check_in(items, scene)
        hinges = [la.hinge for la in latches] + [la.hinge for la in scene.latches]
        if len(set(hinges)) != len(hinges):
            raise ValueError(
                f"at most one latch (ideal or compliant) per hinge, got hinges {hinges}"
            )
        D0 = scene.initial_hinge_angles()
        for la in latches:
            _check_ahead(la, float(D0[la.hinge]))
        return latches


Row = tuple[float, ...]


@dataclass(frozen=True)
class HingeTorque(HingeItem):
    """An item that applies a moment M(t, dD/dt) (N m) across its hinge, positive driving the
    hinge angle D up (it acts on rod ``hinge`` with +M and on the rod before it, or the
    base, with -M). A kind gives its closed form (``moment``: the exudyn model and the
    Python path evaluate it) and the same law as compiled load-table rows (``rows``:
    components ``COMP_MOMENT`` and ``COMP_RATE``, ``rodval.core.load_table``); every model then
    applies it with its own hinge rate, and the energy audit books its power M dD/dt as
    external work."""

    def moment(self, t: float, rate: float) -> float:
        """M (N m) at time t (s) and hinge rate ``rate`` (rad/s)."""
        raise NotImplementedError

    def rows(self) -> list[Row]:
        """The compiled rows of ``moment`` (``rodval.core.load_table.LOAD_COLUMNS`` without
        track_end)."""
        raise NotImplementedError

    def breakpoints(self) -> tuple[float, ...]:
        """Times (s) where the moment has kinks or jumps."""
        return ()


def _constant_row(hinge: int, component: str, value: float) -> Row:
    """The row of a constant ``component`` ("moment", N m, or "rate", N m s/rad) across
    ``hinge`` (numba is imported with the loads, not at import: `rodval --help`)."""
    from rodval.core.load_table import COMP_MOMENT, COMP_RATE, LAW_CONSTANT

    comp = COMP_MOMENT if component == "moment" else COMP_RATE
    return (hinge, comp, LAW_CONSTANT, 0.0, math.inf, 1.0, value, 0.0, 0.0)


#: The load laws a motor's ``torque`` table may name (its ``value`` is the law's X, in N m).
MOTOR_LAWS = ("constant", "ramp", "harmonic", "tabulated")


@dataclass(frozen=True)
class Motor(HingeTorque):
    """A motor across hinge ``hinge`` (0..n-1) applying the torque M (N m, positive driving
    the hinge angle D up), either a law of time, ``torque`` = a load law's table with the
    torque as ``value`` (``{type = "constant", value = 2.0, t_on = 0.5}``; types
    ``MOTOR_LAWS``, their keys as for ``[[loads]]``), or the torque-speed line of a
    deployment actuator, M = ``stall_torque`` (1 - dD/dt / ``no_load_speed``) (N m > 0,
    rad/s > 0): full torque at rest, none at the no-load speed, braking beyond it (the line
    is not clipped). The energy audit books its work int M dD/dt as external."""

    TABLE = "motors"
    NOUN = "motor"
    KEYS = _torque_keys(
        torque=Key(TABLE_KIND, "N m", "a load law's table with the torque as `value`"),
        stall_torque=Key(NUMBER, "N m", "> 0 (with no_load_speed)"),
        no_load_speed=Key(NUMBER, "rad/s", "> 0 (with stall_torque)"),
    )

    torque: dict[str, Any] | None = None
    stall_torque: float | None = None
    no_load_speed: float | None = None
    #: the force its ``torque`` table's load law builds (``_motor_law``), None for a line
    _law: Any = dataclasses.field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        line = (self.stall_torque, self.no_load_speed)
        if (self.torque is None) == (line == (None, None)):
            raise ValueError(
                "motor needs either torque (a law of time) or stall_torque with "
                "no_load_speed (a torque-speed line), "
                + ("got neither" if self.torque is None else "not both")
            )
        if self.torque is None:
            if None in line:
                raise ValueError("motor stall_torque and no_load_speed go together")
            for name, v, unit in (
                ("stall_torque", self.stall_torque, "N m"),
                ("no_load_speed", self.no_load_speed, "rad/s"),
            ):
                check_number(f"motor {name}", v, low=0.0, low_open=True, finite=True, unit=unit)
        else:
            object.__setattr__(self, "_law", _motor_law(self.torque))

    def moment(self, t: float, rate: float) -> float:
        if self.torque is None:
            assert self.stall_torque is not None and self.no_load_speed is not None
            return self.stall_torque * (1.0 - rate / self.no_load_speed)
        force = self._law
        return float(force.fx(t)) if force.active(t) and force.fx is not None else 0.0

    def rows(self) -> list[Row]:
        if self.torque is None:
            assert self.stall_torque is not None and self.no_load_speed is not None
            return [
                _constant_row(self.hinge, "moment", self.stall_torque),
                _constant_row(self.hinge, "rate", self.stall_torque / self.no_load_speed),
            ]
        from rodval.core.load_table import COMP_MOMENT

        return [(self.hinge, COMP_MOMENT, *row[2:]) for row in self._law.rows() or []]

    def breakpoints(self) -> tuple[float, ...]:
        return () if self.torque is None else self._law.breakpoints

    def as_dict(self) -> dict[str, Any]:
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.init}
        return {k: v for k, v in d.items() if v is not None}


def _motor_law(spec: Any) -> Any:
    """A motor's ``torque`` table as the force its load law builds (on node 1, the torque as
    X; ``rodval.core.loads.LOAD_FACTORIES``); ValueError naming the key."""
    from rodval.core.loads import LOAD_FACTORIES

    if not isinstance(spec, dict) or spec.get("type") not in MOTOR_LAWS:
        raise ValueError(
            f"motor torque must be a table with type one of {', '.join(MOTOR_LAWS)}, got {spec!r}"
        )
    args = {k: v for k, v in spec.items() if k != "type"}
    if "value" not in args:
        raise ValueError("motor torque needs value (the torque in N m)")
    args["X"] = args.pop("value")
    try:
        return LOAD_FACTORIES[spec["type"]](1, **args)
    except ValueError as exc:  # the law's own check, in a motor's words
        words = str(exc).replace(" X ", " value ").replace("(N)", "(N m)")
        raise ValueError(f"motor torque: {words.replace(' load ', ' law ')}") from None
    except TypeError:
        raise ValueError(
            f"motor torque: a {spec['type']} law takes value and its times, got {sorted(spec)}"
        ) from None


@dataclass(frozen=True)
class RateDamper(HingeTorque):
    """A viscous rate damper across hinge ``hinge`` (0..n-1): the moment -``damping`` (dD/dt -
    ``rate``) (N m; damping > 0 in N m s/rad, the set rate in rad/s, default 0: a plain
    viscous deployment damper). Its power is booked with the external work (it may drive the
    hinge towards its set rate)."""

    TABLE = "rate_dampers"
    NOUN = "rate damper"
    KEYS = _torque_keys(
        damping=Key(NUMBER, "N m s/rad", "> 0, <= 1e12", required=True),
        rate=Key(NUMBER, "rad/s", "finite"),
    )

    damping: float = 1.0
    rate: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        from rodval.core.bounds import bounded_number

        bounded_number("rate damper damping (N m s/rad)", self.damping, positive=True)
        check_number("rate damper rate", self.rate, finite=True, unit="rad/s")

    def moment(self, t: float, rate: float) -> float:
        return -self.damping * (rate - self.rate)

    def rows(self) -> list[Row]:
        rows = [_constant_row(self.hinge, "rate", self.damping)]
        if self.rate:
            rows.append(_constant_row(self.hinge, "moment", self.damping * self.rate))
        return rows


#: The hinge items by scene table (and ``Scene`` field) name, in the scene files' order.
HINGE_ITEMS: dict[str, type[HingeItem]] = {
    kind.TABLE: kind for kind in (Latch, Stop, Motor, RateDamper, CompliantLatch)
}
