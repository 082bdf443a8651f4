"""rodval report DIR: rebuild DIR/report.md and DIR/figures/ from a study's saved tables."""

from __future__ import annotations

import argparse
from pathlib import Path

from rodval.cli import SUMMARIES
from rodval.cli.options import acceptance_exit, add_junit_option, check_junit

#: ``rodval report --help``'s description (argparse rewraps it).
DESCRIPTION = """Rebuild DIR/report.md and DIR/figures/*.png from the CSV tables a `rodval study`
run saved in DIR; nothing is recomputed."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("report", help=SUMMARIES["report"], description=DESCRIPTION)
    p.add_argument("dir", metavar="DIR", type=Path, help="output folder of `rodval study`")
    add_junit_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rodval.report.study_report import build_report

    check_junit(args.junit, args.dir)
    print(build_report(args.dir))
    return acceptance_exit(args.dir, args.junit)
