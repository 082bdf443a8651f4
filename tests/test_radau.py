"""The compiled Radau IIA (``rodval.solvers.radau``) and the stiffness switch of "auto"
(``rodval.solvers.stiffness``): the method's algebra, agreement with scipy's Radau and with
tight references, and the switch's choices on the scenes that motivated it (issue 20)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rodval import paper_scene, simulate
from rodval.bench.stiffness import rigid_latch, stiff_paper
from rodval.core.settings import IntegratorSettings
from rodval.models import get_model
from rodval.solvers import radau, stiffness
from rodval.solvers.compiled import Controls, integrate_compiled, packed
from rodval.solvers.dop853 import RADAU_STEPPER
from rodval.solvers.dop853_events import interpolate
from rodval.solvers.guard import GuardSpec


@pytest.mark.parametrize("dtype", [float, complex])
def test_lu_solves_to_backward_stability(dtype):
    """Partial pivoting is backward stable: |A x - b| <= c N eps |A| |x| (c ~ 1 for these
    well-scaled random matrices; bound 10 N eps)."""
    rng = np.random.default_rng(3)
    for N in (1, 2, 7, 40):
        A = rng.normal(size=(N, N)) + (1j * rng.normal(size=(N, N)) if dtype is complex else 0)
        b = rng.normal(size=N).astype(dtype)
        LU, piv, x = A.astype(dtype).copy(), np.zeros(N, np.int64), b.copy()
        radau.lu_factor(LU, piv)
        radau.lu_solve(LU, piv, x)
        eps = np.finfo(float).eps
        bound = 10 * N * eps * np.linalg.norm(A, 2) * np.linalg.norm(x)
        assert np.linalg.norm(A @ x - b) <= bound


def test_dense_output_passes_through_the_collocation_points():
    """The cubic interpolant in the DOP853 loop's form (``dense_coefficients``) is the
    collocation polynomial: y + Z[a] at x = C[a] and y at x = 0, to round-off (the
    coefficients are O(1), so 1e-14 absolute)."""
    rng = np.random.default_rng(5)
    y, Z, F, out = rng.normal(size=6), rng.normal(size=(3, 6)), np.empty((7, 6)), np.empty(6)
    radau.dense_coefficients(Z, F)
    for a in range(3):
        interpolate(F, y, radau.C[a], out)
        np.testing.assert_allclose(out, y + Z[a], rtol=0, atol=1e-14)
    interpolate(F, y, 0.0, out)
    np.testing.assert_array_equal(out, y)


def test_compiled_radau_is_scipys_radau():
    """Same method, constants and step control as scipy's Radau: on the paper chain (full
    model, rtol 1e-6) the accepted steps agree within 5 % (the controllers differ only in
    the previous step size kept and the Jacobian's increments) and the end states within
    the tolerance (1e-6 relative)."""
    scene = paper_scene(4)
    system = get_model("full").system(scene)
    edges = np.concatenate([[0.0], scene.breakpoints, [scene.t_end]])
    Y = np.empty((scene.times.size, system.y0.size))
    controls = Controls(1e-6, 1e-8, np.inf, None, 10**7, stepper=RADAU_STEPPER)
    ours = integrate_compiled(
        system.compiled(), system.y0, edges, scene.times, Y, controls, GuardSpec()
    )
    y, steps = system.y0, 0
    for a, b in zip(edges[:-1], edges[1:]):
        sol = solve_ivp(system.rhs, (a, b), y, method="Radau", rtol=1e-6, atol=1e-8)
        y, steps = sol.y[:, -1], steps + sol.t.size - 1
    assert ours.code == 0 and abs(ours.nsteps / steps - 1) < 0.05, (ours.nsteps, steps)
    np.testing.assert_allclose(Y[-1], y, rtol=1e-6, atol=1e-8)


def test_auto_switches_to_radau_on_near_rigid_panels_and_stays_accurate():
    """Paper chain at EI = 1e9 (issue 20: the explicit cost grew as sqrt(EI)): "auto" finds
    DOP853's steps set by the bending block and goes on with Radau IIA, recorded with its
    figures; it needs < 1/10 of DOP853's evaluations (measured 1/46) and its phi is within
    the tolerance of a tight reference (Radau IIA at rtol 1e-11; measured 4.1e-9 against
    rtol |phi| = 5.8e-8)."""
    scene = stiff_paper(1e9)
    auto = simulate(scene, "full")
    dop = simulate(scene, "full", method="DOP853-numba")
    tight = IntegratorSettings("Radau-numba", rtol=1e-11, atol=1e-13, max_evaluations=10**8)
    ref = simulate(scene, "full", settings=tight)
    assert auto.success and dop.success and ref.success
    switch = auto.stats.switch
    assert switch["ended_on"] == "Radau-numba" and switch["spectral_radius"] > 1e5
    assert "spent on the fastest mode" in switch["reason"]
    assert switch["implicit_cost_per_s"] < switch["explicit_cost_per_s"]
    assert auto.stats.nfev < dop.stats.nfev / 10
    phi = np.abs(ref["phi"])
    assert np.max(np.abs(auto["phi"] - ref["phi"]) / np.maximum(phi, 1.0)) < 1e-8 * 6


def test_auto_comes_back_to_dop853_where_radau_is_dearer():
    """Paper chain at EI = 1e5: DOP853 sits near the fastest mode (h rho = 2-4), but the motion
    excites it, so Radau IIA is dearer (6x the evaluations by name). "auto" tries it, comes
    back, and costs within 10 % of DOP853 (measured +1.8 %) with the same phi to 1e-9."""
    scene = stiff_paper(1e5)
    auto = simulate(scene, "full")
    dop = simulate(scene, "full", method="DOP853-numba")
    switch = auto.stats.switch
    assert switch["ended_on"] == "DOP853-numba" and switch["failed_trials"] >= 1
    assert auto.stats.nfev < 1.1 * dop.stats.nfev
    np.testing.assert_allclose(auto["phi"], dop["phi"], rtol=0, atol=1e-9)


def test_a_switch_is_the_same_on_every_run_and_recorded_in_run_files(tmp_path):
    """The switch is decided on counts, not the clock: two runs agree bit for bit; the
    record survives run.json."""
    from rodval.report.run_files import read_run, write_run

    scene = stiff_paper(1e8)
    a, b = simulate(scene, "full"), simulate(scene, "full")
    np.testing.assert_array_equal(a["phi"], b["phi"])
    assert a.stats.switch is not None and a.stats.nfev == b.stats.nfev
    assert a.stats.switch == b.stats.switch
    write_run(a, scene, tmp_path / "run")
    assert read_run(tmp_path / "run").stats.switch == a.stats.switch


def test_the_rigid_two_rod_latch_runs_cheaply_in_the_reduced_model():
    """Issue 19/20: two near-rigid rods (EI = 1e9), free root, hinge 1 latching at 0. The
    locked reduced model holds the hinge through a constraint mode of ~1e5 1/s; "auto" goes
    on with Radau IIA after the lock and needs < 1/100 of DOP853's evaluations (measured
    647 vs 300,583); the hinge stays locked and the rate after the lock is H / I (rigid
    body about the root: I = sum of the rods' inertia about it), to 1e-6."""
    scene = rigid_latch()  # the scene of ``rodval bench stiffness``
    auto = simulate(scene, "reduced")
    dop = simulate(scene, "reduced", method="DOP853-numba")
    assert auto.success and auto.stats.switch["ended_on"] == "Radau-numba"
    assert auto.stats.nfev < dop.stats.nfev / 100
    after = auto.times > auto.events[0]["t"] + 0.05
    assert np.max(np.abs(auto["hinge_angle"][after, 1])) < 1e-12
    H = auto["angular_momentum"][-1, 0]
    # straight, rigid, about the free root: rods 1 m, 1 kg, tip masses 0.5 kg at 1 m and 2 m
    inertia = 2.0**3 / 3.0 + 0.5 * 1.0**2 + 0.5 * 2.0**2
    np.testing.assert_allclose(auto["dphi"][after], H / inertia, rtol=1e-6)


def test_radau_numba_refuses_systems_too_large_for_dense_algebra():
    scene = paper_scene(200)
    with pytest.raises(ValueError, match=r"'Radau-numba'.*N = 1200 states, allowed N <= 600"):
        simulate(scene, "full", method="Radau-numba")


def test_spectral_radius_finds_the_bending_frequency():
    """The power iteration on J^2 against the eigenvalues of the finite-difference Jacobian:
    within 10 % on the paper chain (its top pairs cluster; measured within 1 %)."""
    system = get_model("full").system(stiff_paper(1e7))
    form = system.compiled()
    y = system.y0.copy()
    N = y.size
    f = np.empty(N)
    form.rhs(0.0, y, form.P, form.S, form.M, form.L, f)
    J = np.empty((N, N))
    for j in range(N):
        yy, fj = y.copy(), np.empty(N)
        yy[j] += 1e-7
        form.rhs(0.0, yy, form.P, form.S, form.M, form.L, fj)
        J[:, j] = (fj - f) / 1e-7
    exact = np.max(np.abs(np.linalg.eigvals(J)))
    rho = stiffness.spectral_radius(packed(form), 0.0, y, f, np.empty(N), np.empty(N), np.empty(N))
    assert abs(rho / exact - 1) < 0.1, (rho, exact)


def test_dop853_stability_boundary_on_the_imaginary_axis():
    """``stiffness.STABILITY_IMAG`` is DOP853's: the first y where |R(i y)| > 1 for its
    stability function R(z) = 1 + z b^T (I - z A)^-1 1 (scipy's coefficients), on a grid of
    0.002 (the constant's stated 3 digits)."""
    from scipy.integrate._ivp import dop853_coefficients as dc

    A, b, one = dc.A[: dc.N_STAGES, : dc.N_STAGES], dc.B, np.ones(dc.N_STAGES)
    grid = np.arange(0.002, 12.0, 0.002)
    R = [abs(1 + 1j * y * b @ np.linalg.solve(np.eye(dc.N_STAGES) - 1j * y * A, one)) for y in grid]
    first = grid[np.argmax(np.array(R) > 1.0 + 1e-9)]
    assert abs(first - stiffness.STABILITY_IMAG) < 0.005, first
