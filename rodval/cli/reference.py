"""rodval reference SCENE --converge TOL --out DIR: the exudyn reference refined level by level
until its quantities of interest settle, every level recorded with the finest one's error bar
(``rodval.analysis.convergence``; docs/reference_model.md).

Each level is written as it finishes (DIR/level_I.json, stamped, listed in DIR's rodval.json
before it is written) and keyed by a digest of what it depends on (``level_digest``): a rerun
of a killed or interrupted command reuses the finished levels of the same request and says so.
The error bar compares the finest level with the levels before it that finished, are valid by
the model's own checks and lock alike (``convergence.compared_from``); a failed level ends the
refinement and no error bar is written."""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rodval.cli import SUMMARIES
from rodval.cli.options import positive_float, positive_int

#: Levels a refinement may ask for: at least three (two changes, one ratio); at most eight
#: (the finest level runs 2**7 = 128 times the elements and steps of the first).
LEVELS_RANGE = (3, 8)
DEFAULT_LEVELS = 4
#: The schema of a finished level's file (``rodval.core.out_paths.stamp``).
LEVEL_SCHEMA = "rodval-reference-level"
#: The summary files, written once the refinement ends.
LEVELS_CSV, REFERENCE_JSON = "levels.csv", "reference.json"


def level_count(text: str) -> int:
    """--levels N: an integer in LEVELS_RANGE."""
    low, high = LEVELS_RANGE
    try:
        v = int(text)
    except ValueError:
        v = 0
    if not low <= v <= high:
        raise argparse.ArgumentTypeError(
            f"--levels must be an integer in [{low}, {high}], got {text!r}"
        )
    return v


#: ``rodval reference --help``'s description (argparse rewraps it).
DESCRIPTION = """Run SCENE ('paper', a TOML scene file or the run.json of an earlier run: its scene)
with the exudyn model at levels i = 0, 1, ...: elements E0 * 2**i per rod and step H0 / 2**i, until
every quantity of interest (each lock's time, s, and impulse, relative; the chord angles at the
scene's output times and their mean after the last lock, the deployed state, rad; on a free base the
body's attitude the same way) has an estimated error below TOL over at least three compared levels,
or --levels levels ran. The levels compared are the finest and those just before it that finished,
are valid by the model's own checks and lock alike; a level that fails ends the refinement, and then
no error bar is given. The error of the finest level is Richardson's |d| / (2**p - 1) where the
observed order p shows, else the last change |d| (rodval.analysis.convergence). Writes
DIR/level_I.json as each level finishes (a rerun of the same request reuses them), then
DIR/levels.csv (one row per level) and DIR/reference.json (the finest level's settings, the levels
compared and their error bar, whose reference_error a study's [agreement] takes as it is; none when
a level failed or fewer than two levels compare). Exit 0 converged, 1 not converged or no error bar
(naming the quantity or the level), 2 bad input. DIR must be new, empty or an output folder of
rodval reference (refused before any work otherwise). The levels record the outputs phi, energy (its
audit is part of the verdict) and base only."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("reference", help=SUMMARIES["reference"], description=DESCRIPTION)
    p.add_argument("scene", metavar="SCENE", help="'paper', a TOML scene file or a run.json")
    p.add_argument(
        "--converge",
        required=True,
        metavar="TOL",
        type=positive_float("--converge"),
        help="bound on every quantity's estimated error (s, relative or rad; > 0)",
    )
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--levels",
        type=level_count,
        default=DEFAULT_LEVELS,
        help=f"most levels (integer in [{LEVELS_RANGE[0]}, {LEVELS_RANGE[1]}], default "
        f"{DEFAULT_LEVELS})",
    )
    p.add_argument(
        "--elements",
        type=positive_int("--elements"),
        metavar="E0",
        help="elements per rod at level 0 (default: the exudyn model's default)",
    )
    p.add_argument(
        "--step",
        type=positive_float("--step"),
        metavar="H0",
        help="time step at level 0, s (default: the exudyn model's default)",
    )
    p.add_argument(
        "--max-wall",
        type=positive_float("--max-wall", finite=False),
        default=math.inf,
        metavar="S",
        help="the whole command's wall-clock budget, s (default: no limit), from its start: "
        "each level is given what the levels before it left; a level it cannot finish is "
        "reported and the finished levels are kept",
    )
    # DIR is claimed before any work and marked rodval's (rodval.cli._run, out_paths)
    p.set_defaults(func=run, out_folder="reference")


# ------------------------------------------------------------------------- the request


def read_scene(source: str) -> tuple[Any, list[str]]:
    """SCENE's Scene and the notes on it: 'paper' or a TOML scene file, or an earlier run's
    run.json read as ``rodval simulate`` reads it (``read_run_record``: its keys and the digest
    of its scene_arrays.npz checked), of which the levels take the scene only."""
    from rodval.core.scene_file import load_scene, scene_from_dict

    path = Path(source)
    if path.suffix != ".json":
        return load_scene(source), []
    from rodval.report.run_files import read_run_record

    record = read_run_record(path)
    note = (
        f"{path}: its scene only (model {record['model']!r}, its options and settings are not "
        "the levels': every level runs exudyn at its own elements and step)"
    )
    return scene_from_dict(record["scene"], where=str(path)), [note]


def with_qoi_outputs(scene: Any) -> Any:
    """``scene`` with the outputs the levels need and no others: "phi" (the quantities of
    interest), "energy" (its audit, part of every level's verdict) and, on a free base, "base"
    (the body's attitude). The command writes no trajectory, so the scene's other outputs
    would only cost memory (exudyn records every step of each)."""
    need = ("phi", "energy", "base") if scene.base.kind == "free" else ("phi", "energy")
    return scene.with_(outputs=need)


def plan(scene: Any, levels: int, elements: int | None, step: float | None) -> list[Any]:
    """The exudyn model of each level, each checked against ``scene`` before any work (its
    options, the scene's latches and base, its planned steps and their memory, as for a run
    without a wall-clock budget: --max-wall bounds the levels' time, not their memory):
    ValueError naming the level."""
    from rodval.core.settings import IntegratorSettings
    from rodval.models.registry import check_scene, get_model

    base = get_model("exudyn")
    e0 = base.options()["elements"] if elements is None else elements
    h0 = base.options()["step"] if step is None else step
    if not isinstance(h0, float):
        raise ValueError(f"--step: the exudyn model's default step is {h0!r}; give --step H0 (s)")
    settings = IntegratorSettings()
    models = []
    for i in range(levels):
        try:
            model: Any = get_model("exudyn", elements=e0 * 2**i, step=h0 / 2**i)
            check_scene(model, scene, settings)
            model.check_scene(scene)
            model.check_plan(scene, settings)
        except ValueError as exc:
            raise ValueError(
                f"level {i} (elements {e0 * 2**i}, step {h0 / 2**i:g} s): {exc}"
            ) from None
        models.append(model)
    return models


def level_digest(scene: Any, model: Any) -> str:
    """SHA-256 of what a level's result depends on: the resolved scene (every key,
    ``scene_to_dict``), the model and its options at that level (elements, step and the
    rest), the versions of rodval and exudyn, and the sources of this command (with every
    rodval module it reaches: the quantities of interest, the registry) and of the exudyn
    model (``rodval.core.jit_cache.closure_digest``): a level is reused for this request only."""
    import hashlib
    import sys

    from rodval.core.jit_cache import closure_digest
    from rodval.core.provenance import package_versions
    from rodval.core.scene_file import scene_to_dict

    versions = package_versions()
    model_file = Path(str(sys.modules[type(model).__module__].__file__)).resolve()
    here = Path(__file__).resolve()
    key = {
        "scene": scene_to_dict(scene),
        "model": model.name,
        "options": model.options(),
        "versions": {name: versions[name] for name in ("rodval", "exudyn")},
        "sources": [
            closure_digest(here, here.parents[1]),
            closure_digest(model_file, model_file.parent),
        ],
    }
    text = json.dumps(key, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


# --------------------------------------------------------------------------- the levels


def level_name(i: int) -> str:
    """The file of level ``i`` in the output folder."""
    return f"level_{i}.json"


def run_level(scene: Any, model: Any, settings: Any) -> dict[str, Any]:
    """One level's run under ``settings`` (its wall-clock budget): its settings, wall time,
    how it ended (status name, message, time reached, s), verdict, and, when it reached t_end,
    its quantities of interest and the lock impulses that are none (``unmeasured``)."""
    from rodval.analysis.convergence import quantities_of_interest, unmeasured
    from rodval.core.status import Status
    from rodval.core.validity import describe
    from rodval.models.registry import simulate

    start = time.perf_counter()
    tr = simulate(scene, model, settings=settings)
    row: dict[str, Any] = {
        "elements": model.elements,
        "step": model.step,
        "wall_s": time.perf_counter() - start,
        "status": Status(tr.stats.status).name,
        "message": tr.stats.message,
        "t_reached": float(tr.stats.t_reached),
        "valid": tr.stats.valid,
        "verdict": describe(tr.stats.valid, tr.stats.validity),
    }
    if tr.success and tr.times.size == scene.times.size:
        attitude = tr["base_attitude"] if scene.base.kind == "free" else None
        row["qoi"] = quantities_of_interest(tr.events, tr.times, tr["phi"], attitude)
        row["not_measured"] = unmeasured(tr.events)
    return row


def not_run(model: Any, why: str) -> dict[str, Any]:
    """The row of a level the command's wall-clock budget left no time for."""
    return {
        "elements": model.elements,
        "step": model.step,
        "wall_s": 0.0,
        "status": "WALL",
        "message": why,
        "t_reached": 0.0,
        "valid": None,
        "verdict": "not run",
    }


def save_level(path: Path, i: int, digest: str, row: dict[str, Any]) -> None:
    """Write a finished level to ``path`` (atomically, stamped with LEVEL_SCHEMA): its digest
    (``level_digest``), row and quantities (``qoi_record``: every digit) and provenance."""
    from rodval.analysis.convergence import qoi_record
    from rodval.core.out_paths import stamp, write_file
    from rodval.core.provenance import provenance

    body = {**row, "qoi": qoi_record(row["qoi"])}
    record = {"level": i, "digest": digest, "row": body, "provenance": provenance()}
    write_file(path, json.dumps(stamp(record, LEVEL_SCHEMA), indent=1))


def load_level(path: Path, i: int, digest: str) -> tuple[dict[str, Any] | None, str | None]:
    """(the row of level ``i`` saved in ``path`` when it is of this request, else None; why a
    file there is not reused, else None): a file whose stamp does not hold (damaged, edited)
    or whose digest is another's (another scene, level settings or code) is not reused."""
    from rodval.analysis.convergence import qoi_from_record
    from rodval.core.out_paths import is_stamped, read_json

    if not path.exists():
        return None, None
    record = read_json(path)
    if not is_stamped(record, LEVEL_SCHEMA) or record.get("level") != i:
        return None, f"{path} is damaged or edited (its stamp does not hold): not reused"
    if record.get("digest") != digest:
        return None, (
            f"{path} is of another request (another scene, level settings or rodval/exudyn "
            "code): not reused"
        )
    row = dict(record["row"])
    row["qoi"] = qoi_from_record(row["qoi"])
    return row, None


def level_budget(max_wall_s: float, started: float) -> float:
    """The wall-clock budget (s) of the next level: what the command's ``max_wall_s`` leaves
    after the time since ``started`` (``time.perf_counter`` s) and the margin of
    ``rodval.cli.simulate.integration_budget`` (ValueError naming --max-wall when nothing is
    left); inf without a budget."""
    from rodval.cli.simulate import integration_budget

    return integration_budget(max_wall_s, time.perf_counter() - started, 0.0, 0.0)


@dataclass
class Levels:
    """The refinement's state: each level's row (``run_level``'s, or a reused one's with
    ``reused``: its file) and the judgement of the rows so far (``judge``)."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    compared: list[int] = field(default_factory=list)
    left_out: dict[int, str] = field(default_factory=dict)
    found: list[Any] = field(default_factory=list)


def usable(row: dict[str, Any]) -> bool:
    """Whether a level may be compared: it reached t_end and the model did not judge it
    INVALID (a verdict of None, nothing checked, is no judgement against it)."""
    return "qoi" in row and row["valid"] is not False


def failure(row: dict[str, Any], t_end: float) -> str:
    """How a level that did not reach t_end ended, in a few words."""
    return f"{row['status']} at t = {row['t_reached']:g} s of {t_end:g} s: {row['message']}"


def judge(levels: Levels, t_end: float) -> None:
    """Set the levels compared (``compared_from``), why each level before them is left out,
    and every quantity's estimate over the compared levels (none for fewer than two)."""
    from rodval.analysis.convergence import compared_from, estimates, missing_quantity

    rows = levels.rows
    start = compared_from([r["qoi"] if usable(r) else None for r in rows])
    levels.compared = list(range(start, len(rows)))
    levels.left_out = {}
    for i in range(start):
        row = rows[i]
        if "qoi" not in row:
            why = "failed (" + failure(row, t_end) + ")"
        elif row["valid"] is False:
            why = row["verdict"]
        elif start < len(rows):
            pair = [row["qoi"], rows[start]["qoi"]]
            differs = missing_quantity(pair, numbers=[i, start])
            why = differs or f"comes before level {start - 1}, which is left out"
        else:
            why = f"comes before level {len(rows) - 1}, which is left out"
        levels.left_out[i] = why
    compared = [rows[i]["qoi"] for i in levels.compared]
    levels.found = estimates(compared) if len(compared) >= 2 else []
    if levels.found:
        rows[-1]["changes"] = {e.name: e.changes[-1] for e in levels.found}


def no_error_bar(levels: Levels, t_end: float) -> str | None:
    """Why the levels give no error bar (a level failed; fewer than two levels compare), or
    None when they give one."""
    rows, last = levels.rows, len(levels.rows) - 1
    if "qoi" not in rows[-1]:
        return f"level {last} failed ({failure(rows[-1], t_end)})"
    if not levels.compared:
        return f"the finest level {last} is left out ({rows[-1]['verdict']})"
    if len(levels.compared) < 2:
        return (
            f"only level {last} can be compared (level {last - 1}: {levels.left_out[last - 1]}); "
            "an error bar compares two levels at least"
        )
    return None


def not_converged(levels: Levels, tol: float) -> str | None:
    """Why the compared levels are not converged to ``tol`` (too few of them, or the quantity
    with the largest error), or None when they are."""
    from rodval.analysis.convergence import MIN_LEVELS, unconverged

    if len(levels.compared) < MIN_LEVELS:
        return f"levels {span(levels.compared)} compared, convergence needs {MIN_LEVELS} at least"
    worst = unconverged(levels.found, tol)
    if worst is None:
        return None
    return f"{worst.name} error {worst.error:.3g} {worst.unit} >= {tol:g} ({worst.method})"


def span(compared: list[int]) -> str:
    """Levels a..b as text."""
    return f"{compared[0]}..{compared[-1]}" if compared else "none"


def left_out_note(levels: Levels) -> str:
    """' (level i left out: why; ...)' for the levels before the compared ones, else ''."""
    if not levels.left_out:
        return ""
    return " (" + "; ".join(f"level {i} left out: {w}" for i, w in levels.left_out.items()) + ")"


def refine(
    scene: Any,
    models: list[Any],
    digests: list[str],
    saved: list[dict[str, Any] | None],
    args: argparse.Namespace,
) -> Levels:
    """Run the levels, or take the finished ones ``saved`` (a row of this request's or None
    per level), until the compared levels converge to --converge, a level fails, or the last;
    each level run is given what --max-wall leaves, and written to --out as it finishes (with
    its ``digests`` entry); one printed line per level."""
    from rodval.analysis.convergence import MIN_LEVELS

    levels, budget, tol = Levels(), (args.max_wall, args.started), args.converge
    for i, (model, digest, row) in enumerate(zip(models, digests, saved, strict=True)):
        path = args.out / level_name(i)
        if row is not None:
            row["reused"] = str(path)
        else:
            row = fresh_level(scene, model, budget)
            if "qoi" in row:
                save_level(path, i, digest, row)
        levels.rows.append(row)
        judge(levels, scene.t_end)
        print(level_line(i, row))
        if "qoi" not in row:
            break
        if len(levels.compared) >= MIN_LEVELS and not_converged(levels, tol) is None:
            break
    return levels


def fresh_level(scene: Any, model: Any, budget: tuple[float, float]) -> dict[str, Any]:
    """Run a level with what the command's budget (--max-wall s, its start) leaves, or the row
    of a level it leaves no time for."""
    from rodval.core.settings import IntegratorSettings

    max_wall_s, started = budget
    try:
        left = level_budget(max_wall_s, started)
    except ValueError:
        spent = time.perf_counter() - started
        return not_run(model, f"not run: {spent:.1f} s of --max-wall {max_wall_s:g} s are spent")
    return run_level(scene, model, IntegratorSettings(max_wall_s=left))


def level_line(i: int, row: dict[str, Any]) -> str:
    """One printed line per level: where it comes from (reused), settings, wall time, verdict,
    lock times (or how it failed), largest change."""
    reused = f"reused {row['reused']} (same scene, settings and code): " if "reused" in row else ""
    locks = {k: v for k, v in row.get("qoi", {}).items() if k.startswith("lock_t[")}
    times = ", ".join(f"{k[7:-1]} {v:.6f} s" for k, v in locks.items())
    if "qoi" not in row:
        times = f"{row['status']} at t = {row['t_reached']:g} s: {row['message']}"
    change = row.get("changes", {}).get("phi_times")
    moved = "" if change is None else f"; phi change {change:.3g} rad"
    return (
        f"level {i}: {reused}elements {row['elements']}, step {row['step']:g} s, "
        f"{row['wall_s']:.1f} s, {row['verdict']}; {times or 'no lock'}{moved}"
    )


def levels_table(levels: Levels) -> str:
    """levels.csv: level, elements, step, wall_s, verdict, then every scalar quantity's value
    and phi_times_change (rad: largest change of the chord angles from the level compared
    before; with a free base attitude_times_change, the body's attitude's), then how the level
    ended (status, t_reached s, message), whether the error bar compares it and whether it was
    reused from an earlier run."""
    import pandas as pd

    from rodval.analysis.convergence import is_array

    records = []
    for i, row in enumerate(levels.rows):
        rec = {"level": i, **{k: row[k] for k in ("elements", "step", "wall_s", "verdict")}}
        qoi = row.get("qoi", {})
        rec.update({k: v for k, v in qoi.items() if not is_array(k)})
        for name in (k for k in qoi if is_array(k)):
            rec[f"{name}_change"] = row.get("changes", {}).get(name)
        rec.update({k: row[k] for k in ("status", "t_reached", "message")})
        rec["compared"] = i in levels.compared
        rec["reused"] = "reused" in row
        records.append(rec)
    frame = pd.DataFrame.from_records(records)
    tail = ["status", "t_reached", "message", "compared", "reused"]
    frame = frame[[c for c in frame.columns if c not in tail] + tail]
    return str(frame.to_csv(index=False, float_format="%.10g"))


def reference_record(scene_name: str, tol: float, levels: Levels, t_end: float) -> dict[str, Any]:
    """reference.json: the levels compared and those left out (why), the finest level's
    settings, the verdict, each quantity's estimate and the error bar as a study's
    [agreement] reference_error; no error bar (None, ``unusable`` says why) when a level
    failed or fewer than two levels compare."""
    import numpy as np

    from rodval.analysis.convergence import UNITS, error_bar, group_errors

    rows, found = levels.rows, levels.found
    finest = rows[-1]
    why_none = no_error_bar(levels, t_end)
    why_not = why_none if why_none is not None else not_converged(levels, tol)
    failed = None
    if "qoi" not in finest:
        failed = {"level": len(rows) - 1, **{k: finest[k] for k in ("status", "t_reached")}}
        failed["message"] = finest["message"]
    scale = float(np.max(np.abs(finest["qoi"]["phi_times"]))) if "qoi" in finest else 0.0
    bar = None if why_none is not None else error_bar(found, scale)
    return {
        "scene": scene_name,
        "model": "exudyn",
        "tol": tol,
        "converged": why_not is None,
        "not_converged": why_not,
        "usable": bar is not None,
        "unusable": why_none,
        "failed": failed,
        "levels": len(rows),
        "compared_levels": levels.compared,
        "left_out": {str(i): why for i, why in levels.left_out.items()},
        "finest": {"elements": finest["elements"], "step": finest["step"]},
        "phi_scale_rad": scale,
        "reference_error": bar,
        "not_measured": finest.get("not_measured", []) if bar is not None else [],
        "errors": {
            group: {"error": error, "unit": UNITS[group]}
            for group, error in group_errors(found).items()
        },
        "agreement_toml": None
        if bar is None
        else "reference_error = { " + ", ".join(f"{k} = {v:.3g}" for k, v in bar.items()) + " }",
        "quantities": [
            {
                "name": e.name,
                "unit": e.unit,
                "changes": list(e.changes),
                "order": e.order,
                "error": e.error,
                "method": e.method,
            }
            for e in found
        ],
    }


def summary(record: dict[str, Any], levels: Levels) -> list[str]:
    """The printed lines after the levels: the error bar over the levels it compares, or why
    there is none."""
    if record["reference_error"] is None:
        return [f"no error bar: {record['unusable']}"]
    verdict = "converged" if record["converged"] else f"not converged: {record['not_converged']}"
    finest = record["finest"]
    lines = [
        f"error bar ({verdict}) over levels {span(levels.compared)}{left_out_note(levels)}: "
        f"{record['agreement_toml']} (finest level {len(levels.rows) - 1}: elements "
        f"{finest['elements']}, step {finest['step']:g} s)",
        "errors by group: "
        + ", ".join(f"{g} {e['error']:.3g} {e['unit']}" for g, e in record["errors"].items()),
    ]
    if record["not_measured"]:
        lines.append(
            "not measured at the finest level (its lock window did not close by t_end): "
            + ", ".join(record["not_measured"])
        )
    return lines


def run(args: argparse.Namespace) -> int:
    from rodval.core.out_paths import clear_previous, mark_output_folder, write_file

    scene, notes = read_scene(args.scene)
    scene = with_qoi_outputs(scene)
    models = plan(scene, args.levels, args.elements, args.step)
    digests = [level_digest(scene, model) for model in models]
    level_budget(args.max_wall, args.started)  # before any work: refused when nothing is left
    names = [level_name(i) for i in range(len(models))]
    found = [load_level(args.out / n, i, d) for i, (n, d) in enumerate(zip(names, digests))]
    notes += [f"level {i}: {why}" for i, (_, why) in enumerate(found) if why is not None]
    saved = [row for row, _ in found]
    # the earlier run's files but this request's levels go; every file to come is listed first
    clear_previous(args.out, "reference", keep=[n for n, r in zip(names, saved) if r])
    args.out.mkdir(parents=True, exist_ok=True)
    mark_output_folder(args.out, "reference", coming=[*names, LEVELS_CSV, REFERENCE_JSON])
    for note in notes:
        print(f"note: {note}")
    levels = refine(scene, models, digests, saved, args)
    record = reference_record(str(args.scene), args.converge, levels, scene.t_end)
    write_file(args.out / LEVELS_CSV, levels_table(levels))
    write_file(args.out / REFERENCE_JSON, json.dumps(record, indent=1))
    for line in summary(record, levels):
        print(line)
    if math.isfinite(args.max_wall):
        print(
            f"note: --max-wall {args.max_wall:g} s is the whole command's budget: each level "
            f"was given what the levels before it left; the command took "
            f"{time.perf_counter() - args.started:.3g} s"
        )
    print(f"-> {args.out / REFERENCE_JSON}")
    return 0 if record["converged"] else 1
