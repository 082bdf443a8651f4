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


def test_the_study_file_is_named_relative_to_the_study_folder(study_dir):
    """The header names the study file by its path from the folder report.md lies in (the
    study was run from another folder: a path relative to that one would not resolve)."""
    report = (study_dir / "report.md").read_text()
    assert "Study file: `../tiny.toml` (copied to `study.toml`)" in report


def _latched_study(**extra):
    """A one-case latched deployment of the native models (a few seconds)."""
    return {
        "study": {"name": "latched", "reference": "full"},
        "scene": {
            "n": 3,
            "t_end": 0.6,
            "times": {"num": 31},
            "outputs": ["phi", "dphi"],
            "chain": {"l": 1.0, "m": 3.0, "EI": 5e4, "mu": 0.5, "kappa": [1e5, 50.0, 50.0]},
            "initial": {"phi": [0.0, 3.0915926535897933, 0.0]},
            "latches": [{"hinge": 2, "angle": 0.0}],
        },
        "models": {"full": {}, "reduced": {}},
        **extra,
    }


def test_a_one_case_report_opens_with_the_answer_and_drops_constant_columns(tmp_path):
    """The report's first section is the Answer (a paragraph and one short table, model by
    model); no table repeats a column that is the same throughout the study (case, n,
    horizon, reference), the header says their values once; the sentence that called later
    lock gaps "different motions, not model error" without measuring it is gone."""
    from rodval.study import StudySpec

    run_study(StudySpec.from_dict(_latched_study()), tmp_path / "out", workers=1, progress=False)
    report = (tmp_path / "out" / "report.md").read_text()
    assert report.splitlines()[2] == "## Answer"
    answer = report.split("## Study")[0]
    assert "`reduced` is " in answer and "it agrees with `full` until" in answer
    assert "whether the motion is predictable is not measured" in answer
    assert (
        "Left out of the tables as the same throughout: case = base, n = 3, horizon = 0.6 s"
        in report
    )
    for table in _tables(report):
        head = [c.strip() for c in table[0].strip("|").split("|")]
        assert not {"case", "n", "horizon", "reference"} & set(head), head
    assert "not model error" not in report


def _sampled_study(count: int) -> dict:
    return {
        **_latched_study(),
        "sample": {
            "design": "sobol",
            "count": count,
            "seed": 7,
            "keys": {"scene.chain.kappa": {"dist": "uniform", "low": 40.0, "high": 60.0}},
        },
    }


def test_a_sampled_study_report_does_not_grow_with_its_samples(tmp_path):
    """A sampled study's report gives distributions and worst cases, not per-case tables:
    four times the samples, the same report length (it was 1,704 lines for 200 samples)."""
    from rodval.study import StudySpec

    sizes, reports = {}, {}
    for count in (4, 16):
        spec = StudySpec.from_dict(_sampled_study(count))
        run_study(spec, tmp_path / str(count), workers=2, progress=False)
        reports[count] = (tmp_path / str(count) / "report.md").read_text()
        sizes[count] = len(reports[count].splitlines())
    assert sizes[16] <= sizes[4] + 2, sizes
    assert "## Answer" in reports[16] and "valid in" in reports[16]


def test_a_long_value_table_is_a_link_a_short_one_is_printed(study_dir):
    """The report cases' values at the report times: printed when short, else linked to
    trajectories.md (the same table) and trajectories.csv, both in the study folder."""
    import pandas as pd

    from rodval.report.study_figures import INLINE_VALUE_ROWS, values_at_report_times

    short = pd.DataFrame({"quantity": ["phi"] * 3, "k": [1, 1, 1], "t": [0.0, 0.1, 0.2]})
    assert "| phi" in "\n".join(values_at_report_times(short))
    long = pd.concat([short] * (INLINE_VALUE_ROWS // 3 + 1), ignore_index=True)
    (line,) = values_at_report_times(long)
    assert f"{len(long)} rows" in line and "(trajectories.md)" in line
    assert "(trajectories.csv)" in line and "| phi" not in line
    assert values_at_report_times(short.iloc[:0]) == []
    report = (study_dir / "report.md").read_text()
    for name in re.findall(r"\]\((trajectories\.(?:md|csv))\)", report):
        assert (study_dir / name).is_file(), name
