"""The trust issue's study items: single-model studies, --fresh on a user's folder, report
settings checked when the study file is read, the grid size limit, damaged tables."""

from __future__ import annotations

import pandas as pd
import pytest
from study_helpers import write_study

from rodval.cli import main

ONE_MODEL = "[models.reduced]\n"


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err, err
    return lines[0]


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
