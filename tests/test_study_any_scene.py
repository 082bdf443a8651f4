"""Any valid rodval.Scene is a study's [scene] (issue 37): latches and stops (their None fields
mean the default and are left out of the study file), a free base, loads of every law,
non-uniform chains, output times. The study's case runs exactly the given scene, also when
read back from the study.toml written beside the results; what a study file cannot hold (a
plain Python callable load) is refused in one line naming the field."""

from __future__ import annotations

import math
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rodval
from rodval.core.base import PINNED, Base
from rodval.core.hinges import Latch, Stop
from rodval.core.loads import NodalForce, constant, harmonic, pulse, ramp, tabulated
from rodval.core.scene import QUANTITIES, Chain, InitialState, Scene
from rodval.core.scene_file import scene_to_dict
from rodval.study.spec import study_from_dict

MODELS = {"full": {}, "reduced": {}}


def latched_scene(t_end: float = 0.8) -> Scene:
    """The issue's example: 3 rods, hinges 1 and 2 latch at 0 rad (direction and window None)."""
    chain = Chain.uniform(3, l=1.5, m=3.0, EI=1e5, mu=0.5, kappa=[0.0, 50.0, 50.0], nu=0.0)
    return Scene(
        chain=chain,
        initial=InitialState(phi=[0.0, math.pi - 0.05, 0.0]),
        latches=(Latch(1, 0.0), Latch(2, 0.0)),
        t_end=t_end,
        outputs=("phi",),
    )


def case_scene_round_trips(scene: Scene) -> None:
    """The study's only case runs ``scene``, from the dict and from its study.toml text (the
    reduced model, which refuses a moving base when the study is read, left out there)."""
    models = {"full": {}} if scene.base.moving else MODELS
    spec = rodval.Study.from_dict({"scene": scene, "models": models})
    (case,) = spec.cases
    assert scene_to_dict(case.scene) == scene_to_dict(scene)
    again = study_from_dict(tomllib.loads(spec.text), where="study.toml")
    assert scene_to_dict(again.cases[0].scene) == scene_to_dict(scene)
    assert again.cases[0].fingerprint == case.fingerprint


def test_a_latched_scene_object_runs_as_a_study(tmp_path):
    scene = latched_scene(t_end=0.05)
    case_scene_round_trips(scene)
    res = rodval.run_study(
        {"scene": scene, "models": MODELS},
        tmp_path / "out",
        workers=1,
        progress=False,
        report=False,
    )
    assert res.ran == ["base"] and res.failed_runs == 0
    again = rodval.load_study(tmp_path / "out" / "study.toml")
    assert scene_to_dict(again.cases[0].scene) == scene_to_dict(scene)


def test_a_callable_load_is_refused_naming_the_field():
    scene = latched_scene().with_(loads=(pulse(3), NodalForce(2, fx=lambda t: 1.0)))
    with pytest.raises(ValueError, match=r"^scene\.loads\[1\]: the load on node 2 is a plain") as e:
        rodval.Study.from_dict({"scene": scene, "models": MODELS})
    assert "\n" not in str(e.value)


@st.composite
def per_rod(draw, n: int, lo: float, hi: float):
    """A scalar or a list of n values in [lo, hi] (non-uniform chains)."""
    values = st.floats(lo, hi, allow_nan=False)
    return draw(st.one_of(values, st.lists(values, min_size=n, max_size=n)))


@st.composite
def loads(draw, n: int) -> tuple:
    """Loads of every law of rodval.core.loads on nodes 1..n."""
    node = st.integers(1, n)
    force = st.floats(-100.0, 100.0)
    laws = [
        st.builds(pulse, node, force, force, st.floats(0.1, 2.0)),
        st.builds(constant, node, force, force, st.floats(0.0, 0.1), st.just(math.inf)),
        st.builds(ramp, node, force, force, st.just(0.0), st.floats(0.1, 1.0)),
        st.builds(harmonic, node, force, force, st.floats(0.5, 20.0), st.floats(-3.0, 3.0)),
        st.builds(
            lambda k, f: tabulated(k, t=[0.0, 0.1, 0.3], X=[0.0, f, 0.0]),
            node,
            force,
        ),
    ]
    return tuple(draw(st.lists(st.one_of(laws), max_size=3)))


@st.composite
def scenes(draw) -> Scene:
    """Valid scenes (starting straight, so that a latch at a non-zero angle lies ahead)."""
    n = draw(st.integers(1, 4))
    chain = Chain(
        l=draw(per_rod(n, 0.5, 2.0)),
        m=draw(per_rod(n, 1.0, 5.0)),
        EI=draw(per_rod(n, 1e3, 1e5)),
        mu=draw(per_rod(n, 0.0, 2.0)),
        kappa=draw(per_rod(n, 0.0, 100.0)),
        nu=draw(per_rod(n, 0.0, 0.1)),
        rest_angle=draw(per_rod(n, -0.5, 0.5)),
        bending_damping=draw(per_rod(n, 0.0, 1.0)),
        _n=n,
    )
    hinges = draw(st.lists(st.integers(0, n - 1), unique=True, max_size=n))
    latches = []
    for h in hinges:
        angle = draw(st.sampled_from([-1.0, 1.0])) * draw(st.floats(0.1, 2.0))
        direction = draw(st.sampled_from([None, 1 if angle > 0 else -1]))
        window = draw(st.one_of(st.none(), st.floats(1e-3, 0.1)))
        latches.append(Latch(h, angle, direction, window))
    stops = draw(
        st.lists(
            st.builds(
                Stop,
                st.integers(0, n - 1),
                st.floats(-1.0, 1.0),
                st.sampled_from(["upper", "lower"]),
                st.floats(1.0, 1e3),
                st.floats(0.0, 1.0),
            ),
            max_size=2,
        )
    )
    free = Base(
        "free",
        mass=draw(st.floats(1.0, 100.0)),
        inertia=draw(st.floats(0.1, 10.0)),
        hinge_offset=(draw(st.floats(-1.0, 1.0)), 0.0),
        velocity=(0.0, draw(st.floats(-1.0, 1.0))),
        rate=draw(st.floats(-1.0, 1.0)),
    )
    base = draw(st.sampled_from([PINNED, free]))
    # "base" needs a moving base, "drive" a prescribed one (none is drawn here)
    quantities = [q for q in QUANTITIES if (base.free or q != "base") and q != "drive"]
    t_end = draw(st.floats(0.05, 1.0))
    times = draw(
        st.one_of(
            st.none(),
            st.lists(st.floats(0.0, t_end), min_size=1, max_size=4, unique=True).map(sorted),
        )
    )
    return Scene(
        chain=chain,
        loads=draw(loads(n)),
        t_end=t_end,
        times=times,
        outputs=tuple(draw(st.lists(st.sampled_from(quantities), min_size=1, unique=True))),
        initial=InitialState(dphi=draw(per_rod(n, -1.0, 1.0))),
        name=draw(st.sampled_from(["scene", "wing 2", 'a"b'])),
        latches=tuple(latches),
        stops=tuple(stops),
        base=base,
    )


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenes())
def test_every_valid_scene_is_the_scene_its_study_runs(scene):
    case_scene_round_trips(scene)
