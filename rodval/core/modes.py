"""Results of a modal analysis, shared by the native models' analysis
(``rodval.models.observation.linear_modes``) and the reference model's (``reference_models.exudyn_modes``):
the configuration a model is linearised about, its constant loads, and the modes. The
computations that produce them (static loads, rigid-mode split, damping ratios) are in
``rodval.mechanics.modal``.

Units: frequencies in rad/s (``omega``) and Hz (``f_hz``); mode shapes as node displacements
(m per unit of the largest node displacement) and hinge angles (rad per the same unit).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pandas as pd


#: What a model is linearised about: its initial state at rest (free vibration, loads
#: ignored; it must be an equilibrium, see ``rodval.models.observation.statics.check_at_rest``) or the
#: static equilibrium under the scene's static loads (``static_loads``) and hinge rest angles.
ABOUT = ("initial", "equilibrium")


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
    ``rigid``: how many of the first modes are the rigid motions of a chain on a free base
    (translation x, translation y, rotation about the system's centre of mass; omega ~ 0,
    ``split_rigid``), 0 otherwise; the rest are the flexible modes (``flexible``).
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
    info: dict[str, Any] = field(default_factory=dict)
    rigid: int = 0

    @property
    def f_hz(self) -> np.ndarray:
        return self.omega / (2 * np.pi)

    @property
    def count(self) -> int:
        return self.omega.size

    def rows(self, index: Any) -> Modes:
        """The modes ``index`` (a slice or index array) of these, as a Modes (``rigid``
        counting the rigid ones kept)."""
        keep = np.arange(self.count)[index]
        return Modes(
            model=self.model,
            about=self.about,
            omega=self.omega[keep],
            damping=self.damping[keep],
            dx=self.dx[keep],
            dy=self.dy[keep],
            hinge=self.hinge[keep],
            phi0=self.phi0,
            l=self.l,
            equilibrium=self.equilibrium,
            info=self.info,
            rigid=int(np.sum(keep < self.rigid)),
        )

    def flexible(self) -> Modes:
        """The flexible modes only (all of them on a pinned base): the rigid motions of a free
        base (the first ``rigid``) left out, for frequency comparisons."""
        return self if self.rigid == 0 else self.rows(slice(self.rigid, None))

    def shape_vectors(self) -> np.ndarray:
        """(count, 3n+2): [dx; dy; l_mean * D] per mode, the vectors MAC compares."""
        return np.hstack([self.dx, self.dy, float(np.mean(self.l)) * self.hinge])

    def node_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """Node coordinates (m) of the configuration, nodes 0..n."""
        x = np.concatenate([[0.0], np.cumsum(self.l * np.cos(self.phi0))])
        y = np.concatenate([[0.0], np.cumsum(self.l * np.sin(self.phi0))])
        return x, y

    def to_dict(self) -> dict[str, Any]:
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
            "rigid": int(self.rigid),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Modes:
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
            rigid=int(d.get("rigid", 0)),
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
