"""Latches held from t = 0 (``Latch.held``): a clamp or a joint locked before the run."""

from __future__ import annotations

import numpy as np
import pytest

from rodval import simulate
from rodval.core.hinges import Latch
from rodval.core.scene import Chain, InitialState, Scene
from rodval.core.scene_file import scene_from_dict, scene_to_dict


def cantilever(n: int, held: bool = True, phi0: float = 0.0) -> Scene:
    """A straight chain of n rods (l = 1 m, m = 1 kg/m, EI = 1e3 N m^2) at rest, every hinge
    held at 0; hinge springs absent, so without the latches the chain would fall."""
    chain = Chain.uniform(n, l=1.0, m=1.0, EI=1e3, mu=0.0, kappa=0.0, nu=0.0)
    return Scene(
        chain=chain,
        t_end=0.5,
        times=np.linspace(0.0, 0.5, 11),
        outputs=("phi", "hinge_angle"),
        initial=InitialState(phi=[phi0] * n),
        latches=tuple(Latch(k, 0.0, held=held) for k in range(n)),
    )


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_a_held_chain_stays_held_and_fires_no_event(model):
    tr = simulate(cantilever(3), model)
    assert tr.success and tr.events == []
    assert np.abs(tr["hinge_angle"]).max() < 1e-12  # held exactly (a linear invariant)


def test_a_held_latch_must_start_at_its_angle_and_at_rest():
    with pytest.raises(
        ValueError, match="held latch on hinge 0: the hinge must start at its angle"
    ):
        cantilever(2, phi0=0.1)
    with pytest.raises(ValueError, match=r"dD/dt = 0.5 rad/s"):
        cantilever(2).with_(initial=InitialState(phi=[0.0, 0.0], dphi=[0.5, 0.5]))


def test_held_is_recorded_only_when_true():
    d = scene_to_dict(cantilever(2))
    assert all(la["held"] is True for la in d["latches"])
    assert scene_from_dict(d).latches == cantilever(2).latches
    armed = cantilever(2).with_(initial=InitialState(phi=[0.0, 0.5]), latches=(Latch(1, 0.0),))
    assert "held" not in scene_to_dict(armed)["latches"][0]  # other scenes' records unchanged
