"""Modes inside studies: a [modes] table asks every model for its first modes; the tables
hold them, paired by shape with the reference's, and the report shows them."""

import re

import numpy as np
import pandas as pd
import pytest

from rodval import Chain, Scene, paper_scene
from rodval.models.observation.linear_modes import modes
from rodval.study import load_study, run_study

STUDY = """
[study]
name = "modes-tiny"
reference = "full"

[scene]
based_on = "paper"
t_end = 0.1
times = {{ num = 3 }}

[models.full]
[models.reduced]

{modes}

[grid]
scene.n = [2, 3]
"""


def test_study_modes_tables_and_report(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text(STUDY.format(modes="[modes]\ncount = 4"))
    run_study(load_study(path), tmp_path / "out", workers=1, progress=False)
    out = tmp_path / "out"
    freq = pd.read_csv(out / "modes.csv")
    # the table holds what the modal analysis gives for that case and model
    direct = modes(paper_scene(3, t_end=0.1), "full", count=4)
    got = freq[(freq["case"] == "n=3") & (freq["model"] == "full")].sort_values("mode")
    np.testing.assert_allclose(got["omega_rad_s"], direct.omega, rtol=1e-12)
    mac = pd.read_csv(out / "mac.csv")
    hinge_modes = mac[mac["mode_b"].notna()]  # the reduced model has only the n hinge modes
    assert len(hinge_modes) == 2 + 3 and (hinge_modes["mac"] > 0.999).all()
    assert (hinge_modes["rel_gap"].abs() < 1e-3).all()
    report = (out / "report.md").read_text()
    assert "## Modes" in report
    figs = re.findall(r"\(figures/(modes_[^)]+\.png)\)", report)
    assert figs and all((out / "figures" / f).stat().st_size > 10_000 for f in figs)


@pytest.mark.parametrize(
    "table, key",
    [
        ("[modes]\ncount = 0", "modes.count"),
        ("[modes]\nabout = 'here'", "modes.about"),
        ("[modes]\nnumber = 3", "modes.number"),
    ],
)
def test_bad_modes_tables_are_refused(tmp_path, table, key):
    path = tmp_path / "m.toml"
    path.write_text(STUDY.format(modes=table))
    with pytest.raises(ValueError, match=re.escape(key)):
        load_study(path)


def test_modes_of_a_scene_without_a_modal_form_are_recorded_not_fatal():
    from rodval.study.worker import case_modes

    scene = Scene(chain=Chain.uniform(2), t_end=0.1)
    rec = case_modes(scene, {"model": "nosuch", "options": {}}, {"count": 2, "about": "initial"})
    assert "modes_error" in rec and "modes" not in rec


def test_a_free_spacecraft_study_tables_its_flexible_modes_numbered_as_mac(tmp_path):
    """Issue 46: on a free base the study's modes.csv listed the three rigid motions as modes
    1-3 while mac.csv numbered the flexible modes from 1 (rodval modes writes the flexible
    ones only); both now number the flexible modes from 1, as the modal analysis gives them."""
    from rodval.core.base import Base
    from rodval.models.observation.free_modes import free_modes

    study = STUDY.replace("[models.reduced]\n", "").replace(
        "[grid]\nscene.n = [2, 3]",
        '[scene.base]\nkind = "free"\nmass = 50.0\ninertia = 20.0\nhinge_offset = [0.5, 0.0]\n'
        "[grid]\nscene.n = [2]",
    )
    path = tmp_path / "m.toml"
    path.write_text(study.format(modes="[modes]\ncount = 3"))
    run_study(load_study(path), tmp_path / "out", workers=1, progress=False)
    freq = pd.read_csv(tmp_path / "out" / "modes.csv").sort_values("mode")
    scene = paper_scene(2, t_end=0.1).with_(
        base=Base(kind="free", mass=50.0, inertia=20.0, hinge_offset=(0.5, 0.0))
    )
    flexible = free_modes(scene, count=3).flexible()
    assert freq["mode"].tolist() == list(range(1, flexible.count + 1))
    np.testing.assert_allclose(freq["omega_rad_s"], flexible.omega, rtol=1e-12)
