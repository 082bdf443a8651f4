"""Issue 47, "Valid defaults": exudyn's ``step = "auto"`` (its default) resolves every lock
window it meets (>= MIN_WINDOW_STEPS = 20 steps) and keeps its energy residual within bound,
by fixed-step attempts (``reference_models.exudyn_step``), recording each attempt and why the
final step was chosen; a float step runs as before; a bad step is refused before any work.

The refinement's logic is checked on stand-in runs (no exudyn: windows of w / h steps, energy
residuals that fall with the step or do not), its wiring on exudyn runs of two rods over
0.42 s (the lock at 0.404 s; well under a second each)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scenes

from reference_models import exudyn_step
from reference_models.exudyn_budget import record_bytes, refinement_refusal
from reference_models.exudyn_chain import ExudynModel
from reference_models.exudyn_step import (
    AUTO,
    ELEMENTS_FIX,
    MAX_REFINEMENTS,
    STEP_CAP_S,
    a_priori_step,
    run_auto,
)
from rodval.cli import main
from rodval.core.resources import ENV_LIMIT
from rodval.core.scene import Chain, InitialState, Latch, Scene
from rodval.core.status import STATUS_BLOWUP, STATUS_SUCCESS
from rodval.core.trajectory import SolverStats, Trajectory
from rodval.mechanics.lock_window import MIN_WINDOW_STEPS, lock_window
from rodval.study.spec import load_study

BAD_STEP = r'^step must be "auto" or a number in \(0, 0\.1\] s, got '


SCENE_TOML = """
n = 2
t_end = 0.42
times = { num = 43 }
outputs = ["phi", "dphi"]

[chain]
l = 1.5
m = 3.0
EI = 1e7
mu = 0.5
kappa = [0.0, 50.0]
nu = 0.0

[initial]
phi = [0.0, 3.0915926535897933]
dphi = [1.0, 1.0]

[[latches]]
hinge = 1
angle = 0.0
"""


# -- the option: accepted and refused values (no exudyn needed) -------------------------------


@pytest.mark.parametrize(
    "value", ["fast", "AUTO", "", 0.0, -1e-3, 0.2, math.nan, math.inf, True, None, [1e-4]]
)
def test_a_bad_step_is_refused_naming_step_and_the_allowed_values(value):
    with pytest.raises(ValueError, match=BAD_STEP) as info:
        ExudynModel(step=value)
    assert "\n" not in str(info.value)
    with pytest.raises(ValueError, match=BAD_STEP):
        ExudynModel.check_options({"step": value})


def test_auto_is_the_default_and_a_float_is_kept():
    assert ExudynModel().options()["step"] == AUTO
    assert ExudynModel(step=AUTO).step == AUTO
    assert ExudynModel(step=1e-4).options()["step"] == 1e-4
    numpy_step = ExudynModel(step=np.float32(1e-3)).step
    assert type(numpy_step) is float and numpy_step == pytest.approx(1e-3)


def test_the_command_line_refuses_a_bad_step_in_one_line_before_any_work(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["simulate", "paper", "--model", "exudyn", "--set", "step=fast", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "Traceback" not in err[0]
    for word in ("step", '"auto"', "(0, 0.1] s", "'fast'"):
        assert word in err[0], (word, err[0])
    assert not (out / "run.json").exists()


def test_a_study_file_takes_auto_and_refuses_a_bad_step(tmp_path):
    from study_helpers import write_study

    good = write_study(
        tmp_path, "good.toml", reference="exudyn", models='[models.exudyn]\nstep = "auto"\n'
    )
    assert load_study(good).models[-1].options == {"step": AUTO}
    bad = write_study(
        tmp_path, "bad.toml", reference="exudyn", models='[models.exudyn]\nstep = "fast"\n'
    )
    with pytest.raises(ValueError) as info:
        load_study(bad)
    msg = str(info.value)
    assert "\n" not in msg and "step" in msg and '"auto"' in msg and "(0, 0.1]" in msg


# -- the a-priori step ------------------------------------------------------------------------


def test_the_a_priori_step_resolves_the_shortest_lock_window():
    """The pair's window over 20 steps, rounded down to two digits, when below the cap; the
    cap (2e-4 s) otherwise; a latch held from the start opens no window."""
    scene = scenes.two_rod_latch(1e7)
    w = lock_window(scene.chain, scene.latches[0])
    assert w == pytest.approx(2.28e-3, rel=1e-3)
    step, why = a_priori_step(scene)
    assert step == pytest.approx(1.1e-4, rel=1e-12)
    assert w / step >= MIN_WINDOW_STEPS and "lock window" in why
    assert w / STEP_CAP_S < MIN_WINDOW_STEPS  # the former fixed default does not resolve it
    assert a_priori_step(scenes.two_rod_latch(1e3))[0] == STEP_CAP_S
    # a window of exactly 20 cap steps: strictly below, so no run holds 19.999... steps
    assert a_priori_step(scenes.two_rod_latch(1e3, window=20 * STEP_CAP_S))[0] == pytest.approx(
        1.9e-4
    )
    free = Scene(chain=Chain.uniform(2), t_end=0.1, times=[0.0, 0.1])
    assert a_priori_step(free) == (STEP_CAP_S, f"the cap {STEP_CAP_S:g} s (no lock windows)")
    held = scenes.two_rod_latch(1e7).with_(
        initial=InitialState(phi=[0.0, 0.0]), latches=(Latch(1, 0.0, held=True),)
    )
    assert a_priori_step(held)[0] == STEP_CAP_S


# -- the refinement's logic on stand-in runs (no exudyn) ----------------------------------------


def _stand_in(window: float | None, residual, status: int = STATUS_SUCCESS):
    """run_at(step) of a run whose lock window (s) holds window / step steps and whose energy
    residual is ``residual(step)`` (None: not audited); the steps it was called with."""
    calls: list[float] = []

    def run_at(step: float) -> Trajectory:
        calls.append(step)
        events = [] if window is None else [{"t": 0.1, "window_steps": window / step}]
        stats = SolverStats(
            status=status, message="m", t_reached=1.0, energy_residual=residual(step)
        )
        settings = {"step": step, "step_used": step, "max_rotation_per_step_seen": 1e-3}
        return Trajectory("exudyn", "s", np.zeros(1), {}, {}, stats, settings, {}, events)

    return run_at, calls


def _never(step: float, predicted: float) -> None:
    return None


BOUNDS = (1e-2, 0.1)


def test_a_coarse_step_is_refined_as_far_as_the_window_needs_at_once(monkeypatch):
    """A window of 4.5 steps at 1e-3 s needs 20 / 4.5 = 4.4x: three halvings at once."""
    monkeypatch.setattr(exudyn_step, "a_priori_step", lambda scene: (1e-3, "coarse"))
    run_at, calls = _stand_in(4.5e-3, lambda h: None)
    tr, auto = run_auto(scenes.two_rod_latch(), run_at, _never, BOUNDS)
    assert calls == [1e-3, 1.25e-4]
    assert auto.met and tr.settings["step"] == 1.25e-4
    assert [a.window_steps_min for a in auto.attempts] == pytest.approx([4.5, 36.0])
    assert auto.attempts[0].needs == ["a lock window holds 4.5 steps (< 20)"]
    assert "every lock window holds >= 20 steps (fewest 36)" in auto.note()


def test_an_energy_residual_falling_with_the_step_is_halved_until_within_bound():
    """r = 100 h: 0.02 at 2e-4 s, 0.01 (the bound, which holds) at 1e-4 s."""
    run_at, calls = _stand_in(1.0, lambda h: 100 * h)
    tr, auto = run_auto(scenes.two_rod_latch(1e3), run_at, _never, BOUNDS)
    assert calls == [2e-4, 1e-4]
    assert auto.met and auto.record()["chosen"] == 1e-4
    assert auto.record()["attempts"][0]["needs"] == ["the energy residual 0.02 > 0.01"]
    assert "the energy residual is 0.01 (within bound)" in auto.note()


def test_a_residual_that_does_not_fall_with_the_step_stops_and_names_more_elements():
    """exudyn at 2 elements on studies/deployment.toml: 0.231 at 2e-4 s, 0.233 at 1e-4 s."""
    residuals = {2e-4: 0.231, 1e-4: 0.233}
    run_at, calls = _stand_in(1.0, residuals.__getitem__)
    tr, auto = run_auto(scenes.two_rod_latch(1e3), run_at, _never, BOUNDS)
    assert calls == [2e-4, 1e-4]
    assert not auto.met and auto.energy_fix == ELEMENTS_FIX
    note = auto.note()
    assert "no step within its limits met its checks" in note
    assert "does not fall with the step (0.231 at 0.0002 s, 0.233 at 0.0001 s)" in note


def test_no_step_within_the_limits_is_said_never_silently():
    """r = 1e3 h falls with the step but needs 1e-5 s, below the a-priori step / 16."""
    run_at, calls = _stand_in(1.0, lambda h: 1e3 * h)
    tr, auto = run_auto(scenes.two_rod_latch(1e3), run_at, _never, BOUNDS)
    assert calls == [2e-4 / 2**i for i in range(MAX_REFINEMENTS + 1)]
    assert not auto.met and auto.record()["met"] is False
    assert tr.settings["step"] == 2e-4 / 2**MAX_REFINEMENTS  # the last attempt is the run
    assert "no step within its limits met its checks" in auto.note()
    assert "below the smallest" in auto.note() and "give step explicitly" in auto.note()


def test_a_run_that_ends_for_another_reason_is_not_refined():
    run_at, calls = _stand_in(1.0, lambda h: 0.5, status=STATUS_BLOWUP)
    tr, auto = run_auto(scenes.two_rod_latch(1e3), run_at, _never, BOUNDS)
    assert calls == [2e-4] and not auto.met
    assert "its run ended before t_end: m (a smaller step is not tried)" in auto.note()


def test_a_refinement_that_would_not_fit_the_budgets_is_not_run():
    run_at, calls = _stand_in(1.0, lambda h: 100 * h)
    tr, auto = run_auto(
        scenes.two_rod_latch(1e3), run_at, lambda step, predicted: f"no room for {step:g}", BOUNDS
    )
    assert calls == [2e-4] and not auto.met
    assert "the attempt at 0.0001 s was not run: no room for 0.0001" in auto.note()


def test_refinement_refusal_names_the_budget(monkeypatch):
    """Memory (always), the steps of a run without a wall budget, the wall budget left."""
    assert refinement_refusal(1.0, 1e-4, 90, 10.0, 5.0, 4.0) is None
    wall = refinement_refusal(1.0, 1e-4, 90, 10.0, 5.0, 6.0)
    assert wall is not None and "max_wall_s 10 s" in wall and "leaves 5 s" in wall
    steps = refinement_refusal(2e3, 1e-4, 1, math.inf, math.inf, 0.0)  # 0.64 GB recorded
    assert steps is not None and "2e+07 steps" in steps and "max_wall_s" in steps
    monkeypatch.setenv(ENV_LIMIT, str(1000 * record_bytes(90) / 1e9))  # 1000 steps
    memory = refinement_refusal(1.0, 5e-4, 90, 10.0, 5.0, 0.0)  # 2000 steps
    assert memory is not None and "memory" in memory and ENV_LIMIT in memory


def test_the_verdict_names_more_elements_when_the_step_does_not_close_the_balance():
    stats = SolverStats(energy_residual=0.23)
    settings = {
        "step_auto": {"energy_fix": ELEMENTS_FIX},
        "max_rotation_per_step_seen": 1e-3,
        "step_used": 1e-4,
    }
    tr = Trajectory("exudyn", "s", np.zeros(1), {}, {}, stats, settings)
    checks = ExudynModel().validity_checks(scenes.two_rod_latch(), tr)
    energy = next(c for c in checks if c.assumption == "energy balance")
    assert energy.fix == ELEMENTS_FIX and not energy.holds
    tr.settings.pop("step_auto")
    energy = next(
        c for c in ExudynModel().validity_checks(scenes.two_rod_latch(), tr) if c.figure == 0.23
    )
    assert "smaller step" in energy.fix


# -- exudyn runs -------------------------------------------------------------------------------


@pytest.fixture
def exudyn():
    return pytest.importorskip("exudyn")


@pytest.mark.exudyn
def test_auto_resolves_every_lock_window_where_the_former_default_did_not(exudyn):
    """The former fixed default (2e-4 s) leaves the 2.28 ms window 11.4 steps; "auto" runs the
    a-priori 1.1e-4 s in one attempt, every window >= 20 steps, and says why."""
    scene = scenes.two_rod_latch(1e7)
    fixed = ExudynModel(step=2e-4).simulate(scene)
    assert fixed.success, fixed.stats.message
    assert [ev["window_steps"] for ev in fixed.events] == pytest.approx([11.4], rel=1e-3)
    tr = ExudynModel().simulate(scene)
    assert tr.success, tr.stats.message
    assert tr.events and all(ev["window_steps"] >= MIN_WINDOW_STEPS for ev in tr.events)
    auto = tr.settings["step_auto"]
    assert [a["step"] for a in auto["attempts"]] == [1.1e-4] and auto["met"]
    assert tr.settings["step"] == 1.1e-4 and tr.options["step"] == AUTO
    assert tr.stats.notes[0].startswith('step = "auto" ran 0.00011 s')


@pytest.mark.exudyn
def test_auto_refines_a_coarse_step_and_its_run_is_the_fixed_step_run(exudyn, monkeypatch):
    """From a coarse 4e-4 s (5.7 steps a window) two halvings at once to 1e-4 s (22.8 steps);
    the run kept is exactly the fixed-step run at 1e-4 s, its counters the attempts' sum."""
    monkeypatch.setattr(exudyn_step, "a_priori_step", lambda scene: (4e-4, "coarse (test)"))
    scene = scenes.two_rod_latch(1e7)
    tr = ExudynModel().simulate(scene)
    assert tr.success, tr.stats.message
    attempts = tr.settings["step_auto"]["attempts"]
    assert [a["step"] for a in attempts] == [4e-4, 1e-4]
    assert attempts[0]["window_steps_min"] < MIN_WINDOW_STEPS <= attempts[1]["window_steps_min"]
    assert all(ev["window_steps"] >= MIN_WINDOW_STEPS for ev in tr.events)
    fixed = ExudynModel(step=1e-4).simulate(scene)
    assert np.array_equal(tr.times, fixed.times)
    for q in ("phi", "dphi"):
        assert np.array_equal(tr[q], fixed[q]), q
    assert tr.events == fixed.events
    assert tr.stats.nsteps == fixed.stats.nsteps + int(round(0.42 / 4e-4))


@pytest.mark.exudyn
def test_a_float_step_records_what_it_did_before(exudyn):
    """A float step is one fixed-step run: its settings hold the keys they held before
    "auto" (no attempts, no requested step) and its notes nothing of "auto"."""
    tr = ExudynModel(step=2e-4).simulate(scenes.two_rod_latch(1e3))
    assert tr.success, tr.stats.message
    assert "step_auto" not in tr.settings and "requested_step" not in tr.settings
    assert tr.settings["step"] == 2e-4 and tr.options["step"] == 2e-4
    assert tr.stats.nsteps == int(round(0.42 / 2e-4))
    assert not any("auto" in n for n in tr.stats.notes)


@pytest.mark.exudyn
def test_run_json_records_step_auto_and_every_attempt(exudyn, monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(exudyn_step, "a_priori_step", lambda scene: (4e-4, "coarse (test)"))
    scene = tmp_path / "pair.toml"
    scene.write_text(SCENE_TOML)
    out = tmp_path / "run"
    argv = ["simulate", str(scene), "--model", "exudyn", "--set", "step=auto", "--out", str(out)]
    code = main(argv)
    text = capsys.readouterr().out
    assert code == 0, text
    assert 'step = "auto" ran 0.0001 s (attempts at 0.0004, 0.0001 s' in text
    rec = json.loads((out / "run.json").read_text())
    assert rec["options"]["step"] == AUTO
    settings = rec["settings"]
    assert settings["requested_step"] == AUTO and settings["step"] == 1e-4
    auto = settings["step_auto"]
    assert auto["a_priori"] == 4e-4 and auto["a_priori_why"] == "coarse (test)"
    assert auto["chosen"] == 1e-4 and auto["met"] is True
    assert [a["step"] for a in auto["attempts"]] == [4e-4, 1e-4]
    for a in auto["attempts"]:
        assert set(a) >= {"step", "window_steps_min", "energy_residual", "status", "wall_s"}
    assert rec["stats"]["notes"][0] == auto["note"]


@pytest.mark.exudyn
def test_a_refinement_beyond_the_memory_limit_is_refused_and_said(exudyn, monkeypatch):
    """1050 recorded steps at 4e-4 s fit a limit of 1736 steps; the 4200 of 1e-4 s do not:
    the coarse run is kept and its note says why no finer one ran."""
    monkeypatch.setattr(exudyn_step, "a_priori_step", lambda scene: (4e-4, "coarse (test)"))
    monkeypatch.setenv(ENV_LIMIT, "0.005")
    tr = ExudynModel().simulate(scenes.two_rod_latch(1e7))
    assert tr.success, tr.stats.message
    auto = tr.settings["step_auto"]
    assert [a["step"] for a in auto["attempts"]] == [4e-4] and not auto["met"]
    assert "the attempt at 0.0001 s was not run" in tr.stats.notes[0]
    assert "memory" in tr.stats.notes[0] and ENV_LIMIT in tr.stats.notes[0]
