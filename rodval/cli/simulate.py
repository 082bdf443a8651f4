"""rodval simulate SCENE --model M --out DIR: one run, its trajectory + run.json.

SCENE is 'paper', a TOML scene file, or the run.json of an earlier run (rerun exactly: the
same resolved scene, model, options and integrator settings; options given here override).
DIR must be new, empty or a run folder of rodval (checked before any work); --max-wall is the
whole command's budget, from the process start to the last file written.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from rodval.cli.options import (
    add_integrator_options,
    add_model_options,
    integrator_settings,
    model_options,
    positive_float,
    time_list,
    with_scene_values,
)
from rodval.core.checks import check_keys
from rodval.core.scene import EXPANDS, MAX_TIMES, Scene
from rodval.core.scene_file import (
    read_scene_document,
    scene_from_dict,
    with_horizon,
)
from rodval.core.settings import SETTING_NAMES, IntegratorSettings
from rodval.core.validity import describe
from rodval.models import REGISTRY, simulate
from rodval.models.registry import uses_integrator
from rodval.report.run_files import (
    CSV_MAX_VALUES,
    INLINE_MAX,
    TABLE_FORMATS,
    TABLE_NPZ,
    claim_run_folder,
    read_run_record,
    table_file,
    value_count,
    write_estimate_s,
    write_run,
)
from rodval.solvers.progress import progress_bar

#: The keys of a run.json's settings a rerun reads: the settings, and the method asked for
#: when "auto" chose one.
RERUN_SETTINGS = (*SETTING_NAMES, "requested_method")
#: The model's work in the command outside its integration loop, per rod (s): building the
#: system (its arrays, the reduced model's banded factors), its first evaluation, the
#: guard's start, observation and the validity checks. Measured at n = 1e6 on the loaded
#: 2-core test machine (load average 9; the command's time in ``simulate`` outside the loop
#: with --set n=1000000 --set 'outputs=["phi"]' --times 0,1,2 --max-evaluations 30: full
#: 5.1e-6, reduced 4.1e-6, rigid 9.9e-6; the reduced model's was 2.2e-5 before issue 50's
#: set-up) with a margin; other models take the largest.
MODEL_S_PER_ROD = {"full": 6e-6, "reduced": 5e-6, "rigid": 1.2e-5}
#: Loading the compiled loop and kernels from numba's cache (s), once per process: 1.7-1.9 s
#: measured in a fresh process at load 9 (the native models at n = 8).
LOAD_S = 2.0
#: Slack (s) the integration's deadline leaves besides the estimated set-up and writing, for
#: estimates that fall short (at most a tenth of the budget).
MARGIN_S = 0.5


def register(sub: Any) -> None:
    p = sub.add_parser(
        "simulate",
        help="run one scene with one model",
        description="Run SCENE ('paper', a TOML scene file, or the run.json of an earlier run) "
        "with one model and write the run folder DIR: DIR/trajectory.csv (t, quantity, k, "
        f"value; for a run of more than {CSV_MAX_VALUES} values DIR/trajectory.npz instead, "
        "see --table), DIR/run.json (the complete resolved scene, model, options, settings, "
        "how the run ended, the files written and their SHA-256) and, for a scene with lists "
        f"of more than {INLINE_MAX} numbers (per-rod data of a large chain), "
        "DIR/scene_arrays.npz, which run.json refers to. DIR must be new, empty or a run "
        "folder of rodval (one whose run.json rodval wrote and nobody edited): refused before "
        "any work otherwise; a new run there removes the earlier run's files it does not "
        "write. --max-wall is the whole command's budget (from the process start: imports, "
        "reading, set-up, integration, writing): the integration gets what the estimated "
        "set-up and writing leave, and a budget they leave nothing of is refused before any work.",
    )
    p.add_argument("scene", metavar="SCENE", help="'paper', a TOML scene file or a run.json")
    p.add_argument(
        "--model", choices=tuple(REGISTRY), help="model (default full; a run.json's own model)"
    )
    add_integrator_options(p)
    p.add_argument(
        "--t-end",
        type=positive_float("--t-end"),
        help="horizon, s (> 0); the scene's output times up to it are kept; past the "
        "scene's horizon a {start, stop, num} grid of the file that ends at the horizon goes "
        "on at its spacing, other output times are kept as they are (a note says which)",
    )
    p.add_argument("--times", type=time_list, help="output times t1,t2,... (s), increasing")
    add_model_options(p, coefficients_default=None)
    p.add_argument("--out", required=True, type=Path, help="run folder (new, empty, or rodval's)")
    p.add_argument(
        "--wide",
        action="store_true",
        help="also write DIR/trajectory_wide.csv: one row per output time, a column t and "
        "one column quantity[k] per quantity and index",
    )
    p.add_argument(
        "--table",
        choices=TABLE_FORMATS,
        default="auto",
        help="format of the trajectory: csv (DIR/trajectory.csv, tidy text), npz "
        "(DIR/trajectory.npz: t, and per quantity q the arrays values:q (times x k) and k:q; "
        "numpy.load reads it), auto (default: csv up to "
        f"{CSV_MAX_VALUES} values, npz above: a text table of 8e6 values takes minutes)",
    )
    p.set_defaults(func=run)


# ------------------------------------------------------------------------- the scene


def _listing(times: np.ndarray) -> str:
    """Output times (s) for a message: all of up to 6, else the first three and the last."""
    shown = [f"{t:g}" for t in times]
    if len(shown) > 6:
        shown = [*shown[:3], "...", shown[-1]]
    return ", ".join(shown) + " s"


def _grid_step(doc: dict[str, Any], scene: Scene) -> float | None:
    """The spacing (s) of the scene's output times when they are the file's evenly spaced
    ``{start, stop, num}`` grid ending at the horizon (num >= 2), else None."""
    times: np.ndarray = scene.times
    if not isinstance(doc.get("times"), dict) or times.size < 2 or times[-1] != scene.t_end:
        return None
    return float(times[-1] - times[0]) / (times.size - 1)


def past_horizon(doc: dict[str, Any], scene: Scene, t_end: float, where: str) -> tuple[Scene, str]:
    """The scene of ``doc`` (built: ``scene``) over ``t_end`` (s) past its horizon, and the
    note that says which output times it has: the file's evenly spaced grid ending at the
    horizon goes on at its spacing up to t_end; any other output times are kept as they are."""
    step = _grid_step(doc, scene)
    past = f"--t-end {t_end:g} s is past the scene's horizon ({scene.t_end:g} s)"
    if step is None:
        return scene.with_(t_end=t_end), (
            f"{past}: outputs at the scene's own {scene.times.size} output times only "
            f"({_listing(scene.times)}); give --times for output times up to {t_end:g} s"
        )
    start = float(scene.times[0])
    count = int(math.floor((t_end - start) / step + 1e-9)) + 1
    if count > MAX_TIMES:
        raise ValueError(
            f"{where}: --t-end {t_end:g} s: the scene's output grid (every {step:g} s) would "
            f"hold {count} output times, more than {MAX_TIMES}; give --times"
        )
    stop = float(f"{start + (count - 1) * step:.12g}")
    grid = {"start": start, "stop": stop, "num": count}
    extended = scene_from_dict({**doc, "t_end": t_end, "times": grid}, where=where)
    return extended, (
        f"{past}: its output grid goes on every {step:.6g} s, {count} output times "
        f"{start:g}..{stop:g} s"
    )


def build_scene(
    doc: dict[str, Any], where: str, t_end: float | None, times: list[float] | None
) -> tuple[Scene, list[str]]:
    """The Scene of ``doc`` with --t-end and --times applied, built once, and the notes that
    say what --t-end did to the output times. --times replaces the document's times (so a
    large scene's default grid is never built)."""
    if times is not None:
        new = {**doc, "times": [float(t) for t in times]}
        if t_end is not None:
            new["t_end"] = t_end
        return scene_from_dict(new, where=where), []
    if t_end is None:
        return scene_from_dict(doc, where=where), []
    if "times" not in doc:
        return with_horizon(doc, t_end, where), []
    scene = scene_from_dict(doc, where=where)
    if t_end > scene.t_end:
        extended, note = past_horizon(doc, scene, t_end, where)
        return extended, [note]
    return with_horizon(doc, t_end, where), []


# ------------------------------------------------------------------ the wall-clock budget


def predicted_values(scene: Scene) -> int:
    """The number of values the run will write (upper estimate): each output quantity (and
    what it expands to) at most n + 1 labels at each output time."""
    per_time = sum(len(EXPANDS.get(q, (q,))) for q in scene.outputs) * (scene.n + 1)
    return int(scene.times.size * per_time)


def model_estimate_s(model: str, n: int) -> float:
    """Estimated seconds of model ``model``'s work outside its integration loop on a chain of
    ``n`` rods (``MODEL_S_PER_ROD``), with ``LOAD_S`` for a model rodval integrates when this
    process has not loaded the compiled loop yet (``rodval.solvers.dop853`` loads it on
    import)."""
    per_rod = MODEL_S_PER_ROD.get(model, max(MODEL_S_PER_ROD.values()))
    loaded = "rodval.solvers.dop853" in sys.modules or not uses_integrator(model)
    return (0.0 if loaded else LOAD_S) + per_rod * n


def write_bound_s(values: int, fmt: str, rods: int, wide: bool) -> float:
    """Estimated seconds to write the run folder (``write_estimate_s``) whatever time the run
    reaches: all ``values`` in the format they take (``table_file``), or, for a run cut
    short, at most ``CSV_MAX_VALUES`` of them as text, the slower writer, which ``--table
    auto`` chooses for so few (at n = 1e6: 1e6 values as text 6.6 s, 3e6 as npz 1.3 s)."""
    counts = {values, min(values, CSV_MAX_VALUES)}
    return max(write_estimate_s(v, table_file(fmt, v), rods, wide=wide) for v in counts)


def integration_budget(max_wall_s: float, used_s: float, setup_s: float, write_s: float) -> float:
    """The integration's wall-clock budget (s) within the command's ``max_wall_s``: what is
    left after the time ``used_s`` already spent, the estimated model set-up ``setup_s`` and
    writing ``write_s`` and a margin (``MARGIN_S``, at most a tenth of the budget). ValueError
    naming --max-wall, before any work, when nothing is left."""
    if math.isinf(max_wall_s):
        return max_wall_s
    margin = min(MARGIN_S, 0.1 * max_wall_s)
    left = max_wall_s - used_s - setup_s - write_s - margin
    if left <= 0:
        need = used_s + setup_s + write_s + margin
        raise ValueError(
            f"--max-wall {max_wall_s:g} s cannot cover this command (the whole command's "
            f"budget): reading and set-up {used_s + setup_s:.3g} s and writing the outputs "
            f"{write_s:.3g} s are estimated, leaving no time to integrate; give --max-wall "
            f"well above {need:.3g} s, fewer output times, quantities or rods, or no "
            "--max-wall"
        )
    return left


# ------------------------------------------------------------------------- the command


def rerun_request(
    args: argparse.Namespace,
) -> tuple[dict[str, Any], str, dict[str, Any], dict[str, Any]]:
    """(scene document, model, integrator settings, options) of SCENE: a run.json's own, or
    a scene file's with the defaults."""
    path = Path(args.scene)
    if path.suffix != ".json":
        return read_scene_document(args.scene), args.model or "full", {}, {}
    previous = read_run_record(path)
    model = args.model or previous["model"]
    options = dict(previous["options"]) if model == previous["model"] else {}
    settings_kw: dict[str, Any] = {}
    if uses_integrator(model):
        ran = previous["settings"]
        check_keys(ran, RERUN_SETTINGS, f"{path} key 'settings'")
        settings_kw = {k: v for k, v in ran.items() if k in SETTING_NAMES}
        settings_kw["method"] = ran.get("requested_method", settings_kw.get("method"))
    return dict(previous["scene"]), model, settings_kw, options


def run(args: argparse.Namespace) -> int:
    start = args.started  # the command's start (rodval.cli.main): its budget counts from it
    doc, model, settings_kw, options = rerun_request(args)
    doc, where = with_scene_values(doc, args)
    scene, notes = build_scene(doc, where, args.t_end, args.times)
    options.update(model_options(args))
    settings_kw.update(integrator_settings(args))
    settings = IntegratorSettings(**settings_kw)
    claim_run_folder(args.out)  # before any work: nothing of the user's is overwritten
    requested = settings.max_wall_s
    share = write_s = setup_s = math.inf
    if math.isfinite(requested):
        values = predicted_values(scene)
        write_s = write_bound_s(values, args.table, scene.n, wide=args.wide)
        setup_s = model_estimate_s(model, scene.n)
        share = integration_budget(requested, time.perf_counter() - start, setup_s, write_s)
        settings = settings.with_(max_wall_s=share)
    with progress_bar(scene.t_end, enabled=sys.stderr.isatty()):
        traj = simulate(scene, model, settings=settings, **options)
    if "max_wall_s" in traj.settings:  # the command's budget, which a rerun shares out again
        traj.settings["max_wall_s"] = requested
    write_run(traj, scene, args.out, wide=args.wide, table=args.table, claimed=True)
    if table_file(args.table, value_count(traj)) == TABLE_NPZ:
        why = f" (more than {CSV_MAX_VALUES}; --table csv writes text)" * (args.table == "auto")
        notes.append(f"the trajectory ({value_count(traj)} values) is in {TABLE_NPZ}{why}")
    if math.isfinite(requested):
        notes.append(
            f"--max-wall {requested:g} s is the whole command's budget: {share:.3g} s were "
            f"left for the integration (which stops within one step of it) after reading, "
            f"{setup_s:.3g} s estimated for the model's set-up and observation and "
            f"{write_s:.3g} s for writing; the command took {time.perf_counter() - start:.3g} s"
        )
    print(
        f"{traj.model}: {traj.stats.message}, {describe(traj.stats.valid, traj.stats.validity)}, "
        f"method {traj.settings.get('method')}, "
        f"t_reached = {traj.stats.t_reached:g} s, nfev = {traj.stats.nfev}, "
        f"wall = {traj.stats.wall_s:.3f} s -> {args.out}"
    )
    for note in [*traj.stats.notes, *notes]:
        print(f"note: {note}")
    return 0 if traj.success else 1
