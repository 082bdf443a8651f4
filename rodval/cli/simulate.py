"""rodval simulate SCENE --model M --out DIR: one run, tidy CSV + run.json.

SCENE is 'paper', a TOML scene file, or the run.json of an earlier run (rerun exactly: the
same resolved scene, model, options and integrator settings; options given here override).
"""

from __future__ import annotations

import sys
from pathlib import Path

from rodval.cli.options import (
    add_integrator_options,
    add_model_options,
    integrator_settings,
    model_options,
    positive_float,
    time_list,
)
from rodval.core.checks import check_keys
from rodval.core.scene_file import read_scene_document, scene_from_dict, with_horizon
from rodval.core.settings import SETTING_NAMES, IntegratorSettings
from rodval.core.validity import describe
from rodval.models import REGISTRY, simulate
from rodval.models.registry import uses_integrator
from rodval.report.run_files import read_run_record, write_run
from rodval.solvers.progress import progress_bar

#: The keys of a run.json's settings a rerun reads: the settings, and the method asked for
#: when "auto" chose one.
RERUN_SETTINGS = (*SETTING_NAMES, "requested_method")


def register(sub) -> None:
    p = sub.add_parser(
        "simulate",
        help="run one scene with one model",
        description="Run SCENE ('paper', a TOML scene file, or the run.json of "
        "an earlier run) with one model and write "
        "DIR/trajectory.csv (t, quantity, k, value) and DIR/run.json "
        "(the complete resolved scene, model, options, settings "
        "and how the run ended).",
    )
    p.add_argument("scene", metavar="SCENE", help="'paper', a TOML scene file or a run.json")
    p.add_argument(
        "--model", choices=tuple(REGISTRY), help="model (default full; a run.json's own model)"
    )
    add_integrator_options(p)
    p.add_argument(
        "--t-end",
        type=positive_float("--t-end"),
        help="horizon, s (> 0); the scene's output times up to it are kept",
    )
    p.add_argument("--times", type=time_list, help="output times t1,t2,... (s), increasing")
    add_model_options(p, coefficients_default=None)
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--wide",
        action="store_true",
        help="also write DIR/trajectory_wide.csv: one row per output time, a column t and "
        "one column quantity[k] per quantity and index",
    )
    p.set_defaults(func=run)


def run(args) -> int:
    path = Path(args.scene)
    previous = read_run_record(path) if path.suffix == ".json" else None
    if previous is not None:
        doc, model = dict(previous["scene"]), args.model or previous["model"]
        options = dict(previous["options"]) if model == previous["model"] else {}
        settings_kw = {}
        if uses_integrator(model):
            ran = previous["settings"]
            check_keys(ran, RERUN_SETTINGS, f"{path} key 'settings'")
            settings_kw = {k: v for k, v in ran.items() if k in SETTING_NAMES}
            settings_kw["method"] = ran.get("requested_method", settings_kw.get("method"))
    else:
        doc, model, settings_kw, options = (
            read_scene_document(args.scene),
            args.model or "full",
            {},
            {},
        )
    where = str(args.scene)
    scene = (
        with_horizon(doc, args.t_end, where)
        if args.t_end is not None
        else scene_from_dict(doc, where=where)
    )
    if args.times is not None:
        scene = scene.with_(times=args.times)
    options.update(model_options(args))
    settings_kw.update(integrator_settings(args))
    with progress_bar(scene.t_end, enabled=sys.stderr.isatty()):
        traj = simulate(scene, model, settings=IntegratorSettings(**settings_kw), **options)
    write_run(traj, scene, args.out)
    if args.wide:
        traj.to_frame(wide=True).to_csv(args.out / "trajectory_wide.csv", index=False)
    print(
        f"{traj.model}: {traj.stats.message}, {describe(traj.stats.valid, traj.stats.validity)}, "
        f"method {traj.settings.get('method')}, "
        f"t_reached = {traj.stats.t_reached:g} s, nfev = {traj.stats.nfev}, "
        f"wall = {traj.stats.wall_s:.3f} s -> {args.out}"
    )
    for note in traj.stats.notes:
        print(f"note: {note}")
    return 0 if traj.success else 1
