"""Sampling of uncertain parameters in studies (issue 21): seeded Sobol / Latin hypercube /
random designs through uniform, (truncated) normal and lognormal distributions; one case per
sample; the report's percentiles and latch-locking probability; the same seed, the same
tables."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import rodval
from rodval.report.sample_stats import lock_statistics
from rodval.report.tables import read_tables
from rodval.study.sampling import quantiles, sample_columns

KEYS = {
    "scene.chain.EI": {"dist": "uniform", "low": 1e4, "high": 2e4},
    "scene.chain.nu": {"dist": "lognormal", "median": 0.05, "sigma": 0.5, "low": 0.01, "high": 0.5},
    "scene.t_end": {"dist": "normal", "mean": 0.1, "std": 0.02, "low": 0.05, "high": 0.15},
}


def test_the_same_seed_gives_the_same_samples_within_their_bounds():
    for design in ("sobol", "lhs", "random"):
        table = {"design": design, "count": 64, "seed": 7, "keys": KEYS}
        a, b = sample_columns(table, "s"), sample_columns(dict(table), "s")
        assert a == b
        assert sample_columns({**table, "seed": 8}, "s") != a
        ei, nu, t = (np.array(a[k]) for k in KEYS)
        assert ei.min() >= 1e4 and ei.max() <= 2e4
        assert nu.min() >= 0.01 and nu.max() <= 0.5
        assert t.min() >= 0.05 and t.max() <= 0.15
    # a Sobol design of 64 points stratifies each axis: one point in each 1/64 of [0, 1)
    ei = np.array(sample_columns({"count": 64, "seed": 7, "keys": KEYS}, "s")["scene.chain.EI"])
    assert sorted(np.floor((ei - 1e4) / 1e4 * 64).astype(int).tolist()) == list(range(64))


def test_quantile_functions_against_closed_forms():
    u = np.array([0.5, 0.8413447460685429])  # Phi(0), Phi(1)
    normal = quantiles({"dist": "normal", "mean": 2.0, "std": 3.0}, u)
    np.testing.assert_allclose(normal, [2.0, 5.0], rtol=1e-12)
    logn = quantiles({"dist": "lognormal", "median": 0.05, "sigma": 0.5}, u)
    np.testing.assert_allclose(logn, [0.05, 0.05 * math.exp(0.5)], rtol=1e-12)
    np.testing.assert_allclose(
        quantiles({"dist": "uniform", "low": 1.0, "high": 3.0}, u),
        [2.0, 2.6826894921370859],
        rtol=1e-15,
    )
    # truncation maps u = 0 and u -> 1 onto the bounds, and keeps the median of a symmetric cut
    cut = {"dist": "normal", "mean": 0.0, "std": 1.0, "low": -0.5, "high": 0.5}
    np.testing.assert_allclose(
        quantiles(cut, np.array([0.0, 0.5, 1.0])), [-0.5, 0.0, 0.5], atol=1e-12
    )


@pytest.mark.parametrize(
    "table, words",
    [
        (
            {"count": 100, "seed": 1, "keys": KEYS},
            r"sample\.count': a Sobol design needs a power of 2.*64 or 128",
        ),
        ({"count": 8, "keys": KEYS}, r"sample\.seed': must be an integer >= 0"),
        (
            {"count": 8, "seed": 1, "design": "grid", "keys": KEYS},
            r"sample\.design': must be one of",
        ),
        (
            {"count": 8, "seed": 1, "keys": {"scene.chain.EI": {"dist": "beta"}}},
            r"sample\.keys\.scene\.chain\.EI': must be a table with dist",
        ),
        (
            {"count": 8, "seed": 1, "keys": {"scene.chain.EI": {"dist": "normal", "mean": 1.0}}},
            r"needs std",
        ),
        (
            {
                "count": 8,
                "seed": 1,
                "keys": {"scene.chain.EI": {"dist": "uniform", "low": 2.0, "high": 1.0}},
            },
            r"low must be < high",
        ),
        (
            {
                "count": 8,
                "seed": 1,
                "keys": {"scene.chain.EI": {"dist": "uniform", "low": 1, "high": 2, "mode": 1}},
            },
            r"unknown key 'mode'",
        ),
        ({"count": 8, "seed": 1, "keys": {}, "extra": 1}, r"sample\.extra': unknown key"),
    ],
)
def test_bad_sample_tables_are_refused_naming_the_key(table, words):
    with pytest.raises(ValueError, match=words):
        sample_columns(table, "s")


def _deployment(count: int, seed: int) -> dict:
    """A three-panel deployment (two latches) with its panel hinges' stiffness and damping
    and the latch angle sampled; short horizon so that a few samples run in seconds."""
    return {
        "study": {"name": "sampled", "reference": "full"},
        "scene": {
            "n": 3,
            "t_end": 1.2,
            "times": {"num": 13},
            "outputs": ["phi"],
            "loads": [],
            "chain": {
                "l": 1.0,
                "m": 3.0,
                "EI": 5e3,
                "mu": 0.5,
                "kappa": {"first": [1e5], "rest": 50.0},
                "nu": {"first": [10.0], "rest": 0.05},
            },
            "initial": {"phi": [0.0, 3.0915926535897933, 0.0]},
            "latches": [{"hinge": 1, "angle": 0.0}, {"hinge": 2, "angle": 0.0}],
        },
        "models": {"full": {}, "reduced": {}},
        "sample": {
            "design": "sobol",
            "count": count,
            "seed": seed,
            "keys": {
                "scene.chain.kappa.rest": {"dist": "uniform", "low": 30.0, "high": 70.0},
                "scene.latches.*.angle": {
                    "dist": "normal",
                    "mean": 0.0,
                    "std": 0.02,
                    "low": -0.05,
                    "high": 0.05,
                },
            },
        },
    }


def _tables(out) -> dict[str, pd.DataFrame]:
    return {
        k: v.drop(columns=[c for c in ("wall_s", "setup_s") if c in v])
        for k, v in read_tables(out).items()
    }


def test_a_sampled_deployment_reports_locking_and_repeats_exactly(tmp_path):
    spec = rodval.Study.from_dict(_deployment(8, 3))
    assert [c.id for c in spec.cases][:2] == ["sample=1", "sample=2"]
    angles = [c.scene.latches[0].angle for c in spec.cases]
    assert all(c.scene.latches[1].angle == c.scene.latches[0].angle for c in spec.cases)
    assert len(set(angles)) == 8
    a = rodval.run_study(spec, tmp_path / "a", workers=2, progress=False)
    b = rodval.run_study(_deployment(8, 3), tmp_path / "b", workers=2, progress=False, report=False)
    ta, tb = _tables(a.out), _tables(b.out)
    for name in ta:
        pd.testing.assert_frame_equal(ta[name], tb[name], check_exact=True, obj=name)
    cases = ta["cases"]
    assert (
        set(spec.labels.values()) == {"rest", "angle"} <= set(cases.columns)
    )  # shortest unambiguous
    np.testing.assert_array_equal(cases["angle"].to_numpy(), angles)
    events = pd.read_csv(a.out / "events.csv")
    locks = lock_statistics(cases, events, ["full", "reduced"])
    assert set(locks["hinge"]) == {1, 2}
    full = locks[locks["model"] == "full"]
    assert (full["samples"] == 8).all()
    # every sample of this release deploys (the springs drive each hinge through its latch)
    assert full["p_all_locked"].iloc[0] == 1.0 and (full["locked"] == 1.0).all()
    assert (full["t_p5"] <= full["t_p50"]).all() and (full["t_p50"] <= full["t_p95"]).all()
    report = (a.out / "report.md").read_text()
    assert (
        "## Sample statistics" in report
        and "every latch locked by the end of the run in 100.0% of the samples" in report
    )
    assert "8 samples, sobol design, seed 3" in report


def test_a_study_has_a_grid_or_a_sample_not_both():
    doc = _deployment(8, 3)
    doc["grid"] = {"scene.n": [3]}
    with pytest.raises(ValueError, match="a study has a \\[grid\\] or a \\[sample\\], not both"):
        rodval.Study.from_dict(doc)
    doc = _deployment(8, 3)
    doc["sample"]["keys"] = {"scene.latches.5.angle": {"dist": "uniform", "low": 0.0, "high": 0.1}}
    with pytest.raises(ValueError, match=r"'5' is not '\*' or an index of a list of 2"):
        rodval.Study.from_dict(doc)
