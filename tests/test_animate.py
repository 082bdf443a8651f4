"""`rodval animate`: the shipped four-panel deployment (studies/deployment.toml) written as a
GIF from run folders, read back: frame count, frames that differ (the chain unfolds), every
lock marked; and the refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rodval import simulate
from rodval.cli import main
from rodval.report.run_files import write_run
from rodval.study import load_study

STUDY = Path(__file__).resolve().parents[1] / "studies" / "deployment.toml"


@pytest.fixture(scope="module")
def deployment_runs(tmp_path_factory) -> list[Path]:
    """The shipped deployment scene run by the reduced and the full model (three latches)."""
    scene = load_study(STUDY).cases[0].scene
    folders = []
    for model in ("reduced", "full"):
        folder = tmp_path_factory.mktemp("runs") / model
        write_run(simulate(scene, model), scene, folder)
        folders.append(folder)
    return folders


def test_animate_writes_a_gif_of_the_chain_unfolding_with_locks_marked(
    deployment_runs, tmp_path, capsys
):
    """12 frames over 0..2.5 s, both runs overlaid: the GIF has 12 frames, the first and last
    differ in many pixels (folded vs deployed), and all 6 locks (3 per model) are marked."""
    out = tmp_path / "deploy.gif"
    code = main(["animate", *map(str, deployment_runs), "--out", str(out), "--frames", "12"])
    line = capsys.readouterr().out.strip()
    assert code == 0
    assert line.startswith("12 frames, 6 events marked, t = 0..2.5 s")
    with Image.open(out) as gif:
        assert gif.n_frames == 12
        gif.seek(0)
        first = np.asarray(gif.convert("RGB"), dtype=int)
        gif.seek(11)
        last = np.asarray(gif.convert("RGB"), dtype=int)
    changed = np.mean(np.any(first != last, axis=-1))
    assert changed > 0.01, changed  # the chain moved: > 1 % of the pixels differ


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--out", "x.png"], "--out must end in one of"),
        (["--out", "x.gif", "--frames", "1"], "frames must be an integer in [2,"),
    ],
)
def test_animate_refusals_are_one_line(
    deployment_runs, tmp_path, capsys, monkeypatch, extra, words
):
    """Bad output file or frame count: exit 2, one line naming it, no file written."""
    monkeypatch.chdir(tmp_path)
    assert main(["animate", str(deployment_runs[0]), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and len(err.splitlines()) == 1
    assert not list(tmp_path.glob("x.*"))


def test_animate_bad_fps_is_a_one_line_usage_error(deployment_runs, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["animate", str(deployment_runs[0]), "--out", "x.gif", "--fps", "0"])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "--fps must be an integer in [1, " in err and len(err.splitlines()) == 1
