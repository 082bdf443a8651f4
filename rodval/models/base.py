"""The model interface: every model (native or reference) turns a Scene into a Trajectory."""
from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, Callable, ClassVar

import numpy as np

from ..scene import Scene
from ..settings import IntegratorSettings
from ..trajectory import Trajectory


class Model(ABC):
    """A named model of the chain. Subclasses set ``name`` and implement ``simulate``."""

    name: ClassVar[str]

    @abstractmethod
    def simulate(self, scene: Scene, settings: IntegratorSettings) -> Trajectory:
        """Run the scene; never raise for a failed integration (report it in the stats)."""

    def options(self) -> dict[str, Any]:
        """Model options (recorded beside the solver statistics)."""
        return {}


class OdeSystem(ABC):
    """A first-order ODE y' = f(t, y) built for one scene, plus its observation map."""

    y0: np.ndarray
    #: Analytic Jacobian df/dy (t, y) -> (N, N), or None to let the integrator difference.
    jac: Callable[[float, np.ndarray], np.ndarray] | None = None
    #: Mechanical energy E = T + Pi (J) at one state, (t, y) -> float, or None. Used by the
    #: energy audit (rodval.energy).
    energy: Callable[[float, np.ndarray], float] | None = None
    #: Kinetic energy T (J) at one state, y -> float, or None. Cheap (no bending recovery);
    #: used by the per-step blow-up check (rodval.divergence), valid because Pi >= 0.
    kinetic_energy: Callable[[np.ndarray], float] | None = None
    #: E = T + Pi (J) at one state without bending recovery, y -> float, or None (the
    #: blow-up check's initial budget; for the reduced model exact at rest, see reduced.py).
    stored_energy: Callable[[np.ndarray], float] | None = None
    #: (P_ext, P_diss) (W) at one state, (t, y) -> (float, float), or None: the power of the
    #: applied loads and the power dissipated by the dampers. Integrated along the trajectory
    #: by the energy audit (rodval.energy) and the blow-up check.
    power: Callable[[float, np.ndarray], tuple[float, float]] | None = None

    @abstractmethod
    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """Time derivative of the state."""

    @abstractmethod
    def observe(self, times: np.ndarray, Y: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """The scene's requested quantities from states Y (len(times), N):
        quantity -> (values (len(times), n_k), k labels)."""


class OdeModel(Model):
    """A model that is an ODE system integrated by rodval's ODE driver."""

    @abstractmethod
    def system(self, scene: Scene) -> OdeSystem:
        """Build the ODE system of ``scene`` (all scene-constant work happens here)."""

    def simulate(self, scene: Scene, settings: IntegratorSettings) -> Trajectory:
        from ..integrate import integrate

        return integrate(self.system(scene), scene, settings, model=self.name,
                         options=self.options())
