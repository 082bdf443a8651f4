"""The chain engine's parts chosen independently (issue 40): the base (pinned, free body,
prescribed motion) x the kinematics (first-order, exact) x the shapes (p = 1, 3), with the
paper's dynamic bending, on the latched 3-rod scene (``benchmarks/exudyn_speed.latch3_scene``:
hinge 0 free, hinges 1 and 2 unfold onto latches). The quasi-static bending (the reduced
model) runs on the pinned paper rung only; it refuses a moving base before any work."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from exudyn_speed import latch3_scene  # noqa: E402

from rodval import Base, simulate  # noqa: E402
from rodval.core.base import Motion  # noqa: E402

BASES = {
    "pinned": Base(),
    "free": Base(kind="free", mass=50.0, inertia=20.0, hinge_offset=(0.5, 0.0)),
    "prescribed": Base(
        kind="prescribed",
        hinge_offset=(0.5, 0.0),
        motion={
            "attitude": Motion("spin_up", (2.0, 1.0)),
            "x": Motion("harmonic", (0.1, 3.0, 0.0)),
        },
    ),
}
#: rtol 1e-10 of the default integrator: a conserved quantity is kept to a few rtol of its
#: scale; the locks (plastic jumps in the total mass matrix) keep P and H to round-off.
KEPT = 1e-10


def scene(base: str):
    outputs = ("phi", "energy") + (
        ("base", "momentum", "angular_momentum") if base == "free" else ()
    )
    return latch3_scene().with_(base=BASES[base], outputs=outputs)


@pytest.mark.parametrize("shapes", [1, 3])
@pytest.mark.parametrize("kinematics", ["first-order", "exact"])
@pytest.mark.parametrize("base", list(BASES))
def test_every_combination_runs_locks_and_keeps_its_energy_balance(base, kinematics, shapes):
    tr = simulate(scene(base), "full", kinematics=kinematics, shapes=shapes)
    st = tr.stats
    assert tr.success, st.message
    assert sorted(e["hinge"] for e in tr.events) == [1, 2]  # both latches lock
    # energy audit (the drive's power booked on a prescribed base): on the exact kinematics
    # integration error only (rtol 1e-10 per step over ~1e4 steps: 1e-6); the first-order
    # kinematics drops O(bending) terms of T, its residual (0.04-0.05 here) is its own
    assert st.energy_residual is not None
    if kinematics == "exact":
        assert st.energy_residual < 1e-6
    if base == "free" and kinematics == "exact":
        # the system starts at rest: P and H (about the centre of mass) are 0; the drift is
        # measured against the gross momenta (1 N s; the audit's sum of |h_k|)
        P = tr["momentum"]
        assert np.abs(P - P[0]).max() < KEPT * 1.0
        assert st.momentum_residual < KEPT


def test_the_first_rung_on_a_free_body_is_the_paper_free_base_to_round_off():
    """The ladder's p = 1 first-order rung on a free body (``chain_base``) against the paper's
    free-base kernels (``free_base``): the same equations, other arithmetic: 1e-14."""
    from rodval.models.systems.chain_system import ChainSystem, LadderSystem

    body = Base(kind="free", mass=1e3, inertia=2e3, hinge_offset=(1.0, 0.0), rate=0.3)
    sc = latch3_scene().with_(base=body)
    paper = ChainSystem(sc)
    rung = LadderSystem(sc, "printed", "numba", 1, "first-order")
    rng = np.random.default_rng(1)
    for _ in range(3):
        y = paper.y0 + 0.1 * rng.standard_normal(paper.y0.size)
        a, b = paper.rhs(0.0, y), rung.rhs(0.0, y)
        assert np.abs(a - b).max() <= 1e-13 * np.abs(a).max()
        assert abs(paper.kinetic_energy(0, y) - rung.kinetic_energy(0, y)) <= 1e-13 * abs(
            paper.kinetic_energy(0, y)
        )


def test_a_prescribed_base_follows_its_laws_and_books_the_drive():
    """The body's coordinates follow the laws to the integration's tolerance; the energy
    balance with the drive's power F_d . v_0 + m_1 theta' closes on the exact kinematics
    (without it the drive's work, the chain's whole kinetic energy, would be missing)."""
    tr = simulate(
        scene("prescribed").with_(outputs=("phi", "base", "energy")), "full", kinematics="exact"
    )
    law = BASES["prescribed"]
    for t, theta in zip(tr.times, tr["base_attitude"][:, 0]):
        assert abs(theta - law.state_at(float(t))[2]) < 1e-8
    assert tr.success and tr.stats.energy_residual < 1e-6  # integration error only


def test_quasi_static_bending_refuses_a_moving_base_before_any_work():
    for base in ("free", "prescribed"):
        with pytest.raises(ValueError, match=f"model 'reduced' has no {base} base"):
            simulate(scene(base), "reduced")


def test_the_drive_of_a_stiff_clamped_beam_is_the_rigid_body_s():
    """A stiff beam (2 rods, 1 m each, 1 kg/m, EI 1e8) clamped to a hub spun up by the law:
    the base's force on it is M a_cm (M = 2 kg, centre at 1 m) and its moment I_O theta''
    (I_O = M L^2 / 3 = 8/3 kg m^2), to the beam's flexibility (deflection / length ~ 1e-7)."""
    from rodval.core.hinges import Latch
    from rodval.core.scene import Chain, InitialState, Scene

    hub = Base(kind="prescribed", motion={"attitude": Motion("spin_up", (3.0, 1.0))})
    sc = Scene(
        chain=Chain.uniform(2, l=1.0, m=1.0, EI=1e8, mu=0.0, kappa=0.0, nu=0.0),
        t_end=1.5,
        times=np.linspace(0.0, 1.5, 31),
        outputs=("phi", "base", "drive"),
        initial=InitialState(phi=[0.0, 0.0]),
        latches=(Latch(0, 0.0, held=True), Latch(1, 0.0, held=True)),
        base=hub,
    )
    tr = simulate(sc, "full", kinematics="exact")
    assert tr.success
    th, w = tr["base_attitude"][:, 0], tr["base_rate"][:, 0]
    acc = np.array(
        [hub.motion[2].params[0] * (1 - np.cos(2 * np.pi * min(t, 1.0))) for t in tr.times]
    )
    acc[tr.times >= 1.0] = 0.0
    e = np.stack([np.cos(th), np.sin(th)], -1)
    n = np.stack([-np.sin(th), np.cos(th)], -1)
    F = 2.0 * 1.0 * (acc[:, None] * n - (w * w)[:, None] * e)  # M (theta'' n - theta'^2 e) r_cm
    scale = np.abs(F).max()
    assert np.abs(tr["drive_force"] - F).max() < 1e-5 * scale
    assert np.abs(tr["drive_moment"][:, 0] - 8.0 / 3.0 * acc).max() < 1e-5 * 8.0 / 3.0 * 3.0 * 2


def test_quasi_static_bending_approaches_the_dynamic_as_one_over_EI():
    """The quasi-static bending (the reduced preset, pinned paper rung) against the dynamic
    (the full preset) on the latched 3-rod scene up to just before its first lock (0.30 s):
    max |phi_full - phi_reduced| falls 10x per decade of EI (the bending compliance), within
    30 % (the gap's own O(1/EI^2) part and rtol 1e-10). Measured 1.9e-4, 1.8e-5 and 1.9e-6 rad
    at EI = 1e5, 1e6, 1e7 N m^2 (ratios 10.8 and 9.6)."""
    gaps = []
    for EI in (1e5, 1e6):
        sc = scene("pinned")
        sc = sc.with_(
            chain=sc.chain.with_(EI=EI), t_end=0.3, times=np.linspace(0, 0.3, 31), outputs=("phi",)
        )
        full, reduced = simulate(sc, "full"), simulate(sc, "reduced")
        assert full.success and reduced.success and full.events == reduced.events == []
        gaps.append(np.abs(full["phi"] - reduced["phi"]).max())
    assert 7.0 < gaps[0] / gaps[1] < 13.0
