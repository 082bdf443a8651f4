"""exudyn's energy audit of the rods' Kelvin-Voigt bending damping at start-up (issue 37;
docs/deployment.md, "Where the lock energy goes", "exudyn's start-up with bending damping").

The deployment_stiff scene (EI 1e7, bending damping 2500 N m^2 s, stowed with pre-stressed
hinge springs) starts at rest out of equilibrium. With generalized-alpha's computed initial
accelerations (exudyn's default ``computeInitialAccelerations``), the step after t = 0 kicks
the element-scale bending modes, which the damping makes overdamped: E rises by tens of J
within a few steps, no load acting, and the damping then takes that energy out. The audit
books that removal as exudyn's ``bendingDamping`` law defines it (c int K' delta K ds), so R
rises over the first ten or so steps and then stays flat: the residual is the energy the
integrator put in, not a mis-booked dissipation. Without the computed initial accelerations
the start is clean: the audit balances to 1e-6 of E and the booked dissipation converges with
refinement to the full model's.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from rodval import simulate
from rodval.core.scene_file import scene_from_dict
from rodval.core.validity import ENERGY_RESIDUAL_BOUND

pytest.importorskip("exudyn")
from reference_models.exudyn_chain import ExudynModel  # noqa: E402

pytestmark = pytest.mark.exudyn

STUDY = Path(__file__).resolve().parents[1] / "studies" / "deployment_stiff.toml"
#: the study's three exudyn refinements: (elements per rod, step (s))
REFINEMENTS = ((2, 2e-4), (4, 1e-4), (8, 2.5e-5))


def stiff_scene(t_end: float, num: int):
    """The deployment_stiff study's scene over a short horizon (no lock before 0.42 s)."""
    with STUDY.open("rb") as f:
        d = dict(tomllib.load(f)["scene"])
    d.update(t_end=t_end, times={"num": num})
    return scene_from_dict(d)


@pytest.fixture
def initial_accelerations(monkeypatch):
    """Set exudyn's generalizedAlpha.computeInitialAccelerations for the runs of a test
    (whatever ExudynModel's default is)."""

    def use(flag: bool) -> None:
        settings = ExudynModel._settings

        def patched(self, scene):
            s = settings(self, scene)
            s.timeIntegration.generalizedAlpha.computeInitialAccelerations = flag
            return s

        monkeypatch.setattr(ExudynModel, "_settings", patched)

    return use


def run(scene, E: int, h: float):
    tr = simulate(scene, "exudyn", elements=E, step=h, spectral_radius=0.0)
    assert tr.success, tr.stats.message
    return tr


def test_startup_residual_is_the_integrators_energy(initial_accelerations):
    """Computed initial accelerations (4 elements, 1e-4 s, every step an output): E rises by
    more than 10 J within the first steps with no load acting, the damping takes it out again,
    and from 2 ms on R = E - E(0) + D stays constant to 1e-5 of itself: the audit books
    exactly the energy E loses, and R is what the start-up put in (about 115 J)."""
    initial_accelerations(True)
    scene = stiff_scene(0.01, 101)
    tr = run(scene, 4, 1e-4)
    energy = tr["energy"][:, 0]
    R = tr["energy_residual"][:, 0]
    D = tr["dissipated"][:, 0]
    assert np.max(energy[:5] - energy[0]) > 10.0
    late = tr.times >= 2e-3
    assert R[-1] > 100.0
    assert np.ptp(R[late]) < 1e-5 * R[-1]
    # the energy lost after 2 ms is what the audit books: dE + dD = 0
    i = np.flatnonzero(late)[0]
    assert abs((energy[-1] - energy[i]) + (D[-1] - D[i])) < 1e-3
    assert tr.stats.energy_residual > ENERGY_RESIDUAL_BOUND


def test_clean_start_balances_and_converges_to_the_full_model(initial_accelerations):
    """Without computed initial accelerations, at the study's three refinements over 0.05 s:
    the residual is far below the validity bound, the booked dissipation converges (each
    refinement closer to the full model's, the last change smaller than the coarser run's
    gap) to within 0.5 % of the full model's (0.12 % at 8 elements), which resolves the same
    damping laws."""
    initial_accelerations(False)
    scene = stiff_scene(0.05, 51)
    reference = float(simulate(scene, "full")["dissipated"][-1, 0])
    booked = []
    for E, h in REFINEMENTS:
        tr = run(scene, E, h)
        assert tr.stats.energy_residual < 1e-3 * ENERGY_RESIDUAL_BOUND
        booked.append(float(tr["dissipated"][-1, 0]))
    gaps = np.abs(np.array(booked) - reference)
    assert gaps[2] < gaps[1] < gaps[0]
    assert abs(booked[2] - booked[1]) < gaps[1]
    assert gaps[2] < 5e-3 * reference


def test_default_start_is_valid():
    """exudyn with the model's default settings: a scene with bending damping starts from
    a = 0 (``initial_kick``, recorded in the run's settings), so the start-up's residual is
    within the validity bound (it was 0.161 with computed initial accelerations)."""
    scene = stiff_scene(0.05, 51)
    tr = run(scene, 4, 1e-4)
    assert tr.settings["initial_accelerations"] is False
    assert tr.stats.energy_residual < ENERGY_RESIDUAL_BOUND
