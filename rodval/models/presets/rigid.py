"""The rigid-panel model (``rigid``): the chain of rigid rods, n ODEs in phi, O(n) per
evaluation, on a pinned, free or prescribed base (docs/model.md, "The rigid model").

A named composition of the engine, not a model of its own: the ladder's kernels on zero bending
mobility (``rodval.models.kinematics.ladder.rigid_constants``, the limit EI -> inf of every
rung), restricted to the rigid coordinates (``rodval.models.systems.chain_system.RigidSystem``), with
the chain systems' hinge items (springs, dampers, stops; latches as exact linear constraints,
the plastic lock, which is the rigid-panel lock of ``rodval.mechanics.rigid``) and bases. It
takes no options.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rodval.core.scene import Scene
from rodval.solvers.ode_model import OdeModel
from rodval.solvers.system import OdeSystem

#: The scene's bending data the rigid rods have nowhere to put, named in the run's notes.
BENDING_INITIAL = ("alpha", "beta", "dalpha", "dbeta")


class RigidModel(OdeModel):
    """Rigid rods (n ODEs): no options; every base (pinned, free, prescribed)."""

    name = "rigid"
    OPTIONS: ClassVar[tuple[str, ...]] = ()
    MODAL_ANALYSIS = "rodval.models.observation.rigid_modes:rigid_modes"
    MODES_OPTIONS: ClassVar[tuple[str, ...]] = ()

    def check_base(self, scene: Scene) -> None:
        """Every base kind runs (``chain_system``): nothing to refuse."""

    def system(self, scene: Scene) -> OdeSystem:
        """The rigid chain of ``scene`` on its base (the chain systems' module, and its
        compiled kernels, imported only when asked for)."""
        from rodval.models.systems.chain_system import RigidSystem

        return RigidSystem(scene)

    def stiffness_fix(self, scene: Scene) -> str:
        """A rigid chain has no bending vibration: what stiffens it is its hinges' springs
        and stops."""
        return (
            "softer limit stops or hinge springs (the rigid chain has no bending vibration), "
            "a larger max_evaluations, or a looser rtol and atol"
        )

    def scene_notes(self, scene: Scene) -> list[str]:
        """The scene's bending data, which rigid rods leave out: EI and bending damping (the
        rods do not bend) and initial bending angles or rates."""
        chain = scene.chain
        notes = [
            f"EI (up to {float(chain.EI.max()):g} N m^2) is not used by the rigid model: its "
            "rods do not bend (the limit EI -> inf)"
        ]
        if np.any(chain.bending_damping > 0):
            notes.append("bending_damping has no effect in the rigid model: its rods do not bend")
        given = [k for k in BENDING_INITIAL if getattr(scene.initial, k) is not None]
        if any(np.any(np.asarray(getattr(scene.initial, k)) != 0) for k in given):
            notes.append(
                "initial alpha, beta, dalpha, dbeta are not used by the rigid model: its rods "
                "do not bend"
            )
        return notes
