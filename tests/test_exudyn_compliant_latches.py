"""Compliant latches in the exudyn reference model (issue 56): the latch's two stops' laws on
the hinge's rotation markers, zero until the hinge crosses the latch angle (detected as an
ideal latch's crossing, without locking), against the native full model: engagement time,
peak hinge moment after it (on exudyn's recorded steps) and the energy the latch's damper
takes out."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodval import Chain, InitialState, Scene
from rodval.core.hinges import CompliantLatch
from rodval.core.scene import Latch
from rodval.models.registry import simulate

exu = pytest.importorskip("exudyn")

pytestmark = pytest.mark.exudyn

LATCH = CompliantLatch(1, 0.0, stiffness=1e4, damping=5.0)


def unfolding_pair(latch: Latch | CompliantLatch) -> Scene:
    """Two rods (l = 1.5 m, m = 3 kg/m, EI = 1e7 N m^2, mu = 0.5 kg), hinge 0 free, hinge 1
    stowed at pi - 0.05 rad unfolding on a 50 N m/rad spring, both turning at 1 rad/s; the
    latch on hinge 1 at 0 rad; 0.6 s at 2001 output times."""
    chain = Chain.uniform(2, l=1.5, m=3.0, EI=1e7, mu=0.5, kappa=[0.0, 50.0], nu=0.0)
    items = {"compliant_latches": (latch,)} if isinstance(latch, CompliantLatch) else {}
    return Scene(
        chain=chain,
        t_end=0.6,
        times=np.linspace(0.0, 0.6, 2001),
        outputs=("phi", "hinge_angle", "hinge_moment", "energy"),
        initial=InitialState(phi=[0.0, math.pi - 0.05], dphi=[1.0, 1.0]),
        latches=() if items else (latch,),
        **items,
    )


@pytest.fixture(scope="module")
def runs():
    """The compliant latch's scene in exudyn and in the native full model."""
    scene = unfolding_pair(LATCH)
    exudyn, native = simulate(scene, "exudyn"), simulate(scene, "full")
    assert exudyn.success, exudyn.stats.message
    assert native.success, native.stats.message
    return exudyn, native


def engagement(trajectory) -> float:
    """The time (s) of the run's one "latch hinge 1" event."""
    (t,) = [ev["t"] for ev in trajectory.events if ev["label"] == "latch hinge 1"]
    return float(t)


def hinge_peak(trajectory) -> tuple[float, float]:
    """(peak |hinge moment| of hinge 1, N m; its time, s) of the run's recorded peaks."""
    (row,) = [r for r in trajectory.stats.peaks["values"]["hinge_moment"] if r["k"] == 1]
    return float(row["peak"]), float(row["t"])


def test_engages_with_the_native_model_and_the_ideal_latch(runs):
    """One engagement, no impact: within 0.1 ms of the native full model's (whose engagement
    is its ideal latch's lock time to 1e-9 s, tests/test_compliant_latches.py; exudyn's ideal
    latch, a 32 s run, finds the same crossing: 0.4039441 s both, measured)."""
    exudyn, native = runs
    assert engagement(exudyn) == pytest.approx(engagement(native), abs=1e-4)
    assert not any("impulse" in ev for ev in exudyn.events)


def test_moment_is_the_springs_until_engagement(runs):
    """Before engagement hinge 1's moment is its spring's alone (kappa D, nu = 0): the latch's
    law is zero there."""
    exudyn, _ = runs
    D, M = exudyn["hinge_angle"][:, 1], exudyn["hinge_moment"][:, 1]
    before = np.asarray(exudyn.scene.times)[: D.size] <= engagement(exudyn)
    assert before.sum() > 1000
    np.testing.assert_allclose(M[before], 50.0 * D[before], rtol=1e-12, atol=1e-9)


def test_peak_moment_and_energy_lost_against_the_native_model(runs):
    """The peak hinge moment after engagement (exudyn's recorded steps) within 2 % of the
    native full model's, the energy the latch's damper dissipated by t_end within 1 %, and
    the audit balanced (the latch's work internal, as a stop's)."""
    exudyn, native = runs
    peak, t_peak = hinge_peak(exudyn)
    assert exudyn.stats.peaks["read_on"] == "every recorded step"
    assert t_peak > engagement(exudyn)
    assert peak == pytest.approx(hinge_peak(native)[0], rel=0.02)
    lost = float(exudyn["dissipated"][-1, 0])
    assert lost > 0
    assert lost == pytest.approx(float(native["dissipated"][-1, 0]), rel=0.01)
    assert exudyn.stats.energy_residual < 1e-3
