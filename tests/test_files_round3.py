"""Issue 46, what rodval writes and where: never through a link it did not make, each
command's folder holding its own files only (an earlier run's stale files removed, never a
user's), the folders above --junit and animate's --out made as users expect, a run.json
event without a time refused, and a moving base's animation drawn where the body is."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from checks import assert_refused, run_main

from rodval.cli import main
from rodval.core.out_paths import (
    OUTPUT_MARKER,
    check_output_file,
    claim_output_folder,
)
from rodval.core.scene_file import load_scene
from rodval.core.trajectory import SolverStats, Trajectory
from rodval.report.run_files import read_run, read_run_record, write_run

CHAIN = "[chain]\nl = 2.0\nm = 3.0\nEI = 1e5\n"
TINY = (
    'n = 2\nt_end = 0.05\ntimes = {start = 0.0, stop = 0.05, num = 11}\noutputs = ["phi"]\n'
    + CHAIN
    + "[initial]\ndphi = 1.0\n"
)
PRESCRIBED = (
    'n = 2\nt_end = 0.2\ntimes = {start = 0.0, stop = 0.2, num = 5}\noutputs = ["phi"]\n'
    + CHAIN
    + '[base]\nkind = "prescribed"\nhinge_offset = [0.5, 0.0]\n[base.motion]\n'
    + 'x = {law = "linear", value = 0.0, rate = 2.0}\n'
    + 'attitude = {law = "linear", value = 0.0, rate = 1.0}\n'
)


def scene_file(folder: Path, text: str = TINY, name: str = "tiny") -> Path:
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


def snapshot(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and not p.is_symlink()
    }


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory) -> tuple[Path, Path, Path]:
    """Two run folders of the tiny scene (reduced, full) and the scene file."""
    d = tmp_path_factory.mktemp("runs")
    scene = scene_file(d)
    for name, model in (("A", "reduced"), ("B", "full")):
        assert main(["simulate", str(scene), "--model", model, "--out", str(d / name)]) == 0
    return d / "A", d / "B", scene


def run_with_events(out: Path, scene_path: Path, events: list[dict]) -> Path:
    """A run folder of the tiny scene written by rodval (``write_run``) with ``events``."""
    scene = load_scene(scene_path)
    times = np.asarray(scene.times, float)
    phi = np.outer(times, [1.0, 2.0])
    traj = Trajectory(
        "reduced", "tiny", times, {"phi": phi}, {"phi": np.array([1, 2])}, SolverStats()
    )
    traj.events = events
    write_run(traj, scene, out)
    return out


LOCK = {"t": 0.02, "label": "latch 1", "hinge": 1, "impulse": 1.5, "rigid_impulse": 2.0}


# -- 1. never through a link --------------------------------------------------------------


def test_a_rerun_into_a_folder_whose_run_json_links_to_another_run_is_refused(
    two_runs, tmp_path, capsys
):
    """Issue 46 data loss: C/run.json a symbolic link to A's run.json: a rerun into C wrote
    its record through the link, and A no longer read. Refused before work, naming the link;
    A unchanged and still read."""
    a, _, scene = two_runs
    c = tmp_path / "C"
    c.mkdir()
    (c / "run.json").symlink_to(a / "run.json")
    before = snapshot(a)
    proc = run_main(capsys, "simulate", str(scene), "--model", "reduced", "--out", str(c))
    assert_refused(proc, ["--out", str(c / "run.json"), "symbolic link"])
    assert snapshot(a) == before
    read_run(a)
    assert sorted(p.name for p in c.iterdir()) == ["run.json"]


@pytest.mark.parametrize("command", ["simulate", "compare"])
def test_a_linked_output_folder_is_refused(two_runs, tmp_path, capsys, command):
    """--out a symbolic link to another folder of rodval (a run folder, a compare folder)
    would write into that folder: refused before work, naming the link."""
    a, b, scene = two_runs
    target = tmp_path / "target"
    assert main(["compare", str(a), str(b), "--out", str(target)]) == 0
    if command == "simulate":
        target = tmp_path / "run"
        assert main(["simulate", str(scene), "--model", "reduced", "--out", str(target)]) == 0
    capsys.readouterr()
    link = tmp_path / "link"
    link.symlink_to(target, target_is_directory=True)
    before = snapshot(target)
    args = {
        "simulate": ["simulate", str(scene), "--model", "reduced"],
        "compare": ["compare", str(a), str(b)],
    }[command]
    proc = run_main(capsys, *args, "--out", str(link))
    assert_refused(proc, ["--out", str(link), "symbolic link"])
    assert snapshot(target) == before


def test_a_study_folder_holding_a_link_is_refused(tmp_path):
    """A study folder whose cases/ links to another study's would write its records there."""
    from rodval.study.store import StudyStore

    other = tmp_path / "other"
    other.mkdir()
    out = tmp_path / "study"
    out.mkdir()
    (out / "cases").symlink_to(other, target_is_directory=True)
    with pytest.raises(ValueError, match="symbolic link"):
        StudyStore(out).check_folder()


def test_write_file_never_writes_through_a_link(tmp_path):
    """The one writer refuses a link at its target; the linked file is untouched."""
    from rodval.core.out_paths import write_file

    theirs = tmp_path / "theirs.txt"
    theirs.write_text("someone else's")
    link = tmp_path / "out.txt"
    link.symlink_to(theirs)
    with pytest.raises(ValueError, match="symbolic link"):
        write_file(link, "mine")
    assert theirs.read_text() == "someone else's"
    with pytest.raises(ValueError, match="symbolic link"):
        check_output_file(link, "--junit", ours=lambda p: True)


# -- 2. each command's folder holds its files only ----------------------------------------


def test_a_compare_folder_is_refused_to_another_command(two_runs, tmp_path, capsys):
    """`rodval modes --out` into a compare folder mixed the two commands' files: an output
    folder belongs to the command that made it (rodval.json names it), refused to another
    before any work, nothing changed."""
    a, b, _ = two_runs
    out = tmp_path / "cmp"
    assert main(["compare", str(a), str(b), "--out", str(out)]) == 0
    capsys.readouterr()
    before = snapshot(out)
    proc = run_main(capsys, "modes", str(a / "run.json"), "--out", str(out))
    assert_refused(proc, ["--out", str(out), "output folder of rodval compare", "modes"])
    assert snapshot(out) == before
    with pytest.raises(ValueError, match="rodval compare"):
        claim_output_folder(out, command="reproduce")
    claim_output_folder(out, command="compare")


def test_a_second_compare_leaves_no_stale_events_csv(two_runs, tmp_path, capsys):
    """Issue 46: a compare into the folder of an earlier compare left the old events.csv
    when the new runs had no locks. The earlier compare's listed files are replaced."""
    _, _, scene = two_runs
    locked = [run_with_events(tmp_path / n, scene, [LOCK]) for n in ("LA", "LB")]
    plain = [run_with_events(tmp_path / n, scene, []) for n in ("PA", "PB")]
    out = tmp_path / "cmp"
    assert main(["compare", *map(str, locked), "--out", str(out)]) == 0
    assert (out / "events.csv").is_file() and (out / "events.md").is_file()
    assert main(["compare", *map(str, plain), "--out", str(out)]) == 0
    capsys.readouterr()
    names = sorted(p.name for p in out.iterdir())
    assert names == ["discrepancies.csv", "discrepancies.md", "histories.png", OUTPUT_MARKER]
    marker = json.loads((out / OUTPUT_MARKER).read_text())
    assert marker["command"] == "compare"
    assert marker["files"] == ["discrepancies.csv", "discrepancies.md", "histories.png"]


def test_a_users_file_in_a_compare_folder_is_kept_and_refused(two_runs, tmp_path, capsys):
    """A file the user put into a compare folder is not rodval's: never removed; the next
    compare there is refused naming it (rodval would otherwise mix or later remove it)."""
    a, b, _ = two_runs
    out = tmp_path / "cmp"
    assert main(["compare", str(a), str(b), "--out", str(out)]) == 0
    (out / "notes.txt").write_text("my notes")
    capsys.readouterr()
    proc = run_main(capsys, "compare", str(a), str(b), "--out", str(out))
    assert_refused(proc, ["--out", str(out), "'notes.txt'", "does not list"])
    assert (out / "notes.txt").read_text() == "my notes"
    assert (out / "discrepancies.csv").is_file()


def test_animate_into_another_commands_folder_is_refused(two_runs, tmp_path, capsys):
    a, b, _ = two_runs
    out = tmp_path / "cmp"
    assert main(["compare", str(a), str(b), "--out", str(out)]) == 0
    capsys.readouterr()
    proc = run_main(capsys, "animate", str(a), "--out", str(out / "x.gif"))
    assert_refused(proc, ["--out", "output folder of rodval compare"])
    assert not (out / "x.gif").exists()


# -- 3. missing parent folders ------------------------------------------------------------


def test_animate_makes_the_folders_above_its_file(two_runs, tmp_path, monkeypatch, capsys):
    """`rodval animate --out anim/x.gif` failed with a raw [Errno 2]: the folder is made."""
    a, _, _ = two_runs
    monkeypatch.chdir(tmp_path)
    assert main(["animate", str(a), "--out", "anim/deep/x.gif", "--frames", "3"]) == 0
    assert (tmp_path / "anim" / "deep" / "x.gif").is_file()
    assert sorted(p.name for p in (tmp_path / "anim" / "deep").iterdir()) == ["x.gif"]


def test_junit_makes_the_folders_above_its_file(tmp_path, monkeypatch, capsys):
    """`--junit reports/gate.xml` was refused when reports/ did not exist: it is made."""
    from study_helpers import write_study

    study = write_study(tmp_path, models="[models.reduced]\n", grid="scene.t_end = [0.1]")
    monkeypatch.chdir(tmp_path)
    quick = ["--no-progress", "--workers", "1", "--no-report"]
    args = ["study", str(study), "--out", "so", *quick, "--junit", "reports/gate.xml"]
    assert main(args) == 0, capsys.readouterr().err
    assert (tmp_path / "reports" / "gate.xml").read_bytes().startswith(b"<?xml")
    assert main(["report", "so", "--junit", "reports/ci/again.xml"]) == 0
    assert (tmp_path / "reports" / "ci" / "again.xml").is_file()
    (tmp_path / "afile").write_text("x")
    proc = run_main(capsys, "report", "so", "--junit", "afile/sub/gate.xml")
    assert_refused(proc, ["--junit", "afile", "is a file"])


# -- 4. a run.json event without a time ---------------------------------------------------


@pytest.mark.parametrize("t", [math.nan, None, "0.02", math.inf])
def test_a_run_json_lock_without_a_time_is_refused_naming_it(two_runs, tmp_path, capsys, t):
    """Issue 46: a NaN lock time in a run.json went into events.csv as blank cells without
    a reason. rodval records every event at its time, so such a run.json is edited or
    damaged: refused, one line naming the file, the event and 't'; nothing written."""
    _, _, scene = two_runs
    a = run_with_events(tmp_path / "A", scene, [LOCK])
    b = run_with_events(tmp_path / "B", scene, [LOCK])
    rec = json.loads((a / "run.json").read_text())
    rec["events"][0]["t"] = t
    (a / "run.json").write_text(json.dumps(rec))
    out = tmp_path / "cmp"
    proc = run_main(capsys, "compare", str(a), str(b), "--out", str(out))
    assert_refused(proc, [str(a / "run.json"), "'events' item 0", "'latch 1'", "'t'"])
    assert not out.exists()
    with pytest.raises(ValueError, match="finite"):
        read_run_record(a / "run.json")


# -- 5. a moving base animated where the body is ------------------------------------------


@pytest.fixture(scope="module")
def prescribed_run(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("prescribed")
    scene = scene_file(d, PRESCRIBED, "pres")
    assert main(["simulate", str(scene), "--model", "full", "--out", str(d / "P")]) == 0
    return d / "P"


def test_a_prescribed_base_without_x_y_is_drawn_where_its_laws_put_it(prescribed_run):
    """A moving-base run without x, y (nor output 'base') was animated with its root pinned
    at the origin while the body moved: node 0 is r_c + R(theta) h from the motion laws."""
    from rodval.core.base import Base
    from rodval.report.animation import node_history

    traj = read_run(prescribed_run)
    base = Base.from_dict(read_run_record(prescribed_run / "run.json")["scene"]["base"])
    x, y = node_history(traj, np.array([2.0, 2.0]), base)
    t = traj.times
    np.testing.assert_allclose(x[:, 0], 2.0 * t + 0.5 * np.cos(t), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(y[:, 0], 0.5 * np.sin(t), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(x[:, 1] - x[:, 0], 2.0 * np.cos(traj["phi"][:, 0]))


def test_the_body_of_a_moving_base_is_drawn_at_its_pose(prescribed_run, tmp_path, capsys):
    """The animation of a moving base did not draw the body: a square about its centre,
    turned by its attitude, half side its hinge offset (node 0 on its edge)."""
    from rodval.core.base import Base
    from rodval.report.animation import body_outline, body_pose, body_size

    traj = read_run(prescribed_run)
    base = Base.from_dict(read_run_record(prescribed_run / "run.json")["scene"]["base"])
    centre, attitude = body_pose(traj, base)
    np.testing.assert_allclose(centre[:, 0], 2.0 * traj.times, atol=1e-12)
    np.testing.assert_allclose(attitude, traj.times, atol=1e-12)
    half = body_size(base, np.array([2.0, 2.0]))
    assert half == 0.5
    bx, by = body_outline(centre, attitude, half)
    np.testing.assert_allclose(bx[:, :4].mean(axis=1), centre[:, 0], atol=1e-12)
    i = -1
    np.testing.assert_allclose(
        (bx[i, 0] - centre[i, 0], by[i, 0] - centre[i, 1]),
        0.5
        * np.array(
            [np.cos(attitude[i]) - np.sin(attitude[i]), np.sin(attitude[i]) + np.cos(attitude[i])]
        ),
        atol=1e-12,
    )
    out = tmp_path / "p.gif"
    assert main(["animate", str(prescribed_run), "--out", str(out), "--frames", "3"]) == 0
    assert out.is_file()
    assert "note" not in capsys.readouterr().out
