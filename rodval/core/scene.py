"""What to simulate: the chain, its loads, its initial state, the horizon and the outputs.

Conventions (used throughout rodval)
-----------------------------------
* Rods k = 1..n join node k-1 to node k; node 0 is pinned at the origin, or belongs to a free
  body (``Scene.base``, ``rodval.core.base``). Arrays indexed by rod
  are 0-based numpy arrays of length n (entry i is rod i+1).
* ``phi_k`` (rad) is the angle of the chord node k-1 -> node k from the global x axis,
  counter-clockwise positive. ``alpha_k``, ``beta_k`` (rad) are the angles from that chord to
  the bent rod's tangent at its left (node k-1) and right (node k) end, counter-clockwise
  positive. ``dphi`` is d(phi)/dt in rad/s.
* Hinge k (k = 0..n-1) sits at node k, between rod k and rod k+1 (hinge 0: ground and rod 1).
  ``kappa[i]``, ``nu[i]`` belong to hinge i. The tip node n has no hinge.
* ``mu[i]`` (kg) is the point mass at node i+1.
* Units: m, kg, s, N, rad. ``m`` is mass per length (kg/m), ``EI`` in N m^2, ``kappa`` in
  N m/rad, ``nu`` in N m s/rad, ``bending_damping`` in N m^2 s.
* A rod's bending moment is EI kappa_b + bending_damping dkappa_b/dt (Kelvin-Voigt material
  damping; kappa_b the curvature, 1/m), the same law in every model (docs/model.md).
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from rodval.core.base import PINNED, Base
from rodval.core.bounds import as_rod_array
from rodval.core.checks import check_keys, check_number
from rodval.core.damping import DampingRequest
from rodval.core.hinges import HINGE_ITEMS, HingeTorque
from rodval.core.hinges import CompliantLatch as CompliantLatch
from rodval.core.hinges import Latch as Latch  # re-exported: a scene's items
from rodval.core.hinges import Motor as Motor
from rodval.core.hinges import RateDamper as RateDamper
from rodval.core.hinges import Stop as Stop
from rodval.core.loads import NodalForce
from rodval.core.quantities import GROUPS, OUTPUTS, UNIT, check_output_bases, quantities_of
from rodval.core.resources import check_rods, check_run_memory

#: Quantities a scene may ask for (the outputs of ``rodval.core.quantities.QUANTITY_TABLE``,
#: where each is declared once: unit, k, definition, bases, models). "x"/"y" are node
#: positions (k = 0..n); "energy" yields kinetic, potential and total energy (k = 0);
#: "angular_momentum" (N m s, counter-clockwise positive) has k = 0: H about the root node and
#: k = 1: H about the centre of mass (the whole system's, a free base's body included);
#: "momentum" (N s): the whole system's linear momentum (k = 0, 1: x, y). "base" (a moving
#: base only) yields base_position, base_velocity, base_attitude and base_rate; "drive" (a
#: prescribed base only) drive_force and drive_moment; docs/quantities.md.
QUANTITIES: tuple[str, ...] = OUTPUTS
#: What the group outputs ("energy", "base", "drive") yield in a trajectory.
EXPANDS: dict[str, tuple[str, ...]] = GROUPS
#: Units of every trajectory quantity (the energy audit adds work, dissipated, residual).
UNITS: dict[str, str] = UNIT


def trajectory_quantities(outputs: Iterable[str]) -> tuple[str, ...]:
    """The trajectory quantities a scene's ``outputs`` produce: "energy" and "base" yield
    their parts (``EXPANDS``); the others themselves."""
    return quantities_of(outputs)


#: ``Chain.uniform``'s values where a field is not given (the paper's example, SI units).
UNIFORM_DEFAULTS: dict[str, float] = dict(
    l=2.0, m=3.0, EI=1e5, mu=3.0, kappa=100.0, nu=0.01, rest_angle=0.0, bending_damping=0.0
)


#: Each chain field's words in messages and its sign (``as_rod_array``'s ``positive``: True
#: > 0, False >= 0, None any finite value).
_FIELD_CHECKS: dict[str, tuple[str, bool | None]] = {
    "l": ("l (rod length)", True),
    "m": ("m (mass per length)", True),
    "EI": ("EI (bending stiffness)", True),
    "mu": ("mu (node mass)", False),
    "kappa": ("kappa (hinge stiffness)", False),
    "nu": ("nu (hinge damping)", False),
    "rest_angle": ("rest_angle (hinge rest angle, rad)", None),
    "bending_damping": ("bending_damping (rod bending damping, N m^2 s)", False),
}


@dataclass(frozen=True, eq=False)
class Chain:
    """Physical data of a plane chain of n rods (see module docstring for conventions).

    Scalars are broadcast to all rods/nodes/hinges. ``rest_angle[i]`` (rad) is the angle at
    which hinge i's spring is relaxed: its moment is kappa_i (D_i - rest_angle_i), so a chain
    that starts away from its rest angles (stowed) is pre-stressed.
    """

    l: np.ndarray
    m: np.ndarray
    EI: np.ndarray
    mu: np.ndarray
    kappa: np.ndarray
    nu: np.ndarray
    rest_angle: np.ndarray
    bending_damping: np.ndarray

    #: The per-rod / per-hinge arrays, in order.
    FIELDS = tuple(_FIELD_CHECKS)

    @classmethod
    def uniform(cls, n: int, **values: Any) -> Chain:
        """Chain of n rods; each field (``FIELDS``) a scalar or a length-n sequence, the paper's
        example values (``UNIFORM_DEFAULTS``) where not given."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"n (number of rods) must be an integer >= 1, got {n!r}")
        check_keys(values, cls.FIELDS, "Chain.uniform", noun="field")
        return cls(**{**UNIFORM_DEFAULTS, **values}, _n=int(n))

    def __init__(
        self,
        l: Any,
        m: Any,
        EI: Any,
        mu: Any,
        kappa: Any,
        nu: Any,
        rest_angle: Any = 0.0,
        bending_damping: Any = 0.0,
        _n: int | None = None,
        **unknown: Any,
    ) -> None:
        check_keys(unknown, self.FIELDS, "Chain", noun="field")  # a ValueError, not TypeError
        given = dict(zip(self.FIELDS, (l, m, EI, mu, kappa, nu, rest_angle, bending_damping)))
        n = _n
        if n is None:
            sizes = [np.size(v) for v in given.values() if np.ndim(v) > 0]
            n = sizes[0] if sizes else 1
        n = int(check_number("n (number of rods)", n, integer=True))
        if n < 1:
            raise ValueError(f"n (number of rods) must be >= 1, got {n}")
        check_rods(n)  # before any n-sized array
        for name, (words, positive) in _FIELD_CHECKS.items():
            object.__setattr__(self, name, as_rod_array(words, given[name], n, positive=positive))

    @property
    def n(self) -> int:
        n: int = self.l.shape[0]
        return n

    @property
    def damped(self) -> bool:
        """Whether any hinge damper or rod bending damping acts (the models skip the damping
        terms otherwise)."""
        return bool(np.any(self.nu > 0) or np.any(self.bending_damping > 0))

    def as_dict(self) -> dict[str, list[float]]:
        return {k: getattr(self, k).tolist() for k in self.FIELDS}

    def with_(self, **changes: Any) -> Chain:
        """A copy with some fields replaced (scalars broadcast); an unknown field is refused."""
        check_keys(changes, self.FIELDS, "Chain.with_", noun="field")
        d = {k: getattr(self, k) for k in self.FIELDS}
        d.update(changes)
        return Chain(**d, _n=self.n)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Chain) and all(
            np.array_equal(getattr(self, k), getattr(other, k)) for k in self.FIELDS
        )

    def __hash__(self) -> int:  # pragma: no cover - frozen dataclass with arrays
        return hash(tuple(getattr(self, k).tobytes() for k in self.FIELDS))


@dataclass(frozen=True, eq=False)
class InitialState:
    """Initial generalized coordinates and rates; ``None`` means zeros (straight, at rest).

    A model that has no bending coordinates (the reduced model) ignores alpha/beta entries.
    """

    phi: np.ndarray | None = None
    dphi: np.ndarray | None = None
    alpha: np.ndarray | None = None
    beta: np.ndarray | None = None
    dalpha: np.ndarray | None = None
    dbeta: np.ndarray | None = None

    #: The coordinates and rates, in order.
    KEYS = ("phi", "dphi", "alpha", "beta", "dalpha", "dbeta")

    def __init__(
        self,
        phi: Any = None,
        dphi: Any = None,
        alpha: Any = None,
        beta: Any = None,
        dalpha: Any = None,
        dbeta: Any = None,
        **unknown: Any,
    ) -> None:
        """Each a scalar (rad, rad/s), a sequence of n, or None (zeros); an unknown keyword
        is a ValueError naming it and the allowed keys."""
        check_keys(unknown, self.KEYS, "InitialState")
        given = (phi, dphi, alpha, beta, dalpha, dbeta)
        for key, value in zip(self.KEYS, given):
            object.__setattr__(self, key, value)

    def resolve(self, n: int) -> dict[str, np.ndarray]:
        """Every coordinate and rate as an array of n (zeros where None), checked."""
        out = {}
        for key in self.KEYS:
            v = getattr(self, key)
            if v is None:
                out[key] = np.zeros(n)
                continue
            out[key] = as_rod_array(f"initial {key}", v, n, positive=None)
        return out


def hinge_angles(
    phi: np.ndarray, alpha: np.ndarray, beta: np.ndarray, attitude: Any = None
) -> np.ndarray:
    """Hinge angles D_k (rad), k = 0..n-1: D_k = (phi_{k+1} + alpha_{k+1}) - (phi_k + beta_k),
    phi_0 + beta_0 = the base's attitude theta (hinge 0 measures rod 1's root tangent from
    the body frame; ``attitude`` None: a pinned base, theta = 0). Arrays may carry leading
    axes (..., n); ``attitude`` (...) those axes. Of rates, the hinge rates."""
    left = np.concatenate([np.zeros(phi.shape[:-1] + (1,)), (phi + beta)[..., :-1]], axis=-1)
    if attitude is not None:
        left[..., 0] = attitude
    angles: np.ndarray = (phi + alpha) - left
    return angles


#: Output times when a scene gives none, and the most a scene may ask for.
DEFAULT_NUM_TIMES = 201
MAX_TIMES = 1_000_000


def output_times(start: float, stop: float, num: int) -> np.ndarray:
    """``num`` equally spaced output times from ``start`` to ``stop`` (s), each the shortest
    decimal within 1e-12 s of the exact grid value (no float noise such as 0.30000000000000004
    in tables), the end points exact."""
    grid = np.linspace(start, stop, num)
    clean = np.array([float(f"{t:.12g}") for t in grid]) if num <= 100_000 else np.round(grid, 12)
    clean[0], clean[-1] = start, stop
    return clean


@dataclass(frozen=True)
class Grid:
    """Output times given as a grid: ``num`` equally spaced from ``start`` to ``stop`` (s;
    None: the scene's t_end), resolved by the Scene once its horizon is checked (a scene
    file's ``times = { start, stop, num }``)."""

    start: float = 0.0
    stop: float | None = None
    num: int = DEFAULT_NUM_TIMES


def _times_array(value: Any) -> np.ndarray:
    """Output times as given: a 1-D sequence of real numbers (s), nothing converted."""
    if isinstance(value, (str, bytes, dict, set)) or np.ndim(value) != 1:
        raise ValueError(f"times (output times) must be a 1-D sequence of seconds, got {value!r}")
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"times (output times) must be real numbers (s), got {value!r}")
    if arr.size > MAX_TIMES:
        raise ValueError(f"times (output times): at most {MAX_TIMES}, got {arr.size}")
    return arr.astype(float)


def _scene_loads(loads: Any, n: int) -> tuple[NodalForce, ...]:
    """The scene's loads as a tuple of NodalForce on nodes 1..n (ValueError otherwise)."""
    if isinstance(loads, (str, bytes, dict)) or not isinstance(loads, Iterable):
        raise ValueError(
            f"loads must be a sequence of NodalForce (e.g. () for none), got {loads!r}"
        )
    out = tuple(loads)
    for f in out:
        if not isinstance(f, NodalForce):
            raise ValueError(f"loads must be NodalForce objects, got {type(f).__name__}")
        if f.node > n:
            raise ValueError(f"load node must be in 1..n = 1..{n}, got {f.node}")
    return out


def _scene_times(times: Any, t_end: float) -> np.ndarray:
    """The output times (s) as a read-only array: finite, strictly increasing, in
    [0, t_end]; a ``Grid`` is resolved on the horizon, None gives the default grid."""
    if times is None:
        times = Grid()
    if isinstance(times, Grid):
        stop = t_end if times.stop is None else times.stop
        arr = output_times(float(times.start), float(stop), times.num)
    else:
        arr = _times_array(times)
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError("times (output times) must be a non-empty 1-D sequence of seconds")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"times (output times) must be finite, got {arr.tolist()}")
    if np.any(np.diff(arr) <= 0):
        raise ValueError("times (output times) must be strictly increasing")
    if arr[0] < 0 or arr[-1] > t_end * (1 + 1e-12):
        raise ValueError(
            f"times (output times) must lie in [0, t_end] = [0, {t_end}], got [{arr[0]}, {arr[-1]}]"
        )
    arr = arr.copy()
    arr.setflags(write=False)
    return arr


def _scene_outputs(outputs: Any) -> tuple[str, ...]:
    """The requested quantities as a tuple without repeats (a single name allowed)."""
    if isinstance(outputs, Iterable) and not isinstance(outputs, str | list | tuple | dict):
        outputs = tuple(outputs)
    if not isinstance(outputs, str | list | tuple):
        raise ValueError(f"outputs must be a non-empty subset of {QUANTITIES}, got {outputs!r:.60}")
    names = (outputs,) if isinstance(outputs, str) else tuple(outputs)
    bad = [q for q in names if q not in QUANTITIES]
    if bad or not names:
        raise ValueError(f"outputs must be a non-empty subset of {QUANTITIES}, got {list(names)}")
    return tuple(dict.fromkeys(names))


def check_horizon(t_end: Any) -> float:
    """The horizon t_end (s) as a float: a finite real number > 0 (the one check of it; the
    message says "a real number" to a value of another type, "finite and > 0 s" to one out
    of range)."""
    real = isinstance(t_end, numbers.Real) and not isinstance(t_end, bool)
    allowed = "finite and > 0 s" if real else "a real number > 0 s"
    return check_number(
        "t_end (horizon)", t_end, low=0, low_open=True, finite=True, allowed=allowed
    )


@dataclass(frozen=True, eq=False)
class Scene:
    """A complete simulation request: the *what*, independent of any model or integrator.

    Parameters
    ----------
    chain : Chain
    loads : sequence of NodalForce
    t_end : float
        Horizon (s), > 0. Integration runs over [0, t_end].
    times : array_like, optional
        Output times (s), sorted ascending, within [0, t_end]. Default: 201 equally spaced.
    outputs : iterable of str
        Quantities to compute, from ``QUANTITIES``. Nothing else is computed.
    initial : InitialState
    latches : sequence of Latch
        Hinges that lock at an angle (at most one latch per hinge).
    stops : sequence of Stop
        One-sided limit stops in the hinges.
    motors, rate_dampers : sequence of Motor, RateDamper
        Moments across hinges (``rodval.core.hinges.HingeTorque``).
    compliant_latches : sequence of CompliantLatch
        Latches that hold their hinge by a spring-damper once engaged.
    base : Base
        The body node 0 belongs to: pinned at the origin (default) or a free rigid body.
    name : str
    damping : DampingRequest or None
        The bending damping as a scene file stated it, ``{ ratio, of }``
        (``rodval.core.damping``), recorded with the run; the chain holds the c it gives. A
        deployed request's c is 0 until the models layer converts it
        (``DampingRequest.pending``). None: c as given.
    """

    chain: Chain
    loads: tuple[NodalForce, ...] = ()
    t_end: float = 2.0
    #: Output times (s): a sequence or None (the default grid) on input; always a read-only
    #: float array after construction.
    times: Any = None
    outputs: tuple[str, ...] = ("phi", "dphi", "alpha", "beta")
    initial: InitialState = field(default_factory=InitialState)
    name: str = "scene"
    latches: tuple[Latch, ...] = ()
    stops: tuple[Stop, ...] = ()
    motors: tuple[Motor, ...] = ()
    rate_dampers: tuple[RateDamper, ...] = ()
    compliant_latches: tuple[CompliantLatch, ...] = ()
    base: Base = PINNED
    damping: DampingRequest | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise ValueError(f"name (the scene's label) must be a string, got {self.name!r}")
        if not isinstance(self.chain, Chain):
            raise ValueError(f"chain must be a rodval.Chain, got {type(self.chain).__name__}")
        n = self.chain.n
        t_end = check_horizon(self.t_end)
        object.__setattr__(self, "t_end", t_end)
        object.__setattr__(self, "loads", _scene_loads(self.loads, n))
        times = _scene_times(self.times, t_end)
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "outputs", _scene_outputs(self.outputs))
        check_run_memory(
            n,
            times.size,
            trajectory_quantities(self.outputs),
            what=f"scene {self.name!r} (n = {n}, {times.size} output times)",
        )
        if not isinstance(self.initial, InitialState):
            raise ValueError("initial must be a rodval.InitialState")
        self.initial.resolve(n)  # validate now, before any work
        if not isinstance(self.base, Base):
            raise ValueError(f"base must be a rodval.Base, got {type(self.base).__name__}")
        check_output_bases(self.outputs, self.base.kind)
        for table, kind in HINGE_ITEMS.items():  # the field named by each item's table
            object.__setattr__(self, table, kind.check_in(getattr(self, table), self))
        if self.damping is not None and not isinstance(self.damping, DampingRequest):
            raise ValueError(
                "damping must be a rodval.core.damping.DampingRequest or None, got "
                f"{type(self.damping).__name__}"
            )

    @property
    def n(self) -> int:
        return self.chain.n

    def initial_hinge_angles(self) -> np.ndarray:
        """D_k at t = 0 (rad), k = 0..n-1 (hinge 0 from the base's attitude)."""
        init = self.initial.resolve(self.n)
        attitude = self.base.initial_attitude()
        return hinge_angles(init["phi"], init["alpha"], init["beta"], attitude)

    def initial_hinge_rates(self) -> np.ndarray:
        """dD_k/dt at t = 0 (rad/s), k = 0..n-1 (hinge 0 from the base's rate)."""
        init = self.initial.resolve(self.n)
        b = self.base
        rate = b.state_at(0.0)[3] if b.prescribed else (b.rate if b.free else None)
        return hinge_angles(init["dphi"], init["dalpha"], init["dbeta"], rate)

    @property
    def torques(self) -> tuple[HingeTorque, ...]:
        """The items that apply a moment across a hinge (motors, rate dampers), in
        ``HINGE_ITEMS`` order."""
        return tuple(
            item
            for table in HINGE_ITEMS
            for item in getattr(self, table)
            if isinstance(item, HingeTorque)
        )

    @property
    def breakpoints(self) -> np.ndarray:
        """Sorted load kinks strictly inside (0, t_end), where integration restarts."""
        bps = {b for f in self.loads for b in f.breakpoints if 0 < b < self.t_end}
        bps |= {b for b in self.base.breakpoints if 0 < b < self.t_end}
        bps |= {b for item in self.torques for b in item.breakpoints() if 0 < b < self.t_end}
        return np.array(sorted(bps))

    def with_(self, **changes: Any) -> Scene:
        """A copy with fields replaced (validated again); an unknown field is refused."""
        check_keys(changes, (f.name for f in fields(self)), "Scene.with_", noun="field")
        return replace(self, **changes)

    def wants(self, *quantities: str) -> bool:
        return any(q in self.outputs for q in quantities)


def paper_scene(
    n: int = 8,
    *,
    t_end: float = 2.0,
    times: Iterable[float] | None = None,
    outputs: Iterable[str] = ("phi", "dphi", "alpha", "beta"),
    load_node: int | None = None,
    **chain_overrides: Any,
) -> Scene:
    """The example of the paper (section 3): n uniform rods, the pulse at the last node.

    l = 2 m, m = 3 kg/m, mu = 3 kg, EI = 1e5 N m^2, kappa = 100 N m/rad, nu = 0.01 N m s/rad,
    Xbar = -150 N, Ybar = 1200 N, T = 1 s; straight along x at rest; 0 <= t <= 2 T.
    """
    from rodval.core.loads import pulse

    chain = Chain.uniform(n, **chain_overrides)
    node = n if load_node is None else load_node
    return Scene(
        chain=chain,
        loads=(pulse(node),),
        t_end=t_end,
        times=times,
        outputs=outputs,  # type: ignore[arg-type]  # Scene checks it and takes any iterable
        name=f"paper-n{n}",
    )


#: Output times of the paper's Table 1 and Fig. 3 (s).
TABLE1_TIMES = (0.5, 1.0, 1.5, 2.0)
