"""Issue 39: the exudyn model's per-step Python made cheap (closed-form vectorized latch
crossing test, vectorized hinge angles, one state read a step, gathers instead of products in
the guard) gives the results of the code before the change.

The reference values were measured with the code before the change (commit of main before
issue 39, the latch crossing test by numpy.roots per latch per step), by

    PYTHONPATH=$PWD .venv/bin/python -c "from rodval import simulate;
        from benchmarks.exudyn_speed import paper, latch3_scene;
        tr = simulate(paper(), 'exudyn'); print(tr.values['phi'][[50, 100, 150, 200]][:, 1::2]);
        print([(e['label'], e['t']) for e in simulate(latch3_scene(), 'exudyn').events])"

(paper() is paper_scene(8); exudyn 1.13.6; the model's defaults: 2 elements per rod, step
2e-4 s)."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from rodval import paper_scene, simulate

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from exudyn_speed import latch3_scene  # noqa: E402

pytestmark = pytest.mark.exudyn

#: phi of rods 2, 4, 6, 8 (columns) at t = 0.5, 1, 1.5, 2 s (rows) of the paper example, before
PAPER_PHI_BEFORE = np.array(
    [
        [-8.850839618168e-04, -4.130157383206e-04, 2.046127693650e-01, 1.685333128721e00],
        [1.580749099140e-02, 1.702512422621e00, 1.472719563917e00, 1.485580178310e00],
        [1.552942018232e00, 1.922077005974e00, 1.785880327417e00, 1.674974522674e00],
        [3.249514722807e00, 2.657604980911e00, 1.242377012292e00, 2.566861989043e00],
    ]
)
#: lock times (s) of the latched 3-rod scene (benchmarks/exudyn_speed.latch3_scene), before
LATCH3_LOCKS_BEFORE = {"latch hinge 2": 0.3178366319430856, "latch hinge 1": 0.6982280523396831}


def _latches_module():
    pytest.importorskip("exudyn")
    from reference_models import exudyn_latches

    return exudyn_latches


def _roots_reference(g, dg, ddg, h):
    """The crossing test before the change: numpy.roots of the step's Taylor polynomial."""
    roots = np.roots([0.5 * ddg, dg, g]) if abs(ddg) > 0 or abs(dg) > 0 else np.array([])
    real = sorted(
        float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and 0 < r.real <= h
    )
    return real[0] if real else None


def test_closed_form_crossing_equals_numpy_roots():
    """20,000 random steps (g over 8 decades, linear and quadratic cases, roots inside and
    outside the step): the same step found, the root to 1e-12 h."""
    lat = _latches_module()
    rng = np.random.default_rng(7)
    N, h = 20000, 2e-4
    g = rng.normal(size=N) * 10 ** rng.uniform(-8, 0, N)
    dg = rng.normal(size=N) * 10 ** rng.uniform(-3, 2, N)
    ddg = rng.normal(size=N) * 10 ** rng.uniform(-2, 4, N)
    ddg[::7] = 0.0
    got = lat._taylor_roots(g, dg, ddg, h)
    found = 0
    for i in range(N):
        ref = _roots_reference(g[i], dg[i], ddg[i], h)
        if ref is None:
            assert not math.isfinite(got[i])
        else:
            found += 1
            assert got[i] == pytest.approx(ref, abs=1e-12 * h, rel=1e-9)
    assert found > 1000
    one = [np.array([x]) for x in (1e-6, -1.0, 0.0)]
    assert lat._taylor_roots(*one, h)[0] == pytest.approx(1e-6)
    one[1] = np.array([1.0])
    assert not math.isfinite(lat._taylor_roots(*one, h)[0])


def test_vectorized_hinge_angles_equal_the_per_hinge_ones():
    """``_Sides.hinges`` (ground, body and slope sides mixed) equals ``Latches._angle`` per
    hinge, D continued from a previous value past +-pi."""
    lat = _latches_module()
    rng = np.random.default_rng(3)
    q, v, a = rng.normal(size=(3, 20))
    left = [None, 4, np.array([6, 7]), np.array([10, 11])]
    right = [np.array([2, 3]), np.array([8, 9]), np.array([12, 13]), np.array([0, 1])]
    D_prev = np.array([0.1, 3.0, -3.1, 7.0])
    D, dD, ddD = lat._Sides(left, right).hinges(q, v, a, D_prev)
    for i in range(4):
        tl, rl, al = lat.Latches._angle(q, v, a, left[i])
        tr, rr, ar = lat.Latches._angle(q, v, a, right[i])
        wrapped = math.remainder((tr - tl) - D_prev[i], 2 * math.pi)
        assert D[i] == pytest.approx(D_prev[i] + wrapped, abs=1e-12)
        assert dD[i] == pytest.approx(rr - rl, rel=1e-12, abs=1e-12)
        assert ddD[i] == pytest.approx(ar - al, rel=1e-12, abs=1e-12)


def test_paper_example_phi_as_before():
    """phi within 1e-6 rad of the values before the change (measured: 0, the same Newton
    path)."""
    pytest.importorskip("exudyn")
    tr = simulate(paper_scene(8), "exudyn")
    assert tr.stats.status == 0
    rows = [int(np.argmin(abs(tr.times - t))) for t in (0.5, 1.0, 1.5, 2.0)]
    got = tr.values["phi"][rows][:, [1, 3, 5, 7]]
    assert np.max(np.abs(got - PAPER_PHI_BEFORE)) < 1e-6


def test_latched_three_rod_lock_times_as_before():
    """Both locks within 0.05 ms of their times before the change (measured: 0)."""
    pytest.importorskip("exudyn")
    tr = simulate(latch3_scene(), "exudyn")
    assert tr.stats.status == 0
    got = {ev["label"]: ev["t"] for ev in tr.events if ev["label"].startswith("latch")}
    assert set(got) == set(LATCH3_LOCKS_BEFORE)
    for label, t in LATCH3_LOCKS_BEFORE.items():
        assert abs(got[label] - t) < 5e-5, label
