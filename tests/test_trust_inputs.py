"""Inputs rodval used to accept without a word (the "trust" issue): runs of different scenes
compared, damaged run folders read, values clamped, coerced or dropped silently, and Python
API calls that failed deep inside. Each is now refused up front with one line naming the
parameter (or file) and what is allowed."""

import json
import shutil

import pytest
from checks import assert_refused, run_main
from study_helpers import write_study

import rodval
from rodval import IntegratorSettings, Latch, paper_scene, tabulated
from rodval.cli import main
from rodval.core.scene_file import load_scene
from rodval.core.settings import MIN_RTOL

TINY = (
    'based_on = "paper"\nn = 2\nt_end = 0.05\ntimes = {start = 0.0, stop = 0.05, num = 11}\n'
    'outputs = ["phi"]\n'
)


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


# -- item 2: nothing clamped, coerced or dropped silently -------------------------------------


def test_rtol_below_what_the_integrators_honour_is_refused(tmp_path, capsys):
    proc = run_main(capsys, "simulate", "paper", "--rtol", "1e-300", "--out", str(tmp_path))
    assert_refused(proc, ["--rtol", "(0, 1)", "2.22e-14", "'1e-300'"])
    assert not (tmp_path / "run.json").exists()
    with pytest.raises(ValueError, match=r"^rtol must be .*2\.22e-14.*got 1e-300$"):
        IntegratorSettings(rtol=1e-300)
    assert IntegratorSettings(rtol=MIN_RTOL).rtol == MIN_RTOL  # the bound itself is honoured


def test_unknown_setting_in_an_edited_run_json_is_refused(runs, tmp_path, capsys):
    doc = json.loads((runs / "A" / "run.json").read_text())
    doc["settings"]["rtoll"] = 1e-3
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(doc))
    proc = run_main(capsys, "simulate", str(edited), "--out", str(tmp_path / "out"))
    assert_refused(proc, [str(edited), "'settings'", "unknown key 'rtoll'", "rtol", "atol"])
    assert not (tmp_path / "out").exists()


def test_unknown_top_level_key_in_an_edited_run_json_is_refused(runs, tmp_path, capsys):
    doc = json.loads((runs / "A" / "run.json").read_text())
    doc["modell"] = "reduced"
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(doc))
    proc = run_main(capsys, "simulate", str(edited), "--out", str(tmp_path / "out"))
    assert_refused(proc, [str(edited), "unknown key 'modell'", "model", "scene"])


def test_scene_name_must_be_a_string(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('based_on = "paper"\nname = 123\n')
    with pytest.raises(ValueError, match=r"s\.toml key 'name': must be a string, got int 123$"):
        load_scene(path)
    with pytest.raises(ValueError, match="^name .*must be a string"):
        paper_scene(2).with_(name=123)


@pytest.mark.parametrize("direction", [-1.0, 1.0, 0.5, "-1"])
def test_latch_direction_must_be_the_integer_plus_or_minus_one(direction):
    with pytest.raises(ValueError, match=r"^latch direction must be the integer \+1 or -1"):
        Latch(hinge=1, angle=0.5, direction=direction)
    assert Latch(hinge=1, angle=0.5, direction=-1).direction == -1


def test_latch_direction_float_in_a_scene_file_is_refused(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(
        'based_on = "paper"\nn = 2\n[[latches]]\nhinge = 1\nangle = -0.5\ndirection = -1.0\n'
    )
    with pytest.raises(
        ValueError,
        match=r"s\.toml key 'latches\.0\.direction': must be an integer \(\+1 or -1\), got float -1\.0$",
    ):
        load_scene(path)


def test_tabulated_load_file_with_a_column_named_twice_is_refused(tmp_path):
    csv = tmp_path / "f.csv"
    csv.write_text("t,X,X\n0,1,2\n1,3,4\n")
    with pytest.raises(ValueError, match=r"f\.csv: column 'X' named twice"):
        tabulated(node=1, file=str(csv))


@pytest.mark.parametrize("times", ["0,,0.1", "0,0.1,", ",0.1"])
def test_times_with_an_empty_item_are_refused(times, tmp_path, capsys):
    proc = run_main(capsys, "simulate", "paper", "--times", times, "--out", str(tmp_path))
    assert_refused(proc, ["--times", "empty item", repr(times)])


def test_coefficients_given_twice_are_refused(tmp_path, capsys):
    proc = run_main(
        capsys,
        "simulate",
        "paper",
        "--coefficients",
        "published",
        "--set",
        "coefficients=printed",
        "--out",
        str(tmp_path),
    )
    assert_refused(proc, ["--coefficients published", "coefficients=printed", "conflict"])
    assert not (tmp_path / "run.json").exists()


def test_a_set_key_given_twice_is_refused(tmp_path, capsys):
    args = ["--set", "kernel=numba", "--set", "kernel=numpy", "--out", str(tmp_path)]
    proc = run_main(capsys, "simulate", "paper", *args)
    assert_refused(proc, ["--set kernel", "twice", "kernel='numba'", "kernel='numpy'"])


# -- item 3: the Python API checks its arguments up front ---------------------------------


@pytest.fixture(scope="module")
def traj():
    return rodval.simulate(rodval.paper_scene(2, t_end=0.05, times=[0.0, 0.05]), "reduced")


@pytest.mark.parametrize("swap", [False, True])
def test_compare_refuses_what_is_not_a_trajectory(traj, swap):
    args = ("x", traj) if swap else (traj, "x")
    name = "traj" if swap else "reference"
    with pytest.raises(ValueError, match=rf"^{name} must be a rodval\.Trajectory .*got str 'x'$"):
        rodval.compare(*args)


def test_compare_refuses_a_bare_string_of_quantities(traj):
    # 'phi' used to be read as the quantities 'p', 'h', 'i'
    with pytest.raises(ValueError, match=r"^quantities must be a list .*got 'phi'$"):
        rodval.compare(traj, traj, "phi")
    assert list(rodval.compare(traj, traj, ["phi"])["quantity"]) == ["phi"]


def test_unknown_quantity_names_it_and_the_available_ones(traj):
    with pytest.raises(KeyError, match=r"'gamma' .*available: phi, dphi") as info:
        traj["gamma"]
    assert isinstance(info.value, ValueError)  # one-line CLI errors catch it too
    assert str(info.value).startswith("quantity 'gamma'")
    with pytest.raises(KeyError, match="'gamma'"):
        traj.at("gamma", 0.0, 1)


def test_at_a_time_that_is_not_an_output_time_is_named(traj):
    with pytest.raises(ValueError, match=r"^t = 0\.3 s is not an output time"):
        traj.at("phi", 0.3, 1)
    with pytest.raises(ValueError, match=r"^k = 7 is not a label of 'phi' \(allowed: 1, 2\)$"):
        traj.at("phi", 0.05, 7)


def test_with_an_unknown_field_names_it_and_the_allowed_ones():
    scene = rodval.paper_scene(2)
    with pytest.raises(ValueError, match=r"^Scene\.with_: unknown field 'foo' \(allowed: .*t_end"):
        scene.with_(foo=1)
    with pytest.raises(ValueError, match=r"^Chain\.with_: unknown field 'foo' \(allowed: .*EI"):
        scene.chain.with_(foo=1)
    assert scene.with_(t_end=3.0).t_end == 3.0


def test_run_study_takes_a_str_path(tmp_path):
    path = write_study(tmp_path, grid="")
    out = str(tmp_path / "out")
    run = rodval.run_study(str(path), out, workers=1, progress=False, report=False)
    tables = rodval.read_study_tables(out)
    assert run.out == tmp_path / "out" and len(run.ran) == 2
    assert len(tables["cases"]) == 2


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda: rodval.run_study(123, "out"), "^spec must be a study"),
        (lambda: rodval.run_study("nope.toml", 5), "study file 'nope.toml' does not exist"),
        (lambda: rodval.load_study(123), r"^path must be a path \(str or pathlib.Path\), got int"),
        (lambda: rodval.read_study_tables(1), r"^out must be a path .*got int 1$"),
        (lambda: rodval.modes("paper", "full"), r"^scene must be a rodval\.Scene"),
        (lambda: rodval.modes(rodval.paper_scene(2), "full", count="3"), r"^count .*integer >= 1"),
        (lambda: rodval.modes(rodval.paper_scene(2), "full", count=2.7), r"^count .*got 2\.7$"),
        (lambda: rodval.paper_scene(2, times=5), r"^times \(output times\) must be a 1-D"),
    ],
    ids=[
        "run_study(123)",
        "run_study(out=5)",
        "load_study",
        "tables",
        "modes",
        "count",
        "2.7",
        "times",
    ],
)
def test_api_entry_points_refuse_wrong_types_in_one_line(call, words):
    with pytest.raises(ValueError, match=words) as info:
        call()
    assert "\n" not in str(info.value)


def test_modes_about_equilibrium_of_a_chain_with_a_free_hinge(tmp_path, capsys):
    scene = tmp_path / "free.toml"
    scene.write_text(
        'based_on = "paper"\nn = 3\n[chain]\nkappa = [100.0, 0.0, 100.0]\n'
        '[[loads]]\ntype = "constant"\nnode = "last"\nY = 50.0\n'
    )
    args = ["modes", str(scene), "--about", "equilibrium", "--out", str(tmp_path / "m")]
    proc = run_main(capsys, *args)
    assert_refused(proc, ["no stiffness (kappa = 0)", "hinge(s) [1]", "--about initial"])
    assert "Singular matrix" not in proc.stderr
