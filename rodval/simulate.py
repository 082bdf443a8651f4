"""The entry point: scene + model + integrator settings -> Trajectory."""
from __future__ import annotations

import math

from .models import Model, get_model
from .scene import Scene
from .settings import IntegratorSettings
from .trajectory import Trajectory


def simulate(scene: Scene, model: str | Model = "full", *, method: str = "DOP853",
             rtol: float = 1e-8, atol: float = 1e-10, max_step: float = math.inf,
             first_step: float | None = None, settings: IntegratorSettings | None = None,
             **model_options) -> Trajectory:
    """Simulate ``scene`` with ``model`` ("full", "reduced", "exudyn" or a Model instance).

    Integrator settings are given either as keywords (``method``: any solve_ivp method;
    ``rtol``, ``atol``; ``max_step`` in s) or as an ``IntegratorSettings``. Remaining keywords
    are model options (e.g. ``coefficients="published"``; exudyn: discretization settings).
    A failed integration does not raise: see ``trajectory.stats.status`` / ``message``.
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a rodval.Scene, got {type(scene).__name__}")
    if settings is None:
        settings = IntegratorSettings(method=method, rtol=rtol, atol=atol, max_step=max_step,
                                      first_step=first_step)
    return get_model(model, **model_options).simulate(scene, settings)
