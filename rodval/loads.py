"""Nodal force laws X_k(t), Y_k(t) acting on the chain's nodes.

Units: forces in N, time in s. X is along the global x axis, Y along the global y axis.
A force law may have kinks (discontinuous derivatives) at declared ``breakpoints``; the
integrator steps exactly across them instead of smoothing over them. Outside its ``support``
interval a force is exactly zero and is not evaluated at all.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

ForceLaw = Callable[[float], float]


@dataclass(frozen=True)
class NodalForce:
    """A force acting on one node of the chain.

    Parameters
    ----------
    node : int
        Node index k = 1..n (node 0 is the pinned root and carries no load).
    fx, fy : callable t -> float, optional
        Components X_k(t), Y_k(t) in N. ``None`` means identically zero.
    support : (t0, t1)
        The force is zero outside [t0, t1] (s); it is not evaluated there.
    breakpoints : tuple of float
        Times (s) where the law has kinks or jumps.
    name : str
        Label used in reports and scene files.
    params : dict
        The named parameters the law was built from (for serialisation).
    """

    node: int
    fx: ForceLaw | None = None
    fy: ForceLaw | None = None
    support: tuple[float, float] = (0.0, math.inf)
    breakpoints: tuple[float, ...] = ()
    name: str = "callable"
    params: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if isinstance(self.node, bool) or not isinstance(self.node, (int, np.integer)):
            raise ValueError(f"load node must be an integer >= 1, got {self.node!r}")
        if self.node < 1:
            raise ValueError(f"load node must be >= 1 (node 0 is the pinned root), got {self.node}")
        for label, f in (("fx", self.fx), ("fy", self.fy)):
            if f is not None and not callable(f):
                raise ValueError(f"load {label} must be callable t -> float or None, got {f!r}")
        t0, t1 = self.support
        if not (math.isfinite(t0) and t0 >= 0 and t1 > t0) or math.isnan(t1):
            raise ValueError(f"load support must satisfy 0 <= t0 < t1, got {self.support}")
        for b in self.breakpoints:
            if not math.isfinite(b) or b < 0:
                raise ValueError(f"load breakpoints must be finite and >= 0, got {self.breakpoints}")

    def active(self, t: float) -> bool:
        return self.support[0] <= t <= self.support[1]


def pulse(node: int, Xbar: float = -150.0, Ybar: float = 1200.0, T: float = 1.0) -> NodalForce:
    """The paper's load pulse at ``node`` (section 3, Table 1).

    X(t) = Xbar (1/2 - 1/2 cos(4 pi t / T)) for 0 <= t <= T/2, else 0;
    Y(t) = Ybar (1/2 - 1/2 cos(2 pi t / T)) for 0 <= t <= T,   else 0.
    Both components are C1 at t = 0 but have kinks at T/2 (X) and T (Y).
    """
    for label, v in (("Xbar", Xbar), ("Ybar", Ybar)):
        if not math.isfinite(v):
            raise ValueError(f"pulse {label} must be finite, got {v}")
    if not (math.isfinite(T) and T > 0):
        raise ValueError(f"pulse T must be a finite period > 0 s, got {T}")
    w_x, w_y, half = 4.0 * math.pi / T, 2.0 * math.pi / T, 0.5 * T

    def fx(t: float) -> float:
        return Xbar * (0.5 - 0.5 * math.cos(w_x * t)) if t <= half else 0.0

    def fy(t: float) -> float:
        return Ybar * (0.5 - 0.5 * math.cos(w_y * t)) if t <= T else 0.0

    return NodalForce(node, fx, fy, support=(0.0, T), breakpoints=(half, T), name="pulse",
                      params={"Xbar": Xbar, "Ybar": Ybar, "T": T})


def constant(node: int, X: float = 0.0, Y: float = 0.0, t_on: float = 0.0,
             t_off: float = math.inf) -> NodalForce:
    """A constant force (X, Y) in N switched on at ``t_on`` and off at ``t_off`` (s)."""
    for label, v in (("X", X), ("Y", Y)):
        if not math.isfinite(v):
            raise ValueError(f"constant load {label} must be finite, got {v}")
    bps = tuple(b for b in (t_on, t_off) if math.isfinite(b) and b > 0)
    return NodalForce(node, (lambda t: X) if X else None, (lambda t: Y) if Y else None,
                      support=(t_on, t_off), breakpoints=bps, name="constant",
                      params={"X": X, "Y": Y, "t_on": t_on, "t_off": t_off})


LOAD_FACTORIES: dict[str, Callable[..., NodalForce]] = {"pulse": pulse, "constant": constant}


class LoadSet:
    """All nodal forces of a scene, evaluated together.

    ``suffix_sums(t)`` returns (SX, SY) with SX[k] = sum_{j >= k} X_j (rods k = 1..n, 0-based
    arrays of length n), or ``None`` when no force is active at t, so that a model can skip
    the generalized-force term entirely.
    """

    def __init__(self, loads: tuple[NodalForce, ...], n: int):
        self.n = n
        self.loads = tuple(loads)
        self.support_end = max((f.support[1] for f in self.loads), default=-math.inf)

    def nodal(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Nodal forces X, Y (N) at nodes 1..n as arrays of length n, or None if all zero."""
        if t > self.support_end:
            return None
        X = np.zeros(self.n)
        Y = np.zeros(self.n)
        any_active = False
        for f in self.loads:
            if f.active(t):
                any_active = True
                if f.fx is not None:
                    X[f.node - 1] += f.fx(t)
                if f.fy is not None:
                    Y[f.node - 1] += f.fy(t)
        if any_active and not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
            bad = int(np.flatnonzero(~(np.isfinite(X) & np.isfinite(Y)))[0]) + 1
            raise ValueError(f"load at node {bad} is not finite at t = {t:.6g} s "
                             f"(X = {X[bad - 1]}, Y = {Y[bad - 1]})")
        return (X, Y) if any_active else None

    def suffix_sums(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        xy = self.nodal(t)
        if xy is None:
            return None
        X, Y = xy
        return np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1]
