"""Stiff chains on the default method: "auto" (compiled DOP853 that goes on with the
compiled Radau IIA when the bending block sets its steps, ``rodval.solvers.stiffness``)
against each compiled method alone, side by side in one run.

Scenes:

* the paper chain (``paper_scene(4)``) with every rod's EI from 1e5 (the paper's
  flexible panels) to 1e9 N m^2 (near-rigid), same loads and horizon;
* the rigid two-rod latch (``rigid_latch``): two near-rigid rods, free root, hinge 1
  pre-stressed and latching straight.

Per scene, native model and method: wall seconds (``stats.wall_s``, best of ``repeats``
after a warm-up), evaluations, whether and where "auto" switched, and the largest phi
error against a tight reference (the compiled DOP853 at rtol 1e-13 where its cost allows,
EI <= 1e6, the compiled Radau IIA at rtol 1e-11 above), in rad.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pandas as pd

from rodval.bench.fast_path import best_run
from rodval.bench.precision import Progress
from rodval.core.scene import Chain, InitialState, Latch, Scene, paper_scene
from rodval.core.settings import AUTO, IntegratorSettings
from rodval.core.status import Status
from rodval.core.trajectory import Trajectory
from rodval.models.registry import integrated_models, simulate

#: EI (N m^2) of the paper chain's sweep.
EI_VALUES = (1e5, 1e6, 1e7, 1e8, 1e9)
METHODS = (AUTO, "DOP853-numba", "Radau-numba")


def stiff_paper(EI: float) -> Scene:
    """The paper example (n = 4) with every rod's bending stiffness EI (N m^2)."""
    scene = paper_scene(4)
    chain = dataclasses.replace(scene.chain, EI=np.full(4, float(EI)))
    return dataclasses.replace(scene, name=f"paper_EI_{EI:.0e}", chain=chain)


def rigid_latch(EI: float = 1e9) -> Scene:
    """Two rods (1 m, 1 kg/m, tip masses 0.5 kg), free root, hinge 1 (kappa = 5 N m/rad)
    released from -2.5 rad with rates (1, 1.5) rad/s and latching at 0; 0..1.5 s."""
    chain = Chain.uniform(2, l=1.0, m=1.0, EI=EI, mu=0.5, kappa=[0.0, 5.0], nu=0.0)
    return Scene(
        name="rigid_latch",
        chain=chain,
        t_end=1.5,
        times=np.linspace(0.0, 1.5, 31),
        initial=InitialState(phi=np.array([0.0, -2.5]), dphi=np.array([1.0, 1.5])),
        latches=(Latch(1, 0.0),),
        outputs=("phi", "dphi", "hinge_angle", "angular_momentum"),
    )


def reference(scene: Scene, model: str, EI: float) -> Trajectory:
    """The tight reference of the module docstring."""
    if EI <= 1e6:
        settings = IntegratorSettings("DOP853-numba", rtol=1e-13, atol=1e-15, max_evaluations=10**8)
    else:
        settings = IntegratorSettings("Radau-numba", rtol=1e-11, atol=1e-13, max_evaluations=10**8)
    return simulate(scene, model, settings=settings)


def _row(
    scene: Scene, model: str, method: str, tr: Trajectory, ref: Trajectory | None
) -> dict[str, Any]:
    switch = tr.stats.switch or {}
    err = np.nan
    if ref is not None and ref.success and tr.times.size == ref.times.size:
        err = float(np.max(np.abs(tr["phi"] - ref["phi"])))
    return {
        "scene": scene.name,
        "EI": float(np.max(scene.chain.EI)),
        "model": model,
        "method": method,
        "status": Status(tr.stats.status).name.lower(),
        "wall_s": tr.stats.wall_s,
        "nfev": tr.stats.nfev,
        "switches": switch.get("switches", 0),
        "ended_on": switch.get("ended_on", tr.settings["method"]),
        "phi_error": err,
    }


def stiffness_rows(
    repeats: int = 3, progress: Progress = print, budget_s: float = 20.0
) -> pd.DataFrame:
    """One row per scene, native model and method (module docstring); each run may use
    ``budget_s`` wall seconds (a method that cannot finish is reported so, not waited for)."""
    rows = []
    for scene, EI in [(stiff_paper(EI), EI) for EI in EI_VALUES] + [(rigid_latch(), None)]:
        for model in integrated_models():
            ref = reference(scene, model, EI) if EI is not None else None
            for method in METHODS:
                settings = IntegratorSettings(method, max_wall_s=budget_s)
                tr = best_run(scene, model, settings, repeats)
                rows.append(_row(scene, model, method, tr, ref))
                progress(f"{scene.name}, {model}, {method}: {tr.stats.wall_s:.3f} s")
    return pd.DataFrame(rows)


def growth(frame: pd.DataFrame) -> pd.DataFrame:
    """Per model and method over the paper chain's EI sweep: the largest over the smallest
    wall time (the issue's "grows less than 3x from EI = 1e5 to 1e9")."""
    sweep = frame[frame.scene.str.startswith("paper_EI")]
    out = []
    for (model, method), g in sweep.groupby(["model", "method"], sort=False):
        out.append(
            {
                "model": model,
                "method": method,
                "wall_at_1e5_s": float(g[g.EI == min(EI_VALUES)].wall_s.iloc[0]),
                "wall_at_1e9_s": float(g[g.EI == max(EI_VALUES)].wall_s.iloc[0]),
                "max_over_min": float(g.wall_s.max() / g.wall_s.min()),
            }
        )
    return pd.DataFrame(out)
