"""The validity verdict: every run says whether it kept its model's assumptions (small bending,
energy balance, step resolution), with figures, in the API, the CLI's summary line, run.json,
runtime.csv and the study report's headline; success and validity are separate."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from study_helpers import write_study

from rodval import Chain, Scene, paper_scene, simulate
from rodval.cli import main
from rodval.core.validity import (
    ENERGY_RESIDUAL_BOUND,
    SMALL_BENDING_RAD,
    Check,
    describe,
    verdict,
)
from rodval.study import load_study, run_study

#: Rods so soft (EI = 1e-3 N m^2, the trust review's case) that the paper load bends them by
#: hundreds of radians: the run reaches t_end, its results mean nothing.
ABSURD = """
based_on = "paper"
name = "absurd"
n = 3
t_end = 0.5
outputs = ["phi", "energy"]
[chain]
EI = 1e-3
"""


def _absurd() -> Scene:
    chain = Chain.uniform(3, EI=1e-3)
    return paper_scene(3).with_(chain=chain, t_end=0.5, times=None, outputs=("phi", "energy"))


def test_check_and_verdict():
    """A check holds when its finite figure is at most its bound; a non-finite figure breaks
    it; no checks: not judged (None)."""
    ok = Check("small bending", 0.1, SMALL_BENDING_RAD, "rad", "largest bending angle")
    bad = Check("energy balance", math.inf, ENERGY_RESIDUAL_BOUND, "", "energy-audit residual")
    assert ok.holds and not bad.holds
    assert verdict([]) == (None, [])
    valid, validity = verdict([ok, bad])
    assert valid is False
    assert [c["holds"] for c in validity] == [True, False]
    assert validity[1]["figure"] is None  # JSON-safe
    assert describe(valid, validity) == "INVALID: " + bad.reason()
    assert describe(True, validity[:1]) == "valid"


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_absurdly_soft_rods_reach_t_end_but_are_invalid(model):
    """EI = 1e-3: success (the integration is fine) but invalid, both reasons with figures:
    largest bending angle >> 0.2 rad and an energy-audit residual >> 1e-2."""
    traj = simulate(_absurd(), model)
    st = traj.stats
    assert st.success, st.message
    assert st.valid is False
    broken = {c["assumption"]: c for c in st.validity if not c["holds"]}
    assert set(broken) == {"small bending", "energy balance"}, st.validity
    assert broken["small bending"]["figure"] > 10 * SMALL_BENDING_RAD
    assert broken["energy balance"]["figure"] > 10 * ENERGY_RESIDUAL_BOUND


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_paper_example_is_valid(model):
    """The paper example keeps both assumptions: bending <= 0.2 rad (measured ~4e-3) and,
    with energy, a residual <= 1e-2 (measured 5e-5 .. 2e-3, docs/stability.md)."""
    traj = simulate(paper_scene().with_(outputs=("phi", "alpha", "beta", "energy")), model)
    assert traj.stats.success and traj.stats.valid is True, traj.stats.validity
    assert {c["assumption"] for c in traj.stats.validity} == {"small bending", "energy balance"}


@pytest.mark.exudyn
def test_exudyn_run_reports_step_resolution():
    """exudyn (geometrically exact: no small-bending check) states its step resolution: the
    largest rod rotation per step against max_rotation_per_step."""
    pytest.importorskip("exudyn")
    traj = simulate(paper_scene(2).with_(t_end=0.2, times=None), "exudyn")
    checks = {c["assumption"]: c for c in traj.stats.validity}
    assert set(checks) == {"step resolution"}
    assert traj.stats.valid is True
    assert 0 < checks["step resolution"]["figure"] <= checks["step resolution"]["bound"]


def test_cli_summary_and_run_json_say_invalid(tmp_path, capsys):
    """The CLI's summary line names the broken assumptions; run.json carries stats.valid and
    stats.validity; a run rebuilt from it keeps them."""
    scene = tmp_path / "absurd.toml"
    scene.write_text(ABSURD)
    out = tmp_path / "run"
    code = main(["simulate", str(scene), "--model", "reduced", "--out", str(out)])
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert code == 0
    assert "reached t_end, INVALID: " in line
    assert "(small bending)" in line and "(energy balance)" in line
    stats = json.loads((out / "run.json").read_text())["stats"]
    assert stats["valid"] is False and stats["success"] is True
    assert any(not c["holds"] for c in stats["validity"])


def test_study_runtime_table_and_report_count_invalid_runs(tmp_path):
    """A study over EI (1e5: valid, 1e-3: invalid over 0.5 s; over 0.1 s the full model's
    bending has not yet grown, its period being ~1400 s): runtime.csv has `valid` and
    `invalid_because` beside `status`; the report's headline counts the invalid runs and lists
    them with their reasons."""
    path = write_study(
        tmp_path,
        models='[models.reduced]\n[models.full]\nmodel = "full"',
        grid="scene.chain.EI = [1e5, 1e-3]\nscene.t_end = [0.5]",
    )
    out = tmp_path / "out"
    run_study(load_study(path), out)
    runtime = pd.read_csv(out / "runtime.csv")
    assert (runtime["status"] == "success").all()
    soft = runtime[np.isclose(runtime["EI"], 1e-3)] if "EI" in runtime else None
    assert soft is not None and len(soft) == 4  # 2 n x 2 models
    assert (soft["valid"].astype(str) == "False").all()
    assert soft["invalid_because"].str.contains("small bending").all()
    stiff = runtime[np.isclose(runtime["EI"], 1e5)]
    assert (stiff["valid"].astype(str) == "True").all()
    report = (out / "report.md").read_text()
    assert f"{len(runtime)} model runs, 0 failed, 4 invalid;" in report
