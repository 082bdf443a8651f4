"""The reduced model's O(n) set-up and sweep at scale (rodval.models.bending.reduced_banded,
reduced_band_lu): the sweep's quiet root part (rods at rest skipped, their solution exactly
0), the banded LU's equilibration written on its first use, and a paper-chain run equal to
the values the code gave before these changes (commit f5a97d9)."""

import numpy as np

from rodval.core.scene import paper_scene
from rodval.models.bending import reduced_band_lu as lu
from rodval.models.bending import reduced_banded as rb
from rodval.models.presets.reduced import ReducedSystem
from rodval.models.registry import simulate

#: the kernels' "no hinge moments" (``Tq`` of length 0)
NO_TQ = np.zeros(0)


def quiet_state(n: int, moving: int, seed: int = 3, kernel: str = "numpy"):
    """A paper-chain state with the last ``moving`` rods bent and turning and the others
    exactly at rest (phi = phi' = 0), the pulse's load sums at t = 0.3 s; the system on
    ``kernel`` (numpy: with the dense reference, O(n^2) to build)."""
    rng = np.random.default_rng(seed)
    phi, dphi = np.zeros(n), np.zeros(n)
    phi[n - moving :] = rng.normal(scale=0.3, size=moving)
    dphi[n - moving :] = rng.normal(scale=0.5, size=moving)
    system = ReducedSystem(paper_scene(n), kernel=kernel)
    SX, SY = system.loads.suffix_sums(0.3)
    return system, phi, dphi, np.ascontiguousarray(SX), np.ascontiguousarray(SY)


def test_the_sweep_skips_the_rods_at_rest_and_matches_the_dense_reduced_model():
    """n = 400, 20 rods moving: phi'' and gamma agree with the dense elimination (numpy
    kernel) to 1e-11 of their largest value (the dense solve of a 400 x 400 system carries
    ~1e-13), the rods at rest get exactly 0, and the tip-to-root pass never wrote their
    T_k (left NaN): it stopped where the rest of the chain is quiet."""
    n, moving = 400, 20
    system, phi, dphi, SX, SY = quiet_state(n, moving)
    Cst = rb.banded_constants(system.cc, system.chain)
    c, s = np.cos(phi), np.sin(phi)
    y = np.concatenate([phi, dphi])
    f = np.empty((3, n))
    rb.reduced_forces(Cst, y, (c, s), (True, SX, SY, NO_TQ), system.damped, f)
    T = np.full((n, 3, 4), np.nan)
    ddphi, gamma = np.empty(n), np.empty(2 * n)
    assert rb.solve_sweep(Cst, c, s, f, T, (ddphi, gamma))
    ref = system.numpy_rhs(0.3, y)[n:]
    np.testing.assert_allclose(ddphi, ref, rtol=0, atol=1e-11 * np.max(np.abs(ref)))
    ref_gamma = system.recover_bending(0.3, y)
    np.testing.assert_allclose(gamma, ref_gamma, rtol=0, atol=1e-11 * np.max(np.abs(ref_gamma)))
    skipped = np.flatnonzero(np.isnan(T[:, 0, 0]))
    assert skipped.size > n // 2, "the tip-to-root pass went on through the quiet rods"
    assert np.array_equal(skipped, np.arange(skipped.size)), "only a root part is skipped"
    assert not np.any(ddphi[skipped]) and not np.any(gamma[skipped])
    assert not np.any(gamma[n + skipped])


def test_the_quiet_part_and_the_banded_lu_agree_at_n_3000():
    """The sweep with its quiet root part against the banded LU (an independent O(n)
    elimination, no skipping): the same phi'' and gamma to 1e-9 of the largest (the LU's
    pivot growth along the running sums, tests/test_reduced_banded.py)."""
    n = 3000
    system, phi, dphi, SX, SY = quiet_state(n, 40, kernel="numba")  # no dense reference here
    Cst = rb.banded_constants(system.cc, system.chain)
    sweep = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_SWEEP)
    band = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_BAND)
    for u, v in zip(sweep, band):
        np.testing.assert_allclose(u, v, rtol=0, atol=1e-9 * np.max(np.abs(v)))


def dense_ruiz_scales(T: np.ndarray, sweeps: int) -> tuple[np.ndarray, np.ndarray]:
    """Ruiz equilibration of the band magnitudes T (7n x W) as a dense matrix, numpy, each
    scale rounded to the nearest power of two: the rule ``equilibrate`` implements."""
    N = T.shape[0]
    A = np.zeros((N, N + lu.W))
    for o in range(lu.W):
        A[np.arange(N), np.arange(N) - lu.KL + o + lu.KL] = T[:, o]
    A = A[:, lu.KL : lu.KL + N]
    rs, cs = np.ones(N), np.ones(N)
    for _ in range(sweeps):
        r = np.sqrt(A.max(axis=1))
        c = np.sqrt(A.max(axis=0))
        rs /= r
        cs /= c
        A = A / r[:, None] / c[None, :]
    return np.exp2(np.round(np.log2(rs))), np.exp2(np.round(np.log2(cs)))


def test_the_equilibration_is_written_on_the_banded_lus_first_use():
    """banded_constants leaves the scales at 1 (flag 0: the sweep does not read them); the
    first banded LU solve writes the Ruiz scales (flag 1), equal to a dense numpy Ruiz of the
    same magnitudes, and the solve with them agrees with the sweep."""
    n = 40
    system, phi, dphi, SX, SY = quiet_state(n, n)
    Cst = rb.banded_constants(system.cc, system.chain)
    assert not np.any(Cst[lu.C_EQUIL]) and np.all(Cst[lu.C_RSCALE :] == 1.0)
    rows, cols = dense_ruiz_scales(lu.band_magnitudes(Cst), lu.RUIZ_SWEEPS)
    band = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_BAND)
    assert np.all(Cst[lu.C_EQUIL] == 1.0)
    np.testing.assert_array_equal(Cst[lu.C_RSCALE : lu.C_RSCALE + lu.NB].T.ravel(), rows)
    np.testing.assert_array_equal(Cst[lu.C_CSCALE : lu.C_CSCALE + lu.NB].T.ravel(), cols)
    assert not np.all(rows == 1.0) and not np.all(cols == 1.0)
    sweep = rb.bending_at(Cst, phi, dphi, (True, SX, SY, NO_TQ), True, rb.METHOD_SWEEP)
    for u, v in zip(sweep, band):
        np.testing.assert_allclose(u, v, rtol=0, atol=1e-11 * np.max(np.abs(v)))


#: phi (rad) of the paper chain, n = 1000, pulse at the last node, compiled DOP853 at rtol
#: 1e-6, atol 1e-8, output times 0, 0.5, 1, 1.5, 2 s: rods 999, 990, 960, 930 at t = 1 s and
#: t = 2 s, as commit f5a97d9 (before the quiet part and the fused forces) gave them.
REFERENCE = {
    2: (
        1.4853562923077077,
        0.014395764556604941,
        -4.1732425176623633e-38,
        -2.8771228048329576e-138,
    ),
    4: (1.917051834240701, 1.5933723550620156, -2.8272758294377733e-15, -4.933758573215451e-96),
}


def test_a_paper_chain_of_1000_rods_gives_the_values_of_before():
    """Same steps, same phi: the changes reorder no arithmetic (the quiet rods' solution is 0
    whatever their T_k; the fused forces add in the old kernels' order), so phi equals the
    old run's to 1e-12 relative (bit for bit when measured), down to the rods whose phi is
    1e-138; the 883 rods nearest the root stay exactly at 0."""
    times = np.linspace(0.0, 2.0, 5)
    traj = simulate(
        paper_scene(1000, times=times, outputs=("phi",)), "reduced", rtol=1e-6, atol=1e-8
    )
    phi = np.asarray(traj["phi"])
    for i, values in REFERENCE.items():
        np.testing.assert_allclose(phi[i, [999, 990, 960, 930]], values, rtol=1e-12, atol=0)
    assert not np.any(phi[-1, :883])
