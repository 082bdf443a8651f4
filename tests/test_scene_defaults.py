"""Issue 36: a scene file holds what it says. What it omits is a physically neutral default
(no loads, no node masses, no hinge springs or dampers, straight at rest, pinned) or an error
naming the missing key; the paper's example data only with ``based_on = "paper"``."""

import numpy as np
import pytest

from rodval import Chain, InitialState, paper_scene
from rodval.core.scene import DEFAULT_NUM_TIMES, Scene
from rodval.core.scene_file import (
    load_scene,
    read_scene_document,
    scene_from_dict,
    scene_to_dict,
)
from rodval.study.spec import StudySpec, load_study

WING = """
n = 3
t_end = 1.5

[chain]
l = 1.5
m = 2.0
EI = 5e3
"""


def _wing(tmp_path, text: str = WING, name: str = "wing.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_user_file_without_loads_has_no_loads_masses_springs_or_dampers(tmp_path):
    scene = load_scene(_wing(tmp_path))
    assert scene.loads == ()
    chain = scene.chain
    for field in ("mu", "kappa", "nu", "rest_angle", "bending_damping"):
        np.testing.assert_array_equal(getattr(chain, field), np.zeros(3), err_msg=field)
    np.testing.assert_array_equal(chain.l, [1.5] * 3)
    np.testing.assert_array_equal(chain.m, [2.0] * 3)
    np.testing.assert_array_equal(chain.EI, [5e3] * 3)
    assert scene.latches == () and scene.stops == () and not scene.base.free
    assert scene.outputs == Scene.outputs  # the class default: outputs are not physics
    assert scene.times.size == DEFAULT_NUM_TIMES and scene.times[-1] == 1.5
    assert scene.name == "wing"
    assert all(not np.any(v) for v in scene.initial.resolve(3).values())


def test_a_dict_without_a_name_is_called_scene():
    d = {"n": 2, "t_end": 1.0, "chain": {"l": 1.0, "m": 1.0, "EI": 1.0}}
    assert scene_from_dict(d).name == "scene"


@pytest.mark.parametrize(
    "drop,key",
    [
        ("n", "n"),
        ("t_end", "t_end"),
        ("l", "chain.l"),
        ("m", "chain.m"),
        ("EI", "chain.EI"),
    ],
)
def test_a_missing_required_key_is_refused_naming_it(tmp_path, drop, key):
    text = "\n".join(line for line in WING.splitlines() if not line.startswith(f"{drop} ="))
    with pytest.raises(ValueError) as err:
        load_scene(_wing(tmp_path, text))
    msg = str(err.value)
    assert "\n" not in msg
    assert msg.startswith(str(tmp_path / "wing.toml"))
    assert f"key '{key}'" in msg and "missing" in msg
    assert 'based_on = "paper"' in msg


def test_a_file_without_a_chain_table_names_the_first_rod_key():
    with pytest.raises(ValueError, match=r"wing.toml: key 'chain.l' .* is missing"):
        scene_from_dict({"n": 2, "t_end": 1.0}, where="wing.toml")


def test_based_on_paper_gives_exactly_the_papers_scene():
    for doc, expected in (
        ({"based_on": "paper"}, paper_scene()),
        ({"based_on": "paper", "n": 3, "t_end": 1.0}, paper_scene(3, t_end=1.0)),
    ):
        scene = scene_from_dict(doc)
        assert scene.chain == expected.chain
        assert scene_to_dict(scene) == scene_to_dict(expected)
        assert scene.outputs == expected.outputs
        np.testing.assert_array_equal(scene.times, expected.times)
        assert [(f.name, f.node, f.params) for f in scene.loads] == [
            (f.name, f.node, f.params) for f in expected.loads
        ]


def test_based_on_paper_takes_the_file_over_the_paper():
    scene = scene_from_dict({"based_on": "paper", "n": 3, "t_end": 1.0, "chain": {"mu": 0.0}})
    assert scene.chain == paper_scene(3).chain.with_(mu=0.0)
    assert scene.loads[0].node == 3


def test_paper_as_a_source_is_based_on_paper():
    assert read_scene_document("paper") == {"based_on": "paper"}
    assert scene_to_dict(load_scene("paper")) == scene_to_dict(paper_scene())


def test_the_old_string_base_is_refused_naming_based_on():
    with pytest.raises(ValueError) as err:
        scene_from_dict({"base": "paper", "n": 2, "t_end": 1.0}, where="old.toml")
    msg = str(err.value)
    assert msg.startswith("old.toml") and "key 'base'" in msg
    assert 'based_on = "paper"' in msg and "\n" not in msg


def test_a_wrong_based_on_is_refused_naming_the_allowed_values():
    with pytest.raises(ValueError, match=r"x.toml key 'based_on': .*'paper'.*got 'papers'"):
        scene_from_dict({"based_on": "papers"}, where="x.toml")


def test_the_resolved_scene_rebuilds_without_based_on():
    scene = paper_scene(3, t_end=1.0, times=[0.5, 1.0]).with_(
        chain=paper_scene(3).chain.with_(rest_angle=0.1, bending_damping=2.0)
    )
    d = scene_to_dict(scene)
    assert "based_on" not in d and set(d["chain"]) == set(Chain.FIELDS)
    again = scene_from_dict(d)
    assert scene_to_dict(again) == d and again.chain == scene.chain


def test_an_older_record_without_the_newer_chain_fields_reads_them_as_zero():
    d = scene_to_dict(paper_scene(3, t_end=1.0))
    for key in ("rest_angle", "bending_damping"):
        del d["chain"][key]
    chain = scene_from_dict(d).chain
    assert chain == paper_scene(3).chain  # the paper's values of both are 0 too


def test_initial_state_refuses_an_unknown_key_with_a_value_error():
    with pytest.raises(ValueError, match=r"gamma.*allowed: alpha, beta, dalpha, dbeta, dphi, phi"):
        InitialState(gamma=1.0)  # type: ignore[call-arg]
    assert InitialState(phi=[0.1]).resolve(1)["phi"][0] == 0.1


def test_chain_refuses_an_unknown_key_with_a_value_error():
    with pytest.raises(ValueError, match=r"gamma.*allowed: .*EI"):
        Chain(l=1.0, m=1.0, EI=1.0, mu=0.0, kappa=0.0, nu=0.0, gamma=1.0)  # type: ignore[call-arg]


STUDY = """
[study]
name = "own_wing"

[scene]
{scene}

[models.reduced]
"""


def test_a_study_scene_without_based_on_holds_what_it_says(tmp_path):
    path = tmp_path / "own.toml"
    path.write_text(
        STUDY.format(scene="n = 2\nt_end = 0.5\nchain = { l = 1.0, m = 2.0, EI = 1e4 }")
    )
    scene = load_study(path).cases[0].scene
    assert scene.loads == () and not np.any(scene.chain.mu) and not np.any(scene.chain.kappa)


def test_a_study_scene_missing_a_rod_key_is_refused(tmp_path):
    path = tmp_path / "own.toml"
    path.write_text(STUDY.format(scene="n = 2\nt_end = 0.5\nchain = { l = 1.0, EI = 1e4 }"))
    with pytest.raises(ValueError, match=r"own.toml \[scene\]: key 'chain.m' .* is missing"):
        load_study(path)


def test_a_study_based_on_paper_with_a_grid_gives_the_papers_scenes():
    spec = StudySpec.from_dict(
        {
            "scene": {"based_on": "paper", "t_end": 1.0, "times": [1.0]},
            "models": {"reduced": {}},
            "grid": {"scene": {"n": [2, 3]}},
        }
    )
    for case, n in zip(spec.cases, (2, 3)):
        expected = paper_scene(n, t_end=1.0, times=[1.0])
        assert scene_to_dict(case.scene) == {**scene_to_dict(expected), "name": case.id}


def test_a_study_refuses_the_old_string_base(tmp_path):
    path = tmp_path / "old.toml"
    path.write_text(STUDY.format(scene='base = "paper"\nn = 2\nt_end = 0.5'))
    with pytest.raises(ValueError, match=r"old.toml \[scene\] key 'base'.*based_on"):
        load_study(path)
