"""rodval modes SCENE --model M --out DIR: linearized natural frequencies and mode shapes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rodval.cli.options import add_model_options, positive_int, set_options
from rodval.core.scene_file import load_scene
from rodval.report.figures import plot_modes

MODEL_CHOICES = ("full", "reduced", "exudyn")
#: Mode shapes drawn in modes.png.


def register(sub) -> None:
    p = sub.add_parser(
        "modes",
        help="natural frequencies and mode shapes about a configuration",
        description="Linearize SCENE ('paper' or a TOML scene file) about its initial state or "
        "its static equilibrium under its constant loads and write "
        "DIR/frequencies.csv (mode, omega_rad_s, f_hz, damping_ratio), DIR/modes.csv "
        "(mode, kind node_dx/node_dy/hinge, k, value; shapes normalized to a largest "
        "node displacement of 1), DIR/modes.png and DIR/modes.json. With --compare, "
        "also DIR/compare.csv: the modes of the other models paired with this "
        "model's by MAC (see docs/modes.md).",
    )
    p.add_argument("scene", metavar="SCENE", help="'paper' or a TOML scene file")
    p.add_argument("--model", default="full", choices=MODEL_CHOICES)
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--count",
        type=positive_int("--count"),
        default=10,
        help="number of lowest modes to write (default 10)",
    )
    p.add_argument(
        "--about",
        default="initial",
        choices=("initial", "equilibrium"),
        help="linearize about the initial state (loads ignored) or the static "
        "equilibrium under the scene's constant loads (default initial)",
    )
    add_model_options(p, coefficients_default="printed")
    p.add_argument(
        "--compare",
        nargs="?",
        const="full,reduced,exudyn",
        metavar="MODELS",
        help="also pair the modes of these models (comma-separated, default "
        "full,reduced,exudyn) with --model's and write DIR/compare.csv",
    )
    p.set_defaults(func=run)


def run(args) -> int:
    from rodval.analysis.modes import compare_modes, model_modes

    compare = ()
    if args.compare:
        compare = tuple(x.strip() for x in args.compare.split(",") if x.strip())
        bad = [x for x in compare if x not in MODEL_CHOICES]
        if bad or not compare:
            raise ValueError(f"--compare models must be from {MODEL_CHOICES}, got {args.compare!r}")
    scene = load_scene(args.scene)
    options = set_options(args.options)
    if options and args.model != "exudyn" and not args.compare:
        raise ValueError(f"--set applies to the exudyn model only, got {sorted(options)}")
    m = model_modes(
        scene,
        args.model,
        about=args.about,
        count=args.count,
        coefficients=args.coefficients,
        **(options if args.model == "exudyn" else {}),
    )
    args.out.mkdir(parents=True, exist_ok=True)
    m.frequencies_frame().to_csv(args.out / "frequencies.csv", index=False)
    m.modes_frame().to_csv(args.out / "modes.csv", index=False)
    plot_modes(m, args.out / "modes.png", title=f"{scene.name}: {m.model} about {m.about}")
    record = {
        "scene": scene.name,
        "model": m.model,
        "about": m.about,
        "coefficients": args.coefficients if m.model != "exudyn" else None,
        "options": m.info.get("options", {}),
        "count": m.count,
    }
    eq = m.equilibrium
    if eq is not None:
        record["equilibrium"] = {
            "iterations": eq.iterations,
            "load_steps": eq.load_steps,
            "residual_Nm": eq.residual,
            "phi": eq.phi.tolist(),
            "ignored_loads": list(eq.loads.ignored) if eq.loads else [],
        }
    lines = [f"{m.model} modes of {scene.name} about the {m.about} state -> {args.out}"]
    if eq is not None:
        ign = (
            f"; ignored loads: {', '.join(eq.loads.ignored)}"
            if eq.loads and eq.loads.ignored
            else ""
        )
        unit = "(exudyn's Newton residual norm)" if m.model == "exudyn" else "N m"
        res = f", residual {eq.residual:.2g} {unit}" if np.isfinite(eq.residual) else ""
        lines.append(f"static equilibrium: {eq.iterations} Newton iterations{res}{ign}")
    lines.append(" mode   omega (rad/s)        f (Hz)   damping ratio")
    for i in range(m.count):
        z = "" if not np.isfinite(m.damping[i]) else f"{m.damping[i]:.3e}"
        lines.append(f"{i + 1:5d} {m.omega[i]:15.6g} {m.f_hz[i]:13.6g}   {z}")
    if compare:
        models = compare
        computed = {args.model: m}
        for other in models:
            if other not in computed:
                computed[other] = model_modes(
                    scene,
                    other,
                    about=args.about,
                    coefficients=args.coefficients,
                    **(options if other == "exudyn" else {}),
                )
        order = tuple(x for x in models if x != args.model) + (args.model,)
        table = compare_modes(
            scene,
            order,
            about=args.about,
            count=args.count,
            reference=args.model,
            computed=computed,
        )
        table.to_csv(args.out / "compare.csv", index=False)
        lines.append("paired by MAC (gap relative to " + args.model + "):")
        lines.append(table.to_string(index=False, float_format=lambda v: f"{v:.6g}"))
    (args.out / "modes.json").write_text(json.dumps(record, indent=2, default=str))
    print("\n".join(lines))
    return 0
