"""rodval reproduce paper --out DIR: the paper's Table 1 and Fig. 3, and the exudyn cross-check."""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path

from rodval.cli import SUMMARIES, CliError
from rodval.core.out_paths import write_file

#: ``rodval reproduce --help``'s description (argparse rewraps it).
DESCRIPTION = """Run the paper's example with the full and reduced models and write DIR/table1.csv,
DIR/table1.md, DIR/configurations.png; with exudyn installed, also cross-check against the
independent beam model (DIR/crosscheck.csv, DIR/crosscheck.md)."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("reproduce", help=SUMMARIES["reproduce"], description=DESCRIPTION)
    p.add_argument("target", choices=("paper",), help="what to reproduce")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--variant",
        choices=("printed", "published"),
        default="printed",
        help="coefficients: printed (from the kinematics, default) or published "
        "(the erratum that reproduces the paper's alpha/beta)",
    )
    p.add_argument(
        "--cross-check",
        dest="cross_check",
        action="store_true",
        default=None,
        help="require the exudyn cross-check (default: run it when exudyn is installed)",
    )
    p.add_argument(
        "--no-cross-check",
        dest="cross_check",
        action="store_false",
        help="skip the exudyn cross-check",
    )
    p.set_defaults(func=run, out_folder="reproduce")


def run(args: argparse.Namespace) -> int:
    from rodval.report.paper import crosscheck_markdown, reproduce_paper

    have_exudyn = importlib.util.find_spec("exudyn") is not None
    if args.cross_check and not have_exudyn:
        raise CliError("--cross-check needs exudyn: pip install 'rodval[exudyn]'")
    errors = reproduce_paper(args.out, args.variant)
    wide = errors.pivot_table(
        index=["quantity", "formulation"], columns="t", values="error", sort=False
    )
    print(
        f"Table 1 column errors (max_k |rodval - published| / max_k |published|), "
        f"coefficients = {args.variant}:"
    )
    print(wide.to_string(float_format=lambda v: f"{v:.2e}"))
    print(f"wrote {args.out}/table1.csv, table1.md, configurations.png")
    if args.cross_check is False or not have_exudyn:
        return 0
    from rodval.analysis.crosscheck import crosscheck_paper

    table, runs = crosscheck_paper()
    write_file(args.out / "crosscheck.csv", table.to_csv(index=False))
    write_file(args.out / "crosscheck.md", crosscheck_markdown(table, runs["exudyn"]))
    print("Cross-check against exudyn (phi/alpha/beta max |gap| in rad, dphi relative):")
    print(table.drop(columns="status").to_string(index=False, float_format=lambda v: f"{v:.2e}"))
    print(f"wrote {args.out}/crosscheck.csv, crosscheck.md")
    return 0 if table.iloc[0]["within_acceptance"] else 1
