"""Sobol sensitivity indices of a sampled study's design quantities (issue 58): SALib's
Saltelli scheme (``[sample] design = "saltelli"``), its count rule, the indices against closed
forms within their bootstrap intervals, failed runs left out and said so, too few samples
refused, and the study report's table and figures."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import rodval
from rodval.report.sensitivity import (
    MIN_BASE_SAMPLES,
    complete_blocks,
    indices_lines,
    saltelli_count_error,
    sobol_indices,
)
from rodval.study.sampling import sample_columns

PI = math.pi


def _ishigami_theory(a: float, b: float) -> np.ndarray:
    """Ishigami's f = sin x1 + a sin^2 x2 + b x3^4 sin x1, x_i ~ U(-pi, pi): rows x1..x3,
    columns S1, ST (closed form: V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V13 = b^2 pi^8
    (1/18 - 1/50), V = V1 + V2 + V13; ST1 = (V1 + V13) / V, ST2 = S2, S3 = 0, ST3 = V13 / V)."""
    v1, v2, v13 = 0.5 * (1 + b * PI**4 / 5) ** 2, a * a / 8, b * b * PI**8 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    return np.array([[v1 / v, (v1 + v13) / v], [v2 / v, v2 / v], [0.0, v13 / v]])


def test_ishigami_indices_match_theory_within_their_bootstrap_intervals():
    keys = {f"x{i}": {"dist": "uniform", "low": -PI, "high": PI} for i in (1, 2, 3)}
    x = sample_columns({"design": "saltelli", "count": 1024 * 5, "seed": 3, "keys": keys}, "s")
    x1, x2, x3 = (np.array(x[k]) for k in keys)
    y = np.sin(x1) + 7.0 * np.sin(x2) ** 2 + 0.1 * x3**4 * np.sin(x1)
    got = sobol_indices(y, list(keys), seed=3)
    theory = _ishigami_theory(7.0, 0.1)
    # the estimates carry the bootstrap's error, so theory within each 95 % half-width
    assert (np.abs(got["S1"] - theory[:, 0]) <= got["S1_conf"]).all(), got
    assert (np.abs(got["ST"] - theory[:, 1]) <= got["ST_conf"]).all(), got
    assert (got["S1"] <= got["ST"] + np.hypot(got["S1_conf"], got["ST_conf"])).all()
    assert got["S1"].sum() <= 1.0 + np.sqrt((got["S1_conf"] ** 2).sum())
    # x3 acts only with x1: no first-order share, a total one
    assert got["S1"][2] < got["S1_conf"][2] and got["ST"][2] > 3 * got["ST_conf"][2]


def test_a_linear_model_through_the_studys_distributions_has_its_closed_form_indices():
    """y = sum a_i x_i of independent x_i: S1_i = ST_i = a_i^2 var_i / sum_j a_j^2 var_j, sum
    S1 = 1 (additive); x drawn by sample_columns through a uniform and a normal, so the
    blocks of cases are in SALib's order and the columns in the keys' order."""
    keys = {
        "scene.chain.EI": {"dist": "uniform", "low": 1.0, "high": 3.0},  # var = 4 / 12
        "scene.chain.mu": {"dist": "normal", "mean": 0.0, "std": 0.5},  # var = 0.25
        "scene.chain.m": {"dist": "uniform", "low": -1.0, "high": 1.0},  # var = 1 / 3
    }
    a, var = np.array([1.0, 2.0, 0.5]), np.array([4 / 12, 0.25, 1 / 3])
    x = sample_columns({"design": "saltelli", "count": 512 * 5, "seed": 11, "keys": keys}, "s")
    y = sum(ai * np.array(x[k]) for ai, k in zip(a, keys))
    got = sobol_indices(y, list(keys), seed=11)
    share = a**2 * var / (a**2 * var).sum()
    assert (np.abs(got["S1"] - share) <= got["S1_conf"]).all(), got
    assert (np.abs(got["ST"] - share) <= got["ST_conf"]).all(), got
    assert abs(got["S1"].sum() - 1.0) <= np.sqrt((got["S1_conf"] ** 2).sum())
    # the same seed, the same indices and intervals (the bootstrap is seeded)
    pd.testing.assert_frame_equal(got, sobol_indices(y, list(keys), seed=11))


def test_the_saltelli_count_rule_is_checked_when_the_sample_is_read():
    assert saltelli_count_error(8 * 4, 2) == "" and saltelli_count_error(64 * 5, 3) == ""
    keys = {
        "scene.chain.EI": {"dist": "uniform", "low": 1.0, "high": 3.0},
        "scene.chain.mu": {"dist": "uniform", "low": 0.1, "high": 0.2},
    }
    for count, words in [
        (30, "got 30; use 32 or 64"),  # not whole blocks of D + 2 = 4
        (96, "got 96; use 64 or 128"),  # N = 24: not a power of 2
        (16, "got 16; use 32 or 64"),  # N = 4 < MIN_BASE_SAMPLES
    ]:
        with pytest.raises(ValueError, match=r"sample\.count': design = 'saltelli' needs count"):
            sample_columns({"design": "saltelli", "count": count, "seed": 0, "keys": keys}, "s")
        assert words in saltelli_count_error(count, 2)
    assert "N x 4 (D = 2 keys) with N a power of 2 >= 8" in saltelli_count_error(30, 2)


def test_too_few_or_constant_samples_are_refused_with_the_reason():
    names = ["a", "b"]
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match=f"7 base samples, fewer than the {MIN_BASE_SAMPLES}"):
        sobol_indices(rng.random(7 * 4), names, seed=0)
    with pytest.raises(ValueError, match="constant over the 8 base samples"):
        sobol_indices(np.ones(8 * 4), names, seed=0)
    with pytest.raises(ValueError, match="not whole blocks of D \\+ 2 = 4"):
        complete_blocks(np.ones(33), 2)
    y = rng.random(8 * 4)
    y[5] = np.nan  # a failed run in block 2 takes the whole block out
    kept, left = complete_blocks(y, 2)
    assert left == 1 and kept.size == 7 * 4 and np.isfinite(kept).all()
    np.testing.assert_array_equal(kept, np.delete(y, range(4, 8)))


def _synthetic_study(failed: str | None) -> tuple[dict, dict[str, pd.DataFrame]]:
    """A Saltelli sample of two keys (16 base samples, 64 cases) whose one model's lock time
    of hinge 1 is linear in them, t = 0.4 + 0.01 a + 0.02 b (s), as the report reads it;
    ``failed``: the case whose run failed (runtime.csv's status)."""
    keys = {
        "scene.chain.kappa.1": {"dist": "uniform", "low": 0.0, "high": 1.0},
        "scene.chain.mu": {"dist": "uniform", "low": 0.0, "high": 1.0},
    }
    x = sample_columns({"design": "saltelli", "count": 64, "seed": 2, "keys": keys}, "s")
    ids = [f"sample={i + 1:02d}" for i in range(64)]
    a, b = np.array(x["scene.chain.kappa.1"]), np.array(x["scene.chain.mu"])
    meta = {
        "sample": {"design": "saltelli", "count": 64, "seed": 2, "keys": keys},
        "labels": {"scene.chain.kappa.1": "1", "scene.chain.mu": "mu"},
    }
    status = ["integration failed" if c == failed else "success" for c in ids]
    tables = {
        "cases": pd.DataFrame({"case": ids, "n": 2, "horizon": 1.0, "1": a, "mu": b}),
        "runtime": pd.DataFrame({"case": ids, "model": "rigid", "status": status}),
        "trajectories": pd.DataFrame(columns=["case", "model", "t", "quantity", "k", "value"]),
    }
    events = pd.DataFrame(
        {"case": ids, "model": "rigid", "t": 0.4 + 0.01 * a + 0.02 * b, "label": "latch hinge 1"}
    )
    return meta, {**tables, "events": events}


def test_a_failed_run_is_left_out_and_the_report_says_so():
    from rodval.report.sensitivity import design_values

    for failed, samples, left in ((None, 16, 0), ("sample=06", 15, 1)):
        meta, t = _synthetic_study(failed)
        values = design_values({**t, "peaks": pd.DataFrame()})
        lines = "\n".join(indices_lines(meta, t, values))
        row = lines.splitlines()
        hit = [r for r in row if r.startswith("| rigid") and "kappa.1" in r]
        assert hit and hit[0].split("|")[-3].strip() == str(samples), lines
        assert hit[0].split("|")[-2].strip() == str(left)
        said = "`rigid`: 1 of 64 runs failed (integration failed)" in lines
        assert said == (failed is not None)


def test_a_sampled_latched_study_reports_its_sobol_indices_and_figures(tmp_path):
    doc = {
        "study": {"name": "latch_sensitivity", "reference": "rigid"},
        "scene": {
            "n": 2,
            "t_end": 0.6,
            "times": {"num": 13},
            "outputs": ["phi", "hinge_moment"],
            "loads": [],
            "chain": {"l": 1.5, "m": 3.0, "EI": 1e5, "mu": 0.5, "kappa": [0.0, 50.0], "nu": 0.0},
            "initial": {"phi": [0.0, PI - 0.05], "dphi": [1.0, 1.0]},
            "latches": [{"hinge": 1, "angle": 0.0}],
        },
        "models": {"rigid": {}},
        "sample": {
            "design": "saltelli",
            "count": 32,
            "seed": 5,
            "keys": {
                "scene.chain.kappa.1": {"dist": "uniform", "low": 40.0, "high": 60.0},
                "scene.chain.mu": {"dist": "uniform", "low": 0.3, "high": 0.7},
            },
        },
    }
    res = rodval.run_study(doc, tmp_path / "s", workers=1, progress=False)
    report = (res.out / "report.md").read_text()
    section = report.split("## Sensitivity of the design quantities")[1].split("\n## ")[0]
    assert "8 base samples of 4 cases" in section
    rows = [r for r in section.splitlines() if r.startswith("| rigid")]
    # hinge 1's lock time and impulse against both keys, over all 8 base samples
    assert {tuple(c.strip() for c in r.split("|")[2:5]) for r in rows} == {
        (q, "1", p) for q in ("t_lock", "impulse") for p in ("kappa.1", "mu")
    }
    assert all(r.split("|")[-3].strip() == "8" for r in rows)
    # the rigid model's hinge 1 moment is an impulse at the lock: no peak, refused with why
    assert "`rigid` peak_moment k = 1: not computed" in section
    for name in ("sensitivity_vs_kappa.1.png", "sensitivity_vs_mu.png"):
        assert f"(figures/{name})" in section and (res.out / "figures" / name).is_file()


def test_a_grid_or_another_design_gets_the_figures_and_no_indices(tmp_path):
    from rodval.report.sensitivity import sensitivity_section

    meta, t = _synthetic_study(None)
    tables = {k: v for k, v in t.items() if k != "events"}
    sobol = {**meta, "sample": {**meta["sample"], "design": "sobol"}}
    lines = "\n".join(sensitivity_section(tmp_path, sobol, tables, t["events"], pd.DataFrame()))
    assert "this sample's design is `sobol`: the figures only" in lines
    assert "| rigid" not in lines and (tmp_path / "sensitivity_vs_kappa.1.png").is_file()
    grid = {"labels": meta["labels"]}  # a grid study: no [sample]; its axes are the labels
    lines = "\n".join(sensitivity_section(tmp_path, grid, tables, t["events"], pd.DataFrame()))
    assert "Sobol" not in lines and "(figures/sensitivity_vs_mu.png)" in lines
    # no design quantity (no lock, no peak, no free base): no section
    none = t["events"].iloc[:0]
    assert sensitivity_section(tmp_path, grid, tables, none, pd.DataFrame()) == []
