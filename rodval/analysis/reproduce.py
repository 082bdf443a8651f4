"""Reproduction of the paper's example: Table 1 side by side with rodval, and Fig. 3.

Error measure of a Table 1 column (one quantity, formulation and time):
max over k of |rodval - published| divided by max over k of |published|.
"""

from __future__ import annotations

from importlib import resources

import pandas as pd

from rodval.analysis.metrics import relative_error
from rodval.core.scene import TABLE1_TIMES, paper_scene
from rodval.core.settings import IntegratorSettings
from rodval.core.trajectory import Trajectory
from rodval.models.registry import simulate

#: Table 1 formulation letters: P = full ("полная"), R = reduced.
FORMULATIONS = {"P": "full", "R": "reduced"}
QUANTITY_ORDER = ("phi", "dphi", "alpha", "beta")
#: Tight enough that integration error is far below the published digits.
REPRODUCTION_SETTINGS = IntegratorSettings(method="DOP853", rtol=1e-10, atol=1e-12)


def published_table1() -> pd.DataFrame:
    """The published Table 1: columns quantity, k, formulation, t, value."""
    with resources.files("rodval.data").joinpath("table1.csv").open() as fh:
        return pd.read_csv(fh)


def run_paper_models(
    coefficients: str = "printed",
    settings: IntegratorSettings = REPRODUCTION_SETTINGS,
    outputs: tuple[str, ...] = ("phi", "dphi", "alpha", "beta"),
) -> dict[str, Trajectory]:
    """Full and reduced models on the paper example at the Table 1 times."""
    scene = paper_scene(times=TABLE1_TIMES, outputs=outputs)
    return {
        f: simulate(scene, model, settings=settings, coefficients=coefficients)
        for f, model in FORMULATIONS.items()
    }


def compare_table1(trajectories: dict[str, Trajectory]) -> pd.DataFrame:
    """Published values beside rodval's: quantity, k, formulation, t, rodval, published, diff."""
    pub = published_table1()
    ours = []
    for f, traj in trajectories.items():
        frame = traj.to_frame()
        frame["formulation"] = f
        ours.append(frame)
    ours_df = pd.concat(ours, ignore_index=True).rename(columns={"value": "rodval"})
    ours_df["t"] = ours_df["t"].round(9)
    pub = pub.assign(t=pub["t"].round(9)).rename(columns={"value": "published"})
    table = pub.merge(ours_df, on=["quantity", "k", "formulation", "t"], how="left")
    table["diff"] = table["rodval"] - table["published"]
    table["quantity"] = pd.Categorical(table["quantity"], QUANTITY_ORDER, ordered=True)
    table = table.sort_values(["quantity", "formulation", "t", "k"]).reset_index(drop=True)
    table["quantity"] = table["quantity"].astype(str)
    return table[["quantity", "k", "formulation", "t", "rodval", "published", "diff"]]


def column_errors(table: pd.DataFrame) -> pd.DataFrame:
    """Error per Table 1 column (quantity, formulation, t): max over k of |diff| divided by
    max over k of |published| (``relative_error`` with scale "time")."""
    rows = []
    for (q, f), part in table.groupby(["quantity", "formulation"], sort=False):
        ours = part.pivot(index="t", columns="k", values="rodval")
        pub = part.pivot(index="t", columns="k", values="published")
        err = relative_error(ours.to_numpy(float), pub.to_numpy(float), "time")
        rows += [
            {"quantity": q, "formulation": f, "t": t, "error": float(e)}
            for t, e in zip(ours.index, err)
        ]
    return pd.DataFrame(rows, columns=["quantity", "formulation", "t", "error"])
