"""Energy audit: the balance E - E(0) - W_ext + D closes where the physics says it must."""

import numpy as np
import pytest

from rodval import Chain, InitialState, Scene, constant, paper_scene, simulate
from rodval.solvers.audit import balance


def test_rigid_limit_closes_the_balance_with_load_and_damping():
    # EI -> inf: the reduced model becomes the rigid chain, a Lagrangian system, so
    # E(t) - E(0) = W_ext(t) - D(t) up to the integration error (which scales with rtol).
    scene = paper_scene(4, EI=1e12, nu=5.0, outputs=("energy",), times=np.linspace(0, 2, 21))
    loose, tight = (simulate(scene, "reduced", rtol=r, atol=r * 1e-2) for r in (1e-7, 1e-10))
    assert tight["work"][-1, 0] > 1000.0  # the pulse does real work (J)
    assert tight["dissipated"][-1, 0] > 0.1 * tight["work"][-1, 0]
    assert tight.stats.energy_residual < 1e-9
    assert tight.stats.energy_residual < 1e-2 * loose.stats.energy_residual


def test_work_of_a_constant_force_is_force_times_displacement():
    n, X, Y = 3, 40.0, -25.0
    scene = Scene(
        Chain.uniform(n),
        loads=(constant(n, X=X, Y=Y),),
        t_end=1.5,
        outputs=("energy", "x", "y"),
        times=np.linspace(0, 1.5, 16),
    )
    tr = simulate(scene, "reduced", rtol=1e-10, atol=1e-12)
    x, y = tr["x"][:, n], tr["y"][:, n]
    expected = X * (x - x[0]) + Y * (y - y[0])
    assert np.max(np.abs(expected)) > 10.0
    np.testing.assert_allclose(tr["work"][:, 0], expected, rtol=1e-7, atol=1e-7)


def test_dissipation_grows_and_vanishes_without_dampers():
    scene = paper_scene(outputs=("energy",), times=np.linspace(0, 2, 11))
    tr = simulate(scene, "reduced", rtol=1e-9, atol=1e-11)
    assert np.all(np.diff(tr["dissipated"][:, 0]) > 0)
    undamped = simulate(scene.with_(chain=scene.chain.with_(nu=0.0)), "reduced")
    assert np.all(undamped["dissipated"] == 0.0)


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_audit_does_not_change_the_trajectory(model):
    scene = paper_scene(2, t_end=0.3, times=[0.1, 0.2, 0.3], outputs=("phi", "alpha"))
    plain = simulate(scene, model, method="DOP853")
    audited = simulate(scene.with_(outputs=("phi", "alpha", "energy")), model, method="DOP853")
    np.testing.assert_array_equal(plain["phi"], audited["phi"])
    assert set(audited.quantities) >= {"work", "dissipated", "energy_residual"}
    assert plain.stats.energy_residual is None and audited.stats.energy_residual is not None


def test_free_vibration_residual_is_a_model_property_not_integration_error():
    # nu = 0, no load: W = D = 0. Both models leave a residual that does not shrink with
    # the tolerance (full: first-order truncation; reduced: non-Lagrangian, docs/stability.md).
    scene = Scene(
        Chain.uniform(3, nu=0.0),
        t_end=0.3,
        outputs=("energy",),
        initial=InitialState(dphi=[1.0, -0.5, 0.8]),
    )
    for model in ("full", "reduced"):
        r1, r2 = (
            simulate(scene, model, rtol=r, atol=r * 1e-2).stats.energy_residual
            for r in (1e-7, 1e-9)
        )
        assert r1 > 1e-8
        assert r2 == pytest.approx(r1, rel=0.05)


def test_balance_scalar():
    E = np.array([1.0, 2.0, 3.0])
    R, scalar = balance(E, 1.0, W=np.array([0.0, 1.0, 1.5]), D=np.array([0.0, 0.0, 0.1]))
    np.testing.assert_allclose(R, [0.0, 0.0, 0.6])
    assert scalar == pytest.approx(0.6 / 3.0)
