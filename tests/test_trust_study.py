"""The trust issue's study items: single-model studies, --fresh on a user's folder, report
settings checked when the study file is read, the grid size limit, damaged tables."""

from __future__ import annotations

import pandas as pd
import pytest
from checks import one_line
from study_helpers import write_study

from rodval.cli import main

ONE_MODEL = "[models.reduced]\n"


@pytest.fixture(scope="module")
def single(tmp_path_factory):
    """A finished single-model study (two cases, one model, report written)."""
    tmp = tmp_path_factory.mktemp("single")
    study = write_study(tmp, models=ONE_MODEL, grid="scene.t_end = [0.1]")
    out = tmp / "out"
    code = main(["study", str(study), "--out", str(out), "--no-progress", "--workers", "1"])
    return code, out


# ------------------------------------------------------------------ 1. one model, no pairs


def test_single_model_study_finishes_with_tables_and_a_report(single):
    """Issue: every single-model study exited 2 after all its work (discrepancies.csv:
    column 'n' must hold numbers, got None). It exits 0, writes its tables and a report
    saying there is nothing to compare."""
    code, out = single
    assert code == 0
    runtime = pd.read_csv(out / "runtime.csv")
    assert sorted(runtime["case"]) == ["n=2,t_end=0.1", "n=3,t_end=0.1"]
    assert set(runtime["status"]) == {"success"}
    assert pd.read_csv(out / "discrepancies.csv").empty
    report = (out / "report.md").read_text()
    assert "nothing to compare" in report and "one model" in report


# --------------------------------------------------------- 2. --fresh removes only its own


def test_fresh_refuses_a_folder_that_is_not_a_study_folder(tmp_path, capsys):
    """Issue: `rodval study FILE --out DIR --fresh` emptied any folder (a user's thesis.tex was
    deleted). A folder with files but no study.json is refused, exit 2, one line naming --out;
    nothing in it is touched and nothing is added."""
    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1]")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("\\documentclass{article}")
    argv = ["study", str(study), "--out", str(mine), "--fresh", "--no-progress"]
    assert main(argv) == 2
    line = one_line(capsys)
    assert "--out" in line and "not a study folder" in line and "thesis.tex" in line, line
    assert sorted(p.name for p in mine.iterdir()) == ["thesis.tex"]
    assert (mine / "thesis.tex").read_text() == "\\documentclass{article}"


def test_fresh_on_a_study_folder_keeps_the_users_files(single, tmp_path):
    """--fresh on a study folder removes what the study wrote (records, tables, report,
    figures) and keeps the files a user put there, also inside cases/ and figures/."""
    import shutil

    _, finished = single
    out = tmp_path / "out"
    shutil.copytree(finished, out)
    own = [out / "notes.txt", out / "cases" / "README", out / "figures" / "sketch.png"]
    for path in own:
        path.write_text("mine")
    old_records = sorted(p.name for p in (out / "cases").glob("*.json"))
    assert len(old_records) == 2
    other = write_study(tmp_path, "other.toml", models=ONE_MODEL, grid="scene.t_end = [0.2]")
    other.write_text(other.read_text().replace('name = "tiny"', 'name = "other"'))
    argv = ["study", str(other), "--out", str(out), "--fresh", "--no-progress", "--no-report"]
    assert main(argv) == 0
    assert all(path.read_text() == "mine" for path in own)
    records = sorted(p.name for p in (out / "cases").glob("*.json"))
    assert records == ["n=2,t_end=0.2.json", "n=3,t_end=0.2.json"]
    assert not (out / "report.md").exists()  # the old study's report is gone
    assert sorted(p.name for p in (out / "figures").iterdir()) == ["sketch.png"]


# ------------------------------------------- 3. report settings checked when the file is read


@pytest.mark.parametrize(
    "report, words",
    [
        ("rods = [1, 99]", "key 'report.rods': rod 99 is beyond the chain of report case "
         "'n=2,t_end=0.1' (n = 2); allowed: 1..2 or \"last\""),
        ('quantities = ["phi", "x"]', "key 'report.quantities': must be a list of quantities "
         "every report case outputs (phi, dphi, alpha, beta), got ['phi', 'x']"),
        ("times = [0.05, 5.0]", "key 'report.times': must be a list of times in 0..0.1 s"),
    ],
)  # fmt: skip
def test_report_settings_are_refused_before_any_case_runs(tmp_path, capsys, report, words):
    """Issue: [report] rods beyond n, a quantity not among the outputs and times beyond t_end
    failed only after every case had run. They are refused when the study file is read: exit
    2, one line naming the key and what is allowed, no output folder."""
    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1, 0.2]")
    study.write_text(study.read_text() + f"\n[report]\n{report}\n")
    out = tmp_path / "out"
    assert main(["study", str(study), "--out", str(out), "--no-progress"]) == 2
    line = one_line(capsys)
    assert str(study) in line and words in line, line
    assert not out.exists()


def test_report_rods_and_times_are_checked_against_the_report_cases_only(tmp_path):
    """The rule: rods within the chain and times within the horizon of every report case
    (the cases the report draws); other cases of the grid do not restrict them."""
    from rodval.study import load_study

    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1, 0.2]")
    study.write_text(
        study.read_text()
        + '\n[report]\ncases = ["n=3,t_end=0.2"]\nrods = [3]\ntimes = [0.2]\n'
        + 'quantities = ["dphi"]\n'
    )
    rep = load_study(study).report
    assert (rep.rods, rep.times, rep.quantities) == ((3,), (0.2,), ("dphi",))


# ------------------------------------------------------------- 4. the grid's size, at once


def _no_cases(*args, **kwargs):
    raise AssertionError("the grid's cases were built")


def test_a_4_million_case_grid_is_refused_at_once(tmp_path, capsys, monkeypatch):
    """Issue: a grid of 4 million cases gave no answer for minutes (every case was built
    first). Its size is computed before it is expanded and refused before any case is built
    (a probe, not a clock), one line naming the size, the limit and how to raise it."""
    from rodval.study import load_study, spec
    from rodval.study.spec import MAX_CASES

    monkeypatch.setattr(spec, "_build_cases", _no_cases)

    t_end = ", ".join(f"{0.1 + i * 1e-4:.4f}" for i in range(2000))
    kappa = ", ".join(str(10 + i) for i in range(1000))
    grid = f"scene.t_end = [{t_end}]\nscene.chain.kappa = [{kappa}]"
    study = write_study(tmp_path, models=ONE_MODEL, grid=grid)
    with pytest.raises(ValueError) as info:
        load_study(study)
    assert f"key 'grid': 4000000 cases, more than the limit of {MAX_CASES}" in str(info.value)
    out = tmp_path / "out"
    assert main(["study", str(study), "--out", str(out)]) == 2
    line = one_line(capsys)
    assert "4000000 cases" in line and "--max-cases N" in line, line
    assert not out.exists()


def test_the_limit_can_be_raised_and_the_number_of_cases_is_announced(tmp_path, capsys):
    """--max-cases sets the limit (a 4-case grid over a limit of 3 is refused); within the
    limit the number of cases is printed before they are checked and run."""
    from rodval.study import load_study

    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1, 0.2]")
    with pytest.raises(ValueError, match="4 cases, more than the limit of 3"):
        load_study(study, max_cases=3)
    assert len(load_study(study, max_cases=4).cases) == 4
    with pytest.raises(ValueError, match="max_cases must be an integer >= 1, got 0"):
        load_study(study, max_cases=0)
    out = tmp_path / "out"
    assert main(["study", str(study), "--out", str(out), "--max-cases", "3"]) == 2
    assert "more than the limit of 3" in one_line(capsys)
    with pytest.raises(SystemExit) as exit_info:
        main(["study", str(study), "--out", str(out), "--max-cases", "0"])
    assert exit_info.value.code == 2
    assert "--max-cases must be an integer in [1, " in one_line(capsys)
    announced = []
    load_study(study, announce=announced.append)
    assert announced == [4]


def test_the_cli_announces_the_number_of_cases_on_stdout(tmp_path, capsys):
    """The announcement goes to stdout before the cases are checked (so a bad case is still
    one line on stderr), and not with --no-progress."""
    study = write_study(tmp_path, models=ONE_MODEL, grid="scene.t_end = [0.1, -1.0]")
    out = str(tmp_path / "out")
    assert main(["study", str(study), "--out", out]) == 2
    captured = capsys.readouterr()
    assert captured.out == f"{study}: 4 cases; checking them before any runs\n"
    assert len(captured.err.strip().splitlines()) == 1 and "t_end" in captured.err
    assert main(["study", str(study), "--out", out, "--no-progress"]) == 2
    assert capsys.readouterr().out == ""


# ---------------------------------------------------------- 5. damaged and truncated tables


@pytest.fixture(scope="module")
def paired(tmp_path_factory):
    """A finished two-model study (two cases; tables and report written)."""
    tmp = tmp_path_factory.mktemp("paired")
    study = write_study(tmp, grid="scene.t_end = [0.1]")
    out = tmp / "out"
    argv = ["study", str(study), "--out", str(out), "--no-progress", "--workers", "1"]
    assert main(argv) == 0
    return out


def _copy(finished, tmp_path):
    import shutil

    out = tmp_path / "out"
    shutil.copytree(finished, out)
    return out


def _cut_bytes(path, fraction: float) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])


def _cut_in_quotes(path) -> None:
    """Cut just inside the first quoted field (pandas then says 'EOF inside string'): where a
    byte cut lands depends on the table's bytes, which vary with the run's timings."""
    data = path.read_bytes()
    assert b'"' in data, "the table has no quoted field to cut inside"
    path.write_bytes(data[: data.index(b'"') + 2])


def _cut_rows(path, fraction: float) -> None:
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[: max(2, int(len(lines) * fraction))]))


def _nan_max_abs(path, quantity: str = "phi") -> None:
    df = pd.read_csv(path)
    df.loc[df["quantity"] == quantity, "max_abs"] = float("nan")
    df.to_csv(path, index=False)


@pytest.mark.parametrize(
    "table, damage, words",
    [
        ("discrepancies", lambda p: _cut_bytes(p, 0.3), "the file is truncated or was edited"),
        ("discrepancies", lambda p: _cut_rows(p, 0.5), "the file is truncated or was edited"),
        ("runtime", lambda p: _cut_bytes(p, 0.3), "the file is truncated or was edited"),
        ("runtime", lambda p: _cut_rows(p, 0.7), "the file is truncated or was edited"),
        ("runtime", _cut_in_quotes, "the file is truncated or was edited"),
        ("discrepancies", _nan_max_abs, "max_abs is NaN although status is 'ok'"),
    ],
    ids=[
        "cut to 30 % of its bytes",
        "cut at a row",
        "runtime cut",
        "runtime cut at a row",
        "runtime cut inside a quoted field",
        "NaN max_abs",
    ],
)
def test_damaged_tables_are_refused_in_one_line(paired, tmp_path, capsys, table, damage, words):
    """Issue: `rodval report` accepted a discrepancies.csv cut to 30 % of its bytes; a NaN in
    max_abs gave `internal error: KeyError`. Exit 2, one line naming the file and what is
    wrong."""
    out = _copy(paired, tmp_path)
    damage(out / f"{table}.csv")
    assert main(["report", str(out)]) == 2
    line = one_line(capsys)
    assert f"{out / table}.csv" in line and words in line, line


def test_tables_without_their_manifest_are_refused(paired, tmp_path, capsys):
    """Tables that cannot be checked against what the study wrote (no tables.json) are
    refused with the way to rewrite them."""
    out = _copy(paired, tmp_path)
    (out / "tables.json").unlink()
    assert main(["report", str(out)]) == 2
    line = one_line(capsys)
    assert "tables.json is missing" in line and "rodval study FILE --out" in line, line
