"""The exudyn reference model: closed-form limits, option validation, and the CI comparison
against the native full and reduced models."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodval import Chain, InitialState, Scene, paper_scene, simulate
from rodval.analysis.crosscheck import ACCEPTANCE, crosscheck_paper, table1_gaps

exu = pytest.importorskip("exudyn")
from reference_models.exudyn_chain import ExudynModel  # noqa: E402

pytestmark = pytest.mark.exudyn


def test_clamped_rod_first_bending_frequency():
    """A single rod, its root clamped by a very stiff hinge-0 spring (kappa = 1e10 N m/rad,
    2e5 x EI/l), no tip mass: exudyn's eigenvalue solver on the model's own system gives the
    first bending frequency of an Euler-Bernoulli cantilever, 1.8751^2 sqrt(EI / (m l^4))."""
    l, m, EI = 2.0, 3.0, 1e5
    chain = Chain.uniform(1, l=l, m=m, EI=EI, mu=0.0, kappa=1e10, nu=0.0)
    built = ExudynModel(elements=4)._build(Scene(chain=chain, t_end=1.0))
    eig, _ = exu.solver.ComputeODE2Eigenvalues(built.mbs)
    omega = np.sqrt(np.sort(np.abs(eig)))
    first_bending = omega[omega > 1.0][0]
    expected = 1.8751**2 * math.sqrt(EI / (m * l**4))
    assert first_bending == pytest.approx(expected, rel=1e-2)


def test_rigid_pendulum_period():
    """One very stiff rod (EI = 1e9 N m^2) on a hinge-0 spring kappa with a tip mass mu and no
    load: small oscillations have omega = sqrt(kappa / (m l^3 / 3 + mu l^2)). The period is read
    from the upward zero crossings of phi over two periods."""
    l, m, mu, kappa = 2.0, 3.0, 3.0, 100.0
    omega = math.sqrt(kappa / (m * l**3 / 3 + mu * l**2))
    period = 2 * math.pi / omega
    chain = Chain.uniform(1, l=l, m=m, EI=1e9, mu=mu, kappa=kappa, nu=0.0)
    times = np.arange(0.0, 2.2 * period, 1e-3)
    scene = Scene(
        chain=chain,
        t_end=float(times[-1]),
        times=times,
        outputs=("phi",),
        initial=InitialState(phi=[0.01]),
    )
    tr = simulate(scene, "exudyn", elements=1, step=1e-3)
    assert tr.success, tr.stats.message
    phi = tr["phi"][:, 0]
    i = np.flatnonzero((phi[:-1] < 0) & (phi[1:] >= 0))
    crossings = times[i] - phi[i] * (times[i + 1] - times[i]) / (phi[i + 1] - phi[i])
    assert crossings.size >= 2
    assert np.diff(crossings).mean() == pytest.approx(period, rel=2e-3)
    assert np.abs(phi).max() == pytest.approx(0.01, rel=1e-2)


@pytest.mark.parametrize(
    "option, value",
    [
        ("elements", 0),
        ("elements", 1.5),
        ("step", 0.0),
        ("step", 1.0),
        ("EA", -1.0),
        ("element", "beam3d"),
        ("solver", "rk4"),
        ("spectral_radius", 1.5),
        ("newton_rtol", 0.5),
        ("newton_atol_per_EA", 0.0),
        ("max_rotation_per_step", 0.0),
        ("max_rotation_per_step", 4.0),
    ],
)
def test_bad_option_names_the_option(option, value):
    with pytest.raises(ValueError, match=option):
        ExudynModel(**{option: value})


def test_outputs_labels_and_stats():
    """Exactly the requested quantities at the requested times, with the native k labels
    ("energy" brings the energy audit, as in the native models)."""
    scene = paper_scene(
        2,
        t_end=0.1,
        times=[0.0, 0.05, 0.1],
        outputs=("phi", "dphi", "alpha", "beta", "x", "y", "energy"),
    )
    tr = simulate(scene, "exudyn", step=1e-3)
    assert tr.success, tr.stats.message
    assert np.array_equal(tr.times, scene.times)
    assert set(tr.quantities) == {
        "phi",
        "dphi",
        "alpha",
        "beta",
        "x",
        "y",
        "kinetic",
        "potential",
        "energy",
        "work",
        "dissipated",
        "energy_residual",
    }
    assert tr.k_index["phi"].tolist() == [1, 2]
    assert tr.k_index["x"].tolist() == [0, 1, 2]
    assert tr.k_index["energy"].tolist() == [0]
    assert tr.stats.nsteps >= 100 and tr.stats.wall_s > 0
    assert tr.stats.t_reached == pytest.approx(0.1)
    # chord geometry: node positions follow from phi and l (inextensible to ~F/EA)
    x = np.concatenate([[0.0], np.cumsum(2.0 * np.cos(tr["phi"][-1]))])
    np.testing.assert_allclose(tr["x"][-1], x, atol=1e-6)
    # energy: starts at rest, straight (zero), then the load does positive work
    assert tr["energy"][0, 0] == pytest.approx(0.0, abs=1e-12)
    assert tr["energy"][-1, 0] > 0


def test_failure_is_data_not_a_crash():
    """A load law that raises ends the run with a status and the message."""
    from rodval import NodalForce

    def bad(t):
        raise RuntimeError("load exploded")

    scene = Scene(chain=Chain.uniform(1), loads=(NodalForce(1, fx=bad),), t_end=0.01)
    tr = simulate(scene, "exudyn", step=1e-3)
    assert not tr.success
    assert "load exploded" in tr.stats.message


def test_ci_comparison_native_vs_exudyn_n3():
    """n = 3 chain, paper per-rod data, pulse at node 3, 0..0.5 s: native full (printed) and
    reduced (DOP853 rtol 1e-10, atol 1e-12) against exudyn at its defaults (2 elements/rod,
    step 2e-4 s, EA 1e10 N).

    Measured gaps on this run (max over t = 0.1..0.5 s, all rods): full: phi 1.4e-4 rad, dphi
    1.5e-4 of the column scale, alpha/beta 6.5e-6 rad; reduced: phi 1.9e-4, dphi 2.1e-4,
    alpha/beta 5.8e-6. The convergence study (benchmarks/exudyn_convergence.py, n = 8, 0..2 s,
    docs/reference_model.md) shows the exudyn discretization moves phi by < 2e-5 rad, dphi by
    < 3e-4 and alpha/beta by < 1e-6 rad between step 2e-4 and 5e-5 s, and EA 1e10 -> 1e11 by
    ~7e-5 rad: what remains is the model difference (first-order assumed-mode rods vs exact
    beams). The bounds below are ~3x the measured gaps: phi 5e-4 rad, dphi 1e-3, alpha/beta
    2e-5 rad (the issue's acceptance bounds, 1.5e-3 / 2e-2 / 2e-4, are checked on n = 8 in the
    slow study).
    """
    scene = paper_scene(3, t_end=0.5, times=np.linspace(0.1, 0.5, 5))
    ex = simulate(scene, "exudyn")
    assert ex.success, ex.stats.message
    for model in ("full", "reduced"):
        gaps = table1_gaps(ex, simulate(scene, model, rtol=1e-10, atol=1e-12), rods=(1, 2, 3))
        for q, bound in (("phi", 5e-4), ("dphi", 1e-3), ("alpha", 2e-5), ("beta", 2e-5)):
            assert gaps[q] < bound, f"{model} {q}: max gap {gaps[q]:.3g} >= {bound}"


def test_paper_example_supports_printed_not_published():
    """Paper example (n = 8, 0..2 s), rods 2, 4, 6, 8 at t = 0.5, 1, 1.5, 2 s: exudyn at its
    converged defaults agrees with the native full model (printed coefficients) within phi
    1.5e-3 rad, dphi 2e-2 of the column scale, alpha/beta 2e-4 rad; against the ``published``
    variant the alpha/beta gap exceeds 2e-4 rad."""
    table, runs = crosscheck_paper()
    assert runs["exudyn"].success, runs["exudyn"].stats.message
    rows = table.set_index("comparison")
    for q, bound in ACCEPTANCE.items():
        assert rows.loc["exudyn vs full printed", q] < bound, q
    for q in ("alpha", "beta"):
        assert rows.loc["exudyn vs full published", q] > ACCEPTANCE[q], q
    assert rows.loc["exudyn vs full printed", "within_acceptance"]
