"""rodval compare A B --out DIR: discrepancies of run A against run B (two `rodval simulate`
output folders of the same scene: same output times and k labels). Runs of different scenes
are refused, naming the scene keys that differ, unless ``--allow-different-scenes``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rodval.cli import SUMMARIES, CliError

#: ``rodval compare --help``'s description (argparse rewraps it).
DESCRIPTION = """Compare run A against the reference run B (output folders of `rodval simulate`):
DIR/discrepancies.csv and .md (per quantity: max_abs, rms, final_abs, max_rel, where the maximum is;
see rodval.analysis.metrics) and DIR/histories.png. When either run recorded lock events (latches),
also the lock table: per lock label both lock times, dt = t_A - t_B (s), both lock impulses and
impulse_rel, both impulse_to_rigid and why a lock is not comparable pointwise (locks only one run
has included), printed and written to DIR/events.csv and DIR/events.md (see rodval.analysis.events).
A run whose trajectory is not the one its run.json records (cut, edited) or whose run.json records
no digest of it is refused. DIR must be new, empty or an output folder of rodval compare (refused
before any work otherwise: another command's folder, a folder holding a file or link rodval did not
write); the files of an earlier compare there are replaced (an events.csv the new runs have no locks
for is removed)."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("compare", help=SUMMARIES["compare"], description=DESCRIPTION)
    p.add_argument("a", metavar="A", type=Path, help="run folder to compare")
    p.add_argument("b", metavar="B", type=Path, help="reference run folder")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--allow-different-scenes",
        action="store_true",
        help="compare runs whose scenes differ (chain, loads, horizon, ...: refused "
        "otherwise); the table then mixes a model's error with the change of scene",
    )
    # DIR is claimed before any work and marked rodval's (rodval.cli._run, out_paths)
    p.set_defaults(func=run, out_folder="compare")


def run(args: argparse.Namespace) -> int:
    from rodval.analysis.metrics import discrepancies
    from rodval.core.out_paths import clear_previous, write_file, write_with
    from rodval.core.quantities import ROD_QUANTITIES
    from rodval.core.scene_file import scene_differences
    from rodval.report.figures import plot_time_histories
    from rodval.report.markdown import to_markdown
    from rodval.report.run_files import read_run, read_run_record

    differ = scene_differences(
        read_run_record(args.a / "run.json")["scene"], read_run_record(args.b / "run.json")["scene"]
    )
    if differ and not args.allow_different_scenes:
        raise CliError(
            f"{args.a} and {args.b} are runs of different scenes ({', '.join(differ)} differ); "
            "give --allow-different-scenes to compare them anyway"
        )
    a, b = read_run(args.a), read_run(args.b)
    table = discrepancies(a, b)
    locks = lock_table(a.events, b.events)
    # this compare's files only: the earlier compare's (an events.csv of runs that locked) go
    clear_previous(args.out, "compare")
    write_file(args.out / "discrepancies.csv", table.to_csv(index=False))
    write_file(
        args.out / "discrepancies.md",
        f"# {args.a} ({a.model}) against {args.b} ({b.model})\n\n" + to_markdown(table),
    )
    quantities = [q for q in ROD_QUANTITIES if q in table["quantity"].values]
    if quantities:
        n = int(max(b.k_index[quantities[0]]))
        histories = {f"A: {a.model}": a, f"B: {b.model}": b}
        write_with(
            args.out / "histories.png",
            lambda tmp: plot_time_histories(
                histories, quantities, sorted({1, n}), tmp, title=f"{args.a} against {args.b}"
            ),
        )
    print(table.to_string(index=False, float_format=lambda v: f"{v:.3e}"))
    print(f"-> {args.out / 'discrepancies.md'}")
    if not locks.empty:
        write_file(args.out / "events.csv", locks.to_csv(index=False))
        write_file(
            args.out / "events.md",
            f"# Locks of {args.a} ({a.model}) against {args.b} ({b.model})\n\n"
            + to_markdown(locks, ".6g"),
        )
        print(f"\nLocks: A = {args.a} ({a.model}) against B = {args.b} ({b.model}):")
        print(locks.to_string(index=False, na_rep="", float_format=lambda v: f"{v:.6g}"))
        print(f"-> {args.out / 'events.md'}")
    return 0


if TYPE_CHECKING:
    import pandas as pd

#: Columns of compare's lock table (A: the run compared, B: the reference run).
LOCK_TABLE_COLUMNS = {
    "label": "label",
    "t_m": "t_A",
    "t_ref": "t_B",
    "dt": "dt",
    "impulse_m": "impulse_A",
    "impulse_ref": "impulse_B",
    "impulse_rel": "impulse_rel",
    "impulse_to_rigid_m": "impulse_to_rigid_A",
    "impulse_to_rigid_ref": "impulse_to_rigid_B",
    "not_comparable": "not_comparable",
}


def lock_table(events_a: list[dict[str, Any]], events_b: list[dict[str, Any]]) -> pd.DataFrame:
    """The locks of run A against the reference run B side by side (one row per lock label,
    ``rodval.analysis.events.lock_comparison``, columns LOCK_TABLE_COLUMNS); empty when
    neither run recorded a lock."""
    from rodval.analysis.events import events_frame, lock_comparison

    events = events_frame(
        [({"case": "", "model": "A"}, events_a), ({"case": "", "model": "B"}, events_b)]
    )
    if events.empty:
        return events
    table = lock_comparison(events, "A", "B")
    table["not_comparable"] = table["not_comparable"].str.replace(
        r"^only in (A|B)$", r"only in \1 (the other run did not lock)", regex=True
    )
    return table[list(LOCK_TABLE_COLUMNS)].rename(columns=LOCK_TABLE_COLUMNS)
