"""The benchmark helpers' pure parts and the bench CLI's input checks (no timing runs here;
the benchmarks themselves run on demand, see benchmarks/run_all.sh)."""

import numpy as np
import pytest

from rodval import bench
from rodval.cli import main


def test_pareto_front_is_monotone_and_non_dominated():
    rng = np.random.default_rng(0)
    cost, err = rng.uniform(1, 100, 200), rng.uniform(1e-10, 1, 200)
    err[5] = np.nan
    f = bench.pareto_front(cost, err)
    assert np.all(np.diff(cost[f]) >= 0) and np.all(np.diff(err[f]) < 0)
    for i in range(200):  # every finite point is dominated by (or on) the front
        if np.isfinite(err[i]):
            assert np.any((cost[f] <= cost[i]) & (err[f] <= err[i]))


def test_fitted_exponent_recovers_a_power_law():
    n = np.array([2, 4, 8, 16, 32, 64, 128])
    assert bench.fitted_exponent(n, 3e-6 * n**1.7) == pytest.approx(1.7)
    cost = np.where(n < 32, 1e-3, 1e-5 * n**2.0)
    assert bench.fitted_exponent(n, cost, n_min=32) == pytest.approx(2.0)


def test_errors_are_relative_and_give_scd():
    from rodval import paper_scene, simulate

    sc = paper_scene(2, times=[0.5, 1.0], outputs=("phi",))
    ref = simulate(sc, "reduced", rtol=1e-10, atol=1e-12)
    loose = simulate(sc, "reduced", rtol=1e-3, atol=1e-5)
    e = bench.errors(loose, ref, ("phi", "dphi"))
    d = np.max(np.abs(loose["phi"] - ref["phi"])) / np.max(np.abs(ref["phi"]))
    assert e["max_phi"] == pytest.approx(d) and "max_dphi" not in e
    assert e["scd"] == pytest.approx(-np.log10(d))
    assert bench.errors(ref, ref, ("phi",))["max_phi"] == 0.0


@pytest.mark.parametrize(
    "argv",
    [
        ["bench", "work-precision", "--out", "x", "--methods", "RK99"],
        ["bench", "work-precision", "--out", "x", "--rtols", "1e-4,2"],
        ["bench", "cost-n", "--out", "x", "--n-values", "0,4"],
        ["bench", "skips", "--out", "x", "--repeats", "0"],
    ],
)
def test_bench_cli_rejects_bad_options(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert "must" in capsys.readouterr().err


def test_scale_scene_is_the_paper_chain_with_the_pulse_at_the_last_node():
    sc = bench.scale_scene(5)
    assert sc.chain.n == 5 and sc.outputs == ("phi", "dphi")
    assert sc.times[0] == 0.0 and sc.times[-1] == 2.0 and len(sc.times) == 21
    assert sc.loads[0].node == 5


def test_subnormal_count():
    tiny = np.finfo(float).tiny
    assert bench.subnormal_count(np.array([0.0, tiny, tiny / 4, -5e-324, 1.0])) == 2


def test_scale_fits_recover_each_models_exponent():
    import pandas as pd

    n = np.array([16, 64, 256, 1024, 4096])
    rows = []
    for model, p in (("reduced", 1.0), ("full", 1.5)):
        for k, c in zip(n, 1e-6 * n.astype(float) ** p):
            rows.append(
                {
                    "model": model,
                    "n": k,
                    **dict.fromkeys(
                        ("wall_s", "rhs_random_s", "rhs_run_s", "wall_per_eval_s", "setup_s"), c
                    ),
                }
            )
    fits = bench.scale_fits(pd.DataFrame(rows), 64).set_index("model")
    assert fits.loc["reduced", "wall_s"] == pytest.approx(1.0)
    assert fits.loc["full", "rhs_run_s"] == pytest.approx(1.5)
    assert fits.loc["full", "n range"] == "64..4096"


def test_bench_scale_cli_rejects_bad_options(capsys):
    for argv in (
        ["bench", "scale", "--out", "x", "--n-values", "0,4"],
        ["bench", "scale", "--out", "x", "--budget", "-1"],
        ["bench", "scale", "--out", "x", "--speedup-n", "a"],
    ):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
    assert "must" in capsys.readouterr().err
