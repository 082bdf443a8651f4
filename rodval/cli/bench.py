"""rodval bench {work-precision, cost-n, skips, speedup, scale, fast-path, stiffness} --out DIR:
performance measurements (see ``rodval.bench``). Each writes a CSV (with machine and package
versions), a markdown summary and, where it applies, plots into DIR."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from rodval import bench
from rodval.cli import SUMMARIES
from rodval.cli.options import positive_float
from rodval.core.out_paths import write_file
from rodval.core.provenance import provenance
from rodval.core.scene import paper_scene
from rodval.core.settings import METHODS
from rodval.models.registry import MODEL_NAMES, integrated_models, uses_integrator
from rodval.report.figures import plot_scale, plot_work_precision
from rodval.report.markdown import to_markdown

DEFAULT_METHODS = ("RK45", "DOP853", "Radau", "BDF", "LSODA", "DOP853-numba")
DEFAULT_RTOLS = "1e-4,1e-6,1e-8,1e-10"


def _float_list(name: str) -> Callable[[str], list[float]]:
    def parse(text: str) -> list[float]:
        values = []
        for part in text.split(","):
            try:
                v = float(part)
            except ValueError:
                raise argparse.ArgumentTypeError(
                    f"{name} must be comma-separated numbers, got {text!r}"
                ) from None
            if not (0 < v < 1):
                raise argparse.ArgumentTypeError(f"{name} values must be in (0, 1), got {v}")
            values.append(v)
        return values

    return parse


def _choice_list(name: str, allowed: tuple[str, ...]) -> Callable[[str], list[str]]:
    def parse(text: str) -> list[str]:
        values = [v.strip() for v in text.split(",") if v.strip()]
        bad = [v for v in values if v not in allowed]
        if bad or not values:
            raise argparse.ArgumentTypeError(
                f"{name} must be a comma-separated subset of {allowed}, got {text!r}"
            )
        return values

    return parse


def _int_list(text: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--n-values must be comma-separated integers >= 1, got {text!r}"
        ) from None
    if any(v < 1 for v in values):
        raise argparse.ArgumentTypeError(f"--n-values must be integers >= 1, got {text!r}")
    return values


def _repeats(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        v = 0
    if v < 1:
        raise argparse.ArgumentTypeError(f"--repeats must be an integer >= 1, got {text!r}")
    return v


#: ``rodval bench --help``'s description (argparse rewraps it).
DESCRIPTION = """Performance measurements on the paper example; see docs/performance.md."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("bench", help=SUMMARIES["bench"], description=DESCRIPTION)
    bsub = p.add_subparsers(dest="bench", metavar="BENCH", required=True)
    _add_work_precision(bsub)
    cn = bsub.add_parser("cost-n", help="seconds per RHS evaluation against n, fitted exponent")
    cn.add_argument("--n-values", type=_int_list, default=[2, 4, 8, 16, 32, 64, 128, 256, 512])
    cn.set_defaults(func=run_cost_n)
    sk = bsub.add_parser("skips", help="cost with and without each skipped piece of work")
    sk.set_defaults(func=run_skips)
    sp = bsub.add_parser(
        "speedup", help="reduced vs full (and exudyn) at equal phi accuracy against n"
    )
    sp.add_argument("--n-values", type=_int_list, default=[2, 4, 8, 16, 32])
    sp.set_defaults(func=run_speedup)
    _add_scale(bsub)
    for name, text, func in (
        (
            "fast-path",
            "the default method against scipy's DOP853 with and without events and energy",
            run_fast_path,
        ),
        (
            "stiffness",
            "near-rigid panels: auto against the compiled DOP853 and Radau IIA across EI",
            run_stiffness,
        ),
    ):
        bsub.add_parser(name, help=text).set_defaults(func=func)
    for q in bsub.choices.values():
        q.add_argument(
            "--repeats", type=_repeats, default=3, help="timed runs after a warm-up (min is kept)"
        )
        q.add_argument("--out", required=True, type=Path, help="output folder")
        q.set_defaults(out_folder="bench")


def _add_work_precision(bsub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    wp = bsub.add_parser("work-precision", help="error against cost for every model and integrator")
    wp.add_argument("--n", type=int, default=8, help="number of rods (default 8)")
    wp.add_argument(
        "--models",
        type=_choice_list("--models", MODEL_NAMES),
        default=list(MODEL_NAMES),
    )
    wp.add_argument(
        "--methods", type=_choice_list("--methods", METHODS), default=list(DEFAULT_METHODS)
    )
    wp.add_argument(
        "--rtols",
        type=_float_list("--rtols"),
        default=_float_list("--rtols")(DEFAULT_RTOLS),
        help=f"tolerance ladder (default {DEFAULT_RTOLS}; atol = rtol/100)",
    )
    wp.add_argument(
        "--budget",
        type=positive_float("--budget"),
        default=20.0,
        help="stop a method's ladder after a run slower than this, s (default 20)",
    )
    wp.set_defaults(func=run_work_precision)


def _add_scale(bsub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    sc = bsub.add_parser(
        "scale",
        help="wall time and cost per evaluation against n up to 1e5 (reduced vs full), "
        "exponents, speed-up at equal phi accuracy",
    )
    sc.add_argument("--n-values", type=_int_list, default=list(bench.SCALE_N))
    sc.add_argument(
        "--models",
        type=_choice_list("--models", MODEL_NAMES),
        default=None,
        help="models (default: the native ones; the scale benchmark times rodval's own "
        "integration)",
    )
    sc.add_argument(
        "--budget",
        type=positive_float("--budget"),
        default=60.0,
        help="a model stops after its first run slower than this, s (default 60)",
    )
    sc.add_argument(
        "--speedup-n",
        type=_int_list,
        default=[2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 10000],
        help="n of the reduced-vs-full speed-up at equal phi accuracy",
    )
    sc.add_argument(
        "--no-speedup", dest="speedup", action="store_false", help="skip the speed-up part"
    )
    sc.set_defaults(func=run_scale)


def _write(out: Path, stem: str, frame: pd.DataFrame, title: str, body: list[str]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    write_file(out / f"{stem}.csv", frame.to_csv(index=False))
    write_file(out / "provenance.json", json.dumps(provenance(), indent=2, default=str))
    command = "rodval " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    text = [f"# {title}", "", f"Command: `{command}`", "", *body, ""]
    write_file(out / f"{stem}.md", "\n".join(text))
    print(f"-> {out / (stem + '.md')}")


def _table(frame: pd.DataFrame, columns: list[str], floatfmt: str = ".3g") -> str:
    return to_markdown(frame[columns], floatfmt)


def run_work_precision(args: argparse.Namespace) -> int:
    if args.n < 1:
        raise ValueError(f"--n must be an integer >= 1, got {args.n}")
    scene = paper_scene(args.n, times=np.linspace(0, 2, 41))
    frame, unc, notes = bench.work_precision(
        scene, args.models, args.methods, args.rtols, repeats=args.repeats, budget_s=args.budget
    )
    args.out.mkdir(parents=True, exist_ok=True)
    plots = plot_work_precision(frame, args.out)
    ratios = bench.baseline_ratios(scene, tuple(args.models), repeats=args.repeats)
    write_file(args.out / "baseline_ratios.csv", ratios.to_csv(index=False))
    ratio_cols = "model method kernel rtol wall_s nfev max_phi speedup_vs_numpy_DOP853".split()
    best = bench.cheapest(frame)
    cols = [*ratio_cols[:6], *"njev nlu nsteps max_phi rms_phi final_phi max_dphi".split()]
    cols += "max_alpha max_beta scd".split()
    body = [
        f"Paper example, n = {args.n}, 0..2 s, 41 output times. Errors: max relative over "
        "output times (see rodval.bench).",
        "",
        "Reference uncertainty (max relative difference of the two references, phi/dphi): "
        + ", ".join(f"{m}: {u:.1e}" for m, u in unc.items()),
        "",
        "## Fastest run per integrator with phi error <= 1e-6",
        "",
        _table(best, cols),
        "",
        "## Side by side at equal tolerance: compiled DOP853 vs scipy DOP853 (numba and "
        "numpy right-hand sides)",
        "",
        _table(ratios, ratio_cols)
        if len(ratios)
        else "None of the models asked for has a numpy right-hand side (the models rodval "
        f"integrates that take the option kernel: {', '.join(bench.numpy_models())}).",
        "",
        "## All runs",
        "",
        _table(frame, [c for c in cols if c in frame]),
        "",
        "## Notes",
        "",
        *[f"- {n}" for n in notes or ["none"]],
        "",
        "Plots: " + ", ".join(p.name for p in plots),
    ]
    _write(args.out, "work_precision", frame, "Work-precision", body)
    return 0


#: The smallest n of the cost-per-evaluation fit that leaves out the small chains' fixed cost.
FIT_N_MIN = 32


def run_cost_n(args: argparse.Namespace) -> int:
    distinct = sorted(set(args.n_values))
    if len(distinct) < 2:
        raise ValueError(
            f"--n-values must hold at least two different n (the fitted exponent), got {distinct}"
        )
    frame = bench.per_eval_cost(args.n_values, models=integrated_models(), repeats=args.repeats)
    ranges = {"all n": 1}
    if sum(n >= FIT_N_MIN for n in distinct) >= 2:
        ranges = {f"n >= {FIT_N_MIN}": FIT_N_MIN, **ranges}
    fits = []
    for (model, kernel), part in frame.groupby(["model", "kernel"]):
        n, c = part.n.to_numpy(), part.s_per_eval.to_numpy()
        exponents = {label: bench.fitted_exponent(n, c, n_min) for label, n_min in ranges.items()}
        fits.append(
            {
                "model": model,
                "kernel": kernel,
                **{f"exponent ({label})": p for label, p in exponents.items()},
            }
        )
        shown = ", ".join(f"{p:.2f} ({label})" for label, p in exponents.items())
        print(f"{model} {kernel}: fitted exponent {shown}")
    wide = frame.pivot_table(index="n", columns=["model", "kernel"], values="s_per_eval")
    wide.columns = [f"{m}/{k} (us)" for m, k in wide.columns]
    left_out = (
        []
        if len(ranges) == 2
        else ["", f"No exponent for n >= {FIT_N_MIN}: fewer than two such n were measured."]
    )
    body = [
        "Seconds per right-hand-side evaluation, paper chain, load active, random state.",
        "",
        (wide * 1e6).reset_index().to_markdown(index=False, floatfmt=".3g"),
        "",
        "Fitted exponent of cost ~ n^p:",
        "",
        pd.DataFrame(fits).to_markdown(index=False, floatfmt=".2f"),
        *left_out,
    ]
    _write(args.out, "cost_n", frame, "Cost per evaluation against n", body)
    return 0


def run_skips(args: argparse.Namespace) -> int:
    frame = bench.skip_rows(repeats=args.repeats)
    body = [_table(frame, ["skip", "model", "with_skip_s", "without_skip_s", "saving", "note"])]
    _write(args.out, "skips", frame, "What a scene does not need: cost with and without", body)
    return 0


def run_fast_path(args: argparse.Namespace) -> int:
    frame = bench.fast_path_rows(repeats=args.repeats)
    costs = bench.feature_costs(frame)
    body = [
        "Wall s (`stats.wall_s`, best of the repeats after a warm-up) of the default method "
        "(`auto`) and of scipy's DOP853, one after the other in one process; "
        "`max_event_dt_s`, `max_impulse_rel`: the largest lock-time and impulse differences "
        "between the two.",
        "",
        _table(
            frame,
            "scene feature with_feature model auto_method auto_wall_s auto_nfev scipy_wall_s "
            "speedup events max_event_dt_s max_impulse_rel auto_residual scipy_residual".split(),
        ),
        "",
        "The default method with the feature over without it (wall time and cost per evaluation):",
        "",
        _table(costs, list(costs.columns)),
    ]
    _write(
        args.out, "fast_path", frame, "The fast path: events and energy on the default method", body
    )
    return 0


def run_stiffness(args: argparse.Namespace) -> int:
    frame = bench.stiffness_rows(repeats=args.repeats)
    body = [
        "Wall s (`stats.wall_s`, best of the repeats after a warm-up) of the default method "
        "(`auto`) and of the compiled DOP853 and Radau IIA alone, one after the other in one "
        "process, on the paper chain with every rod's EI from 1e5 to 1e9 N m^2 and on the "
        "rigid two-rod latch (EI = 1e9); `switches`, `ended_on`: where `auto` went; "
        "`phi_error`: largest |phi - phi_ref| (rad) against a tight reference (DOP853 at "
        "rtol 1e-13 up to EI = 1e6, Radau IIA at rtol 1e-11 above); runs capped at 20 s.",
        "",
        _table(frame, list(frame.columns)),
        "",
        "Growth of the wall time over the EI sweep (largest over smallest):",
        "",
        _table(
            bench.growth(frame),
            ["model", "method", "wall_at_1e5_s", "wall_at_1e9_s", "max_over_min"],
        ),
    ]
    _write(args.out, "stiffness", frame, "Near-rigid panels on the default method", body)
    return 0


def run_speedup(args: argparse.Namespace) -> int:
    frame, notes = bench.speedup_vs_n(args.n_values, repeats=args.repeats)
    body = [
        "Fastest run with phi error <= 1e-6 against each model's own reference; wall times in s.",
        "",
        _no_provenance(frame).to_markdown(index=False, floatfmt=".3g"),
        "",
        *[f"- {n}" for n in notes],
    ]
    _write(args.out, "speedup", frame, "Speed-up at equal phi accuracy against n", body)
    return 0


def _no_provenance(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` without the provenance columns (versions, machine)."""
    prov = ("version_", "python", "platform", "processor", "cpu_count")
    return frame[[c for c in frame if not c.startswith(prov)]]


def _load() -> str:
    """The machine's load averages (1, 5, 15 min) and core count, for the record."""
    import os

    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f} / {five:.2f} / {fifteen:.2f} on {os.cpu_count()} cores"


def run_scale(args: argparse.Namespace) -> int:
    foreign = [m for m in args.models or () if not uses_integrator(m)]
    if foreign:
        raise ValueError(
            f"--models: the scale benchmark runs the models rodval integrates "
            f"({', '.join(integrated_models())}), got {', '.join(foreign)}"
        )
    load_before = _load()
    frame, notes = bench.scale_rows(
        args.n_values, args.models, repeats=args.repeats, budget_s=args.budget
    )
    args.out.mkdir(parents=True, exist_ok=True)
    write_file(args.out / "scale.csv", frame.to_csv(index=False))
    fits = bench.scale_fits(frame, 64)
    speedup = None
    if args.speedup:
        speedup = bench.speedup_scale(args.speedup_n, repeats=args.repeats)
        write_file(args.out / "speedup_scale.csv", speedup.to_csv(index=False))
    plot = plot_scale(frame, speedup, args.out / "scale.png")
    wall = frame.pivot(index="n", columns="model", values="wall_s")
    wall.columns = [f"{m} wall (s)" for m in wall.columns]
    cols = "model n setup_s wall_s nfev nsteps wall_per_eval_s rhs_random_s rhs_run_s".split()
    cols += ["observe_s_per_time", "subnormals_run_state"]
    body = [
        "Paper chain of n rods, the paper's pulse at the last node, 0..2 s, 21 output times "
        "(phi, phi'), compiled DOP853 at rtol 1e-6 (atol 1e-8); wall = integration and "
        "observation (stats.wall_s), min over runs. rhs_random_s / rhs_run_s: the compiled "
        "right-hand side called from a compiled loop at a random state / at the run's state at "
        "t = 0.5 s; wall_per_eval_s = wall / nfev; observe_s_per_time: alpha, beta recovery per "
        "output time.",
        "",
        to_markdown(wall.reset_index(), ".3g"),
        "",
        "## All columns",
        "",
        _table(frame, cols),
        "",
        "## Fitted exponents (cost ~ n^p, n >= 64)",
        "",
        to_markdown(fits, ".2f"),
        "",
    ]
    if speedup is not None:
        body += [
            "## Reduced vs full at equal phi accuracy (<= 1e-6 against the same model at "
            f"rtol {bench.SCALE_REFERENCE_RTOL:g})",
            "",
            to_markdown(_no_provenance(speedup), ".3g"),
            "",
        ]
    notes = [f"machine before: {load_before}; after: {_load()}", *notes]
    body += ["## Notes", "", *[f"- {n}" for n in notes], "", f"Plot: {plot.name}"]
    _write(args.out, "scale", frame, "Scale: cost against n", body)
    return 0
