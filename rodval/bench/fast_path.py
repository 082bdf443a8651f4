"""The fast path for every scene: the default method ("auto") against scipy's DOP853 on the
scenes that used to fall off the compiled loop (events, energy), side by side in one run.

Scenes:

* ``four_panel_wing``: the four-panel zig-zag wing of ``studies/deployment.toml`` (stowed,
  released by its pre-stressed hinges, latching straight), with and without its latches;
* ``eight_rod_wing``: an 8-rod non-uniform damped wing under a tip pulse and a mid-span
  constant force, 0..3 s, with and without "energy" among the outputs;
* the paper example (``paper_scene(8)``), with and without "energy".

Per scene and native model: the method "auto" chose, wall seconds (``stats.wall_s``, best of
``repeats`` after a warm-up), evaluations, seconds per evaluation, and the speed-up of "auto"
over scipy's DOP853; for the latch scenes the largest lock-time difference (s) and impulse
difference (relative) between the two; for the energy scenes both audit residuals.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from rodval.bench.precision import Progress
from rodval.core.loads import constant, pulse
from rodval.core.scene import Chain, InitialState, Latch, Scene, paper_scene
from rodval.core.settings import AUTO, IntegratorSettings
from rodval.core.trajectory import Trajectory
from rodval.models.registry import integrated_models, simulate


def four_panel_wing(latches: bool = True, t_end: float = 2.5, times: int = 501) -> Scene:
    """The four-panel wing of ``studies/deployment.toml``: l = 1.5 m, m = 3 kg/m, EI = 5e3 N
    m^2, 0.5 kg fittings, a stiff damped root hinge (1e5 N m/rad, 10 N m s), kappa = 50 N m/rad
    and nu = 0.05 N m s elsewhere, rest angles 0, folded zig-zag (D = +-(pi - 0.05) rad),
    latching straight on hinges 1-3 (``latches``), outputs as the study's."""
    return Scene(
        name="four_panel_wing",
        chain=Chain.uniform(
            4,
            l=1.5,
            m=3.0,
            EI=5e3,
            mu=0.5,
            kappa=[1e5, 50.0, 50.0, 50.0],
            nu=[10.0, 0.05, 0.05, 0.05],
        ),
        t_end=t_end,
        times=np.linspace(0.0, t_end, times),
        initial=InitialState(phi=np.array([0.0, np.pi - 0.05, 0.0, np.pi - 0.05])),
        latches=tuple(Latch(k, 0.0) for k in (1, 2, 3)) if latches else (),
        outputs=("phi", "dphi", "alpha", "beta", "x", "y", "energy"),
    )


def eight_rod_wing(energy: bool = True) -> Scene:
    """An 8-rod non-uniform damped wing (rods 0.6-1.2 m, 0.8-2 kg, EI = 2e4 N m^2, hinge
    springs and dampers), a 1 s pulse at the tip and a constant force at node 4, 0..3 s."""
    chain = Chain(
        l=[1.2, 0.8, 1.0, 0.6, 0.9, 1.1, 0.7, 1.0],
        m=[2.0, 1.5, 1.0, 1.2, 0.8, 1.4, 0.9, 1.1],
        EI=2e4,
        mu=[0, 1.0, 0, 0.5, 0.3, 0, 0.2, 0.4],
        kappa=[0, 80, 40, 60, 20, 50, 30, 40],
        nu=[0, 0.4, 0.2, 0.1, 0.3, 0.2, 0.1, 0.2],
    )
    return Scene(
        name="eight_rod_wing",
        chain=chain,
        loads=(pulse(8, T=1.0), constant(4, X=5.0, Y=-8.0)),
        t_end=3.0,
        times=np.linspace(0, 3.0, 61),
        outputs=("phi", "energy") if energy else ("phi",),
    )


def _paper(energy: bool) -> Scene:
    return paper_scene(8, outputs=("phi", "energy") if energy else ("phi",))


#: (scene label, feature, scene builder with the feature on/off)
CASES: tuple[tuple[str, str, Callable[[bool], Scene]], ...] = (
    ("four-panel wing", "latches", four_panel_wing),
    ("8-rod wing", "energy", eight_rod_wing),
    ("paper example", "energy", _paper),
)


def best_run(
    scene: Scene, model: str, method: str | IntegratorSettings, repeats: int
) -> Trajectory:
    """The run with the smallest ``stats.wall_s`` of ``repeats`` after a warm-up (``method``:
    a method name, or whole settings)."""
    settings = method if isinstance(method, IntegratorSettings) else IntegratorSettings(method)
    simulate(scene, model, settings=settings)
    runs = [simulate(scene, model, settings=settings) for _ in range(repeats)]
    return min(runs, key=lambda tr: tr.stats.wall_s)


def event_gaps(fast: Trajectory, ref: Trajectory) -> tuple[float, float]:
    """(largest |lock-time difference| (s), largest relative impulse difference) between the
    events of two runs of one scene; NaN when their event sequences differ."""
    if [e["label"] for e in fast.events] != [e["label"] for e in ref.events]:
        return np.nan, np.nan
    dt = max((abs(a["t"] - b["t"]) for a, b in zip(fast.events, ref.events)), default=0.0)
    rel = 0.0
    for a, b in zip(fast.events, ref.events):
        if "angular_impulses" in b:
            x, y = np.asarray(a["angular_impulses"]), np.asarray(b["angular_impulses"])
            rel = max(rel, float(np.max(np.abs(x - y) / np.abs(y))))
    return dt, rel


def _row(
    label: str, feature: str, on: bool, model: str, fast: Trajectory, ref: Trajectory
) -> dict[str, Any]:
    row: dict[str, Any] = {
        "scene": label,
        "feature": feature,
        "with_feature": on,
        "model": model,
        "auto_method": fast.settings["method"],
        "auto_wall_s": fast.stats.wall_s,
        "auto_nfev": fast.stats.nfev,
        "auto_s_per_eval": fast.stats.wall_s / max(fast.stats.nfev, 1),
        "scipy_wall_s": ref.stats.wall_s,
        "scipy_nfev": ref.stats.nfev,
        "speedup": ref.stats.wall_s / fast.stats.wall_s,
        "events": len(fast.events),
        "max_event_dt_s": np.nan,
        "max_impulse_rel": np.nan,
        "auto_residual": fast.stats.energy_residual,
        "scipy_residual": ref.stats.energy_residual,
    }
    if on and feature == "latches":
        row["max_event_dt_s"], row["max_impulse_rel"] = event_gaps(fast, ref)
    return row


def fast_path_rows(repeats: int = 3, progress: Progress = print) -> pd.DataFrame:
    """One row per case, feature on/off and native model (module docstring)."""
    rows = []
    for label, feature, build in CASES:
        for on in (True, False):
            scene = build(on)
            for model in integrated_models():
                fast = best_run(scene, model, AUTO, repeats)
                ref = best_run(scene, model, "DOP853", repeats)
                rows.append(_row(label, feature, on, model, fast, ref))
                progress(
                    f"{label} ({feature} {'on' if on else 'off'}), {model}: auto "
                    f"{fast.stats.wall_s:.3f} s, scipy {ref.stats.wall_s:.3f} s"
                )
    return pd.DataFrame(rows)


def feature_costs(frame: pd.DataFrame) -> pd.DataFrame:
    """Per case and model: the default method's wall time and cost per evaluation with the
    feature over without it (the issue's "within 1.3x")."""
    out = []
    for (label, feature, model), g in frame.groupby(["scene", "feature", "model"], sort=False):
        on, off = g[g.with_feature].iloc[0], g[~g.with_feature].iloc[0]
        out.append(
            {
                "scene": label,
                "feature": feature,
                "model": model,
                "wall_ratio": on.auto_wall_s / off.auto_wall_s,
                "per_eval_ratio": on.auto_s_per_eval / off.auto_s_per_eval,
                "speedup_with_feature": on.speedup,
            }
        )
    return pd.DataFrame(out)
