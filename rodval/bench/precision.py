"""Work-precision: errors against a reference computed with a different method, runs timed
side by side, the cheapest settings per accuracy and the baseline ratios (conventions in
``rodval.bench``)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rodval.analysis.metrics import scaled_errors
from rodval.core.provenance import machine, package_versions
from rodval.core.scene import Scene
from rodval.core.settings import IntegratorSettings
from rodval.core.trajectory import Trajectory
from rodval.models import get_model
from rodval.models.registry import (
    integrated_models,
    option_names,
    simulate,
    uses_integrator,
)
from rodval.models.systems.paper_system import PaperSystem
from rodval.solvers.ode_model import OdeModel

QUANTITIES = ("phi", "dphi", "alpha", "beta")
#: Where a benchmark reports each run (``print`` by default).
Progress = Callable[[str], object]


DOP853_FAMILY = ("DOP853", "DOP853-numba")


#: The two references: (method, rtol, atol).
REFERENCE_DOP = ("LSODA", 1e-12, 1e-14)


REFERENCE_OTHER = ("DOP853-numba", 1e-13, 1e-15)


#: Reference models (exudyn) integrate with a fixed step: their precision ladder is the step
#: (s), and their reference is a run with a *different* solver at a much finer step.
REFERENCE_MODEL_STEPS = (1e-3, 5e-4, 2e-4, 1e-4, 5e-5)


REFERENCE_MODEL_REF: dict[str, Any] = {"solver": "trapezoidal", "step": 2e-5}


#: The right-hand sides a native model may take (its option ``kernel``): compiled, and the
#: dense numpy reference.
KERNELS = ("numba", "numpy")


def kernel_options(model: str) -> dict[str, dict[str, str]]:
    """The right-hand sides the benchmarks time native model ``model`` with, each with the
    model options that select it: both ``KERNELS`` for a model that takes the option
    ``kernel`` (full, reduced), the compiled one alone, with no option, for a model that
    does not (rigid: its kernel is fixed). From the registry (``option_names``)."""
    if "kernel" in option_names(model):
        return {kernel: {"kernel": kernel} for kernel in KERNELS}
    return {"numba": {}}


def numpy_models(models: tuple[str, ...] | None = None) -> tuple[str, ...]:
    """Those of ``models`` (default: every model) that rodval integrates and that have a numpy
    right-hand side (``kernel_options``), in their order."""
    native = integrated_models()
    chosen = native if models is None else models
    return tuple(m for m in chosen if m in native and "numpy" in kernel_options(m))


def paper_system_of(model: str, scene: Scene, **options: Any) -> PaperSystem:
    """The ODE system of ``scene`` in paper model ``model`` (its options given), what the
    cost benchmarks time; ValueError for any other model."""
    m = get_model(model, **options)
    system = m.system(scene) if isinstance(m, OdeModel) else None
    if not isinstance(system, PaperSystem):
        raise ValueError(f"model {model!r} is not one of the paper's models")
    return system


def ladder(
    model: str, method: str, rtols: Sequence[float]
) -> list[tuple[float, IntegratorSettings, dict[str, Any]]]:
    """(precision knob, settings, model options), loosest first: the tolerance ladder
    (atol = rtol / 100) for native models, the step ladder for fixed-step reference models."""
    if uses_integrator(model):
        return [
            (r, IntegratorSettings(method=method, rtol=r, atol=r * 1e-2), {})
            for r in sorted(rtols, reverse=True)
        ]
    return [(h, IntegratorSettings(), {"step": h}) for h in REFERENCE_MODEL_STEPS]


def reference_model_reference(scene: Scene, model: str) -> Trajectory:
    """A fixed-step reference model's reference: another solver at a much finer step."""
    run = simulate(scene, model, **REFERENCE_MODEL_REF)
    if not run.success:
        raise RuntimeError(f"reference run of {model} failed: {run.stats.message}")
    return run


#: Runs whose warm-up takes longer than this (s) are timed once (their noise is relatively small).
SLOW_RUN_S = 2.0


def timed(
    scene: Scene, model: str, settings: IntegratorSettings, repeats: int = 3, **options: Any
) -> tuple[Trajectory, float]:
    """(trajectory, min wall time over ``repeats`` runs after a warm-up run) in s."""
    warm = simulate(scene, model, settings=settings, **options)
    count = 1 if warm.stats.wall_s > SLOW_RUN_S else repeats
    runs = [simulate(scene, model, settings=settings, **options) for _ in range(count)]
    return runs[-1], min(r.stats.wall_s for r in runs)


def loosest_within(
    scene: Scene,
    model: str,
    rungs: list[tuple[float, IntegratorSettings, dict[str, Any]]],
    ref: Trajectory,
    tol: float,
    repeats: int,
) -> tuple[float, Trajectory, float, float] | None:
    """The first (loosest) of ``rungs`` (``ladder``) whose run's phi error (``max_phi`` of
    ``errors``) against ``ref`` is <= tol: (its knob, trajectory, wall time (s, ``timed``),
    error); None when none is."""
    for knob, settings, opts in rungs:
        traj, wall = timed(scene, model, settings, repeats, **opts)
        err = errors(traj, ref, ("phi",))["max_phi"]
        if err <= tol:
            return knob, traj, wall, err
    return None


def errors(
    traj: Trajectory, ref: Trajectory, quantities: Sequence[str] = QUANTITIES
) -> dict[str, float]:
    """Relative errors of ``traj`` against ``ref`` (``rodval.analysis.metrics.scaled_errors``
    per quantity as ``final_q``, ``rms_q``, ``max_q``, and ``scd``; see module docstring); NaN
    for a run that did not reach every output time. A reference that is zero throughout (the
    rigid model's alpha, beta) has no scale: the errors are 0 where the run is zero too, else
    inf."""
    out: dict[str, float] = {}
    worst = 0.0
    for q in quantities:
        if q not in ref.values:
            continue
        if q not in traj.values or len(traj.times) != len(ref.times):
            out.update({f"final_{q}": math.nan, f"rms_{q}": math.nan, f"max_{q}": math.nan})
            worst = math.inf
            continue
        if not np.any(ref[q]):
            e = 0.0 if not np.any(traj[q]) else math.inf
            out.update({f"final_{q}": e, f"rms_{q}": e, f"max_{q}": e})
        else:
            out.update({f"{k}_{q}": v for k, v in scaled_errors(traj[q], ref[q]).items()})
        worst = max(worst, out[f"max_{q}"])
    out["scd"] = (
        -math.log10(worst) if 0 < worst < math.inf else (math.inf if worst == 0 else math.nan)
    )
    return out


@dataclass
class References:
    """The two references of one (scene, model) and their mutual difference."""

    dop: Trajectory  # for the DOP853 family
    other: Trajectory  # for every other method
    uncertainty: float  # max relative difference over phi, dphi

    def for_method(self, method: str) -> Trajectory:
        return self.dop if method in DOP853_FAMILY else self.other


def references(scene: Scene, model: str, **options: Any) -> References:
    runs = [
        simulate(scene, model, method=m, rtol=r, atol=a, **options)
        for m, r, a in (REFERENCE_DOP, REFERENCE_OTHER)
    ]
    for run in runs:
        if not run.success:
            raise RuntimeError(f"reference run of {model} failed: {run.stats.message}")
    e = errors(runs[0], runs[1], ("phi", "dphi"))
    return References(runs[0], runs[1], max(e["max_phi"], e["max_dphi"]))


def work_precision(
    scene: Scene,
    models: list[str],
    methods: list[str],
    rtols: list[float],
    *,
    repeats: int = 3,
    budget_s: float = 20.0,
    baseline: bool = True,
    progress: Progress = print,
) -> tuple[pd.DataFrame, dict[str, float], list[str]]:
    """One row per (model, method, kernel, rtol): cost and errors. For each model and method
    the ladder (loosest first) stops after a run slower than ``budget_s``. ``baseline`` adds
    scipy DOP853 with the numpy right-hand side (``kernel="numpy"``) for native models.

    Returns (rows, reference uncertainty per model, notes)."""
    rows: list[dict[str, Any]] = []
    uncertainty: dict[str, float] = {}
    notes: list[str] = []
    for model in models:
        try:
            get_model(model)
        except ValueError as exc:
            notes.append(f"model {model} skipped: {exc}")
            continue
        native, kernels = uses_integrator(model), kernel_options(model)
        refs, variants = _model_plan(scene, model, methods, baseline, notes)
        if isinstance(refs, References):
            uncertainty[model] = refs.uncertainty
        for method, kernel in variants:
            for knob, settings, opts in ladder(model, method, rtols):
                if native:
                    opts = kernels[kernel]
                traj, wall = timed(scene, model, settings, repeats, **opts)
                ref = refs.for_method(method) if isinstance(refs, References) else refs
                row = {
                    "model": model,
                    "method": method if native else traj.options["solver"],
                    "kernel": kernel,
                    "rtol": knob if native else math.nan,
                    "atol": settings.atol if native else math.nan,
                    "step": math.nan if native else knob,
                    **traj.stats.as_dict(),
                    "reference": (
                        f"{ref.settings['method']} rtol {ref.settings['rtol']:g}"
                        if native
                        else f"{model} {REFERENCE_MODEL_REF}"
                    ),
                }
                row["wall_s"] = wall  # the minimum, not the last run's
                row.update(errors(traj, ref))
                rows.append(row)
                progress(
                    f"{model:8s} {row['method']:13s} {kernel:6s} "
                    f"{'rtol' if native else 'step'} {knob:7.0e}  wall {wall * 1e3:9.2f} ms  "
                    f"nfev {traj.stats.nfev:7d}  phi err {row.get('max_phi', math.nan):.2e}"
                )
                if wall > budget_s:
                    notes.append(
                        f"{model} {method} {kernel}: ladder stopped after {knob:g} "
                        f"({wall:.1f} s > budget {budget_s:g} s)"
                    )
                    break
    frame = pd.DataFrame(rows)
    return with_provenance(frame), uncertainty, notes


def _model_plan(
    scene: Scene, model: str, methods: list[str], baseline: bool, notes: list[str]
) -> tuple[References | Trajectory, list[tuple[str, str]]]:
    """The references of ``model`` (``References`` of a native model, the fixed-step reference
    of a reference model) and its (method, kernel) variants: every one of ``methods`` on the
    compiled right-hand side, and with ``baseline`` scipy DOP853 on the numpy one where the
    model has it, for a native model; its default solver for a reference model (``notes``
    say so)."""
    if uses_integrator(model):
        refs = references(scene, model)
        variants = [(m, "numba") for m in methods]
        if baseline and "numpy" in kernel_options(model):
            variants.append(("DOP853", "numpy"))
        elif baseline:
            notes.append(f"model {model}: no numpy right-hand side, so no numpy baseline")
        return refs, variants
    ref_model = reference_model_reference(scene, model)
    notes.append(
        f"model {model}: step ladder {REFERENCE_MODEL_STEPS} s (its default "
        f"solver); reference = {REFERENCE_MODEL_REF}"
    )
    return ref_model, [("default", "")]


def with_provenance(frame: pd.DataFrame) -> pd.DataFrame:
    """Machine and package versions as constant columns (so a CSV carries its own context)."""
    info = {
        **{k: str(v) for k, v in machine().items()},
        **{f"version_{k}": str(v) for k, v in package_versions().items()},
    }
    return frame.assign(**info)


def cheapest(frame: pd.DataFrame, quantity: str = "phi", tol: float = 1e-6) -> pd.DataFrame:
    """Per (model, method, kernel): the fastest run whose ``max_<quantity>`` <= tol."""
    ok = frame[frame[f"max_{quantity}"] <= tol]
    idx = ok.groupby(["model", "method", "kernel"])["wall_s"].idxmin()
    return ok.loc[idx].sort_values(["model", "wall_s"])


def baseline_ratios(
    scene: Scene,
    models: tuple[str, ...] | None = None,
    tol: float = 1e-6,
    rtols: Sequence[float] = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10),
    repeats: int = 3,
    progress: Progress = print,
) -> pd.DataFrame:
    """Per model of ``models`` (default: every model) that has a numpy right-hand side
    (``numpy_models``; the others have no baseline and are left out): the loosest rtol at
    which the compiled DOP853 reaches phi error <= tol, then, side by side at that same
    tolerance, scipy DOP853 with the numba kernel and with the straightforward numpy kernel;
    speed-up = baseline wall / compiled wall."""
    rows = []
    for model in numpy_models(models):
        refs = references(scene, model)
        for rtol in sorted(rtols, reverse=True):
            settings = IntegratorSettings("DOP853-numba", rtol=rtol, atol=rtol * 1e-2)
            fast, wall = timed(scene, model, settings, repeats)
            err = errors(fast, refs.dop)["max_phi"]
            if err <= tol:
                break
        runs = {"DOP853-numba/numba": (fast, wall)}
        for kernel in ("numba", "numpy"):
            s = IntegratorSettings("DOP853", rtol=rtol, atol=rtol * 1e-2)
            runs[f"DOP853/{kernel}"] = timed(scene, model, s, repeats, kernel=kernel)
        for name, (traj, w) in runs.items():
            method, kernel = name.split("/")
            rows.append(
                {
                    "model": model,
                    "method": method,
                    "kernel": kernel,
                    "rtol": rtol,
                    "wall_s": w,
                    "nfev": traj.stats.nfev,
                    "max_phi": errors(traj, refs.dop)["max_phi"],
                    "speedup_vs_numpy_DOP853": runs["DOP853/numpy"][1] / w,
                }
            )
            progress(f"{model:8s} {name:20s} rtol {rtol:g}: {w * 1e3:9.2f} ms")
    return with_provenance(pd.DataFrame(rows))
