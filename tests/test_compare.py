"""Discrepancy metrics against closed forms, and the Trajectory round trips the study uses."""

import numpy as np
import pandas as pd
import pytest

from rodval.analysis.metrics import discrepancies, error_metrics
from rodval.core.trajectory import SolverStats, Trajectory


def _traj(values: dict, times, model="m") -> Trajectory:
    return Trajectory(
        model=model,
        scene_name="s",
        times=np.asarray(times, float),
        values={q: np.asarray(v, float) for q, v in values.items()},
        k_index={q: np.arange(1, np.shape(v)[1] + 1) for q, v in values.items()},
        stats=SolverStats(),
    )


def test_metrics_of_a_known_error():
    t = np.linspace(0.0, 1.0, 11)
    ref = np.column_stack([np.cos(2 * np.pi * t), 10 * np.cos(2 * np.pi * t)])  # scales 1, 10
    err = np.column_stack([0.01 * t, -0.05 * t**2])
    m = error_metrics(t, np.array([1, 2]), ref + err, ref)
    assert m["max_abs"] == pytest.approx(0.05)
    assert (m["k_at_max"], m["t_at_max"]) == (2, 1.0)
    assert m["final_abs"] == pytest.approx(0.05)
    assert m["rms"] == pytest.approx(np.sqrt(np.mean(err**2)))
    # column 1: 0.01 / 1 = 0.01; column 2: 0.05 / 10 = 0.005 -> max_rel from column 1
    assert m["max_rel"] == pytest.approx(0.01)


def test_max_rel_skips_columns_without_scale_and_is_nan_without_any():
    t = np.array([0.0, 1.0])
    ref = np.array([[0.0, 2.0], [0.0, -4.0]])
    m = error_metrics(t, np.array([1, 2]), ref + 0.1, ref)
    assert m["max_rel"] == pytest.approx(0.1 / 4.0)
    zero = np.zeros((2, 1))
    assert np.isnan(error_metrics(t, np.array([1]), zero + 1.0, zero)["max_rel"])


def test_discrepancies_one_row_per_common_quantity_and_checks_times():
    t = [0.0, 0.5, 1.0]
    a = _traj({"phi": np.ones((3, 2)), "dphi": np.zeros((3, 2))}, t, "a")
    b = _traj({"phi": np.full((3, 2), 1.5)}, t, "b")
    df = discrepancies(b, a)
    assert list(df["quantity"]) == ["phi"] and df["max_abs"].iloc[0] == pytest.approx(0.5)
    with pytest.raises(ValueError, match="different output times"):
        discrepancies(_traj({"phi": np.ones((2, 2))}, [0.0, 1.0]), a)
    with pytest.raises(ValueError, match="not in both"):
        discrepancies(b, a, ["dphi"])


def test_trajectory_dict_and_frame_round_trips():
    tr = _traj({"phi": np.arange(6.0).reshape(3, 2), "energy": np.ones((3, 1))}, [0.0, 0.5, 1.0])
    tr.stats = SolverStats(status=-1, message="gave up", t_reached=0.7, nfev=12)
    back = Trajectory.from_dict(tr.to_dict())
    assert back.stats == tr.stats
    pd.testing.assert_frame_equal(back.to_frame(), tr.to_frame())
    again = Trajectory.from_frame(tr.to_frame(), "m")
    pd.testing.assert_frame_equal(again.to_frame(), tr.to_frame())
    with pytest.raises(ValueError, match="every"):
        Trajectory.from_frame(tr.to_frame().iloc[1:], "m")
