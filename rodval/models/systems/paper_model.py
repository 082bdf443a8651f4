"""What a model of the paper's chain takes (its options) and judges (its validity checks)."""

from __future__ import annotations

from typing import Any, ClassVar

from rodval.core.checks import check_choice
from rodval.core.scene import Scene
from rodval.core.trajectory import Trajectory
from rodval.core.validity import Check, small_bending
from rodval.models.assembly.paper_matrices import DEFAULT_VARIANT, VARIANTS
from rodval.models.systems.paper_system import KERNELS, PaperSystem
from rodval.solvers.ode_model import OdeModel


class PaperModel(OdeModel):
    """A model of the paper. ``coefficients``: "printed" (default, from the kinematics) or
    "published" (the erratum that reproduces the paper's alpha/beta; see paper_matrices).
    ``kernel``: "numba" (default, compiled O(n) kernels) or "numpy" (the straightforward
    dense right-hand side, kept as the reference and benchmark baseline)."""

    system_class: type[PaperSystem]
    OPTIONS: ClassVar[tuple[str, ...]] = ("coefficients", "kernel")
    MODES_OPTIONS: ClassVar[tuple[str, ...]] = ("coefficients",)

    def __init__(self, coefficients: str = DEFAULT_VARIANT, kernel: str = "numba"):
        self.coefficients = check_choice("coefficients", coefficients, VARIANTS)
        self.kernel = check_choice("kernel", kernel, KERNELS)

    def options(self) -> dict[str, Any]:
        return {"coefficients": self.coefficients, "kernel": self.kernel}

    def system(self, scene: Scene) -> PaperSystem:
        return self.system_class(scene, self.coefficients, self.kernel)

    def validity_checks(self, scene: Scene, trajectory: Trajectory) -> list[Check]:
        """The energy balance (where audited) and the small-bending assumption of the paper's
        first-order kinematics (largest |alpha|, |beta| over the output times reached)."""
        return super().validity_checks(scene, trajectory) + small_bending(
            trajectory.stats.max_bending
        )
