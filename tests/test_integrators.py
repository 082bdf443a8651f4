"""The compiled DOP853 loop against scipy's DOP853, Table 1 with the default kernels, and the
method's input checks."""

import math

import numpy as np
import pandas as pd
import pytest

from rodval import paper_scene, simulate
from rodval.core.loads import NodalForce
from rodval.core.scene import TABLE1_TIMES, Chain, Scene
from rodval.core.settings import METHODS, IntegratorSettings

TABLE1 = pd.read_csv(__import__("rodval").__path__[0] + "/data/table1.csv")


@pytest.mark.parametrize("model", ["reduced", "full"])
@pytest.mark.parametrize("rtol", [1e-5, 1e-9])
def test_compiled_dop853_reproduces_scipy_dop853(model, rtol):
    """Same method, same step control, across the load breakpoints: the same evaluations and
    states, except where the step size is limited by stability (the full model's 2700 rad/s
    bending mode at loose tolerance): there accept/reject decisions follow round-off, so the
    step sequences may part and both runs only agree to within the tolerance."""
    sc = paper_scene(4, times=np.linspace(0, 2, 21))
    ours = simulate(sc, model, method="DOP853-numba", rtol=rtol, atol=rtol * 1e-2)
    ref = simulate(sc, model, method="DOP853", rtol=rtol, atol=rtol * 1e-2)
    assert ours.success and ref.success
    stability_limited = model == "full" and rtol > 1e-7
    if stability_limited:
        assert abs(ours.stats.nfev - ref.stats.nfev) <= 0.02 * ref.stats.nfev
    else:
        assert ours.stats.nfev == ref.stats.nfev
        assert ours.stats.nsteps == ref.stats.nsteps
    agree = 10 * rtol if stability_limited else 1e-7
    for q in ("phi", "dphi"):
        scale = np.max(np.abs(ref[q]))
        np.testing.assert_allclose(ours[q], ref[q], rtol=0, atol=agree * scale)


def test_compiled_dop853_dense_output_matches_restart():
    """Values at output times between steps (dense output) equal a run that ends there."""
    base = paper_scene(3, t_end=1.3, times=[0.37, 0.81, 1.3])
    dense = simulate(base, "reduced", method="DOP853-numba", rtol=1e-11, atol=1e-13)
    for i, t in enumerate(base.times):
        end = simulate(
            base.with_(t_end=float(t), times=[float(t)]),
            "reduced",
            method="DOP853-numba",
            rtol=1e-11,
            atol=1e-13,
        )
        np.testing.assert_allclose(dense["phi"][i], end["phi"][0], rtol=0, atol=1e-8)


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_table1_phi_dphi_with_default_kernels(model):
    """Correctness did not move: the published Table 1 phi within 2e-3, dphi within 2e-2."""
    tr = simulate(paper_scene(times=TABLE1_TIMES), model, rtol=1e-10, atol=1e-12)
    form = "P" if model == "full" else "R"
    for q, tol in (("phi", 2e-3), ("dphi", 2e-2)):
        pub = TABLE1[(TABLE1.quantity == q) & (TABLE1.formulation == form)]
        for t, rows in pub.groupby("t"):
            ours = np.array([tr.at(q, t, int(k)) for k in rows.k])
            err = np.max(np.abs(ours - rows.value.to_numpy())) / np.max(np.abs(rows.value))
            assert err < tol, (q, t, err)


def test_compiled_method_is_listed_and_validated():
    assert "DOP853-numba" in METHODS
    assert IntegratorSettings(method="DOP853-numba").compiled
    with pytest.raises(ValueError, match="method must be one of"):
        IntegratorSettings(method="DOP854")
    sc = paper_scene(2, times=[1.0])
    with pytest.raises(ValueError, match="kernel='numba'"):
        simulate(sc, "full", method="DOP853-numba", kernel="numpy")
    callable_load = Scene(chain=Chain.uniform(2), loads=(NodalForce(2, fy=math.cos),), t_end=1.0)
    with pytest.raises(ValueError, match="pulse/constant"):
        simulate(callable_load, "reduced", method="DOP853-numba")


def test_compiled_failure_is_data():
    """A step-size collapse is reported with status, message and the time reached."""
    chain = Chain.uniform(2, kappa=0.0, nu=0.0)
    sc = Scene(chain=chain, t_end=1.0, times=[0.5, 1.0]).with_(
        initial=__import__("rodval").InitialState(dphi=[1e150, -1e150])
    )
    tr = simulate(sc, "reduced", method="DOP853-numba", rtol=1e-6, atol=1e-8)
    assert not tr.success
    assert tr.stats.t_reached < 1.0 and tr.stats.message
    assert len(tr.times) < 2
