"""Performance measurements: work-precision, cost per evaluation against n, the cost of what a
scene may skip, and reduced-vs-full speed-up at equal accuracy.

Conventions
-----------
* Wall time is the integration's own ``stats.wall_s`` (no model set-up, no compilation), the
  minimum over ``repeats`` runs after one warm-up run. Runs that are compared are measured in
  the same process, one after the other, so that their ratio is meaningful on a shared machine.
* Errors are against a reference computed with a *different* method: LSODA at rtol 1e-12 for
  the DOP853 family, the compiled DOP853 at rtol 1e-13 for every other method (their mutual
  difference is reported as the reference uncertainty). Per quantity q (phi, dphi, alpha,
  beta), with d = q - q_ref over all output times and rods and s = max |q_ref|:
  ``final_q`` = max_k |d(t_end)| / s, ``rms_q`` = RMS(d) / s, ``max_q`` = max |d| / s;
  ``scd`` = -log10 of the largest ``max_q``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numba import njit

from rodval.analysis.metrics import pareto_front, scaled_errors  # noqa: F401 - pareto_front: bench API
from rodval.core.provenance import machine, package_versions
from rodval.core.scene import Scene, paper_scene
from rodval.core.settings import IntegratorSettings
from rodval.core.trajectory import Trajectory
from rodval.models import get_model
from rodval.models.registry import simulate
from rodval.solvers.driver import integrate

QUANTITIES = ("phi", "dphi", "alpha", "beta")
DOP853_FAMILY = ("DOP853", "DOP853-numba")
#: The two references: (method, rtol, atol).
REFERENCE_DOP = ("LSODA", 1e-12, 1e-14)
REFERENCE_OTHER = ("DOP853-numba", 1e-13, 1e-15)
#: Reference models (exudyn) integrate with a fixed step: their precision ladder is the step
#: (s), and their reference is a run with a *different* solver at a much finer step.
REFERENCE_MODEL_STEPS = (1e-3, 5e-4, 2e-4, 1e-4, 5e-5)
REFERENCE_MODEL_REF = {"solver": "trapezoidal", "step": 2e-5}
NATIVE = ("full", "reduced")


def ladder(model: str, method: str, rtols) -> list[tuple[float, IntegratorSettings, dict]]:
    """(precision knob, settings, model options), loosest first: the tolerance ladder
    (atol = rtol / 100) for native models, the step ladder for fixed-step reference models."""
    if model in NATIVE:
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
    scene: Scene, model: str, settings: IntegratorSettings, repeats: int = 3, **options
) -> tuple[Trajectory, float]:
    """(trajectory, min wall time over ``repeats`` runs after a warm-up run) in s."""
    warm = simulate(scene, model, settings=settings, **options)
    count = 1 if warm.stats.wall_s > SLOW_RUN_S else repeats
    runs = [simulate(scene, model, settings=settings, **options) for _ in range(count)]
    return runs[-1], min(r.stats.wall_s for r in runs)


def errors(traj: Trajectory, ref: Trajectory, quantities=QUANTITIES) -> dict[str, float]:
    """Relative errors of ``traj`` against ``ref`` (``rodval.analysis.metrics.scaled_errors``
    per quantity as ``final_q``, ``rms_q``, ``max_q``, and ``scd``; see module docstring); NaN
    for a run that did not reach every output time."""
    out: dict[str, float] = {}
    worst = 0.0
    for q in quantities:
        if q not in ref.values:
            continue
        if q not in traj.values or len(traj.times) != len(ref.times):
            out.update({f"final_{q}": math.nan, f"rms_{q}": math.nan, f"max_{q}": math.nan})
            worst = math.inf
            continue
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


def references(scene: Scene, model: str, **options) -> References:
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
    progress=print,
) -> tuple[pd.DataFrame, dict[str, float], list[str]]:
    """One row per (model, method, kernel, rtol): cost and errors. For each model and method
    the ladder (loosest first) stops after a run slower than ``budget_s``. ``baseline`` adds
    scipy DOP853 with the numpy right-hand side (``kernel="numpy"``) for native models.

    Returns (rows, reference uncertainty per model, notes)."""
    rows, uncertainty, notes = [], {}, []
    for model in models:
        try:
            get_model(model)
        except ValueError as exc:
            notes.append(f"model {model} skipped: {exc}")
            continue
        native = model in NATIVE
        if native:
            refs = references(scene, model)
            uncertainty[model] = refs.uncertainty
            variants = [(m, "numba") for m in methods] + ([("DOP853", "numpy")] if baseline else [])
        else:
            ref_model = reference_model_reference(scene, model)
            notes.append(
                f"model {model}: step ladder {REFERENCE_MODEL_STEPS} s (its default "
                f"solver); reference = {REFERENCE_MODEL_REF}"
            )
            variants = [("default", "")]
        for method, kernel in variants:
            for knob, settings, opts in ladder(model, method, rtols):
                if native:
                    opts = {"kernel": kernel}
                traj, wall = timed(scene, model, settings, repeats, **opts)
                ref = refs.for_method(method) if native else ref_model
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
    tol: float = 1e-6,
    rtols=(1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10),
    repeats: int = 3,
    progress=print,
) -> pd.DataFrame:
    """Per native model: the loosest rtol at which the compiled DOP853 reaches phi error <= tol,
    then, side by side at that same tolerance, scipy DOP853 with the numba kernel and with
    the straightforward numpy kernel; speed-up = baseline wall / compiled wall."""
    rows = []
    for model in ("reduced", "full"):
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


def per_eval_cost(
    n_values=(2, 4, 8, 16, 32, 64, 128, 256, 512),
    kernels=("numba", "numpy"),
    models=("full",),
    min_time: float = 0.05,
    repeats: int = 3,
    progress=print,
) -> pd.DataFrame:
    """Seconds per right-hand-side evaluation (min over repeats of a timed loop) against n at
    a random state with the load active."""
    rows = []
    rng = np.random.default_rng(0)
    for model in models:
        for kernel in kernels:
            for n in n_values:
                system = get_model(model, kernel=kernel).system(paper_scene(n))
                y = rng.normal(scale=0.5, size=system.y0.size)
                system.rhs(0.3, y)
                reps = max(1, int(min_time / _once(system, y)))
                best = min(_loop(system, y, reps) for _ in range(repeats)) / reps
                rows.append({"model": model, "kernel": kernel, "n": n, "s_per_eval": best})
                progress(f"{model} {kernel:5s} n = {n:4d}: {best * 1e6:10.2f} us/eval")
    return with_provenance(pd.DataFrame(rows))


def _once(system, y) -> float:
    t = time.perf_counter()
    system.rhs(0.3, y)
    return max(time.perf_counter() - t, 1e-7)


def _loop(system, y, reps: int) -> float:
    t = time.perf_counter()
    for _ in range(reps):
        system.rhs(0.3, y)
    return time.perf_counter() - t


def fitted_exponent(n: np.ndarray, cost: np.ndarray, n_min: int = 1) -> float:
    """Least-squares slope of log(cost) against log(n) over n >= n_min."""
    keep = np.asarray(n) >= n_min
    return float(np.polyfit(np.log(np.asarray(n)[keep]), np.log(np.asarray(cost)[keep]), 1)[0])


def skip_rows(repeats: int = 5, progress=print) -> pd.DataFrame:
    """Cost with and without each skip, paper example n = 8, compiled DOP853 at rtol 1e-8
    (outputs and dense output: scipy DOP853, where they run in Python):

    * damping: nu = 0 chain, damping terms skipped vs forced on (C = 0, same result);
    * load: RHS evaluation past the load's support (no load term) vs inside it;
    * gamma recovery: reduced model with outputs phi, dphi vs phi, dphi, alpha, beta;
    * dense output: 4 output times vs 2001 (dense output formed only on steps containing one).
    """
    rows = []
    settings = IntegratorSettings("DOP853-numba", rtol=1e-8, atol=1e-10)
    undamped = paper_scene(8, times=(0.5, 1.0, 1.5, 2.0), nu=0.0)
    for model in ("reduced", "full"):
        walls = {}
        for forced in (False, True):
            system = get_model(model).system(undamped)
            system.damped = forced
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
    for model in ("reduced", "full"):
        for kernel in ("numba", "numpy"):
            system = get_model(model, kernel=kernel).system(paper_scene(8))
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
    for r in rows:
        progress(
            f"{r['skip']:60s} {r['model']:8s} {r['with_skip_s'] * 1e3:9.3f} ms vs "
            f"{r['without_skip_s'] * 1e3:9.3f} ms"
        )
    return with_provenance(pd.DataFrame(rows))


def _timeit(system, y, t, reps: int = 2000) -> float:
    start = time.perf_counter()
    for _ in range(reps):
        system.rhs(t, y)
    return (time.perf_counter() - start) / reps


def _skip_row(skip: str, model: str, with_skip: float, without: float, note: str) -> dict:
    return {
        "skip": skip,
        "model": model,
        "with_skip_s": with_skip,
        "without_skip_s": without,
        "saving": 1 - with_skip / without,
        "note": note,
    }


def speedup_vs_n(
    n_values=(2, 4, 8, 16, 32),
    tol: float = 1e-6,
    rtols=(1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10),
    repeats: int = 3,
    models=("full", "reduced", "exudyn"),
    progress=print,
) -> tuple[pd.DataFrame, list[str]]:
    """For each n and model: the cheapest rung of its precision ladder (``ladder``: compiled
    DOP853 tolerances for native models, the step for exudyn) with phi error <= tol against
    that model's own reference; then the full/reduced (and exudyn/native) wall-time ratios at
    that equal accuracy. For exudyn the accuracy is that of its time integration at fixed
    spatial discretization (2 elements per rod by default)."""
    rows, notes = [], []
    available = []
    for model in models:
        try:
            get_model(model)
            available.append(model)
        except ValueError as exc:
            notes.append(f"model {model} skipped: {exc}")
    for n in n_values:
        scene = paper_scene(n, times=np.linspace(0, 2, 21), outputs=("phi", "dphi"))
        for model in available:
            native = model in NATIVE
            ref = (
                references(scene, model).dop if native else reference_model_reference(scene, model)
            )
            method = "DOP853-numba" if native else "default"
            best = None
            for knob, settings, opts in ladder(model, method, rtols):
                traj, wall = timed(scene, model, settings, repeats, **opts)
                if errors(traj, ref, ("phi",))["max_phi"] <= tol:
                    best = (knob, wall, traj.stats.nfev)
                    break
            rows.append(
                {
                    "n": n,
                    "model": model,
                    "method": method,
                    "rtol" if native else "step": best[0] if best else math.nan,
                    "wall_s": best[1] if best else math.nan,
                    "nfev": best[2] if best else math.nan,
                }
            )
            knob = "rtol" if native else "step"
            progress(
                f"n = {n:3d} {model:8s}: {rows[-1]['wall_s'] * 1e3:9.2f} ms at {knob} "
                f"{rows[-1][knob]:g}"
            )
    frame = pd.DataFrame(rows)
    wide = frame.pivot(index="n", columns="model", values="wall_s")
    if {"full", "reduced"} <= set(wide):
        wide["full/reduced"] = wide["full"] / wide["reduced"]
    if "exudyn" in wide:
        for m in ("full", "reduced"):
            wide[f"exudyn/{m}"] = wide["exudyn"] / wide[m]
    return with_provenance(wide.reset_index()), notes


# --- Scale: cost against n up to 1e5 rods -------------------------------------------------

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
def _rhs_loop(rhs, t, y, P, S, M, L, out, reps):
    for _ in range(reps):
        rhs(t, y, P, S, M, L, out)


def compiled_rhs_cost(form, t: float, y: np.ndarray, min_time: float = 0.05, repeats: int = 3):
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


def compiled_states(system, scene: Scene, settings: IntegratorSettings) -> np.ndarray:
    """The full state vectors at the scene's output times, from the compiled DOP853 run with
    ``settings`` (no guard; the driver's own run is timed separately)."""
    from rodval.solvers import dop853
    from rodval.solvers.driver import segment_edges

    times = np.asarray(scene.times, float)
    Y = np.empty((times.size, system.y0.size))
    n_out = dop853.integrate_compiled(
        system.compiled(),
        system.y0,
        segment_edges(scene),
        times,
        settings.rtol,
        settings.atol,
        settings.max_step,
        settings.first_step,
        settings.max_evaluations,
        np.array([0.0, math.inf, 0.0, 0.0]),
        10**9,
        Y,
    )[0]
    return Y[:n_out]


def subnormal_count(y: np.ndarray) -> int:
    """Entries of ``y`` that are subnormal (0 < |v| < the smallest normal float64)."""
    a = np.abs(np.asarray(y, float))
    return int(np.count_nonzero((a > 0) & (a < np.finfo(float).tiny)))


def scale_row(
    model: str, n: int, rtol: float = 1e-6, repeats: int = 3, min_time: float = 0.05
) -> dict:
    """One (model, n) of the scale benchmark: set-up, integration wall time (min over
    ``repeats`` runs, one run when slower than SLOW_RUN_S), evaluations, the compiled RHS cost
    at a random state and at the run's state at RUN_STATE_T, the loop's cost per evaluation
    (wall / nfev) and the cost of the alpha/beta recovery per output time."""
    scene = scale_scene(n)
    settings = IntegratorSettings("DOP853-numba", rtol=rtol, atol=rtol * 1e-2)
    start = time.perf_counter()
    system = get_model(model).system(scene)
    setup = time.perf_counter() - start
    runs = [integrate(system, scene, settings, model=model)]
    if runs[0].stats.wall_s <= SLOW_RUN_S:
        runs += [integrate(system, scene, settings, model=model) for _ in range(repeats)]
    traj = runs[-1]
    wall = min(r.stats.wall_s for r in runs)
    form = system.compiled()
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
    n_values=SCALE_N,
    models=("reduced", "full"),
    rtol: float = 1e-6,
    repeats: int = 3,
    budget_s: float = 60.0,
    progress=print,
) -> tuple[pd.DataFrame, list[str]]:
    """``scale_row`` for every n (ascending) and model, the models side by side at each n; a
    model stops after its first run slower than ``budget_s`` (noted)."""
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
    n_values=(2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 10000),
    tol: float = 1e-6,
    rtols=(1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9),
    repeats: int = 3,
    progress=print,
) -> pd.DataFrame:
    """Reduced vs full at equal phi accuracy against n, both models at each n in one run: per
    model the loosest rung of the compiled DOP853 ladder (atol = rtol/100) whose max phi error
    (``errors``) against the same model at rtol SCALE_REFERENCE_RTOL is <= tol; its wall time
    (min over repeats, one run when slower than SLOW_RUN_S). LSODA references (``references``)
    are O(n^3) and out of reach at these sizes."""
    rows = []
    for n in n_values:
        scene = scale_scene(n)
        for model in ("reduced", "full"):
            ref = simulate(
                scene,
                model,
                method="DOP853-numba",
                rtol=SCALE_REFERENCE_RTOL,
                atol=SCALE_REFERENCE_RTOL * 1e-2,
            )
            if not ref.success:
                raise RuntimeError(f"reference run of {model} n = {n} failed: {ref.stats.message}")
            best = None
            for rtol in sorted(rtols, reverse=True):
                settings = IntegratorSettings("DOP853-numba", rtol=rtol, atol=rtol * 1e-2)
                traj, wall = timed(scene, model, settings, repeats)
                err = errors(traj, ref, ("phi",))["max_phi"]
                if err <= tol:
                    best = (rtol, wall, traj.stats.nfev, err)
                    break
            rtol, wall, nfev, err = best if best else (math.nan,) * 4
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
