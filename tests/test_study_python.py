"""Studies built in Python (issue 21): ``rodval.Study.from_dict`` (a dict, [scene] possibly a
``rodval.Scene``) runs, resumes and reports like the same study from TOML, with identical
tables; ``run_study`` takes either; the caller's dict is never changed."""

from __future__ import annotations

import copy
import math
import tomllib

import pandas as pd
import pytest

import rodval
from rodval.report.tables import read_tables
from rodval.study.toml_text import toml_text

DOC = {
    "study": {"name": "py", "reference": "full"},
    "scene": {
        "based_on": "paper",
        "n": 2,
        "t_end": 0.05,
        "times": {"num": 3},
        "outputs": ["phi", "beta"],
    },
    "integrator": {"rtol": 1e-8, "atol": 1e-10},
    "models": {"full": {}, "reduced": {}},
    "grid": {"scene.chain.EI": [1e4, 1e5], "scene.n": [2, 3]},
}
TOML = """
[study]
name = "py"
reference = "full"

[scene]
based_on = "paper"
n = 2
t_end = 0.05
times = { num = 3 }
outputs = ["phi", "beta"]

[integrator]
rtol = 1e-8
atol = 1e-10

[models.full]
[models.reduced]

[grid]
"scene.chain.EI" = [1e4, 1e5]
"scene.n" = [2, 3]
"""

NUMERIC = {"runtime": ["wall_s", "setup_s"]}  # timings differ run to run, nothing else may


def _tables(out):
    t = read_tables(out)
    return {name: df.drop(columns=NUMERIC.get(name, [])) for name, df in t.items()}


def test_a_study_from_a_dict_gives_the_tables_of_the_same_study_from_toml(tmp_path):
    path = tmp_path / "py.toml"
    path.write_text(TOML)
    given = copy.deepcopy(DOC)
    a = rodval.run_study(DOC, tmp_path / "dict", workers=1, progress=False, report=False)
    b = rodval.run_study(path, tmp_path / "toml", workers=1, progress=False, report=False)
    assert DOC == given  # the caller's dict is not changed
    ta, tb = _tables(a.out), _tables(b.out)
    assert set(ta) == set(tb) and len(ta["cases"]) == 4
    for name in ta:
        pd.testing.assert_frame_equal(ta[name], tb[name], check_exact=True, obj=name)
    # study.toml beside the dict study's results reads back to the same study (same cases)
    again = rodval.load_study(a.out / "study.toml")
    from_toml = rodval.load_study(path)
    assert [c.fingerprint for c in again.cases] == [c.fingerprint for c in from_toml.cases]
    # and resumes: nothing is recomputed
    c = rodval.run_study(
        rodval.Study.from_dict(DOC), a.out, workers=1, progress=False, report=False
    )
    assert len(c.reused) == 4 and c.ran == []


def test_a_scene_object_is_a_studys_scene(tmp_path):
    """[scene] may be a rodval.Scene: its cases are the scene's (the same fingerprints as its
    scene-file table)."""
    from rodval.core.scene_file import scene_to_dict

    scene = rodval.paper_scene(n=2, t_end=0.05, times=[0.025, 0.05])
    with_object = rodval.Study.from_dict({"scene": scene, "models": {"reduced": {}}})
    with_table = rodval.Study.from_dict({"scene": scene_to_dict(scene), "models": {"reduced": {}}})
    assert [c.fingerprint for c in with_object.cases] == [c.fingerprint for c in with_table.cases]
    assert with_object.cases[0].scene.n == 2


def test_study_toml_text_round_trips_and_refuses_what_toml_cannot_hold():
    doc = {"a": {"b c": [1, 2.5, math.inf, 'x"y'], "d": True}, "e": [{"f": 1e-300}]}
    back = tomllib.loads(toml_text(doc))
    assert back == doc
    with pytest.raises(ValueError, match=r"a\.g: object .* cannot be written to a study file"):
        toml_text({"a": {"g": object()}})
    with pytest.raises(ValueError, match="a study document must be a dict, got list"):
        rodval.Study.from_dict([1, 2])


def test_study_text_holds_any_unicode_and_refuses_a_lone_surrogate():
    """A study's name in any script round-trips through study.toml; a lone surrogate (JSON
    writes it as an escape TOML readers refuse: the study could not be read back) is refused
    naming the key."""
    doc = {"study": {"name": 'café \\ "q" \t \u0001 \U0001f600', "description": "a\nb"}}
    assert tomllib.loads(toml_text(doc)) == doc
    with pytest.raises(ValueError, match=r"^study.name: text .* holds a lone surrogate"):
        toml_text({"study": {"name": "a\ud800"}})
