"""rodval reference SCENE --converge TOL --out DIR: the exudyn reference refined level by level
until its quantities of interest settle, every level recorded with the finest one's error bar
(``rodval.analysis.convergence``; docs/reference_model.md)."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

from rodval.cli.options import positive_float, positive_int

#: Levels a refinement may ask for: at least three (two changes, one ratio); at most eight
#: (the finest level runs 2**7 = 128 times the elements and steps of the first).
LEVELS_RANGE = (3, 8)
DEFAULT_LEVELS = 4


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


def register(sub) -> None:
    p = sub.add_parser(
        "reference",
        help="refine the exudyn reference until it converges, with its error bar",
        description="Run SCENE ('paper' or a TOML scene file) with the exudyn model at levels "
        "i = 0, 1, ...: elements E0 * 2**i per rod and step H0 / 2**i, until every quantity "
        "of interest (each lock's time, s, and impulse, relative; the chord angles at the "
        "scene's output times and their mean after the last lock, the deployed state, rad; on "
        "a free base the body's attitude the same way) has an estimated error below TOL after at "
        "least three levels, or --levels levels ran. The error of the finest level is "
        "Richardson's |d| / (2**p - 1) where the observed order p shows, else the last change "
        "|d| (rodval.analysis.convergence). Writes DIR/levels.csv (one row per level) and "
        "DIR/reference.json (the finest level's settings and its error bar, whose "
        "reference_error a study's [agreement] takes as it is). Exit 0 converged, 1 not "
        "converged (naming the quantity), 2 bad input. DIR must be new, empty or an output "
        "folder of rodval reference (refused before any work otherwise). The levels record the "
        "outputs phi, energy (its audit is part of the verdict) and base only.",
    )
    p.add_argument("scene", metavar="SCENE", help="'paper' or a TOML scene file")
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
    # DIR is claimed before any work and marked rodval's (rodval.cli._run, out_paths)
    p.set_defaults(func=run, out_folder="reference")


def with_qoi_outputs(scene: Any) -> Any:
    """``scene`` with the outputs the levels need and no others: "phi" (the quantities of
    interest), "energy" (its audit, part of every level's verdict) and, on a free base, "base"
    (the body's attitude). The command writes no trajectory, so the scene's other outputs
    would only cost memory (exudyn records every step of each)."""
    need = ("phi", "energy", "base") if scene.base.kind == "free" else ("phi", "energy")
    return scene.with_(outputs=need)


def plan(scene: Any, levels: int, elements: int | None, step: float | None) -> list[Any]:
    """The exudyn model of each level, each checked against ``scene`` before any work (its
    options, the scene's latches and base, its planned steps): ValueError naming the level."""
    from rodval.core.settings import IntegratorSettings
    from rodval.models.presets.registry import check_scene, get_model

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


def run_level(scene: Any, model: Any) -> dict[str, Any]:
    """One level's run: its settings, wall time, verdict and quantities of interest (None
    when the run failed, with its message)."""
    from rodval.analysis.convergence import quantities_of_interest
    from rodval.core.validity import describe
    from rodval.models.presets.registry import simulate

    start = time.perf_counter()
    tr = simulate(scene, model)
    row: dict[str, Any] = {
        "elements": model.elements,
        "step": model.step,
        "wall_s": time.perf_counter() - start,
        "verdict": describe(tr.stats.valid, tr.stats.validity),
    }
    if not tr.success or tr.times.size != scene.times.size:
        row["failed"] = (
            f"the run failed at t = {tr.times[-1] if tr.times.size else 0:g} s: {tr.stats.message}"
        )
        return row
    attitude = tr["base_attitude"] if scene.base.kind == "free" else None
    row["qoi"] = quantities_of_interest(tr.events, tr.times, tr["phi"], attitude)
    return row


def refine(
    scene: Any, models: list[Any], tol: float
) -> tuple[list[dict[str, Any]], list, str | None]:
    """Run the levels until converged after MIN_LEVELS or the last: (rows, estimates of the
    last levels run, None when converged else why not), printing one line per level."""
    from rodval.analysis.convergence import MIN_LEVELS, estimates, missing_quantity, unconverged

    rows: list[dict[str, Any]] = []
    found: list = []
    why: str | None = "not run"
    for i, model in enumerate(models):
        row = run_level(scene, model)
        rows.append(row)
        if "failed" in row:
            print(level_line(i, row))
            return rows, found, f"level {i} {row['failed']}"
        qoi = [r["qoi"] for r in rows]
        missing = missing_quantity(qoi)
        if missing is not None:
            print(level_line(i, row))
            return rows, found, f"{missing}: the levels do not lock alike"
        if i >= 1:
            found = estimates(qoi)
            row["changes"] = {e.name: e.changes[-1] for e in found}
        print(level_line(i, row))
        if i + 1 >= MIN_LEVELS:
            worst = unconverged(found, tol)
            why = (
                None
                if worst is None
                else (
                    f"{worst.name} error {worst.error:.3g} {worst.unit} >= {tol:g} ({worst.method})"
                )
            )
            if why is None:
                break
    return rows, found, why


def level_line(i: int, row: dict[str, Any]) -> str:
    """One printed line per level: settings, wall time, verdict, lock times, largest change."""
    locks = {k: v for k, v in row.get("qoi", {}).items() if k.startswith("lock_t[")}
    times = ", ".join(f"{k[7:-1]} {v:.6f} s" for k, v in locks.items())
    change = row.get("changes", {}).get("phi_times")
    moved = "" if change is None else f"; phi change {change:.3g} rad"
    return (
        f"level {i}: elements {row['elements']}, step {row['step']:g} s, {row['wall_s']:.1f} s, "
        f"{row['verdict']}; {times or 'no lock'}{moved}"
    )


def levels_table(rows: list[dict[str, Any]]) -> str:
    """levels.csv: level, elements, step, wall_s, verdict, then every scalar quantity's value
    and phi_times_change (rad: largest change of the chord angles from the level before; with
    a free base attitude_times_change, the body's attitude's)."""
    import pandas as pd

    records = []
    for i, row in enumerate(rows):
        rec = {"level": i, **{k: row[k] for k in ("elements", "step", "wall_s", "verdict")}}
        qoi = row.get("qoi", {})
        rec.update({k: v for k, v in qoi.items() if not k.endswith("_times")})
        for name in (k for k in qoi if k.endswith("_times")):
            rec[f"{name}_change"] = row.get("changes", {}).get(name)
        records.append(rec)
    return pd.DataFrame.from_records(records).to_csv(index=False, float_format="%.10g")


def reference_record(scene_name: str, tol: float, rows: list, found: list, why: str | None) -> dict:
    """reference.json: the finest level's settings, the verdict, each quantity's estimate and
    the error bar as a study's [agreement] reference_error."""
    import numpy as np

    from rodval.analysis.convergence import UNITS, error_bar, group_errors

    done = [r for r in rows if "qoi" in r]
    finest = done[-1] if done else rows[-1]
    scale = float(np.max(np.abs(finest["qoi"]["phi_times"]))) if "qoi" in finest else 0.0
    bar = error_bar(found, scale)
    return {
        "scene": scene_name,
        "model": "exudyn",
        "tol": tol,
        "converged": why is None,
        "not_converged": why,
        "levels": len(rows),
        "finest": {"elements": finest["elements"], "step": finest["step"]},
        "phi_scale_rad": scale,
        "reference_error": bar,
        "errors": {
            group: {"error": error, "unit": UNITS[group]}
            for group, error in group_errors(found).items()
        },
        "agreement_toml": "reference_error = { "
        + ", ".join(f"{k} = {v:.3g}" for k, v in bar.items())
        + " }",
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


def run(args) -> int:
    from rodval.core.out_paths import clear_previous, write_file
    from rodval.core.scene_file import load_scene

    scene = with_qoi_outputs(load_scene(args.scene))
    models = plan(scene, args.levels, args.elements, args.step)
    rows, found, why = refine(scene, models, args.converge)
    record = reference_record(str(args.scene), args.converge, rows, found, why)
    clear_previous(args.out, "reference")
    write_file(args.out / "levels.csv", levels_table(rows))
    write_file(args.out / "reference.json", json.dumps(record, indent=1))
    verdict = "converged" if why is None else f"not converged: {why}"
    print(
        f"error bar ({verdict}): {record['agreement_toml']} (levels {len(rows)}, finest "
        f"elements {record['finest']['elements']}, step {record['finest']['step']:g} s)"
    )
    print(
        "errors by group: "
        + ", ".join(f"{g} {e['error']:.3g} {e['unit']}" for g, e in record["errors"].items())
    )
    print(f"-> {args.out / 'reference.json'}")
    return 0 if why is None else 1
