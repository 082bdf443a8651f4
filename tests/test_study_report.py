"""The report: figures that are real images, GitHub pipe tables, rebuilt from the CSVs alone."""

import re
import shutil
import subprocess
import sys

import matplotlib.image as mpimg
import pytest
from study_helpers import write_study

from rodval.study import load_study, run_study

SEPARATOR = re.compile(r"^\|(\s*:?-+:?\s*\|)+$")


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("report")
    path = write_study(tmp, grid="scene.t_end = [0.1, 0.2]")
    run_study(load_study(path), tmp / "out", workers=2, progress=False)
    return tmp / "out"


def _tables(markdown: str) -> list[list[str]]:
    tables, current = [], []
    for line in markdown.splitlines():
        if line.startswith("|"):
            current.append(line)
        elif current:
            tables.append(current)
            current = []
    return tables + ([current] if current else [])


def test_figures_exist_and_are_not_blank(study_dir):
    report = (study_dir / "report.md").read_text()
    linked = re.findall(r"\(figures/([^)]+\.png)\)", report)
    names = {
        "discrepancy_vs_n.png",
        "discrepancy_vs_horizon.png",
        "runtime_vs_n.png",
        "speedup_vs_n.png",
        "history_n2_t_end0.1.png",
        "configurations_n2_t_end0.1.png",
    }
    assert names <= set(linked)
    for name in linked:
        png = study_dir / "figures" / name
        assert png.stat().st_size > 10_000, name
        img = mpimg.imread(png)[..., :3]
        assert img.std() > 0.02, f"{name} looks blank"


def test_markdown_tables_are_github_pipe_tables(study_dir):
    for name in ("report.md", "discrepancies.md", "runtime.md", "trajectories.md"):
        tables = _tables((study_dir / name).read_text())
        assert tables, name
        for table in tables:
            assert SEPARATOR.match(table[1]), (name, table[1])
            widths = {len(re.findall(r"(?<!\\)\|", row)) for row in table}
            assert len(widths) == 1, (name, table[0])  # same number of cells in every row
            assert len(table) >= 3


def test_report_is_rebuilt_from_the_saved_tables_only(study_dir, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(study_dir, copy)
    shutil.rmtree(copy / "cases")  # no case records, no study file
    (copy / "study.toml").unlink()
    shutil.rmtree(copy / "figures")
    (copy / "report.md").unlink()
    res = subprocess.run(
        [sys.executable, "-m", "rodval", "report", str(copy)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    assert (copy / "report.md").read_text() == (study_dir / "report.md").read_text()
    assert sorted(p.name for p in (copy / "figures").iterdir()) == sorted(
        p.name for p in (study_dir / "figures").iterdir()
    )


def test_report_of_a_folder_without_tables_exits_2(tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "rodval", "report", str(tmp_path)], capture_output=True, text=True
    )
    assert res.returncode == 2 and "not a study folder" in res.stderr


def _events(rows):
    import pandas as pd

    return pd.DataFrame(
        [{"case": "base", "model": m, "t": t, "label": lab, **kw} for m, t, lab, kw in rows]
    )


def test_repeated_event_labels_are_paired_in_order():
    """A stop's k-th contact is compared with the reference's k-th, not its first."""
    from rodval.report.study_report import event_discrepancies

    events = _events(
        [
            ("ref", 0.10, "stop hinge 1 on", {}),
            ("ref", 0.30, "stop hinge 1 on", {}),
            ("full", 0.11, "stop hinge 1 on", {}),
            ("full", 0.32, "stop hinge 1 on", {}),
        ]
    )
    disc = event_discrepancies(events, "ref")
    assert disc["label"].tolist() == ["stop hinge 1 on", "stop hinge 1 on #2"]
    assert disc["dt"].tolist() == pytest.approx([0.01, 0.02])


@pytest.mark.parametrize(
    "ref_after, model_after, grazing",
    [(50.0, 50.0, ""), (99.5, 50.0, "the reference's"), (50.0, 99.5, "its")],
)
def test_a_grazing_lock_is_not_compared_pointwise(ref_after, model_after, grazing):
    """A lock whose rigid-panel lock takes less than 1 % of the kinetic energy (the hinge
    creeps onto the latch angle) is marked not comparable, whichever model grazes."""
    from rodval.report.study_report import event_discrepancies

    lock = {"rigid_kinetic_before": 100.0, "kinetic_before": 100.0, "impulse": 1.0}
    events = _events(
        [
            ("ref", 0.5, "latch hinge 1", {**lock, "rigid_kinetic_after": ref_after}),
            ("full", 0.5, "latch hinge 1", {**lock, "rigid_kinetic_after": model_after}),
        ]
    )
    why = event_discrepancies(events, "ref")["not_comparable"].iloc[0]
    if grazing:
        assert why.startswith(f"grazing: {grazing} rigid-panel lock takes 0.50%")
    else:
        assert why == ""


def test_a_quantity_without_a_relative_discrepancy_keeps_its_columns():
    """A quantity whose reference is zero throughout (the loads' work in a deployment without
    loads) has max_abs but no max_rel; the Discrepancies table keeps both columns, the second
    blank, instead of failing on the missing one (the deployment studies did, once exudyn
    output the work)."""
    import numpy as np
    import pandas as pd

    from rodval.report.study_summary import _discrepancies

    disc = pd.DataFrame(
        {
            "case": ["a", "a"],
            "model": ["full", "full"],
            "quantity": ["phi", "work"],
            "max_abs": [0.1, 0.0],
            "max_rel": [0.01, np.nan],
            "status": ["ok", "ok"],
        }
    )
    table = "\n".join(_discrepancies(disc, pd.DataFrame(), "exudyn", 2, []))
    assert "work max_abs" in table and "work max_rel" in table
