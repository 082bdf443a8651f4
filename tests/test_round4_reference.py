"""rodval reference, issue 54: a level that failed or that the model itself judges INVALID never
yields an error bar; the error bar compares the finest level with the levels before it that
finished, are valid and lock alike, and says which; each level is written as it finishes and a
rerun of the same request resumes from them; --max-wall is the whole command's budget; a
run.json is read as SCENE the way ``rodval simulate`` reads it.

The scenes are the two-rod latched chain of tests/test_reference_converge.py (0.1 s, one lock
at 0.0275 s): at E0 = 1, H0 = 4e-4 s its level 0 is INVALID by its own energy audit (residual
0.0129 > 0.01) and levels 1 and 2 are valid; at H0 = 0.05 s level 0 fails at t = 0 (a step of
0.5 rad); over 0.02747 s levels 0 and 1 lock just before the end (their lock windows do not
close) and level 2 does not lock."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rodval.analysis.convergence import (
    compared_from,
    estimates,
    qoi_from_record,
    qoi_record,
    quantities_of_interest,
)
from rodval.cli import main
from rodval.core.out_paths import OUTPUT_MARKER, is_stamped, listed_files, read_json

TINY = """\
n = 2
t_end = 0.1
times = { num = 11 }
outputs = ["phi"]

[chain]
l = 1.0
m = 3.0
EI = 1e4
mu = 0.5
kappa = [0.0, 50.0]
nu = 0.0

[initial]
phi = [0.0, 0.3]
dphi = [0.0, -10.0]

[[latches]]
hinge = 1
angle = 0.0
"""
#: The levels' start of the tests: E0 = 1 element per rod, H0 = 4e-4 s (level 0 INVALID).
START = ["--elements", "1", "--step", "4e-4"]

#: The installed command (a process of its own, to be killed).
RODVAL = str(Path(sys.executable).parent / "rodval")


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


def reference(scene, out, *extra, levels=3):
    """``rodval reference SCENE`` in this process: its exit code."""
    argv = ["reference", str(scene), "--converge", "1e-3", "--out", str(out)]
    return main([*argv, "--levels", str(levels), *extra])


def record_of(out):
    return json.loads((out / "reference.json").read_text())


# ------------------------------------------------------- 1. a failed level: no error bar


@pytest.mark.exudyn
def test_a_level_that_fails_at_t0_yields_no_error_bar(tiny, tmp_path, capsys):
    """Before: `reference_error = { rel = 0, lock_dt = 0, impulse_rel = 0 }` printed and
    written, a perfect error bar from no comparison at all."""
    pytest.importorskip("exudyn")
    out = tmp_path / "ref"
    code = reference(tiny, out, "--elements", "1", "--step", "0.05")
    printed = capsys.readouterr().out
    record = record_of(out)
    assert code == 1
    assert "reference_error = {" not in printed
    assert record["reference_error"] is None and record["agreement_toml"] is None
    assert record["usable"] is False and record["converged"] is False
    failed = record["failed"]
    assert failed["level"] == 0 and failed["status"] == "FAILED" and failed["t_reached"] == 0.0
    assert "under-resolved" in failed["message"]
    assert "no error bar: level 0 failed (FAILED at t = 0 s of 0.1 s:" in printed
    assert record["compared_levels"] == []


# ------------------------------------------- an INVALID level is not compared, and said so


@pytest.mark.exudyn
def test_an_invalid_level_is_left_out_of_the_error_bar_which_names_its_levels(
    tiny, tmp_path, capsys
):
    """Before: "converged" (exit 0) on levels 0..2, the Richardson ratios taken with the
    change from level 0, which its own energy audit judges INVALID."""
    pytest.importorskip("exudyn")
    out = tmp_path / "ref"
    code = reference(tiny, out, *START)
    printed = capsys.readouterr().out
    record = record_of(out)
    assert record["levels"] == 3
    assert record["compared_levels"] == [1, 2]
    assert record["left_out"]["0"].startswith("INVALID: energy-audit residual")
    # two levels compared: one change, no ratio, not converged whatever the errors
    assert code == 1 and record["converged"] is False
    assert "levels 1..2 compared" in record["not_converged"]
    assert all(len(q["changes"]) == 1 for q in record["quantities"])
    rows = (out / "levels.csv").read_text().splitlines()
    head = rows[0].split(",")
    lock = head.index("lock_t[latch hinge 1#1]")
    t1, t2 = (float(rows[k].split(",")[lock]) for k in (2, 3))
    # levels.csv carries 10 significant digits: the lock times' change to 1e-10 s
    assert record["reference_error"]["lock_dt"] == pytest.approx(abs(t2 - t1), abs=1e-10)
    assert "over levels 1..2 (level 0 left out: INVALID" in printed


# ------------------------------------------------- levels that lock differently: no bar


@pytest.mark.exudyn
def test_levels_that_lock_differently_are_not_compared(tiny, tmp_path, capsys):
    """Before: the error bar of levels 0..1 written as the finest level 2's (which has no
    lock), scaled by level 2's angles, and the lock impulses' error 0 from windows that never
    closed (impulse 0 at both levels)."""
    pytest.importorskip("exudyn")
    short = tmp_path / "short.toml"
    short.write_text(TINY.replace("t_end = 0.1", "t_end = 0.02747"))
    out = tmp_path / "ref"
    code = reference(short, out, *START)
    printed = capsys.readouterr().out
    record = record_of(out)
    assert code == 1
    assert record["compared_levels"] == [2]
    assert record["reference_error"] is None and record["usable"] is False
    assert "lock_t[latch hinge 1#1] (not at level 2)" in record["left_out"]["1"]
    assert "no error bar:" in printed and "reference_error = {" not in printed


def test_an_impulse_whose_lock_window_did_not_close_is_no_quantity():
    """A lock window the run ended inside holds a partial impulse (the exudyn run above: 0.0,
    `window_closed` False): not the lock's impulse, so no quantity of interest."""
    times, phi = np.array([0.0, 1.0]), np.zeros((2, 1))
    events = [
        {"t": 0.3, "label": "latch hinge 1", "impulse": 2.0, "window_closed": True},
        {"t": 0.9, "label": "latch hinge 1", "impulse": 0.0, "window_closed": False},
    ]
    qoi = quantities_of_interest(events, times, phi)
    assert "lock_impulse[latch hinge 1#1]" in qoi and "lock_t[latch hinge 1#2]" in qoi
    assert "lock_impulse[latch hinge 1#2]" not in qoi


def test_the_compared_levels_are_the_finest_and_those_alike_before_it():
    a = {"lock_t[x#1]": 0.3, "phi_times": np.zeros((2, 1))}
    b = {"phi_times": np.zeros((2, 1))}
    assert compared_from([a, a, a]) == 0
    assert compared_from([None, a, a]) == 1  # level 0 left out (failed or INVALID)
    assert compared_from([a, None, a]) == 2
    assert compared_from([a, a, b]) == 2  # level 2 locks differently
    assert compared_from([a, a, None]) == 3  # the finest left out: nothing compared


def test_a_level_record_gives_back_the_same_quantities_bit_for_bit():
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 1.0, 7)
    events = [{"t": 0.1 + 1e-17, "label": "latch hinge 1", "impulse": -np.pi}]
    qoi = quantities_of_interest(events, t, rng.normal(size=(7, 3)), rng.normal(size=7))
    back = qoi_from_record(json.loads(json.dumps(qoi_record(qoi))))
    assert back.keys() == qoi.keys()
    for name, value in qoi.items():
        np.testing.assert_array_equal(back[name], value)  # JSON keeps every digit of a float
    assert [e.changes for e in estimates([qoi, back])] == [e.changes for e in estimates([qoi, qoi])]


# ------------------------------------------------------ 2. each level written, resumed


def level_files(out):
    return sorted(p.name for p in out.glob("level_*.json"))


@pytest.mark.exudyn
def test_an_interrupted_run_keeps_its_finished_levels_and_a_rerun_resumes(
    tiny, tmp_path, capsys, monkeypatch
):
    """Before: nothing was written until the last level ended."""
    pytest.importorskip("exudyn")
    import rodval.cli.reference as cli

    fresh = tmp_path / "fresh"
    assert reference(tiny, fresh, *START) == 1
    capsys.readouterr()
    out = tmp_path / "ref"
    real = cli.run_level

    def interrupted(scene, model, settings):
        if model.elements == 4:  # level 2
            raise KeyboardInterrupt
        return real(scene, model, settings)

    monkeypatch.setattr(cli, "run_level", interrupted)
    assert reference(tiny, out, *START) == 130
    assert level_files(out) == ["level_0.json", "level_1.json"]
    for name in level_files(out):
        assert is_stamped(read_json(out / name), cli.LEVEL_SCHEMA)
    assert set(level_files(out)) <= set(listed_files(out) or ())
    monkeypatch.setattr(cli, "run_level", real)
    capsys.readouterr()
    assert reference(tiny, out, *START) == 1
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith(f"level 0: reused {out / 'level_0.json'} (same scene")
    assert printed[1].startswith("level 1: reused")
    assert printed[2].startswith("level 2: elements 4")
    resumed, whole = record_of(out), record_of(fresh)
    for key in ("quantities", "reference_error", "compared_levels", "not_converged"):
        assert resumed[key] == whole[key]
    assert level_files(out) == ["level_0.json", "level_1.json", "level_2.json"]


@pytest.mark.exudyn
def test_another_request_reuses_no_level(tiny, tmp_path, capsys):
    pytest.importorskip("exudyn")
    out = tmp_path / "ref"
    assert reference(tiny, out, *START) == 1
    capsys.readouterr()
    other = tmp_path / "other.toml"
    other.write_text(TINY.replace("kappa = [0.0, 50.0]", "kappa = [0.0, 51.0]"))
    reference(other, out, *START)
    printed = capsys.readouterr().out
    assert ": reused " not in printed  # no level line says reused
    assert "level 0: " + str(out / "level_0.json") + " is of another request" in printed
    capsys.readouterr()
    reference(other, out, "--elements", "2", "--step", "2e-4")
    printed = capsys.readouterr().out
    # level i of this request is level i + 1 of the one before: other files, other settings
    assert ": reused " not in printed  # no level line says reused
    assert level_files(out) == ["level_0.json", "level_1.json", "level_2.json"]


@pytest.mark.exudyn
def test_a_killed_command_resumes_from_the_levels_it_wrote(tiny, tmp_path):
    """SIGKILL (no clean-up at all) after level 1 is written: the folder is still rodval's
    (every file it holds is listed in rodval.json before it is written) and the rerun reuses
    levels 0 and 1."""
    pytest.importorskip("exudyn")
    out = tmp_path / "ref"

    def command(levels: int) -> list[str]:
        argv = [RODVAL, "reference", str(tiny), "--converge", "1e-9", "--out", str(out)]
        return [*argv, "--levels", str(levels), *START]

    proc = subprocess.Popen(command(5), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 240
    while not (out / "level_1.json").exists() and time.monotonic() < deadline:
        assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert (out / "level_1.json").exists()
    assert not (out / "reference.json").exists()
    assert is_stamped(read_json(out / OUTPUT_MARKER), "rodval-output")
    done = subprocess.run(command(3), capture_output=True, text=True, timeout=240)
    assert done.returncode == 1, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("level 0: reused") and lines[1].startswith("level 1: reused")


# --------------------------------------------------------------------- 3. --max-wall


@pytest.mark.exudyn
def test_max_wall_is_shared_over_the_levels(tiny, tmp_path, capsys, monkeypatch):
    """Before: --max-wall was refused (no such option). Each level is given what the levels
    before it left of the whole command's budget."""
    pytest.importorskip("exudyn")
    import rodval.cli.reference as cli

    given, real = [], cli.run_level

    def watched(scene, model, settings):
        given.append(settings.max_wall_s)
        return real(scene, model, settings)

    monkeypatch.setattr(cli, "run_level", watched)
    out = tmp_path / "ref"
    assert reference(tiny, out, *START, "--max-wall", "200") == 1
    walls = [float(r.split(",")[3]) for r in (out / "levels.csv").read_text().splitlines()[1:]]
    assert len(given) == 3 and given[0] < 200
    for i in (1, 2):
        assert given[i] <= given[i - 1] - walls[i - 1]
    assert "--max-wall 200 s is the whole command's budget" in capsys.readouterr().out


@pytest.mark.exudyn
def test_a_level_the_budget_cannot_finish_is_reported_and_the_finished_kept(
    tiny, tmp_path, capsys, monkeypatch
):
    pytest.importorskip("exudyn")
    import rodval.cli.reference as cli

    real = cli.run_level

    def squeezed(scene, model, settings):
        if model.elements == 4:  # level 2 given 0.05 s, as if the levels before took the rest
            settings = settings.with_(max_wall_s=0.05)
        return real(scene, model, settings)

    monkeypatch.setattr(cli, "run_level", squeezed)
    out = tmp_path / "ref"
    assert reference(tiny, out, *START, "--max-wall", "300") == 1
    printed = capsys.readouterr().out
    record = record_of(out)
    assert record["failed"]["level"] == 2 and record["failed"]["status"] == "WALL"
    assert 0 <= record["failed"]["t_reached"] < 0.1
    assert record["reference_error"] is None
    assert "no error bar: level 2 failed (WALL at t = " in printed
    assert level_files(out) == ["level_0.json", "level_1.json"]


@pytest.mark.exudyn
def test_a_level_the_budget_leaves_no_time_for_is_not_run_and_said_so(
    tiny, tmp_path, capsys, monkeypatch
):
    """The command's clock (rodval.cli.reference's, not exudyn's) jumps 1000 s once level 1
    has run: level 2 finds nothing left of --max-wall 100 and is not run."""
    pytest.importorskip("exudyn")
    import types

    import rodval.cli.reference as cli

    jump, real = [0.0], cli.run_level
    clock = types.SimpleNamespace(perf_counter=lambda: time.perf_counter() + jump[0])

    def run_then_jump(scene, model, settings):
        row = real(scene, model, settings)
        jump[0] += 1000.0 * (model.elements == 2)
        return row

    monkeypatch.setattr(cli, "time", clock)
    monkeypatch.setattr(cli, "run_level", run_then_jump)
    out = tmp_path / "ref"
    assert reference(tiny, out, *START, "--max-wall", "100") == 1
    printed = capsys.readouterr().out
    failed = record_of(out)["failed"]
    assert failed["level"] == 2 and failed["status"] == "WALL" and failed["t_reached"] == 0.0
    assert re.fullmatch(r"not run: 10\d\d\.\d s of --max-wall 100 s are spent", failed["message"])
    assert "level 2: elements 4, step 0.0001 s, 0.0 s, not run; WALL at t = 0 s: not run" in printed
    assert level_files(out) == ["level_0.json", "level_1.json"]


def test_a_budget_spent_before_any_level_is_refused_before_any_work(tiny, tmp_path, capsys):
    out = tmp_path / "ref"
    code = reference(tiny, out, *START, "--max-wall", "1e-6")
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("rodval reference: error: --max-wall 1e-06 s cannot cover")
    assert len(err.strip().splitlines()) == 1
    assert level_files(out) == [] and not (out / "reference.json").exists()


def test_a_bad_max_wall_is_refused_in_one_line(tiny, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        reference(tiny, tmp_path / "ref", *START, "--max-wall", "0")
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--max-wall must be a number > 0 (inf allowed), got '0'" in err


# --------------------------------------------------------------- 4. a run.json as SCENE


@pytest.mark.exudyn
def test_a_run_json_is_read_as_simulate_reads_it(tiny, tmp_path, capsys):
    """Before: "run.json: malformed TOML". Its scene is the scene file's bit for bit, so the
    levels of the scene file's run are this request's and are reused."""
    pytest.importorskip("exudyn")
    run = tmp_path / "run"
    assert main(["simulate", str(tiny), "--model", "full", "--out", str(run)]) == 0
    out = tmp_path / "ref"
    assert reference(tiny, out, *START) == 1
    capsys.readouterr()
    assert reference(run / "run.json", out, *START) == 1
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith(f"note: {run / 'run.json'}: its scene only (model 'full'")
    assert all(printed[1 + i].startswith(f"level {i}: reused") for i in range(3))
