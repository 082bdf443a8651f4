"""Run a study: every case in worker processes (or on a dask cluster), each finished case
written to ``OUT/cases/<case id>.json`` at once and atomically, then the tables and report.

Resuming: a case whose file exists with the same fingerprint (same scene, models and
settings) is not run again, unless one of its runs ended by ``timeout`` or ``worker crashed``
(conditions of the run, not of the case). The runner knows nothing of the physics.
"""
from __future__ import annotations

import json
import os
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

from tqdm import tqdm

from ..compare import discrepancies
from ..provenance import provenance
from ..trajectory import STATUS_CRASHED, STATUS_MESSAGES, STATUS_TIMEOUT, Trajectory
from .spec import Case, StudySpec
from .worker import complete_runs, kill_live_workers, run_case_isolated

BACKENDS = ("processes", "dask")
RETRIED = (STATUS_TIMEOUT, STATUS_CRASHED)


def case_path(out: Path, case_id: str) -> Path:
    return Path(out) / "cases" / f"{case_id}.json"


def write_json_atomic(path: Path, obj: Any) -> None:
    """Write JSON to a temporary file beside ``path`` and rename it over ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(obj, indent=1, default=repr))
    os.replace(tmp, path)


def _expected_quantities(case: Case) -> tuple[str, ...]:
    out = []
    for q in case.scene.outputs:
        out.extend(("kinetic", "potential", "energy") if q == "energy" else (q,))
    return tuple(out)


def compare_runs(case: Case, runs: list[dict]) -> list[dict[str, Any]]:
    """Discrepancy rows of every non-reference model against the reference, one per quantity.

    When either run failed, the metrics are NaN and ``status`` says which run failed.
    """
    trajs = {r["label"]: Trajectory.from_dict(r["trajectory"]) for r in runs}
    ref = trajs[case.reference]
    quantities = ref.quantities if ref.success else _expected_quantities(case)
    rows = []
    for label, traj in trajs.items():
        if label == case.reference:
            continue
        base = {"model": label, "reference": case.reference}
        if not ref.success:
            status = f"reference failed ({STATUS_MESSAGES[ref.stats.status]})"
        elif not traj.success:
            status = f"model failed ({STATUS_MESSAGES[traj.stats.status]})"
        else:
            try:
                rows += [{**base, **r, "status": "ok"}
                         for r in discrepancies(traj, ref, quantities).to_dict("records")]
                continue
            except ValueError as exc:
                status = f"not comparable: {exc}"
        rows += [{**base, "quantity": q, "status": status} for q in quantities]
    return rows


def case_record(case: Case, runs: list[dict]) -> dict[str, Any]:
    """Everything the tables need about one finished case."""
    order = {m.label: i for i, m in enumerate(case.models)}
    runs = sorted(runs, key=lambda r: order[r["label"]])
    return {"case": case.id, "fingerprint": case.fingerprint, "params": case.params,
            "n": case.scene.n, "horizon": case.scene.t_end, "l": case.scene.chain.l.tolist(),
            "reference": case.reference, "runs": runs,
            "discrepancies": compare_runs(case, runs)}


def is_finished(out: Path, case: Case) -> bool:
    """True if the case's file holds a result of this very case that need not be redone."""
    path = case_path(out, case.id)
    try:
        rec = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return False
    if rec.get("fingerprint") != case.fingerprint:
        return False
    return all(r["trajectory"]["stats"]["status"] not in RETRIED for r in rec["runs"])


def study_meta(spec: StudySpec) -> dict[str, Any]:
    """The study's description saved beside the tables (the report reads it)."""
    return {"name": spec.name, "description": spec.description, "source": spec.source,
            "reference": spec.reference, "models": [m.as_dict() for m in spec.models],
            "axes": spec.axes, "labels": spec.labels, "report": spec.report.as_dict(),
            "cases": [{"id": c.id, "params": c.params, "fingerprint": c.fingerprint}
                      for c in spec.cases]}


Runner = Callable[[list[Case], Callable[[Case, list[dict]], None]], None]


def _run_processes(workers: int, timeout: float | None) -> Runner:
    def run(cases, done):
        pool = ThreadPoolExecutor(max_workers=workers)
        try:
            futures = {pool.submit(run_case_isolated, c.payload(), timeout): c for c in cases}
            for fut in as_completed(futures):
                done(futures[fut], fut.result())
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            kill_live_workers()
            raise
        pool.shutdown()
    return run


def _run_dask(scheduler: str, timeout: float | None) -> Runner:
    def run(cases, done):
        from dask.distributed import Client, as_completed as dask_completed

        with Client(scheduler) as client:
            futures = client.map(run_case_isolated, [c.payload() for c in cases],
                                 timeout=timeout, pure=False)
            by_key = {f.key: c for f, c in zip(futures, cases)}
            for fut in dask_completed(futures):
                case = by_key[fut.key]
                try:
                    runs = fut.result()
                except Exception as exc:  # noqa: BLE001 - the task itself failed
                    runs = complete_runs(case.payload(), [], STATUS_CRASHED,
                                     f"dask task failed: {type(exc).__name__}: {exc}")
                done(case, runs)
    return run


@dataclass
class StudyRun:
    """What a study run did: cases run now, cases reused from disk, failed model runs."""

    out: Path
    ran: list[str]
    reused: list[str]
    failed_runs: int
    wall_s: float


def run_study(spec: StudySpec, out: str | Path, *, workers: int | None = None,
              case_timeout: float | None = None, resume: bool = True,
              backend: str = "processes", scheduler: str | None = None,
              progress: bool = True, report: bool = True) -> StudyRun:
    """Run the cases of ``spec`` not yet on disk in ``out``, then write tables and report.

    workers: parallel cases for the processes backend (default: all cores).
    case_timeout: seconds after which a case's unfinished runs are stopped (None: no limit).
    resume: reuse finished cases in ``out`` (False: run every case again).
    backend: "processes" or "dask" (then ``scheduler`` is the address of a running
    dask.distributed scheduler).
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if backend == "dask" and not scheduler:
        raise ValueError("backend 'dask' needs --scheduler ADDRESS of a running dask scheduler")
    workers = (os.cpu_count() or 1) if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if case_timeout is not None and not case_timeout > 0:
        raise ValueError(f"case_timeout must be > 0 s or None, got {case_timeout!r}")
    out = Path(out)
    start = time.perf_counter()
    (out / "cases").mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "study.json", study_meta(spec))
    write_json_atomic(out / "provenance.json", provenance())
    (out / "study.toml").write_text(spec.text)
    reused = [c.id for c in spec.cases if resume and is_finished(out, c)]
    # Longest first (rods x horizon as the cost guess) so that no big case starts last.
    todo = sorted((c for c in spec.cases if c.id not in reused),
                  key=lambda c: -c.scene.n * c.scene.t_end)
    failed = 0
    bar = tqdm(total=len(todo), desc=spec.name, unit="case", disable=not progress or not todo)

    def done(case: Case, runs: list[dict]) -> None:
        nonlocal failed
        record = case_record(case, runs)
        write_json_atomic(case_path(out, case.id), record)
        failed += sum(r["trajectory"]["stats"]["status"] != 0 for r in runs)
        bar.update(1)
        bar.set_postfix(failed_runs=failed)

    runner = (_run_processes(workers, case_timeout) if backend == "processes"
              else _run_dask(scheduler, case_timeout))
    try:
        runner(todo, done)
    finally:
        bar.close()
    from .tables import write_tables

    write_tables(out)
    if report:
        from ..report import build_report

        build_report(out)
    return StudyRun(out=out, ran=[c.id for c in todo], reused=reused, failed_runs=failed,
                    wall_s=time.perf_counter() - start)


def load_records(out: Path, case_ids: Iterable[str]) -> list[dict[str, Any]]:
    """The saved records of ``case_ids`` (ValueError naming the first missing one)."""
    records = []
    for cid in case_ids:
        path = case_path(out, cid)
        if not path.is_file():
            raise ValueError(f"case {cid!r} has no result in {path.parent}; run the study to finish it")
        records.append(json.loads(path.read_text()))
    return records
