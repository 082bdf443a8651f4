"""Issue 54: the shipped deployment studies' references, valid by their own checks, and what
docs/deployment.md says about them (docs/deployment.md, "Stiff damped panels" and "The wing
on a spacecraft")."""

import re
from pathlib import Path

import numpy as np
import pytest

import rodval
from rodval.core.scene import InitialState, Latch
from rodval.core.validity import ENERGY_RESIDUAL_BOUND, SMALL_BENDING_RAD
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
    assert run.stats.energy_residual is not None
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


def test_the_showcases_error_bar_is_the_one_rodval_reference_measures_without_invalid_levels():
    """studies/deployment.toml's reference_error is the bar `rodval reference` prints for its
    scene (docs/reference_model.md, "A converged reference with an error bar": levels 2/4/8
    elements, the INVALID 2-element level left out since da687c3): rel = 0.043, not the 0.00648
    of a Richardson estimate over that INVALID level. The study copies the printed line, so
    the comparison is exact."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "reference_model.md").read_text()
    showcase = doc[doc.index("Measured on the showcase's scene") :]
    found = re.search(
        r"`reference_error = \{ rel = ([0-9.e-]+), lock_dt = ([0-9.e-]+), impulse_rel =\s+([0-9.e-]+) \}`",
        showcase,
    )
    assert found is not None
    printed = dict(zip(("rel", "lock_dt", "impulse_rel"), map(float, found.groups())))
    agreement = load_study(STUDIES / "deployment.toml").agreement
    assert agreement is not None
    assert agreement["reference_error"] == printed


@pytest.mark.slow
@pytest.mark.exudyn
def test_the_companion_studys_reference_is_valid_by_its_energy_audit_with_margin():
    """studies/companion_three_panel.toml's reference, exudyn at 2 elements per rod and 1e-4 s
    over the study's 6 s: valid, its energy-audit residual (read on every step) 0.0031, within
    half the bound. At the study's former 1e-3 s it was 0.040 (INVALID); step "auto" (0.0084)
    and 4 elements at 2.5e-4 s (0.0087) are valid but within 16 % of the bound, which is why
    the study does not take them. About 15 s under load."""
    pytest.importorskip("exudyn")
    spec = load_study(STUDIES / "companion_three_panel.toml")
    reference = next(m for m in spec.models if m.label == spec.reference)
    run = rodval.simulate(spec.cases[0].scene, reference.model, **reference.options)
    assert run.success
    assert run.stats.valid, run.stats.validity
    # a factor 2 of margin below the bound (the measured 0.0031 carries it three times over)
    assert run.stats.energy_residual is not None
    assert run.stats.energy_residual <= ENERGY_RESIDUAL_BOUND / 2


def test_the_sample_studys_reference_is_valid_by_its_own_checks():
    """studies/deployment_sample.toml's reference, the full model, on the first four points of
    its Sobol sample (the study file with `sample.count = 4`): valid, the largest bending angle
    within the small-bending bound and the energy audit run. On deployment.toml's soft
    undamped panels (EI = 5e3) it was INVALID in 244 of the 256 samples (bending 0.2-0.31 rad,
    the panels ringing after the locks; the first sample 0.31 rad); on the stiff damped panels
    of deployment_stiff_panels.toml (EI = 5e4, 30 % bending damping) it measures 0.040-0.053
    rad and an energy residual below 1e-9. A few seconds."""
    spec = load_study(STUDIES / "deployment_sample.toml", overrides={"sample.count": 4})
    reference = next(m for m in spec.models if m.label == spec.reference)
    for case in spec.cases:
        run = rodval.simulate(case.scene, reference.model, **reference.options)
        assert run.success, case.id
        assert run.stats.valid, (case.id, run.stats.validity)
        assert run.stats.max_bending is not None
        assert run.stats.max_bending <= SMALL_BENDING_RAD
        assert run.stats.energy_residual is not None
