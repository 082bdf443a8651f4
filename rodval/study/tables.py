"""The study's tables, built from the saved case records (pandas; written as CSV and markdown).

* ``cases``: case, n, horizon (s), one column per grid axis, l (rod lengths, JSON),
  latch_hinges (JSON), base_kind (pinned, free, prescribed: where the figures hang the
  chain), fingerprint.
* ``trajectories``: tidy case, model, t (s), quantity, k, value (rad, rad/s, m or J).
* ``discrepancies``: case, n, horizon, axes, model, reference, quantity, max_abs, rms,
  final_abs, max_rel, k_at_max, t_at_max (see ``rodval.analysis.metrics``), status.
* ``runtime``: case, n, horizon, axes, model, options (JSON: the model options the run ran
  with, an "auto" resolved, e.g. the full model's kinematics and shapes), the settings that
  change what ran (``rodval.core.trajectory.RUN_SETTINGS``: method, rtol, atol, max_step,
  first_step, error_control, block_frequency, bending_scale; blank for a model that
  integrates itself) and exudyn's step, wall_s (integration, s), setup_s (model set-up, s),
  nfev, njev, nlu, nsteps, t_reached (s), the audits' residuals, the validity verdict,
  status, message, and the run's peaks (``peaks``: JSON of ``SolverStats.peaks``' values,
  quantity -> [{k, peak, t}], read between the output times as ``peaks_read_on`` says).

* ``events``: case, n, horizon, axes, model, then one row per state event of a run
  (``Trajectory.events``: t (s), label, hinge, impulse (N m s, the lock impulse over the lock
  window, ``rodval.mechanics.lock_window``), impulse_window (s), rigid_impulse (N m s, the
  rigid-panel lock of the model's chords, ``rodval.mechanics.rigid``), impulse_to_rigid =
  impulse / rigid_impulse, kinetic_before, kinetic_after (J), energy_lost = kinetic_before -
  kinetic_after (J), the lock window's energy accounts (instant_energy_loss, the hinge and
  bending energy before the lock, kinetic, hinge, bending energy, work and dissipated energy
  at the window's end and the balance's residual, J: docs/deployment.md, "Where the lock
  energy goes"), and every further key a model records, e.g. impulse_momentum,
  angular_momentum_root_jump). Written only when some run has events.

``provenance.json`` (machine and package versions) and ``study.json`` lie beside them.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rodval.analysis.events import EVENT_COLUMNS as EVENT_COLUMNS
from rodval.analysis.events import events_frame
from rodval.analysis.metrics import METRICS
from rodval.analysis.modes import pair_modes
from rodval.core.modes import Modes
from rodval.core.out_paths import write_file

# EVENT_COLUMNS: the events table's leading columns, named here for the table's readers
from rodval.core.status import STATUS_MESSAGES
from rodval.core.trajectory import RUN_SETTINGS
from rodval.core.validity import broken
from rodval.report.markdown import to_markdown
from rodval.report.tables import MANIFEST, axis_columns, table_digest, trajectory_samples
from rodval.study.records import CaseRecord, DamagedRecord, read_case
from rodval.study.spec import StudySpec, case_value_text
from rodval.study.store import StudyStore, write_json_atomic


def _case_columns(rec: CaseRecord, axes: dict[str, str], full: bool = False) -> dict[str, Any]:
    """The columns that name a case: id, n, horizon and each grid value; a list or table
    value as JSON when ``full`` (cases.csv), else as its short text (``case_value_text``)."""
    return {
        "case": rec.case,
        "n": rec.n,
        "horizon": rec.t_end,
        **{col: _grid_value(rec.params.get(label), full) for label, col in axes.items()},
    }


def _grid_value(v: Any, full: bool) -> Any:
    if not isinstance(v, (list, dict)):
        return v
    return json.dumps(v, sort_keys=True) if full else case_value_text(v)


def cases_table(records: list[CaseRecord], axes: dict[str, str]) -> pd.DataFrame:
    return pd.DataFrame(
        [
            {
                **_case_columns(r, axes, full=True),
                "l": json.dumps(r.lengths),
                "latch_hinges": json.dumps(
                    sorted(
                        int(la["hinge"]) for la in r.scene.get("latches", []) if not la.get("held")
                    )
                ),
                "base_kind": r.scene.get("base", {}).get("kind", "pinned"),
                "fingerprint": r.fingerprint,
            }
            for r in records
        ]
    )


def trajectories_table(records: list[CaseRecord]) -> pd.DataFrame:
    parts = []
    for rec in records:
        for run in rec.runs:
            frame = run.trajectory.to_frame()
            frame.insert(0, "model", run.label)
            frame.insert(0, "case", rec.case)
            parts.append(frame)
    cols = ["case", "model", "t", "quantity", "k", "value"]
    return pd.concat(parts, ignore_index=True)[cols] if parts else pd.DataFrame(columns=cols)


def discrepancies_table(records: list[CaseRecord], axes: dict[str, str]) -> pd.DataFrame:
    rows = [{**_case_columns(rec, axes), **row} for rec in records for row in rec.discrepancies]
    cols = (
        [*_case_columns(records[0], axes), "model", "reference", "quantity", *METRICS, "status"]
        if records
        else []
    )
    return pd.DataFrame(rows).reindex(columns=cols)


def runtime_table(records: list[CaseRecord], axes: dict[str, str]) -> pd.DataFrame:
    rows = []
    for rec in records:
        for run in rec.runs:
            st, se = run.trajectory.stats, run.trajectory.settings
            rows.append(
                {
                    **_case_columns(rec, axes),
                    "model": run.label,
                    "options": json.dumps(run.trajectory.options, sort_keys=True),
                    **{k: se.get(k) for k in RUN_SETTINGS},
                    "step": se.get("step"),
                    "wall_s": st.wall_s,
                    "setup_s": run.setup_s,
                    "nfev": st.nfev,
                    "njev": st.njev,
                    "nlu": st.nlu,
                    "nsteps": st.nsteps,
                    "t_reached": st.t_reached,
                    "energy_residual": st.energy_residual,
                    "momentum_residual": st.momentum_residual,
                    "max_bending": st.max_bending,
                    "small_bending": st.small_bending,
                    "valid": st.valid,
                    "invalid_because": "; ".join(broken(st.validity)),
                    "status": STATUS_MESSAGES[st.status],
                    "message": st.message,
                    "peaks": None if st.peaks is None else json.dumps(st.peaks["values"]),
                    "peaks_read_on": None if st.peaks is None else st.peaks["read_on"],
                }
            )
    return pd.DataFrame(rows)


def events_table(records: list[CaseRecord], axes: dict[str, str]) -> pd.DataFrame:
    """One row per event of every run (see module docstring; ``events_frame``): columns beyond
    EVENT_COLUMNS are the union of the models' own keys, in first-seen order (blank where a
    model lacks one)."""
    lead = [*(_case_columns(records[0], axes) if records else {}), "model"]
    return events_frame(
        (
            ({**_case_columns(rec, axes), "model": run.label}, run.trajectory.events)
            for rec in records
            for run in rec.runs
        ),
        lead,
    )


def load_records(out: Path, case_ids: list[str], labels: list[str]) -> list[CaseRecord]:
    """The verified records of ``case_ids`` (ValueError naming the first missing or damaged)."""
    store, records = StudyStore(out), []
    for cid in case_ids:
        path = store.case_path(cid)
        if not path.is_file():
            raise ValueError(
                f"case {cid!r} has no result in {path.parent}; run the study to finish it"
            )
        try:
            records.append(read_case(path, labels=labels))
        except DamagedRecord as exc:
            raise ValueError(f"{exc}; run the study again to recompute it") from None
    return records


def build_tables(out: str | Path, spec: StudySpec | None = None) -> dict[str, pd.DataFrame]:
    """All tables of the study in ``out`` from its case records: the cases of ``spec``, or
    of the folder's study.json when no spec is given."""
    out = Path(out)
    meta = StudyStore(out).meta()
    if meta is None:
        raise ValueError(f"{out} is not a study folder: study.json is missing")
    ids = [c.id for c in spec.cases] if spec else [c["id"] for c in meta["cases"]]
    labels = [m["label"] for m in meta["models"]]
    records = load_records(out, ids, labels)
    axes = axis_columns(meta)
    tables = {
        "cases": cases_table(records, axes),
        "trajectories": trajectories_table(records),
        "discrepancies": discrepancies_table(records, axes),
        "runtime": runtime_table(records, axes),
    }
    events = events_table(records, axes)
    if not events.empty:
        tables["events"] = events
    if any(run.modes is not None or run.modes_error for rec in records for run in rec.runs):
        tables.update(modes_tables(records, axes))
    return tables


def modes_tables(records: list[CaseRecord], axes: dict[str, str]) -> dict[str, pd.DataFrame]:
    """When the study asks for modes ([modes]): ``modes`` (case, model, mode, omega_rad_s,
    f_hz, damping_ratio, or the modal analysis' error), ``mac`` (each model's modes paired by
    shape with the reference's, ``rodval.analysis.modes.pair_modes``: mode of the reference,
    both frequencies, rel_gap, mac) and ``mode_shapes`` (tidy: case, model, mode, kind,
    k, value; kind node_dx/node_dy/hinge, and node_x0/node_y0 for the configuration, mode 0).
    On a free base the modes are the flexible ones, numbered from 1 as ``rodval modes`` and
    ``mac`` number them (the three rigid motions stay in the case records)."""
    freq, mac, shapes = [], [], []
    for rec in records:
        base = _case_columns(rec, axes)
        got = {r.label: Modes.from_dict(r.modes) for r in rec.runs if r.modes is not None}
        for run in rec.runs:
            if run.modes is None:
                freq.append({**base, "model": run.label, "error": run.modes_error})
                continue
            m = got[run.label].flexible()  # a free base's rigid modes are not tabled
            frame = m.frequencies_frame()
            freq += [{**base, "model": run.label, **row} for row in frame.to_dict("records")]
            x0, y0 = m.node_positions()
            conf = pd.DataFrame(
                {
                    "mode": 0,
                    "kind": ["node_x0"] * x0.size + ["node_y0"] * y0.size,
                    "k": list(range(x0.size)) * 2,
                    "value": np.concatenate([x0, y0]),
                }
            )
            for part in (conf, m.modes_frame()):
                part = part.assign(model=run.label)
                for col, value in reversed(list(base.items())):
                    part.insert(0, col, value)
                shapes.append(part)
        ref = got.get(rec.reference)
        for label, m in got.items():
            if ref is None or label == rec.reference:
                continue
            paired = pair_modes(ref, m)
            mac += [
                {**base, "model": label, "reference": rec.reference, **row}
                for row in paired.to_dict("records")
            ]
    return {
        "modes": pd.DataFrame(freq),
        "mac": pd.DataFrame(mac),
        "mode_shapes": pd.concat(shapes, ignore_index=True) if shapes else pd.DataFrame(),
    }


def write_tables(out: str | Path, spec: StudySpec | None = None) -> dict[str, pd.DataFrame]:
    """Write ``<table>.csv`` for every table, ``<table>.md`` for the readable ones, and the
    manifest of the CSV files (``rodval.report.tables.MANIFEST``: size and SHA-256 of each),
    written last, so that a reader can tell a truncated or edited table."""
    out = Path(out)
    tables = build_tables(out, spec)
    for name, df in tables.items():
        write_file(out / f"{name}.csv", df.to_csv(index=False))
    meta = StudyStore(out).meta()
    assert meta is not None
    write_file(out / "discrepancies.md", to_markdown(tables["discrepancies"]))
    write_file(out / "runtime.md", to_markdown(tables["runtime"]))
    if "events" in tables:
        write_file(out / "events.md", to_markdown(tables["events"], ".6g"))
    for name in ("modes", "mac"):
        if name in tables:
            write_file(out / f"{name}.md", to_markdown(tables[name], ".6g"))
    write_file(
        out / "trajectories.md",
        to_markdown(trajectory_samples(tables["trajectories"], meta, tables["cases"]), ".6g"),
    )
    write_json_atomic(out / MANIFEST, {name: table_digest(out / f"{name}.csv") for name in tables})
    return tables
