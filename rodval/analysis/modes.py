"""Modes of every model side by side: ``model_modes`` checks once what the modes are about
(``rodval.models.observation.linear_modes.check_configuration``) and asks the model for them
(``Model.modes``: the paper models' linearization in ``rodval.models.observation.linear_modes``, exudyn's
in ``reference_models.exudyn_modes``).

Comparison
----------
``mac`` is the modal assurance criterion |a.b|^2 / ((a.a)(b.b)) on the shape vector
[dx; dy; l_mean * D] (hinge angles times the mean rod length, so that both parts are lengths);
``pair_modes`` pairs the modes of two models by shape (``scipy.optimize.linear_sum_assignment``
on 1 - MAC), not by index; ``compare_modes`` tabulates several models against a reference.
On a free base both compare the flexible modes only: each model reports its three rigid modes
(omega ~ 0) first and apart (``Modes.rigid``, ``rodval.mechanics.modal.split_rigid``), and
``Modes.flexible`` leaves them out.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import linear_sum_assignment

from rodval.core.modes import Modes
from rodval.core.scene import Scene
from rodval.models.observation.deployed_damping import resolve_damping
from rodval.models.observation.linear_modes import check_arguments, check_configuration, mac_matrix
from rodval.models.registry import MODEL_NAMES, modal_options, model_class


def model_modes(
    scene: Scene,
    model: str,
    *,
    about: str = "initial",
    count: int | None = None,
    load_at: float | None = None,
    allow_unbalanced: bool = False,
    **options: Any,
) -> Modes:
    """The modes of ``model`` (a registered name) about the scene's initial state or its
    static equilibrium, every model about the same configuration, checked here once
    (``check_configuration``); ``options``: the model's own (``Model.modes``; e.g. the paper
    models' ``coefficients``, exudyn's discretization). A bending damping stated for the
    deployed structure is converted first (``resolve_damping``), as for a run."""
    check_arguments(scene, count)
    cls = model_class(model)
    scene = resolve_damping(scene)
    balance = check_configuration(scene, about, load_at, allow_unbalanced)
    m = cls.modes(scene, about=about, count=count, load_at=load_at, **options)
    m.info.update(balance)
    return m


def rerun_options(
    model: str, options: dict[str, Any], where: str
) -> tuple[dict[str, Any], dict[str, Any]]:
    """A run's model options (its run.json's ``options``, ``where`` naming the file) split for
    a modal analysis of the same ``model``: (the ones its modes take, ``MODES_OPTIONS``: the
    model's equations, e.g. the full model's coefficients, shapes and kinematics; the ones
    that set only how the run was computed, the model's ``OPTIONS`` its modes leave out: the
    native models' ``kernel``, the same equations compiled or in numpy, which a
    linearization does not run). Any other option is refused (ValueError naming it)."""
    cls = model_class(model)
    taken = {k: v for k, v in options.items() if k in cls.MODES_OPTIONS}
    computed = {
        k: v for k, v in options.items() if k in getattr(cls, "OPTIONS", ()) and k not in taken
    }
    other = sorted(set(options) - set(taken) - set(computed))
    if other:
        raise ValueError(
            f"{where}: the {model} run's option {other[0]!r} cannot be honoured by its modes "
            f"(a modal analysis of the {model} model takes: "
            f"{', '.join(cls.MODES_OPTIONS) or 'none'})"
        )
    return taken, computed


# -- pairing -----------------------------------------------------------------------------------
def pair_modes(a: Modes, b: Modes) -> pd.DataFrame:
    """Pair the modes of b with those of a by shape: maximum total MAC (Hungarian assignment on
    1 - MAC). One row per mode of a (by index), with b's paired mode (NaN if none), both
    frequencies, the relative gap (omega_b - omega_a) / omega_a and the MAC. On a free base
    the flexible modes are paired (``Modes.flexible``: the three rigid modes, omega ~ 0, left
    out of both); mode numbers then count the flexible modes."""
    a, b = a.flexible(), b.flexible()
    if a.dx.shape[1] != b.dx.shape[1]:
        raise ValueError("modes of different chains cannot be paired")
    macs = mac_matrix(a.shape_vectors(), b.shape_vectors())
    rows, cols = linear_sum_assignment(-macs)
    partner = np.full(a.count, -1)
    partner[rows] = cols
    out = []
    for i in range(a.count):
        j = partner[i]
        wa = a.omega[i]
        wb = b.omega[j] if j >= 0 else np.nan
        out.append(
            {
                "mode_a": i + 1,
                "mode_b": j + 1 if j >= 0 else np.nan,
                "omega_a": wa,
                "omega_b": wb,
                "rel_gap": (wb - wa) / wa if j >= 0 and wa != 0 else np.nan,
                "mac": macs[i, j] if j >= 0 else np.nan,
            }
        )
    return pd.DataFrame(out)


def compare_modes(
    scene: Scene,
    models: tuple[str, ...] = MODEL_NAMES,
    *,
    about: str = "initial",
    count: int = 10,
    reference: str | None = None,
    computed: dict[str, Modes] | None = None,
    load_at: float | None = None,
    allow_unbalanced: bool = False,
    **options: Any,
) -> pd.DataFrame:
    """Side-by-side table of the lowest ``count`` modes of ``reference`` (default: the last of
    ``models``, e.g. exudyn) with the paired modes of the other models: columns mode,
    omega_<ref>, and per other model omega_<m>, gap_<m> (relative to the reference) and
    mac_<m>; on a free base the flexible modes (``Modes.flexible``), numbered from 1.
    ``computed`` may pass Modes already computed (name -> Modes); ``about``,
    ``load_at``, ``allow_unbalanced``: see ``model_modes``; ``options``: each model takes the
    ones its modal analysis accepts (``modal_options``)."""
    models = tuple(models)
    reference = models[-1] if reference is None else reference
    got = dict(computed or {})
    for m in models:
        if m not in got:
            got[m] = model_modes(
                scene,
                m,
                about=about,
                load_at=load_at,
                allow_unbalanced=allow_unbalanced,
                **modal_options(m, options),
            )
    ref = got[reference].flexible()  # a free base's rigid modes are left out (pair_modes)
    table = pd.DataFrame({"mode": np.arange(1, min(count, ref.count) + 1)})
    table[f"omega_{reference}"] = ref.omega[: len(table)]
    for m in models:
        if m == reference:
            continue
        p = pair_modes(_head(ref, len(table)), got[m])
        table[f"omega_{m}"] = p["omega_b"].to_numpy()
        table[f"gap_{m}"] = p["rel_gap"].to_numpy()
        table[f"mac_{m}"] = p["mac"].to_numpy()
    return table


def _head(m: Modes, count: int) -> Modes:
    """The lowest ``count`` modes of m."""
    return Modes(
        model=m.model,
        about=m.about,
        omega=m.omega[:count],
        damping=m.damping[:count],
        dx=m.dx[:count],
        dy=m.dy[:count],
        hinge=m.hinge[:count],
        phi0=m.phi0,
        l=m.l,
        equilibrium=m.equilibrium,
        info=m.info,
    )
