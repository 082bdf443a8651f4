"""The model contract: every model, native or reference, turns a Scene into a Trajectory.

Models are registered by name (``rodval.models.registry``); a run never raises for a failed
integration (the Trajectory's stats say how it ended), but a bad option or a setting the
model cannot honour is a ValueError raised before any work. After every run the model judges
its own validity (``validity_checks``, ``rodval.core.validity``): ``stats.valid`` and
``stats.validity``, whatever path ran it (the CLI, the API, a study worker).
"""

from __future__ import annotations

import importlib
from abc import ABC, abstractmethod
from typing import Any, ClassVar

from rodval.core.checks import check_keys
from rodval.core.damping import check_resolved
from rodval.core.modes import Modes
from rodval.core.resources import check_run_memory, dense_path
from rodval.core.scene import Scene, trajectory_quantities
from rodval.core.settings import IntegratorSettings
from rodval.core.status import STATUS_BUDGET
from rodval.core.trajectory import Trajectory
from rodval.core.validity import (
    ENERGY_RESIDUAL_BOUND,
    Check,
    energy_balance,
    momentum_balance,
    verdict,
)


class Model(ABC):
    """A named model of the chain. Subclasses set ``name`` and implement ``run``; callers use
    ``simulate`` (the run, then the model's verdict on its assumptions)."""

    name: ClassVar[str]
    #: "module:function" of this model's modal analysis, loaded when asked for (as the
    #: registry loads models): f(scene, *, about, count, load_at, **options) -> Modes.
    MODAL_ANALYSIS: ClassVar[str | None] = None
    #: The option names its modal analysis takes.
    MODES_OPTIONS: ClassVar[tuple[str, ...]] = ()
    #: Largest energy-audit residual of a valid run of this model (``rodval.core.validity``).
    energy_residual_bound: ClassVar[float] = ENERGY_RESIDUAL_BOUND
    #: What its options resolved to for its scene, and why (``scene_options``; first in notes).
    chosen: tuple[str, ...] = ()

    def simulate(self, scene: Scene, settings: IntegratorSettings | None = None) -> Trajectory:
        """Run the scene (default integrator settings when None) and judge the run's validity;
        never raise for a failed integration (report it in the stats). Refused before any
        work (ValueError): settings against the horizon, a base the model does not have, a
        deployed damping request not converted, a run that would not fit in memory."""
        settings = IntegratorSettings() if settings is None else settings
        model = self.for_scene(scene)[0]
        if model is not self:  # an option resolved for the scene: run the model it resolves to
            return model.simulate(scene, settings)
        settings.check_horizon(scene.t_end)
        self.check_base(scene)
        check_resolved(scene, f"model {self.name!r}")  # a deployed damping request, converted
        check_run_memory(
            scene.n,
            scene.times.size,
            trajectory_quantities(scene.outputs),
            model=self.name,
            dense=dense_path(self.name, self.options(), settings.method),
            what=f"scene {scene.name!r} with model {self.name!r}",
        )
        trajectory = self.run(scene, settings)
        trajectory.scene = scene
        stats = trajectory.stats
        if stats.status == STATUS_BUDGET and stats.switch is not None:
            stats.message += f"; fix: {self.stiffness_fix(scene)}"
        checks = self.validity_checks(scene, trajectory)
        stats.valid, stats.validity = verdict(checks, finished=trajectory.success)
        stats.notes = [*self.chosen, *self.scene_notes(scene)]
        return trajectory

    @abstractmethod
    def run(self, scene: Scene, settings: IntegratorSettings) -> Trajectory:
        """Run the scene; never raise for a failed integration (report it in the stats)."""

    @classmethod
    def scene_options(
        cls, scene: Scene, options: dict[str, Any]
    ) -> tuple[dict[str, Any], list[str]]:
        """``options`` with those that depend on the scene ("auto") resolved for ``scene`` before
        the model is built (one model object), and the notes that say to what and why
        (``chosen``); by default as given, no notes."""
        return options, []

    def for_scene(self, scene: Scene) -> tuple[Model, list[str]]:
        """This model with its options that depend on the scene resolved for ``scene``
        (``scene_options``), and the notes that say so (its ``chosen``, recorded first in
        ``SolverStats.notes``); ``simulate`` runs the resolved model. Itself, no notes, when
        nothing was left to resolve (or it was built for the scene: ``chosen`` set)."""
        options, notes = ({}, []) if self.chosen else self.scene_options(scene, self.options())
        if not notes:
            return self, []
        model = type(self)(**options)
        model.chosen = tuple(notes)
        return model, notes

    def check_base(self, scene: Scene) -> None:
        """ValueError (before any work) unless this model, with its options, has the scene's
        kind of base (``rodval.core.base``); by default a pinned base only."""
        if scene.base.moving:
            raise ValueError(
                f"model {self.name!r} has no {scene.base.kind} base (base kind "
                f"{scene.base.kind!r}); docs/base.md lists the models that do"
            )

    def validity_checks(self, scene: Scene, trajectory: Trajectory) -> list[Check]:
        """The checks of this model's assumptions on a run of ``scene`` (over the output times
        it reached). By default the energy balance and the angular-momentum balance where the
        run was audited."""
        stats = trajectory.stats
        return energy_balance(
            stats.energy_residual, self.energy_residual_bound, self.energy_fix()
        ) + momentum_balance(stats.momentum_residual, fix=self.momentum_fix(scene))

    def energy_fix(self) -> str:
        """The setting that would close a broken energy balance of this model's run (named
        in the verdict); by default the integration's tolerance."""
        return "a tighter rtol (integration error)"

    def stiffness_fix(self, scene: Scene) -> str:
        """The settings that would let a run whose budget went on a stiff vibration finish
        (appended to its message); by default a larger budget or looser tolerances."""
        return "a larger max_evaluations, or a looser rtol and atol"

    def momentum_fix(self, scene: Scene) -> str:
        """The setting that would keep a drifting angular momentum of this model's run of
        ``scene`` (named in the verdict); by default the energy balance's."""
        return self.energy_fix()

    def scene_notes(self, scene: Scene) -> list[str]:
        """What this model leaves out of ``scene`` by its premise, one sentence each with the
        reason (recorded in ``SolverStats.notes``, so nothing a user gives is dropped
        silently); none by default."""
        return []

    def options(self) -> dict[str, Any]:
        """Model options (recorded in ``Trajectory.options``)."""
        return {}

    @classmethod
    def modes(
        cls,
        scene: Scene,
        *,
        about: str = "initial",
        count: int | None = None,
        load_at: float | None = None,
        **options: Any,
    ) -> Modes:
        """Linearized modes of this model about the scene's initial state (``about="initial"``)
        or its static equilibrium (``"equilibrium"``, loads held at ``load_at`` s) by its
        modal analysis (``MODAL_ANALYSIS``); ``options``: among ``MODES_OPTIONS``, with the
        model's defaults for a modal analysis. The configuration check (at rest, balanced) is
        the caller's (``rodval.analysis.modes.model_modes``), done once for every model."""
        check_keys(
            options,
            cls.MODES_OPTIONS,
            f"{cls.name} modes",
            noun="option",
        )
        if cls.MODAL_ANALYSIS is None:
            raise ValueError(f"model {cls.name!r} has no modal analysis")
        check_resolved(scene, f"model {cls.name!r} modes")
        if scene.torques:
            kinds = sorted({type(item).TABLE for item in scene.torques})
            raise ValueError(
                f"model {cls.name!r}: modes of a scene with {' and '.join(kinds)} are not built "
                "(a moment across a hinge would load the equilibrium and its rate coefficient "
                "damp the modes); remove them for the structure's own modes"
            )
        if scene.base.prescribed:
            raise ValueError(
                f"model {cls.name!r}: modes of a chain on a prescribed base (a motion that is a "
                "law of time, not a configuration at rest) are not built (docs/base.md)"
            )
        module, function = cls.MODAL_ANALYSIS.split(":")
        analysis = getattr(importlib.import_module(module), function)
        # a free base (the spacecraft): only analyses that separate its three rigid modes
        # (``rodval.mechanics.modal.split_rigid``) say so by a true ``FREE_BASE`` attribute
        if scene.base.free and not getattr(analysis, "FREE_BASE", False):
            raise ValueError(
                f"model {cls.name!r}: modes of a chain on a free base (the free spacecraft) are "
                "not built for this model (docs/base.md; the full and exudyn models have them)"
            )
        modes: Modes = analysis(scene, about=about, count=count, load_at=load_at, **options)
        return modes
