"""One guard: the scipy loop, the compiled loop and the exudyn model give the same verdict and
the same message on the same blow-up.

The state: a two-rod chain at rest in its straight initial configuration, its initial rates
(rigid rod rotations, dphi) scaled by 1e4. The kinetic energy of a rigid rotation is exact in
every model (linear velocity field along each rod: the native rigid-rod terms, and exudyn's
cubic elements represent it exactly), so T and the budget E(0) + W+ + floor agree to round-off
(~1e-15 relative) and their 4-digit figures in the message are identical.
"""

import numpy as np
import pytest

from rodval import Chain, InitialState, IntegratorSettings, Scene
from rodval.core.status import STATUS_BLOWUP
from rodval.models import get_model
from rodval.solvers.compiled import verdict_message
from rodval.solvers.guard import DivergenceGuard, blowup_message, guard_step

SCENE = Scene(
    chain=Chain.uniform(2),
    t_end=1.0,
    initial=InitialState(dphi=[0.5, -0.3]),
)
SCALE = 1e4
T_CHECK, H = 0.1, 1e-3


def _scaled(system) -> np.ndarray:
    """y0 with its rates (the second half of the native state) scaled by SCALE."""
    y = system.y0.astype(float).copy()
    y[y.size // 2 :] *= SCALE
    return y


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_scipy_and_compiled_guards_give_one_verdict(model):
    system = get_model(model).system(SCENE)
    guard = DivergenceGuard(system, IntegratorSettings(), SCENE.t_end, system.y0)
    y = _scaled(system)
    scipy_verdict = guard.check(T_CHECK - H, T_CHECK, y)
    form = system.compiled()
    mech = np.zeros(3)
    form.mechanics(T_CHECK, y, form.P, form.S, form.M, form.L, mech)
    mon = np.zeros(6)
    mon[3] = 0.0  # no loads: the positive power at the start is 0
    code = guard_step(guard.spec.as_array(), mon, H, mech, True)
    compiled_verdict = verdict_message(code, mon, T_CHECK - H, guard.spec)
    assert scipy_verdict[0] == compiled_verdict[0] == STATUS_BLOWUP
    assert scipy_verdict[1] == compiled_verdict[1]
    # the message is the shared one, with this state's figures: T = SCALE^2 T(0)
    T0 = system.kinetic_energy(0.0, system.y0)
    assert scipy_verdict[1] == blowup_message(SCALE**2 * T0, 100.0, guard.spec.budget(0.0), T_CHECK)


def test_exudyn_guard_gives_the_native_verdict():
    pytest.importorskip("exudyn")
    from reference_models.exudyn_chain import ExudynModel
    from reference_models.exudyn_guard import Guard

    built = ExudynModel()._build(SCENE)
    guard = Guard(built, SCENE, 2, 1e10, IntegratorSettings().blowup_factor, 0.1)
    sd = built.mbs.systemData
    sd.SetODE2Coordinates_t(SCALE * sd.GetODE2Coordinates_t())
    assert not guard.check(T_CHECK, H)
    status, message = guard.verdict[:2]
    system = get_model("full").system(SCENE)
    native = DivergenceGuard(system, IntegratorSettings(), SCENE.t_end, system.y0)
    assert (status, message) == native.check(T_CHECK - H, T_CHECK, _scaled(system))
