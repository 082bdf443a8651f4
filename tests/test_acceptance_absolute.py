"""Absolute requirements in a study's [acceptance] (issue 47): [[acceptance.require]] bounds a
model's own lock times, lock impulses, peak hinge moments and final state, not only its gaps
to the reference; each requirement one JUnit test case, each breach one line naming the case,
the model, the hinge or quantity, the figure and the bound; bad keys refused when the study
file is read.

The evaluator on synthetic tables (fast); the shipped stiff-panel deployment
(studies/deployment_stiff_panels.toml) as a gate that passes on its defaults and breaks, naming
the lock, when hinge 2's spring is 20 % stiffer (slow)."""

from __future__ import annotations

import re
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
import pytest
from scenes import latch3_toml

from rodval.analysis.events import events_frame
from rodval.cli import main
from rodval.report.acceptance import acceptance_checks, breach_lines
from rodval.study import load_study
from rodval.study.acceptance import acceptance_spec
from rodval.study.toml_text import toml_text

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "studies" / "deployment_stiff_panels.toml"


def _events():
    """Two runs of one case "c": full locks hinges 2 then 1; reduced only hinge 2."""
    return events_frame(
        [
            (
                {"case": "c", "model": "full"},
                [
                    {"t": 0.6, "label": "latch hinge 2", "impulse": -47.8},
                    {"t": 2.2, "label": "latch hinge 1", "impulse": -121.0},
                ],
            ),
            ({"case": "c", "model": "reduced"}, [{"t": 0.59, "label": "latch hinge 2"}]),
        ]
    )


def _tables():
    """cases (latches on hinges 1 and 2, horizon 2.5 s), full's trajectories and both runs'
    runtime rows (reached t_end; full's recorded peaks)."""
    traj = pd.DataFrame(
        {
            "case": "c",
            "model": "full",
            "t": [0.0, 0.0, 1.0, 1.0, 2.5, 2.5, 0.0, 2.5],
            "quantity": ["hinge_moment"] * 6 + ["phi"] * 2,
            "k": [0, 1, 0, 1, 0, 1, 4, 4],
            "value": [10.0, -5.0, -310.0, 40.0, 20.0, 2.0, 3.09, 0.02],
        }
    )
    return {
        "cases": pd.DataFrame({"case": ["c"], "horizon": [2.5], "latch_hinges": ["[1, 2]"]}),
        "discrepancies": pd.DataFrame(columns=["case", "model", "quantity", "status"]),
        "runtime": pd.DataFrame(
            {
                "case": ["c", "c"],
                "model": ["full", "reduced"],
                "status": "success",
                "t_reached": 2.5,
                # the runs' peaks as runtime.csv records them (SolverStats.peaks), the same
                # as full's trajectories above
                "peaks": [
                    '{"hinge_moment": [{"k": 0, "peak": 310.0, "t": 1.0}, '
                    '{"k": 1, "peak": 40.0, "t": 1.0}]}',
                    None,
                ],
            }
        ),
        "trajectories": traj,
    }


def _meta(requires):
    return {
        "reference": "full",
        "models": [{"label": "full"}, {"label": "reduced"}],
        "acceptance": {"valid": False, "bounds": [], "events": [], "requires": requires},
    }


def test_each_requirement_is_one_check_and_each_breach_one_line_with_figure_and_bound():
    requires = [
        {
            "model": "full",
            "locked_by": 2.0,
            "lock_time": [{"hinge": 2, "min": 0.5, "max": 0.7}, {"hinge": 1, "max": 2.1}],
            "impulse": [{"hinge": 1, "max": 100.0}, {"hinge": 2, "min": 40.0}],
            "peak_hinge_moment": {"max": 300.0},
            "final": [{"quantity": "phi", "k": 4, "min": -0.01, "max": 0.01}],
        },
        {"model": "reduced", "locked_by": 5.0, "lock_time": [{"hinge": 1, "max": 3.0}]},
    ]
    checks = acceptance_checks(_meta(requires), _tables(), _events())
    assert {c.classname for c in checks} == {"acceptance.require"}
    assert [c.name for c in checks] == [
        "c: full: every latch locked by 2 s",
        "c: full: hinge 2 lock time",
        "c: full: hinge 1 lock time",
        "c: full: hinge 1 lock impulse",
        "c: full: hinge 2 lock impulse",
        "c: full: peak |hinge_moment| (every hinge)",
        "c: full: final phi[4]",
        "c: reduced: every latch locked by 5 s",
        "c: reduced: hinge 1 lock time",
    ]
    assert breach_lines(checks) == [
        "acceptance breached: c: full: every latch locked by 2 s: hinge 1 locked at t = 2.2 s > 2 s",
        "acceptance breached: c: full: hinge 1 lock time: t = 2.2 s > max 2.1 s",
        "acceptance breached: c: full: hinge 1 lock impulse: |impulse| = 121 N m s > max 100 N m s",
        "acceptance breached: c: full: peak |hinge_moment| (every hinge): 310 N m at t = 1 s "
        "(hinge 0) > max 300 N m",
        "acceptance breached: c: full: final phi[4]: phi[4] at t = 2.5 s = 0.02 rad > max 0.01 rad",
        "acceptance breached: c: reduced: every latch locked by 5 s: hinge 1 never locked > 5 s",
        "acceptance breached: c: reduced: hinge 1 lock time: no lock (required in [-inf, 3] s)",
    ]


def test_requirements_that_hold_pass_and_one_hinge_peak_reads_that_hinge_only():
    requires = [
        {
            "model": "full",
            "locked_by": 2.2,
            "lock_time": [{"hinge": 1, "min": 2.19, "max": 2.21}],
            "impulse": [{"hinge": 2, "min": 47.0, "max": 48.0}],
            "peak_hinge_moment": {"hinge": 1, "max": 40.0},
            "final": [{"quantity": "phi", "k": 4, "max": 0.03}],
        }
    ]
    checks = acceptance_checks(_meta(requires), _tables(), _events())
    assert len(checks) == 5 and all(c.held for c in checks), [c.failure for c in checks]
    assert checks[3].name == "c: full: peak |hinge_moment| (hinge 1)"


def test_a_final_state_the_run_did_not_reach_breaks_the_requirement():
    tables = _tables()
    tables["trajectories"] = tables["trajectories"][tables["trajectories"]["t"] < 2.0]
    requires = [{"model": "full", "final": [{"quantity": "phi", "k": 4, "max": 1.0}]}]
    (check,) = acceptance_checks(_meta(requires), tables, _events())
    assert check.failure == "the output ends at t = 0 s, not t_end = 2.5 s"


# a latched three-rod study read (never run) for the read-time checks
SCENE = latch3_toml("scene", outputs=("phi", "energy"))
STUDY = """
[study]
name = "latched"
reference = "full"

{scene}
[models.full]
[models.reduced]

[acceptance]
{acceptance}
"""


def _spec(acceptance: str):
    """acceptance_spec on STUDY's [acceptance] with its labels, outputs and scene."""
    doc = tomllib.loads(STUDY.format(scene=SCENE, acceptance=acceptance))
    from rodval.study import study_from_dict

    base = tomllib.loads(STUDY.format(scene=SCENE, acceptance="valid = true"))
    spec = study_from_dict(base, "s.toml")
    quantities = {"phi", "kinetic", "potential", "energy"}
    return acceptance_spec(
        doc["acceptance"],
        ["full", "reduced"],
        "full",
        quantities,
        "s.toml:",
        scenes=[c.scene for c in spec.cases],
    )


REQ = '[[acceptance.require]]\nmodel = "{model}"\n{items}'


@pytest.mark.parametrize(
    "items, words",
    [
        ("", r"acceptance\.require\[0\]': needs at least one of locked_by, lock_time, impulse"),
        ("foo = 1", r"acceptance\.require\[0\]\.foo': unknown key"),
        ("locked_by = -1.0", r"acceptance\.require\[0\]\.locked_by': must be a finite number >= 0"),
        (
            "lock_time = { hinge = 3, max = 1.0 }",
            r"acceptance\.require\[0\]\.lock_time\.hinge': must be a hinge every case latches "
            r"\(1, 2\), got 3",
        ),
        (
            "lock_time = { hinge = 1 }",
            r"acceptance\.require\[0\]\.lock_time': needs min, max or both",
        ),
        (
            "lock_time = { hinge = 1, min = 0.5, max = 0.4 }",
            r"acceptance\.require\[0\]\.lock_time\.min': must be <= max = 0\.4, got 0\.5",
        ),
        (
            "impulse = [{ hinge = 1, max = 1.0 }, { hinge = 2, max = inf }]",
            r"acceptance\.require\[0\]\.impulse\[1\]\.max': must be a finite number >= 0",
        ),
        (
            "impulse = { hinge = 1, mx = 1.0 }",
            r"acceptance\.require\[0\]\.impulse\.mx': is not a key of impulse \(allowed: hinge, "
            r"max, min\)",
        ),
        (
            "peak_hinge_moment = 300.0",
            r"acceptance\.require\[0\]\.peak_hinge_moment': needs \"hinge_moment\" among the "
            r"\[scene\] outputs: add it there",
        ),
        (
            'final = { quantity = "x", k = 3, max = 1.0 }',
            r"acceptance\.require\[0\]\.final\.quantity': must be a quantity the cases output "
            r"\(energy, kinetic, phi, potential\), got 'x': add \"x\" to the \[scene\] outputs",
        ),
        (
            'final = { quantity = "phi", k = 0, max = 1.0 }',
            r"acceptance\.require\[0\]\.final\.k': must be an integer in 1\.\.3, got 0",
        ),
        ('final = "phi"', r"acceptance\.require\[0\]\.final': must be a table or a non-empty"),
    ],
)
def test_bad_requirements_are_refused_in_one_line_naming_the_key(items, words):
    with pytest.raises(ValueError, match=words) as info:
        _spec(REQ.format(model="full", items=items))
    assert "\n" not in str(info.value)


def test_a_requirement_names_any_model_the_reference_included_and_no_other():
    spec = _spec(REQ.format(model="full", items="locked_by = 0.8"))
    assert spec["requires"] == [{"model": "full", "locked_by": 0.8}]
    with pytest.raises(ValueError, match=r"require\[0\]\.model': must be one of the model labels"):
        _spec(REQ.format(model="exudyn", items="locked_by = 0.8"))


def test_the_study_file_reader_checks_requirements_before_any_work(tmp_path):
    """Through load_study: a requirement on an output the cases lack is refused."""
    path = tmp_path / "s.toml"
    path.write_text(
        STUDY.format(
            scene=SCENE, acceptance=REQ.format(model="reduced", items="peak_hinge_moment = 1.0")
        )
    )
    with pytest.raises(ValueError, match=r"add it there"):
        load_study(path)


def _kappa2_variant(tmp_path: Path, kappa2: float) -> Path:
    """The shipped stiff-panel study with hinge 2's spring ``kappa2`` N m/rad (shipped: 50),
    written beside the test; everything else as shipped."""
    doc = tomllib.loads(SHIPPED.read_text())
    assert doc["scene"]["chain"]["kappa"][2] == 50.0
    doc["scene"]["chain"]["kappa"][2] = kappa2
    path = tmp_path / "kappa2.toml"
    path.write_text(toml_text(doc))
    return path


def _gate(path: Path, out: Path, junit: Path) -> int:
    return main(["study", str(path), "--out", str(out), "--no-progress", "--junit", str(junit)])


@pytest.mark.slow
def test_the_shipped_gate_passes_on_its_defaults_and_names_the_lock_a_stiffer_spring_moves(
    tmp_path, capsys
):
    """studies/deployment_stiff_panels.toml as shipped: exit 0, every check held; with hinge
    2's spring 20 % stiffer (50 -> 60 N m/rad): exit 1, a line naming hinge 2's lock, its
    time and the bound it left (measured: 0.5524 s against [0.59571, 0.59771] s), one line
    per JUnit failure."""
    ok = _gate(SHIPPED, tmp_path / "ok", tmp_path / "ok.xml")
    out = capsys.readouterr().out
    assert ok == 0, out
    assert "acceptance breached" not in out
    root = ET.parse(tmp_path / "ok.xml").getroot()
    assert root.findall(".//failure") == [] and len(root.findall(".//testcase")) == 11
    changed = _gate(_kappa2_variant(tmp_path, 60.0), tmp_path / "bad", tmp_path / "bad.xml")
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("acceptance breached")]
    assert changed == 1
    hinge2 = [x for x in lines if ": exudyn: hinge 2 lock time: " in x]
    assert len(hinge2) == 1, lines
    t = float(re.search(r"t = ([\d.]+) s < min 0\.59571 s$", hinge2[0]).group(1))
    assert t < 0.59571 - 0.02  # tens of ms early: far outside the 1 ms window
    failures = ET.parse(tmp_path / "bad.xml").getroot().findall(".//failure")
    assert len(failures) == len(lines)
    # the full model follows the reference through the changed deployment: a change of the
    # design breaks the absolute requirements, not the bounds against the reference
    assert not any(": full vs exudyn" in x for x in lines), lines
