"""The full model on a free base (a spacecraft body, docs/base.md): input checks, the bordered
solve against the mass matrix of the model's own kinetic energy, the first integrals, the
heavy-body limit and latches that lock against the body."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scenes import three_panel_free_scene  # noqa: E402

from rodval import Base, paper_scene, simulate
from rodval.core.scene_file import scene_from_dict, scene_to_dict
from rodval.models.systems.chain_system import ChainSystem

STUDIES = Path(__file__).resolve().parents[1] / "studies"
BODY = dict(kind="free", mass=50.0, inertia=20.0, hinge_offset=[0.5, 0.2])
OUT = ("phi", "alpha", "x", "y", "energy", "angular_momentum", "momentum", "base")


def free_scene(n=3, t_end=1.0, EI=1e5, **body):
    s = paper_scene(n, t_end=t_end)
    base = Base(**{**BODY, "rate": 0.3, "velocity": [0.1, -0.2], **body})
    return s.with_(chain=s.chain.with_(EI=EI), loads=(), outputs=OUT, base=base)


@pytest.mark.parametrize(
    "fields, message",
    [
        (dict(kind="free"), r"a free base needs its mass \(base.mass\)"),
        (dict(kind="free", mass=1.0), r"needs its inertia"),
        (
            dict(kind="free", mass=-1.0, inertia=1.0),
            r"base mass \(kg\) must be a finite real number > 0",
        ),
        (dict(kind="free", mass=1.0, inertia=1.0, position=[1.0]), r"base position must be a pair"),
        (dict(kind="free", mass=1.0, inertia=1.0, rate=float("nan")), r"base rate \(rad/s\)"),
        (dict(kind="pinned", mass=3.0), r"base mass describes a free body"),
        (dict(kind="orbiting"), r"base kind must be one of \('pinned', 'free', 'prescribed'\)"),
    ],
)
def test_bad_base_is_refused_naming_the_field(fields, message):
    with pytest.raises(ValueError, match=message):
        Base(**fields)


def test_base_table_round_trips_and_a_pinned_scene_dict_is_unchanged():
    s = free_scene()
    d = scene_to_dict(s)
    assert d["base"]["mass"] == 50.0 and scene_from_dict(d).base == s.base
    assert "base" not in scene_to_dict(paper_scene(3))  # pinned records as before
    with pytest.raises(ValueError, match=r"\[base\]: unknown key 'spin'"):
        scene_from_dict({"base": {**BODY, "spin": 1.0}})
    with pytest.raises(ValueError, match="output 'base' needs a free or prescribed base"):
        paper_scene(2).with_(outputs=("base",))


@pytest.mark.parametrize(
    "model, options, message",
    [
        ("reduced", {}, "model 'reduced' has no free base"),
        ("full", {"kernel": "numpy"}, "kernel must be 'numba'"),
    ],
)
def test_models_without_a_free_base_refuse_it_before_any_work(model, options, message):
    with pytest.raises(ValueError, match=message):
        simulate(free_scene(), model, **options)


def _mass_matrix(system, y):
    """M(Q) of the model's own kinetic energy (compiled T) by polarization: T is quadratic in
    Q', so M_ij = T(e_i + e_j) - T(e_i) - T(e_j) exactly up to round-off."""
    N = system.N
    q = y[:N]

    def T(v):
        return system.kinetic_energy(0.0, np.concatenate([q, v]))

    E = np.eye(N)
    return np.array([[T(E[i] + E[j]) - T(E[i]) - T(E[j]) for j in range(N)] for i in range(N)])


def _rotation(system, y):
    """dQ of a rigid rotation of the whole system about the origin."""
    n, N = system.n, system.N
    d = np.zeros(N)
    d[:n] = 1.0
    d[3 * n : 3 * n + 2] = -y[3 * n + 1], y[3 * n]
    d[3 * n + 2] = 1.0
    return d


def test_bordered_solve_inverts_the_mass_matrix_of_the_kinetic_energy():
    """The kernel's O(n) solve (chain eliminated, 3 x 3 Schur complement) against the dense
    M(Q) of the compiled T at a random state: M U^T = A^T for the unit hinge moments, hinge 0
    acting on the body too (entries ~1e2..1e3 kg m^2: 1e-10 is ~1e3 ulps of them)."""
    system = ChainSystem(free_scene(4))
    rng = np.random.default_rng(7)
    y = system.y0 + 0.2 * rng.standard_normal(system.y0.size)
    M = _mass_matrix(system, y)
    hinges = np.arange(4)
    U = system.unit_responses(y, hinges)
    A = system.hinge_rows(hinges)
    assert np.abs(M - M.T).max() < 1e-10 * np.abs(M).max()
    assert np.abs(M @ U.T - A.T).max() < 1e-10
    assert np.abs(A @ _rotation(system, y)).max() == 0.0  # hinge moments are internal


def test_momenta_are_the_models_own_conjugate_momenta():
    """P is dT/dx_c'; H about the origin is T's momentum of a rigid rotation when the rods
    are straight (the first-order velocity field of rod_momenta is exact there)."""
    system = ChainSystem(free_scene(3))
    rng = np.random.default_rng(3)
    y = system.y0 + 0.2 * rng.standard_normal(system.y0.size)
    n, N = system.n, system.N
    y[n : 3 * n] = 0.0
    y[N + n : N + 3 * n] = 0.0
    p = _mass_matrix(system, y) @ y[N:]
    P = system.momentum_rows(y[None, :])[0]
    assert np.abs(P - p[3 * n : 3 * n + 2]).max() < 1e-12 * np.abs(P).max()
    H = system.angular_momentum_rows(np.zeros(1), y[None, :])[0, 0]
    r0 = system.root_motion(y)[0]
    HO = H + r0[0] * P[1] - r0[1] * P[0]
    assert abs(HO - _rotation(system, y) @ p) < 1e-12 * abs(HO)


def _drift(values):
    return float(np.abs(values - values[0]).max() / np.abs(values[0]).max())


def test_free_chain_keeps_its_momentum_and_its_angular_momentum_to_the_first_order_limit():
    """No load: P constant to 1e-10 relative at rtol 1e-10 (the translation equation is
    dP/dt = 0 exactly; measured 4.4e-15 by benchmarks/free_base_checks.py). H about the
    system's centre of mass is kept up to the paper's first-order kinematics, whose dropped
    terms are O(bending) relative: the drift stays below max |alpha| and falls with it
    (EI x 100: bending / 100, drift measured 3.1e-7 -> 3.1e-9)."""
    drifts = []
    for EI in (1e5, 1e7):
        tr = simulate(free_scene(EI=EI), "full", kinematics="first-order", rtol=1e-10, atol=1e-12)
        assert tr.stats.success
        assert _drift(tr["momentum"]) < 1e-10
        bending = np.abs(tr["alpha"]).max()
        drifts.append(_drift(tr["angular_momentum"][:, 1]))
        assert drifts[-1] < bending
    assert drifts[1] < drifts[0] / 50


def test_a_heavy_body_converges_to_the_pinned_chain():
    """The body's motion is O(chain mass / body mass): the gap to the pinned chain falls 1000x
    with the body 1000x heavier (measured 5.69e-5 -> 5.69e-8 rad of phi)."""
    base = paper_scene(3, t_end=1.0)
    first = {"kinematics": "first-order"}  # the paper's rung on both bases
    ref = simulate(base, "full", **first, rtol=1e-10, atol=1e-12)["phi"]
    gaps = []
    for mass in (1e6, 1e9):
        body = Base(kind="free", mass=mass, inertia=mass)
        tr = simulate(base.with_(base=body), "full", **first, rtol=1e-10, atol=1e-12)
        gaps.append(np.abs(tr["phi"] - ref).max())
    assert gaps[1] < 1e-6
    assert 0.5e-3 < gaps[1] / gaps[0] < 2e-3


def test_latches_lock_against_the_body_keeping_the_momentum():
    """The companion paper's three panels deploying from a 1000 kg, 2000 kg m^2 body: hinge 0
    locks rod 1 to the body, hinge 2 locks later; the locked hinges stay at their angles, the
    linear momentum is kept through the plastic locks (1e-10 relative, as without them), and
    the lock's own jump keeps T's momentum of a rigid rotation (internal impulses)."""
    scene = three_panel_free_scene()
    tr = simulate(scene, "full", rtol=1e-10, atol=1e-12)
    assert tr.stats.success
    labels = [ev["label"] for ev in tr.events]
    assert labels == ["latch hinge 0", "latch hinge 2"]
    assert _drift(tr["momentum"]) < 1e-10
    D = tr["hinge_angle"]
    after = tr.times > tr.events[-1]["t"]
    assert np.abs(D[after][:, [0, 2]]).max() < 1e-9  # held at 0 (the latch angle)
    assert np.abs(tr["base_attitude"][-1, 0]) > 0.05  # the body turned: it took the impulse
    system = ChainSystem(scene)
    y = system.y0.copy()
    held = np.array([0, 2])
    y_new, _ = system.plastic_jump(y, held, system.hinge_rows(held) @ y[: system.N])
    assert np.abs(system.hinge_rows(held) @ y_new[system.N :]).max() < 1e-12  # rates stopped
    d = _rotation(system, y)
    before = d @ _mass_matrix(system, y) @ y[system.N :]
    jumped = d @ _mass_matrix(system, y_new) @ y_new[system.N :]
    assert abs(jumped - before) < 1e-10 * abs(before)
