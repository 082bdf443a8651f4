"""The simulation entry point: outputs, loads across breakpoints, failures as data."""

import json
import math

import numpy as np
import pytest

from rodval import (
    Chain,
    InitialState,
    IntegratorSettings,
    NodalForce,
    Scene,
    constant,
    paper_scene,
    simulate,
)
from rodval.core.status import STATUS_ERROR
from rodval.models.presets.reduced import ReducedSystem


def small_scene(**kw):
    base = dict(
        chain=Chain.uniform(2),
        loads=(),
        t_end=0.2,
        times=np.linspace(0, 0.2, 5),
        outputs=("phi", "dphi"),
    )
    base.update(kw)
    return Scene(**base)


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_tidy_frame_has_exactly_the_requested_quantities(model):
    scene = paper_scene(t_end=0.5, times=[0.0, 0.25, 0.5], outputs=("phi", "x", "energy"))
    tr = simulate(scene, model)
    assert tr.success and tr.stats.nfev > 0 and tr.stats.wall_s > 0
    energy_terms = {"kinetic", "potential", "energy", "work", "dissipated", "energy_residual"}
    assert set(tr.quantities) == {"phi", "x"} | energy_terms
    df = tr.to_frame()
    assert list(df.columns) == ["t", "quantity", "k", "value"]
    assert len(df) == 3 * (8 + 9 + len(energy_terms))
    assert df.loc[df.quantity == "x", "k"].tolist()[:9] == list(range(9))
    assert np.all(np.isfinite(df["value"]))
    assert tr.at("phi", 0.0, 3) == 0.0 and tr["x"][0, -1] == pytest.approx(16.0)


def test_reduced_model_recovers_bending_only_when_asked(monkeypatch):
    calls = []
    original = ReducedSystem.recover_bending
    monkeypatch.setattr(
        ReducedSystem, "recover_bending", lambda self, t, y: calls.append(t) or original(self, t, y)
    )
    simulate(paper_scene(t_end=0.5, times=[0.5], outputs=("phi",)), "reduced")
    assert calls == []
    simulate(paper_scene(t_end=0.5, times=[0.25, 0.5], outputs=("alpha",)), "reduced")
    # asked: at the output times, then at the states alpha's peak is read on, between them
    # (the run's peaks, SolverStats.peaks: rodval.solvers.outputs.PeakGrid)
    assert calls[:2] == [0.25, 0.5] and len(calls) > 2


@pytest.mark.parametrize(
    "model,EI,method", [("reduced", 1e8, "DOP853"), ("full", 1e7, "DOP853-numba")]
)
def test_step_load_on_a_rigid_pendulum_has_the_closed_form_response(model, EI, method):
    """Tip force Y switched on at t_on (a breakpoint): for small angles
    phi(t) = Y l / kappa (1 - cos w (t - t_on)), w^2 = kappa / (m l^3/3 + mu l^2).
    EI is large enough that the rod's flexibility shifts w by < 3e-6 (linearized model)."""
    l, m, mu, kappa, Y, t_on = 2.0, 3.0, 3.0, 100.0, 1e-3, 0.3
    w = math.sqrt(kappa / (m * l**3 / 3 + mu * l**2))
    times = np.linspace(0, 2.0, 41)
    scene = Scene(
        chain=Chain.uniform(1, l=l, m=m, mu=mu, kappa=kappa, nu=0.0, EI=EI),
        loads=(constant(1, Y=Y, t_on=t_on),),
        t_end=2.0,
        times=times,
        outputs=("phi",),
    )
    tr = simulate(scene, model, method=method, rtol=1e-10, atol=1e-14)
    exact = np.where(times > t_on, Y * l / kappa * (1 - np.cos(w * (times - t_on))), 0.0)
    assert np.max(np.abs(tr["phi"][:, 0] - exact)) < 1e-4 * np.max(exact)


def test_a_model_error_is_reported_with_time_reached_and_partial_history():
    def fy(t):
        if t > 0.1:
            raise RuntimeError("sensor broke")
        return 1.0

    scene = small_scene(loads=(NodalForce(2, fy=fy),))
    tr = simulate(scene, "reduced")
    assert tr.stats.status == STATUS_ERROR and "sensor broke" in tr.stats.message
    assert 0.0 < tr.stats.t_reached <= 0.1 and tr.stats.nfev > 0
    assert np.all(tr.times <= tr.stats.t_reached) and tr.times[0] == 0.0
    assert np.all(np.isfinite(tr["phi"]))


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_a_nan_load_ends_the_run_with_a_named_error_not_a_nan_table(model):
    scene = small_scene(loads=(NodalForce(2, fy=lambda t: math.nan if t > 0.1 else 0.0),))
    tr = simulate(scene, model)
    assert tr.stats.status == STATUS_ERROR and "load at node 2 is not finite" in tr.stats.message
    assert tr.stats.t_reached <= 0.1 and np.all(np.isfinite(tr["phi"]))


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"method": "Euler"}, "method must be one of"),
        ({"rtol": 0.0}, "rtol must be"),
        ({"atol": -1.0}, "atol must be"),
        ({"max_step": 0.0}, "max_step must be"),
        ({"first_step": -1.0}, "first_step"),
    ],
)
def test_bad_integrator_settings(kw, match):
    with pytest.raises(ValueError, match=match):
        IntegratorSettings(**kw)


def test_bad_model_and_option():
    with pytest.raises(ValueError, match="model must be one of"):
        simulate(small_scene(), "fancy")
    with pytest.raises(ValueError, match="coefficients must be one of"):
        simulate(small_scene(), "full", coefficients="guessed")


def test_full_model_starts_from_the_given_bending_state():
    scene = small_scene(
        times=[0.0],
        t_end=0.1,
        outputs=("alpha", "beta"),
        initial=InitialState(alpha=[1e-3, 2e-3], beta=-1e-3),
    )
    tr = simulate(scene, "full")
    assert tr["alpha"][0].tolist() == [1e-3, 2e-3] and tr["beta"][0].tolist() == [-1e-3, -1e-3]


@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau", "BDF", "LSODA"])
def test_every_scipy_method_agrees_on_the_reduced_model(method):
    scene = paper_scene(t_end=1.0, times=[1.0], outputs=("phi",))
    ref = simulate(scene, "reduced", rtol=1e-11, atol=1e-13)
    tr = simulate(scene, "reduced", method=method, rtol=1e-8, atol=1e-10)
    assert tr.success and np.max(np.abs(tr["phi"] - ref["phi"])) < 1e-5
    json.dumps(tr.to_dict())  # counters are plain ints (LSODA's are numpy int32)
