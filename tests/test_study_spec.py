"""Study files: the grid, stable case ids, and errors that name the file and the key."""

import subprocess
import sys

import pytest
from study_helpers import write_study

from rodval.study import load_study


def test_grid_is_the_cartesian_product_with_readable_stable_ids(tmp_path):
    spec = load_study(write_study(tmp_path))
    assert [c.id for c in spec.cases] == [
        "n=2,t_end=0.1",
        "n=2,t_end=0.2",
        "n=3,t_end=0.1",
        "n=3,t_end=0.2",
    ]
    case = spec.case("n=3,t_end=0.2")
    assert (case.scene.n, case.scene.t_end) == (3, 0.2)
    assert case.scene.times[-1] == pytest.approx(0.2)  # times {num} follow the horizon
    assert [m.label for m in case.models] == ["reduced", "published"]
    assert case.models[1].options == {"coefficients": "published"}
    # adding a value to an axis keeps the other cases' ids and fingerprints
    bigger = load_study(write_study(tmp_path, "b.toml", grid="scene.t_end = [0.1, 0.2, 0.4]"))
    old = {c.id: c.fingerprint for c in spec.cases}
    new = {c.id: c.fingerprint for c in bigger.cases}
    assert len(new) == 6 and all(new[k] == v for k, v in old.items())


def test_grid_reaches_chain_integrator_and_model_options(tmp_path):
    grid = 'scene.chain.EI = [1e3, 1e5]\nmodels.reduced.rtol = [1e-6, 1e-8]\nintegrator.method = ["RK45"]'
    spec = load_study(write_study(tmp_path, grid=grid))
    assert len(spec.cases) == 2 * 2 * 2 * 1
    c = spec.case("n=3,EI=1000,rtol=1e-08,method=RK45")
    assert c.scene.chain.EI.tolist() == [1e3] * 3
    settings = {m.label: m.settings for m in c.models}
    assert settings["reduced"].rtol == 1e-8 and settings["published"].rtol == 1e-7
    assert settings["reduced"].method == settings["published"].method == "RK45"


@pytest.mark.parametrize(
    "grid, models, reference, key, words",
    [
        ("bogus = 1", None, "reduced", "grid.bogus", "path into"),
        ("scene.t_end = [0.1, -1.0]", None, "reduced", "t_end", "> 0"),
        ("scene.chain.XX = [1.0]", None, "reduced", "XX", "unknown key"),
        ("scene.t_end = []", None, "reduced", "grid.scene.t_end", "non-empty"),
        ("models.nosuch.rtol = [1e-6]", None, "reduced", "grid.models.nosuch.rtol", "LABEL"),
        ("", "[models.reduced]\nrtol = -1", "reduced", "models.reduced.rtol", "> 0"),
        ("", "[models.reduced]\nspeed = 3", "reduced", "models.reduced", "speed"),
        ("", "[models.foo]", "foo", "models.foo", "must be one of"),
        ("", "[models.reduced]", "full", "study.reference", "model labels"),
    ],
)
def test_bad_files_name_file_and_key(tmp_path, grid, models, reference, key, words):
    kwargs = {"grid": grid, "reference": reference}
    if models is not None:
        kwargs["models"] = models
    path = write_study(tmp_path, **kwargs)
    with pytest.raises(ValueError) as info:
        load_study(path)
    msg = str(info.value)
    assert str(path) in msg and key in msg and words in msg, msg


def test_unknown_top_level_and_table_keys(tmp_path):
    path = write_study(tmp_path)
    path.write_text(path.read_text() + "\n[reprot]\ncases = []\n")
    with pytest.raises(ValueError, match=r"tiny\.toml: key 'reprot': unknown key"):
        load_study(path)
    path = write_study(tmp_path)
    path.write_text(path.read_text().replace('name = "tiny"', 'name = "tiny"\nrefrence = "x"'))
    with pytest.raises(ValueError, match=r"key 'study.refrence': unknown key"):
        load_study(path)


def test_cli_bad_study_exits_2_with_one_line(tmp_path):
    path = write_study(tmp_path, grid="scene.t_end = [0.1, -1.0]")
    res = subprocess.run(
        [sys.executable, "-m", "rodval", "study", str(path), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0] and "t_end" in lines[0], res.stderr
    assert not (tmp_path / "out").exists()  # no work before validation


def test_shipped_studies_and_the_readme_example_are_valid():
    import re
    import tomllib
    from pathlib import Path

    from rodval.study import study_from_dict

    root = Path(__file__).parent.parent / "studies"
    sizes = {p.stem: len(load_study(p).cases) for p in sorted(root.glob("*.toml"))}
    assert sizes == {
        "companion_three_panel": 1,
        "companion_three_panel_free": 2,
        "deployment": 1,
        "deployment_stiff": 1,
        "deployment_stiff_panels": 1,
        "deployment_sample": 256,
        "deployment_spacecraft": 1,
        "exudyn_convergence": 80,
        "model_error_budget": 8,
        "n_sweep": 20,
        "paper": 1,
        "scale_study": 1000,
        "scale_study_10k": 10000,
        "scale_study_50": 50,
        "stability": 18,
        "stiffness_sweep": 16,
        "work_precision_full": 20,
        "work_precision_reduced": 20,
    }
    n_sweep = load_study(root / "n_sweep.toml")
    assert {(c.scene.n, c.scene.t_end) for c in n_sweep.cases} == {
        (n, t) for n in (2, 4, 8, 16, 32) for t in (1.0, 2.0, 5.0, 10.0)
    }
    assert all(c.scene.loads[0].node == c.scene.n for c in n_sweep.cases)  # load at the tip
    block = re.search(r"```toml\n(.*?)```", (root / "README.md").read_text(), re.S).group(1)
    assert len(study_from_dict(tomllib.loads(block), "README").cases) == 24


def test_several_grids_give_the_union_of_their_products(tmp_path):
    """[[grid]] tables: each its own cartesian product; a load axis can follow n ("last")."""
    path = tmp_path / "union.toml"
    text = (
        write_study(tmp_path)
        .read_text()
        .replace(
            "[grid]\nscene.n = [2, 3]\nscene.t_end = [0.1, 0.2]\n",
            "[[grid]]\nscene.n = [2, 3]\n\n[[grid]]\nscene.n = [4]\n"
            'scene.loads = [[{ type = "pulse", node = "last", Ybar = 10.0 }]]\n',
        )
    )
    path.write_text(text)
    spec = load_study(path)
    assert [c.id for c in spec.cases] == ["n=2", "n=3", "n=4,loads=pulse(node=last,Ybar=10)"]
    assert spec.axes["scene.n"] == [2, 3, 4]
    last = spec.case("n=4,loads=pulse(node=last,Ybar=10)").scene.loads
    assert len(last) == 1 and last[0].node == 4 and last[0].params["Ybar"] == 10.0
    assert spec.case("n=3").scene.loads[0].params["Ybar"] == 1200.0  # the paper's pulse
