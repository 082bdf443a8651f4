"""Issue 54, round four: study reports and animations that crashed or misled.

1. a twin run ([agreement.twin]) over a grid crashed the figures against a grid parameter;
2. a run that never locked crashed the answer's lock list, and a latch that never locked was
   described as deployed;
3. a free-base run without x, y was animated (API) with its root pinned at the origin;
4. the animation's event list covered the chain;
5. study figures drew a free base's chain from a pin at the origin with no body; a grid axis
   ``scene.chain.kappa.first`` was named "first".
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

import rodval
from rodval.core.base import Base
from rodval.core.scene import Chain, InitialState, Latch, Scene
from rodval.report import animation, figures
from rodval.report.study_answer import answer_section
from rodval.report.study_figures import param_figures
from rodval.report.study_report import build_report, residual_vibration
from rodval.report.tables import axis_columns, read_events, read_tables
from rodval.study import load_study, run_study

#: A three-rod latched chain (tests/scenes.py ``latch3_toml``'s, hinge 0 on a profile so that
#: ``kappa.first`` can be a grid axis): hinge 2 locks at t = 0.318 s, hinge 1 at 0.698 s. The
#: grid's t_end = 0.25 s ends before any lock, 0.5 s between the two; the reference's twin.
STUDY = """
[study]
name = "round4"
reference = "full"

[scene]
n = 3
t_end = 0.5
times = { num = 51 }
outputs = ["phi", "x", "y"]
loads = []

[scene.chain]
l = 1.5
m = 3.0
EI = 1e5
mu = 0.5
kappa = { first = [0.0], rest = 50.0 }
nu = 0.0

[scene.initial]
phi = [0.0, 3.0915926535897933, 0.0]

[[scene.latches]]
hinge = 1
angle = 0.0

[[scene.latches]]
hinge = 2
angle = 0.0

[models.full]
[models.reduced]

[grid]
"scene.chain.kappa.first" = [0.0, 1.0]
"scene.t_end" = [0.25, 0.5]

[agreement]
twin = { rod = 2, angle = 1e-6 }
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The study's folder (tables, no report) and its tables, events and study.json."""
    tmp = tmp_path_factory.mktemp("round4")
    (tmp / "round4.toml").write_text(STUDY)
    run_study(load_study(tmp / "round4.toml"), tmp / "out", workers=1, progress=False, report=False)
    out = tmp / "out"
    meta = json.loads((out / "study.json").read_text())
    return out, meta, read_tables(out), read_events(out)


# -- 1. the twin in the figures against a grid parameter --------------------------------------


def test_the_twin_is_drawn_in_the_figures_against_a_grid_parameter(study, tmp_path):
    """param_figures raised KeyError: 'full twin': the line styles knew the study's models
    only, not the reference's twin run that the discrepancy and run-time tables hold."""
    out, meta, tables, _ = study
    assert "full twin" in set(tables["runtime"]["model"])
    params = ["n", "horizon", *axis_columns(meta).values()]
    lines = param_figures(tmp_path, meta, tables, params)
    drawn = {p.name for p in tmp_path.iterdir()}
    assert {"discrepancy_vs_kappa.first.png", "runtime_vs_kappa.first.png"} <= drawn
    assert any("figures/runtime_vs_kappa.first.png" in line for line in lines)


def test_model_styles_cover_every_run_drawn_in_the_studys_order():
    styles = figures.model_styles(["full", "reduced"], ["reduced", "full twin", "full"])
    assert list(styles) == ["full", "reduced", "full twin"]
    assert styles["full twin"]["color"] not in (styles["full"]["color"], styles["reduced"]["color"])


# -- 2. runs that never lock -------------------------------------------------------------------


def test_the_answer_of_a_case_where_nothing_locked_is_written(study):
    """answer_section raised KeyError: 't' (lock_list of a run without locks in a study
    with events: the empty selection of labels read as a list of columns)."""
    _, meta, tables, events = study
    assert not events[events["case"].str.contains("t_end=0.25")].shape[0]
    text = "\n".join(answer_section(meta, tables, events))
    assert "## Answer" in text


def test_latches_that_never_locked_are_named_and_the_structure_not_called_deployed(study):
    """Where a latch never locked within the horizon the answer said nothing of it (and
    called the state after the last lock 'deployed'): it names the latches and says the
    structure is not deployed, in the sentences and in the table's ``deployed`` column."""
    _, meta, tables, events = study
    text = "\n".join(answer_section(meta, tables, events))
    # t_end = 0.5 s: hinge 2 locked (0.318 s), hinge 1 not (0.698 s)
    assert "(case `first=0,t_end=0.5`) is valid, not deployed: latch hinge 1 never locked" in text
    assert "no: latch hinge 1, latch hinge 2 never locked" in text  # t_end = 0.25 s
    assert "no: latch hinge 1 never locked" in text
    assert "deployed angles" not in text  # no run deployed: no deployed state to compare
    assert "angles after the last lock (not deployed)" in text
    assert "latch hinge 1 never locked in either run" in text


def test_the_residual_vibration_names_the_latches_that_never_locked(study):
    """The residual vibration table described a half-open chain's motion as a deployed
    one's and left out the runs that never locked: ``never_locked`` says which did not."""
    _, _, tables, events = study
    resid = residual_vibration(tables["trajectories"], events, tables["cases"])
    by = resid.set_index(["case", "model"])["never_locked"]
    assert by[("first=0,t_end=0.5", "full")] == "latch hinge 1"
    assert by[("first=0,t_end=0.25", "reduced")] == "latch hinge 1, latch hinge 2"


@pytest.mark.slow  # the whole report (17 s here); the tests above check its parts
def test_the_report_of_the_study_is_written(study):
    """rodval report on the folder ended in an internal error (items 1 and 2)."""
    out, *_ = study
    report = build_report(out).read_text()
    assert "### Against kappa.first" in report
    assert "`never_locked`: the latches that did not lock within the run" in report


# -- 3. the API animates a free base where it is, or refuses ---------------------------------


def _free_latch(outputs: tuple[str, ...]) -> Scene:
    """Two rods unfolding from a 10 kg free body (hinge offset 0.5 m), latch at 0 (locks at
    t = 0.355 s)."""
    chain = Chain.uniform(2, l=1.5, m=3.0, EI=1e5, mu=0.5, kappa=[0.0, 50.0], nu=0.0)
    base = Base(kind="free", mass=10.0, inertia=5.0, hinge_offset=(0.5, 0.0))
    return Scene(
        chain=chain,
        t_end=0.4,
        times=np.linspace(0.0, 0.4, 41),
        outputs=outputs,
        initial=InitialState(phi=[0.0, math.pi - 0.05], dphi=[1.0, 1.0]),
        latches=(Latch(1, 0.0),),
        base=base,
    )


def test_the_api_refuses_a_free_base_it_cannot_place(tmp_path):
    """animate_runs without ``bases`` took a free-base run (outputs phi only) as pinned and
    drew its root at the origin; the run carries its scene, whose base it now uses: refused
    in one line naming the missing outputs."""
    traj = rodval.simulate(_free_latch(("phi",)), model="full")
    with pytest.raises(ValueError, match="base_position, base_attitude") as err:
        animation.animate_runs({"free": traj}, {"free": traj.scene.chain.l}, tmp_path / "a.gif")
    assert "\n" not in str(err.value)
    assert not (tmp_path / "a.gif").exists()


# -- 4. the event list beside the drawing --------------------------------------------------


def test_the_event_list_never_covers_the_drawing(tmp_path, monkeypatch):
    """The event list was written in the axes' lower left corner, over the chain: it is
    beside the axes, at most LISTED_EVENTS + 1 lines."""
    made = []
    frame_axes = animation._frame_axes

    def keep(*args, **kw):
        made.append(frame_axes(*args, **kw))
        return made[-1]

    monkeypatch.setattr(animation, "_frame_axes", keep)
    traj = rodval.simulate(_free_latch(("phi", "x", "y", "base")), model="full")
    lengths = {"a": traj.scene.chain.l, "b": traj.scene.chain.l}
    animation.animate_runs({"a": traj, "b": traj}, lengths, tmp_path / "a.gif", frames=3)
    fig, ax = made[0]
    renderer = FigureCanvasAgg(fig).get_renderer()
    frame = ax.get_window_extent(renderer)
    listed = [t for t in [*fig.texts, *ax.texts] if "latch hinge 1" in t.get_text()]
    assert listed
    for text in listed:
        assert not text.get_window_extent(renderer).overlaps(frame)


def test_the_event_list_keeps_the_latest_events():
    events = [(0.1 * i, f"e{i}") for i in range(20)]
    lines = animation.listed(events)
    assert len(lines) == animation.LISTED_EVENTS + 1
    assert lines[0] == f"... {20 - animation.LISTED_EVENTS} earlier" and lines[-1] == "e19"
    assert animation.listed(events[:3]) == ["e0", "e1", "e2"]
    assert animation.listed([(0.3, "b: latch"), (0.1, "a: latch")]) == ["a: latch", "b: latch"]


# -- 5. study figures of a free base; the name of an axis -------------------------------------


def test_a_free_base_is_drawn_with_its_body_and_no_pin(tmp_path, monkeypatch):
    """plot_configurations drew the pin at the origin for a free base's chain, and no
    body: the body is a square at its pose with node 0 on its edge, and no pin."""
    traj = rodval.simulate(_free_latch(("phi", "x", "y", "base")), model="full")
    drawn = []
    monkeypatch.setattr(figures, "write_figure", lambda fig, path, **kw: drawn.append(fig))
    l = np.asarray(traj.scene.chain.l)
    figures.plot_configurations({"full": traj}, [0.0, 0.4], l, tmp_path / "c.png")
    ax = drawn[0].axes[0]
    markers = [line.get_marker() for line in ax.lines]
    assert "^" not in markers  # no pin
    body = figures.body_at(traj, float(traj.times[-1]), l)
    assert body is not None
    x0, y0 = traj["x"][-1, 0], traj["y"][-1, 0]
    cx, cy = traj["base_position"][-1]
    # node 0 lies on the square's edge: its distance to the centre is the half side, along
    # the body's x axis for the hinge offset (0.5, 0): to rounding (1e-12 m)
    half = np.hypot(x0 - cx, y0 - cy)
    # node 0 = r_c + R(theta) h with |h| = 0.5 m, a rotation of the body's offset: exact but
    # for rounding (a few ulps of 1 m)
    assert half == pytest.approx(0.5, abs=1e-12)
    corners = np.hypot(body[0][:4] - cx, body[1][:4] - cy)
    np.testing.assert_allclose(corners, math.sqrt(2) * half, rtol=1e-12)


def test_a_moving_base_without_x_y_is_not_drawn_from_the_origin(tmp_path):
    """chain_nodes hung a moving base's chain from the origin when its outputs had no x, y
    (base outputs only): refused; the study figures name the run instead of drawing it."""
    traj = rodval.simulate(_free_latch(("phi", "base")), model="full")
    assert not figures.drawable(traj)
    with pytest.raises(ValueError, match="moving base but no x, y"):
        figures.chain_nodes(traj, 0.0, np.asarray(traj.scene.chain.l))


def test_a_profile_key_axis_is_named_with_its_key(study):
    """A grid axis scene.chain.kappa.first was named 'first' in the figures: kappa.first."""
    from rodval.report.study_figures import axis_names, key_name

    _, meta, _, _ = study
    assert axis_names(meta) == {"first": "kappa.first"}
    assert key_name("scene.initial.phi.1", "1") == "phi.1"
    assert key_name("scene.latches.*.angle", "angle") == "angle"
    assert key_name("scene.chain.EI", "EI") == "EI"


# -- of the same kind: a failed run, a figure without any line --------------------------------


def test_a_failed_run_is_not_said_to_agree_until_the_end():
    """A run that failed at t = 0 'agreed with the reference until the end (0 s)': it agrees
    until its failure, where the run ends."""
    from rodval.report.study_answer import _until

    row = pd.Series({"role": "model", "status": "failed", "horizon": math.nan, "compared_to": 0.0})
    assert _until(row) == "its failure at t = 0 s (the run ends there)"
    done = row.copy()
    done["status"], done["compared_to"] = "success", 0.8
    assert _until(done) == "the end (0.8 s)"


def test_a_run_compared_with_a_reference_that_failed_is_not_said_to_agree_until_the_end():
    """A reference stopped by its evaluation budget at 0.0185 s of 0.3 s made the reduced
    model 'agree with full until the end (0 s)' (tests/test_fuzz_round4.py's find): the pair
    is compared up to the reference's failure, and the answer says so."""
    from rodval.report.study_answer import _until

    row = pd.Series({"role": "model", "status": "success", "horizon": math.nan, "compared_to": 0.0})
    ref = pd.Series({"role": "reference", "status": "evaluation budget exhausted"})
    assert _until(row, ref) == "the reference's failure at t = 0 s (compared that far)"
    assert _until(row, ref.replace("evaluation budget exhausted", "success")) == "the end (0 s)"


def test_a_figure_against_a_parameter_without_any_successful_run_says_so(tmp_path):
    """The run-time figure of a study whose runs all failed drew empty axes with an empty
    legend (matplotlib's warning): it says there is nothing to draw."""
    runtime = pd.DataFrame(
        {"case": ["a", "b"], "EI": [1.0, 2.0], "model": ["full"] * 2, "status": ["failed"] * 2}
    ).assign(wall_s=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        path = figures.plot_runtime_vs(runtime, "EI", [], ["full"], tmp_path / "r.png")
    assert path.is_file()


FREE_STUDY = """
[study]
name = "free"
reference = "full"

[scene]
n = 2
t_end = 0.4
times = { num = 41 }
outputs = ["phi"]
loads = []

[scene.chain]
l = 1.5
m = 3.0
EI = 1e5
mu = 0.5
kappa = [0.0, 50.0]
nu = 0.0

[scene.initial]
phi = [0.0, 3.0915926535897933]
dphi = [1.0, 1.0]

[[scene.latches]]
hinge = 1
angle = 0.0

[scene.base]
kind = "free"
mass = 10.0
inertia = 5.0
hinge_offset = [0.5, 0.0]

[models.full]
"""


def test_study_figures_do_not_hang_a_free_base_from_the_origin(tmp_path):
    """A free-base study whose outputs have no x, y drew its configurations and deployment
    from a pin at the origin (the chain as if pinned): cases.csv records the base kind, and
    the report names the runs it cannot place instead of drawing them."""
    from rodval.report.study_figures import case_figures, deployment_figures

    (tmp_path / "free.toml").write_text(FREE_STUDY)
    out = tmp_path / "out"
    run_study(load_study(tmp_path / "free.toml"), out, workers=1, progress=False, report=False)
    meta = json.loads((out / "study.json").read_text())
    tables, events = read_tables(out), read_events(out)
    fig_dir = tmp_path / "figures"
    fig_dir.mkdir()
    lines = case_figures(fig_dir, meta, tables) + deployment_figures(fig_dir, meta, tables, events)
    text = "\n".join(lines)
    assert "Chain not drawn for `full`: a moving base without outputs x, y" in text
    assert not list(fig_dir.glob("configurations_*")) and not list(fig_dir.glob("deployment_*"))
    assert list(fig_dir.glob("history_*"))  # the time histories need no placing
    assert list(tables["cases"]["base_kind"]) == ["free"]
