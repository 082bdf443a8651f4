"""The exudyn reference model's reliability: bent initial states start unstretched, energy is
conserved without numerical damping, blow-ups and under-resolved runs are not reported as
success, native integrator settings and unknown options are refused, and the run records what
it used."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodval import Chain, InitialState, Scene, simulate
from rodval.core.settings import IntegratorSettings
from rodval.core.status import STATUS_BLOWUP, STATUS_FAILED

exu = pytest.importorskip("exudyn")
from reference_models.exudyn_beam import _bent_rod  # noqa: E402
from reference_models.exudyn_chain import DEFAULTS, ExudynModel  # noqa: E402

pytestmark = pytest.mark.exudyn

L, M, EI, KAPPA = 2.0, 3.0, 1e5, 100.0


def one_rod(a: float, *, t_end: float, times, outputs=("energy",)) -> Scene:
    """One rod, pinned root with a hinge-0 spring kappa = 100 N m/rad, no tip mass, no damper,
    bent at alpha = -beta = a, at rest, no load."""
    chain = Chain.uniform(1, l=L, m=M, EI=EI, mu=0.0, kappa=KAPPA, nu=0.0)
    return Scene(
        chain=chain,
        t_end=t_end,
        times=times,
        outputs=outputs,
        initial=InitialState(alpha=[a], beta=[-a]),
    )


@pytest.mark.parametrize("alpha, beta, elements", [(0.1, -0.1, 2), (0.05, 0.03, 3), (0.3, -0.2, 4)])
def test_bent_rod_shape_has_arc_length_l_and_unit_tangents(alpha, beta, elements):
    """The initial curve: end tangent angles alpha, beta to the chord (which lies on the x axis
    and is shorter than l), unit slopes, beam nodes at equal arc length l / elements along the
    curve y = eta(x); the alpha/beta derivatives agree with central differences."""
    p, t, dp, dt = _bent_rod(alpha, beta, L, elements)
    assert np.allclose(np.linalg.norm(t, axis=1), 1.0, rtol=0, atol=1e-14)
    assert math.atan2(t[0, 1], t[0, 0]) == pytest.approx(alpha, abs=1e-14)
    assert math.atan2(t[-1, 1], t[-1, 0]) == pytest.approx(beta, abs=1e-14)
    assert p[0] == pytest.approx([0.0, 0.0]) and p[-1, 1] == pytest.approx(0.0, abs=1e-15)
    assert p[-1, 0] < L
    # arc length between consecutive nodes on the curve (slope of y(x) = t_y / t_x)
    X, ta, tb = p[-1, 0], math.tan(alpha), math.tan(beta)
    for j in range(elements):
        x = np.linspace(p[j, 0], p[j + 1, 0], 20001)
        xi = x / X
        g = ta * (1 - xi) * (1 - 3 * xi) - tb * xi * (2 - 3 * xi)
        f = np.sqrt(1 + g**2)
        arc = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x))
        assert arc == pytest.approx(L / elements, rel=1e-9)
    h = 1e-6
    for i, (da, db) in enumerate(((h, 0.0), (0.0, h))):
        pp, tp, _, _ = _bent_rod(alpha + da, beta + db, L, elements)
        pm, tm, _, _ = _bent_rod(alpha - da, beta - db, L, elements)
        np.testing.assert_allclose((pp - pm) / (2 * h), dp[i], atol=1e-8)
        np.testing.assert_allclose((tp - tm) / (2 * h), dt[i], atol=1e-8)


@pytest.mark.parametrize("a", [0.01, 0.05, 0.1])
def test_bent_start_is_unstretched(a):
    """Potential energy at t = 0 of the bent rod: exudyn (bending + axial + hinge, measured on
    its elements) within 1 % of the native full model's Pi = 1/2 (4 EI / l)(a^2 + ab + b^2) +
    1/2 kappa a^2 (measured: relative gaps 2e-9, 2.3e-6, 8.9e-5; the old stretched start gave
    1439 J instead of 160 J at a = 0.04). The measured alpha, beta at t = 0 are the scene's."""
    scene = one_rod(a, t_end=1e-3, times=[0.0], outputs=("alpha", "beta", "energy"))
    ex = simulate(scene, "exudyn", step=1e-4)
    assert ex.success, ex.stats.message
    native = simulate(scene, "full")
    closed = 0.5 * (4 * EI / L) * (a * a - a * a + a * a) + 0.5 * KAPPA * a * a
    pot_ex, pot_nat = ex["potential"][0, 0], native["potential"][0, 0]
    print(
        f"a = {a}: potential at t = 0: exudyn {pot_ex:.6g} J, native {pot_nat:.6g} J, "
        f"closed form {closed:.6g} J, relative gap {pot_ex / pot_nat - 1:.3g}"
    )
    assert pot_nat == pytest.approx(closed, rel=1e-12)
    assert pot_ex == pytest.approx(pot_nat, rel=1e-2)
    assert ex["kinetic"][0, 0] == pytest.approx(0.0, abs=1e-12)
    assert ex["alpha"][0, 0] == pytest.approx(a, abs=1e-12)
    assert ex["beta"][0, 0] == pytest.approx(-a, abs=1e-12)


@pytest.mark.parametrize("a", [0.01, 0.05, 0.1])
def test_bent_release_conserves_energy_without_numerical_damping(a):
    """Released at rest, nu = 0, no load, trapezoidal rule (no numerical damping), step 5e-5 s:
    the total energy stays within 1 % of its initial value over 0.5 s (measured max drift
    6.9e-5, 1.6e-3, 2.6e-3). At the default step 2e-4 s the trapezoidal rule is not
    energy-stable on this stiff geometrically nonlinear beam (a = 0.05: 1.4 % drift; a = 0.1:
    blow-up, see test_energy_blowup_is_detected_during_the_run)."""
    scene = one_rod(a, t_end=0.5, times=np.linspace(0.0, 0.5, 101))
    tr = simulate(scene, "exudyn", solver="trapezoidal", step=5e-5)
    assert tr.success, tr.stats.message
    E = tr["energy"][:, 0]
    drift = np.abs(E / E[0] - 1).max()
    print(f"a = {a}: E(0) = {E[0]:.6g} J, max |E/E(0) - 1| over 0.5 s = {drift:.3g}")
    assert drift < 1e-2


def test_initial_rates_follow_the_curve():
    """Straight chain of two rods with dphi, dalpha, dbeta: the velocities are the assumed-mode
    field, so exudyn's kinetic energy at t = 0 equals the native full model's (exact at
    alpha = beta = 0) and the measured chord rates are the scene's dphi."""
    chain = Chain.uniform(2, mu=3.0, kappa=100.0, nu=0.0)
    initial = InitialState(phi=[0.3, -0.2], dphi=[1.5, -2.0], dalpha=[3.0, -1.0], dbeta=[-2.0, 4.0])
    scene = Scene(chain=chain, t_end=1e-3, times=[0.0], outputs=("dphi", "energy"), initial=initial)
    ex = simulate(scene, "exudyn", step=1e-4)
    assert ex.success, ex.stats.message
    native = simulate(scene, "full")
    assert ex["kinetic"][0, 0] == pytest.approx(native["kinetic"][0, 0], rel=1e-9)
    np.testing.assert_allclose(ex["dphi"][0], [1.5, -2.0], rtol=1e-12)


def test_energy_blowup_is_detected_during_the_run():
    """A real blow-up: the bent rod (a = 0.1) under the trapezoidal rule at a fixed step of
    2e-4 s (the default "auto" would refine the looser run below until it is resolved) gains
    energy without bound (the old code reported such runs as success). The per-step check
    stops it as STATUS_BLOWUP at the detection time (measured t = 0.4635 s, T = 1.3e5 J >
    100 x 1001 J), well before t_end, keeping the output times before it."""
    scene = one_rod(0.1, t_end=1.0, times=np.linspace(0.0, 1.0, 201))
    tr = simulate(scene, "exudyn", solver="trapezoidal", step=2e-4)
    print(tr.stats.status, tr.stats.message, tr.stats.t_reached, tr.settings["steps"])
    assert tr.stats.status == STATUS_BLOWUP
    assert "energy blow-up" in tr.stats.message and "blowup_factor 100" in tr.stats.message
    assert 0 < tr.stats.t_reached < 0.9
    assert tr.times.size > 0 and np.all(tr.times < tr.stats.t_reached)
    assert tr.times[-1] > tr.stats.t_reached - 0.01  # the output times before it are kept
    assert tr.settings["steps"] < 0.95 * tr.settings["steps_planned"]  # stopped early
    # the budget follows the settings: a looser factor lets the run go on further
    looser = simulate(
        scene,
        "exudyn",
        solver="trapezoidal",
        step=2e-4,
        settings=IntegratorSettings(blowup_factor=1e12),
    )
    assert looser.stats.t_reached > tr.stats.t_reached


def test_under_resolved_rotation_is_a_failure():
    """n = 2 with initial dphi = 1e6 rad/s turns by 200 rad per step of 2e-4 s: STATUS_FAILED
    at t = 0 (only the exact initial output kept), with the rotation in the message. A
    resolved run records its largest rotation per step."""
    chain = Chain.uniform(2)
    times = np.linspace(0.0, 0.1, 11)
    scene = Scene(
        chain=chain,
        t_end=0.1,
        times=times,
        outputs=("phi", "dphi"),
        initial=InitialState(dphi=[1e6, 0.0]),
    )
    tr = simulate(scene, "exudyn")
    print(tr.stats.message)
    assert tr.stats.status == STATUS_FAILED
    assert "under-resolved" in tr.stats.message and "max_rotation_per_step" in tr.stats.message
    assert tr.stats.t_reached == 0.0 and tr.times.tolist() == [0.0]
    assert tr.settings["max_rotation_per_step_seen"] == pytest.approx(200.0)
    ok = simulate(scene.with_(initial=InitialState(dphi=[50.0, 0.0])), "exudyn")
    assert ok.success, ok.stats.message
    assert 0.005 < ok.settings["max_rotation_per_step_seen"] < DEFAULTS["max_rotation_per_step"]


@pytest.mark.parametrize(
    "field, value",
    [
        ("method", "RK45"),
        ("rtol", 1e-10),
        ("atol", 1e-12),
        ("max_step", 1e-3),
        ("first_step", 1e-4),
    ],
)
def test_native_integrator_settings_are_refused(monkeypatch, field, value):
    """Any native integrator field exudyn cannot honour raises before any work."""

    def no_build(*args, **kwargs):
        raise AssertionError("the model was built")

    monkeypatch.setattr(ExudynModel, "_build", no_build)
    scene = Scene(chain=Chain.uniform(1), t_end=0.01)
    with pytest.raises(
        ValueError,
        match=f"{field}=.*exudyn's integrator is set by its own options "
        r"\(elements, step, .*solver",
    ):
        ExudynModel().simulate(scene, IntegratorSettings(**{field: value}))
    with pytest.raises(ValueError, match=field):
        simulate(scene, "exudyn", **{field: value})


def test_default_settings_and_blowup_factor_are_accepted():
    scene = Scene(chain=Chain.uniform(1), t_end=0.01, times=[0.0, 0.01])
    tr = ExudynModel(step=1e-3).simulate(scene, IntegratorSettings(blowup_factor=50.0))
    assert tr.success, tr.stats.message
    assert tr.settings["blowup_factor"] == 50.0


def test_unknown_options_list_the_allowed_ones():
    allowed = "elements, step, EA, element, solver, spectral_radius, newton_rtol"
    for call in (
        lambda: ExudynModel(stepsize=1e-3),
        lambda: ExudynModel.check_options({"stepsize": 1e-3, "step": 1e-3}),
        lambda: simulate(Scene(chain=Chain.uniform(1), t_end=0.01), "exudyn", stepsize=1e-3),
    ):
        with pytest.raises(ValueError, match="unknown exudyn model option.*'stepsize'") as info:
            call()
        assert allowed in str(info.value) and "unexpected keyword" not in str(info.value)
    with pytest.raises(ValueError, match="step"):
        ExudynModel.check_options({"step": -1.0})
    assert ExudynModel.check_options({"step": 1e-3}) == {**DEFAULTS, "step": 1e-3}


def test_settings_record_what_was_used():
    """trajectory.options: every option; trajectory.settings: the integrator, the planned and
    taken steps, the fixed step used."""
    scene = Scene(chain=Chain.uniform(1), t_end=0.01, times=[0.0, 0.01])
    tr = simulate(scene, "exudyn", step=3e-4, elements=3)
    assert tr.success, tr.stats.message
    s = tr.settings
    assert tr.options == {**DEFAULTS, "step": 3e-4, "elements": 3}
    assert s["method"] == "exudyn generalized-alpha"
    assert s["steps_planned"] == 34 and s["step_used"] == pytest.approx(0.01 / 34)
    assert s["steps"] == tr.stats.nsteps == 34
    assert s["min_step_used"] == pytest.approx(0.01 / 34)
    assert s["blowup_factor"] == IntegratorSettings().blowup_factor


def test_guard_verdicts_on_a_set_state():
    """The per-step check on states set by hand: a NaN velocity is STATUS_DIVERGED (exudyn's
    Newton usually gives up before a state turns non-finite, so no run reaches this), a huge
    one STATUS_BLOWUP, and its kinetic energy agrees with the measured one."""
    from reference_models.exudyn_guard import Guard
    from rodval.core.status import STATUS_DIVERGED

    scene = Scene(
        chain=Chain.uniform(2),
        t_end=1.0,
        outputs=("energy",),
        initial=InitialState(dphi=[0.5, -0.3], dalpha=[2.0, 1.0]),
    )
    built = ExudynModel()._build(scene)
    guard = Guard(built, scene, 2, 1e10, 100.0, 0.1)
    sd = built.mbs.systemData
    v0 = sd.GetODE2Coordinates_t()
    assert 0.5 * v0 @ guard.M @ v0 == pytest.approx(
        simulate(scene.with_(t_end=1e-3, times=[0.0]), "exudyn", step=1e-4)["kinetic"][0, 0],
        rel=1e-12,
    )
    assert guard.check(0.0, 1e-4) and guard.verdict is None
    sd.SetODE2Coordinates_t(1e4 * v0)
    assert not guard.check(0.1, 1e-6) and guard.verdict[0] == STATUS_BLOWUP
    guard.verdict = None
    bad = v0.copy()
    bad[3] = np.nan
    sd.SetODE2Coordinates_t(bad)
    assert not guard.check(0.2, 1e-6) and guard.verdict[0] == STATUS_DIVERGED
