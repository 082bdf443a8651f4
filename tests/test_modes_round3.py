"""Issue 46, `rodval modes` honours every item of its scene: held latches held in every model,
a run.json's model options carried, 60 short stiff rods, the free spacecraft's --count and
figure, and docs/modes.md's loaded-equilibrium example run as written."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rodval import Base
from rodval.analysis.modes import model_modes
from rodval.cli import main
from rodval.core.hinges import Latch
from rodval.core.loads import constant
from rodval.core.scene import Chain, InitialState, Scene
from rodval.core.scene_file import scene_from_dict
from rodval.models.observation.linear_modes import modes

ROOT = Path(__file__).resolve().parents[1]

#: One 10 m clamped-free beam (1.2 kg/m, EI 1.4e4 N m^2) as a pinned chain of 4 rods of
#: 2.5 m with every hinge held: omega_i = (beta_i L)^2 sqrt(EI / (m L^4)), beta L =
#: 1.87510407, 4.69409113, 7.85475744 (computed: 3.797731, 23.79997, 66.64061 rad/s).
CLAMPED_FREE = np.array([3.797731, 23.79997, 66.64061])
BETA_L = np.array([1.87510407, 4.69409113, 7.85475744])


def held_beam(kappa: float = 0.0) -> Scene:
    """The pinned 4-rod chain, every hinge held straight (kappa: the hinge springs, which a
    held hinge makes irrelevant)."""
    chain = Chain.uniform(4, l=2.5, m=1.2, EI=1.4e4, mu=0.0, kappa=kappa, nu=0.0)
    latches = tuple(Latch(k, 0.0, held=True) for k in range(4))
    return Scene(chain=chain, t_end=1.0, latches=latches)


def test_clamped_free_values_stated_to_seven_digits() -> None:
    exact = BETA_L**2 * np.sqrt(1.4e4 / (1.2 * 10.0**4))
    np.testing.assert_allclose(CLAMPED_FREE, exact, rtol=5e-7)


@pytest.mark.parametrize("kappa", [0.0, 50.0])
def test_held_chain_is_the_clamped_free_beam_natively(kappa: float) -> None:
    """The full model holds the held latches: p = 3 shapes per rod give the beam's first three
    frequencies within 1e-4 (p = 2: 3.5e-4 on mode 3; before: four zero modes at kappa = 0,
    the chain swinging at kappa = 50 N m/rad)."""
    m = modes(held_beam(kappa), "full", count=3, shapes=3)
    np.testing.assert_allclose(m.omega, CLAMPED_FREE, rtol=1e-4)
    assert m.info["held_hinges"] == [0, 1, 2, 3]
    assert m.count == 3


def test_held_chain_is_the_clamped_free_beam_in_exudyn() -> None:
    m = model_modes(held_beam(), "exudyn", count=3, elements=16)
    np.testing.assert_allclose(m.omega, CLAMPED_FREE, rtol=1e-4)


def test_held_chain_cli_compare_pairs_the_same_structure(tmp_path: Path) -> None:
    """`rodval modes --compare` of the held chain: native (p = 3) and exudyn within 1e-4 of
    the beam and paired with MAC > 0.999 (before: MAC 0.03-0.66 against four zero modes)."""
    scene = tmp_path / "held.toml"
    latches = "".join(f"[[latches]]\nhinge = {k}\nangle = 0.0\nheld = true\n" for k in range(4))
    scene.write_text("n = 4\nt_end = 1.0\n[chain]\nl = 2.5\nm = 1.2\nEI = 1.4e4\n" + latches)
    out = tmp_path / "out"
    argv = ["modes", str(scene), "--model", "full", "--set", "shapes=3", "--count", "3"]
    assert main([*argv, "--compare", "full,exudyn", "--out", str(out)]) == 0
    table = pd.read_csv(out / "compare.csv")
    np.testing.assert_allclose(table["omega_full"], CLAMPED_FREE, rtol=1e-4)
    np.testing.assert_allclose(table["omega_exudyn"], CLAMPED_FREE, rtol=1e-4)
    assert (table["mac_exudyn"] > 0.999).all()


def held_pair_scene() -> Scene:
    """4 rods with springs, hinge 1 held at 0.3 rad away from its spring's rest angle 0 (the
    latch holds the spring's moment), hinge 2 with an unheld latch ahead of it."""
    chain = Chain.uniform(4, l=1.5, m=3.0, EI=1e5, mu=0.5, kappa=50.0, nu=0.01)
    phi = np.cumsum([0.0, 0.3, 0.0, 0.0])
    return Scene(
        chain=chain,
        t_end=1.0,
        initial=InitialState(phi=phi),
        latches=(Latch(1, 0.3, held=True), Latch(2, 0.5)),
    )


@pytest.mark.parametrize("loaded", [False, True])
def test_held_latch_every_model_agrees(loaded: bool) -> None:
    """A held hinge away from its spring's rest angle is an equilibrium (before: refused as
    unbalanced) and every model holds it, about the initial state and about the static
    equilibrium under a tip load: the three hinge modes of full (p = 3) within 1e-5 and of
    reduced within 1e-4 of exudyn (16 elements)."""
    scene = held_pair_scene()
    about = "equilibrium" if loaded else "initial"
    if loaded:
        scene = scene.with_(loads=(constant(4, Y=20.0),))
    ref = model_modes(scene, "exudyn", about=about, count=3, elements=16)
    full = model_modes(scene, "full", about=about, count=3, shapes=3)
    reduced = model_modes(scene, "reduced", about=about, count=3)
    assert full.count == reduced.count == 3
    np.testing.assert_allclose(full.omega, ref.omega, rtol=1e-5)
    np.testing.assert_allclose(reduced.omega, ref.omega, rtol=1e-4)
    if loaded:  # the held hinge stays at its latch's angle in the equilibrium
        from rodval.models.assembly.paper_matrices import hinge_matrix

        D = hinge_matrix(4) @ full.equilibrium.q
        assert abs(D[1] - 0.3) < 1e-12


def test_held_latches_on_a_free_base() -> None:
    """Free spacecraft, hinge 0 held and hinge 1 held without a spring (before: refused as a
    mechanism): native (p = 3) and exudyn agree on the first three flexible modes."""
    chain = Chain.uniform(3, l=1.5, m=3.0, EI=1e5, mu=0.5, kappa=[50.0, 0.0, 50.0], nu=0.01)
    scene = Scene(
        chain=chain,
        t_end=1.0,
        base=Base(kind="free", mass=50.0, inertia=20.0, hinge_offset=(0.5, 0.0)),
        latches=(Latch(0, 0.0, held=True), Latch(1, 0.0, held=True)),
    )
    full = model_modes(scene, "full", count=3, shapes=3).flexible()
    ref = model_modes(scene, "exudyn", count=3, elements=16).flexible()
    assert full.omega[0] > 1.0  # no mechanism mode: the held hinge 1 does not turn
    np.testing.assert_allclose(full.omega, ref.omega, rtol=1e-5)


def test_published_coefficients_with_held_latches_refused() -> None:
    with pytest.raises(ValueError, match="held latches .* coefficients='printed'"):
        modes(held_beam(), "full", coefficients="published")


# -- item 2: a run.json's model options --------------------------------------------------------
def small_scene(tmp_path: Path) -> Path:
    path = tmp_path / "small.toml"
    path.write_text('based_on = "paper"\nn = 3\nt_end = 0.02\n')
    return path


def test_run_json_rerun_carries_shapes(tmp_path: Path, capsys) -> None:
    """`rodval modes RUN/run.json` of a shapes = 2 run computes the p = 2 model (before: p = 1,
    its bending pair 11 % high instead of 3e-4)."""
    run = tmp_path / "run"
    argv = ["simulate", str(small_scene(tmp_path)), "--model", "full", "--set", "shapes=2"]
    assert main([*argv, "--out", str(run)]) == 0
    out = tmp_path / "modes"
    assert main(["modes", str(run / "run.json"), "--out", str(out), "--count", "6"]) == 0
    got = pd.read_csv(out / "frequencies.csv")["omega_rad_s"].to_numpy()
    scene = scene_from_dict(json.loads((run / "run.json").read_text())["scene"])
    p2 = modes(scene, "full", count=6, shapes=2).omega
    p1 = modes(scene, "full", count=6).omega
    np.testing.assert_allclose(got, p2, rtol=1e-12)
    assert abs(got[-1] - p1[-1]) > 1e-3 * p1[-1]
    record = json.loads((out / "modes.json").read_text())
    assert record["options"]["shapes"] == 2
    assert "kernel" in capsys.readouterr().out  # the run's integration option, named


def test_run_json_option_modes_cannot_honour_is_refused(tmp_path: Path, capsys) -> None:
    run = tmp_path / "run"
    assert main(["simulate", str(small_scene(tmp_path)), "--out", str(run)]) == 0
    record = json.loads((run / "run.json").read_text())
    record["options"]["warp"] = 3
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(record))
    out = tmp_path / "modes"
    assert main(["modes", str(edited), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "warp" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_command_line_option_overrides_the_run_json(tmp_path: Path) -> None:
    run = tmp_path / "run"
    argv = ["simulate", str(small_scene(tmp_path)), "--model", "full", "--set", "shapes=2"]
    assert main([*argv, "--out", str(run)]) == 0
    out = tmp_path / "modes"
    argv = ["modes", str(run / "run.json"), "--set", "shapes=3", "--count", "2"]
    assert main([*argv, "--out", str(out)]) == 0
    assert json.loads((out / "modes.json").read_text())["options"]["shapes"] == 3


# -- item 3: 60 short stiff rods -----------------------------------------------------------
def test_sixty_short_stiff_rods_reduced() -> None:
    """60 rods of 0.1 m, EI 1e6 N m^2: the reduced model's non-symmetric pencil, scaled by
    rho^k, lost 59 eigenvalues to infinity at rho = 4 and 8 and the Hungarian matching of the
    runs failed ("cost matrix is infeasible"). Now the spectrum is real, agrees with the plain
    QZ to 1e-8, and its lowest modes with the full model's to 1e-7."""
    import scipy.linalg

    from rodval.models.observation.linear_modes import linear_system

    chain = Chain.uniform(60, l=0.1, m=1.0, EI=1e6, mu=0.0, kappa=100.0, nu=0.01)
    scene = Scene(chain=chain, t_end=1.0)
    m = modes(scene, "reduced")
    M, _, K = linear_system(chain, "reduced")
    plain = np.sort(scipy.linalg.eigvals(K, M).real)
    np.testing.assert_allclose(m.omega**2, plain, rtol=1e-8)
    full = modes(scene, "full", count=4)
    np.testing.assert_allclose(m.omega[:4], full.omega, rtol=1e-7)


# -- item 4: the free spacecraft's --count and figure --------------------------------------
def free_toml(tmp_path: Path) -> Path:
    path = tmp_path / "free.toml"
    path.write_text(
        'based_on = "paper"\nn = 3\nt_end = 1.0\nloads = []\n'
        "[chain]\nl = 1.5\nm = 3.0\nEI = 1e5\nmu = 0.5\nkappa = 50.0\n"
        '[base]\nkind = "free"\nmass = 50.0\ninertia = 20.0\nhinge_offset = [0.5, 0.0]\n'
    )
    return path


def test_free_spacecraft_count_is_flexible_modes(tmp_path: Path, capsys) -> None:
    """--count 6 writes the 6 flexible modes, numbered 1..6 as compare.csv numbers them
    (before: 9 rows, the rigid ones first); the rigid ones are reported apart (printed and in
    modes.json); modes.png draws flexible modes only."""
    out = tmp_path / "out"
    argv = ["modes", str(free_toml(tmp_path)), "--model", "full", "--count", "6"]
    assert main([*argv, "--out", str(out)]) == 0
    freq = pd.read_csv(out / "frequencies.csv")
    assert freq["mode"].tolist() == [1, 2, 3, 4, 5, 6]
    assert (freq["omega_rad_s"] > 1.0).all()
    shapes = pd.read_csv(out / "modes.csv")
    assert sorted(shapes["mode"].unique()) == [1, 2, 3, 4, 5, 6]
    record = json.loads((out / "modes.json").read_text())
    assert record["count"] == 6
    assert record["rigid_modes"]["modes"] == ["translation_x", "translation_y", "rotation"]
    assert record["rigid_modes"]["omega_rad_s"] == [0.0, 0.0, 0.0]
    printed = capsys.readouterr().out
    assert "3 rigid modes" in printed


def test_free_spacecraft_figure_draws_flexible_modes(tmp_path: Path) -> None:
    """modes.png of a free spacecraft draws its first flexible modes (before: the three rigid
    ones and one flexible one), numbered from 1."""
    from rodval.report.figures import drawn_modes, plot_modes

    scene = scene_from_dict(
        {
            "n": 3,
            "t_end": 1.0,
            "chain": {"l": 1.5, "m": 3.0, "EI": 1e5, "mu": 0.5, "kappa": 50.0},
            "base": {"kind": "free", "mass": 50.0, "inertia": 20.0},
        }
    )
    m = model_modes(scene, "full", count=6)
    assert m.rigid == 3 and m.count == 9
    drawn = drawn_modes(m, 4)
    assert drawn.rigid == 0 and drawn.count == 4
    np.testing.assert_array_equal(drawn.omega, m.omega[3:7])
    assert plot_modes(m, tmp_path / "modes.png").is_file()


# -- item 5: docs/modes.md's loaded-equilibrium example ------------------------------------
def doc_example() -> tuple[str, list[str]]:
    """tip.toml and the command of docs/modes.md's "Loaded equilibrium", as written."""
    text = (ROOT / "docs" / "modes.md").read_text()
    section = text[text.index("## Loaded equilibrium") :]
    section = section[: section.index("\n## ", 5)]
    toml = re.search(r"```toml\n# tip.toml\n(.*?)```", section, re.S)
    command = re.search(r"```bash\n(rodval modes tip\.toml[^\n]*)\n```", section)
    assert toml and command, "docs/modes.md's tip.toml example not found"
    return toml.group(1), command.group(1).split()[1:]


def test_loaded_equilibrium_doc_example_runs_as_written(tmp_path: Path, monkeypatch) -> None:
    """The documented tip.toml and command, run from a fresh folder (before: "key 't_end' is
    missing"); the frequencies the doc states, 0.8236, 2.987, 6.943 rad/s, and the gaps it
    states (full within 6e-6, reduced within 5e-5 of exudyn)."""
    toml, argv = doc_example()
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tip.toml").write_text(toml)
    assert main(argv) == 0
    out = tmp_path / argv[argv.index("--out") + 1]
    table = pd.read_csv(out / "compare.csv").head(3)
    np.testing.assert_allclose(table["omega_full"], [0.8236, 2.987, 6.943], rtol=5e-4)
    for model, bound in (("full", 6e-6), ("reduced", 5e-5)):
        gap = table[f"omega_{model}"] / table["omega_exudyn"] - 1.0
        assert (gap.abs() < bound).all(), (model, gap.tolist())
