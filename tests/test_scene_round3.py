"""Issue 46, scene values: every scene-file and API value type-checked at the boundary (one
key table, ``rodval.core.scene_keys``, drives the check and docs/scene_file.md), the advice
for ``base = "free"``, a study file named as a scene file, ``--max-wall inf``, scene values
overridden on the command line (``--set chain.EI=2e8``), scene files ``based_on`` another,
and a verdict's fix in both spellings."""

import json
import math
from pathlib import Path

import pytest

from rodval.cli import main
from rodval.cli.options import positive_float
from rodval.core import loads
from rodval.core.motion import Motion
from rodval.core.scene import Chain
from rodval.core.scene_file import load_scene, scene_from_dict
from rodval.core.scene_keys import SCENE_KEYS, STRING, TABLES, set_path, with_doc_table
from rodval.core.validity import setting, step_resolution

ROOT = Path(__file__).resolve().parents[1]
SCENE = "n = 3\nt_end = 0.05\n[chain]\nl = 1.0\nm = 1.0\nEI = 1e4\nkappa = 10.0\n"


@pytest.mark.parametrize("value", [5, [1, 2], True, "x"])
def test_chain_of_a_wrong_type_is_one_line_naming_the_key(value):
    """`chain = 5`, `[1, 2]`, `true` were an internal error (TypeError), `"x"` a raw
    dict-update message."""
    with pytest.raises(ValueError, match=r"^f.toml key 'chain': must be a table, got "):
        scene_from_dict({"based_on": "paper", "chain": value}, "f.toml")


def _leaves(keys, prefix=""):
    for name, key in keys.items():
        path = f"{prefix}{name}"
        yield path, key
        yield from _leaves(key.keys, f"{path}.0." if key.kind is TABLES else f"{path}.")


@pytest.mark.parametrize("path,key", list(_leaves(SCENE_KEYS)), ids=lambda p: str(p)[:40])
def test_every_key_of_the_table_is_type_checked_naming_it(path, key):
    """Each key of the table, given a value of another type, is refused in one line naming
    its dotted path, before anything is built (free base keys on a pinned scene included)."""
    item = {"hinge": 1, "angle": 0.3}
    load = {"type": "constant", "node": 1}
    doc = {"based_on": "paper", "latches": [item], "stops": [dict(item)], "loads": [load]}
    doc["motors"] = [{"hinge": 1, "stall_torque": 1.0, "no_load_speed": 1.0}]
    doc["rate_dampers"] = [{"hinge": 1, "damping": 1.0}]
    doc["compliant_latches"] = [{"hinge": 2, "angle": 0.3, "stiffness": 1e4}]
    bad = 5 if key.kind is STRING or path == "base" else "x"
    set_path(doc, path, bad)
    with pytest.raises(ValueError) as err:
        scene_from_dict(doc, "f.toml")
    msg = str(err.value)
    assert "\n" not in msg
    within = f" ({key.allowed})" if key.allowed else ""
    assert msg.startswith(f"f.toml key '{path}': must be {key.kind.words}{within}, got "), msg


def test_required_keys_of_array_tables_are_named():
    """A latch without its angle: the key by its path, not Latch.__init__'s TypeError text."""
    with pytest.raises(ValueError, match=r"key 'latches.0.angle': is missing"):
        scene_from_dict({"based_on": "paper", "latches": [{"hinge": 1}]}, "f.toml")


def test_docs_key_table_is_the_generated_one():
    """docs/scene_file.md holds the table ``SCENE_KEYS`` generates (regenerate: python -m
    rodval.core.scene_keys --write docs/scene_file.md)."""
    text = (ROOT / "docs" / "scene_file.md").read_text()
    assert with_doc_table(text) == text


@pytest.mark.parametrize("params", [1.0, None, 5, "abc"])
def test_motion_params_of_a_wrong_type_are_a_value_error(params):
    """Motion("constant", 1.0) and Motion("constant", None) raised TypeError."""
    with pytest.raises(ValueError, match=r"motion params must be a tuple of numbers \(value\)"):
        Motion("constant", params)


@pytest.mark.parametrize(
    "build,match",
    [
        (lambda: loads.tabulated(1, file=5), "tabulated file must be a path"),
        (lambda: loads.NodalForce(1, breakpoints=1.0), "load breakpoints must be a tuple"),
        (lambda: Chain(1.0, 1.0, 1.0, 0.0, 0.0, 0.0, _n="x"), "n \\(number of rods\\) must be"),
    ],
)
def test_api_constructors_refuse_wrong_types_with_value_errors(build, match):
    """The hostile sweep of the API constructors: these raised TypeError."""
    with pytest.raises(ValueError, match=match):
        build()


@pytest.mark.parametrize("kind", ["free", "pinned", "prescribed"])
def test_a_base_kind_as_a_top_level_string_gets_the_table_advice(kind):
    """`base = "free"` got the advice meant for `base = "paper"` (write based_on)."""
    with pytest.raises(ValueError, match=rf'write \[base\] kind = "{kind}"') as err:
        scene_from_dict({"base": kind, "n": 2, "t_end": 1.0}, "f.toml")
    assert "based_on" not in str(err.value)


def test_a_study_file_named_as_scene_file_is_named(tmp_path):
    """`[scene] file` naming a study file said "unknown key 'grid'" without naming it."""
    from rodval.study import load_study

    other = tmp_path / "other.toml"
    other.write_text(
        '[study]\nreference = "full"\n[scene]\nbased_on = "paper"\n[models.full]\n'
        'model = "full"\n[grid]\n"scene.n" = [2, 3]\n'
    )
    study = tmp_path / "study.toml"
    study.write_text(
        '[study]\nreference = "full"\n[scene]\nfile = "other.toml"\n[models.full]\nmodel = "full"\n'
    )
    with pytest.raises(ValueError, match=r"other.toml' is a study file \(it has \[grid\]\)"):
        load_study(study)


def test_max_wall_inf_is_accepted_as_the_message_promises():
    """--max-wall inf was refused with "must be a number > 0 (inf allowed), got 'inf'"."""
    assert positive_float("--max-wall", finite=False)("inf") == math.inf
    assert positive_float("--max-step", finite=False)("inf") == math.inf


def _simulate(tmp_path, scene: Path, *extra: str) -> dict:
    out = tmp_path / "run"
    assert main(["simulate", str(scene), "--out", str(out), *extra]) == 0
    return json.loads((out / "run.json").read_text())


def test_set_overrides_scene_values_and_run_json_records_them(tmp_path, capsys):
    """`--set chain.EI=2e8` (and the grid's spelling scene.t_end) overrides the scene; a model
    option beside it stays a model option; run.json holds the scene that ran."""
    scene = tmp_path / "wing.toml"
    scene.write_text(SCENE)
    record = _simulate(
        tmp_path,
        scene,
        "--set",
        "chain.EI=2e8",
        "--set",
        "scene.t_end=0.02",
        "--set",
        "latches=[{hinge = 1, angle = 0.5}]",
        "--set",
        "kernel=numba",
        "--max-wall",
        "inf",
    )
    assert record["scene"]["chain"]["EI"] == [2e8] * 3
    assert record["scene"]["chain"]["kappa"] == [10.0] * 3
    assert record["scene"]["t_end"] == 0.02
    assert record["scene"]["latches"][0]["angle"] == 0.5
    assert record["options"]["kernel"] == "numba"


@pytest.mark.parametrize(
    "pair,match",
    [
        ("chain.EI=abc", r"key 'chain.EI': must be a number"),
        ("chain=5", r"key 'chain': must be a table, got int 5"),
        ("chain.EI=-1.0", r"EI \(bending stiffness\) must be > 0"),
        ("n.x=1", r"--set n.x: 'x' goes into 3"),
    ],
)
def test_set_scene_values_are_checked_like_the_files(tmp_path, capsys, pair, match):
    scene = tmp_path / "wing.toml"
    scene.write_text(SCENE)
    assert main(["simulate", str(scene), "--set", pair, "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert pytest.importorskip("re").search(match, err), err
    assert not (tmp_path / "r").exists()


def test_set_t_end_beside_t_end_option_is_refused(tmp_path, capsys):
    scene = tmp_path / "wing.toml"
    scene.write_text(SCENE)
    args = ["simulate", str(scene), "--set", "t_end=0.02", "--t-end", "0.03"]
    assert main([*args, "--out", str(tmp_path / "r")]) == 2
    assert "--set t_end and --t-end both given" in capsys.readouterr().err


def test_based_on_another_scene_file_merges_key_by_key(tmp_path):
    """A variant starts from wing.toml (relative to its own folder): [chain] merged key by
    key, the later file winning; the name is the variant's file name."""
    (tmp_path / "base").mkdir()
    (tmp_path / "base" / "wing.toml").write_text(
        SCENE + '[[loads]]\ntype = "constant"\nnode = 3\nY = 1.0\n'
    )
    (tmp_path / "stiff.toml").write_text('based_on = "base/wing.toml"\n[chain]\nEI = 2e4\n')
    scene = load_scene(tmp_path / "stiff.toml")
    assert scene.chain.EI.tolist() == [2e4] * 3
    assert scene.chain.kappa.tolist() == [10.0] * 3
    assert len(scene.loads) == 1 and scene.n == 3
    assert scene.name == "stiff"


def test_based_on_a_chain_ending_at_paper(tmp_path):
    (tmp_path / "a.toml").write_text('based_on = "paper"\nn = 4\n')
    (tmp_path / "b.toml").write_text('based_on = "a.toml"\nt_end = 0.5\n')
    scene = load_scene(tmp_path / "b.toml")
    assert (scene.n, scene.t_end, scene.chain.EI[0]) == (4, 0.5, 1e5)


def test_based_on_loops_and_missing_files_are_refused_naming_the_files(tmp_path):
    (tmp_path / "a.toml").write_text('based_on = "b.toml"\n')
    (tmp_path / "b.toml").write_text('based_on = "a.toml"\n')
    with pytest.raises(
        ValueError, match=r"start from each other: .*a.toml -> .*b.toml -> .*a.toml"
    ):
        load_scene(tmp_path / "a.toml")
    (tmp_path / "c.toml").write_text('based_on = "nowhere.toml"\n')
    with pytest.raises(ValueError, match=r"c.toml key 'based_on': .*nowhere.toml' is not a scene"):
        load_scene(tmp_path / "c.toml")


def test_based_on_depth_is_bounded(tmp_path):
    for i in range(20):
        (tmp_path / f"s{i}.toml").write_text(f'based_on = "s{i + 1}.toml"\n')
    (tmp_path / "s20.toml").write_text(SCENE)
    with pytest.raises(ValueError, match=r"more than 16 files start from one another"):
        load_scene(tmp_path / "s0.toml")


def test_a_fix_is_given_in_both_spellings():
    """A verdict's fix was in file syntax only (`kinematics = "exact"`)."""
    assert setting("kinematics", "exact") == (
        'kinematics = "exact" (command line: --set kinematics=exact)'
    )
    assert setting("rtol", 1e-10, "integrator").endswith("(command line: --rtol 1e-10)")
    assert setting("chain.bending_damping", "{ ratio = 0.01 }", "scene") == (
        "[chain] bending_damping = { ratio = 0.01 } "
        "(command line: --set chain.bending_damping={ratio=0.01})"
    )
    (coarse,) = step_resolution(0.4, 0.1, step=2e-4)
    assert "fix: step = 5e-05 (command line: --set step=5e-05)" in coarse.reason()


@pytest.mark.parametrize("value", ["array", "text"])
def test_a_prescribed_base_given_a_position_of_any_type_names_it(value):
    """A fuzz find: Base(kind="prescribed", position=np.array([1.0])) raised numpy's "truth
    value of an array is ambiguous"; a position in any form is refused naming it (the laws
    give a prescribed base its position), the default's numbers in another form accepted."""
    import numpy as np

    from rodval.core.base import Base

    given = np.array([1.0]) if value == "array" else "x"
    with pytest.raises(ValueError, match=r"^base position: a prescribed base"):
        Base(kind="prescribed", position=given)
    assert Base(kind="prescribed", position=[0.0, 0.0]).prescribed
