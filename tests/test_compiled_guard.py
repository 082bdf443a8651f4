"""The divergence guard inside the compiled loop: its kinetic energy and load power equal the
Python-side ones, and its verdicts match the scipy path's."""

import numpy as np
import pytest

from rodval import Chain, InitialState, Scene, constant, paper_scene, pulse, simulate
from rodval.core.settings import IntegratorSettings
from rodval.core.status import STATUS_STALLED
from rodval.models import get_model
from rodval.solvers.guard import GuardSpec


@pytest.mark.parametrize("model", ["full", "reduced"])
@pytest.mark.parametrize("coefficients", ["printed", "published"])
def test_compiled_mechanics_equal_the_python_energy_and_power(model, coefficients):
    rng = np.random.default_rng(3)
    chain = Chain(
        l=rng.uniform(0.5, 2, 5),
        m=rng.uniform(1, 3, 5),
        EI=1e4,
        mu=[0, 1, 2, 0, 1],
        kappa=[0, 50, 0, 10, 20],
        nu=0.01,
    )
    scene = Scene(chain=chain, loads=(pulse(5, T=1.0), constant(2, X=3.0, Y=-4.0)), t_end=1.0)
    system = get_model(model, coefficients=coefficients).system(scene)
    form = system.compiled()
    out = np.zeros(3)
    for t in (0.2, 0.7):
        y = rng.normal(size=system.y0.size)
        form.mechanics(t, y, form.P, form.S, form.M, form.L, out)
        assert out[0] == pytest.approx(system.kinetic_energy(t, y), rel=1e-12)
        assert out[1] == pytest.approx(system.power(t, y)[0], rel=1e-12, abs=1e-12)


def test_compiled_loop_stops_when_kinetic_energy_exceeds_its_budget():
    # Physically T <= E(0) + W+; a budget of half the load work (factor 0.5, allowed only in
    # this direct call) is exceeded as soon as the pulse has set the chain moving.
    from rodval.solvers import budget, compiled

    scene = paper_scene(2, t_end=0.5)
    system = get_model("full").system(scene)
    form = system.compiled()
    Y = np.empty((scene.times.size, system.y0.size))
    edges = np.array([0.0, 0.5])
    controls = compiled.Controls(1e-8, 1e-10, np.inf, None, 10**7)
    args = (form, system.y0, edges, scene.times, Y, controls)
    n_out, _, _, code, t, *_ = compiled.integrate_compiled(
        *args, GuardSpec(stall_steps=1000, blowup_factor=0.5)
    )
    assert code == budget.BLOWUP and 0 < t < 0.5 and n_out < scene.times.size
    n_out, _, _, code, t, *_ = compiled.integrate_compiled(
        *args, GuardSpec(stall_steps=1000, blowup_factor=1.0001)
    )
    assert code == budget.OK and t == 0.5 and n_out == scene.times.size


def test_compiled_loop_reports_a_stall():
    scene = paper_scene(2)
    settings = IntegratorSettings(method="DOP853-numba", min_step_fraction=1e-3, stall_steps=50)
    tr = simulate(scene, "full", settings=settings)
    assert tr.stats.status == STATUS_STALLED, tr.stats.message


def test_initial_state_energy_budget_in_the_compiled_loop():
    # released from a deflected state at rest: no blow-up at the default factor
    scene = Scene(chain=Chain.uniform(3), t_end=0.5, initial=InitialState(phi=[0.3, -0.2, 0.1]))
    tr = simulate(scene, "full")
    assert tr.success and tr.settings["method"] == "DOP853-numba", tr.stats.message
