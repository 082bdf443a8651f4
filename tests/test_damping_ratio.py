"""Bending damping stated as a modal damping ratio (issue 37, ``rodval.core.damping``):
``[chain] bending_damping = { ratio = 0.01 }`` becomes, per rod, the Kelvin-Voigt c (N m^2 s)
that gives the rod's first free-free bending mode that ratio, and that c is what the scene,
run.json and every model hold."""

import json

import numpy as np
import pytest
import scipy.linalg

from rodval.cli import main
from rodval.core.damping import bending_damping_for_ratio, first_free_free_frequency
from rodval.core.scene_file import scene_from_dict
from rodval.mechanics.lock_window import _element

WING = {
    "n": 3,
    "t_end": 0.02,
    "chain": {"l": [1.2, 1.0, 0.8], "m": 8.0 / 1.2, "EI": [1e8, 2e4, 5e5]},
}


def _free_free_fe(l: float, m: float, EI: float, elements: int = 32) -> float:
    """The first flexible eigenfrequency (rad/s) of a free-free beam of cubic Hermite
    elements (consistent mass): independent of the closed form's beta_1 l."""
    size = 2 * (elements + 1)
    K, M = np.zeros((size, size)), np.zeros((size, size))
    for e in range(elements):
        k, me = _element(EI, m, l / elements)
        K[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += k
        M[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += me
    lam = scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, 2])
    return float(np.sqrt(lam[2]))  # two rigid modes (translation, rotation) first


@pytest.mark.parametrize("l, m, EI", [(1.2, 8.0 / 1.2, 2e4), (2.0, 3.0, 1e5), (0.5, 10.0, 1e9)])
def test_the_first_free_free_frequency_is_the_beams(l, m, EI):
    """The Hermite element's frequency error falls as h^4 (from above): 32 elements give it
    to ~1e-7 relative; bound 1e-6."""
    fe = _free_free_fe(l, m, EI)
    closed = float(first_free_free_frequency(l, m, EI))
    assert abs(fe / closed - 1.0) < 1e-6


def test_the_ratio_gives_that_mode_the_stated_damping_ratio():
    """A Kelvin-Voigt rod's modes have zeta = c omega / (2 EI) (docs/model.md): converted
    back, each rod's first mode has exactly the ratio asked for."""
    scene = scene_from_dict(
        {**WING, "chain": {**WING["chain"], "bending_damping": {"ratio": 0.01}}}
    )
    ch = scene.chain
    zeta = ch.bending_damping * first_free_free_frequency(ch.l, ch.m, ch.EI) / (2.0 * ch.EI)
    np.testing.assert_allclose(zeta, 0.01, rtol=1e-14)
    per_rod = scene_from_dict(
        {**WING, "chain": {**WING["chain"], "bending_damping": {"ratio": [0.0, 0.01, 0.02]}}}
    ).chain.bending_damping
    np.testing.assert_allclose(per_rod, [0.0, ch.bending_damping[1], 2 * ch.bending_damping[2]])


@pytest.mark.parametrize(
    "value, words",
    [
        ({"ratio": 1.0}, ">= 0 and < 1"),
        ({"ratio": -0.01}, ">= 0 and < 1"),
        ({"ratio": True}, "key 'chain.bending_damping.ratio': must be a number"),
        ({"ratio": [0.01, 0.02]}, "one per rod (3), got 2"),
        ({"ratio": 0.01, "c": 3.0}, "takes no other key"),
    ],
)
def test_a_bad_ratio_is_refused_naming_it(value, words):
    with pytest.raises(ValueError, match="bending_damping") as err:
        scene_from_dict({**WING, "chain": {**WING["chain"], "bending_damping": value}})
    assert words in str(err.value)


def test_run_json_records_the_converted_damping_in_n_m2_s(tmp_path):
    text = (
        "n = 3\nt_end = 0.02\ntimes = [0.0, 0.01, 0.02]\n[chain]\nl = [1.2, 1.0, 0.8]\nm = 6.0\n"
        "EI = [1e8, 2e4, 5e5]\nbending_damping = { ratio = 0.01 }\n"
    )
    (tmp_path / "wing.toml").write_text(text)
    out = tmp_path / "run"
    assert (
        main(["simulate", str(tmp_path / "wing.toml"), "--model", "full", "--out", str(out)]) == 0
    )
    recorded = json.loads((out / "run.json").read_text())["scene"]["chain"]["bending_damping"]
    expected = bending_damping_for_ratio(0.01, [1.2, 1.0, 0.8], 6.0, [1e8, 2e4, 5e5])
    np.testing.assert_allclose(recorded, expected, rtol=1e-15)


def test_a_budget_spent_on_a_stiff_vibration_names_it_and_the_fixes():
    """The rigid two-rod latch with EI 1e9 undamped: DOP853's steps are held by the rods'
    bending modes; the run that runs out of evaluations says at which frequency, what the rest
    would cost and which settings would let it finish (issue 37)."""
    from rodval.bench.stiffness import rigid_latch
    from rodval.core.status import STATUS_BUDGET
    from rodval.models import simulate

    stats = simulate(rigid_latch(1e9), "full", max_evaluations=100_000).stats
    assert stats.status == STATUS_BUDGET
    rho = stats.switch["spectral_radius"]
    assert f"held by a vibration of {rho:.4g} rad/s" in stats.message
    assert "more evaluations to t_end" in stats.message
    assert "fix: damp the rods' bending ([chain] bending_damping = { ratio" in stats.message
    assert "the reduced model" in stats.message


def _proposed_budget(scene) -> float:
    """The max_evaluations the message of a run held at 100,000 evaluations proposes."""
    import re

    from rodval.models import simulate

    stats = simulate(scene, "full", max_evaluations=100_000).stats
    return float(re.search(r"max_evaluations = ([0-9.e+]+) would reach it", stats.message)[1])


@pytest.mark.slow
def test_the_proposed_budget_reaches_t_end():
    """Reaching for the budget the message proposes finishes (4.5e7 evaluations, about 100 s:
    slow, split from the message's test below)."""
    from rodval.bench.stiffness import rigid_latch
    from rodval.models import simulate

    scene = rigid_latch(1e9)
    assert simulate(scene, "full", max_evaluations=int(_proposed_budget(scene))).stats.success


def test_a_held_budget_names_the_budget_that_would_finish_and_only_fixes_the_scene_takes():
    """The message gives the max_evaluations that would reach t_end (used plus the predicted
    rest, a quarter more for the rate's change; that it finishes: the slow test above); on a
    free base it does not propose the reduced model, which refuses one (issue 49: it did)."""
    from rodval.bench.stiffness import rigid_latch
    from rodval.core.base import Base
    from rodval.core.status import STATUS_BUDGET
    from rodval.models import simulate

    scene = rigid_latch(1e9)
    assert _proposed_budget(scene) > 100_000
    free = scene.with_(base=Base(kind="free", mass=800.0, inertia=533.0))
    held = simulate(free, "full", max_evaluations=100_000).stats
    assert held.status == STATUS_BUDGET and "would reach it" in held.message
    assert "reduced model" not in held.message and "the rigid model" in held.message
