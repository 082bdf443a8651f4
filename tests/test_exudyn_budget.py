"""Issue 36, "Unbounded": the exudyn model honours the wall-clock budget (max_wall_s, CLI
--max-wall) and keeps what it computed; a run without one is refused before any work when
its step count (t_end / step) or the memory of its recorded steps is beyond a stated limit,
and a budgeted run stops at the memory bound."""

from __future__ import annotations

import json
import math
import re
import time

import numpy as np
import pytest

from rodval import Chain, Scene, paper_scene, simulate
from rodval.cli import main
from rodval.core.resources import ENV_LIMIT
from rodval.core.settings import IntegratorSettings
from rodval.core.status import STATUS_FAILED, STATUS_WALL
from rodval.report.run_files import read_run

exu = pytest.importorskip("exudyn")
from reference_models.exudyn_chain import ExudynModel  # noqa: E402

pytestmark = pytest.mark.exudyn


def _no_build(*args, **kwargs):
    raise AssertionError("the model was built")


def _finite_up_to(tr, t_reached: float) -> None:
    """Every output of ``tr`` is finite, at output times up to ``t_reached`` (s)."""
    assert tr.times.size >= 1
    assert tr.times[-1] <= t_reached + 1e-12
    for q, v in tr.values.items():
        assert v.shape[0] == tr.times.size, q
        assert np.isfinite(v).all(), q


def test_a_wall_budget_stops_the_run_and_keeps_what_it_reached():
    """2 s of the paper chain take ~10,000 steps (3 s or more here): a 0.5 s budget stops the
    run part way, with the wall-clock status, the one budget message and the outputs up to
    the time reached."""
    # the clock counts the set-up: compile the load's kernels (numba, after a change of
    # rodval's sources) outside it
    simulate(paper_scene(8, t_end=0.002), "exudyn")
    settings = IntegratorSettings(max_wall_s=0.5)
    start = time.perf_counter()
    tr = simulate(paper_scene(8, t_end=2.0), "exudyn", settings=settings)
    assert time.perf_counter() - start < 10.0  # 0.5 s budget + observation of what it reached
    s = tr.stats
    assert s.status == STATUS_WALL, s.message
    assert 0.0 < s.t_reached < 2.0
    assert s.message == settings.budget_message("max_wall_s", s.t_reached)
    assert tr.settings["max_wall_s"] == 0.5
    assert 0 < tr.settings["steps"] < tr.settings["steps_planned"] == 10_000
    _finite_up_to(tr, s.t_reached)
    assert tr.times.size > 1  # the run got past t = 0


def test_a_tiny_wall_budget_is_spent_in_the_set_up():
    """The clock starts with the run (the build counts): 1e-9 s is used up before the first
    step, which exudyn still completes, so the run ends at t = one step."""
    tr = simulate(paper_scene(2, t_end=1.0), "exudyn", max_wall_s=1e-9)
    s = tr.stats
    assert s.status == STATUS_WALL, s.message
    assert s.message == "wall-clock budget exhausted: max_wall_s = 1e-09 s used (t = 0.0002 s)"
    assert s.t_reached == pytest.approx(ExudynModel().first_step(paper_scene(2, t_end=1.0)))
    assert tr.settings["steps"] == 1
    _finite_up_to(tr, s.t_reached)


def test_too_many_steps_without_a_wall_budget_are_refused(monkeypatch):
    """t_end / step = 5e9 steps without max_wall_s: one-line ValueError before any work,
    naming step, t_end, the limit and how to bound the run."""
    monkeypatch.setattr(ExudynModel, "_build", _no_build)
    scene = Scene(chain=Chain.uniform(1), t_end=1e6, times=[0.0, 1.0])
    with pytest.raises(ValueError) as info:
        simulate(scene, "exudyn")
    msg = str(info.value)
    assert "\n" not in msg
    for part in ("t_end / step", "5e+09 steps", "1e+07", "max_wall_s", "--max-wall", "step"):
        assert part in msg, (part, msg)
    # 1e6 steps are under the limit: the run goes on to its build (the first work)
    tr = ExudynModel(step=0.1).run(scene.with_(t_end=1e5), IntegratorSettings())
    assert "the model was built" in tr.stats.message


def test_the_memory_of_the_recorded_steps_is_checked(monkeypatch):
    """exudyn records every step; without a wall budget a run whose records exceed the memory
    limit is refused before any work, with one; a budgeted run stops at the memory bound
    (STATUS_FAILED, the bound in the message) keeping the outputs it reached."""
    scene = paper_scene(2, t_end=0.5)  # 2500 steps
    monkeypatch.setenv(ENV_LIMIT, "0.001")  # 1 MB: a few hundred of its steps
    with monkeypatch.context() as m:
        m.setattr(ExudynModel, "_build", _no_build)
        with pytest.raises(ValueError, match=f"2500 steps.*{ENV_LIMIT}") as info:
            ExudynModel().simulate(scene)
        assert "\n" not in str(info.value)
    tr = ExudynModel().simulate(scene, IntegratorSettings(max_wall_s=60.0))
    s = tr.stats
    assert s.status == STATUS_FAILED, s.message
    assert "memory bound" in s.message and ENV_LIMIT in s.message
    assert 0.0 < s.t_reached < 0.5
    assert tr.settings["steps"] < 2500
    _finite_up_to(tr, s.t_reached)


def test_cli_paper_over_1e6_s_ends_at_its_wall_budget(tmp_path, capsys):
    """The issue's command: 5e9 planned steps, bounded by --max-wall 5. In-process (no import
    or numba start-up): the 5 s budget (set-up included), the observation of the steps
    reached and the writing take ~6 s; 30 s leaves room for a shared, loaded 2-core machine
    while still failing a run that ignores its budget (it would go on for days)."""
    out = tmp_path / "x"
    start = time.perf_counter()
    code = main(
        ["simulate", "paper", "--model", "exudyn", "--t-end", "1e6", "--max-wall", "5"]
        + ["--out", str(out)]
    )
    elapsed = time.perf_counter() - start
    text = capsys.readouterr().out
    assert elapsed < 30.0, elapsed
    assert code == 1, text
    # the command's own budget may leave the run less than 5 s for its reading and writing
    assert re.search(r"wall-clock budget exhausted: max_wall_s = [0-9.]+ s used", text), text
    rec = json.loads((out / "run.json").read_text())
    assert rec["stats"]["status"] == STATUS_WALL
    tr = read_run(out)
    t_reached = tr.stats.t_reached
    assert 0.0 < t_reached < 1e6 and math.isfinite(t_reached)
    _finite_up_to(tr, t_reached)


def test_cli_refuses_the_unbounded_run_at_once(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(ExudynModel, "_build", _no_build)
    code = main(  # refused before the model is built (_no_build), not timed
        ["simulate", "paper", "--model", "exudyn", "--t-end", "1e6", "--out", str(tmp_path / "y")]
    )
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1, err
    assert "--max-wall" in lines[0] and "5e+09 steps" in lines[0]
    assert not (tmp_path / "y").exists()
