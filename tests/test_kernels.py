"""The compiled (numba) kernels against the straightforward numpy right-hand sides, the load
table against LoadSet, and the analytic Jacobians against central differences."""

import math

import numpy as np
import pytest

from rodval import paper_scene
from rodval.core.load_table import load_sums, load_table
from rodval.core.loads import LoadSet, NodalForce, constant, pulse
from rodval.core.scene import Chain, Scene
from rodval.models.presets.full import FullSystem
from rodval.models.presets.reduced import ReducedSystem

SYSTEMS = {"full": (FullSystem, 6), "reduced": (ReducedSystem, 2)}


def scene(n: int, damped: bool, loaded: bool) -> Scene:
    """A non-uniform chain (so that no symmetry hides an index error)."""
    rng = np.random.default_rng(n)
    chain = Chain(
        l=rng.uniform(0.5, 2.5, n),
        m=rng.uniform(1, 4, n),
        EI=rng.uniform(1e3, 1e5, n),
        mu=rng.uniform(0, 3, n),
        kappa=rng.uniform(0, 200, n),
        nu=rng.uniform(0.01, 0.5, n) if damped else 0.0,
    )
    loads = (pulse(n), constant(1, X=30.0, Y=-20.0, t_on=0.2)) if loaded else ()
    return Scene(chain=chain, loads=loads, t_end=2.0)


@pytest.mark.parametrize("model", SYSTEMS)
@pytest.mark.parametrize("coefficients", ["printed", "published"])
@pytest.mark.parametrize("n", [1, 2, 5, 8])
@pytest.mark.parametrize("damped", [True, False])
@pytest.mark.parametrize("loaded", [True, False])
def test_numba_rhs_matches_numpy(model, coefficients, n, damped, loaded):
    cls, width = SYSTEMS[model]
    sc = scene(n, damped, loaded)
    fast, ref = cls(sc, coefficients, "numba"), cls(sc, coefficients, "numpy")
    assert fast.damped == damped
    rng = np.random.default_rng(100 * n + damped)
    for t in (0.3, 0.5, 1.7):  # inside both supports, at a kink, past the pulse
        for _ in range(5):
            y = rng.normal(scale=1.5, size=width * n)
            a, b = fast.rhs(t, y), ref.rhs(t, y)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-11 * np.max(np.abs(b)))


@pytest.mark.parametrize("coefficients", ["printed", "published"])
def test_structured_solve_at_large_n(coefficients):
    """The O(n) Schur-complement solve stays accurate for a long chain."""
    sc = paper_scene(64)
    fast, ref = FullSystem(sc, coefficients, "numba"), FullSystem(sc, coefficients, "numpy")
    y = np.random.default_rng(7).normal(size=6 * 64)
    b = ref.rhs(0.4, y)
    np.testing.assert_allclose(fast.rhs(0.4, y), b, rtol=0, atol=1e-10 * np.max(np.abs(b)))


def test_load_table_matches_loadset():
    loads = LoadSet(
        (
            pulse(3, Xbar=-150.0, Ybar=1200.0, T=1.0),
            pulse(1, Xbar=10.0, Ybar=5.0, T=0.4),
            constant(2, X=7.0, Y=-3.0, t_on=0.25, t_off=1.2),
        ),
        4,
    )
    table = load_table(loads.loads)
    for t in np.concatenate([np.linspace(0, 2, 81), [0.2, 0.5, 1.0, 1.2]]):
        SX, SY = np.full(4, np.nan), np.full(4, np.nan)
        active = load_sums(table, t, SX, SY)
        ref = loads.suffix_sums(t)
        assert active == (ref is not None)
        if ref is not None:
            np.testing.assert_allclose(SX, ref[0], rtol=1e-15, atol=1e-12)
            np.testing.assert_allclose(SY, ref[1], rtol=1e-15, atol=1e-12)


def test_callable_loads_have_no_table():
    loads = LoadSet((NodalForce(1, fx=math.sin),), 2)
    assert load_table(loads.loads) is None


@pytest.mark.parametrize("model", SYSTEMS)
@pytest.mark.parametrize("coefficients", ["printed", "published"])
@pytest.mark.parametrize("damped", [True, False])
def test_analytic_jacobian_matches_differences(model, coefficients, damped):
    cls, width = SYSTEMS[model]
    n = 5
    system = cls(scene(n, damped, loaded=True), coefficients, "numpy")
    y = np.random.default_rng(3).normal(scale=0.8, size=width * n)
    t = 0.3
    J = system.jacobian(t, y)
    h = 1e-6
    Jd = np.column_stack(
        [(system.rhs(t, y + h * e) - system.rhs(t, y - h * e)) / (2 * h) for e in np.eye(y.size)]
    )
    np.testing.assert_allclose(J, Jd, rtol=0, atol=1e-7 * np.max(np.abs(Jd)))
    # and the Jacobian is not just the trivial [[0, I], [0, 0]] part
    assert np.max(np.abs(J[width * n // 2 :])) > 1.0


def test_kernel_option_is_validated():
    with pytest.raises(ValueError, match="kernel must be one of"):
        FullSystem(paper_scene(2), "printed", "fortran")
