"""Regressions found by the fuzz suite at 2000 examples (issue 17): every wrong argument is a
one-line ValueError naming it, never numpy's "truth value of an array is ambiguous", a
TypeError from deep inside, or a value coerced silently; runs of different scenes are not
compared without a word in Python either."""

from __future__ import annotations

import json

import numpy as np
import pytest
from checks import assert_refused, run_main

import rodval
from rodval import Chain, paper_scene

SCENE = paper_scene(n=2, t_end=0.05, times=[0.025, 0.05])
ARRAY = np.array([1.0, 2.0])


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"kernel": ARRAY}, r"^kernel must be one of \('numba', 'numpy'\)"),
        ({"coefficients": ARRAY}, r"^coefficients must be one of"),
        ({"coefficients": None}, r"^coefficients must be one of"),
    ],
)
def test_model_options_of_the_wrong_type_are_named(kwargs, words):
    with pytest.raises(ValueError, match=words):
        rodval.simulate(SCENE, "reduced", **kwargs)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"case_timeout": ARRAY}, r"^case_timeout must be a finite number > 0 s or None"),
        ({"case_timeout": ""}, r"^case_timeout must be a finite number > 0 s or None"),
        ({"case_timeout": float("inf")}, r"^case_timeout must be a finite number > 0 s or None"),
        ({"backend": ARRAY}, r"^backend must be one of"),
    ],
)
def test_study_arguments_of_the_wrong_type_are_named(tmp_path, kwargs, words):
    doc = {"scene": {"based_on": "paper", "n": 2, "t_end": 0.05}, "models": {"reduced": {}}}
    with pytest.raises(ValueError, match=words):
        rodval.run_study(doc, tmp_path / "out", **kwargs)
    assert not (tmp_path / "out").exists()


def test_a_study_out_that_is_a_file_is_refused(tmp_path):
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"\x00\x01")
    doc = {"scene": {"based_on": "paper", "n": 2, "t_end": 0.05}, "models": {"reduced": {}}}
    with pytest.raises(ValueError, match=r"^out must be a folder, got the file"):
        rodval.run_study(doc, junk)
    assert junk.read_bytes() == b"\x00\x01"


def test_scene_outputs_none_and_modes_arrays_are_named():
    with pytest.raises(ValueError, match=r"^outputs must be a non-empty subset"):
        SCENE.with_(outputs=None)
    with pytest.raises(ValueError, match=r"^outputs must be a non-empty subset"):
        paper_scene(n=2, outputs=None)
    with pytest.raises(ValueError, match=r"^about must be one of"):
        rodval.modes(SCENE, "full", about=ARRAY)
    with pytest.raises(ValueError, match=r"^model must be one of"):
        rodval.modes(SCENE, ARRAY)


def test_a_boolean_or_a_nested_list_among_chain_values_is_refused():
    """An edited run.json with mu = [false, 3.0] ran with mu = 0 (bool coerced); l = [[], 2.0]
    ended in numpy's 'inhomogeneous shape' message."""
    for bad in ([False, 3.0], [[], 2.0], ["1", 2.0]):
        with pytest.raises(ValueError, match=r"^mu \(node mass\) must be a real number or a list"):
            Chain.uniform(2, mu=bad)


def test_python_compare_refuses_runs_of_different_scenes():
    a = rodval.simulate(SCENE, "reduced")
    b = rodval.simulate(SCENE.with_(chain=SCENE.chain.with_(EI=1e3)), "reduced")
    with pytest.raises(ValueError, match=r"different scenes \(chain\.EI differ\).*allow_different"):
        rodval.compare(a, b)
    assert len(rodval.compare(a, b, allow_different_scenes=True)) > 0
    same = rodval.simulate(SCENE, "full")
    assert np.isfinite(rodval.compare(same, a)["max_abs"]).all()  # same scene, other model


def test_edited_run_json_events_and_binary_tables_are_named(tmp_path, capsys):
    for label in ("A", "B"):
        assert (
            rodval.cli.main(
                [
                    "simulate",
                    "paper",
                    "--t-end",
                    "0.05",
                    "--model",
                    "reduced",
                    "--out",
                    str(tmp_path / label),
                ]
            )
            == 0
        )
    rec = json.loads((tmp_path / "A" / "run.json").read_text())
    rec["events"] = 0
    (tmp_path / "A" / "run.json").write_text(json.dumps(rec))
    capsys.readouterr()
    proc = run_main(
        capsys, "compare", str(tmp_path / "A"), str(tmp_path / "B"), "--out", str(tmp_path / "c")
    )
    assert_refused(proc, ["run.json", "'events' must be a list of tables"])


def test_a_binary_table_is_refused_in_rodvals_words(tmp_path, capsys):
    doc = {"scene": {"based_on": "paper", "n": 2, "t_end": 0.05}, "models": {"reduced": {}}}
    res = rodval.run_study(doc, tmp_path / "s", workers=1, progress=False)
    (res.out / "cases.csv").write_bytes(b"\x80\x81")
    proc = run_main(capsys, "report", str(res.out))
    assert_refused(proc, ["cases.csv", "byte 0 is not UTF-8 text"])
    assert "codec" not in proc.stderr


def test_a_quantity_of_the_wrong_type_is_named():
    traj = rodval.simulate(SCENE, "reduced")
    with pytest.raises(KeyError, match=r"quantity \[\] is not in this trajectory"):
        traj[[]]


def test_a_first_step_beyond_the_horizon_is_refused_before_the_run():
    """It failed at run time as 'ValueError: `first_step` exceeds bounds' reported as a
    failed run (exit 1), i.e. an input error found after the work began."""
    with pytest.raises(ValueError, match=r"^first_step must be at most the horizon t_end = 0.05 s"):
        rodval.simulate(SCENE, "reduced", method="RK45", first_step=1.0)


def test_run_json_records_the_method_asked_for_whatever_it_is(tmp_path):
    """An explicit method was recorded only as 'method'; a rerun of an edited
    requested_method then had nothing to compare with."""
    traj = rodval.simulate(SCENE, "reduced", method="RK45")
    assert traj.settings["requested_method"] == "RK45" == traj.settings["method"]


def test_unhashable_names_in_files_are_refused_in_one_line(tmp_path):
    """An edited run.json with a load "type": [] ended in 'unhashable type: list'."""
    from rodval.core.scene_file import scene_from_dict
    from rodval.study.sampling import check_distribution

    wrong_type = r"key 'loads\.0\.type': must be a string \(`pulse`, .*got list \[\]"
    with pytest.raises(ValueError, match=wrong_type):
        scene_from_dict(
            {"based_on": "paper", "n": 2, "loads": [{"type": [], "node": 1}]}, where="s"
        )
    with pytest.raises(ValueError, match=r"model must be one of"):
        rodval.Study.from_dict({"models": {"a": {"model": ["full"]}}})
    with pytest.raises(ValueError, match=r"must be a table with dist"):
        check_distribution("k", {"dist": ["uniform"]})
