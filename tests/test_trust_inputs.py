"""Inputs rodval used to accept without a word (the "trust" issue): runs of different scenes
compared, damaged run folders read, values clamped, coerced or dropped silently, and Python
API calls that failed deep inside. Each is now refused up front with one line naming the
parameter (or file) and what is allowed."""

import json
import shutil

import pytest
from test_cli_errors import assert_refused, run_main

from rodval.cli import main

TINY = 'n = 2\nt_end = 0.05\ntimes = {start = 0.0, stop = 0.05, num = 11}\noutputs = ["phi"]\n'


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Two run folders of a tiny scene (A, A2: the same scene) and one of another EI (B)."""
    d = tmp_path_factory.mktemp("runs")
    (d / "a.toml").write_text(TINY)
    (d / "b.toml").write_text(TINY + "[chain]\nEI = 2e5\n")
    for scene, out in (("a", "A"), ("a", "A2"), ("b", "B")):
        assert main(["simulate", str(d / f"{scene}.toml"), "--out", str(d / out)]) == 0
    return d


# -- item 1: rodval compare ---------------------------------------------------------------


def test_compare_refuses_runs_of_different_scenes(runs, tmp_path, capsys):
    proc = run_main(capsys, "compare", str(runs / "A"), str(runs / "B"), "--out", str(tmp_path))
    assert_refused(proc, ["different scenes", "chain.EI", "--allow-different-scenes"])
    assert not (tmp_path / "discrepancies.csv").exists()


def test_compare_of_different_scenes_when_asked(runs, tmp_path, capsys):
    args = ["compare", str(runs / "A"), str(runs / "B"), "--out", str(tmp_path)]
    assert main([*args, "--allow-different-scenes"]) == 0
    assert (tmp_path / "discrepancies.csv").is_file()


def test_compare_of_the_same_scene_under_two_names(runs, tmp_path):
    # the name labels a scene; it does not change what is simulated
    assert main(["compare", str(runs / "A"), str(runs / "A2"), "--out", str(tmp_path)]) == 0


@pytest.fixture
def damaged(runs, tmp_path):
    """A copy of run A to damage."""
    shutil.copytree(runs / "A", tmp_path / "A")
    return tmp_path / "A"


def test_compare_refuses_a_truncated_trajectory(runs, damaged, tmp_path, capsys):
    csv = damaged / "trajectory.csv"
    assert csv.stat().st_size > 300
    csv.write_bytes(csv.read_bytes()[:300])
    proc = run_main(capsys, "compare", str(damaged), str(runs / "A"), "--out", str(tmp_path / "c"))
    assert_refused(proc, [str(csv), "damaged", "300 bytes"])


def test_compare_refuses_a_trajectory_cut_at_a_line_end(runs, damaged, tmp_path, capsys):
    # cut after a complete time: a table that reads as a shorter run
    csv = damaged / "trajectory.csv"
    csv.write_text("".join(csv.read_text().splitlines(keepends=True)[:3]))
    proc = run_main(capsys, "compare", str(damaged), str(runs / "A"), "--out", str(tmp_path / "c"))
    assert_refused(proc, [str(csv), "damaged"])


def test_compare_refuses_an_edited_trajectory(runs, damaged, tmp_path, capsys):
    csv = damaged / "trajectory.csv"
    text = csv.read_text()
    csv.write_text(text.replace("0.0,phi,1,0.0", "0.0,phi,1,1.0"))
    assert csv.read_text() != text
    proc = run_main(capsys, "compare", str(damaged), str(runs / "A"), "--out", str(tmp_path / "c"))
    assert_refused(proc, [str(csv), "SHA-256"])


def test_compare_refuses_a_truncated_run_json(runs, damaged, tmp_path, capsys):
    rec = damaged / "run.json"
    rec.write_bytes(rec.read_bytes()[:300])
    proc = run_main(capsys, "compare", str(damaged), str(runs / "A"), "--out", str(tmp_path / "c"))
    assert_refused(proc, [str(rec), "damaged", "not valid JSON"])


def test_compare_refuses_a_run_json_of_wrong_types(runs, damaged, tmp_path, capsys):
    rec = damaged / "run.json"
    doc = json.loads(rec.read_text())
    rec.write_text(json.dumps({**doc, "scene": [1, 2]}))
    proc = run_main(capsys, "compare", str(damaged), str(runs / "A"), "--out", str(tmp_path / "c"))
    assert_refused(proc, [str(rec), "'scene'", "table"])
