"""The shipped studies run to completion on the 2-core machine (slow: `pytest -m slow`)."""

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from rodval.study import load_study

pytestmark = pytest.mark.slow


def run_study(name: str, out, *extra: str) -> None:
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "rodval",
            "study",
            f"studies/{name}.toml",
            "--out",
            str(out),
            *extra,
        ],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 0, res.stderr[-2000:]


def test_n_sweep_has_one_row_per_case_model_and_quantity_without_nan(tmp_path):
    run_study("n_sweep", tmp_path)
    spec = load_study("studies/n_sweep.toml")
    runtime = pd.read_csv(tmp_path / "runtime.csv")
    disc = pd.read_csv(tmp_path / "discrepancies.csv")
    assert len(runtime) == len(spec.cases) * len(spec.models)
    assert not runtime.duplicated(["case", "model"]).any()
    others = len(spec.models) - 1
    assert len(disc) == len(spec.cases) * others * 4
    ok = runtime[runtime.status == "success"][["case", "model"]]
    rows = disc.merge(ok, on=["case", "model"])
    assert len(rows) > 0 and rows[["max_abs", "rms", "final_abs"]].notna().all().all()


def test_stability_study_has_a_status_and_an_energy_residual_for_every_case(tmp_path):
    run_study("stability", tmp_path, "--case-timeout", "900")
    spec = load_study("studies/stability.toml")
    runtime = pd.read_csv(tmp_path / "runtime.csv")
    assert len(runtime) == len(spec.cases) * len(spec.models)
    assert runtime["status"].notna().all()
    done = runtime[runtime.status == "success"]
    assert np.isfinite(done["energy_residual"]).all()
    per_case = done.groupby("case")["energy_residual"].count()
    assert set(per_case.index) == {c.id for c in spec.cases}
    assert "## Stability map" in (tmp_path / "report.md").read_text()
