"""The model contract: every model, native or reference, turns a Scene into a Trajectory.

Models are registered by name (``rodval.models.registry``); a run never raises for a failed
integration (the Trajectory's stats say how it ended), but a bad option or a setting the
model cannot honour is a ValueError raised before any work.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

from rodval.core.scene import Scene
from rodval.core.settings import IntegratorSettings
from rodval.core.trajectory import Trajectory


class Model(ABC):
    """A named model of the chain. Subclasses set ``name`` and implement ``simulate``."""

    name: ClassVar[str]

    @abstractmethod
    def simulate(self, scene: Scene, settings: IntegratorSettings) -> Trajectory:
        """Run the scene; never raise for a failed integration (report it in the stats)."""

    def options(self) -> dict[str, Any]:
        """Model options (recorded in ``Trajectory.options``)."""
        return {}
