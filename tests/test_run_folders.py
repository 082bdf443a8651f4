"""Run folders of `rodval simulate`, `rodval compare` and `rodval animate` (issue 36): nothing
of the user's overwritten, no stale file of an earlier run left beside a new one, no
trajectory read without its digest, animations that draw what ran (a free base where it
moved, each run at its own output times), --t-end past the horizon said out loud, and large
scene arrays kept out of run.json (scene_arrays.npz) within the wall-clock budget."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from checks import assert_refused, run_main

import rodval.cli.simulate as simulate_cli
from rodval import paper_scene, simulate
from rodval.cli import main
from rodval.core.base import Base
from rodval.core.out_paths import is_stamped
from rodval.core.scene_file import load_scene
from rodval.report.animation import node_history
from rodval.report.run_files import read_run, read_run_record, write_run

#: The rods' data a scene file states (no ``based_on``): the paper's rods.
CHAIN = "[chain]\nl = 2.0\nm = 3.0\nEI = 1e5\n"
TINY = (
    'n = 2\nt_end = 0.05\ntimes = {start = 0.0, stop = 0.05, num = 11}\noutputs = ["phi"]\n'
    + CHAIN
    + "[initial]\ndphi = 1.0\n"
)


def tiny_scene(folder: Path, text: str = TINY, name: str = "tiny") -> Path:
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


def simulate_into(out: Path, scene: Path | str, *extra: str) -> int:
    return main(["simulate", str(scene), "--model", "reduced", "--out", str(out), *extra])


# -- 1. nothing overwritten --------------------------------------------------------------


@pytest.mark.parametrize(
    "own", [("trajectory.csv",), ("run.json",), ("notes.txt",), ("run.json", "trajectory.csv")]
)
def test_simulate_refuses_a_folder_of_the_users_files_before_any_work(
    own, tmp_path, capsys, monkeypatch
):
    """A --out folder holding files rodval did not write (the user's own trajectory.csv,
    run.json or anything else) was overwritten; it is refused before the run, naming them."""
    scene = tiny_scene(tmp_path)
    out = tmp_path / "mine"
    out.mkdir()
    for name in own:
        (out / name).write_text(f"the user's {name}\n")
    ran = []
    monkeypatch.setattr(simulate_cli, "simulate", lambda *a, **k: ran.append(a))
    proc = run_main(capsys, "simulate", str(scene), "--out", str(out))
    assert_refused(proc, ["--out", str(out), *(repr(n) for n in own), "new or empty folder"])
    assert ran == []
    for name in own:
        assert (out / name).read_text() == f"the user's {name}\n"
    assert sorted(p.name for p in out.iterdir()) == sorted(own)


def test_a_rodval_run_folder_is_stamped_and_may_be_rewritten(tmp_path):
    scene = tiny_scene(tmp_path)
    out = tmp_path / "run"
    assert simulate_into(out, scene) == 0
    assert is_stamped(json.loads((out / "run.json").read_text()), "rodval-run")
    assert simulate_into(out, scene, "--t-end", "0.03") == 0
    assert read_run(out).times[-1] == pytest.approx(0.03)
    (out.parent / "empty").mkdir()
    assert simulate_into(out.parent / "empty", scene) == 0


def test_an_edited_run_json_is_a_scene_input_but_its_folder_no_longer_an_output(tmp_path, capsys):
    """An edited run.json reruns as SCENE (it is the user's request now: no checksum asked);
    its folder is no longer rodval's and is refused as --out, saying why and what to do."""
    scene = tiny_scene(tmp_path)
    run = tmp_path / "run"
    assert simulate_into(run, scene) == 0
    record = json.loads((run / "run.json").read_text())
    record["scene"]["t_end"] = 0.04
    record["scene"]["times"] = [0.0, 0.02, 0.04]
    (run / "run.json").write_text(json.dumps(record))
    assert main(["simulate", str(run / "run.json"), "--out", str(tmp_path / "again")]) == 0
    assert read_run(tmp_path / "again").times.tolist() == [0.0, 0.02, 0.04]
    capsys.readouterr()
    before = (run / "trajectory.csv").read_bytes()
    proc = run_main(capsys, "simulate", str(scene), "--out", str(run))
    assert_refused(proc, ["--out", "'run.json'", "edited", "older rodval", "new folder"])
    assert (run / "trajectory.csv").read_bytes() == before


def test_an_older_run_folder_without_a_stamp_is_refused_as_out(tmp_path, capsys):
    scene = tiny_scene(tmp_path)
    run = tmp_path / "old"
    assert simulate_into(run, scene) == 0
    record = json.loads((run / "run.json").read_text())
    old = {k: v for k, v in record.items() if not k.startswith("rodval_")}
    (run / "run.json").write_text(json.dumps(old, indent=2))
    proc = run_main(capsys, "simulate", str(scene), "--out", str(run))
    assert_refused(proc, ["--out", "'run.json'", "older rodval", "new folder"])


# -- 2. stale files ----------------------------------------------------------------------


def test_a_rerun_without_wide_removes_the_earlier_wide_table_only(tmp_path):
    """A rerun into the same folder without --wide left the earlier run's trajectory_wide.csv
    (of another n) beside the new run. run.json lists the files its run wrote; a new run
    removes those of the previous run it does not write, and nothing else."""
    out = tmp_path / "run"
    three = tiny_scene(tmp_path, TINY.replace("n = 2", "n = 3"), "three")
    assert simulate_into(out, three, "--wide") == 0
    assert json.loads((out / "run.json").read_text())["files"] == [
        "trajectory.csv",
        "trajectory_wide.csv",
    ]
    (out / "my_notes.txt").write_text("kept")
    assert simulate_into(out, tiny_scene(tmp_path)) == 0
    assert not (out / "trajectory_wide.csv").exists()
    assert (out / "my_notes.txt").read_text() == "kept"
    assert json.loads((out / "run.json").read_text())["files"] == ["trajectory.csv"]
    assert read_run(out).values["phi"].shape[1] == 2


def test_a_file_named_like_a_runs_that_the_run_did_not_write_is_refused(tmp_path, capsys):
    """A run folder of rodval where the user put a trajectory_wide.csv of their own (its
    run.json does not list it): refused, the file kept, rather than overwritten by --wide."""
    out = tmp_path / "run"
    assert simulate_into(out, tiny_scene(tmp_path)) == 0
    (out / "trajectory_wide.csv").write_text("my own table\n")
    capsys.readouterr()
    proc = run_main(capsys, "simulate", str(tiny_scene(tmp_path)), "--wide", "--out", str(out))
    assert_refused(proc, ["--out", "'trajectory_wide.csv'", "does not list"])
    assert (out / "trajectory_wide.csv").read_text() == "my own table\n"


# -- 3. no digest, no silent cut ---------------------------------------------------------


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory) -> tuple[Path, Path]:
    d = tmp_path_factory.mktemp("two")
    scene = tiny_scene(d)
    for name in ("A", "B"):
        assert simulate_into(d / name, scene) == 0
    return d / "A", d / "B"


@pytest.mark.parametrize("cut", [None, 300, "rows"])
def test_compare_refuses_a_trajectory_without_a_recorded_digest(two_runs, cut, tmp_path, capsys):
    """With run.json's digest of trajectory.csv removed (an older run, or edited), a
    trajectory.csv cut to 300 bytes was compared silently; any such table is now refused,
    naming the file, why, and the rerun that makes a checked one."""
    folder = tmp_path / "A"
    folder.mkdir()
    record = json.loads((two_runs[0] / "run.json").read_text())
    del record["trajectory_csv"]
    (folder / "run.json").write_text(json.dumps(record))
    table = (two_runs[0] / "trajectory.csv").read_bytes()
    if cut == "rows":  # cut at the end of a time: it reads as a shorter run
        table = b"".join(table.splitlines(keepends=True)[: 1 + 2 * 5])
    elif cut is not None:
        table = table[:cut]
    (folder / "trajectory.csv").write_bytes(table)
    proc = run_main(capsys, "compare", str(folder), str(two_runs[1]), "--out", str(tmp_path / "c"))
    assert_refused(
        proc,
        [str(folder / "trajectory.csv"), "no digest", "rodval simulate", "run.json --out"],
    )
    assert not (tmp_path / "c").exists()


# -- 4. animate --------------------------------------------------------------------------

FREE = (
    "n = 2\nt_end = 0.5\ntimes = {start = 0.0, stop = 0.5, num = 6}\n"
    'outputs = ["phi", "base"]\nloads = []\n'
    '[base]\nkind = "free"\nmass = 100.0\ninertia = 50.0\nhinge_offset = [1.0, 0.0]\n'
    "velocity = [4.0, 0.0]\n" + CHAIN
)


@pytest.fixture(scope="module")
def free_run(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("free")
    out = d / "free"
    scene = tiny_scene(d, FREE, "free")
    assert main(["simulate", str(scene), "--model", "full", "--out", str(out)]) == 0
    return out


def test_a_free_base_is_drawn_where_the_body_moved(free_run, tmp_path, capsys):
    """A free-base run with outputs phi, base (no x, y) was drawn with its root pinned at
    the origin while the body moved 2 m; the chain now hangs from node 0 = r_c + R(theta) h."""
    traj = read_run(free_run)
    base = Base.from_dict(read_run_record(free_run / "run.json")["scene"]["base"], "base")
    x, y = node_history(traj, np.array([2.0, 2.0]), base)
    rc, theta = traj["base_position"], traj["base_attitude"][:, 0]
    np.testing.assert_allclose(x[:, 0], rc[:, 0] + np.cos(theta) * 1.0)
    np.testing.assert_allclose(y[:, 0], rc[:, 1] + np.sin(theta) * 1.0)
    assert x[-1, 0] - x[0, 0] == pytest.approx(2.0, rel=0.05)  # the body moved ~2 m
    np.testing.assert_allclose(x[:, 1] - x[:, 0], 2.0 * np.cos(traj["phi"][:, 0]))
    with pytest.raises(ValueError, match="pinned"):
        node_history(traj, np.array([2.0, 2.0]))  # a free run is never drawn pinned
    out = tmp_path / "free.gif"
    assert main(["animate", str(free_run), "--out", str(out), "--frames", "3"]) == 0
    assert out.is_file()


def test_a_free_base_without_its_position_is_refused(tmp_path, capsys):
    scene = tiny_scene(tmp_path, FREE.replace('"phi", "base"', '"phi"'), "free_phi")
    run = tmp_path / "run"
    assert main(["simulate", str(scene), "--model", "full", "--out", str(run)]) == 0
    capsys.readouterr()
    proc = run_main(capsys, "animate", str(run), "--out", str(tmp_path / "a.gif"))
    assert_refused(proc, [str(run), "free base", "'base'", "x, y"])
    assert not (tmp_path / "a.gif").exists()


def test_animate_draws_each_run_only_at_output_times_it_has(tmp_path, capsys):
    """B with fewer output times was drawn at its own next time under A's time in the title;
    frames are now the output times both runs have, and the command says so."""
    fine = tiny_scene(tmp_path)
    coarse = tiny_scene(tmp_path, TINY.replace("num = 11", "num = 3"), "coarse")
    assert simulate_into(tmp_path / "A", fine) == 0
    assert simulate_into(tmp_path / "B", coarse) == 0
    capsys.readouterr()
    out = tmp_path / "ab.gif"
    code = main(["animate", str(tmp_path / "A"), str(tmp_path / "B"), "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    assert printed.startswith("3 frames"), printed
    assert "t = 0..0.05 s" in printed
    assert "11" in printed and "3 output times" in printed
    odd = tiny_scene(
        tmp_path, TINY.replace("{start = 0.0, stop = 0.05, num = 11}", "[0.013, 0.027]"), "odd"
    )
    assert simulate_into(tmp_path / "C", odd) == 0
    capsys.readouterr()
    proc = run_main(capsys, "animate", str(tmp_path / "A"), str(tmp_path / "C"), "--out", str(out))
    assert_refused(proc, ["share", "11 output times", "2 output times"])


# -- 5. --t-end past the horizon ---------------------------------------------------------


def test_t_end_past_the_horizon_extends_an_even_grid_of_the_file(tmp_path, capsys):
    """--t-end past the horizon integrated to T but wrote outputs only up to the old horizon,
    without a word. A {start, stop, num} grid ending at the horizon goes on at its spacing."""
    scene = tiny_scene(tmp_path)
    assert simulate_into(tmp_path / "r", scene, "--t-end", "0.1") == 0
    printed = capsys.readouterr().out
    times = read_run(tmp_path / "r").times
    np.testing.assert_allclose(times, np.linspace(0.0, 0.1, 21), rtol=0, atol=1e-15)
    assert "note: --t-end 0.1 s" in printed and "every 0.005 s" in printed


def test_t_end_past_listed_output_times_says_which_it_kept(tmp_path, capsys):
    listed = tiny_scene(
        tmp_path, TINY.replace("{start = 0.0, stop = 0.05, num = 11}", "[0.01, 0.05]"), "list"
    )
    assert simulate_into(tmp_path / "r", listed, "--t-end", "0.1") == 0
    printed = capsys.readouterr().out
    assert read_run(tmp_path / "r").times.tolist() == [0.01, 0.05]
    assert "note: --t-end 0.1 s" in printed and "0.01, 0.05" in printed and "--times" in printed
    # a run.json (its times always a list) likewise
    code = main(["simulate", str(tmp_path / "r" / "run.json"), "--t-end", "0.2", "--out",
                 str(tmp_path / "r2")])  # fmt: skip
    assert code == 0 and "note: --t-end 0.2 s" in capsys.readouterr().out


# -- 6. large scene arrays out of run.json -----------------------------------------------

BIG_N = 1500


@pytest.fixture(scope="module")
def wide_chain(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("wide")
    text = (
        f"n = {BIG_N}\nt_end = 0.002\ntimes = [0.001, 0.002]\noutputs = ['phi']\n"
        "[chain]\nl = 0.01\nm = 3.0\nEI = 1e5\n"
        "[initial]\ndphi = {at = [0.0, 1.0], values = [0.0, 1.0]}\n"
    )
    return tiny_scene(d, text, "wide")


def test_large_scene_arrays_go_to_an_npz_and_a_rerun_rebuilds_the_same_scene(wide_chain, tmp_path):
    run = tmp_path / "run"
    assert simulate_into(run, wide_chain) == 0
    text = (run / "run.json").read_text()
    assert len(text) < 20_000, len(text)  # no per-rod arrays in the JSON
    record = json.loads(text)
    assert record["files"] == ["trajectory.csv", "scene_arrays.npz"]
    assert "scene_arrays" in record and record["scene_arrays"]["sha256"]
    full = read_run_record(run / "run.json")
    assert len(full["scene"]["chain"]["l"]) == BIG_N
    scene = load_scene(wide_chain)
    assert full["scene"]["initial"]["dphi"] == scene.initial.resolve(BIG_N)["dphi"].tolist()
    assert main(["simulate", str(run / "run.json"), "--out", str(tmp_path / "again")]) == 0
    again = tmp_path / "again"
    assert (again / "trajectory.csv").read_bytes() == (run / "trajectory.csv").read_bytes()
    assert read_run_record(again / "run.json")["scene"] == full["scene"]


def test_a_damaged_or_missing_scene_arrays_file_is_refused(wide_chain, tmp_path, capsys):
    run = tmp_path / "run"
    assert simulate_into(run, wide_chain) == 0
    npz = run / "scene_arrays.npz"
    npz.write_bytes(npz.read_bytes()[:-10])
    capsys.readouterr()
    proc = run_main(capsys, "simulate", str(run / "run.json"), "--out", str(tmp_path / "x"))
    assert_refused(proc, [str(npz), "damaged"])
    npz.unlink()
    proc = run_main(capsys, "simulate", str(run / "run.json"), "--out", str(tmp_path / "x"))
    assert_refused(proc, [str(npz), "does not exist"])


def test_the_tidy_table_is_written_as_pandas_writes_it(tmp_path):
    """The fast writer of trajectory.csv: the same bytes as pandas' to_csv (floats shortest
    round trip, -0.0, 1e-05, 1e+16), so the paper's run keeps its file bit for bit."""
    from rodval.report.run_files import tidy_csv

    scene = paper_scene(3, t_end=0.2, times=[0.0, 0.1, 0.2], outputs=("phi", "x", "energy"))
    traj = simulate(scene, "full")
    traj.values["phi"][1] = [-0.0, 1e-05, 1e16]
    traj.values["phi"][2] = [123456789.123, 1e-300, np.pi]
    assert tidy_csv(traj) == traj.to_frame().to_csv(index=False).encode()


def _no_run(*args, **kwargs):
    raise AssertionError("the run was started")


def test_the_wall_budget_covers_the_whole_command(tmp_path, capsys, monkeypatch):
    """--max-wall covered the integration only: a large run then spent minutes writing. The
    command refuses a budget that cannot cover its estimated set-up and writing, naming
    --max-wall, before any work; a budget that can is the whole command's."""
    big = tiny_scene(tmp_path, "n = 200000\nt_end = 2.0\ntimes = [1.0, 2.0]\n" + CHAIN, "big")
    monkeypatch.setattr(simulate_cli, "simulate", _no_run)  # refused before any work
    proc = run_main(capsys, "simulate", str(big), "--max-wall", "0.5", "--out", str(tmp_path / "o"))
    assert_refused(proc, ["--max-wall 0.5 s", "writing", "set-up"])
    assert not (tmp_path / "o").exists()


def test_wide_rows_are_written_with_the_run(tmp_path):
    """write_run writes the wide table too when asked, and lists it."""
    scene = paper_scene(2, t_end=0.02, times=[0.0, 0.02], outputs=("phi",))
    traj = simulate(scene, "reduced")
    files = write_run(traj, scene, tmp_path / "w", wide=True)
    assert files == ["trajectory.csv", "trajectory_wide.csv"]
    wide = pd.read_csv(tmp_path / "w" / "trajectory_wide.csv")
    assert list(wide.columns) == ["t", "phi[1]", "phi[2]"]


def test_compare_refuses_a_folder_of_the_users_files(two_runs, tmp_path, capsys):
    """compare's --out held the user's discrepancies.csv: overwritten; now refused first."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "discrepancies.csv").write_text("my own\n")
    proc = run_main(capsys, "compare", *map(str, two_runs), "--out", str(out))
    assert_refused(proc, ["--out", "'discrepancies.csv'", "new or empty folder"])
    assert (out / "discrepancies.csv").read_text() == "my own\n"
    assert main(["compare", *map(str, two_runs), "--out", str(tmp_path / "new")]) == 0
    assert main(["compare", *map(str, two_runs), "--out", str(tmp_path / "new")]) == 0
