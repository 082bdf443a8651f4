"""Study folders under misuse and damage: concurrent runs, killed runs, another study, damaged
case records, long case ids, damaged tables. Each ends with a one-line error (exit 2) or a
warning naming the file and a recomputed case, never a crash or a silent reuse."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from study_helpers import write_study

from rodval.cli import main
from rodval.study import load_study
from rodval.study.records import DamagedRecord, read_case
from rodval.study.store import MAX_NAME

ROOT = Path(__file__).resolve().parent.parent
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err, err
    return lines[0]


def start_study(study: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "rodval",
            "study",
            str(study),
            "--out",
            str(out),
            "--workers",
            "1",
            "--no-progress",
            "--no-report",
        ],  # fmt: skip
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def wait_for_lock(out: Path, proc: subprocess.Popen, timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    lock = out / ".lock"
    while time.monotonic() < deadline:
        if lock.is_file() and lock.read_text().strip() == str(proc.pid):
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    raise AssertionError("the first run never took the lock")


def assert_complete_tables(out: Path, cases: list[str], models: set[str]) -> None:
    assert sorted(pd.read_csv(out / "cases.csv")["case"]) == sorted(cases)
    traj = pd.read_csv(out / "trajectories.csv")
    for cid in cases:
        sub = traj[traj["case"] == cid]
        assert set(sub["model"]) == models, cid
        assert np.all(np.isfinite(sub["value"].to_numpy(float)))
    runtime = pd.read_csv(out / "runtime.csv")
    assert len(runtime) == len(cases) * len(models)
    assert set(runtime["status"]) == {"success"}


def test_concurrent_study_on_one_folder_is_refused(tmp_path, capsys):
    """Issue: two studies started on one folder both exited 0 and the tables held only the
    second study's cases. The second run (started while the first holds the folder) is
    refused in one line, exit 2; the first finishes with complete, correct tables."""
    first = write_study(tmp_path, "first.toml")
    out = tmp_path / "out"
    proc = start_study(first, out)
    wait_for_lock(out, proc)
    second = write_study(tmp_path, "second.toml", grid="scene.t_end = [0.3]")
    assert main(["study", str(second), "--out", str(out), "--no-progress"]) == 2
    line = one_line(capsys)
    assert "in use by another rodval study" in line and str(proc.pid) in line
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0, stderr
    assert stdout.startswith("tiny: 4 cases run")
    cases = ["n=2,t_end=0.1", "n=2,t_end=0.2", "n=3,t_end=0.1", "n=3,t_end=0.2"]
    assert_complete_tables(out, cases, {"reduced", "published"})


def test_killed_study_leaves_no_stuck_lock_and_another_study_needs_fresh(tmp_path, capsys):
    """A run killed with SIGKILL leaves the lock to the kernel: the next run takes it. A
    different study into that folder is refused unless --fresh."""
    study = write_study(tmp_path)
    out = tmp_path / "out"
    proc = start_study(study, out)
    wait_for_lock(out, proc)
    proc.send_signal(signal.SIGKILL)
    proc.communicate()
    argv = ["--out", str(out), "--no-progress", "--no-report", "--workers", "1"]
    assert main(["study", str(study), *argv]) == 0
    capsys.readouterr()
    other = tmp_path / "other.toml"
    other.write_text(study.read_text().replace('name = "tiny"', 'name = "other"'))
    assert main(["study", str(other), *argv]) == 2
    line = one_line(capsys)
    assert "holds another study ('tiny'" in line and "--fresh" in line
    assert main(["study", str(other), *argv, "--fresh"]) == 0
    assert json.loads((out / "study.json").read_text())["name"] == "other"


#: Child of ``_kill_before_every_change``. argv: study file, start folder (copied into each
#: killed folder when it exists), base folder, "fresh" or "". For n = 1, 2, ... it forks a
#: process that runs the study into ``<base>/killed<n>`` and SIGKILLs itself just before its
#: n-th change of that folder (an open for writing, a folder made or removed, a rename, a
#: removal), as a kill from outside can land between any two changes; it stops at the n whose
#: process reaches the start of the cases (its first worker) and prints how many were killed.
KILL_AT_EVERY_CHANGE = r"""
import os, shutil, signal, sys, traceback
from pathlib import Path
from rodval.study import load_study
from rodval.study.pipeline import run_study

spec, start, base = load_study(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
fresh = sys.argv[4] == "fresh"
CHANGES = ("open", "os.mkdir", "os.rename", "os.remove", "os.rmdir")
WRITES = os.O_WRONLY | os.O_RDWR | os.O_CREAT


def run_killed_before_change(n, out):
    seen = 0

    def hook(event, args):
        nonlocal seen
        if event == "subprocess.Popen" and "rodval.study.worker" in args[1]:
            os._exit(3)  # the folder is taken: the first case would start now
        if event not in CHANGES or not isinstance(args[0], (str, os.PathLike)):
            return
        if event == "open" and not args[2] & WRITES:
            return
        path = os.path.abspath(args[0])
        if path == str(out) or path.startswith(str(out) + os.sep):
            seen += 1
            if seen == n:
                os.kill(os.getpid(), signal.SIGKILL)

    sys.addaudithook(hook)
    run_study(spec, out, workers=1, progress=False, report=False, fresh=fresh)


for n in range(1, 500):
    out = base / f"killed{n:03d}"
    if start.is_dir():
        shutil.copytree(start, out)
    pid = os.fork()
    if pid == 0:
        try:
            run_killed_before_change(n, out)
        except BaseException:
            traceback.print_exc()
        os._exit(4)  # refused, or ended without starting a case
    status = os.waitpid(pid, 0)[1]
    if os.WIFEXITED(status) and os.WEXITSTATUS(status) == 3:
        shutil.rmtree(out, ignore_errors=True)
        print(n - 1)
        break
    assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL, (n, status)
"""


def _kill_before_every_change(
    study: Path, base: Path, start: Path | None, fresh: bool
) -> list[Path]:
    """The folders left by runs of ``study`` killed before each change they make to their
    folder (``KILL_AT_EVERY_CHANGE``), in the order of the changes; each run starts from a
    copy of ``start`` (None: a folder that does not exist yet)."""
    base.mkdir()
    argv = [str(study), str(start or base / "none"), str(base), "fresh" if fresh else ""]
    done = subprocess.run(
        [sys.executable, "-c", KILL_AT_EVERY_CHANGE, *argv],
        env=ENV, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    killed = int(done.stdout)
    return [base / f"killed{n:03d}" for n in range(1, killed + 1)]


class _CasesStart(Exception):
    """Raised where a study run that took its folder would start its cases."""


def _take(spec, out: Path, monkeypatch, *, fresh: bool = False) -> str:
    """What ``run_study`` of ``spec`` makes of the folder ``out``: "taken" when it reaches
    its cases, else the error it gives."""
    from rodval.study import pipeline

    def start_cases(*args, **kwargs):
        raise _CasesStart

    monkeypatch.setattr(pipeline, "_run_cases", start_cases)
    try:
        pipeline.run_study(spec, out, workers=1, progress=False, report=False, fresh=fresh)
    except _CasesStart:
        return "taken"
    except ValueError as exc:
        return str(exc)
    raise AssertionError("run_study ended without starting its cases")


def _state(out: Path) -> list[str]:
    return sorted(str(p.relative_to(out)) for p in out.rglob("*")) if out.exists() else []


def _copy(out: Path, name: str) -> Path:
    import shutil

    copy = out.with_name(f"{out.name}-{name}")
    if out.exists():
        shutil.copytree(out, copy)
    return copy


def _holder(out: Path) -> str | None:
    """The name of the study whose study.json is in ``out`` (None: none there)."""
    path = out / "study.json"
    return json.loads(path.read_text())["name"] if path.exists() else None


def test_study_killed_at_any_point_of_its_claim_leaves_a_folder_the_next_run_takes(
    tmp_path, monkeypatch
):
    """Issue (a flaky test_killed_study_...): a study killed after it had made OUT/cases but
    before its study.json was written left a folder every later run refused as "not a study
    folder of rodval ... it holds 'cases'"; a second study started then, while the first
    still ran, was told the same instead of "in use". Killed before any change it makes to
    a new folder, a study leaves one that it takes again, and that another study takes too,
    or is told holds this study only when its study.json is there; while a run holds the
    folder (a live run at that point), another is told it is in use."""
    from rodval.study.store import StudyStore

    tiny = write_study(tmp_path)
    other = tmp_path / "other.toml"
    other.write_text(tiny.read_text().replace('name = "tiny"', 'name = "other"'))
    spec, other_spec = load_study(tiny), load_study(other)
    killed = _kill_before_every_change(tiny, tmp_path / "runs", None, fresh=False)
    # the folder, its lock, cases/, study.json, provenance.json, study.toml: at least 6
    assert len(killed) >= 6, killed
    for out in killed:
        state, copy, busy = _state(out), _copy(out, "other"), _copy(out, "busy")
        with StudyStore(busy).lock():
            verdict = _take(other_spec, busy, monkeypatch)
        assert "in use by another rodval study" in verdict, (state, verdict)
        assert _take(spec, out, monkeypatch) == "taken", state
        holder = _holder(copy)
        verdict = _take(other_spec, copy, monkeypatch)
        if holder is None:
            assert verdict == "taken", state
        else:
            assert "holds another study ('tiny'" in verdict, (state, verdict)
            assert _take(other_spec, copy, monkeypatch, fresh=True) == "taken", state


def test_study_killed_at_any_point_of_fresh_leaves_a_folder_fresh_takes(
    finished, tmp_path, monkeypatch
):
    """Issue: --fresh removed the old study's study.json first; killed before the new one was
    written, it left the old study's tables and records in a folder no run could take, not
    even with --fresh. Killed before any change of --fresh, the folder is taken by --fresh,
    and a run without it is told the folder holds the study its study.json names."""
    other = write_study(tmp_path, "other.toml", grid="scene.t_end = [0.1]")
    other.write_text(other.read_text().replace('name = "tiny"', 'name = "other"'))
    spec = load_study(other)
    killed = _kill_before_every_change(other, tmp_path / "runs", finished, fresh=True)
    # one removal at least for each file of the old study
    assert len(killed) >= len(list(finished.iterdir())), killed
    for out in killed:
        state, copy = _state(out), _copy(out, "again")
        assert _take(spec, out, monkeypatch, fresh=True) == "taken", state
        holder = _holder(copy)
        verdict = _take(spec, copy, monkeypatch)
        assert holder in ("tiny", "other"), state
        if holder == "other":
            assert verdict == "taken", state
        else:
            assert "holds another study ('tiny'" in verdict, (state, verdict)


# ------------------------------------------------------------------- damaged case records


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("finished")
    study = write_study(tmp, grid="scene.t_end = [0.1]")
    out = tmp / "out"
    assert main(["study", str(study), "--out", str(out), "--no-progress", "--no-report"]) == 0
    return out


def _damages(doc: dict) -> dict[str, object]:
    """Each damage: the new file content (bytes or JSON-able), from a valid record ``doc``."""
    no_runs = {k: v for k, v in doc.items() if k != "runs"}
    one_run = {**doc, "runs": doc["runs"][1:]}
    edited = json.loads(json.dumps(doc))
    q = next(iter(edited["runs"][0]["trajectory"]["values"]))
    edited["runs"][0]["trajectory"]["values"][q][-1][-1] += 0.5
    shaped = json.loads(json.dumps(doc))
    shaped["runs"][0]["trajectory"]["values"][q] = [[1.0, 2.0, 3.0]]
    return {
        "[]": [],
        "null": None,
        "no runs": no_runs,
        "random bytes": os.urandom(64) + b"\xff",
        "wrong-shaped array": shaped,
        "one model's run deleted": one_run,
        "edited value": edited,
        "truncated": json.dumps(doc)[:100].encode(),
    }


def _write(path: Path, content) -> None:
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(json.dumps(content))


def test_every_damage_is_refused_by_read_case(finished, tmp_path):
    """read_case names the file and what is wrong for each damage (no exception of another
    kind)."""
    path = tmp_path / "case.json"
    path.write_text(sorted((finished / "cases").glob("*.json"))[0].read_text())
    doc = json.loads(path.read_text())
    read_case(path, labels=["reduced", "published"])
    for kind, content in _damages(doc).items():
        _write(path, content)
        with pytest.raises(DamagedRecord) as info:
            read_case(path, labels=["reduced", "published"])
        assert str(info.value).startswith(str(path)), kind
    # a checksum recomputed over a record with a run deleted: still incomplete
    from rodval.study.records import checksum

    body = {k: v for k, v in doc.items() if k != "checksum"}
    body["runs"] = body["runs"][1:]
    _write(path, {**body, "checksum": checksum(body)})
    with pytest.raises(DamagedRecord, match="incomplete case record: no run of model"):
        read_case(path, labels=["reduced", "published"])


def test_resume_over_damaged_records_recomputes_them(tmp_path, capsys):
    """Issue: damaged case files ([], null, no 'runs', random bytes, a wrong-shaped array)
    crashed a resume; a file with one model's run deleted or with edited values was reused
    silently. Each damaged file is named in a warning, its case recomputed, the tables
    complete and consistent."""
    study = write_study(tmp_path, grid="scene.t_end = [0.1, 0.2, 0.3, 0.4]")
    out = tmp_path / "out"
    argv = ["study", str(study), "--out", str(out), "--no-progress", "--no-report"]
    assert main(argv) == 0
    files = sorted((out / "cases").glob("*.json"))
    assert len(files) == 8
    capsys.readouterr()
    damages = _damages(json.loads(files[0].read_text()))
    for path, content in zip(files, damages.values()):
        _write(path, content)
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("tiny: 8 cases run, 0 reused"), captured.out
    for path in files:
        assert f"warning: {path}" in captured.err, path
        read_case(path, labels=["reduced", "published"])
    cases = [f"n={n},t_end={t}" for n in (2, 3) for t in (0.1, 0.2, 0.3, 0.4)]
    assert_complete_tables(out, cases, {"reduced", "published"})


# ------------------------------------------------------------------------- long case ids


def test_long_case_id_runs_end_to_end(tmp_path):
    """Issue: a grid of scene.loads with 12 pulses made a case id too long for a file name
    ("File name too long" after the first case ran). Names are bounded and distinct; since
    issue 21 the ids themselves are short (a long value is a label and a hash, its full value
    in cases.csv), they were over 300 characters."""
    pulses = ", ".join(
        f'{{type = "pulse", node = "last", Xbar = {-150 - i}, Ybar = {1200 + i}}}'
        for i in range(12)
    )
    study = write_study(
        tmp_path, grid=f'scene.loads = [[{pulses}], [{{type = "pulse", node = "last"}}]]'
    )
    spec = load_study(study)
    assert max(len(c.id) for c in spec.cases) < 60
    assert len({c.id for c in spec.cases}) == 4
    out = tmp_path / "out"
    assert main(["study", str(study), "--out", str(out), "--no-progress", "--no-report"]) == 0
    names = [p.name for p in (out / "cases").glob("*.json")]
    assert len(names) == len(spec.cases) == 4
    assert max(len(n) for n in names) <= MAX_NAME
    assert_complete_tables(out, [c.id for c in spec.cases], {"reduced", "published"})


def test_colliding_file_names_are_refused_before_any_case_runs(tmp_path, monkeypatch):
    import rodval.study.spec as spec_module

    monkeypatch.setattr(spec_module, "case_file_name", lambda cid: "same.json")
    with pytest.raises(ValueError, match=r"key 'grid': cases .* would share the record file"):
        load_study(write_study(tmp_path))


def test_study_too_large_is_refused_before_any_case_runs(tmp_path, capsys, monkeypatch):
    """The memory of each case's runs, with the dense matrices of an implicit method, and of
    the study's tables, is checked when the file is read."""
    study = write_study(tmp_path, grid="scene.t_end = [0.1]").read_text()
    path = tmp_path / "big.toml"
    path.write_text(study.replace('method = "DOP853"', 'method = "Radau"').replace(
        "scene.n = [2, 3]", "scene.n = [2, 20000]"))  # fmt: skip
    assert main(["study", str(path), "--out", str(tmp_path / "o"), "--no-progress"]) == 2
    line = one_line(capsys)
    assert "case 'n=20000,t_end=0.1', model 'reduced'" in line
    assert "dense matrices of the 20000-rod system" in line and "GB" in line
    monkeypatch.setenv("RODVAL_MAX_MEMORY_GB", "0.0001")
    with pytest.raises(ValueError, match="for its tables"):
        load_study(write_study(tmp_path, grid="scene.t_end = [0.1, 0.2, 0.3, 0.4, 0.5]"))


# --------------------------------------------------------------------------- damaged tables


def _edit(path: Path, change) -> None:
    df = pd.read_csv(path)
    change(df).to_csv(path, index=False)


TABLE_DAMAGES = {
    "missing": ("runtime", lambda p: p.unlink(), "runtime.csv is missing"),
    "empty": ("cases", lambda p: p.write_text(""), "not a readable CSV table"),
    "bytes": ("trajectories", lambda p: p.write_bytes(b"\xff\xfe\x00\x01"), "trajectories.csv"),
    "column": (
        "discrepancies",
        lambda p: _edit(p, lambda d: d.drop(columns=["max_abs"])),
        "column 'max_abs' is missing",
    ),
    "text in numbers": (
        "trajectories",
        lambda p: _edit(
            p, lambda d: d.assign(value=d["value"].astype(object).where(d.index > 0, "oops"))
        ),  # fmt: skip
        "column 'value' must hold numbers, got 'oops'",
    ),
    "unknown case": (
        "trajectories",
        lambda p: _edit(p, lambda d: d.assign(case=d["case"].where(d.index > 0, "ghost"))),
        "case 'ghost' is not in cases.csv",
    ),
    "truncated": (
        "trajectories",
        lambda p: _edit(p, lambda d: d.iloc[:-1]),
        "the table is incomplete",
    ),
    "a quantity cut short": (
        "trajectories",
        lambda p: _edit(p, lambda d: d.iloc[:-3]),
        "output times differ between",
    ),
    "duplicate case": (
        "cases",
        lambda p: _edit(p, lambda d: pd.concat([d, d])),
        "is listed twice",
    ),
}


@pytest.mark.parametrize("kind", list(TABLE_DAMAGES))
def test_report_on_damaged_tables_names_the_file(finished, tmp_path, capsys, kind):
    """Issue: `rodval report` on damaged tables ended in KeyError/IndexError tracebacks or
    messages naming no file. Now exit 2, one line naming the file and what is wrong."""
    import shutil

    out = tmp_path / "out"
    shutil.copytree(finished, out)
    table, damage, words = TABLE_DAMAGES[kind]
    damage(out / f"{table}.csv")
    assert main(["report", str(out)]) == 2
    line = one_line(capsys)
    assert f"{table}.csv" in line and words in line, line


def test_success_with_non_finite_values_is_recorded_as_diverged(tmp_path):
    """A model that reports success with NaN values would make a record the reader refuses
    (recomputed forever, tables never written): the pipeline records it as diverged."""
    import math

    from rodval import paper_scene, simulate
    from rodval.core.status import STATUS_DIVERGED
    from rodval.study.pipeline import case_record

    spec = load_study(write_study(tmp_path, grid="scene.t_end = [0.1]"))
    case = spec.cases[0]
    runs = []
    for m in case.models:
        tr = simulate(paper_scene(2, t_end=0.1), "reduced")
        if m.label == "published":
            tr.values["phi"][-1, 0] = math.nan
        runs.append({"label": m.label, "setup_s": 0.0, "trajectory": tr.to_dict()})
    rec = case_record(case, runs)
    path = tmp_path / "case.json"
    path.write_text(rec.to_json())
    back = read_case(path, labels=["reduced", "published"])
    status = {r.label: r.trajectory.stats.status for r in back.runs}
    assert status == {"reduced": 0, "published": STATUS_DIVERGED}
