"""What modes are about (issue 21): the static loads of an equilibrium (windowed loads left out
and named, --load-at to hold every load at an instant), an initial state that is not at rest
in equilibrium refused unless asked for, the hinge rest angles in every model's equilibrium,
run.json as SCENE, and normalized shapes labelled as such."""

from __future__ import annotations

import json

import numpy as np
import pytest
from checks import assert_refused, run_main

from rodval import Chain, InitialState, Scene, constant, paper_scene
from rodval.cli import main
from rodval.core.loads import harmonic, pulse
from rodval.mechanics.modal import static_loads
from rodval.models.assembly.paper_matrices import hinge_matrix
from rodval.models.observation.linear_modes import modes
from rodval.models.observation.statics import AT_REST_RTOL, static_residual

CHAIN = Chain.uniform(3, nu=0.0)


def _scene(*loads, **kw) -> Scene:
    return Scene(chain=kw.pop("chain", CHAIN), loads=loads, t_end=1.0, **kw)


def test_a_windowed_load_is_left_out_of_the_equilibrium_and_named():
    """A constant tip load switched off at 0.6 s was treated as permanent (a 71 degree
    equilibrium the motion never reaches): now the equilibrium is the unloaded straight chain
    and the load is named; --load-at 0.3 holds it, which gives exactly the equilibrium of the
    same load acting for ever."""
    windowed = _scene(constant(3, Y=30.0, t_off=0.6))
    m = modes(windowed, "full", about="equilibrium", count=3)
    assert m.equilibrium.loads.ignored == ("constant load at node 3 (acts only until t = 0.6 s)",)
    np.testing.assert_array_equal(m.equilibrium.phi, 0.0)
    held = modes(windowed, "full", about="equilibrium", count=3, load_at=0.3)
    permanent = modes(_scene(constant(3, Y=30.0)), "full", about="equilibrium", count=3)
    assert held.equilibrium.phi[-1] > 1.0  # really deflected (~1.3 rad)
    np.testing.assert_array_equal(held.equilibrium.phi, permanent.equilibrium.phi)
    np.testing.assert_array_equal(held.omega, permanent.omega)
    after = modes(windowed, "full", about="equilibrium", count=3, load_at=0.7)
    assert after.equilibrium.loads.ignored == ("constant load at node 3 (not acting at t = 0.7 s)",)


def test_loads_that_settle_count_at_their_final_value_and_others_need_load_at():
    """A ramp acting for ever counts at its held value; a harmonic load acting for ever has
    no static value and is refused, naming load_at; a pulse is left out."""
    from rodval.core.loads import ramp

    loads = static_loads(_scene(ramp(2, X=5.0, Y=-7.0, t_full=0.4), pulse(3, T=0.1)))
    np.testing.assert_array_equal(loads.X, [0.0, 5.0, 0.0])
    np.testing.assert_array_equal(loads.Y, [0.0, -7.0, 0.0])
    assert loads.ignored == ("pulse load at node 3 (acts only until t = 0.1 s)",)
    with pytest.raises(ValueError, match=r"harmonic load at node 2 acts for ever .* load_at"):
        static_loads(_scene(harmonic(2, Y=1.0, omega=3.0)))
    at = static_loads(_scene(harmonic(2, Y=2.0, omega=3.0)), at=0.5)
    assert at.Y[1] == pytest.approx(2.0 * np.sin(1.5), rel=1e-15)
    with pytest.raises(ValueError, match=r"^load_at must be a finite time >= 0 s, got -1"):
        static_loads(_scene(), at=-1.0)


def test_a_prestressed_fold_is_refused_about_its_initial_state():
    """Rest angles 1 rad at every hinge, the chain straight: the hinge springs hold
    kappa x 1 rad = 100 N m each, so the initial state is no equilibrium (it was linearized
    without a word). Refused naming the residual; allowed on request, with the residual
    recorded; about the equilibrium every hinge sits at its rest angle (no load, no bending)."""
    scene = _scene(chain=CHAIN.with_(rest_angle=1.0))
    with pytest.raises(
        ValueError, match=r"not an equilibrium: static residual 100 N m on phi\[2\]"
    ):
        modes(scene, "full")
    m = modes(scene, "full", allow_unbalanced=True, count=2)
    assert m.info["unbalanced_residual_Nm"] == pytest.approx(100.0, rel=1e-14)
    eq = modes(scene, "reduced", about="equilibrium", count=2).equilibrium
    np.testing.assert_allclose(hinge_matrix(3) @ eq.q, 1.0, atol=1e-12)
    np.testing.assert_allclose(eq.q[3:], 0.0, atol=1e-12)


def test_an_equilibrium_state_is_accepted_about_itself_and_others_are_refused():
    """An initial state copied from the pre-stressed chain's equilibrium passes the at-rest
    check (its residual is round-off, far below AT_REST_RTOL of its scale) and gives the same
    modes as the equilibrium; rates are refused; a chain held by a load is refused about its
    initial state (loads are left out there) and pointed to the equilibrium, which holds it."""
    scene = _scene(chain=CHAIN.with_(rest_angle=[0.2, -0.4, 0.7]))
    about_eq = modes(scene, "full", about="equilibrium", count=3)
    q, n = about_eq.equilibrium.q, 3
    at_eq = scene.with_(initial=InitialState(phi=q[:n], alpha=q[n : 2 * n], beta=q[2 * n :]))
    R = static_residual(CHAIN, q, rest=scene.chain.rest_angle)
    assert np.max(np.abs(R)) < AT_REST_RTOL * 100
    np.testing.assert_array_equal(modes(at_eq, "full", count=3).omega, about_eq.omega)
    with pytest.raises(ValueError, match=r"not at rest \(initial\.dphi not zero\)"):
        modes(paper_scene().with_(initial=InitialState(dphi=0.1)), "full", count=1)
    loaded = _scene(constant(3, Y=30.0))
    q = modes(loaded, "full", about="equilibrium", count=1).equilibrium.q
    held = loaded.with_(initial=InitialState(phi=q[:n], alpha=q[n : 2 * n], beta=q[2 * n :]))
    with pytest.raises(ValueError, match=r"not an equilibrium.*loads are left out.*equilibrium"):
        modes(held, "full", count=1)
    with pytest.raises(ValueError, match=r"^load_at applies to about='equilibrium' only"):
        modes(paper_scene(), "full", count=1, load_at=0.5)


def test_paper_scene_is_at_rest_and_unchanged():
    """The paper's example starts straight at rest and its pulse is zero at t = 0: modes about
    its initial state are computed as before (no residual recorded)."""
    m = modes(paper_scene(), "full", count=1)
    assert "unbalanced_residual_Nm" not in m.info
    assert m.omega[0] == pytest.approx(0.07814210665527, rel=1e-11)


def test_cli_modes_refuses_an_unbalanced_initial_state_and_takes_the_flag(tmp_path, capsys):
    path = tmp_path / "fold.toml"
    path.write_text('based_on = "paper"\nn = 3\n[chain]\nrest_angle = 1.0\nnu = 0.0\n')
    proc = run_main(capsys, "modes", str(path), "--out", str(tmp_path / "m"))
    assert_refused(
        proc, ["not an equilibrium", "100 N m", "--allow-unbalanced", "--about equilibrium"]
    )
    assert (
        main(
            ["modes", str(path), "--allow-unbalanced", "--count", "2", "--out", str(tmp_path / "m")]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "NOT an equilibrium (static residual 100 N m)" in out
    record = json.loads((tmp_path / "m" / "modes.json").read_text())
    assert record["unbalanced_residual_Nm"] == pytest.approx(100.0, rel=1e-14)


def test_cli_modes_load_at_holds_a_windowed_load(tmp_path, capsys):
    path = tmp_path / "step.toml"
    path.write_text(
        'based_on = "paper"\nn = 3\n[[loads]]\ntype = "constant"\nnode = 3\nY = 30.0\nt_off = 0.6\n'
    )
    assert (
        main(
            [
                "modes",
                str(path),
                "--about",
                "equilibrium",
                "--count",
                "2",
                "--out",
                str(tmp_path / "a"),
            ]
        )
        == 0
    )
    assert (
        "loads left out: constant load at node 3 (acts only until t = 0.6 s)"
        in capsys.readouterr().out
    )
    args = ["modes", str(path), "--about", "equilibrium", "--load-at", "0.3", "--count", "2"]
    assert main([*args, "--out", str(tmp_path / "b")]) == 0
    record = json.loads((tmp_path / "b" / "modes.json").read_text())
    assert record["load_at"] == 0.3 and record["equilibrium"]["left_out_loads"] == []
    assert record["equilibrium"]["phi"][-1] > 1.0


def test_cli_modes_reads_a_run_json_with_its_model(tmp_path, capsys):
    """`rodval modes RUN/run.json` failed with 'malformed TOML'; it now takes the run's scene
    and, unless --model says otherwise, its model."""
    run = tmp_path / "run"
    assert (
        main(["simulate", "paper", "--model", "reduced", "--t-end", "0.1", "--out", str(run)]) == 0
    )
    assert (
        main(["modes", str(run / "run.json"), "--count", "3", "--out", str(tmp_path / "m1")]) == 0
    )
    assert (
        main(
            ["modes", "paper", "--model", "reduced", "--count", "3", "--out", str(tmp_path / "m2")]
        )
        == 0
    )
    capsys.readouterr()
    one = json.loads((tmp_path / "m1" / "modes.json").read_text())
    assert one["model"] == "reduced"
    a = (tmp_path / "m1" / "frequencies.csv").read_text()
    assert a == (tmp_path / "m2" / "frequencies.csv").read_text()


def test_mode_shape_plot_labels_the_shapes_as_normalized(tmp_path, monkeypatch):
    """Shapes were drawn under 'y (m)' as if they were metres: the legend now says they are
    normalized and at what scale they are drawn."""
    from matplotlib.figure import Figure

    from rodval.report.figures import plot_modes

    saved = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: saved.append(self))
    plot_modes(modes(paper_scene(), "full", count=2), tmp_path / "m.png")
    legend = saved[0].axes[0].get_legend()
    texts = [t.get_text() for t in legend.get_texts()]
    assert any(t.startswith("normalized shape (largest node displacement drawn as") for t in texts)


@pytest.mark.exudyn
def test_exudyn_equilibrium_holds_the_rest_angles_and_the_load_at_an_instant():
    """exudyn's static solve ran only with constant loads, so a pre-stressed chain without
    loads stayed straight; it now runs whenever about='equilibrium' (rest angles or loads),
    and holds a windowed load only with load_at. Node positions agree with the native Newton
    within 1e-3 l (axial stretch at EA = 1e8 N and the beam's own bending)."""
    pytest.importorskip("exudyn")
    from rodval.analysis.modes import model_modes

    scene = _scene(constant(3, Y=10.0, t_off=0.6), chain=CHAIN.with_(rest_angle=0.3))
    for load_at in (None, 0.3):
        native = model_modes(scene, "full", about="equilibrium", count=3, load_at=load_at)
        ex = model_modes(scene, "exudyn", about="equilibrium", count=3, load_at=load_at, elements=4)
        x, y = native.node_positions()
        gap = np.max(
            np.hypot(x - ex.info["node_positions"][:, 0], y - ex.info["node_positions"][:, 1])
        )
        print("load_at", load_at, "node gap (m)", gap, "phi", native.equilibrium.phi)
        assert gap < 1e-3 * 2.0
        np.testing.assert_allclose(ex.omega[:3], native.omega[:3], rtol=1e-2)


# ------------------------------------------------------------- API names and statuses (21)


def test_status_reads_the_same_in_python_and_in_files(tmp_path):
    """stats.status was 0 in Python and 'success' in runtime.csv: it is now a Status (an int,
    as run.json stores it) whose text is the file's."""
    import rodval
    from rodval.core.status import STATUS_MESSAGES, Status

    traj = rodval.simulate(paper_scene(t_end=0.05), "reduced")
    assert traj.stats.status is Status.SUCCESS and traj.stats.status == 0
    assert str(traj.stats.status) == "success" == STATUS_MESSAGES[0]
    assert traj.stats.as_dict()["status"] == 0 and type(traj.stats.as_dict()["status"]) is int
    stats = rodval.SolverStats(status=-9)
    assert stats.status is Status.WALL and str(stats.status) == "wall-clock budget exhausted"
    with pytest.raises(ValueError, match="-42 is not a valid Status"):
        rodval.SolverStats(status=-42)


def test_a_misspelt_setting_names_the_integrator_settings_and_the_nearest_name():
    """simulate(..., max_wall=5) was refused with a list of model options only."""
    import rodval

    with pytest.raises(
        ValueError, match=r"integrator settings: .*max_wall_s.*did you mean 'max_wall_s'\?$"
    ):
        rodval.simulate(paper_scene(t_end=0.05), "reduced", max_wall=5)


def test_load_scene_is_exported():
    import rodval

    assert rodval.load_scene("paper").n == paper_scene().n


def test_wide_tables_on_request(tmp_path, capsys):
    """Trajectory.to_frame(wide=True) and simulate --wide: one row per output time, one column
    per quantity and index, the same numbers as the tidy table."""
    import pandas as pd

    import rodval

    traj = rodval.simulate(paper_scene(t_end=0.1, times=[0.05, 0.1]), "full")
    wide = traj.to_frame(wide=True)
    assert list(wide.columns[:3]) == ["t", "phi[1]", "phi[2]"]  # rods k = 1..n
    assert len(wide) == 2 and wide.shape[1] == 1 + sum(a.shape[1] for a in traj.values.values())
    np.testing.assert_array_equal(wide["beta[8]"], traj["beta"][:, 7])
    with pytest.raises(ValueError, match="^wide must be True or False"):
        traj.to_frame(wide="yes")
    out = tmp_path / "run"
    assert (
        main(
            [
                "simulate",
                "paper",
                "--t-end",
                "0.1",
                "--model",
                "reduced",
                "--wide",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    table = pd.read_csv(out / "trajectory_wide.csv")
    tidy = pd.read_csv(out / "trajectory.csv")
    phi3 = tidy[(tidy.quantity == "phi") & (tidy.k == 3)]["value"].to_numpy()
    np.testing.assert_array_equal(table["phi[3]"].to_numpy(), phi3)


def test_the_compiled_loop_reports_progress_without_changing_the_run():
    """A compiled run showed no progress until it ended: with a reporter set it now reports
    the time reached every WALL_CHECK_EVALUATIONS evaluations; the trajectory is bit for bit
    the one without reporting."""
    import rodval
    from rodval.solvers import progress

    scene = paper_scene(times=[0.5, 1.0, 2.0])
    quiet = rodval.simulate(scene, "full")
    seen: list[float] = []
    token = progress._reporter.set(seen.append)
    try:
        loud = rodval.simulate(scene, "full")
    finally:
        progress._reporter.reset(token)
    assert loud.settings["method"] == "DOP853-numba"
    assert len(seen) > 10 and seen == sorted(seen) and 0 < seen[-1] <= 2.0
    for q in quiet.values:
        np.testing.assert_array_equal(loud[q], quiet[q])
