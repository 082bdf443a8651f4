"""rodval modes SCENE --model M --out DIR: linearized natural frequencies and mode shapes."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rodval.cli import SUMMARIES
from rodval.cli.options import add_model_options, model_options, positive_int, with_scene_values
from rodval.core.out_paths import clear_previous, write_file

if TYPE_CHECKING:
    from rodval.core.modes import Modes
    from rodval.core.scene import Scene


#: ``rodval modes --help``'s description (argparse rewraps it).
DESCRIPTION = """Linearize SCENE ('paper', a TOML scene file or the run.json of a run) about its
initial state at rest or its static equilibrium under its static loads (the loads acting for ever,
or every load at --load-at T) and write DIR/frequencies.csv (mode, omega_rad_s, f_hz,
damping_ratio), DIR/modes.csv (mode, kind node_dx/node_dy/hinge, k, value; shapes normalized to a
largest node displacement of 1), DIR/modes.png and DIR/modes.json. With --compare, also
DIR/compare.csv: the modes of the other models paired with this model's by MAC (see docs/modes.md)."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from rodval.models.registry import MODEL_NAMES

    p = sub.add_parser("modes", help=SUMMARIES["modes"], description=DESCRIPTION)
    p.add_argument(
        "scene",
        metavar="SCENE",
        help="'paper', a TOML scene file or a run.json (its scene, model and model options)",
    )
    p.add_argument(
        "--model", choices=MODEL_NAMES, help="model (default full; a run.json's own model)"
    )
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--count",
        type=positive_int("--count"),
        default=10,
        help="number of lowest modes to write (default 10); on a free base the flexible "
        "ones, the three rigid modes reported apart",
    )
    p.add_argument(
        "--about",
        default="initial",
        choices=("initial", "equilibrium"),
        help="linearize about the initial state (at rest in equilibrium; loads ignored) or "
        "the static equilibrium under the scene's static loads and hinge rest angles "
        "(default initial)",
    )
    p.add_argument(
        "--load-at",
        type=float,
        metavar="T",
        help="hold every load at its value at time T (s) for the equilibrium (default: the "
        "loads that act for ever, windowed ones left out and named)",
    )
    p.add_argument(
        "--allow-unbalanced",
        action="store_true",
        help="linearize about an initial state that is not an equilibrium (refused otherwise; "
        "its static residual is recorded in modes.json)",
    )
    add_model_options(p, coefficients_default=None, settings=False)
    p.add_argument(
        "--compare",
        nargs="?",
        const="full,reduced,exudyn",
        metavar="MODELS",
        help="also pair the modes of these models (comma-separated, default "
        "full,reduced,exudyn) with --model's and write DIR/compare.csv",
    )
    p.set_defaults(func=run, out_folder="modes")


def run(args: argparse.Namespace) -> int:
    from rodval.analysis.modes import model_modes
    from rodval.report.figures import plot_modes

    compare = _compare_list(args.compare)
    scene, model, carried, computed = _scene_and_model(args)
    args.model = model
    given = _given_options(args, model, compare)
    pool = {**carried, **given}  # the command line's over the run.json's
    m = model_modes(
        scene,
        model,
        about=args.about,
        count=args.count,
        load_at=args.load_at,
        allow_unbalanced=args.allow_unbalanced,
        **_options_for(model, pool),
    )
    flex = m.flexible()  # a free base's rigid modes are reported apart (--count: flexible)
    clear_previous(args.out, "modes")  # no compare.csv of an earlier --compare left behind
    write_file(args.out / "frequencies.csv", flex.frequencies_frame().to_csv(index=False))
    write_file(args.out / "modes.csv", flex.modes_frame().to_csv(index=False))
    plot_modes(m, args.out / "modes.png", title=f"{scene.name}: {m.model} about {m.about}")
    lines = _summary(scene, m, args)
    if computed:
        lines.append(
            "not used by a modal analysis (the run.json's options that set how the run was "
            "computed, not the model): " + ", ".join(f"{k}={v!r}" for k, v in computed.items())
        )
    record = _record(scene, m, args)
    if compare:
        table, others = _comparison(scene, m, compare, pool, args)
        lines += table
        record["compared"] = {
            name: _ran_options(other) for name, other in others.items() if name != m.model
        }
    write_file(args.out / "modes.json", json.dumps(record, indent=2, default=str))
    print("\n".join(lines))
    return 0


def _given_options(
    args: argparse.Namespace, model: str, compare: tuple[str, ...]
) -> dict[str, Any]:
    """The model options of the command line (--set KEY=VALUE, --coefficients; the two for
    one key refused, ``model_options``), each one that the modes of ``model`` or of a
    --compare model take (``MODES_OPTIONS``); any other option is refused, naming it, and so
    is an integrator setting (a --set of a scene value is the scene's, ``_scene_and_model``)."""
    from rodval.core.settings import SETTING_NAMES
    from rodval.models.registry import model_class

    given = model_options(args)
    settings = [k for k, _ in args.options if k in SETTING_NAMES]
    if settings:
        raise ValueError(
            f"--set {settings[0]} is an integrator setting, which a modal analysis does not "
            "use (rodval modes linearizes and integrates nothing); rodval simulate takes it"
        )
    models = (model, *compare)
    accepted = sorted({k for name in models for k in model_class(name).MODES_OPTIONS})
    unknown = sorted(k for k in given if k not in accepted)
    if unknown:
        name = unknown[0]
        flag = "--coefficients" if name == "coefficients" and args.coefficients else f"--set {name}"
        raise ValueError(
            f"{flag} does not apply to the modes of {', '.join(dict.fromkeys(models))} "
            f"(their options: {', '.join(accepted) or 'none'})"
        )
    return given


def _compare_list(text: str | None) -> tuple[str, ...]:
    """--compare MODELS as a tuple of registered model names (ValueError otherwise)."""
    from rodval.models.registry import MODEL_NAMES

    if not text:
        return ()
    compare = tuple(x.strip() for x in text.split(",") if x.strip())
    if not compare or any(x not in MODEL_NAMES for x in compare):
        raise ValueError(f"--compare models must be from {MODEL_NAMES}, got {text!r}")
    return compare


def _options_for(model: str, pool: dict[str, Any]) -> dict[str, Any]:
    """The options of ``pool`` (the command line's) that ``model``'s modes take."""
    from rodval.models.registry import model_class

    accepted = model_class(model).MODES_OPTIONS
    return {k: v for k, v in pool.items() if k in accepted}


def _ran_options(m: Modes) -> dict[str, Any]:
    """The options the modal analysis of ``m`` ran with (its model's ``MODES_OPTIONS``, and
    exudyn's resolved model options)."""
    from rodval.models.registry import model_class

    options = dict(m.info.get("options", {}))  # exudyn's: the model's resolved options
    options.update({k: m.info[k] for k in model_class(m.model).MODES_OPTIONS if k in m.info})
    return options


def _record(scene: Scene, m: Modes, args: argparse.Namespace) -> dict[str, Any]:
    """modes.json: what the modes are of and about (the complete resolved scene, as run.json
    records it: ``scene_to_dict``; the options the analysis ran with, the held hinges it
    held), the count of flexible modes written, a free base's rigid modes (reported apart
    from them) and the equilibrium found."""
    from rodval.core.scene_file import scene_to_dict
    from rodval.mechanics.modal import held_hinges

    record: dict[str, Any] = {
        "scene": scene_to_dict(scene),
        "model": m.model,
        "about": m.about,
        "coefficients": m.info.get("coefficients"),
        "options": _ran_options(m),
        "held_hinges": held_hinges(scene).tolist(),
        "count": m.flexible().count,
        "load_at": args.load_at,
        **({k: v for k, v in m.info.items() if k == "unbalanced_residual_Nm"}),
    }
    if m.rigid:
        record["rigid_modes"] = {
            "modes": list(m.info.get("rigid_modes", ())),
            "omega_rad_s": m.omega[: m.rigid].tolist(),
            "shape_residual": m.info.get("rigid_shape_residual", {}),
        }
    eq = m.equilibrium
    if eq is not None:
        record["equilibrium"] = {
            "iterations": eq.iterations,
            "load_steps": eq.load_steps,
            "residual_Nm": eq.residual,
            "phi": eq.phi.tolist(),
            "left_out_loads": list(eq.loads.ignored) if eq.loads else [],
        }
    return record


def _summary(scene: Scene, m: Modes, args: argparse.Namespace) -> list[str]:
    """The printed lines: what was linearized about what, the equilibrium, the modes."""
    import numpy as np

    lines = [f"{m.model} modes of {scene.name} about the {m.about} state -> {args.out}"]
    if "unbalanced_residual_Nm" in m.info:
        lines.append(
            "the initial state is NOT an equilibrium (static residual "
            f"{m.info['unbalanced_residual_Nm']:.3g} N m): linearized there as asked"
        )
    eq = m.equilibrium
    if eq is not None:
        ign = (
            f"; loads left out: {', '.join(eq.loads.ignored)}"
            if eq.loads and eq.loads.ignored
            else ""
        )
        unit = "N m" if "coefficients" in m.info else "(exudyn's Newton residual norm)"
        res = f", residual {eq.residual:.2g} {unit}" if np.isfinite(eq.residual) else ""
        lines.append(f"static equilibrium: {eq.iterations} Newton iterations{res}{ign}")
    if m.rigid:
        names = ", ".join(str(x).replace("_", " ") for x in m.info.get("rigid_modes", ()))
        omega = ", ".join(f"{w:.3g}" for w in m.omega[: m.rigid])
        lines.append(
            f"{m.rigid} rigid modes ({names}; omega {omega} rad/s) reported apart: the modes "
            "below and in the files are the flexible ones (--count counts them)"
        )
    flex = m.flexible()
    lines.append(" mode   omega (rad/s)        f (Hz)   damping ratio")
    for i in range(flex.count):
        z = "" if not np.isfinite(flex.damping[i]) else f"{flex.damping[i]:.3e}"
        lines.append(f"{i + 1:5d} {flex.omega[i]:15.6g} {flex.f_hz[i]:13.6g}   {z}")
    return lines


def _comparison(
    scene: Scene, m: Modes, models: tuple[str, ...], pool: dict[str, Any], args: argparse.Namespace
) -> tuple[list[str], dict[str, Modes]]:
    """The other models' modes paired by MAC with ``m`` (written to DIR/compare.csv): the
    lines printed and every model's modes (name -> Modes; modes.json records their options)."""
    from rodval.analysis.modes import compare_modes, model_modes

    computed = {args.model: m}
    for other in models:
        if other not in computed:
            computed[other] = model_modes(
                scene,
                other,
                about=args.about,
                load_at=args.load_at,
                allow_unbalanced=args.allow_unbalanced,
                **_options_for(other, pool),
            )
    order = tuple(x for x in models if x != args.model) + (args.model,)
    table = compare_modes(
        scene, order, about=args.about, count=args.count, reference=args.model, computed=computed
    )
    write_file(args.out / "compare.csv", table.to_csv(index=False))
    return [
        "paired by MAC (gap relative to " + args.model + "):",
        table.to_string(index=False, float_format=lambda v: f"{v:.6g}"),
    ], computed


def _scene_and_model(args: argparse.Namespace) -> tuple[Scene, str, dict[str, Any], dict[str, Any]]:
    """The scene of SCENE ('paper', a TOML file, or a run.json: its recorded scene) with the
    scene values of --set (``with_scene_values``, as ``rodval simulate`` sets them), the
    model (--model, else a run.json's own model, else "full") and, for a run.json of the same
    model, its model options as ``rodval simulate`` reruns them (``rodval.cli.simulate``'s
    one reading of a run.json): (the ones the modes take, the ones that set only how the run
    was computed; ``rodval.analysis.modes.rerun_options``, which refuses any other)."""
    from rodval.analysis.modes import rerun_options
    from rodval.cli.simulate import rerun_request
    from rodval.core.scene_file import scene_from_dict

    doc, model, _, options = rerun_request(args)
    carried: dict[str, Any] = {}
    computed: dict[str, Any] = {}
    if Path(args.scene).suffix == ".json":
        carried, computed = rerun_options(model, options, str(args.scene))
    doc, where = with_scene_values(doc, args)
    return scene_from_dict(doc, where=where), model, carried, computed
