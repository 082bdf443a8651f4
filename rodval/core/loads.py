"""Nodal force laws X_k(t), Y_k(t) acting on the chain's nodes.

Units: forces in N, time in s. X is along the global x axis, Y along the global y axis.
A force law may have kinks or jumps at declared ``breakpoints``; the integrator steps exactly
across them instead of smoothing over them. Outside its ``support`` interval a force is
exactly zero and is not evaluated at all.

Each load law is one class that owns both of its forms: its closed form (``__call__``, used
by the scipy path and the reference models) and its rows of the compiled load table
(``rows``, evaluated by ``load_sums`` inside the compiled kernels). A plain Python callable is
a valid component too; a scene with one has no compiled form and runs on the scipy path.
(``rodval.core.load_table``: its columns, codes and the compiled evaluation).
"""

from __future__ import annotations

import csv
import math
import numbers
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rodval.core.checks import as_path, check_number, check_reals, check_type
from rodval.core.load_table import (
    LAW_CONSTANT,
    LAW_HARMONIC,
    LAW_LINEAR,
    LAW_RAISED_COSINE,
    Row,
)
from rodval.core.status import exception_line

ForceLaw = Callable[[float], float]


def _real(where: str, value: Any, unit: str, *, positive: bool = False) -> float:
    """A finite real number (> 0 when ``positive``) in ``unit``: ``check_number``."""
    return check_number(
        where, value, unit=unit, finite=True, low=0 if positive else -math.inf, low_open=True
    )


class Law(ABC):
    """A scalar force history f(t) (N) with its compiled rows."""

    @abstractmethod
    def __call__(self, t: float) -> float:
        """f(t) in N (called only inside the force's support)."""

    @abstractmethod
    def rows(self) -> list[Row]:
        """The law as compiled rows (law code, t0, t1, right_closed, p0, p1, p2)."""


@dataclass(frozen=True)
class Constant(Law):
    """f = value on [t0, t1]."""

    value: float
    t0: float = 0.0
    t1: float = math.inf

    def __call__(self, t: float) -> float:
        return self.value

    def rows(self) -> list[Row]:
        return [(LAW_CONSTANT, self.t0, self.t1, True, self.value, 0.0, 0.0)]


@dataclass(frozen=True)
class RaisedCosine(Law):
    """f = amp (1/2 - 1/2 cos(omega t)) on [0, t1] (the paper's pulse components)."""

    amp: float
    omega: float
    t1: float

    def __call__(self, t: float) -> float:
        return self.amp * (0.5 - 0.5 * math.cos(self.omega * t)) if t <= self.t1 else 0.0

    def rows(self) -> list[Row]:
        return [(LAW_RAISED_COSINE, 0.0, self.t1, True, self.amp, self.omega, 0.0)]


@dataclass(frozen=True)
class Harmonic(Law):
    """f = amp sin(omega t + phase) on [t0, t1]."""

    amp: float
    omega: float
    phase: float
    t0: float = 0.0
    t1: float = math.inf

    def __call__(self, t: float) -> float:
        return self.amp * math.sin(self.omega * t + self.phase)

    def rows(self) -> list[Row]:
        return [(LAW_HARMONIC, self.t0, self.t1, True, self.amp, self.omega, self.phase)]


@dataclass(frozen=True, eq=False)
class PiecewiseLinear(Law):
    """f interpolated linearly between samples (t_i, f_i), t strictly increasing; zero
    outside [t_0, t_last] (its support). Its kinks t_i are breakpoints. ``hold`` keeps the
    last value after t_last (a ramp that holds), up to t_end of the support."""

    t: np.ndarray
    f: np.ndarray
    hold: bool = False

    def __call__(self, t: float) -> float:
        return float(np.interp(t, self.t, self.f))

    def rows(self) -> list[Row]:
        out: list[Row] = []
        last = self.t.size - 2
        for i in range(self.t.size - 1):
            slope = (self.f[i + 1] - self.f[i]) / (self.t[i + 1] - self.t[i])
            closed = i == last and not self.hold
            out.append(
                (
                    LAW_LINEAR,
                    float(self.t[i]),
                    float(self.t[i + 1]),
                    closed,
                    float(self.f[i]),
                    float(slope),
                    0.0,
                )
            )
        if self.hold:
            out.append(
                (LAW_CONSTANT, float(self.t[-1]), math.inf, True, float(self.f[-1]), 0.0, 0.0)
            )
        return out


@dataclass(frozen=True)
class NodalForce:
    """A force acting on one node of the chain.

    Parameters
    ----------
    node : int
        Node index k = 1..n (node 0 is the pinned root and carries no load).
    fx, fy : Law or callable t -> float, optional
        Components X_k(t), Y_k(t) in N. ``None`` means identically zero. A ``Law`` has a
        compiled form; a plain callable runs on the scipy path only.
    support : (t0, t1)
        The force is zero outside [t0, t1] (s); it is not evaluated there.
    breakpoints : tuple of float
        Times (s) where the law has kinks or jumps.
    name : str
        The law's name in scene files and reports ("callable" for a Python function).
    params : dict
        The named parameters the law was built from (scene files, run records).
    """

    node: int
    fx: ForceLaw | None = None
    fy: ForceLaw | None = None
    support: tuple[float, float] = (0.0, math.inf)
    breakpoints: tuple[float, ...] = ()
    name: str = "callable"
    params: dict[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if isinstance(self.node, bool) or not isinstance(self.node, numbers.Integral):
            raise ValueError(f"load node must be an integer >= 1, got {self.node!r}")
        if self.node < 1:
            raise ValueError(f"load node must be >= 1 (node 0 is the pinned root), got {self.node}")
        for label, f in (("fx", self.fx), ("fy", self.fy)):
            if f is not None and not callable(f):
                raise ValueError(f"load {label} must be callable t -> float or None, got {f!r}")
        if not (isinstance(self.support, tuple) and len(self.support) == 2):
            raise ValueError(
                f"load support must be a pair (t0, t1) of seconds, got {self.support!r}"
            )
        t0, t1 = check_reals("load support", self.support, "real numbers (s)")
        check_type("load breakpoints", self.breakpoints, (tuple, list), "a tuple of seconds")
        if not (math.isfinite(t0) and t0 >= 0 and t1 > t0):
            raise ValueError(f"load support must satisfy 0 <= t0 < t1, got {self.support}")
        for b in check_reals("load breakpoints", self.breakpoints, "real numbers (s)"):
            if b < 0 or not math.isfinite(b):
                raise ValueError(
                    f"load breakpoints must be finite and >= 0, got {self.breakpoints}"
                )

    def active(self, t: float) -> bool:
        return self.support[0] <= t <= self.support[1]

    def rows(self) -> list[tuple[float, ...]] | None:
        """This force's rows of the compiled load table, or None when a component is a plain
        callable (no compiled form)."""
        out: list[tuple[float, ...]] = []
        for comp, f in ((0, self.fx), (1, self.fy)):
            if f is None:
                continue
            if not isinstance(f, Law):
                return None
            for law, a, b, closed, p0, p1, p2 in f.rows():
                a, b = max(a, self.support[0]), min(b, self.support[1])
                if b > a or (closed and b == a):
                    out.append((self.node - 1, comp, law, a, b, float(closed), p0, p1, p2))
        return out


def _real_or_inf(where: str, value: Any) -> float:
    return check_number(where, value, allowed="real numbers (s)")


def pulse(node: int, Xbar: float = -150.0, Ybar: float = 1200.0, T: float = 1.0) -> NodalForce:
    """The paper's load pulse at ``node`` (section 3, Table 1).

    X(t) = Xbar (1/2 - 1/2 cos(4 pi t / T)) for 0 <= t <= T/2, else 0;
    Y(t) = Ybar (1/2 - 1/2 cos(2 pi t / T)) for 0 <= t <= T,   else 0.
    Both components are C1 at t = 0 but have kinks at T/2 (X) and T (Y).
    """
    Xbar, Ybar = _real("pulse Xbar", Xbar, "N"), _real("pulse Ybar", Ybar, "N")
    T = _real("pulse T", T, "s", positive=True)
    return NodalForce(
        node,
        RaisedCosine(Xbar, 4.0 * math.pi / T, 0.5 * T),
        RaisedCosine(Ybar, 2.0 * math.pi / T, T),
        support=(0.0, T),
        breakpoints=(0.5 * T, T),
        name="pulse",
        params={"Xbar": Xbar, "Ybar": Ybar, "T": T},
    )


def _kinks(*times: float) -> tuple[float, ...]:
    """The switching times that are breakpoints: finite and after t = 0 (s)."""
    return tuple(b for b in times if math.isfinite(b) and b > 0)


def _switch_times(kind: str, t_on: Any, t_off: Any) -> tuple[float, float]:
    t_on = _real(f"{kind} t_on", t_on, "s")
    t_off = _real_or_inf(f"{kind} t_off (s)", t_off)
    if not (0 <= t_on < t_off):
        raise ValueError(f"{kind} load needs 0 <= t_on < t_off, got t_on = {t_on}, t_off = {t_off}")
    return t_on, t_off


def _switched(
    name: str, node: int, X: Any, Y: Any, law: Callable[[float], Law], **params: float
) -> NodalForce:
    """The force ``name`` on ``node`` with the components law(X), law(Y) (X, Y in N, checked
    here; none where zero) acting on [t_on, t_off] (s, in ``params``), with kinks at its
    switching times (the parameters t_*); its params X, Y, then ``params``."""
    X, Y = _real(f"{name} X", X, "N"), _real(f"{name} Y", Y, "N")
    return NodalForce(
        node,
        law(X) if X else None,
        law(Y) if Y else None,
        support=(params["t_on"], params["t_off"]),
        breakpoints=_kinks(*(v for k, v in params.items() if k.startswith("t_"))),
        name=name,
        params={"X": X, "Y": Y, **params},
    )


def constant(
    node: int, X: float = 0.0, Y: float = 0.0, t_on: float = 0.0, t_off: float = math.inf
) -> NodalForce:
    """A constant force (X, Y) in N switched on at ``t_on`` and off at ``t_off`` (s): a step
    load (t_on > 0) or a constant one."""
    t_on, t_off = _switch_times("constant", t_on, t_off)
    return _switched(
        "constant", node, X, Y, lambda v: Constant(v, t_on, t_off), t_on=t_on, t_off=t_off
    )


def ramp(
    node: int,
    X: float = 0.0,
    Y: float = 0.0,
    t_on: float = 0.0,
    t_full: float = 1.0,
    t_off: float = math.inf,
) -> NodalForce:
    """A force rising linearly from 0 at ``t_on`` to (X, Y) N at ``t_full``, then held until
    ``t_off`` (s). Kinks at t_on and t_full, a jump at t_off."""
    t_on, t_off = _switch_times("ramp", t_on, t_off)
    t_full = _real("ramp t_full", t_full, "s")
    if not (t_on < t_full <= t_off):
        raise ValueError(
            f"ramp load needs t_on < t_full <= t_off, got t_on = {t_on}, "
            f"t_full = {t_full}, t_off = {t_off}"
        )
    times = np.array([t_on, t_full])

    def law(v: float) -> PiecewiseLinear:
        return PiecewiseLinear(times, np.array([0.0, v]), hold=True)

    return _switched("ramp", node, X, Y, law, t_on=t_on, t_full=t_full, t_off=t_off)


def harmonic(
    node: int,
    X: float = 0.0,
    Y: float = 0.0,
    omega: float = 1.0,
    phase: float = 0.0,
    t_on: float = 0.0,
    t_off: float = math.inf,
) -> NodalForce:
    """A harmonic force (X, Y) sin(omega t + phase) in N, omega in rad/s, phase in rad, acting
    on [t_on, t_off] (s)."""
    omega = _real("harmonic omega", omega, "rad/s", positive=True)
    phase = _real("harmonic phase", phase, "rad")
    t_on, t_off = _switch_times("harmonic", t_on, t_off)

    def law(v: float) -> Harmonic:
        return Harmonic(v, omega, phase, t_on, t_off)

    return _switched("harmonic", node, X, Y, law, omega=omega, phase=phase, t_on=t_on, t_off=t_off)


#: Largest number of samples of a tabulated force history.
MAX_SAMPLES = 1_000_000


def tabulated(
    node: int,
    t: Sequence[float] | None = None,
    X: Sequence[float] | None = None,
    Y: Sequence[float] | None = None,
    file: str | Path | None = None,
) -> NodalForce:
    """A measured or specified force history: X(t), Y(t) in N linearly interpolated between
    samples at strictly increasing times t (s), zero outside [t_0, t_last]. Either arrays
    ``t`` with ``X`` and/or ``Y``, or ``file``: a CSV file with a header row naming the
    columns ``t``, ``X``, ``Y`` (X or Y may be missing: zero). Every sample time inside the
    support is a breakpoint."""
    if file is not None:
        if t is not None or X is not None or Y is not None:
            raise ValueError("tabulated load: give either file or t with X/Y, not both")
        t, X, Y = _read_history(as_path("tabulated file", file))
    if t is None or (X is None and Y is None):
        raise ValueError("tabulated load needs t and at least one of X, Y (or file)")
    tt = _samples("tabulated t (s)", t)
    if tt.size < 2 or tt.size > MAX_SAMPLES:
        raise ValueError(f"tabulated t must have 2 to {MAX_SAMPLES} samples, got {tt.size}")
    if tt[0] < 0 or np.any(np.diff(tt) <= 0):
        raise ValueError("tabulated t must be >= 0 and strictly increasing")
    laws: list[PiecewiseLinear | None] = []
    params: dict[str, Any] = {"t": tt.tolist()}
    for label, v in (("X", X), ("Y", Y)):
        if v is None:
            laws.append(None)
            continue
        arr = _samples(f"tabulated {label} (N)", v)
        if arr.shape != tt.shape:
            raise ValueError(
                f"tabulated {label} must have one value per time ({tt.size}), got {arr.size}"
            )
        laws.append(PiecewiseLinear(tt, arr))
        params[label] = arr.tolist()
    return NodalForce(
        node,
        laws[0],
        laws[1],
        support=(float(tt[0]), float(tt[-1])),
        breakpoints=tuple(float(b) for b in tt if b > 0),
        name="tabulated",
        params=params,
    )


def _samples(where: str, values: Any) -> np.ndarray:
    arr = np.asarray(values)
    if arr.ndim != 1 or arr.dtype.kind not in "iuf":
        raise ValueError(f"{where} must be a 1-D sequence of real numbers")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where} must be finite")
    return arr


def _read_history(path: Path) -> tuple[list[float], list[float] | None, list[float] | None]:
    """The columns t, X, Y of a tabulated-load CSV file (header row naming them, one number
    per column on every later row); ValueError naming the file, and the row and column of the
    first bad cell, for anything else (a binary file, a ragged row, a word among numbers)."""
    if not path.is_file():
        raise ValueError(f"tabulated load file {str(path)!r} does not exist")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(
            f"{path}: not a text CSV file (byte {exc.start} is not UTF-8 text); a tabulated load "
            "file is text: a header row t, X, Y and one row of numbers per sample"
        ) from None
    if "\x00" in text:
        raise ValueError(f"{path}: not a text CSV file (it holds NUL bytes)")
    rows = [r for r in csv.reader(text.splitlines()) if r]
    if not rows or "t" not in [c.strip() for c in rows[0]]:
        raise ValueError(f"{path}: the first row must name the columns t, X, Y")
    head = [c.strip() for c in rows[0]]
    unknown = sorted(set(head) - {"t", "X", "Y"})
    if unknown:
        raise ValueError(f"{path}: unknown column {unknown[0]!r} (allowed: t, X, Y)")
    twice = sorted({c for c in head if head.count(c) > 1})
    if twice:
        raise ValueError(f"{path}: column {twice[0]!r} named twice (each of t, X, Y at most once)")
    data = np.empty((len(rows) - 1, len(head)))
    for i, row in enumerate(rows[1:]):
        if len(row) != len(head):
            raise ValueError(
                f"{path}: row {i + 2} has {len(row)} cells, the header names {len(head)} "
                f"({', '.join(head)}); every row must have one number per column"
            )
        for j, cell in enumerate(row):
            try:
                data[i, j] = float(cell)
            except ValueError:
                raise ValueError(
                    f"{path}: row {i + 2}, column {head[j]}: {cell.strip()!r} is not a number"
                ) from None
    col = {name: data[:, i].tolist() for i, name in enumerate(head)}
    return col["t"], col.get("X"), col.get("Y")


#: Scene-file load types -> factory (the keys of each table are the factory's arguments).
LOAD_FACTORIES: dict[str, Callable[..., NodalForce]] = {
    "pulse": pulse,
    "constant": constant,
    "ramp": ramp,
    "harmonic": harmonic,
    "tabulated": tabulated,
}


class LoadSet:
    """All nodal forces of a scene, evaluated together by their closed forms.

    ``suffix_sums(t)`` returns (SX, SY) with SX[k] = sum_{j >= k} X_j (rods k = 1..n, 0-based
    arrays of length n), or ``None`` when no force is active at t, so that a model can skip
    the generalized-force term entirely.
    """

    def __init__(self, loads: Sequence[NodalForce], n: int, torques: Sequence[Any] = ()):
        self.n = n
        self.loads = tuple(loads)
        self.support_end = max((f.support[1] for f in self.loads), default=-math.inf)
        #: the hinge items applying moments (``rodval.core.hinges.HingeTorque``)
        self.torques = tuple(torques)

    def hinge_moments(self, t: float, rates: np.ndarray) -> np.ndarray | None:
        """The moments across the hinges (N m, positive driving D up; ``HingeTorque.moment``)
        at t and the hinge rates ``rates`` (rad/s), or None without torque items: the
        closed form of ``hinge_torques``/``applied_torques``."""
        if not self.torques:
            return None
        M = np.zeros(self.n)
        for item in self.torques:
            M[item.hinge] += item.moment(t, float(rates[item.hinge]))
        return M

    def nodal(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Nodal forces X, Y (N) at nodes 1..n as arrays of length n, or None if all zero.
        A law that raises, or returns something that is not a finite real number, is a
        ValueError naming the node and the time."""
        if t > self.support_end:
            return None
        X = np.zeros(self.n)
        Y = np.zeros(self.n)
        any_active = False
        for f in self.loads:
            if f.active(t):
                any_active = True
                for label, law, out in (("X", f.fx, X), ("Y", f.fy, Y)):
                    if law is not None:
                        out[f.node - 1] += _evaluate(law, t, f.node, label)
        return (X, Y) if any_active else None

    def suffix_sums(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        xy = self.nodal(t)
        if xy is None:
            return None
        X, Y = xy
        return np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1]


def _evaluate(law: ForceLaw, t: float, node: int, label: str) -> float:
    try:
        v = law(t)
    except Exception as exc:  # noqa: BLE001 - a user's callable: named, then reported as data
        raise ValueError(
            f"load {label} at node {node} raised at t = {t:.6g} s: {exception_line(exc)}"
        ) from exc
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
        raise ValueError(
            f"load at node {node} is not finite at t = {t:.6g} s: {label} = {v!r} "
            "(a load law must return a finite real number, N)"
        )
    return float(v)
