"""Benchmarks that guard themselves (rodval.bench.drift): a ratio beyond the noise factor and
a count beyond its tolerance are named, in either direction; within them nothing is."""

import math

import pandas as pd
import pytest

from rodval.bench.drift import drift_table, drifted

KEYS = ["scene", "model"]
RECORDED = pd.DataFrame(
    {
        "scene": ["wing", "wing", "paper"],
        "model": ["full", "reduced", "full"],
        "speedup": [15.2, 11.4, 16.1],
        "auto_nfev": [67513, 6605, 31131],
    }
)


def test_ratios_beyond_the_noise_and_changed_counts_are_named():
    fresh = RECORDED.copy()
    fresh.loc[1, "speedup"] = 2.4  # the documented 11x became 2.4x
    fresh.loc[2, "speedup"] = 16.1 * 1.4  # within the 1.5 noise
    fresh.loc[0, "auto_nfev"] = 70889  # 5 % more: another step sequence
    table = drift_table(RECORDED, fresh, KEYS, ["speedup"], ["auto_nfev"], noise=1.5)
    bad = drifted(table)
    assert set(zip(bad["scene"], bad["model"], bad["figure"], bad["verdict"])) == {
        ("wing", "reduced", "speedup", "slower"),
        ("wing", "full", "auto_nfev", "changed"),
    }
    row = bad[bad["figure"] == "speedup"].iloc[0]
    assert row["factor"] == pytest.approx(2.4 / 11.4)


def test_a_faster_ratio_and_a_missing_row_are_named_too():
    fresh = RECORDED.iloc[:2].copy()
    fresh.loc[0, "speedup"] = 40.0
    table = drift_table(RECORDED, fresh, KEYS, ["speedup"], noise=1.5).set_index(KEYS)
    assert table.loc[("wing", "full"), "verdict"] == "faster"
    assert table.loc[("paper", "full"), "verdict"] == "missing"
    assert math.isnan(table.loc[("paper", "full"), "fresh"])
    assert table.loc[("wing", "reduced"), "verdict"] == "within noise"


@pytest.mark.parametrize("kw", [{"noise": 1.0}, {"noise": 0.5}, {"count_tol": -1.0}])
def test_bad_bounds_are_refused(kw):
    with pytest.raises(ValueError, match="noise|count_tol"):
        drift_table(RECORDED, RECORDED, KEYS, ["speedup"], **kw)
