"""``tip_deflection`` (issue 48): the tip's transverse displacement in the base's frame,
(r_n - r_0) . e2, e2 the base's axis e1 = (cos theta, sin theta) rotated +90 deg
(docs/quantities.md). For straight chords at angles phi_k it is sum l_k sin(phi_k - theta):
checked on the function, on a chain whose hinges are all held (a rigid body, whatever its
base does: the closed form is constant in time) in every model on every base it has, and
across the models on a latched deployment."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import two_rod_latch

from rodval import Base, simulate
from rodval.core.base import Motion
from rodval.core.hinges import Latch
from rodval.core.quantities import tip_deflection
from rodval.core.scene import Chain, InitialState, Scene

#: the held hinge angles (rad) and the rods' lengths (m) of the held chain
HELD = np.array([0.3, -0.5, 0.4])
LENGTHS = np.array([1.0, 1.5, 0.8])
#: base kind -> (base, initial attitude (rad), initial rate (rad/s))
BASES = {
    "pinned": (Base(), 0.0, 0.0),
    "free": (
        Base(kind="free", mass=20.0, inertia=5.0, hinge_offset=(0.3, 0.1), attitude=0.4, rate=0.5),
        0.4,
        0.5,
    ),
    "prescribed": (
        Base(
            kind="prescribed",
            hinge_offset=(0.3, 0.1),
            motion={"attitude": Motion("spin_up", (2.0, 0.5))},
        ),
        0.0,
        0.0,
    ),
}
#: every model and the bases it has (the reduced model: pinned only, docs/base.md)
MODEL_BASES = [
    (model, base)
    for model in ("full", "reduced", "rigid", "exudyn")
    for base in BASES
    if model != "reduced" or base == "pinned"
]
#: round-off of the closed forms: a sum of n = 3 terms of size l <= 1.5 m, each carrying
#: ~1e-16 relative, after an integration whose state is O(1): 1e-12 m leaves 3 digits' room
ROUND_OFF = 1e-12


def _chain_nodes(l: np.ndarray, phi: np.ndarray, r0=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """Node positions (m, (..., n + 1)) of straight chords of lengths l at angles phi."""
    zeros = np.zeros(phi.shape[:-1] + (1,))
    x = r0[0] + np.concatenate([zeros, np.cumsum(l * np.cos(phi), -1)], -1)
    y = r0[1] + np.concatenate([zeros, np.cumsum(l * np.sin(phi), -1)], -1)
    return x, y


def test_pinned_closed_form():
    """Pinned base (theta = 0): tip_deflection = sum l_k sin phi_k, relative to the x axis."""
    rng = np.random.default_rng(1)
    l = rng.uniform(0.5, 2.0, 5)
    phi = rng.uniform(-np.pi, np.pi, (7, 5))
    x, y = _chain_nodes(l, phi)
    expected = (l * np.sin(phi)).sum(-1)
    assert np.abs(tip_deflection(x, y) - expected).max() <= 1e-13 * l.sum()


def test_rotated_base_closed_form():
    """A base at attitude theta, node 0 anywhere: (r_n - r_0) . (-sin theta, cos theta) =
    sum l_k (sin phi_k cos theta - cos phi_k sin theta) = sum l_k sin(phi_k - theta); the
    straight chain along e1 (every phi_k = theta) has 0, and a chain at right angles to it
    (phi_k = theta + pi/2) the whole length."""
    rng = np.random.default_rng(2)
    l = rng.uniform(0.5, 2.0, 4)
    theta = rng.uniform(-np.pi, np.pi, 6)
    phi = rng.uniform(-np.pi, np.pi, (6, 4))
    x, y = _chain_nodes(l, phi, r0=(3.0, -7.0))
    expected = (l * np.sin(phi - theta[:, None])).sum(-1)
    assert np.abs(tip_deflection(x, y, theta) - expected).max() <= 1e-13 * (l.sum() + 10)
    straight = np.repeat(theta[:, None], 4, 1)
    assert np.abs(tip_deflection(*_chain_nodes(l, straight, (3.0, -7.0)), theta)).max() <= (
        1e-13 * (l.sum() + 10)
    )
    up = tip_deflection(*_chain_nodes(l, straight + np.pi / 2, (3.0, -7.0)), theta)
    assert np.allclose(up, l.sum(), rtol=1e-13)


def held_chain(base: str) -> Scene:
    """Three rods (LENGTHS, m = 2 kg/m, EI = 1e6 N m^2, mu = 0.5 kg, no springs) with every
    hinge held at HELD, on ``base`` (free: turning at 0.5 rad/s; prescribed: spun up to 2
    rad/s in 0.5 s), 1 s: a rigid body in its base's frame, so tip_deflection is the constant
    sum l_k sin(HELD_0 + ... + HELD_k) while x, y turn with the base."""
    body, theta0, rate0 = BASES[base]
    chain = Chain.uniform(3, l=1.0, m=2.0, EI=1e6, mu=0.5, kappa=0.0, nu=0.0).with_(l=LENGTHS)
    outputs = ("phi", "alpha", "beta", "x", "y", "tip_deflection")
    return Scene(
        chain=chain,
        t_end=1.0,
        times=np.linspace(0.0, 1.0, 11),
        outputs=outputs + (("base",) if base != "pinned" else ()),
        initial=InitialState(phi=theta0 + np.cumsum(HELD), dphi=[rate0] * 3),
        base=body,
        latches=tuple(Latch(k, float(HELD[k]), held=True) for k in range(3)),
    )


def _run(scene: Scene, model: str):
    if model == "exudyn":
        pytest.importorskip("exudyn")
    tr = simulate(scene, model)
    assert tr.success, tr.stats.message
    return tr


def _bending_bound(alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """An upper bound (m, per output time) of |tip_deflection - the held closed form| from the
    rods' bending: the held hinges fix the tangents, so chord k turns from its held angle by
    delta_k = delta_{k-1} + beta_{k-1} - alpha_k (delta_1 = -alpha_1), and
    |sum l_k (sin(a_k + delta_k) - sin a_k)| <= sum l_k |delta_k|."""
    steps = np.concatenate([np.zeros((len(alpha), 1)), beta[:, :-1]], 1) - alpha
    return (LENGTHS * np.abs(np.cumsum(steps, 1))).sum(1)


@pytest.mark.parametrize(("model", "base"), MODEL_BASES)
def test_held_chain_closed_form_in_every_model_on_every_base(model, base):
    """The held chain's tip_deflection is sum l_k sin(HELD_0 + ... + HELD_k) at every output
    time, in the base's frame however the base moves: to round-off in the rigid model (and
    wherever a model's rods stay straight), within the bending bound (``_bending_bound``, from
    the run's own alpha, beta) in the full model and exudyn. Measured: full and exudyn 4e-6 m
    (free) and 7.6e-4 m (prescribed, the spin-up bends the rods), rigid <= 1.5e-14 m.
    It is also (r_n - r_0) . e2 of the run's own x, y and attitude, and for the native models
    (chords of length l) sum l_k sin(phi_k - theta) of its own phi."""
    tr = _run(held_chain(base), model)
    td = tr["tip_deflection"][:, 0]
    closed = float((LENGTHS * np.sin(np.cumsum(HELD))).sum())
    bound = _bending_bound(tr["alpha"], tr["beta"]) + ROUND_OFF
    assert np.all(np.abs(td - closed) <= bound), (np.abs(td - closed).max(), bound.max())
    if model == "rigid":
        assert np.abs(td - closed).max() <= ROUND_OFF
    theta = tr["base_attitude"][:, 0] if base != "pinned" else np.zeros(len(td))
    assert np.abs(td - tip_deflection(tr["x"], tr["y"], theta)).max() <= ROUND_OFF
    if model != "exudyn":  # exudyn's rods stretch (finite EA): its chords are not l long
        own = (LENGTHS * np.sin(tr["phi"] - theta[:, None])).sum(1)
        assert np.abs(td - own).max() <= ROUND_OFF


def _latched() -> Scene:
    """The two-rod latch scene (tests/scenes.py: hinge 1 unfolds onto its latch at 0.404 s)
    with x, y and tip_deflection, 0.42 s."""
    return two_rod_latch(1e5).with_(outputs=("phi", "x", "y", "tip_deflection"))


@pytest.mark.parametrize("model", ["reduced", "rigid", "exudyn"])
def test_every_model_agrees_with_full_on_a_latched_deployment(model):
    """On the pinned two-rod latch both frames are the x axis at the origin, so the gap in
    tip_deflection between two models is at most their tip-position gap (|(a - b) . e2| <=
    |a - b|), and at most what their chord angles' gap carries: |sum c_k sin phi_k - sum l_k
    sin phi'_k| <= sum l_k |phi_k - phi'_k| + sum |c_k - l_k| (c_k the other model's chord
    lengths from its x, y: exudyn's stretch; l_k for the native models). Measured against
    full: reduced 0.032 m (tip gap 0.042 m), rigid 0.032 m (0.042 m), exudyn 1.8e-3 m (2.3e-3
    m) on a tip deflection of 2.08 m after the lock."""
    scene = _latched()
    full = _run(scene, "full")
    other = _run(scene, model)
    gap = np.abs(full["tip_deflection"][:, 0] - other["tip_deflection"][:, 0])
    tip = np.hypot(full["x"][:, -1] - other["x"][:, -1], full["y"][:, -1] - other["y"][:, -1])
    assert np.all(gap <= tip + ROUND_OFF)
    chords = np.hypot(np.diff(other["x"], axis=1), np.diff(other["y"], axis=1))
    l = scene.chain.l
    carried = (l * np.abs(full["phi"] - other["phi"])).sum(1) + np.abs(chords - l).sum(1)
    assert np.all(gap <= carried + ROUND_OFF)
    assert full["tip_deflection"][-1, 0] > 2.0  # unfolded: the tip 2 m off the x axis
