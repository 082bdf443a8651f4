"""Events inside the compiled DOP853 loop (issue "the fast path for every scene"): latches and
limit stops of both native models are detected and located in compiled code, the jump is the
system's own (``rodval.solvers.events.apply_hit``, as on the scipy path), and "auto" keeps the
compiled loop for deployment scenes.

Bounds: both loops run the same method with the same step-size control (the compiled loop is
scipy's DOP853 step for step), locate each crossing by Brent's method on the same interpolant to
the same tolerance (``time_tolerance``: 1e-13 s here), and apply the same jump, so they differ
only by the round-off of the evaluation order (numba vs numpy, ~1e-15 relative per
evaluation). Measured on the four-panel wing: lock times 1e-13 s apart, impulses 1e-10
relative, phi 1e-11 rad over the run. The bounds below (1e-10 s, 1e-8 relative, 1e-8 rad) are
the issue's impulse figure and a factor ~1000 above the measured round-off for the rest.
"""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from rodval import Chain, InitialState, Latch, Scene, Stop, simulate
from rodval.bench import four_panel_wing
from rodval.core.scene_file import scene_from_dict
from rodval.models.presets.full import FullSystem
from rodval.models.presets.reduced import ReducedSystem

#: The four-panel zig-zag wing of studies/deployment.toml (stowed, released by its
#: pre-stressed hinges, latching straight), over its first two locks.
WING = four_panel_wing(t_end=0.8, times=81).with_(outputs=("phi", "hinge_angle", "energy"))

#: A three-rod chain swinging into an upper stop on hinge 1 and a lower one on hinge 2, each
#: switching on and off twice (8 events), with a latch on hinge 2 that stays armed.
STOPS = Scene(
    chain=Chain.uniform(3, l=1.0, m=1.0, EI=2e4, mu=0.2, kappa=[0.0, 20.0, 20.0], nu=0.05),
    t_end=1.2,
    times=np.linspace(0.0, 1.2, 61),
    initial=InitialState(phi=[0.0, 0.3, -0.2], dphi=[2.0, 4.0, -3.0]),
    stops=(Stop(1, 0.32, "upper", 3e3, 1.0), Stop(2, -0.52, "lower", 2e3, 0.5)),
    latches=(Latch(2, 0.6),),
    outputs=("phi", "hinge_angle", "energy"),
)


def _pair(scene, model, method="auto"):
    fast = simulate(scene, model, method=method)
    ref = simulate(scene, model, method="DOP853")
    assert fast.success and ref.success, (fast.stats.message, ref.stats.message)
    return fast, ref


@pytest.mark.parametrize("model", ["full", "reduced"])
@pytest.mark.parametrize("scene", [WING, STOPS], ids=["latches", "stops"])
def test_compiled_events_find_the_scipy_path_events(model, scene):
    """The compiled DOP853 is scipy's DOP853 with the events inside the loop: the same
    events, impulses and energy audit to round-off."""
    fast, ref = _pair(scene, model, "DOP853-numba")
    assert ref.settings["method"] == "DOP853"
    assert [e["label"] for e in fast.events] == [e["label"] for e in ref.events]
    assert len(fast.events) >= 2
    for a, b in zip(fast.events, ref.events):
        assert abs(a["t"] - b["t"]) < 1e-10
        if "angular_impulses" in b:
            np.testing.assert_allclose(a["angular_impulses"], b["angular_impulses"], rtol=1e-8)
            np.testing.assert_allclose(a["kinetic_after"], b["kinetic_after"], rtol=1e-8)
    np.testing.assert_allclose(fast["phi"], ref["phi"], rtol=0, atol=1e-8)
    # the energy audit through the impacts: the same running work, dissipation and residual
    scale = float(np.max(np.abs(ref["energy"])))
    for q in ("work", "dissipated", "energy_residual"):
        np.testing.assert_allclose(fast[q], ref[q], rtol=0, atol=1e-10 * scale)


@pytest.mark.parametrize("model", ["full", "reduced"])
@pytest.mark.parametrize("scene", [WING, STOPS], ids=["latches", "stops"])
def test_auto_runs_events_compiled_and_agrees_with_scipy_to_the_tolerance(model, scene):
    """ "auto" is compiled; where it tries Radau IIA on a stretch (``stats.switch``) the
    results differ from scipy's DOP853 by that method's error, within the tolerance asked
    (rtol 1e-8): lock times within 1e-9 s (measured 4e-12), phi within 1e-8 rad (5e-10),
    impulses 1e-7 relative, the audit within 1e-8 of the energy scale (3.4e-10: Radau's
    cubic dense output under the quadrature)."""
    fast, ref = _pair(scene, model)
    assert fast.settings["method"] == "DOP853-numba"
    assert [e["label"] for e in fast.events] == [e["label"] for e in ref.events]
    for a, b in zip(fast.events, ref.events):
        assert abs(a["t"] - b["t"]) < 1e-9
        if "angular_impulses" in b:
            np.testing.assert_allclose(a["angular_impulses"], b["angular_impulses"], rtol=1e-7)
    np.testing.assert_allclose(fast["phi"], ref["phi"], rtol=0, atol=1e-8)
    scale = float(np.max(np.abs(ref["energy"])))
    for q in ("work", "dissipated", "energy_residual"):
        np.testing.assert_allclose(fast[q], ref[q], rtol=0, atol=1e-8 * scale)


def test_the_wing_locks_in_order_and_the_stops_switch_on_and_off():
    """What the scenes are for: the test above compares like with like only if events happen."""
    fast = simulate(WING, "full")
    assert [e["label"] for e in fast.events] == ["latch hinge 3", "latch hinge 2"]
    labels = [e["label"] for e in simulate(STOPS, "full").events]
    assert "stop hinge 1 on" in labels and "stop hinge 1 off" in labels


@pytest.mark.parametrize("cls", [FullSystem, ReducedSystem])
def test_compiled_form_of_a_locked_mode_is_the_python_right_hand_side(cls):
    """In every mode (stops acting, hinges held) the compiled form's rhs and event values are
    those of the system's Python methods, and its event rows are its event functions."""
    rng = np.random.default_rng(7)
    system = cls(STOPS)
    width = 6 if cls is FullSystem else 2
    for mode in [((True, False), (), ()), ((False, True), (0,), ())]:
        system._activate(mode)
        form = system.compiled()
        specs = system.event_functions()
        assert form.E.shape[0] == len(specs)
        assert [int(d) for d in form.directions] == [s.direction for s in specs]
        for _ in range(3):
            y = rng.normal(scale=0.5, size=width * 3)
            out = np.empty_like(y)
            form.rhs(0.3, y, form.P, form.S, form.M, form.L, out)
            ref = system.rhs(0.3, y)
            np.testing.assert_allclose(out, ref, rtol=0, atol=1e-10 * np.max(np.abs(ref)))
            g = np.empty(form.E.shape[0])
            form.events(0.3, y, form.P, form.S, form.M, form.L, form.E, g)
            np.testing.assert_allclose(g, [s.g(0.3, y) for s in specs], rtol=0, atol=1e-12)


def test_explicit_compiled_method_runs_events_and_numpy_kernel_goes_to_scipy():
    assert simulate(WING, "reduced", method="DOP853-numba").events
    slow = simulate(WING, "reduced", kernel="numpy")
    assert slow.settings["method"] == "DOP853"


def test_the_benchmark_wing_is_the_shipped_deployment_study_scene():
    """``rodval bench fast-path`` times the scene users run (studies/deployment.toml)."""
    path = Path(__file__).resolve().parents[1] / "studies" / "deployment.toml"
    shipped = scene_from_dict(tomllib.loads(path.read_text())["scene"], where=str(path))
    ours = four_panel_wing()
    for field in ("l", "m", "EI", "mu", "kappa", "nu", "rest_angle"):
        np.testing.assert_array_equal(getattr(shipped.chain, field), getattr(ours.chain, field))
    np.testing.assert_array_equal(shipped.initial.resolve(4)["phi"], ours.initial.resolve(4)["phi"])
    np.testing.assert_allclose(shipped.times, ours.times, rtol=0, atol=4 * np.spacing(2.5))
    assert shipped.latches == ours.latches and shipped.t_end == ours.t_end
    assert set(shipped.outputs) == set(ours.outputs)


def test_a_stiff_transient_after_a_lock_is_stepped_through_not_called_divergence():
    """Two near-rigid rods (EI = 1e9), root free, hinge 1 pre-stressed and latching at 0: once
    locked, the reduced model holds the hinge through its bending compliance (a constraint mode
    of ~1e4 rad/s). The first steps after the lock overflow; they are rejected and cut (as
    scipy's DOP853 does with an infinite error norm) instead of ending the run as diverged
    (issue: "non-finite derivative" at the lock). Angular momentum about the free root is then
    kept to the integration's accuracy: rtol 1e-8 per step over ~25,000 steps through the
    stiff mode, measured 2.3e-8 relative; bound 1e-6."""
    chain = Chain.uniform(2, l=1.0, m=1.0, EI=1e9, mu=0.5, kappa=[0.0, 5.0], nu=0.0)
    scene = Scene(
        chain=chain,
        t_end=1.5,
        times=np.linspace(0.0, 1.5, 31),
        initial=InitialState(phi=[0.0, -2.5], dphi=[1.0, 1.5]),
        latches=(Latch(1, 0.0),),
        outputs=("phi", "dphi", "hinge_angle", "angular_momentum"),
    )
    tr = simulate(scene, "reduced", method="DOP853-numba")  # "auto" leaves it: test_radau
    assert tr.success and tr.settings["method"] == "DOP853-numba", tr.stats.message
    assert [e["label"] for e in tr.events] == ["latch hinge 1"]
    H = tr["angular_momentum"][:, 0]
    assert np.max(np.abs(H - H[0])) < 1e-6 * abs(H[0])
    after = tr.times > tr.events[0]["t"]
    assert np.max(np.abs(tr["hinge_angle"][after, 1])) < 1e-12
