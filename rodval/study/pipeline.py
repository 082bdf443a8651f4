"""Run a study: spec -> cases on workers -> one verified record per case -> tables -> report.

Resuming: a case whose record exists, verifies (``rodval.study.records``) and has the same
fingerprint (same scene, models and settings) is not run again, unless one of its runs ended
by ``timeout`` or ``worker crashed`` (conditions of the run, not of the case). A damaged or
incomplete record is named in a warning and recomputed. The pipeline knows nothing of the
physics: comparisons come from ``rodval.analysis.metrics``.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from rodval.analysis.metrics import compare_runs
from rodval.core.checks import as_path, check_choice, check_type
from rodval.core.out_paths import write_file
from rodval.core.provenance import provenance
from rodval.core.scene_file import scene_to_dict
from rodval.core.status import STATUS_CRASHED, STATUS_DIVERGED, STATUS_TIMEOUT, update_status
from rodval.core.trajectory import Trajectory
from rodval.study.case import Case
from rodval.study.records import CaseRecord, DamagedRecord, RunRecord, read_case
from rodval.study.schedule import BACKENDS, Done, default_workers, run_dask, run_processes
from rodval.study.spec import StudySpec, load_study
from rodval.study.store import StudyStore, write_json_atomic

RETRIED = (STATUS_TIMEOUT, STATUS_CRASHED)


def study_meta(spec: StudySpec, out: Path | None = None) -> dict[str, Any]:
    """The study's description saved beside the tables (the report reads it); with the
    study folder ``out``, ``source_path``: the study file's path relative to it (when the
    study was read from a file), which the report names."""
    relative = (
        {"source_path": os.path.relpath(Path(spec.source).resolve(), out.resolve())}
        if out is not None and _is_file(spec.source)
        else {}
    )
    return {
        "name": spec.name,
        "description": spec.description,
        "source": spec.source,
        **relative,
        "agreement": spec.agreement,
        "reference": spec.reference,
        "models": [m.as_dict() for m in spec.models],
        "axes": spec.axes,
        "labels": spec.labels,
        "report": spec.report.as_dict(),
        **({"sample": spec.sample} if spec.sample else {}),
        **({"acceptance": spec.acceptance} if spec.acceptance else {}),
        **({"scene_file": spec.scene_file} if spec.scene_file else {}),
        "cases": [
            {"id": c.id, "params": c.params, "fingerprint": c.fingerprint} for c in spec.cases
        ],
    }


def _is_file(source: str) -> bool:
    """Whether a study's ``source`` names a file (a study built in Python names none)."""
    try:
        return Path(source).is_file()
    except OSError:
        return False


def case_record(case: Case, runs: list[dict[str, Any]]) -> CaseRecord:
    """The record of a finished case: its runs in the study's model order (the reference's
    twin last), and the discrepancies of every run against the reference (the twin's: how
    far the reference parts from itself under the twin's perturbation)."""
    order = {label: i for i, label in enumerate(case.labels)}
    typed = sorted((RunRecord.from_dict(r) for r in runs), key=lambda r: order[r.label])
    for run in typed:
        _no_silent_nonfinite(run.trajectory)
    trajs: dict[str, Trajectory] = {r.label: r.trajectory for r in typed}
    return CaseRecord(
        case=case.id,
        fingerprint=case.fingerprint,
        params=case.params,
        scene=scene_to_dict(case.scene),
        reference=case.reference,
        runs=typed,
        discrepancies=compare_runs(trajs, case.reference, case.scene.outputs),
    )


def _no_silent_nonfinite(traj: Trajectory) -> None:
    """A run that reports success with non-finite values is recorded as diverged (the record
    reader refuses such a success, so it would be recomputed forever)."""
    if not traj.success:
        return
    for q, v in traj.values.items():
        if not np.all(np.isfinite(v)):
            message = f"diverged: the model reported success with non-finite values of {q!r}"
            update_status(traj.stats, STATUS_DIVERGED, message)
            if traj.stats.valid:  # no verdict on a run that failed (rodval.core.validity)
                traj.stats.valid = None
            return


def _reusable(store: StudyStore, case: Case, warnings: list[str]) -> bool:
    """Whether ``case``'s record in ``store`` verifies, is of this case (fingerprint) and has
    no run to retry; a damaged record adds a warning to ``warnings``."""
    path = store.case_path(case.id)
    if not path.exists():
        return False
    try:
        rec = read_case(path, labels=case.labels)
    except DamagedRecord as exc:
        warnings.append(f"{exc}; recomputing case {case.id!r}")
        return False
    if rec.fingerprint != case.fingerprint or rec.case != case.id:
        return False
    return all(r.status not in RETRIED for r in rec.runs)


@dataclass
class StudyRun:
    """What a study run did: cases run now, cases reused from disk, failed model runs, and
    warnings (damaged records that were recomputed)."""

    out: Path
    ran: list[str]
    reused: list[str]
    failed_runs: int
    wall_s: float
    warnings: list[str] = field(default_factory=list)


def run_study(
    spec: StudySpec | dict[str, Any] | str | Path,
    out: str | Path,
    *,
    workers: int | None = None,
    case_timeout: float | None = None,
    resume: bool = True,
    backend: str = "processes",
    scheduler: str | None = None,
    progress: bool = True,
    report: bool = True,
    fresh: bool = False,
) -> StudyRun:
    """Run the cases of ``spec`` (a study, a study document as a dict (``StudySpec.from_dict``)
    or the path of a study file) not yet on disk in ``out``, then write tables and report.

    workers: parallel cases for the processes backend (default: all cores).
    case_timeout: seconds after which a case's unfinished runs are stopped (None: no limit).
    resume: reuse finished cases in ``out`` (False: run every case again).
    backend: "processes" or "dask" (then ``scheduler`` is the address of a running
    dask.distributed scheduler).
    fresh: first remove what the study in ``out`` wrote (needed when it holds another
    study); a folder that holds files but is not a study folder of rodval (no study.json
    with rodval's schema and checksum) is refused, with or without ``fresh``.
    Every argument is checked before any work; a second run on the same folder at the same
    time is refused (``FolderBusy``).
    """
    spec = _as_study(spec)
    out = as_path("out", out)
    runner = _runner(backend, workers, scheduler, case_timeout)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out must be a folder, got the file {str(out)!r}")
    start = time.perf_counter()
    store = StudyStore(out)
    store.check_folder()
    warnings: list[str] = []
    with store.lock():
        store.claim(study_meta(spec, store.out), fresh=fresh)
        write_json_atomic(store.out / "provenance.json", provenance())
        write_file(store.out / "study.toml", spec.text)
        reused = [c.id for c in spec.cases if resume and _reusable(store, c, warnings)]
        # Longest first (rods x horizon as the cost guess) so that no big case starts last.
        todo = sorted(
            (c for c in spec.cases if c.id not in reused), key=lambda c: -c.scene.n * c.scene.t_end
        )
        failed = _run_cases(store, spec.name, todo, runner, progress)
        _write_results(store.out, spec, report)
    return StudyRun(
        out=store.out,
        ran=[c.id for c in todo],
        reused=reused,
        failed_runs=failed,
        wall_s=time.perf_counter() - start,
        warnings=warnings,
    )


def _as_study(spec: Any) -> StudySpec:
    """``run_study``'s ``spec`` as a study: read from a path, built from a dict, or checked."""
    if isinstance(spec, str | Path):
        spec = load_study(spec)
    elif isinstance(spec, dict):
        spec = StudySpec.from_dict(spec)
    check_type("spec", spec, StudySpec, "a study (rodval.load_study) or a study file's path")
    assert isinstance(spec, StudySpec)  # check_type raised otherwise
    return spec


@dataclass(frozen=True)
class Runner:
    """Where a study's cases run: ``backend`` "processes" (``workers`` warm processes on this
    machine) or "dask" (the cluster at ``scheduler``), each case within ``case_timeout`` s
    (None: no limit)."""

    backend: str
    workers: int
    scheduler: str | None
    case_timeout: float | None

    def run(self, payloads: list[dict[str, Any]], done: Done) -> None:
        """Run the ``payloads``, calling ``done`` as each ends."""
        if self.backend == "processes":
            run_processes(payloads, done, self.workers, self.case_timeout)
        else:
            assert self.scheduler is not None
            run_dask(payloads, done, self.scheduler, self.case_timeout)


def _runner(backend: Any, workers: Any, scheduler: Any, case_timeout: Any) -> Runner:
    """``run_study``'s runner arguments checked (ValueError naming the first that is wrong):
    a backend of BACKENDS, a scheduler for dask and none for processes, ``workers`` an
    integer >= 1 (None: every core), ``case_timeout`` None or a finite number > 0 (s)."""
    check_choice("backend", backend, BACKENDS)
    if backend == "dask" and not scheduler:
        raise ValueError("backend 'dask' needs --scheduler ADDRESS of a running dask scheduler")
    if backend == "processes" and scheduler is not None:
        raise ValueError(
            f"scheduler {scheduler!r:.60}: the processes backend runs on this machine and takes "
            "no scheduler; use backend 'dask'"
        )
    workers = default_workers() if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if case_timeout is not None and (
        isinstance(case_timeout, bool)
        or not isinstance(case_timeout, int | float)
        or not 0 < case_timeout < math.inf
    ):
        raise ValueError(
            f"case_timeout must be a finite number > 0 s or None (no limit), got {case_timeout!r:.60}"
        )
    return Runner(backend, workers, scheduler, case_timeout)


def _run_cases(
    store: StudyStore, name: str, todo: list[Case], runner: Runner, progress: bool
) -> int:
    """Run the cases ``todo`` on the ``runner``, writing each one's record to ``store`` as it
    finishes (with a progress bar named ``name``); returns the number of failed model runs.
    A case with a twin run ([agreement.twin]) is two payloads, the case's and the twin's
    (``Case.payloads``); its record is written when both have finished."""
    by_id = {c.id: c for c in todo}
    parts: dict[str, tuple[int, list[list[dict[str, Any]]]]] = {
        c.id: (len(c.payloads()), []) for c in todo
    }
    failed = 0
    bar = tqdm(total=len(todo), desc=name, unit="case", disable=not progress or not todo)

    def done(payload: dict[str, Any], runs: list[dict[str, Any]]) -> None:
        """Record a finished case (its payloads' run records) and advance the bar."""
        nonlocal failed
        case = by_id[payload["case"]]
        expected, got = parts[case.id]
        got.append(runs)
        if len(got) < expected:
            return
        record = case_record(case, [run for part in got for run in part])
        write_file(store.case_path(case.id), record.to_json())
        failed += sum(r.status != 0 for r in record.runs)
        bar.update(1)
        bar.set_postfix(failed_runs=failed)

    payloads = [p for c in todo for p in c.payloads()]
    try:
        runner.run(payloads, done)
    finally:
        bar.close()
    return failed


def _write_results(out: Path, spec: StudySpec, report: bool) -> None:
    """The study's tables in ``out`` from its case records, then its report (when ``report``)."""
    from rodval.study.tables import write_tables

    write_tables(out, spec)
    if report:
        from rodval.report.study_report import build_report

        build_report(out)
