"""Models by name, and the entry point: scene + model + integrator settings -> Trajectory.

Native models: ``full``, ``reduced``, ``rigid``; reference models (``reference_models``) are imported by
name only when asked for, so the models layer does not depend on them.
"""

from __future__ import annotations

import importlib
from typing import Any

from rodval.core.contract import Model
from rodval.core.scene import Scene
from rodval.core.settings import SETTING_NAMES, IntegratorSettings
from rodval.core.trajectory import Trajectory
from rodval.models.observation.deployed_damping import panel_note, resolve_damping

#: name -> "module:Class". Each class lists its option names in ``OPTIONS``.
REGISTRY: dict[str, str] = {
    "full": "rodval.models.presets.full:FullModel",
    "reduced": "rodval.models.presets.reduced:ReducedModel",
    "rigid": "rodval.models.presets.rigid:RigidModel",
    "exudyn": "reference_models.exudyn_chain:ExudynModel",
}


#: Every model name, in registry order: the one list of model names.
MODEL_NAMES: tuple[str, ...] = tuple(REGISTRY)


def integrated_models() -> tuple[str, ...]:
    """The models rodval's driver integrates (``uses_integrator``): the native ones. Resolved
    from the registry, so a model that cannot be imported here is left out."""
    out = []
    for name in MODEL_NAMES:
        try:
            if uses_integrator(name):
                out.append(name)
        except ValueError:
            continue
    return tuple(out)


def model_class(name: str) -> type[Model]:
    """The class registered as ``name`` (ValueError if unknown or not importable)."""
    if not isinstance(name, str) or name not in REGISTRY:
        raise ValueError(f"model must be one of {tuple(REGISTRY)}, got {name!r}")
    module, cls = REGISTRY[name].split(":")
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise ValueError(f"model {name!r} is not available: {exc}") from exc
    found: type[Model] = getattr(mod, cls)
    return found


def uses_integrator(name: str) -> bool:
    """Whether model ``name`` is integrated by rodval's driver, so that IntegratorSettings
    apply to it (False for a model that integrates itself, e.g. exudyn with its own step)."""
    return bool(getattr(model_class(name), "USES_INTEGRATOR_SETTINGS", True))


def option_names(name: str) -> tuple[str, ...]:
    """The option names model ``name`` takes (its class's ``OPTIONS``; ValueError if the
    model is unknown or not importable)."""
    return tuple(getattr(model_class(name), "OPTIONS", ()))


def modal_options(name: str, options: dict[str, Any]) -> dict[str, Any]:
    """The ones of ``options`` that model ``name``'s modal analysis takes
    (``Model.MODES_OPTIONS``), for callers that hold options for several models."""
    accepted = model_class(name).MODES_OPTIONS
    return {k: v for k, v in options.items() if k in accepted}


def get_model(name: str | Model, **options: Any) -> Model:
    """The model called ``name`` with its options (a Model instance is returned as is).
    Unknown option names are a ValueError listing the allowed ones."""
    if isinstance(name, Model):
        if options:
            raise ValueError("model options can only be given with a model name")
        return name
    allowed = option_names(name)
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ValueError(_unknown_keyword(name, unknown[0], allowed))
    return model_class(name)(**options)


def scene_model(model: str | Model, scene: Scene, options: dict[str, Any]) -> Model:
    """The model ``simulate`` runs ``scene`` with, built once: by name, its options that depend
    on the scene resolved first (``Model.scene_options``, its notes the model's ``chosen``); a
    Model instance resolved for the scene (``Model.for_scene``)."""
    if isinstance(model, Model):
        return get_model(model, **options).for_scene(scene)[0]
    resolved, notes = model_class(model).scene_options(scene, options)
    built = get_model(model, **resolved)
    built.chosen = tuple(notes)
    return built


def check_scene(model: Model, scene: Scene, settings: IntegratorSettings) -> Scene:
    """What ``model`` (with its options) refuses for ``scene`` with ``settings``, before any
    work: a ValueError naming the reason. The settings against the scene's horizon
    (``IntegratorSettings.check_horizon``), the base and outputs the model has
    (``Model.check_base``: a moving base on the reduced model, the output "drive" on exudyn)
    and a bending damping stated for the deployed structure, converted to the rods' c
    (``deployed_damping.resolve_damping``: the same c for every model). Returns the scene
    the model runs (``scene`` itself unless converted): what ``simulate`` refuses
    (``Model.simulate``), for a study's plan (``rodval.study.case``) before its runs."""
    settings.check_horizon(scene.t_end)
    model.check_base(scene)
    return resolve_damping(scene)


def _unknown_keyword(model: str, key: str, allowed: tuple[str, ...]) -> str:
    """One line for an unknown keyword of ``simulate``/``get_model``: the model's options and
    the integrator settings (both are keywords of ``simulate``), with the nearest name."""
    import difflib

    uses = uses_integrator(model)
    names = (*allowed, *(SETTING_NAMES if uses else ()))
    near = difflib.get_close_matches(key, names, n=1, cutoff=0.6)
    hint = f"; did you mean {near[0]!r}?" if near else ""
    settings = (
        f"; integrator settings: {', '.join(SETTING_NAMES)}"
        if uses
        else f"; the {model} model takes no integrator settings"
    )
    return (
        f"unknown {model} model option {key!r} (allowed: {', '.join(allowed) or 'none'}"
        f"{settings}){hint}"
    )


def simulate(
    scene: Scene,
    model: str | Model = "full",
    *,
    settings: IntegratorSettings | None = None,
    **keywords: Any,
) -> Trajectory:
    """Simulate ``scene`` with ``model`` ("full", "reduced", "exudyn" or a Model instance).

    Integrator settings are given either as keywords (``method``: "auto" (default), any
    solve_ivp method or "DOP853-numba"; ``rtol``, ``atol``; ``max_step`` in s; budgets; see
    ``IntegratorSettings``) or as one ``settings`` object, not both. The other keywords are
    model options (e.g. ``coefficients="published"``; exudyn: ``elements``, ``step``).
    A failed integration does not raise: see ``trajectory.stats.status`` / ``message``.
    A damping ratio of each panel's first mode on a latched scene adds a note with the ratio
    it gives the deployed structure's first mode (``deployed_damping.panel_note``).
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a rodval.Scene, got {type(scene).__name__}")
    integ = {k: v for k, v in keywords.items() if k in SETTING_NAMES}
    options = {k: v for k, v in keywords.items() if k not in SETTING_NAMES}
    if settings is None:
        settings = IntegratorSettings(**integ)
    elif not isinstance(settings, IntegratorSettings):
        raise ValueError(
            f"settings must be a rodval.IntegratorSettings or None, got {type(settings).__name__}"
        )
    elif integ:
        raise ValueError(
            f"give integrator settings either as settings= or as keywords, not "
            f"both (got settings= and {', '.join(sorted(integ))})"
        )
    # a deployed damping converted to the rods' c; the model refuses the rest (Model.simulate)
    trajectory = scene_model(model, scene, options).simulate(resolve_damping(scene), settings)
    trajectory.stats.notes = [*trajectory.stats.notes, *panel_note(scene)]
    return trajectory
