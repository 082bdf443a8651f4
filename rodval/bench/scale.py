"""Large chains: the compiled right-hand side's cost and states at scale, subnormal counts,
the scale rows and fits, and the reduced-vs-full speed-up at equal accuracy at scale
(conventions in ``rodval.bench``)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from numba import njit

from rodval.bench.cost import fitted_exponent
from rodval.bench.precision import (
    SLOW_RUN_S,
    Progress,
    ladder,
    loosest_within,
    paper_system_of,
    with_provenance,
)
from rodval.core.scene import Scene, paper_scene
from rodval.core.settings import IntegratorSettings
from rodval.models.registry import integrated_models, simulate
from rodval.solvers.driver import integrate
from rodval.solvers.guard import GuardSpec
from rodval.solvers.system import CompiledForm, OdeSystem

#: Chain sizes of ``rodval bench scale`` (each model stops at its own budget, see scale_rows).
SCALE_N = (2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384, 32768, 65536, 100000)


#: Output times of the scale runs: every 0.1 s over 0..2 s, phi and phi' only (the default
#: 201 times with alpha, beta are costed separately: ``observe_s_per_time``).
SCALE_TIMES = tuple(np.linspace(0.0, 2.0, 21))


#: The state whose right-hand-side cost is measured "in the run": t = 0.5 s, mid-pulse.
RUN_STATE_T = 0.5


def scale_scene(n: int) -> Scene:
    """The paper chain of n rods, the paper's pulse at the last node, 0..2 s, 21 output times,
    outputs phi, phi'."""
    return paper_scene(n, times=SCALE_TIMES, outputs=("phi", "dphi"))


@njit(cache=True)
def _rhs_loop(  # the compiled form's rhs and its arguments, called reps times
    rhs: Any, t: float, y: Any, P: Any, S: Any, M: Any, L: Any, out: Any, reps: int
) -> None:
    for _ in range(reps):
        rhs(t, y, P, S, M, L, out)


def compiled_rhs_cost(
    form: CompiledForm, t: float, y: np.ndarray, min_time: float = 0.05, repeats: int = 3
) -> float:
    """Seconds per call of a CompiledForm's right-hand side at (t, y), called from a compiled
    loop (no Python call in between): min over ``repeats`` loops of >= ``min_time`` s."""
    y = np.ascontiguousarray(y, dtype=np.float64)
    out = np.empty_like(y)
    args = (form.rhs, float(t), y, form.P, form.S, form.M, form.L, out)
    _rhs_loop(*args, 1)  # compiles the loop for this function type on first use
    start = time.perf_counter()
    _rhs_loop(*args, 1)
    once = max(time.perf_counter() - start, 1e-7)
    reps = max(1, int(min_time / once))
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        _rhs_loop(*args, reps)
        best = min(best, (time.perf_counter() - start) / reps)
    return best


def _form(system: OdeSystem) -> CompiledForm:
    """The compiled form of ``system`` (ValueError for a system without one)."""
    form = system.compiled()
    if form is None:
        raise ValueError(f"{type(system).__name__} has no compiled form")
    return form


def compiled_states(system: OdeSystem, scene: Scene, settings: IntegratorSettings) -> np.ndarray:
    """The full state vectors at the scene's output times, from the compiled DOP853 run with
    ``settings`` (no guard; the driver's own run is timed separately)."""
    from rodval.solvers import compiled
    from rodval.solvers.driver import segment_edges

    times = np.asarray(scene.times, float)
    Y = np.empty((times.size, system.y0.size))
    controls = compiled.Controls(
        settings.rtol,
        settings.atol,
        settings.max_step,
        settings.first_step,
        settings.max_evaluations,
    )
    n_out = compiled.integrate_compiled(
        _form(system),
        system.y0,
        segment_edges(scene),
        times,
        Y,
        controls,
        GuardSpec(),  # no guard: the driver's own run is timed separately
    ).n_out
    return Y[:n_out]


def subnormal_count(y: np.ndarray) -> int:
    """Entries of ``y`` that are subnormal (0 < |v| < the smallest normal float64)."""
    a = np.abs(np.asarray(y, float))
    return int(np.count_nonzero((a > 0) & (a < np.finfo(float).tiny)))


def scale_row(
    model: str, n: int, rtol: float = 1e-6, repeats: int = 3, min_time: float = 0.05
) -> dict[str, Any]:
    """One (model, n) of the scale benchmark: set-up, integration wall time (min over
    ``repeats`` runs, one run when slower than SLOW_RUN_S), evaluations, the compiled RHS cost
    at a random state and at the run's state at RUN_STATE_T, the loop's cost per evaluation
    (wall / nfev) and the cost of the alpha/beta recovery per output time."""
    scene = scale_scene(n)
    settings = IntegratorSettings("DOP853-numba", rtol=rtol, atol=rtol * 1e-2)
    start = time.perf_counter()
    system = paper_system_of(model, scene)
    setup = time.perf_counter() - start
    runs = [integrate(system, scene, settings, model=model)]
    if runs[0].stats.wall_s <= SLOW_RUN_S:
        runs += [integrate(system, scene, settings, model=model) for _ in range(repeats)]
    traj = runs[-1]
    wall = min(r.stats.wall_s for r in runs)
    form = _form(system)
    y_rand = np.random.default_rng(0).normal(scale=0.5, size=system.y0.size)
    states = compiled_states(system, scene, settings)
    i_mid = int(np.argmin(np.abs(np.asarray(scene.times) - RUN_STATE_T)))
    y_mid = states[i_mid]
    rhs_random = compiled_rhs_cost(form, 0.3, y_rand, min_time)
    rhs_run = compiled_rhs_cost(form, RUN_STATE_T, y_mid, min_time)
    times = np.asarray(scene.times)[: len(states)]
    system.bending(times[:1], states[:1])  # loads the recovery kernel
    start = time.perf_counter()
    system.bending(times, states)
    observe = (time.perf_counter() - start) / len(states)
    row = {
        "model": model,
        "n": n,
        "rtol": rtol,
        "setup_s": setup,
        "wall_s": wall,
        "timed_runs": len(runs),
        "nfev": traj.stats.nfev,
        "nsteps": traj.stats.nsteps,
        "status": traj.stats.status,
        "wall_per_eval_s": wall / max(traj.stats.nfev, 1),
        "rhs_random_s": rhs_random,
        "rhs_run_s": rhs_run,
        "subnormals_run_state": subnormal_count(y_mid),
        "observe_s_per_time": observe,
    }
    return row


def scale_rows(
    n_values: Sequence[int] = SCALE_N,
    models: tuple[str, ...] | None = None,
    rtol: float = 1e-6,
    repeats: int = 3,
    budget_s: float = 60.0,
    progress: Progress = print,
) -> tuple[pd.DataFrame, list[str]]:
    """``scale_row`` for every n (ascending) and model (default: the native ones), the models
    side by side at each n; a model stops after its first run slower than ``budget_s``
    (noted)."""
    models = integrated_models() if models is None else tuple(models)
    rows, notes, stopped = [], [], set()
    for n in sorted(n_values):
        for model in models:
            if model in stopped:
                continue
            row = scale_row(model, n, rtol, repeats)
            rows.append(row)
            progress(
                f"{model:8s} n = {n:6d}: wall {row['wall_s']:9.4f} s  nfev {row['nfev']:6d}  "
                f"set-up {row['setup_s']:7.3f} s  RHS {row['rhs_random_s'] * 1e6:9.1f} us "
                f"(run state {row['rhs_run_s'] * 1e6:9.1f} us)  loop/eval "
                f"{row['wall_per_eval_s'] * 1e6:9.1f} us"
            )
            if row["wall_s"] > budget_s:
                stopped.add(model)
                notes.append(
                    f"{model}: stopped after n = {n} ({row['wall_s']:.1f} s > budget {budget_s:g} s)"
                )
    return with_provenance(pd.DataFrame(rows)), notes


def scale_fits(frame: pd.DataFrame, n_min: int = 64) -> pd.DataFrame:
    """Fitted exponents (``fitted_exponent``, n >= n_min) of each model's costs against n."""
    cols = ("wall_s", "rhs_random_s", "rhs_run_s", "wall_per_eval_s", "setup_s")
    rows = []
    for model, part in frame.groupby("model", sort=False):
        part = part[part.n >= n_min]
        if len(part) < 2:
            continue
        row = {"model": model, "n range": f"{part.n.min()}..{part.n.max()}"}
        for c in cols:
            row[c] = fitted_exponent(part.n.to_numpy(), part[c].to_numpy())
        rows.append(row)
    return pd.DataFrame(rows)


#: The tight reference of ``speedup_scale``: the same model, compiled DOP853 at this rtol.
SCALE_REFERENCE_RTOL = 1e-11


def speedup_scale(
    n_values: Sequence[int] = (2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 10000),
    tol: float = 1e-6,
    rtols: Sequence[float] = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9),
    repeats: int = 3,
    progress: Progress = print,
) -> pd.DataFrame:
    """Reduced vs full at equal phi accuracy against n, both models at each n in one run: per
    model the loosest rung of the compiled DOP853 ladder (atol = rtol/100) whose max phi error
    (``errors``) against the same model at rtol SCALE_REFERENCE_RTOL is <= tol; its wall time
    (min over repeats, one run when slower than SLOW_RUN_S). LSODA references (``references``)
    are O(n^3) and out of reach at these sizes."""
    rows = []
    for n in n_values:
        scene = scale_scene(n)
        for model in integrated_models():
            ref = simulate(
                scene,
                model,
                method="DOP853-numba",
                rtol=SCALE_REFERENCE_RTOL,
                atol=SCALE_REFERENCE_RTOL * 1e-2,
            )
            if not ref.success:
                raise RuntimeError(f"reference run of {model} n = {n} failed: {ref.stats.message}")
            rungs = ladder(model, "DOP853-numba", rtols)
            best = loosest_within(scene, model, rungs, ref, tol, repeats)
            rtol, traj, wall, err = best if best else (math.nan, None, math.nan, math.nan)
            nfev = traj.stats.nfev if traj is not None else math.nan
            rows.append(
                {
                    "n": n,
                    "model": model,
                    "rtol": rtol,
                    "wall_s": wall,
                    "nfev": nfev,
                    "max_phi": err,
                    "reference_wall_s": ref.stats.wall_s,
                }
            )
            progress(f"n = {n:6d} {model:8s}: {wall:9.4f} s at rtol {rtol:g} (phi error {err:.1e})")
    frame = pd.DataFrame(rows)
    wide = frame.pivot(index="n", columns="model", values=["wall_s", "rtol", "nfev", "max_phi"])
    wide.columns = [f"{m}_{c}" for c, m in wide.columns]
    wide["full/reduced"] = wide["full_wall_s"] / wide["reduced_wall_s"]
    return with_provenance(wide.reset_index())
