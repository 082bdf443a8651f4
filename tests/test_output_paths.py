"""Issue 36, data loss and late refusals: rodval writes only into folders it owns and only
files it may; every output path is checked before any work, each refusal one line naming the
flag. And a run that did not finish is never called "valid"."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from checks import one_line
from study_helpers import write_study

from rodval.cli import main

ONE_MODEL = "[models.reduced]\n"
QUICK = ["--no-progress", "--workers", "1", "--no-report"]


def snapshot(folder) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished one-case study folder and its study file."""
    tmp = tmp_path_factory.mktemp("finished")
    study = write_study(tmp, models=ONE_MODEL, grid="scene.t_end = [0.1]")
    out = tmp / "so"
    assert main(["study", str(study), "--out", str(out), *QUICK]) == 0
    return study, out


# ------------------------------------------------------------------------- study folders


@pytest.mark.parametrize("fresh", [[], ["--fresh"]])
def test_study_into_a_users_folder_is_refused_naming_its_files(tmp_path, capsys, fresh):
    """Issue: `rodval study FILE --out .` in a folder holding the user's own report.md,
    cases.csv and study.toml overwrote all three, exit 0. Refused before work, with or
    without --fresh, one line naming --out and the files; nothing changed."""
    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1]")
    mine = tmp_path / "mine"
    mine.mkdir()
    for name in ("report.md", "cases.csv", "study.toml"):
        (mine / name).write_text(f"my own {name}")
    before = snapshot(mine)
    assert main(["study", str(study), "--out", str(mine), *QUICK, *fresh]) == 2
    line = one_line(capsys)
    assert "--out" in line and "not a study folder" in line and "'cases.csv'" in line, line
    assert snapshot(mine) == before


def test_fresh_does_not_trust_a_foreign_study_json(tmp_path, capsys):
    """Issue: --fresh trusted any study.json: a folder with {"name": "my survey"} as
    study.json beside the user's report.md and cases.csv lost both. A study.json without
    rodval's schema and checksum marks no study folder: refused, nothing removed."""
    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1]")
    mine = tmp_path / "survey"
    mine.mkdir()
    (mine / "study.json").write_text(json.dumps({"name": "my survey"}))
    (mine / "report.md").write_text("# my survey")
    (mine / "cases.csv").write_text("case,answer\n1,yes\n")
    before = snapshot(mine)
    for extra in ([], ["--fresh"]):
        assert main(["study", str(study), "--out", str(mine), *QUICK, *extra]) == 2
        line = one_line(capsys)
        assert "--out" in line and "study.json" in line and "not written by rodval" in line
    assert snapshot(mine) == before


def test_an_edited_study_json_is_no_longer_rodvals(finished, tmp_path, capsys):
    """The checksum covers study.json's content: an edited one does not mark the folder."""
    import shutil

    study, done = finished
    out = tmp_path / "copy"
    shutil.copytree(done, out)
    meta = json.loads((out / "study.json").read_text())
    meta["name"] = "edited"
    (out / "study.json").write_text(json.dumps(meta))
    before = snapshot(out)
    assert main(["study", str(study), "--out", str(out), *QUICK, "--fresh"]) == 2
    assert "not written by rodval" in one_line(capsys)
    assert main(["report", str(out)]) == 2
    assert "not a study folder of rodval" in one_line(capsys)
    assert snapshot(out) == before


def test_a_study_folder_of_rodval_resumes_and_keeps_user_files(finished, tmp_path, capsys):
    """The stamped folder is rodval's: the same study resumes there (exit 0, its case
    reused) and a file the user added is kept."""
    import shutil

    study, done = finished
    out = tmp_path / "again"
    shutil.copytree(done, out)
    (out / "notes.txt").write_text("mine")
    assert main(["study", str(study), "--out", str(out), *QUICK]) == 0
    assert "0 cases run, 2 reused" in capsys.readouterr().out
    assert (out / "notes.txt").read_text() == "mine"


# ------------------------------------------------------------------------------ --junit


def test_junit_may_not_name_a_file_of_the_study_or_its_input(finished, capsys):
    """Issue: --junit so/study.json wrote XML over the study's description, --junit st.toml
    over the input study file, `rodval report so --junit so/cases.csv` over a table.
    Each is refused before work, one line naming --junit; nothing changed."""
    study, out = finished
    before, source = snapshot(out), study.read_bytes()
    argv = ["study", str(study), "--out", str(out), *QUICK]
    for target in (out / "study.json", out / "cases" / "x.json", study):
        assert main([*argv, "--junit", str(target)]) == 2
        line = one_line(capsys)
        assert line.startswith("rodval") and "--junit" in line, line
    assert main(["report", str(out), "--junit", str(out / "cases.csv")]) == 2
    assert "--junit" in one_line(capsys)
    assert snapshot(out) == before and study.read_bytes() == source


def test_unwritable_junit_paths_are_refused_before_any_case_runs(tmp_path, capsys):
    """Issue: --junit paths that cannot be written (a folder, under a file, empty, /proc/...)
    were found after every case had run, with a raw [Errno ...] not naming --junit. Refused
    before work: no output folder is made."""
    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1]")
    a_file = tmp_path / "plain.txt"
    a_file.write_text("x")
    out = tmp_path / "never"
    for target in (str(tmp_path), str(a_file / "j.xml"), "", "/proc/rodval-junit.xml"):
        assert main(["study", str(study), "--out", str(out), *QUICK, "--junit", target]) == 2
        line = one_line(capsys)
        assert "--junit" in line and "Errno" not in line, line
        assert not out.exists()


def test_junit_overwrites_its_own_report_but_no_other_file(finished, tmp_path, capsys):
    """A JUnit file rodval wrote may be written again; a user's file of that name is not."""
    _, out = finished
    junit = tmp_path / "junit.xml"
    assert main(["report", str(out), "--junit", str(junit)]) == 0
    assert main(["report", str(out), "--junit", str(junit)]) == 0
    capsys.readouterr()
    mine = tmp_path / "mine.xml"
    mine.write_text("<?xml version='1.0'?><notes/>")
    assert main(["report", str(out), "--junit", str(mine)]) == 2
    assert "not written by rodval" in one_line(capsys)
    assert mine.read_text() == "<?xml version='1.0'?><notes/>"


# ------------------------------------------------------------------ arguments, before work


def test_a_scheduler_without_the_dask_backend_is_refused(tmp_path, capsys):
    """Issue: --scheduler tcp://... with the processes backend was ignored."""
    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1]")
    out = tmp_path / "out"
    argv = ["study", str(study), "--out", str(out), *QUICK, "--scheduler", "tcp://h:8786"]
    assert main(argv) == 2
    line = one_line(capsys)
    assert "--scheduler" in line and "--backend dask" in line, line
    assert not out.exists()


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--coefficients", "published"], "coefficients must be 'printed'"),
        (["--set", "kernel=numpy"], "kernel must be 'numba'"),
    ],
)
def test_a_ladder_rung_with_paper_only_options_is_refused_before_work(
    tmp_path, capsys, extra, words
):
    """Issue: --set kinematics=exact with --coefficients published or --set kernel=numpy
    failed after set-up ("model set-up failed", run folder written). Refused before work."""
    out = tmp_path / "run"
    argv = ["simulate", "paper", "--model", "full", "--set", "kinematics=exact", *extra]
    assert main([*argv, "--t-end", "0.1", "--out", str(out)]) == 2
    assert words in one_line(capsys)
    assert not out.exists()


# ------------------------------------------------------------------------------ verdicts


def test_a_run_that_stopped_early_is_never_called_valid(tmp_path):
    """Issue: "evaluation budget exhausted ..., valid". A run that did not reach t_end has
    no verdict on the part it did not compute: the summary line says so and run.json's
    valid is null (runtime.csv's column is blank)."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "rodval", "simulate", "paper", "--model", "reduced"]
    cmd += ["--max-evaluations", "200", "--out", str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ})
    assert res.returncode == 1, res.stderr
    line = res.stdout.splitlines()[0]
    assert "evaluation budget exhausted" in line and ", valid," not in line, line
    assert "no verdict" in line, line
    stats = json.loads((out / "run.json").read_text())["stats"]
    assert stats["status"] != 0 and stats["valid"] is None
    assert stats["validity"] and all(c["holds"] for c in stats["validity"])
