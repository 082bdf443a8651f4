"""Cost per evaluation against n, the cost of what a scene may skip, and the reduced-vs-full
speed-up against n (conventions in ``rodval.bench``)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from rodval.bench.precision import (
    KERNELS,
    Progress,
    kernel_options,
    ladder,
    loosest_within,
    paper_system_of,
    reference_model_reference,
    references,
    timed,
    with_provenance,
)
from rodval.core.scene import paper_scene
from rodval.core.settings import IntegratorSettings
from rodval.models import get_model
from rodval.models.registry import MODEL_NAMES, integrated_models, uses_integrator
from rodval.models.systems.paper_system import PaperSystem
from rodval.solvers.driver import integrate

#: The wall-time ratios of ``speedup_vs_n`` ("a/b": model a's time over model b's), where
#: both models ran: the paper's reduced-vs-full claim and the independent model against each.
SPEEDUP_RATIOS = ("full/reduced", "exudyn/full", "exudyn/reduced")


def per_eval_cost(
    n_values: Sequence[int] = (2, 4, 8, 16, 32, 64, 128, 256, 512),
    kernels: Sequence[str] = KERNELS,
    models: Sequence[str] = ("full",),
    min_time: float = 0.05,
    repeats: int = 3,
    progress: Progress = print,
) -> pd.DataFrame:
    """Seconds per right-hand-side evaluation (min over repeats of a timed loop) against n at
    a random state with the load active, for each of ``kernels`` a model has
    (``kernel_options``)."""
    rows = []
    rng = np.random.default_rng(0)
    for model in models:
        taken = kernel_options(model)
        for kernel in [k for k in kernels if k in taken]:
            for n in n_values:
                system = paper_system_of(model, paper_scene(n), **taken[kernel])
                y = rng.normal(scale=0.5, size=system.y0.size)
                system.rhs(0.3, y)
                reps = max(1, int(min_time / max(_timeit(system, y, 0.3, 1), 1e-7)))
                best = min(_timeit(system, y, 0.3, reps) for _ in range(repeats))
                rows.append({"model": model, "kernel": kernel, "n": n, "s_per_eval": best})
                progress(f"{model} {kernel:5s} n = {n:4d}: {best * 1e6:10.2f} us/eval")
    return with_provenance(pd.DataFrame(rows))


def fitted_exponent(n: np.ndarray, cost: np.ndarray, n_min: int = 1) -> float:
    """Least-squares slope of log(cost) against log(n) over n >= n_min."""
    keep = np.asarray(n) >= n_min
    return float(np.polyfit(np.log(np.asarray(n)[keep]), np.log(np.asarray(cost)[keep]), 1)[0])


def skip_rows(repeats: int = 5, progress: Progress = print) -> pd.DataFrame:
    """Cost with and without each skip, paper example n = 8, compiled DOP853 at rtol 1e-8
    (outputs and dense output: scipy DOP853, where they run in Python):

    * damping: nu = 0 chain, damping terms skipped vs forced on (C = 0, same result);
    * load: RHS evaluation past the load's support (no load term) vs inside it, with each
      right-hand side a model has (``kernel_options``);
    * gamma recovery: reduced model with outputs phi, dphi vs phi, dphi, alpha, beta;
    * dense output: 4 output times vs 2001 (dense output formed only on steps containing one).
    """
    rows = _damping_rows(repeats) + _load_rows(repeats) + _output_rows(repeats)
    for r in rows:
        progress(
            f"{r['skip']:60s} {r['model']:8s} {r['with_skip_s'] * 1e3:9.3f} ms vs "
            f"{r['without_skip_s'] * 1e3:9.3f} ms"
        )
    return with_provenance(pd.DataFrame(rows))


def _damping_rows(repeats: int) -> list[dict[str, Any]]:
    """Per native model: the damping terms skipped on a nu = 0 chain vs forced on."""
    rows = []
    settings = IntegratorSettings("DOP853-numba", rtol=1e-8, atol=1e-10)
    undamped = paper_scene(8, times=(0.5, 1.0, 1.5, 2.0), nu=0.0)
    for model in integrated_models():
        walls = {}
        for forced in (False, True):
            system = paper_system_of(model, undamped)
            system.damped = forced
            system.use_kernel()  # the compiled kernels read the flag from the arrays it sets
            runs = [integrate(system, undamped, settings, model=model) for _ in range(repeats + 1)]
            walls[forced] = (min(r.stats.wall_s for r in runs[1:]), runs[-1])
        same = np.max(np.abs(walls[True][1]["phi"] - walls[False][1]["phi"]))
        rows.append(
            _skip_row(
                "damping terms (all nu = 0)",
                model,
                walls[False][0],
                walls[True][0],
                f"max |phi difference| = {same:.1e}",
            )
        )
    return rows


def _load_rows(repeats: int) -> list[dict[str, Any]]:
    """Per native model and right-hand side: an evaluation past the load's support vs in it."""
    rows = []
    for model in integrated_models():
        for kernel, options in kernel_options(model).items():
            system = paper_system_of(model, paper_scene(8), **options)
            y = np.random.default_rng(1).normal(scale=0.5, size=system.y0.size)
            cost = {t: min(_timeit(system, y, t) for _ in range(repeats)) for t in (1.5, 0.3)}
            rows.append(
                _skip_row(
                    f"load term past its support ({kernel} RHS, per eval)",
                    model,
                    cost[1.5],
                    cost[0.3],
                    "t = 1.5 s (skipped) vs 0.3 s (evaluated)",
                )
            )
    return rows


def _output_rows(repeats: int) -> list[dict[str, Any]]:
    """The reduced model's gamma recovery skipped (outputs phi, dphi only) and its dense output
    formed only on the steps with output times (4 vs 2001 of them)."""
    rows = []
    scipy_dop = IntegratorSettings("DOP853", rtol=1e-8, atol=1e-10)
    times = np.linspace(0, 2, 201)
    lean = paper_scene(8, times=times, outputs=("phi", "dphi"))
    full_out = paper_scene(8, times=times)
    w_lean = timed(lean, "reduced", scipy_dop, repeats)[1]
    w_full = timed(full_out, "reduced", scipy_dop, repeats)[1]
    rows.append(
        _skip_row(
            "gamma recovery (outputs phi, dphi only; 201 times)",
            "reduced",
            w_lean,
            w_full,
            "vs outputs phi, dphi, alpha, beta",
        )
    )
    few, fe = timed(paper_scene(8, times=(0.5, 1.0, 1.5, 2.0)), "reduced", scipy_dop, repeats)
    many, ma = timed(paper_scene(8, times=np.linspace(0, 2, 2001)), "reduced", scipy_dop, repeats)
    rows.append(
        _skip_row(
            "dense output only on steps with output times",
            "reduced",
            fe,
            ma,
            f"4 vs 2001 output times; nfev {few.stats.nfev} vs {many.stats.nfev}",
        )
    )
    return rows


def _timeit(system: PaperSystem, y: np.ndarray, t: float, reps: int = 2000) -> float:
    """Seconds per right-hand-side evaluation of ``system`` at (t, y), over ``reps`` of them."""
    start = time.perf_counter()
    for _ in range(reps):
        system.rhs(t, y)
    return (time.perf_counter() - start) / reps


def _skip_row(skip: str, model: str, with_skip: float, without: float, note: str) -> dict[str, Any]:
    return {
        "skip": skip,
        "model": model,
        "with_skip_s": with_skip,
        "without_skip_s": without,
        "saving": 1 - with_skip / without,
        "note": note,
    }


def speedup_vs_n(
    n_values: Sequence[int] = (2, 4, 8, 16, 32),
    tol: float = 1e-6,
    rtols: Sequence[float] = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10),
    repeats: int = 3,
    models: tuple[str, ...] = MODEL_NAMES,
    progress: Progress = print,
) -> tuple[pd.DataFrame, list[str]]:
    """For each n and model: the cheapest rung of its precision ladder (``ladder``: compiled
    DOP853 tolerances for native models, the step for exudyn) with phi error <= tol against
    that model's own reference; then the full/reduced (and exudyn/native) wall-time ratios at
    that equal accuracy. For exudyn the accuracy is that of its time integration at fixed
    spatial discretization (2 elements per rod by default)."""
    rows: list[dict[str, Any]] = []
    notes, available = [], []
    for model in models:
        try:
            get_model(model)
            available.append(model)
        except ValueError as exc:
            notes.append(f"model {model} skipped: {exc}")
    for n in n_values:
        scene = paper_scene(n, times=np.linspace(0, 2, 21), outputs=("phi", "dphi"))
        for model in available:
            native = uses_integrator(model)
            ref = (
                references(scene, model).dop if native else reference_model_reference(scene, model)
            )
            method = "DOP853-numba" if native else "default"
            best = loosest_within(scene, model, ladder(model, method, rtols), ref, tol, repeats)
            rows.append(
                {
                    "n": n,
                    "model": model,
                    "method": method,
                    "rtol" if native else "step": best[0] if best else math.nan,
                    "wall_s": best[2] if best else math.nan,
                    "nfev": best[1].stats.nfev if best else math.nan,
                }
            )
            knob_name = "rtol" if native else "step"
            progress(
                f"n = {n:3d} {model:8s}: {rows[-1]['wall_s'] * 1e3:9.2f} ms at {knob_name} "
                f"{rows[-1][knob_name]:g}"
            )
    frame = pd.DataFrame(rows)
    wide = frame.pivot(index="n", columns="model", values="wall_s")
    for ratio in SPEEDUP_RATIOS:
        a, b = ratio.split("/")
        if {a, b} <= set(wide):
            wide[ratio] = wide[a] / wide[b]
    return with_provenance(wide.reset_index()), notes
