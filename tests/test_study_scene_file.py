"""A study's [scene] may name a scene file, ``file = "wing.toml"``, with overrides (issue 37):
the file is read relative to the study file, its load files relative to itself; top-level keys
of [scene] replace the file's, ``chain`` and ``initial`` merge key by key. The cases run and
record the resolved scene; a changed file is a changed study; a bad ``file`` is refused in one
line naming scene.file before any case runs."""

from __future__ import annotations

import errno
import json
import os
import pathlib
import shutil

import pytest

import rodval
from rodval.core.scene_file import load_scene, scene_to_dict

WING = """
name = "wing"
n = 3
t_end = 0.2
outputs = ["phi"]
times = {{ num = 4 }}
[chain]
l = 1.5
m = 3.0
EI = {EI}
mu = 0.5
kappa = [0.0, 50.0, 50.0]
[initial]
phi = [0.0, 0.3, 0.0]
dphi = 0.1
[[loads]]
type = "tabulated"
node = 3
file = "history.csv"
[[latches]]
hinge = 1
angle = -0.2
"""
STUDY = """
[scene]
file = "{file}"
{overrides}
[models.reduced]
{grid}
"""


@pytest.fixture
def folders(tmp_path):
    """scenes/wing.toml (with its load history beside it) and an empty studies/ folder."""
    scenes, studies = tmp_path / "scenes", tmp_path / "studies"
    scenes.mkdir()
    studies.mkdir()
    (scenes / "wing.toml").write_text(WING.format(EI="1e5"))
    (scenes / "history.csv").write_text("t,X,Y\n0,0,0\n0.05,20,10\n0.1,0,0\n")
    return scenes, studies


def study_file(studies, overrides="", grid="", file="../scenes/wing.toml"):
    path = studies / "s.toml"
    path.write_text(STUDY.format(file=file, overrides=overrides, grid=grid))
    return path


def expected_scene(scenes, t_end, EI):
    """The file's scene with t_end and EI changed in its text (an independent route)."""
    text = WING.format(EI=EI).replace("t_end = 0.2", f"t_end = {t_end}")
    (scenes / "expected.toml").write_text(text)
    return load_scene(scenes / "expected.toml")


def test_file_scene_with_overrides_runs_the_files_scene_with_those_changes(folders, tmp_path):
    scenes, studies = folders
    path = study_file(studies, overrides="t_end = 0.05\nchain = { EI = 2e5 }")
    spec = rodval.load_study(path)
    expected = scene_to_dict(expected_scene(scenes, 0.05, "2e5"))
    (case,) = spec.cases
    assert scene_to_dict(case.scene) == expected
    assert case.scene.loads[0].params["X"] == [0.0, 20.0, 0.0]  # the CSV beside the scene
    out = tmp_path / "out"
    res = rodval.run_study(spec, out, workers=1, progress=False, report=False)
    assert res.failed_runs == 0
    record = json.loads(next((out / "cases").glob("*.json")).read_text())
    assert record["scene"] == expected  # the resolved scene, not the path
    meta = json.loads((out / "study.json").read_text())
    assert (
        meta["scene_file"]["path"].endswith("wing.toml") and len(meta["scene_file"]["sha256"]) == 64
    )
    # study.toml beside the results holds the resolved scene: it reruns without the file
    shutil.move(scenes / "wing.toml", tmp_path / "elsewhere.toml")
    again = rodval.load_study(out / "study.toml")
    assert [c.fingerprint for c in again.cases] == [c.fingerprint for c in spec.cases]


def test_a_changed_scene_file_is_a_changed_study(folders, tmp_path):
    scenes, studies = folders
    path = study_file(studies, overrides="t_end = 0.02")
    out = tmp_path / "out"
    rodval.run_study(path, out, workers=1, progress=False, report=False)
    assert rodval.run_study(path, out, workers=1, progress=False, report=False).reused == ["base"]
    (scenes / "wing.toml").write_text(WING.format(EI="1.1e5"))
    with pytest.raises(ValueError, match="the scene file .*wing.toml.* changed") as e:
        rodval.run_study(path, out, workers=1, progress=False, report=False)
    assert "\n" not in str(e.value) and "--fresh" in str(e.value)
    res = rodval.run_study(path, out, workers=1, progress=False, report=False, fresh=True)
    assert res.ran == ["base"]


def test_chain_and_initial_merge_key_by_key_and_lists_replace(folders):
    scenes, studies = folders
    path = study_file(
        studies,
        overrides="initial = { dphi = 0.0 }\nlatches = []\nchain = { mu = 0.0 }",
        file=str(scenes / "wing.toml"),  # an absolute path
    )
    scene = rodval.load_study(path).cases[0].scene
    assert scene.latches == () and list(scene.chain.mu) == [0.0] * 3
    assert list(scene.chain.kappa) == [0.0, 50.0, 50.0]  # the file's
    assert scene.initial.resolve(3)["phi"][1] == 0.3 and not scene.initial.resolve(3)["dphi"].any()


def test_a_grid_over_a_chain_field_of_a_file_scene(folders):
    scenes, studies = folders
    path = study_file(studies, grid='[grid]\n"scene.chain.EI" = [1e4, 3e4]')
    spec = rodval.load_study(path)
    base = load_scene(scenes / "wing.toml")
    for case, EI in zip(spec.cases, (1e4, 3e4)):
        assert scene_to_dict(case.scene) == scene_to_dict(base.with_(chain=base.chain.with_(EI=EI)))
    with pytest.raises(ValueError, match="key 'grid.scene.file': the scene file is read once"):
        rodval.load_study(study_file(studies, grid='[grid]\n"scene.file" = ["a.toml", "b.toml"]'))


def test_a_python_study_reads_its_scene_file_from_the_current_folder(folders, monkeypatch):
    scenes, _ = folders
    monkeypatch.chdir(scenes)
    doc = {"scene": {"file": "wing.toml", "t_end": 0.05}, "models": {"reduced": {}}}
    spec = rodval.Study.from_dict(doc)
    assert spec.cases[0].scene.t_end == 0.05 and spec.cases[0].scene.n == 3


@pytest.mark.parametrize(
    "file, overrides, problem",
    [
        ("missing.toml", "", r"'.*missing\.toml' does not exist"),
        (".", "", "is not a file"),
        ("../scenes/binary.toml", "", "malformed TOML"),
        ("../scenes/wing.toml", 'based_on = "paper"', "cannot be combined with based_on"),
    ],
)
def test_a_bad_scene_file_is_refused_in_one_line(folders, file, overrides, problem):
    scenes, studies = folders
    (scenes / "binary.toml").write_bytes(b"\xff\xfe\x00n = 3")
    with pytest.raises(ValueError, match=f"s.toml: key 'scene.file': .*{problem}") as e:
        rodval.load_study(study_file(studies, overrides=overrides, file=file))
    assert "\n" not in str(e.value)


def test_a_scene_file_that_is_not_a_string_or_cannot_be_read_is_refused(folders, monkeypatch):
    _, studies = folders
    path = studies / "s.toml"
    path.write_text("[scene]\nfile = 3\n[models.reduced]\n")
    with pytest.raises(ValueError, match=r"key 'scene.file': must be the path of a scene file"):
        rodval.load_study(path)
    path = study_file(studies)

    def denied(self):  # what reading a file without read permission raises (root reads it)
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))

    monkeypatch.setattr(pathlib.Path, "read_bytes", denied)
    with pytest.raises(ValueError, match=r"key 'scene.file': cannot read .*Permission denied"):
        rodval.load_study(path)
