"""A model that is an ODE system integrated by rodval's driver."""

from __future__ import annotations

import time
from abc import abstractmethod

from rodval.core.contract import Model
from rodval.core.scene import Scene
from rodval.core.settings import AUTO, COMPILED_METHODS, IntegratorSettings
from rodval.core.status import STATUS_ERROR, exception_line, numerical_failure
from rodval.core.trajectory import SolverStats, Trajectory
from rodval.solvers.driver import integrate
from rodval.solvers.system import OdeSystem


class OdeModel(Model):
    """A model whose ``system(scene)`` is an ``OdeSystem`` run by ``rodval.solvers.driver``."""

    @abstractmethod
    def system(self, scene: Scene) -> OdeSystem:
        """Build the ODE system of ``scene`` (all scene-constant work happens here)."""

    def run(self, scene: Scene, settings: IntegratorSettings) -> Trajectory:
        """Build the system and integrate it. A failure while building it (its constants,
        its first evaluation) is reported like a failure during integration: status
        ``model error`` (or a numerical failure's, ``rodval.core.status.numerical_failure``),
        the message, t_reached = 0."""
        start = time.perf_counter()
        if settings.method in (AUTO, *COMPILED_METHODS):
            from rodval.solvers import dop853

            dop853.warm_up()  # the compiled loop, in the background while the system is built
        try:
            system = self.system(scene)
        except Exception as exc:  # noqa: BLE001 - failures are data
            status, message = numerical_failure(exc, 0.0) or (
                STATUS_ERROR,
                exception_line(exc),
            )
            stats = SolverStats(
                status=status,
                message=f"model set-up failed: {message}",
                wall_s=time.perf_counter() - start,
            )
            return Trajectory.failed(
                self.name, scene.name, stats, settings=settings.as_dict(), options=self.options()
            )
        return integrate(system, scene, settings, model=self.name, options=self.options())
