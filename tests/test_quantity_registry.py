"""The output-quantity registry (``rodval.core.quantities``, issue 48): every quantity declared
once, and what reads it (the scene's names and units, the bases an output exists on, which
models output it, the docs table, the study report's peak hinge moments)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rodval import Base, paper_scene, simulate
from rodval.core.base import BASE_KINDS, Motion
from rodval.core.quantities import (
    GROUPS,
    OUTPUTS,
    QUANTITY,
    QUANTITY_TABLE,
    ROD_QUANTITIES,
    UNIT,
    check_output_bases,
    models_with,
    quantities_of,
    quantity_k,
    with_doc_table,
)
from rodval.core.scene import EXPANDS, QUANTITIES, UNITS, trajectory_quantities
from rodval.models.registry import MODEL_NAMES, get_model
from rodval.report.study_report import peak_hinge_moments

ROOT = Path(__file__).resolve().parents[1]

BASES = {
    "pinned": Base(),
    "free": Base(kind="free", mass=5.0, inertia=2.0, hinge_offset=(0.3, 0.0)),
    "prescribed": Base(
        kind="prescribed",
        hinge_offset=(0.3, 0.0),
        motion={"attitude": Motion("spin_up", (2.0, 0.2))},
    ),
}


def test_scene_names_and_units_are_the_registry():
    """QUANTITIES, EXPANDS, UNITS (rodval.core.scene) are read from the registry, in the order
    they had, with tip_deflection added; every trajectory quantity has a unit."""
    assert QUANTITIES == OUTPUTS
    assert QUANTITIES[:13] == (
        "phi", "dphi", "alpha", "beta", "x", "y", "energy", "hinge_angle", "hinge_moment",
        "angular_momentum", "momentum", "base", "drive",
    )  # fmt: skip
    assert "tip_deflection" in QUANTITIES
    assert EXPANDS is GROUPS and UNITS is UNIT
    assert EXPANDS["energy"] == ("kinetic", "potential", "energy")
    assert EXPANDS["base"] == ("base_position", "base_velocity", "base_attitude", "base_rate")
    assert EXPANDS["drive"] == ("drive_force", "drive_moment")
    assert set(UNITS) == set(QUANTITY)
    assert ROD_QUANTITIES == ("phi", "dphi", "alpha", "beta")
    assert trajectory_quantities(QUANTITIES) == quantities_of(QUANTITIES)
    assert {"work", "dissipated", "energy_residual"} <= set(UNITS)
    assert not {"work", "dissipated", "energy_residual"} & set(quantities_of(QUANTITIES))


def test_every_quantity_is_declared_once_with_its_docs():
    names = [q.name for q in QUANTITY_TABLE]
    assert len(names) == len(set(names))
    for q in QUANTITY_TABLE:
        assert q.unit and q.definition and q.native and q.exudyn, q.name
        assert q.output in OUTPUTS


def test_docs_quantity_table_is_the_generated_one():
    """docs/quantities.md holds the table the registry generates (regenerate: python -m
    rodval.core.quantities --write docs/quantities.md)."""
    text = (ROOT / "docs" / "quantities.md").read_text()
    assert with_doc_table(text) == text
    assert "| `tip_deflection` |" in text


@pytest.mark.parametrize(
    ("name", "n", "k"),
    [
        ("phi", 3, range(1, 4)),
        ("x", 3, range(4)),
        ("hinge_moment", 3, range(3)),
        ("momentum", 3, range(2)),
        ("angular_momentum", 3, range(2)),
        ("tip_deflection", 3, range(1)),
        ("drive_moment", 3, range(1)),
    ],
)
def test_quantity_k(name, n, k):
    assert quantity_k(name, n) == k


def test_unknown_quantity_is_one_line():
    with pytest.raises(ValueError, match=r"^quantity must be one of \(.*\), got 'tip'$"):
        quantity_k("tip", 3)


def test_every_model_outputs_hinge_moment_and_exudyn_no_drive():
    assert models_with("hinge_moment", MODEL_NAMES) == MODEL_NAMES
    assert models_with("tip_deflection", MODEL_NAMES, "free") == MODEL_NAMES
    assert "exudyn" not in models_with("drive_force", MODEL_NAMES, "prescribed")
    assert models_with("base_attitude", MODEL_NAMES, "pinned") == ()


def test_output_bases_messages():
    """The scene's refusals of an output its base lacks, read from the registry."""
    with pytest.raises(ValueError, match=r"^output 'base' needs a free or prescribed base \("):
        paper_scene(2, outputs=("phi", "base"))
    with pytest.raises(ValueError, match=r"^output 'drive' needs a prescribed base \("):
        paper_scene(2, outputs=("phi", "drive")).with_(base=BASES["free"])
    check_output_bases(("phi", "tip_deflection"), "pinned")  # every base has them


@pytest.mark.parametrize("model", MODEL_NAMES)
@pytest.mark.parametrize("base", BASE_KINDS)
def test_models_refuse_exactly_what_the_registry_says_they_lack(model, base):
    """For every model, base and output the base has: the model's check before any work
    (``check_base``) refuses the output iff the registry says the model does not output it
    (a model that has no such base refuses every output: skipped)."""
    try:
        m = get_model(model)
    except ValueError as exc:  # exudyn not installed
        pytest.skip(str(exc))
    scene = paper_scene(2).with_(base=BASES[base])
    try:
        m.check_base(scene)
    except ValueError:
        pytest.skip(f"{model} has no {base} base")
    for out in OUTPUTS:
        if base not in {b for q in QUANTITY_TABLE if q.output == out for b in q.bases}:
            continue
        has = all(QUANTITY[q].provided_by(model, base) for q in quantities_of((out,)))
        try:
            m.check_base(scene.with_(outputs=("phi", out)))
            refused = False
        except ValueError:
            refused = True
        assert refused == (not has), (model, base, out)


def _traj(rows: list[tuple]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=["case", "model", "quantity", "t", "k", "value"])


def test_peak_hinge_moments_from_every_model_with_the_window_beside():
    """Peaks over the output times from every model's hinge_moment (full, reduced, rigid and
    exudyn alike), the lock windows' peak beside where exudyn's lock records carry one, and
    a model with lock records only gives theirs."""
    rows = []
    for model, scale in (("full", 1.0), ("reduced", 2.0), ("rigid", 3.0), ("exu", 4.0)):
        for t, m0, m1 in ((0.0, 1.0, -5.0), (0.1, -2.0, 7.0), (0.2, 0.5, 6.0)):
            rows += [("c", model, "hinge_moment", t, 0, scale * m0)]
            rows += [("c", model, "hinge_moment", t, 1, scale * m1)]
        rows.append(("c", model, "phi", 0.0, 1, 99.0))
    events = pd.DataFrame(
        {
            "case": ["c", "c", "c"],
            "model": ["exu", "exu", "solo"],
            "label": ["lock hinge 1"] * 3,
            "hinge": [1, 1, 1],
            "peak_moment": [30.0, 31.0, 12.0],
        }
    )
    models = [{"label": m, "model": m} for m in ("full", "reduced", "rigid")]
    models += [{"label": "exu", "model": "exudyn"}, {"label": "solo", "model": "exudyn"}]
    peaks = peak_hinge_moments(_traj(rows), events, models)
    got = {(r.model, r.hinge): (r.peak_moment, r.source, r.window_peak) for r in peaks.itertuples()}
    assert got[("full", 0)][:2] == (2.0, "hinge_moment")
    assert got[("full", 1)][:2] == (7.0, "hinge_moment")
    assert got[("reduced", 1)][0] == 14.0
    assert got[("rigid", 1)][0] == 21.0
    assert got[("exu", 1)] == (28.0, "hinge_moment", 31.0)
    assert np.isnan(got[("exu", 0)][2]) and np.isnan(got[("full", 1)][2])
    assert got[("solo", 1)] == (12.0, "lock window", 12.0)
    assert len(peaks) == 9


def test_peak_hinge_moments_skips_models_without_the_quantity(monkeypatch):
    """A model label whose registry name lacks hinge_moment is left out (none does today:
    a made-up model name stands in); no hinge_moment and no lock records: empty."""
    rows = [("c", "mine", "hinge_moment", 0.0, 0, 5.0), ("c", "full", "hinge_moment", 0.0, 0, 1.0)]
    models = [{"label": "mine", "model": "not-a-model"}, {"label": "full", "model": "full"}]
    lacking = dataclasses.replace(QUANTITY["hinge_moment"], missing_in=("not-a-model",))
    monkeypatch.setitem(QUANTITY, "hinge_moment", lacking)
    peaks = peak_hinge_moments(_traj(rows), pd.DataFrame(), models)
    assert list(peaks["model"]) == ["full"]
    assert peak_hinge_moments(_traj([]), pd.DataFrame(), models).empty


def test_report_names_the_models_whose_hinge_moment_was_not_recorded():
    """Lock records only (the study's outputs without hinge_moment): the table gives their
    peak, and the report says which models would give theirs with hinge_moment recorded."""
    from rodval.report.study_report import peak_moment_lines

    events = pd.DataFrame(
        {"case": ["c"], "model": ["exu"], "label": ["lock hinge 1"], "hinge": [1],
         "peak_moment": [12.0]}
    )  # fmt: skip
    models = [{"label": "full", "model": "full"}, {"label": "exu", "model": "exudyn"}]
    tables = {"trajectories": _traj([("c", "full", "phi", 0.0, 1, 0.1)])}
    lines = peak_moment_lines(tables, events, models, lambda d: d)
    assert "lock window" in lines[1]
    assert "`full`, `exu` are not recorded" in lines[2]


@pytest.mark.parametrize("model", MODEL_NAMES)
@pytest.mark.parametrize("base", BASE_KINDS)
def test_every_model_outputs_what_the_registry_says(model, base):
    """A run asked for every output its base has (those the model has, ``provided_by``)
    returns exactly the registry's trajectory quantities of them, plus the energy audit's
    (``audit``) beside "energy"; the k of each is ``quantity_k``."""
    try:
        m = get_model(model)
    except ValueError as exc:  # exudyn not installed
        pytest.skip(str(exc))
    scene = paper_scene(2, t_end=0.01, times=np.linspace(0.0, 0.01, 3)).with_(base=BASES[base])
    try:
        m.check_base(scene)
    except ValueError:
        pytest.skip(f"{model} has no {base} base")
    outputs = tuple(
        out
        for out in OUTPUTS
        if all(QUANTITY[q].provided_by(model, base) for q in quantities_of((out,)))
    )
    tr = simulate(scene.with_(outputs=outputs), model)
    assert tr.success, tr.stats.message
    audit = {q.name for q in QUANTITY_TABLE if q.audit}
    assert set(quantities_of(outputs)) <= set(tr.values)
    assert set(tr.values) - set(quantities_of(outputs)) <= audit
    for q in tr.values:
        assert list(tr.k_index[q]) == list(quantity_k(q, 2)), q
