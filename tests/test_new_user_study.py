"""The new user's study of issue 21: a non-uniform wing (a stiff root rod and repeated panels,
given as profiles), n swept over 4, 8, 16 by one grid axis, "energy" among the outputs, the
full, reduced and exudyn models with exudyn not the reference. Every pair is compared (the
energy audit's quantities, which only the audited native runs output, are left out of the
exudyn pair with a note and counted, the rest compared), no comparison row holds NaN, case
ids stay under 60 characters and every figure title fits its figure."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import rodval
from rodval.report.tables import read_tables

pytestmark = pytest.mark.exudyn

WING = {
    "study": {"name": "wing", "reference": "full"},
    "scene": {
        "based_on": "paper",
        "t_end": 0.1,
        "times": {"num": 6},
        "outputs": ["phi", "dphi", "energy"],
        "chain": {
            "l": {"first": [0.5], "rest": 1.0},
            "EI": {"first": [5e4], "rest": 1e4},
            "m": {"at": [0.0, 1.0], "values": [4.0, 2.0]},
            "kappa": {"first": [1e4], "repeat": [80.0, 120.0]},
        },
    },
    "models": {"full": {}, "reduced": {}, "exudyn": {"elements": 2, "step": 2e-4}},
    "grid": {"scene.n": [4, 8, 16]},
}


def test_the_new_users_wing_study_compares_every_pair(tmp_path):
    pytest.importorskip("exudyn")
    res = rodval.run_study(WING, tmp_path / "wing", workers=2, progress=False)
    tables = read_tables(res.out)
    disc, runtime = tables["discrepancies"], tables["runtime"]
    assert (runtime["status"] == "success").all(), runtime[["case", "model", "message"]]
    assert max(len(c) for c in tables["cases"]["case"]) < 60
    pairs = {(m, r) for m, r in zip(disc["model"], disc["reference"])}
    assert pairs == {("reduced", "full"), ("exudyn", "full")}
    for (case, model), part in disc.groupby(["case", "model"]):
        assert {"phi", "dphi", "kinetic", "potential", "energy"} <= set(part["quantity"]), (
            case,
            model,
        )
    assert (disc["status"] == "ok").all()
    assert np.isfinite(disc[["max_abs", "rms", "final_abs"]].to_numpy(float)).all()
    ex = disc[disc["model"] == "exudyn"]
    # exudyn runs the energy audit too (reference_models.exudyn_audit): every quantity compared
    assert {"work", "dissipated", "energy_residual"} <= set(ex["quantity"])
    report = (res.out / "report.md").read_text()
    assert "_Left out of this comparison" not in report
    assert "48 comparisons made (case, model, quantity)" in report
    assert "No comparison" not in report


def test_a_pair_without_any_common_run_failure_is_not_dropped():
    """The rule in isolation: quantities only one run outputs are left out, the others are
    compared (before, one missing quantity made the whole pair 'not comparable')."""
    from rodval.analysis.metrics import compare_runs, left_out_quantities

    scene = rodval.paper_scene(n=2, t_end=0.05, times=[0.025, 0.05], outputs=["phi", "energy"])
    audited = rodval.simulate(scene, "full", method="DOP853")
    plain = rodval.simulate(scene.with_(outputs=["phi"]), "reduced")
    rows = pd.DataFrame(compare_runs({"full": audited, "reduced": plain}, "full", scene.outputs))
    assert list(rows["quantity"]) == ["phi"] and (rows["status"] == "ok").all()
    assert left_out_quantities(plain.quantities, audited.quantities) == [
        q for q in audited.quantities if q != "phi"
    ]


def test_the_models_table_says_which_settings_apply():
    """A study's [integrator] rtol was listed for exudyn ("auto, 1e-08, 1e-10") although exudyn
    integrates itself: its row now shows its own options (step, elements, ...) and n/a for
    the integrator settings, as the CLI and API refuse them for exudyn."""
    pytest.importorskip("exudyn")
    from rodval.report.study_report import model_row

    spec = rodval.Study.from_dict(
        {
            "scene": {"based_on": "paper", "n": 2, "t_end": 0.05},
            "integrator": {"rtol": 1e-9},
            "models": {"full": {}, "exudyn": {"elements": 2}},
        }
    )
    rows = {m.label: model_row(m.as_dict()) for m in spec.models}
    assert rows["full"]["rtol"] == 1e-9 and rows["full"]["method"] == "auto"
    assert rows["exudyn"]["rtol"] == rows["exudyn"]["method"] == "n/a"
    assert '"elements": 2' in rows["exudyn"]["options"] and '"step"' in rows["exudyn"]["options"]
