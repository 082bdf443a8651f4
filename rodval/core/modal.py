"""Results of a modal analysis, shared by the native models' analysis
(``rodval.models.linear_modes``) and the reference model's (``reference_models.exudyn_modes``):
the configuration a model is linearised about, its constant loads, and the modes.

Units: frequencies in rad/s (``omega``) and Hz (``f_hz``); mode shapes as node displacements
(m per unit of the largest node displacement) and hinge angles (rad per the same unit).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from rodval.core.scene import Scene

if TYPE_CHECKING:
    import pandas as pd

#: What a model is linearised about: its initial state at rest (free vibration, loads
#: ignored; it must be an equilibrium, see ``rodval.models.statics.check_at_rest``) or the
#: static equilibrium under the scene's static loads (``static_loads``) and hinge rest angles.
ABOUT = ("initial", "equilibrium")


#: Load laws that settle to a constant when they act for ever (t_off = inf): their value
#: after their last kink is the load a static equilibrium holds.
SETTLING_LAWS = ("constant", "ramp")


@dataclass(frozen=True)
class ConstantLoads:
    """The nodal loads a static solve holds fixed: X, Y (N, per node 1..n, index k - 1),
    their suffix sums SX, SY (N), the instant ``at`` they were taken at (s; None: the loads
    that act for ever, see ``static_loads``), and the scene's loads left out, each with why."""

    SX: np.ndarray
    SY: np.ndarray
    ignored: tuple[str, ...] = ()
    X: np.ndarray | None = None
    Y: np.ndarray | None = None
    at: float | None = None

    @property
    def any(self) -> bool:
        return bool(np.any(self.SX) or np.any(self.SY))


def _force_at(f, t: float) -> tuple[float, float]:
    return (float(f.fx(t)) if f.fx else 0.0, float(f.fy(t)) if f.fy else 0.0)


def static_loads(scene: Scene, at: float | None = None) -> ConstantLoads:
    """The loads a static equilibrium of ``scene`` holds fixed (one definition for every
    model's ``about="equilibrium"``).

    ``at = None``: the loads that act for ever. A load whose support ends (t_off < inf: a
    pulse, a windowed step, a tabulated history) is left out and named with its end time; a
    constant or ramp load acting for ever counts at its final value; any other load acting for
    ever (harmonic, a Python callable) has no static value: ValueError asking for ``at``.
    ``at = t`` (s, finite, >= 0): every load frozen at its value at t; loads not acting at t
    are named. Cost O(loads + n)."""
    n = scene.n
    X, Y = np.zeros(n), np.zeros(n)
    ignored = []
    if at is not None:
        if isinstance(at, bool) or not isinstance(at, (int, float)) or not 0 <= at < np.inf:
            raise ValueError(f"load_at must be a finite time >= 0 s, got {at!r}")
        at = float(at)
    for f in scene.loads:
        what = f"{f.name} load at node {f.node}"
        if at is not None:
            if not f.active(at):
                ignored.append(f"{what} (not acting at t = {at:g} s)")
                continue
            fx, fy = _force_at(f, at)
        elif f.support[1] < np.inf:
            ignored.append(f"{what} (acts only until t = {f.support[1]:g} s)")
            continue
        elif f.name in SETTLING_LAWS:
            fx, fy = _force_at(f, max((f.support[0], *f.breakpoints)))
        else:
            raise ValueError(
                f"the {what} acts for ever without settling to a constant, so the scene has no "
                "static equilibrium of its own; give load_at (--load-at T, s) to hold every "
                "load at its value at time T"
            )
        X[f.node - 1] += fx
        Y[f.node - 1] += fy
    return ConstantLoads(
        np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1], tuple(ignored), X, Y, at
    )


@dataclass
class Equilibrium:
    """A static equilibrium of the full model: q = [phi; alpha; beta] (rad), Newton
    iterations (all load steps), load steps, final residual max |R| (N m), converged."""

    q: np.ndarray
    iterations: int
    load_steps: int
    residual: float
    converged: bool
    loads: ConstantLoads | None = None

    @property
    def phi(self) -> np.ndarray:
        return self.q[: self.q.size // 3]


@dataclass
class Modes:
    """Linearized modes of one model about one configuration.

    omega (rad/s, ascending; negative = unstable), damping (damping ratio, NaN where not
    defined), dx, dy (count, n+1) node displacements of nodes 0..n, hinge (count, n) hinge
    angles D_0..D_{n-1} (rad per unit of the largest node displacement), phi0 (configuration
    chord angles), l (rod lengths), equilibrium (the static solve, when about="equilibrium").
    """

    model: str
    about: str
    omega: np.ndarray
    damping: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    hinge: np.ndarray
    phi0: np.ndarray
    l: np.ndarray
    equilibrium: Equilibrium | None = None
    info: dict = field(default_factory=dict)

    @property
    def f_hz(self) -> np.ndarray:
        return self.omega / (2 * np.pi)

    @property
    def count(self) -> int:
        return self.omega.size

    def shape_vectors(self) -> np.ndarray:
        """(count, 3n+2): [dx; dy; l_mean * D] per mode, the vectors MAC compares."""
        return np.hstack([self.dx, self.dy, float(np.mean(self.l)) * self.hinge])

    def node_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """Node coordinates (m) of the configuration, nodes 0..n."""
        x = np.concatenate([[0.0], np.cumsum(self.l * np.cos(self.phi0))])
        y = np.concatenate([[0.0], np.cumsum(self.l * np.sin(self.phi0))])
        return x, y

    def to_dict(self) -> dict:
        """Plain JSON-ready form (case records); inverse of ``from_dict``."""
        return {
            "model": self.model,
            "about": self.about,
            "omega": self.omega.tolist(),
            "damping": np.where(np.isfinite(self.damping), self.damping, -1.0).tolist(),
            "dx": self.dx.tolist(),
            "dy": self.dy.tolist(),
            "hinge": self.hinge.tolist(),
            "phi0": self.phi0.tolist(),
            "l": self.l.tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict) -> Modes:
        damping = np.asarray(d["damping"], float)
        return cls(
            model=d["model"],
            about=d["about"],
            omega=np.asarray(d["omega"], float),
            damping=np.where(damping < 0, np.nan, damping),
            dx=np.asarray(d["dx"], float).reshape(len(d["omega"]), -1),
            dy=np.asarray(d["dy"], float).reshape(len(d["omega"]), -1),
            hinge=np.asarray(d["hinge"], float).reshape(len(d["omega"]), -1),
            phi0=np.asarray(d["phi0"], float),
            l=np.asarray(d["l"], float),
        )

    def frequencies_frame(self) -> pd.DataFrame:
        import pandas as pd

        return pd.DataFrame(
            {
                "mode": np.arange(1, self.count + 1),
                "omega_rad_s": self.omega,
                "f_hz": self.f_hz,
                "damping_ratio": self.damping,
            }
        )

    def modes_frame(self) -> pd.DataFrame:
        """Tidy: mode, kind (node_dx, node_dy, hinge), k (node 0..n or hinge 0..n-1), value."""
        import pandas as pd

        rows = []
        for kind, arr in (("node_dx", self.dx), ("node_dy", self.dy), ("hinge", self.hinge)):
            m, k = np.meshgrid(np.arange(1, self.count + 1), np.arange(arr.shape[1]), indexing="ij")
            rows.append(
                pd.DataFrame(
                    {"mode": m.ravel(), "kind": kind, "k": k.ravel(), "value": arr.ravel()}
                )
            )
        return pd.concat(rows, ignore_index=True).sort_values(
            ["mode", "kind", "k"], kind="stable", ignore_index=True
        )


def normalize_shapes(dx: np.ndarray, dy: np.ndarray, hinge: np.ndarray):
    """Scale each mode (row) so that the largest node displacement magnitude is 1 (or, if the
    nodes do not move, the largest |hinge angle| is 1) and the largest node-displacement
    component (else hinge angle) is positive."""
    dx, dy, hinge = (np.array(a, float) for a in (dx, dy, hinge))
    for i in range(dx.shape[0]):
        mag = np.hypot(dx[i], dy[i])
        ref = np.concatenate([dx[i], dy[i]])
        if mag.max() <= 1e-12 * max(np.max(np.abs(hinge[i])), 1e-300):
            scale, ref = np.max(np.abs(hinge[i])), hinge[i]
        else:
            scale = mag.max()
        sign = np.sign(ref[np.argmax(np.abs(ref))]) or 1.0
        s = sign / scale if scale > 0 else 1.0
        dx[i] *= s
        dy[i] *= s
        hinge[i] *= s
    return dx, dy, hinge
