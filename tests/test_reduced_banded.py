"""The O(n) reduced-model solves (rodval.models.bending.reduced_banded: the tip-to-root sweep and the
banded LU) against the dense numpy reference (ReducedSystem with kernel="numpy": numpy_rhs for
phi'', recover_bending for gamma)."""

import numpy as np
import pytest

from rodval.core.loads import constant, pulse
from rodval.core.scene import Chain, InitialState, Scene
from rodval.models.assembly.paper_matrices import (
    angle_differences,
    assemble_mass,
    chain_constants,
    convective_terms,
)
from rodval.models.bending import reduced_band_lu as lu
from rodval.models.bending import reduced_banded as rb
from rodval.models.presets.reduced import ReducedSystem

RTOL = 1e-9
#: the kernels' "no hinge moments" (``Tq`` of length 0)
NO_TQ = np.zeros(0)
TIMES = (0.3, 0.5, 1.7)  # both loads on; at the X kink; past the pulse (constant only)


def make_scene(n: int, damped: bool, loaded: bool, seed: int = 0, kappa=None, mu=None) -> Scene:
    """A non-uniform chain (so that no symmetry hides an index error)."""
    rng = np.random.default_rng(1000 * n + seed)
    chain = Chain(
        l=rng.uniform(0.5, 2.5, n),
        m=rng.uniform(1, 4, n),
        EI=rng.uniform(1e3, 1e5, n),
        mu=rng.uniform(0, 3, n) if mu is None else mu,
        kappa=rng.uniform(0, 200, n) if kappa is None else kappa,
        nu=rng.uniform(0.01, 0.5, n) if damped else 0.0,
    )
    loads = (pulse(n), constant(max(1, n // 2), X=30.0, Y=-20.0, t_on=0.2)) if loaded else ()
    return Scene(chain=chain, loads=loads, t_end=2.0, initial=InitialState(phi=rng.normal(size=n)))


METHODS = (rb.METHOD_SWEEP, rb.METHOD_BAND)


def banded(ref: ReducedSystem, t: float, phi: np.ndarray, dphi: np.ndarray, method: int):
    Cst = rb.banded_constants(ref.cc, ref.scene.chain)
    loads = ref.kernel_loads(t, np.concatenate([phi, dphi]))
    return rb.bending_at(Cst, phi, dphi, loads, ref.damped, method)


def assert_close(a, b):
    np.testing.assert_allclose(a, b, rtol=0, atol=RTOL * np.max(np.abs(b)))


def check_scene(sc: Scene, coefficients: str, seed: int, times=TIMES, states: int = 3):
    ref = ReducedSystem(sc, coefficients, "numpy")
    n = ref.n
    rng = np.random.default_rng(seed)
    for t in times:
        for _ in range(states):
            phi, dphi = rng.normal(size=n), rng.normal(size=n)  # ~1 rad, ~1 rad/s
            y = np.concatenate([phi, dphi])
            want_ddphi, want_gamma = ref.numpy_rhs(t, y)[n:], ref.recover_bending(t, y)
            for method in METHODS:
                ddphi, gamma = banded(ref, t, phi, dphi, method)
                assert_close(ddphi, want_ddphi)
                assert_close(gamma, want_gamma)


@pytest.mark.parametrize("coefficients", ["printed", "published"])
@pytest.mark.parametrize("n", [1, 2, 3, 5, 8, 16, 33, 64])
@pytest.mark.parametrize("damped", [True, False])
@pytest.mark.parametrize("loaded", [True, False])
def test_matches_dense_reference(coefficients, n, damped, loaded):
    sc = make_scene(n, damped, loaded)
    assert ReducedSystem(sc, coefficients, "numpy").damped == damped
    check_scene(sc, coefficients, seed=10 * n + damped)


@pytest.mark.parametrize("coefficients", ["printed", "published"])
@pytest.mark.parametrize("n", [1, 2, 5, 16, 33])
@pytest.mark.parametrize("which", ["some", "all"])
def test_free_hinges_and_massless_nodes(coefficients, n, which):
    """kappa = 0 on some (or all) hinges, mu = 0 on some nodes (and at the tip)."""
    rng = np.random.default_rng(n)
    kappa = rng.uniform(0, 200, n)
    if which == "all":
        kappa[:] = 0.0
    else:
        kappa[rng.random(n) < 0.5] = 0.0
        kappa[0] = 0.0
    mu = rng.uniform(0, 3, n)
    mu[rng.random(n) < 0.5] = 0.0
    mu[-1] = 0.0
    check_scene(make_scene(n, True, True, seed=1, kappa=kappa, mu=mu), coefficients, seed=n)


@pytest.mark.parametrize("coefficients", ["printed", "published"])
def test_undamped_flag_ignores_nu(coefficients):
    """damped=False drops C even when nu > 0 (same contract as the dense kernels)."""
    sc = make_scene(6, True, True)
    ref = ReducedSystem(sc, coefficients, "numpy")
    ref.damped = False
    rng = np.random.default_rng(3)
    phi, dphi = rng.normal(size=6), rng.normal(size=6)
    for method in METHODS:
        ddphi, gamma = banded(ref, 0.3, phi, dphi, method)
        assert_close(ddphi, ref.numpy_rhs(0.3, np.concatenate([phi, dphi]))[6:])
        assert_close(gamma, ref.recover_bending(0.3, np.concatenate([phi, dphi])))


def refined_solution(ref: ReducedSystem, t, phi, dphi):
    """The unreduced (phi'', gamma) system solved densely with iterative refinement (residuals
    in long double): a reference that does not suffer from forming M_r."""
    n, cc = ref.n, ref.cc
    ckj, skj = angle_differences(phi)
    M = assemble_mass(cc, ckj)
    h_p, h_g = convective_terms(cc, skj, dphi)
    K, C = ref.K, ref.C if ref.damped else 0.0 * ref.C
    p, g = slice(0, n), slice(n, 3 * n)
    Q = ref.generalized_force(t, phi)
    r = np.concatenate(
        [
            (0.0 if Q is None else Q) - h_p - C[p, p] @ dphi - K[p, p] @ phi,
            -(h_g + C[g, p] @ dphi + K[g, p] @ phi),
        ]
    )
    A = np.block([[M[p, p], K[p, g]], [M[g, p], K[g, g]]])
    x = np.linalg.solve(A, r)
    AL, rL = A.astype(np.longdouble), r.astype(np.longdouble)
    for _ in range(3):
        x = x + np.linalg.solve(A, (rL - AL @ x.astype(np.longdouble)).astype(float))
    return x[:n], x[n:]


@pytest.mark.parametrize("coefficients", ["printed", "published"])
def test_unreduced_form_is_the_reduced_model(coefficients):
    """The system the banded solve is built on (phi rows M_pp x + K_pg gamma = r_p, bending
    rows M_gp x + B gamma = r_g) has the reduced model's phi'' and gamma as its solution."""
    sc = make_scene(7, True, True)
    ref = ReducedSystem(sc, coefficients, "numpy")
    rng = np.random.default_rng(5)
    phi, dphi = rng.normal(size=7), rng.normal(size=7)
    y = np.concatenate([phi, dphi])
    x, gamma = refined_solution(ref, 0.3, phi, dphi)
    assert_close(x, ref.numpy_rhs(0.3, y)[7:])
    assert_close(gamma, ref.recover_bending(0.3, y))


@pytest.mark.parametrize("coefficients", ["printed", "published"])
def test_stiff_hinges_and_wide_parameters(coefficients):
    """Near-fixed hinges (kappa = 1e9) and parameters over decades: the banded solve stays at
    round-off of the (refined) unreduced solution, where the dense M_r route loses digits."""
    n = 40
    rng = np.random.default_rng(11)
    chain = Chain(
        l=10 ** rng.uniform(-1, 0.7, n),
        m=10 ** rng.uniform(-0.5, 1.5, n),
        EI=10 ** rng.uniform(2, 7, n),
        mu=np.where(rng.random(n) < 0.5, 0.0, 10 ** rng.uniform(-1, 1, n)),
        kappa=np.where(rng.random(n) < 0.3, 1e9, rng.uniform(0, 200, n)),
        nu=rng.uniform(0, 0.5, n),
    )
    sc = Scene(chain=chain, loads=(pulse(n),), t_end=2.0)
    ref = ReducedSystem(sc, coefficients, "numpy")
    for _ in range(3):
        phi, dphi = rng.normal(size=n), rng.normal(size=n)
        x, g = refined_solution(ref, 0.3, phi, dphi)
        for method in METHODS:
            ddphi, gamma = banded(ref, 0.3, phi, dphi, method)
            np.testing.assert_allclose(ddphi, x, rtol=0, atol=1e-10 * np.max(np.abs(x)))
            np.testing.assert_allclose(gamma, g, rtol=0, atol=1e-10 * np.max(np.abs(g)))


@pytest.mark.parametrize("coefficients", ["printed", "published"])
def test_constants_without_chain_constants(coefficients):
    """banded_constants(None, chain, variant) (O(n) memory) equals the one built from cc."""
    sc = make_scene(9, True, False)
    a = rb.banded_constants(chain_constants(sc.chain, coefficients), sc.chain)
    b = rb.banded_constants(None, sc.chain, coefficients)
    np.testing.assert_allclose(a, b, rtol=1e-15, atol=0)
    with pytest.raises(ValueError):
        rb.banded_constants(None, sc.chain, "other")


def test_accel_wrapper_and_band_structure():
    """reduced_accel writes reduced_solve's phi'' (the sweep: METHOD_AUTO with a
    regular system); every coefficient of the assembled
    matrix lies inside the declared band (KL, KU); scales are powers of two."""
    n = 12
    sc = make_scene(n, True, True)
    ref = ReducedSystem(sc, "printed", "numpy")
    Cst = rb.banded_constants(ref.cc, sc.chain)
    rng = np.random.default_rng(2)
    phi, dphi = rng.normal(size=n), rng.normal(size=n)
    SX, SY = ref.loads.suffix_sums(0.3)
    out = np.empty(n)
    rb.reduced_accel(Cst, np.concatenate([phi, dphi]), (True, SX, SY, NO_TQ), True, out)
    ddphi, _ = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_SWEEP)
    np.testing.assert_array_equal(out, ddphi)
    assert_close(out, ref.numpy_rhs(0.3, np.concatenate([phi, dphi]))[n:])
    scales = Cst[lu.C_RSCALE :]
    np.testing.assert_array_equal(np.exp2(np.round(np.log2(scales))), scales)
    T = lu.band_magnitudes(Cst)  # (7n, W), row i holds columns i-KL .. i+KL+KU
    assert not np.any(T[:, lu.KL + lu.KU + 1 :]), "the pivoting fill columns must start empty"
    for i in range(lu.NB * n):
        cols = i - lu.KL + np.flatnonzero(T[i])
        assert cols.min() >= 0 and cols.max() < lu.NB * n


@pytest.mark.parametrize("method", [rb.METHOD_AUTO, rb.METHOD_SWEEP, rb.METHOD_BAND])
@pytest.mark.parametrize("n", [1, 2, 9])
def test_work_array_variant(n, method):
    """reduced_solve_work gives reduced_solve's result bit for bit, whatever the work array
    held before (here NaN, and a second call reusing it)."""
    sc = make_scene(n, True, True)
    Cst = rb.banded_constants(None, sc.chain, "published")
    rng = np.random.default_rng(4)
    loads = (True, rng.normal(size=n), rng.normal(size=n), NO_TQ)
    work = np.full(
        (rb.work_size(n) if method == rb.METHOD_BAND else rb.sweep_work_size(n)) + 3, np.nan
    )
    for _ in range(2):
        y = np.concatenate([rng.normal(size=n), rng.normal(size=n)])
        a = np.empty(n), np.empty(2 * n)
        b = np.empty(n), np.empty(2 * n)
        assert rb.reduced_solve_work(Cst, y, loads, True, a, np.empty(rb.work_size(n)), method)
        assert rb.reduced_solve_work(Cst, y, loads, True, b, work, method)
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[1], b[1])
        if method == rb.METHOD_AUTO:
            assert rb.reduced_solve(Cst, y, loads, True, b)
            np.testing.assert_array_equal(a[0], b[0])
            np.testing.assert_array_equal(a[1], b[1])


@pytest.mark.parametrize("coefficients", ["printed", "published"])
def test_sweep_and_band_agree_on_a_long_chain(coefficients):
    """The two O(n) methods are independent eliminations: they agree at n = 3000, where the
    dense reference would be slow."""
    n = 3000
    rng = np.random.default_rng(8)
    chain = Chain(
        l=rng.uniform(0.5, 2.5, n),
        m=rng.uniform(1, 4, n),
        EI=rng.uniform(1e3, 1e5, n),
        mu=rng.uniform(0, 3, n),
        kappa=np.where(rng.random(n) < 0.2, 0.0, 100.0),
        nu=0.05,
    )
    Cst = rb.banded_constants(None, chain, coefficients)
    phi, dphi = rng.normal(size=n), rng.normal(size=n)
    SX, SY = np.cumsum(rng.normal(size=n)[::-1])[::-1], np.cumsum(rng.normal(size=n)[::-1])[::-1]
    a = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_SWEEP)
    b = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_BAND)
    for u, v in zip(a, b):
        np.testing.assert_allclose(u, v, rtol=0, atol=1e-9 * np.max(np.abs(v)))


def band_residual(Cst, phi, dphi, SX, SY, ddphi, gamma):
    """Componentwise backward error max_i |b - A u|_i / (|A| |u| + |b|)_i of (phi'', gamma),
    completed by its prefix/suffix sums, in the unscaled 7n x 7n banded system (residual in
    long double)."""
    n = phi.size
    N = lu.NB * n
    c, s = np.cos(phi), np.sin(phi)
    f = np.empty((3, n))
    loads = (True, SX, SY, NO_TQ)
    rb.reduced_forces(Cst, np.concatenate([phi, dphi]), (c, s), loads, True, f)
    unscaled = Cst.copy()
    unscaled[lu.C_RSCALE :] = 1.0
    A = np.empty((N, lu.W))
    for k in range(n):
        lu._fill_rod(unscaled, k, c, s, A, -1)
    i = lu.NB * np.arange(n)
    b = np.zeros(N)
    b[i + lu.E_PHI], b[i + lu.E_AL], b[i + lu.E_BE] = f
    l, M = Cst[rb.V_L], Cst[rb.V_OUTER]
    u = np.zeros(N)
    u[i + lu.U_X], u[i + lu.U_A], u[i + lu.U_B] = ddphi, gamma[:n], gamma[n:]
    for e, u_p, u_s in ((c, lu.U_PX, lu.U_SX), (s, lu.U_PY, lu.U_SY)):
        u[i + u_p] = np.concatenate([[0.0], np.cumsum(l * e * ddphi)[:-1]])
        u[i + u_s] = np.cumsum((M * l * e * ddphi)[::-1])[::-1]
    r = b.astype(np.longdouble)
    size = np.abs(b)
    for o in range(lu.W):
        cols = np.arange(N) - lu.KL + o
        rows = np.flatnonzero((cols >= 0) & (cols < N))
        r[rows] -= A[rows, o].astype(np.longdouble) * u[cols[rows]].astype(np.longdouble)
        size[rows] += np.abs(A[rows, o] * u[cols[rows]])
    live = size > 0
    return float(np.max(np.abs(r[live]).astype(float) / size[live]))


def test_backward_error_on_a_long_chain():
    """The sweep solves the unreduced system to a componentwise backward error of round-off at
    n = 20000; the banded LU is stable too, but its error grows with n (pivot growth along
    the running sums), which is why the sweep is the default."""
    n = 20000
    rng = np.random.default_rng(12)
    chain = Chain(
        l=rng.uniform(0.5, 2.5, n),
        m=rng.uniform(1, 4, n),
        EI=rng.uniform(1e3, 1e5, n),
        mu=rng.uniform(0, 3, n),
        kappa=rng.uniform(0, 200, n),
        nu=rng.uniform(0.01, 0.5, n),
    )
    Cst = rb.banded_constants(None, chain, "printed")
    phi, dphi = rng.normal(size=n), rng.normal(size=n)
    SX = np.cumsum(rng.normal(size=n)[::-1])[::-1] * 100.0
    SY = np.cumsum(rng.normal(size=n)[::-1])[::-1] * 100.0
    sweep = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_SWEEP)
    band = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_BAND)
    assert band_residual(Cst, phi, dphi, SX, SY, *sweep) < 1e-13
    assert band_residual(Cst, phi, dphi, SX, SY, *band) < 1e-8
