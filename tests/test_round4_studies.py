"""Issue 54: the shipped deployment studies' references, valid by their own checks, and what
docs/deployment.md says about them (docs/deployment.md, "Stiff damped panels" and "The wing
on a spacecraft")."""

from pathlib import Path

import numpy as np
import pytest

import rodval
from rodval.core.scene import InitialState, Latch
from rodval.core.validity import ENERGY_RESIDUAL_BOUND
from rodval.study import load_study

STUDIES = Path(__file__).resolve().parents[1] / "studies"


@pytest.mark.slow
@pytest.mark.exudyn
def test_the_stiff_studys_reference_is_valid_by_its_energy_audit():
    """studies/deployment_stiff.toml's reference (exudyn_fine) over the study's scene to
    0.65 s, past hinges 3 and 2: its energy audit, read on every recorded step, within the
    bound. At 2.5e-5 s it was not (0.0106: a two-step transient of -7.62 J at hinge 3's
    switch-on, on a scale of 716.85 J); at the study's 1.25e-5 s it is 0.0063, the same as
    over the whole 2.5 s (the largest |R| is at 0.42576 s and the scale is E(0)). About 100 s
    under load."""
    pytest.importorskip("exudyn")
    spec = load_study(STUDIES / "deployment_stiff.toml")
    reference = next(m for m in spec.models if m.label == spec.reference)
    scene = spec.cases[0].scene
    scene = scene.with_(t_end=0.65, times=np.linspace(0.0, 0.65, 131))
    run = rodval.simulate(scene, reference.model, **reference.options)
    assert run.success
    assert run.stats.valid, run.stats.validity
    assert run.stats.energy_residual <= ENERGY_RESIDUAL_BOUND
    assert [e["label"] for e in run.events] == ["latch hinge 3", "latch hinge 2"]


def test_the_five_locked_panels_swing_on_the_free_body_in_11_6_s_not_19():
    """docs/deployment.md, "The wing on a spacecraft": the five outer panels held straight
    (hinges 2-5) swing on hinge 1's 50 N m/rad spring against the free 800 kg body with a
    period of 11.6 s (the full model's linear modes about the straight wing: 0.5404 rad/s,
    11.63 s; the rigid model released at 0.1 rad, measured 11.59 s), not the 19 s of the
    segment pinned to a fixed panel (I = 40 kg x (6 m)^2 / 3 = 480 kg m^2 on 50 N m/rad,
    19.5 s): the body and panel 1 turn back. Bound: the printed digits (0.005 s)."""
    scene = rodval.load_scene(str(STUDIES / "scenes" / "wing6_spacecraft.toml"))
    held = tuple(Latch(k, 0.0, held=True) for k in (2, 3, 4, 5))
    straight = scene.with_(latches=held, initial=InitialState(phi=[0.0] * 6))
    omega = rodval.modes(straight, "full").omega
    assert np.count_nonzero(omega < 1e-6) == 3  # the free body's rigid modes
    swing = 2 * np.pi / omega[3]
    assert swing == pytest.approx(11.63, abs=5e-3)
    pinned = 2 * np.pi * np.sqrt(5 * 8.0 * 6.0**2 / 3 / 50.0)
    assert pinned > 19.0 > swing
