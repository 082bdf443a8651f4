"""The model error budget (rodval.report.error_budget): the split of each rung's gap into
kinematics, shapes, base and remainder parts, and the study report's table of it."""

import math

import pandas as pd
import pytest

from rodval.report.error_budget import (
    NO_BASE_AXIS,
    NO_PINNED,
    error_budget,
    has_ladder,
    split_gaps,
)
from rodval.study import load_study, run_study

# gaps in binary fractions, so that every part is exact: the rungs of docs/model.md's table
# (exact p = 1 closer to the reference than exact p = 3: a negative shapes part)
GAPS = {
    ("first-order", 1): {"phi": 0.875, "alpha": 0.0625},
    ("exact", 1): {"phi": 0.25, "alpha": 0.0625},
    ("exact", 2): {"phi": 0.3125, "alpha": 0.03125},
    ("exact", 3): {"phi": 0.375, "alpha": 0.015625},
}


def _gaps(gaps=GAPS, **columns):
    return pd.DataFrame(
        [
            {**columns, "kinematics": kin, "shapes": p, "quantity": q, "gap": g}
            for (kin, p), by_q in gaps.items()
            for q, g in by_q.items()
        ]
    )


def test_the_parts_are_the_differences_of_the_rungs_gaps():
    split = split_gaps(_gaps())
    assert split is not None
    assert list(split["quantity"]) == ["phi", "alpha"]
    phi, alpha = (split[split["quantity"] == q].iloc[0] for q in ("phi", "alpha"))
    assert phi["unit"] == "rad"
    assert phi["p_max"] == 3
    assert phi["gap first-order p=1"] == 0.875
    assert phi["gap exact p=2"] == 0.3125
    assert phi["kinematics"] == 0.625  # 0.875 - 0.25
    assert phi["shapes"] == -0.125  # 0.25 - 0.375: the rungs' errors cancel
    assert phi["remainder"] == 0.375
    assert alpha["kinematics"] == 0.0
    assert alpha["shapes"] == 0.046875
    assert alpha["remainder"] == 0.015625
    assert split["base"].isna().all()
    assert (split["base_note"] == NO_BASE_AXIS).all()
    for row in split.to_dict("records"):
        assert row["kinematics"] + row["shapes"] + row["remainder"] == row["gap first-order p=1"]


@pytest.mark.parametrize("missing", [("first-order", 1), ("exact", 1), "exact p>1"])
def test_no_table_without_a_rung(missing):
    drop = {("exact", 2), ("exact", 3)} if missing == "exact p>1" else {missing}
    assert split_gaps(_gaps({r: g for r, g in GAPS.items() if r not in drop})) is None


def test_the_base_part_against_the_pinned_case_on_the_same_rung():
    pinned = _gaps(n=2, mass="-", base_kind="pinned")
    free = _gaps(
        {
            r: {q: g + (0.5 if r == ("exact", 3) else 0.25) for q, g in by_q.items()}
            for r, by_q in GAPS.items()
        },
        n=2,
        mass=1000.0,
        base_kind="free",
    )
    lonely = _gaps(n=3, mass=1000.0, base_kind="free")  # no pinned case with n = 3
    split = split_gaps(pd.concat([pinned, free, lonely]), by=["n", "mass"], base_columns=["mass"])
    assert split is not None
    phi = split[split["quantity"] == "phi"].set_index(["n", "base_kind"])
    assert phi.loc[(2, "pinned"), "base"] == 0.0
    assert phi.loc[(2, "pinned"), "remainder"] == 0.375
    # free: gap(exact, 3) = 0.875 against the pinned 0.375
    assert phi.loc[(2, "free"), "base"] == 0.5
    assert phi.loc[(2, "free"), "remainder"] == 0.375
    assert phi.loc[(2, "free"), "shapes"] == 0.25 - 0.5 - 0.125  # 0.5 - 0.875
    row = phi.loc[(2, "free")]
    total = row["kinematics"] + row["shapes"] + row["base"] + row["remainder"]
    assert total == row["gap first-order p=1"]
    assert math.isnan(phi.loc[(3, "free"), "base"])
    assert phi.loc[(3, "free"), "base_note"] == NO_PINNED
    assert phi.loc[(3, "free"), "remainder"] == 0.375


def _meta(models, labels=None, cases=None, reference="exudyn"):
    return {
        "reference": reference,
        "models": [{"label": lab, "model": name, "options": opts} for lab, name, opts in models],
        "labels": labels or {},
        "axes": {},
        "cases": cases or [{"id": "base", "params": {}}],
    }


def _disc(rows):
    return pd.DataFrame(
        [
            {
                "case": c,
                "n": 2,
                "horizon": 1.0,
                "model": m,
                "reference": "exudyn",
                "quantity": q,
                "max_abs": g,
                "status": "ok" if g == g else "failed",
            }
            for c, m, q, g in rows
        ]
    )


def test_rungs_as_model_labels():
    meta = _meta(
        [
            ("paper", "full", {"kinematics": "first-order"}),
            ("exact1", "full", {"kinematics": "exact"}),
            ("exact2", "full", {"kinematics": "exact", "shapes": 2}),
            ("exudyn", "exudyn", {"elements": 8}),
        ]
    )
    assert has_ladder(meta)
    disc = _disc(
        [
            ("base", "paper", "phi", 0.75),
            ("base", "exact1", "phi", 0.25),
            ("base", "exact2", "phi", math.nan),
        ]
    )
    split = error_budget(disc, meta)
    assert split is not None
    row = split.iloc[0]
    assert (row["n"], row["horizon"], row["quantity"]) == (2, 1.0, "phi")
    assert row["kinematics"] == 0.5
    assert math.isnan(row["shapes"])  # exact p = 2 failed: no comparison


def test_rungs_from_the_grid_and_a_missing_rung():
    labels = {"models.full.kinematics": "kinematics", "models.full.shapes": "shapes"}
    cases = [
        {"id": f"kinematics={k},shapes={p}", "params": {"kinematics": k, "shapes": p}}
        for k in ("first-order", "exact")
        for p in (1, 2)
    ]
    meta = _meta([("full", "full", {}), ("exudyn", "exudyn", {})], labels, cases)
    gaps = {"first-order": {1: 0.5, 2: 0.5}, "exact": {1: 0.25, 2: 0.125}}
    disc = _disc(
        [
            (c["id"], "full", "phi", gaps[c["params"]["kinematics"]][c["params"]["shapes"]])
            for c in cases
        ]
    ).assign(
        kinematics=[c["params"]["kinematics"] for c in cases],
        shapes=[c["params"]["shapes"] for c in cases],
    )
    split = error_budget(disc, meta)
    assert split is not None and len(split) == 1  # one group: the rung axes are not a group
    assert list(split.columns[:4]) == ["n", "horizon", "quantity", "unit"]
    assert (split.iloc[0]["kinematics"], split.iloc[0]["shapes"]) == (0.25, 0.125)
    exact_only = {**meta, "cases": [c for c in cases if c["params"]["kinematics"] == "exact"]}
    assert not has_ladder(exact_only)
    assert error_budget(disc, exact_only) is None
    paper_reference = _meta([("full", "full", {})], labels, cases, reference="full")
    assert error_budget(disc, paper_reference) is None  # the reference is no rung


STUDY = """
[study]
name = "tiny_budget"
reference = "ref"

[scene]
based_on = "paper"
n = 2
t_end = 0.05
times = {{ num = 6 }}

[integrator]
rtol = 1e-8
atol = 1e-10

[models.full]
[models.ref]
model = "full"
kinematics = "exact"
shapes = 3
rtol = 1e-11
atol = 1e-13

[grid]
models.full.kinematics = {kinematics}
models.full.shapes = [1, 2]
"""


@pytest.mark.parametrize("ladder", [True, False])
def test_the_study_report_writes_the_budget_when_the_study_runs_the_rungs(tmp_path, ladder):
    path = tmp_path / "budget.toml"
    kinematics = '["first-order", "exact"]' if ladder else '["exact"]'
    path.write_text(STUDY.format(kinematics=kinematics))
    out = tmp_path / "out"
    run_study(load_study(path), out, workers=1, progress=False)
    report = (out / "report.md").read_text()
    if not ladder:
        assert not (out / "error_budget.csv").exists()
        assert not (out / "error_budget.md").exists()
        assert "Error budget" not in report
        return
    budget = pd.read_csv(out / "error_budget.csv")
    assert "## Error budget of the model ladder" in report
    assert (out / "error_budget.md").read_text().startswith("|")
    disc = pd.read_csv(out / "discrepancies.csv").set_index(["kinematics", "shapes", "quantity"])
    assert set(budget["quantity"]) == {"phi", "dphi", "alpha", "beta"}
    for row in budget.to_dict("records"):
        gap = {
            (k, p): disc.loc[(k, p, row["quantity"]), "max_abs"]
            for k in ("first-order", "exact")
            for p in (1, 2)
        }
        assert row["kinematics"] == pytest.approx(gap["first-order", 1] - gap["exact", 1])
        assert row["shapes"] == pytest.approx(gap["exact", 1] - gap["exact", 2])
        assert row["remainder"] == pytest.approx(gap["exact", 2])
        assert math.isnan(row["base"]) and row["base_note"] == NO_BASE_AXIS
