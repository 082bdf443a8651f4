"""Per-rod profiles (issue 21): one scene or one study grid over n describes a non-uniform chain
of any length; case ids stay short with the full values in cases.csv."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rodval.core.profiles import resolve_profile
from rodval.core.scene_file import scene_from_dict
from rodval.study.spec import MAX_VALUE_TEXT, case_value_text, study_from_dict


@pytest.mark.parametrize(
    "spec, n, expected",
    [
        ({"first": [5e4], "rest": 1e4}, 4, [5e4, 1e4, 1e4, 1e4]),
        ({"first": 5e4, "rest": 1e4}, 1, [5e4]),
        ({"rest": 2.0}, 3, [2.0, 2.0, 2.0]),
        ({"first": [1.0], "repeat": [2.0, 3.0]}, 6, [1.0, 2.0, 3.0, 2.0, 3.0, 2.0]),
        ({"at": [0.0, 1.0], "values": [10.0, 2.0]}, 4, [9.0, 7.0, 5.0, 3.0]),  # x = 1/8 ... 7/8
        ({"at": [0.5], "values": [7.0]}, 3, [7.0, 7.0, 7.0]),
    ],
)
def test_profiles_give_n_values(spec, n, expected):
    np.testing.assert_allclose(resolve_profile("EI", spec, n), expected, rtol=1e-15)


@pytest.mark.parametrize(
    "spec, words",
    [
        ({"first": [1.0]}, "exactly one of 'rest', 'repeat' or 'at'"),
        ({"rest": 1.0, "repeat": [1.0]}, "exactly one of"),
        ({"rest": [1.0, 2.0]}, "'rest' must be one number"),
        (
            {"first": [1.0, 2.0, 3.0, 4.0, 5.0], "rest": 1.0},
            "'first' has 5 values, more than n = 4",
        ),
        ({"at": [0.0, 1.0], "values": [1.0]}, "same length"),
        ({"at": [0.5, 0.2], "values": [1.0, 2.0]}, "must increase within \\[0, 1\\]"),
        ({"at": [0.0, 1.5], "values": [1.0, 2.0]}, "must increase within \\[0, 1\\]"),
        ({"rest": "x"}, "'rest' must be a number"),
        ({"rest": True}, "'rest' must be a number"),
        ({"rest": 1.0, "step": 2}, "unknown key 'step'"),
        ({"repeat": []}, "'repeat' must be a non-empty list"),
    ],
)
def test_bad_profiles_are_refused_naming_the_array_and_key(spec, words):
    with pytest.raises(ValueError, match=words):
        resolve_profile("EI", spec, 4)


def test_a_scene_file_profile_builds_the_chain_and_still_checks_bounds():
    doc = {
        "based_on": "paper",
        "n": 5,
        "chain": {"EI": {"first": [5e4], "rest": 1e4}, "m": {"at": [0, 1], "values": [4, 2]}},
    }
    scene = scene_from_dict(doc, where="wing.toml")
    np.testing.assert_array_equal(scene.chain.EI, [5e4, 1e4, 1e4, 1e4, 1e4])
    np.testing.assert_allclose(scene.chain.m, [3.8, 3.4, 3.0, 2.6, 2.2], rtol=1e-14)
    with pytest.raises(ValueError, match=r"^wing\.toml \[chain\]: EI profile: unknown key"):
        scene_from_dict(
            {"based_on": "paper", "n": 2, "chain": {"EI": {"rst": 1.0}}}, where="wing.toml"
        )
    with pytest.raises(ValueError, match=r"EI"):  # the chain's own bounds: EI > 0
        scene_from_dict(
            {"based_on": "paper", "n": 2, "chain": {"EI": {"rest": -1.0}}}, where="wing.toml"
        )


def test_one_grid_sweeps_n_for_a_non_uniform_chain_with_short_ids():
    """The new user's wing: a root rod and repeated panels, n over 4, 8, 16 by one grid axis
    (before: one [[grid]] per n with hand-written lists, 200-character case ids)."""
    doc = {
        "scene": {
            "based_on": "paper",
            "t_end": 0.1,
            "chain": {
                "EI": {"first": [5e4], "rest": 1e4},
                "kappa": {"first": [500.0], "repeat": [80.0, 120.0]},
            },
        },
        "models": {"reduced": {}},
        "grid": {"scene.n": [4, 8, 16]},
    }
    spec = study_from_dict(doc, where="wing")
    assert [c.id for c in spec.cases] == ["n=4", "n=8", "n=16"]
    assert [c.scene.n for c in spec.cases] == [4, 8, 16]
    np.testing.assert_array_equal(spec.cases[2].scene.chain.kappa[:4], [500.0, 80.0, 120.0, 80.0])


def test_long_grid_values_get_a_short_stable_id_and_stay_whole_in_cases_csv():
    long = [1e4 + i for i in range(16)]
    text = case_value_text(long)
    assert text.startswith("list16-") and len(text) <= MAX_VALUE_TEXT
    assert case_value_text(long) == text and case_value_text(long[::-1]) != text
    assert case_value_text(
        [{"type": "pulse", "node": "last", "Xbar": -1500.0, "Ybar": 12000.0}]
    ).startswith("pulse-")
    assert case_value_text(8) == "8" and case_value_text(1e-6) == "1e-06"
    from rodval.study.tables import _case_columns

    class Rec:
        case, n, t_end, params = "x", 16, 1.0, {"EI": long}

    assert json.loads(_case_columns(Rec, {"EI": "EI"}, full=True)["EI"]) == long
    assert _case_columns(Rec, {"EI": "EI"})["EI"] == text


def test_every_figure_title_fits_its_figure(tmp_path):
    """Figure titles were cut at both edges by long case ids: a title is now wrapped to the
    figure's width. Measured: the rendered title's extent lies within the figure's."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from rodval.report.figures import _figure, _save, fit_title

    title = "case " + ",".join(f"EI{i}=1e4+{i}" for i in range(30)) + " against exudyn"
    for width in (4.0, 7.0):
        fig, ax = _figure(1, 1, figsize=(width, 3))
        ax.plot([0, 1], [0, 1])
        _save(fig, tmp_path / "f.png", title=title)
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        box = fig._suptitle.get_window_extent(canvas.get_renderer())
        assert box.x0 >= 0 and box.x1 <= fig.bbox.width, (box, fig.bbox.width)
        assert fig._suptitle.get_text().count("\n") >= 1
    assert fit_title("short", 7.0, 12) == "short"
