"""rodval simulate SCENE --model M --out DIR: one run, tidy CSV + run.json."""
from __future__ import annotations

import json
from pathlib import Path

from ..models import REGISTRY
from ..provenance import provenance
from ..scene_file import load_scene
from ..settings import IntegratorSettings
from ..simulate import simulate
from .options import add_integrator_options, key_value, positive_float, time_list


def register(sub) -> None:
    p = sub.add_parser("simulate", help="run one scene with one model",
                       description="Run SCENE ('paper' or a TOML scene file) with one model and "
                                   "write DIR/trajectory.csv (t, quantity, k, value) and DIR/run.json.")
    p.add_argument("scene", metavar="SCENE", help="'paper' or a TOML scene file")
    p.add_argument("--model", default="full", choices=tuple(REGISTRY))
    add_integrator_options(p)
    p.add_argument("--t-end", type=positive_float("--t-end"), help="horizon, s (> 0)")
    p.add_argument("--times", type=time_list, help="output times t1,t2,... (s), increasing")
    p.add_argument("--coefficients", choices=("printed", "published"),
                   help="coefficient variant of the native models (default printed)")
    p.add_argument("--set", dest="options", type=key_value, action="append", default=[],
                   metavar="KEY=VALUE", help="model option, e.g. elements=2 (repeatable)")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.set_defaults(func=run)


def run(args) -> int:
    scene = load_scene(args.scene)
    changes = {}
    if args.t_end is not None:
        changes["t_end"] = args.t_end
        if args.times is None:
            changes["times"] = None
    if args.times is not None:
        changes["times"] = args.times
    if changes:
        scene = scene.with_(**changes)
    options = dict(args.options)
    if args.coefficients:
        options["coefficients"] = args.coefficients
    settings = IntegratorSettings(method=args.method, rtol=args.rtol, atol=args.atol,
                                  max_step=args.max_step)
    traj = simulate(scene, args.model, settings=settings, **options)
    args.out.mkdir(parents=True, exist_ok=True)
    traj.to_frame().to_csv(args.out / "trajectory.csv", index=False)
    record = {"scene": scene.name, "model": traj.model, "settings": traj.settings,
              **traj.stats.as_dict(), **provenance()}
    (args.out / "run.json").write_text(json.dumps(record, indent=2, default=str))
    print(f"{traj.model}: {traj.stats.message}, t_reached = {traj.stats.t_reached:g} s, "
          f"nfev = {traj.stats.nfev}, wall = {traj.stats.wall_s:.3f} s -> {args.out}")
    return 0 if traj.success else 1
