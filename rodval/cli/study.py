"""rodval study FILE --out DIR: run a study grid, write tables and the report."""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path

from rodval.cli import SUMMARIES
from rodval.cli.options import (
    acceptance_exit,
    add_junit_option,
    add_set_option,
    check_junit,
    positive_float,
    positive_int,
    set_options,
)

#: ``rodval study --help``'s description (argparse rewraps it).
DESCRIPTION = """Run every case of the study FILE (TOML, see studies/README.md) and write
DIR/cases/*.json (one per finished case), DIR/{trajectories,discrepancies,runtime,cases}.csv with
markdown versions, DIR/report.md and DIR/figures/. An interrupted study resumes where it stopped."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("study", help=SUMMARIES["study"], description=DESCRIPTION)
    p.add_argument("file", metavar="FILE", type=Path, help="study file (TOML)")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder")
    p.add_argument(
        "--workers",
        type=positive_int("--workers"),
        metavar="N",
        help="cases run at once by the processes backend (default: all cores)",
    )
    p.add_argument(
        "--case-timeout",
        type=positive_float("--case-timeout"),
        metavar="S",
        help="stop a case after S seconds and record its unfinished runs as 'timeout'",
    )
    p.add_argument(
        "--resume",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="reuse the finished cases in DIR (default); --no-resume runs all again",
    )
    p.add_argument(
        "--backend",
        choices=("processes", "dask"),
        default="processes",
        help="processes on this machine (default) or an existing dask.distributed cluster",
    )
    p.add_argument(
        "--scheduler", metavar="ADDR", help="dask scheduler address, e.g. tcp://host:8786"
    )
    _add_output_options(p)
    p.set_defaults(func=run)


def _add_output_options(p: argparse.ArgumentParser) -> None:
    """The options of what the study writes, its size and the messages it prints."""
    from rodval.study.spec import MAX_CASES

    p.add_argument(
        "--fresh",
        action="store_true",
        help="first remove what the study in DIR wrote (needed when DIR holds another study); "
        "files of your own there are kept, and a folder that is not a study folder is refused",
    )
    p.add_argument(
        "--report",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="write report.md and figures/ after the tables (default); --no-report: tables "
        "only (`rodval report DIR` writes it later)",
    )
    p.add_argument(
        "--max-cases",
        type=positive_int("--max-cases"),
        metavar="N",
        help=f"refuse a grid of more than N cases (default {MAX_CASES}); every case is built "
        "and checked before any runs",
    )
    p.add_argument(
        "--no-progress",
        dest="progress",
        action="store_false",
        help="no progress bar and no announcement of the number of cases",
    )
    add_set_option(
        p,
        "a value of the study file by its dotted path, as a [grid] key gives it, e.g. "
        "integrator.rtol=1e-6 or models.full.shapes=2, or a scene value, e.g. chain.EI=2e8 "
        "(scene. may be left out); the keys: studies/README.md",
    )
    add_junit_option(p)


def run(args: argparse.Namespace) -> int:
    from rodval.study import load_study, run_study
    from rodval.study.spec import MAX_CASES
    from rodval.study.store import StudyStore

    def announce(size: int) -> None:
        if args.progress:
            cases = f"{size} case" + ("s" if size != 1 else "")
            print(f"{args.file}: {cases}; checking them before any runs", flush=True)

    if args.backend == "dask" and not args.scheduler:
        raise ValueError("--backend dask needs --scheduler ADDR")
    if args.backend == "processes" and args.scheduler:
        raise ValueError(
            f"--scheduler {args.scheduler}: the processes backend runs on this machine and "
            "takes no scheduler; add --backend dask to use it"
        )
    check_junit(args.junit, args.out, inputs=(args.file,))
    StudyStore(args.out).check_folder()
    spec = load_study(
        args.file,
        max_cases=args.max_cases or MAX_CASES,
        announce=announce,
        overrides=set_options(args.options),
    )
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        res = run_study(
            spec,
            args.out,
            workers=args.workers,
            case_timeout=args.case_timeout,
            resume=args.resume,
            backend=args.backend,
            scheduler=args.scheduler,
            progress=args.progress,
            report=args.report,
            fresh=args.fresh,
        )
    except KeyboardInterrupt:
        store = StudyStore(args.out)
        done = sum(store.case_path(c.id).is_file() for c in spec.cases)
        print(
            f"rodval study: interrupted; {done} of {len(spec.cases)} cases are in "
            f"{args.out / 'cases'}; run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    for warning in res.warnings:
        print(f"rodval study: warning: {warning}", file=sys.stderr)
    print(
        f"{spec.name}: {len(res.ran)} cases run, {len(res.reused)} reused, "
        f"{res.failed_runs} failed model runs, {res.wall_s:.1f} s -> "
        f"{res.out / 'report.md' if args.report else res.out}"
    )
    return acceptance_exit(res.out, args.junit)
