"""Modal analysis: closed forms, the rigid-chain limit, the published-matrix spectrum against
mpmath, exudyn's modes (Ritz bounds, convergence, the loaded equilibrium), pairing by MAC, and
the ``rodval modes`` command."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodval import Chain, Scene, constant, paper_scene
from rodval.analysis.modes import compare_modes, pair_modes
from rodval.models.observation.linear_modes import mac, modes, natural_frequencies
from rodval.models.observation.statics import static_equilibrium, static_residual

L, M_LEN, EI = 2.0, 3.0, 1e5
EB_SCALE = math.sqrt(EI / (M_LEN * L**4))
CLAMPED_BL = np.array([1.8751040687, 4.6940911330, 7.8547574382])
PINNED_BL = np.array([3.9266023120, 7.0685827897, 10.2101761242])


# -- native closed forms and limits --------------------------------------------------------------
def test_one_rod_full_model_is_a_ritz_upper_bound_of_euler_bernoulli():
    """Clamped-free (hinge-0 spring 1e10 N m/rad) and pinned-free rods: the full model's two
    bending frequencies lie above Euler-Bernoulli's (beta l)^2 sqrt(EI / (m l^4)), the first
    within 0.5 % (clamped: 0.48 %) and 15 % (pinned: 13.8 %; the free-free-like bending of a
    pinned rod is poorly fit by one cubic shape)."""
    clamped = natural_frequencies(Chain.uniform(1, mu=0.0, kappa=1e10, nu=0.0))
    pinned = natural_frequencies(Chain.uniform(1, mu=0.0, kappa=0.0, nu=0.0))
    eb_c, eb_p = CLAMPED_BL**2 * EB_SCALE, PINNED_BL**2 * EB_SCALE
    assert np.all(clamped[:2] >= eb_c[:2])
    assert clamped[0] / eb_c[0] - 1 < 5e-3
    assert pinned[0] == 0.0
    assert np.all(pinned[1:3] >= eb_p[:2])
    assert pinned[1] / eb_p[0] - 1 < 0.15


def _rigid_chain_matrices(l, m, mu, kappa, phi0):
    """Independent Lagrangian of n rigid uniform rods with tip point masses and hinge springs on
    the relative angles, linearized about phi0: T = 1/2 sum_k [int_0^l_k m_k |v(s)|^2 ds +
    mu_k |v_k|^2] with v(s) = sum_{j<k} l_j n_j phi_j' + s n_k phi_k' (n_j the unit normal of
    rod j), integrated by Gauss-Legendre (exact for the quadratic integrand);
    V = 1/2 sum kappa_k theta_k^2, theta_0 = phi_1, theta_k = phi_{k+1} - phi_k."""
    n = len(l)
    nrm = np.stack([-np.sin(phi0), np.cos(phi0)], 1)  # (n, 2)
    x, w = np.polynomial.legendre.leggauss(4)
    M = np.zeros((n, n))
    for k in range(n):
        for s, wt in zip(0.5 * l[k] * (x + 1), 0.5 * l[k] * w):
            J = np.zeros((2, n))
            J[:, :k] = (l[:k, None] * nrm[:k]).T
            J[:, k] = s * nrm[k]
            M += m[k] * wt * J.T @ J
        J = np.zeros((2, n))
        J[:, : k + 1] = (l[: k + 1, None] * nrm[: k + 1]).T
        M += mu[k] * J.T @ J
    R = np.eye(n) - np.eye(n, k=-1)
    return M, R.T @ np.diag(kappa) @ R


def test_rigid_chain_n3_reduced_model_matches_independent_lagrangian():
    """n = 3 rigid rods (unequal l, m, mu, kappa) about a bent configuration: reduced-model
    frequencies at EI = 1e12 N m^2 against the independent rigid-chain M, K to 1e-8 (relative).
    The reduced model's flexibility enters through K_r = K_pp - K_pg B^-1 K_gp and M_r, both
    O(kappa l / EI) = O(1e-10) away from the rigid chain; measured gap <= 6e-11."""
    l, m = np.array([1.5, 2.0, 2.5]), np.array([3.0, 2.0, 4.0])
    mu, kappa = np.array([1.0, 2.0, 3.0]), np.array([100.0, 50.0, 80.0])
    phi0 = np.array([0.3, -0.2, 0.5])
    chain = Chain(l=l, m=m, EI=1e12, mu=mu, kappa=kappa, nu=0.0)
    M, K = _rigid_chain_matrices(l, m, mu, kappa, phi0)
    import scipy.linalg

    exact = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True))
    got = natural_frequencies(chain, "reduced", phi0=phi0)
    print("rigid chain n=3: exact", exact, "reduced", got, "rel", got / exact - 1)
    np.testing.assert_allclose(got, exact, rtol=1e-8)


def test_static_equilibrium_residual_and_rest_angle_argument():
    """Newton on K q - A^T(kappa rest) - [Q; 0; 0]: a tip load converges in a few iterations
    to round-off; hinge rest angles alone give D = rest exactly (no load, no bending)."""
    chain = Chain.uniform(3, nu=0.0)
    X, Y = np.zeros(3), np.array([0.0, 0.0, 30.0])
    SX, SY = np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1]
    eq = static_equilibrium(chain, SX, SY)
    assert eq.converged and eq.iterations < 20
    assert np.max(np.abs(static_residual(chain, eq.q, SX, SY))) < 1e-8
    rest = np.array([0.1, -0.2, 0.3])
    eq2 = static_equilibrium(chain, rest=rest)
    from rodval.models.assembly.paper_matrices import hinge_matrix

    np.testing.assert_allclose(hinge_matrix(3) @ eq2.q, rest, atol=1e-12)
    np.testing.assert_allclose(eq2.q[3:], 0.0, atol=1e-12)


def test_damping_ratios_match_modal_approximation():
    """Paper chain n = 8 (nu = 0.01): damping ratios from the quadratic eigenproblem agree with
    the light-damping estimate x^T C x / (2 omega x^T M x) to 1e-3 (relative)."""
    from rodval.models.observation.linear_modes import eigen, linear_system

    chain = Chain.uniform(8)
    M, C, K = linear_system(chain, "full")
    lam, X = eigen(K, M, chain, "full")
    m = modes(paper_scene(8), "full", count=10)
    approx = np.array(
        [X[:, i] @ C @ X[:, i] / (2 * math.sqrt(lam[i]) * X[:, i] @ M @ X[:, i]) for i in range(10)]
    )
    np.testing.assert_allclose(m.damping, approx, rtol=1e-3)
    assert np.all(m.damping > 0)


# -- the published (non-symmetric) mass matrix -----------------------------------------------------
#: mpmath reference for Chain.uniform(64), "full", coefficients="published": all 192 omega
#: (rad/s, ascending) from mpmath.eig of M^-1 K formed in 40 digits (mp.dps = 40; 958 s, the
#: script in docs/modes.md). Largest imaginary part of the 192 eigenvalues: 6e-31 (of
#: eigenvalues up to 6e6): the spectrum is real.
MP64_OMEGA = np.array(
    [
        0.001400026637021416,
        0.008773785956471328,
        0.02456355262255048,
        0.04812186854289404,
        0.07951711556491925,
        0.1187214895737587,
        0.1657068400377239,
        0.2204379919576047,
        0.2828729338407899,
        0.352962562915035,
        0.4306504178369148,
        0.5158723738880685,
        0.6085563005857791,
        0.7086216802322051,
        0.8159791859448736,
        0.9305302176917679,
        1.052166394881407,
        1.180769004137518,
        1.316208401030434,
        1.458343364755761,
        1.607020405059186,
        1.762073021120126,
        1.923320912643395,
        2.090569144085526,
        2.263607263780469,
        2.442208380748353,
        2.626128203191317,
        2.815104044122059,
        3.008853801252009,
        3.207074920202405,
        3.409443352303938,
        3.615612520723424,
        3.82521231139456,
        4.037848108217955,
        4.253099895202168,
        4.470521451592997,
        4.68963966951186,
        4.909954027099428,
        5.130936253513739,
        5.352030225208046,
        5.572652135527144,
        5.792190981595414,
        6.010009413482247,
        6.225444990456537,
        6.437811887506594,
        6.646403091933028,
        6.850493124468715,
        7.049341311834022,
        7.242195627756733,
        7.428297107229849,
        7.606884824223284,
        7.777201406429676,
        7.938499042296233,
        8.090045916131546,
        8.231132987205298,
        8.36108100935542,
        8.47924766967124,
        8.585034709384219,
        8.677894878217611,
        8.757338566090091,
        8.822939954043036,
        8.874342530136653,
        8.911263826104475,
        8.93349924668893,
        500.0831221068705,
        518.8972914805585,
        519.3477554606693,
        520.0954233740185,
        521.135809902869,
        522.4629326691846,
        524.069520177299,
        525.9471965406346,
        528.0866283607558,
        530.4776340019291,
        533.1092637059764,
        535.9698612230101,
        539.0471163541713,
        542.3281152331253,
        545.7993926276631,
        549.4469885491571,
        553.2565100886408,
        557.2131985385353,
        561.3020013538359,
        565.5076482237904,
        569.8147303708228,
        574.207782108207,
        578.6713636379401,
        583.190144038601,
        587.7489833735461,
        592.3330128423064,
        596.9277119054005,
        601.5189813384551,
        606.0932112195877,
        610.6373429254244,
        615.1389243101235,
        619.5861573594524,
        623.9679377642378,
        628.2738859979805,
        632.4943697004877,
        636.6205172529984,
        640.6442228037422,
        644.5581427810857,
        648.3556848337928,
        652.0309889312144,
        655.5789026990195,
        658.9949499014991,
        662.2752946717679,
        665.4167031597257,
        668.4164934694429,
        671.272510032739,
        673.9830280685669,
        676.5468132238274,
        678.9628548744261,
        681.2307381555536,
        683.3498429641955,
        685.3205879255549,
        687.1423068125691,
        688.8163995252037,
        690.3416587807935,
        691.7206180472226,
        692.951213196341,
        694.0369543888427,
        694.9751285500564,
        695.7694870547592,
        696.4174801427113,
        696.9219975609459,
        697.2815332253824,
        697.497434621034,
        2291.325294698574,
        2291.57971575355,
        2292.087357216957,
        2292.84689435357,
        2293.856052560787,
        2295.11177097308,
        2296.610199672568,
        2298.346688625214,
        2300.315775325943,
        2302.511172974609,
        2304.925760555866,
        2307.551576201704,
        2310.379815267312,
        2313.400834579451,
        2316.604164300646,
        2319.978528781857,
        2323.511877643633,
        2327.191428126604,
        2331.003719485211,
        2334.934679866019,
        2338.969705720456,
        2343.093753362805,
        2347.291441813831,
        2351.547165589224,
        2355.845215624211,
        2360.169906097603,
        2364.505704556883,
        2368.837362475724,
        2373.150043217521,
        2377.429444348189,
        2381.66191134572,
        2385.834539991257,
        2389.935265086029,
        2393.952933601108,
        2397.877360906333,
        2401.699369309787,
        2405.410808736353,
        2409.004559950262,
        2412.474521252263,
        2415.815580032734,
        2419.023570919812,
        2422.095222516595,
        2425.028094871029,
        2427.820509870663,
        2430.471476712142,
        2432.980614476305,
        2435.3480736607,
        2437.574458299939,
        2439.660750057549,
        2441.608235416532,
        2443.418436842922,
        2445.093048557885,
        2446.633877337107,
        2448.042788566558,
        2449.321657623949,
        2450.472326526118,
        2451.496565683461,
        2452.396040531389,
        2453.172282763174,
        2453.826665865196,
        2454.360384651554,
        2454.774438506965,
        2455.069618071939,
        2455.246495139784,
    ]
)


def _mp_frequencies(M, K, dps=40):
    mpmath = pytest.importorskip("mpmath")
    with mpmath.workdps(dps):
        A = mpmath.inverse(mpmath.matrix(M.tolist())) * mpmath.matrix(K.tolist())
        E = mpmath.eig(A, left=False, right=False)
        imag = max(abs(mpmath.im(e)) for e in E)
        re = np.array(sorted(float(mpmath.re(e)) for e in E))
    return np.sqrt(np.clip(re, 0, None)), float(imag)


def test_published_spectrum_against_mpmath_n10():
    """n = 10 (30 x 30): every frequency of the published full model agrees with mpmath's
    (40 digits) to 1e-7 relative."""
    from rodval.models.observation.linear_modes import linear_matrices

    chain = Chain.uniform(10)
    M, K = linear_matrices(chain, "full", coefficients="published")
    ref, imag = _mp_frequencies(M, K)
    assert imag < 1e-30
    got = natural_frequencies(chain, "full", coefficients="published")
    np.testing.assert_allclose(got, ref, rtol=1e-7)


def test_published_spectrum_n64_is_real_and_matches_mpmath():
    """n = 64 (192 x 192): scipy.linalg.eigvals(K, M) gives complex pairs (imaginary parts up
    to 0.8 % of the largest eigenvalue, printed); natural_frequencies returns 192 real
    frequencies, all within 2e-6 of the stored mpmath (40 digits) values (measured: max 6.1e-7
    at a near-double eigenvalue of the bending cluster, median 1.6e-14); its 64 hinge modes
    agree with the reduced model's to 1e-3 (measured 9e-5, the model difference)."""
    import scipy.linalg

    from rodval.models.observation.linear_modes import linear_matrices

    chain = Chain.uniform(64)
    M, K = linear_matrices(chain, "full", coefficients="published")
    naive = scipy.linalg.eigvals(K, M)  # complex here (LAPACK-dependent, not asserted)
    print("naive QZ: max |imag| / max |lam| =", np.max(np.abs(naive.imag)) / np.max(np.abs(naive)))
    got = natural_frequencies(chain, "full", coefficients="published")
    assert got.shape == (192,) and np.all(np.isfinite(got))
    rel = np.abs(got / MP64_OMEGA - 1)
    print("n = 64 vs mpmath: max rel", rel.max(), "median", np.median(rel))
    np.testing.assert_allclose(got, MP64_OMEGA, rtol=2e-6)
    # the rigid-body modes agree with the reduced model's (same chain, n x n problem)
    red = natural_frequencies(chain, "reduced", coefficients="published")
    np.testing.assert_allclose(got[:64], red, rtol=1e-3)


@pytest.mark.slow
def test_published_spectrum_against_mpmath_n32_all():
    """n = 32 (96 x 96, ~75 s in mpmath): all 96 frequencies to 1e-7."""
    from rodval.models.observation.linear_modes import linear_matrices

    chain = Chain.uniform(32)
    M, K = linear_matrices(chain, "full", coefficients="published")
    ref, imag = _mp_frequencies(M, K)
    assert imag < 1e-30
    np.testing.assert_allclose(
        natural_frequencies(chain, "full", coefficients="published"), ref, rtol=1e-7
    )


# -- exudyn ---------------------------------------------------------------------------------------
def _exudyn_modes():
    pytest.importorskip("exudyn")
    from reference_models.exudyn_modes import exudyn_modes

    return exudyn_modes


def test_mac_and_pairing_by_shape_not_index():
    a = modes(paper_scene(4), "full", count=6)
    assert mac(a.shape_vectors()[0], 3 * a.shape_vectors()[0]) == pytest.approx(1.0)
    # b: a's modes in reversed order -> pairing follows the shapes
    from rodval.analysis.modes import _head

    b = _head(a, 6)
    b.omega, b.dx, b.dy, b.hinge = (x[::-1] for x in (a.omega, a.dx, a.dy, a.hinge))
    p = pair_modes(a, b)
    assert p["mode_b"].tolist() == [6, 5, 4, 3, 2, 1]
    np.testing.assert_allclose(p["mac"], 1.0)
    np.testing.assert_allclose(p["rel_gap"], 0.0, atol=1e-14)


@pytest.mark.exudyn
def test_paper_chain_n8_three_models_side_by_side():
    """Paper chain n = 8, straight: first 10 modes of exudyn (8 elements per rod) with the
    paired full and reduced modes. Every pair has MAC >= 0.95 (measured >= 0.999). Modes 1-8
    (hinge modes, 0.078 to 8.5 rad/s): full within 2e-5 (measured <= 3.0e-6, the beam's
    discretization and axial stretch; both models' frequencies carry ~1e-8 or better, see
    docs/modes.md, so the gap is the models', not round-off), mode 1 within 2e-7 (measured
    1.3e-7; it was 5.7e-6 while exudyn's direct eigensolve lost its digits), reduced within
    2e-4 (measured <= 8.5e-5); modes 9-10 (the lowest of the rods' bending cluster, 452.4 and
    467.4 rad/s) are 11 % high in the full model (one cubic shape per rod), and the reduced
    model has no such modes."""
    exudyn_modes = _exudyn_modes()
    scene = paper_scene(8)
    got = {
        "full": modes(scene, "full"),
        "reduced": modes(scene, "reduced"),
        "exudyn": exudyn_modes(scene, elements=8),
    }
    table = compare_modes(scene, computed=got, count=10)
    print("\n" + table.to_string())
    assert len(table) == 10
    assert (table["mac_full"] >= 0.95).all()
    assert (table["mac_reduced"].iloc[:8] >= 0.95).all()
    assert table["mac_reduced"].iloc[8:].isna().all()
    assert (table["gap_full"].iloc[:8].abs() < 2e-5).all()
    assert abs(table["gap_full"].iloc[0]) < 2e-7
    assert (table["gap_reduced"].iloc[:8].abs() < 2e-4).all()
    assert table["gap_full"].iloc[8:].between(0.09, 0.13).all()
    # hinge-damper damping ratios (nu = 0.01): exudyn's complex eigenvalues vs the native
    # quadratic eigenproblem, modes 1-8 (3.9e-6 to 4.3e-4; measured gap <= 8.9e-6 relative)
    np.testing.assert_allclose(got["exudyn"].damping[:8], got["full"].damping[:8], rtol=1e-3)


def _ritz_check(chain, elements=(8, 16), nmodes=None):
    """Full model vs exudyn at two meshes: returns (full, exudyn fine, error estimate)."""
    exudyn_modes = _exudyn_modes()
    scene = Scene(chain=chain, t_end=1.0)
    full = natural_frequencies(chain)
    k = nmodes or full.size
    coarse, fine = (exudyn_modes(scene, elements=e).omega[:k] for e in elements)
    err = np.abs(coarse - fine)
    return full[:k], fine, err


@pytest.mark.exudyn
@pytest.mark.parametrize("kappa", [1e10, 0.0], ids=["clamped", "pinned"])
def test_ritz_bound_one_rod(kappa):
    """One rod (no tip mass): the i-th full-model frequency is >= the i-th of exudyn's
    16-element model, less its convergence error |omega(8) - omega(16)| (+1e-6 relative)."""
    full, ex, err = _ritz_check(Chain.uniform(1, mu=0.0, kappa=kappa, nu=0.0))
    print("one rod", kappa, full, ex, err)
    assert np.all(full >= ex - err - 1e-6 * ex)


@pytest.mark.exudyn
def test_ritz_bound_three_rod_chain():
    """Paper data, n = 3: all 9 full-model frequencies >= exudyn's (16 elements per rod) less
    its convergence error; the 6 bending ones strictly (by > 5 %)."""
    full, ex, err = _ritz_check(Chain.uniform(3, nu=0.0))
    print("3 rods", full, ex, err)
    assert np.all(full >= ex - err - 1e-6 * ex)
    assert np.all(full[3:] > 1.05 * ex[3:])


@pytest.mark.exudyn
def test_exudyn_converges_to_euler_bernoulli():
    """One clamped-free rod: exudyn's first three bending frequencies approach Euler-Bernoulli
    as the elements grow (2, 4, 8, 16 per rod): modes 2 and 3 monotonically, all three < 2e-4
    at 16 elements; pinned-free too. Measured, clamped: mode 1 4.7e-4, 2.3e-5, 7.9e-6, 9.9e-6
    (it levels off at ~1e-5: the clamp is a 1e10 N m/rad spring, and round-off of the stiff
    axial terms), mode 3 0.22, 7.7e-3, 6.0e-4, 3.0e-5."""
    exudyn_modes = _exudyn_modes()
    for kappa, bl in ((1e10, CLAMPED_BL), (0.0, PINNED_BL)):
        scene = Scene(chain=Chain.uniform(1, mu=0.0, kappa=kappa, nu=0.0), t_end=1.0)
        eb = bl**2 * EB_SCALE
        errs = []
        for e in (2, 4, 8, 16):
            w = exudyn_modes(scene, elements=e).omega
            w = w[w > 1.0][:3]  # drop the pinned rod's rigid rotation
            errs.append(np.abs(w / eb - 1))
        errs = np.array(errs)
        print("EB errors", kappa, errs)
        assert np.all(errs[-1] < errs[0])
        assert np.all(np.diff(errs[:, 1:], axis=0) < 0)
        assert np.all(errs[-1] < 2e-4)


@pytest.mark.exudyn
def test_tip_loaded_equilibrium_and_frequencies_native_vs_exudyn():
    """n = 3 paper rods, constant tip load Y = 30 N (root moment 180 N m against kappa = 100
    N m/rad: the chain bends by ~1.3 rad): native Newton and exudyn's static solver agree on the
    node positions within 1e-3 l (measured 1.4e-6 m, the axial stretch at EA = 1e8 N), and the
    first 3 frequencies about the
    equilibrium (load stiffness included natively, geometric stiffness in exudyn) within 1 %
    (measured full <= 6e-6, reduced <= 5e-5)."""
    exudyn_modes = _exudyn_modes()
    scene = Scene(chain=Chain.uniform(3, nu=0.0), loads=(constant(3, X=0.0, Y=30.0),), t_end=1.0)
    native = modes(scene, "full", about="equilibrium")
    red = modes(scene, "reduced", about="equilibrium")
    ex = exudyn_modes(scene, about="equilibrium", elements=4)
    eq = native.equilibrium
    print("native equilibrium: iterations", eq.iterations, "residual", eq.residual, "phi", eq.phi)
    assert eq.converged and eq.residual < 1e-8
    x, y = native.node_positions()
    gap = np.max(np.hypot(x - ex.info["node_positions"][:, 0], y - ex.info["node_positions"][:, 1]))
    print("node position gap (m)", gap)
    assert gap < 1e-3 * L
    assert eq.phi[-1] > 1.0  # really deflected
    table = compare_modes(scene, computed={"full": native, "reduced": red, "exudyn": ex}, count=3)
    print("\n" + table.to_string())
    assert (table[["gap_full", "gap_reduced"]].abs() < 0.01).all().all()
    assert (table[["mac_full", "mac_reduced"]] > 0.95).all().all()
    # the load stiffens: the unloaded chain's first frequency is lower
    assert native.omega[0] > modes(scene, "full").omega[0]


# -- CLI --------------------------------------------------------------------------------------------
def test_cli_modes_writes_files(tmp_path, capsys):
    from rodval.cli import main

    out = tmp_path / "m"
    assert main(["modes", "paper", "--model", "full", "--count", "4", "--out", str(out)]) == 0
    import pandas as pd

    f = pd.read_csv(out / "frequencies.csv")
    assert list(f.columns) == ["mode", "omega_rad_s", "f_hz", "damping_ratio"]
    assert len(f) == 4 and f["omega_rad_s"].iloc[0] == pytest.approx(0.0781421, rel=1e-5)
    m = pd.read_csv(out / "modes.csv")
    assert list(m.columns) == ["mode", "kind", "k", "value"]
    assert set(m["kind"]) == {"node_dx", "node_dy", "hinge"}
    assert (out / "modes.png").stat().st_size > 0
    assert "0.0781" in capsys.readouterr().out


def test_cli_modes_compare_writes_paired_table(tmp_path, capsys):
    """--compare pairs the other models' modes with --model's by MAC into compare.csv."""
    from rodval.cli import main

    out = tmp_path / "c"
    assert (
        main(
            [
                "modes",
                "paper",
                "--model",
                "reduced",
                "--count",
                "8",
                "--compare",
                "full",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    import pandas as pd

    t = pd.read_csv(out / "compare.csv")
    assert list(t.columns) == ["mode", "omega_reduced", "omega_full", "gap_full", "mac_full"]
    assert (t["mac_full"] > 0.999).all() and (t["gap_full"].abs() < 1e-4).all()
    assert "paired by MAC" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv",
    [
        ["modes", "paper", "--model", "nope", "--out", "x"],
        ["modes", "paper", "--count", "0", "--out", "x"],
        ["modes", "paper", "--about", "sideways", "--out", "x"],
        ["modes", "missing.toml", "--out", "x"],
        ["modes", "paper", "--compare", "full,bogus", "--out", "x"],
        ["modes", "paper", "--model", "exudyn", "--set", "elements=0", "--out", "x"],
    ],
)
def test_cli_modes_bad_input_one_line_exit_2(argv, tmp_path, capsys, monkeypatch):
    from rodval.cli import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        code = main(argv)
        raise SystemExit(code)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "error" in err
