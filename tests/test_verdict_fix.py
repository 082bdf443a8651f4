"""Issue 37, "verdicts that name the fix": every INVALID reason carries the setting that
would address it, in the summary line and in run.json's validity; and the fix it names works.
"""

from __future__ import annotations

from rodval import paper_scene, pulse, simulate
from rodval.core.validity import describe, small_bending, step_resolution

OUTPUTS = ("phi", "alpha", "beta", "energy")


def six_times_the_pulse():
    """The paper chain under 6x the paper's pulse: bending up to 0.14 rad (within the
    small-bending bound), and the first-order full model's energy residual 4.3e-2, beyond
    the 1e-2 bound, at rtol 1e-8 as at 1e-6 (the kinematics, not the integrator)."""
    scene = paper_scene(8, outputs=OUTPUTS)
    return scene.with_(loads=(pulse(8, Xbar=-900.0, Ybar=7200.0),))


def test_the_full_models_broken_energy_balance_names_exact_kinematics_which_closes_it():
    """First-order kinematics: INVALID naming kinematics = "exact"; on that rung the same
    run's residual is integration error only (3e-10 measured at rtol 1e-8; the bound 1e-6
    leaves the tolerance's error 100x room to accumulate over 2 s), so the run is valid."""
    scene = six_times_the_pulse()
    first = simulate(scene, "full", rtol=1e-8, atol=1e-10)
    assert first.stats.valid is False
    text = describe(first.stats.valid, first.stats.validity)
    assert 'fix: kinematics = "exact"' in text, text
    energy = next(c for c in first.stats.validity if c["assumption"] == "energy balance")
    assert energy["fix"].startswith('kinematics = "exact"')
    exact = simulate(scene, "full", kinematics="exact", rtol=1e-8, atol=1e-10)
    assert exact.success and exact.stats.energy_residual < 1e-6
    assert exact.stats.valid is True


def test_the_reduced_models_broken_balance_names_the_full_model():
    """At EI = 1e3 N m^2 the reduced model's residual is 3.9e-2 (docs/stability.md)."""
    scene = paper_scene(8, EI=1e3, outputs=OUTPUTS)
    red = simulate(scene, "reduced")
    assert red.stats.valid is False
    assert "fix: the full model with kinematics" in describe(red.stats.valid, red.stats.validity)


def test_each_check_names_its_fix_only_when_broken():
    """The fixes of the small-bending and step-resolution checks; a check that holds names
    none. The step fix: the step that brings the largest rotation per step to the bound,
    step x bound / seen (2e-4 s x 0.1 / 0.4 = 5e-5 s)."""
    (bent,) = small_bending(0.5)
    assert "fix: stiffer rods (EI), or the exudyn beam model" in bent.reason()
    (ok,) = small_bending(0.01)
    assert "fix" not in ok.reason()
    (coarse,) = step_resolution(0.4, 0.1, step=2e-4)
    assert "fix: step = 5e-05 (command line: --set step=5e-05)" in coarse.reason()
