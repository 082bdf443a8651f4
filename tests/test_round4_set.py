"""Issue 54: ``--set`` takes scene values, model options and integrator settings on every
command that has it (simulate, modes), each VALUE read as exactly one TOML value (or a bare
word) and checked like the file's; an error in a ``based_on`` file names that file; a later
file's ``[base]`` of another kind replaces the earlier base; a required key of an inline
table that is missing is said to be missing, with its range."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pandas as pd
import pytest

from rodval.cli import main
from rodval.cli.options import key_value
from rodval.core.scene_file import load_scene, scene_from_dict
from rodval.core.scene_keys import merge_documents
from rodval.models.observation.linear_modes import modes
from rodval.study.spec import StudySpec

#: A two-rod chain over 5 ms: the cheapest run that reaches every part of ``simulate``.
TINY = ["--set", "n=2", "--t-end", "0.005", "--times", "0,0.005"]

WING = "n = 3\nt_end = 0.5\n[chain]\nl = 1.2\nm = 6.7\nEI = 2e4\n"
FREE = WING + "[base]\nkind = 'free'\nmass = 100.0\ninertia = 10.0\n"
SHAKE = "x = { law = 'harmonic', amplitude = 0.01, omega = 10.0, phase = 0.0 }\n"
PRESCRIBED = WING + "[base]\nkind = 'prescribed'\n[base.motion]\n" + SHAKE


def _error(capsys) -> str:
    """The one line a refused command printed (stderr), checked to be one line."""
    err = capsys.readouterr().err.strip()
    assert "\n" not in err, err
    return err


# ---------------------------------------------------------------- 1. integrator settings


def test_set_of_integrator_settings_runs_with_them(tmp_path, capsys):
    """`--set rtol=1e-6`, `--set max_wall_s=...`, `--set error_control=per-block` ended in the
    API's "give integrator settings either as settings= or as keywords, not both"."""
    out = tmp_path / "run"
    sets = ["rtol=1e-6", "max_wall_s=600", "error_control=per-block", "block_frequency=2e3"]
    argv = ["simulate", "paper", "--model", "reduced", *TINY, "--out", str(out)]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 0, capsys.readouterr().err
    settings = json.loads((out / "run.json").read_text())["settings"]
    assert settings["rtol"] == 1e-6
    assert settings["error_control"] == "per-block"
    assert settings["block_frequency"] == 2e3
    assert settings["max_wall_s"] == 600  # the command's budget, as --max-wall records it


@pytest.mark.parametrize(
    ("flag", "setting"),
    [("--rtol=1e-7", "rtol=1e-6"), ("--max-wall=5", "max_wall_s=9"), ("--rtol=1e-8", "rtol=1e-6")],
)
def test_a_setting_given_by_its_flag_and_by_set_is_refused(tmp_path, capsys, flag, setting):
    """Never one of the two winning silently (the flag at its default value included)."""
    argv = ["simulate", "paper", *TINY, flag, "--set", setting, "--out", str(tmp_path / "r")]
    assert main(argv) == 2
    err = _error(capsys)
    assert f"--set {setting.split('=')[0]}" in err and flag.split("=")[0] in err


@pytest.mark.parametrize(
    ("setting", "says"),
    [
        ("rtol=1e-20", "--set rtol: rtol must be a number in (0, 1)"),
        ("error_control=blocky", "--set error_control: error_control must be one of"),
        ("max_evaluations=1e6", "--set max_evaluations: max_evaluations must be an integer"),
    ],
)
def test_a_bad_setting_of_set_is_refused_naming_it(tmp_path, capsys, setting, says):
    """Checked by IntegratorSettings like [integrator]'s (1e6 is a float there too)."""
    argv = ["simulate", "paper", "--set", setting, "--out", str(tmp_path / "r")]
    assert main(argv) == 2
    assert says in _error(capsys)


def test_a_flag_at_its_default_value_overrides_a_rerun(tmp_path, capsys):
    """`--rtol 1e-8` (the default) on the rerun of an rtol = 1e-6 run was dropped as "not
    given", so the rerun ran at 1e-6: the flag given is the setting that runs."""
    first, second = tmp_path / "a", tmp_path / "b"
    argv = ["simulate", "paper", "--model", "reduced", *TINY, "--rtol", "1e-6"]
    assert main([*argv, "--out", str(first)]) == 0, capsys.readouterr().err
    rerun = ["simulate", str(first / "run.json"), "--rtol", "1e-8", "--out", str(second)]
    assert main(rerun) == 0, capsys.readouterr().err
    assert json.loads((second / "run.json").read_text())["settings"]["rtol"] == 1e-8


def test_modes_refuses_an_integrator_setting_saying_why(tmp_path, capsys):
    argv = ["modes", "paper", "--model", "reduced", "--set", "rtol=1e-6"]
    assert main([*argv, "--out", str(tmp_path / "m")]) == 2
    err = _error(capsys)
    assert "--set rtol is an integrator setting" in err and "rodval simulate" in err


@pytest.mark.parametrize("setting", ["rtol", "error_control"])
def test_a_setting_among_a_study_scenes_keys_says_where_it_goes(tmp_path, setting):
    """`[scene] rtol = 1e-6` was "unknown key 'rtol'" with the scene keys listed."""
    (tmp_path / "wing.toml").write_text(WING)
    for scene in ({"file": str(tmp_path / "wing.toml")}, {"based_on": "paper"}):
        doc = {"scene": {**scene, setting: 1e-6}, "models": {"full": {}}}
        with pytest.raises(ValueError, match=rf"key '{setting}': an integrator setting, not a"):
            StudySpec.from_dict(doc)


# ------------------------------------------------------------------ 2. one TOML value


@pytest.mark.parametrize(
    "text",
    [
        "chain.EI=2e8\nfoo = 1",
        "chain.EI=2e8\n[chain]\nm = 1",
        "elements=8\nfoo = 1",
        "kinematics=exact\nfoo=1",
        'step="auto',
        "chain.EI=[1, 2",
        "chain.EI=",
        "rtol=",
    ],
)
def test_set_refuses_anything_but_one_toml_value(text):
    """`--set $'chain.EI=2e8\\nfoo = 1'` kept 2e8 and dropped the rest silently."""
    with pytest.raises(argparse.ArgumentTypeError, match=r"^--set \S+: VALUE must be one TOML"):
        key_value(text)


@pytest.mark.parametrize("text", ["=5", "chain.EI", " =1"])
def test_set_without_a_key_is_refused_naming_set(text):
    """`--set =5` was the model option '' ("unknown full model option ''")."""
    with pytest.raises(argparse.ArgumentTypeError, match=r"^--set expects KEY=VALUE"):
        key_value(text)


def test_set_of_more_than_one_value_is_one_line_on_the_command_line(tmp_path, capsys):
    argv = ["simulate", "paper", "--set", "chain.EI=2e8\nfoo = 1", "--out", str(tmp_path / "r")]
    with pytest.raises(SystemExit) as exit_:
        main(argv)  # the parser's error: exit 2
    assert exit_.value.code == 2
    assert "--set chain.EI: VALUE must be one TOML value" in _error(capsys)


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ('step="auto"', "auto"),  # 3: the quoted text form docs/scene_file.md gives
        ("step='auto'", "auto"),
        ("step=auto", "auto"),  # a bare word is text
        ("kinematics=first-order", "first-order"),
        ("elements=8", 8),
        ("step=2e-4", 2e-4),
        ("chain.EI=2e8  # stiffer", 2e8),
        ("chain.bending_damping={ ratio = 0.01 }", {"ratio": 0.01}),
        ("name=my wing", "my wing"),
    ],
)
def test_set_reads_one_toml_value_or_a_bare_word(text, value):
    assert key_value(text)[1] == value


def test_quoted_step_auto_reaches_the_exudyn_model_as_auto():
    """`--set 'step="auto"'` was handed to exudyn as the text '"auto"' and refused."""
    from rodval.cli import build_parser
    from rodval.cli.options import model_options

    args = build_parser(("simulate",)).parse_args(
        ["simulate", "paper", "--model", "exudyn", "--set", 'step="auto"', "--out", "x"]
    )
    assert model_options(args) == {"step": "auto"}


@pytest.mark.exudyn
@pytest.mark.parametrize(
    "setting",
    [
        "error_control=per-block",
        "block_frequency=100.0",
        "bending_scale=10.0",
        "stall_steps=5",
        "min_step_fraction=1e-3",
    ],
)
def test_exudyn_refuses_a_native_integrator_setting_it_cannot_honour(tmp_path, capsys, setting):
    """`--set error_control=per-block` (and the other settings of rodval's own integrators)
    on exudyn ran with exit 0 and the setting nowhere in run.json: exudyn's check knew only
    method, rtol, atol, max_step, first_step and max_evaluations."""
    pytest.importorskip("exudyn")
    code = main(["simulate", "paper", "--model", "exudyn", *TINY, "--set", setting,
                 "--out", str(tmp_path / "run")])  # fmt: skip
    assert code == 2
    name = setting.split("=")[0]
    err = _error(capsys)
    assert f"integrator setting {name}=" in err and "exudyn" in err
    assert not (tmp_path / "run" / "run.json").exists()


# ------------------------------------------------------------ 4. modes applies scene keys


def test_modes_applies_a_scene_value_of_set(tmp_path, capsys):
    """`rodval modes --set chain.EI=2e8` (the example of its --help) was refused."""
    out = tmp_path / "m"
    argv = ["modes", "paper", "--model", "reduced", "--count", "3", "--set", "chain.EI=2e8"]
    assert main([*argv, "--out", str(out)]) == 0, capsys.readouterr().err
    got = pd.read_csv(out / "frequencies.csv")["omega_rad_s"].to_numpy()
    stiff = scene_from_dict({"based_on": "paper", "chain": {"EI": 2e8}})
    expected = modes(stiff, "reduced", count=3).omega
    np.testing.assert_array_equal(got, expected)  # the same computation: bit for bit
    paper = modes(scene_from_dict({"based_on": "paper"}), "reduced", count=3).omega
    assert not np.allclose(got, paper)
    record = json.loads((out / "modes.json").read_text())  # the scene linearized, recorded
    assert record["scene"]["chain"]["EI"] == [2e8] * 8 and record["scene"]["name"] == "paper-n8"


def test_modes_applies_a_scene_value_over_a_run_json(tmp_path, capsys):
    run = tmp_path / "run"
    argv = ["simulate", "paper", "--model", "reduced", *TINY, "--out", str(run)]
    assert main(argv) == 0, capsys.readouterr().err
    out = tmp_path / "m"
    argv = ["modes", str(run / "run.json"), "--count", "1", "--set", "chain.EI=2e8"]
    assert main([*argv, "--out", str(out)]) == 0, capsys.readouterr().err
    stiff = scene_from_dict({"based_on": "paper", "n": 2, "chain": {"EI": 2e8}})
    got = pd.read_csv(out / "frequencies.csv")["omega_rad_s"].to_numpy()
    np.testing.assert_array_equal(got, modes(stiff, "reduced", count=1).omega)


def test_modes_names_a_bad_scene_value_of_set(tmp_path, capsys):
    argv = ["modes", "paper", "--set", "chain.EI=-1", "--out", str(tmp_path / "m")]
    assert main(argv) == 2
    assert "paper (with --set chain.EI)" in _error(capsys)


# ----------------------------------------------------------- study: --set of its keys

STUDY = (
    '[study]\nname = "s"\n[scene]\nbased_on = "paper"\nn = 2\nt_end = 0.005\n'
    "times = [0.0, 0.005]\n[models.reduced]\n"
)


def test_study_set_applies_scene_values_settings_and_options(tmp_path, capsys):
    """`rodval study` took no --set: "unrecognized arguments", its VALUE printed over two
    lines when it held a newline."""
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    out = tmp_path / "out"
    sets = ["chain.EI=2e4", "integrator.rtol=1e-6", "models.reduced.coefficients=published"]
    argv = ["study", str(study), "--out", str(out), "--workers", "1", "--no-progress"]
    for item in sets:
        argv += ["--set", item]
    assert main([*argv, "--no-report"]) == 0, capsys.readouterr().err
    (case,) = (out / "cases").glob("*.json")
    record = json.loads(case.read_text())
    assert record["scene"]["chain"]["EI"] == [2e4, 2e4]
    (run,) = record["runs"]
    ran = run["trajectory"]
    assert ran["settings"]["rtol"] == 1e-6 and ran["options"]["coefficients"] == "published"
    text = (out / "study.toml").read_text()  # reruns the same study without --set
    assert text.startswith(f"# {study} with --set chain.EI, integrator.rtol, models.reduced")


@pytest.mark.parametrize(
    ("item", "says"),
    [
        ("rtol=1e-6", "--set rtol: a study's integrator setting goes by its path: --set integr"),
        ("shapes=2", "--set shapes: not a key of the study file; give its dotted path"),
        ("chain.EI=2e8\nn = 3", "--set chain.EI: VALUE must be one TOML value"),
    ],
)
def test_study_set_refuses_a_key_that_is_no_path_of_it_in_one_line(tmp_path, capsys, item, says):
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    argv = ["study", str(study), "--out", str(tmp_path / "o"), "--set", item]
    try:
        code = main(argv)
    except SystemExit as exit_:  # the parser's refusal of VALUE
        code = int(exit_.code or 0)
    assert code == 2
    assert says in _error(capsys)


def test_study_set_of_one_path_in_two_spellings_is_refused(tmp_path):
    from rodval.study.spec import load_study

    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    with pytest.raises(ValueError, match=r"--set scene.chain.EI given twice"):
        load_study(study, overrides={"chain.EI": 1e4, "scene.chain.EI": 2e4})


# ----------------------------------------------------- 5. an error in a based_on file


@pytest.mark.parametrize(
    ("bad", "says"),
    [
        ('EI = "stiff"', "key 'chain.EI': must be a number"),
        ("EI = -3.0", "EI"),
        ("EI = 2e4\nnosuch = 1", "unknown key 'nosuch'"),
    ],
)
def test_an_error_in_a_based_on_file_names_that_file(tmp_path, bad, says):
    """The error was blamed on the file that names the bad file."""
    (tmp_path / "wing.toml").write_text(WING.replace("EI = 2e4", bad))
    (tmp_path / "mid.toml").write_text('based_on = "wing.toml"\n[chain]\nmu = 0.5\n')
    (tmp_path / "top.toml").write_text('based_on = "mid.toml"\nt_end = 0.2\n')
    for name in ("mid.toml", "top.toml"):
        with pytest.raises(ValueError) as err:
            load_scene(tmp_path / name)
        msg = str(err.value)
        assert msg.startswith(str(tmp_path / "wing.toml")), msg
        assert says in msg and "\n" not in msg


def test_an_error_in_the_middle_file_names_it(tmp_path):
    (tmp_path / "wing.toml").write_text(WING)
    (tmp_path / "mid.toml").write_text('based_on = "wing.toml"\n[chain]\nmu = -0.5\n')
    (tmp_path / "top.toml").write_text('based_on = "mid.toml"\nt_end = 0.2\n')
    with pytest.raises(ValueError, match=r"^\S*mid\.toml.*mu"):
        load_scene(tmp_path / "top.toml")


def test_an_error_of_the_later_file_still_names_it(tmp_path):
    (tmp_path / "wing.toml").write_text(WING)
    (tmp_path / "top.toml").write_text('based_on = "wing.toml"\n[chain]\nEI = "x"\n')
    with pytest.raises(ValueError, match=r"^\S*top\.toml key 'chain.EI'"):
        load_scene(tmp_path / "top.toml")


def test_a_study_names_the_based_on_file_with_the_error(tmp_path):
    (tmp_path / "wing.toml").write_text(WING.replace("EI = 2e4", "EI = -3.0"))
    (tmp_path / "top.toml").write_text('based_on = "wing.toml"\n')
    doc = {"scene": {"file": str(tmp_path / "top.toml")}, "models": {"reduced": {}}}
    with pytest.raises(ValueError, match=r"key 'scene.file': \S*wing\.toml"):
        StudySpec.from_dict(doc)


# ------------------------------------------------------ 6. [base] of another kind


@pytest.mark.parametrize("earlier", [WING, WING + "[base]\nkind = 'pinned'\n", FREE])
def test_a_later_prescribed_base_replaces_the_earlier_base(tmp_path, earlier):
    """A free base's mass and inertia were merged into the later prescribed base, which
    refused them: a file could not make its base prescribed."""
    (tmp_path / "a.toml").write_text(earlier)
    later = 'based_on = "a.toml"\n[base]\nkind = "prescribed"\n[base.motion]\n' + SHAKE
    (tmp_path / "b.toml").write_text(later)
    base = load_scene(tmp_path / "b.toml").base
    assert base.kind == "prescribed" and base.mass is None
    assert base.motion[0].as_dict() == {
        "law": "harmonic",
        "amplitude": 0.01,
        "omega": 10.0,
        "phase": 0.0,
    }


@pytest.mark.parametrize(("earlier", "kind"), [(PRESCRIBED, "pinned"), (PRESCRIBED, "free")])
def test_a_later_base_of_another_kind_replaces_a_prescribed_one(tmp_path, earlier, kind):
    (tmp_path / "a.toml").write_text(earlier)
    body = "mass = 5.0\ninertia = 1.0\n" if kind == "free" else ""
    (tmp_path / "b.toml").write_text(f'based_on = "a.toml"\n[base]\nkind = "{kind}"\n{body}')
    base = load_scene(tmp_path / "b.toml").base
    assert base.kind == kind and base.motion is None


def test_a_later_base_of_the_same_kind_merges_key_by_key(tmp_path):
    (tmp_path / "a.toml").write_text(FREE)
    (tmp_path / "b.toml").write_text('based_on = "a.toml"\n[base]\nmass = 200.0\n')
    base = load_scene(tmp_path / "b.toml").base
    assert (base.kind, base.mass, base.inertia) == ("free", 200.0, 10.0)
    (tmp_path / "c.toml").write_text('based_on = "a.toml"\n[base]\nkind = "free"\nrate = 0.1\n')
    base = load_scene(tmp_path / "c.toml").base
    assert (base.mass, base.rate) == (100.0, 0.1)


def test_the_replacing_base_has_its_keys_checked_naming_its_file(tmp_path):
    (tmp_path / "a.toml").write_text(FREE)
    later = 'based_on = "a.toml"\n[base]\nkind = "prescribed"\nmass = 5.0\n'
    (tmp_path / "b.toml").write_text(later)
    with pytest.raises(ValueError, match=r"^\S*b\.toml \[base\]: base mass: a prescribed base"):
        load_scene(tmp_path / "b.toml")


def test_a_study_scene_override_of_another_base_kind_replaces_it(tmp_path):
    (tmp_path / "a.toml").write_text(FREE)
    motion = {"x": {"law": "harmonic", "amplitude": 0.01, "omega": 10.0, "phase": 0.0}}
    scene = {"file": str(tmp_path / "a.toml"), "base": {"kind": "prescribed", "motion": motion}}
    spec = StudySpec.from_dict({"scene": scene, "models": {"full": {}}})
    assert spec.cases[0].scene.base.kind == "prescribed"


def test_merge_documents_replaces_a_section_of_another_kind():
    free = {"base": {"kind": "free", "mass": 1.0, "inertia": 1.0}}
    pinned = {"base": {"kind": "pinned"}}
    assert merge_documents(free, pinned) == pinned
    assert merge_documents(free, {"base": {"rate": 1.0}})["base"]["mass"] == 1.0


# ------------------------------------------------ 7. a required key of an inline table


def test_bending_damping_without_its_ratio_says_the_ratio_is_missing():
    """`bending_damping = { of = "deployed" }` said "unknown key 'of'" (read as a profile)."""
    doc = {"based_on": "paper", "chain": {"bending_damping": {"of": "deployed"}}}
    with pytest.raises(ValueError) as err:
        scene_from_dict(doc, "f.toml")
    msg = str(err.value)
    assert msg.startswith("f.toml key 'chain.bending_damping.ratio': is missing"), msg
    assert ">= 0 and < 1" in msg and "\n" not in msg


def test_a_missing_latch_key_names_its_range():
    doc = {"based_on": "paper", "latches": [{"angle": 0.1}]}
    with pytest.raises(ValueError, match=r"key 'latches.0.hinge': is missing \(an integer: 0..n-1"):
        scene_from_dict(doc, "f.toml")


def test_a_profile_at_points_without_values_says_values_are_missing():
    doc = {"based_on": "paper", "chain": {"EI": {"at": [0.0, 1.0]}}}
    with pytest.raises(ValueError, match=r"EI profile: 'at' needs 'values'"):
        scene_from_dict(doc, "f.toml")
