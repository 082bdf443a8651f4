"""Lock events in a study's [acceptance] (issue 37): [[acceptance.event]] bounds on the lock
times and impulses of a model against the reference's, all_latched, and the runs' energy and
momentum residuals; each check one JUnit test case, each breach one line naming the case, the
pair, the lock and the figure; bad keys refused when the study file is read."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pandas as pd
import pytest
from scenes import latch3_toml

from rodval.analysis.events import events_frame, lock_comparison
from rodval.cli import main
from rodval.report.acceptance import acceptance_checks
from rodval.study import load_study

# the three-rod latched deployment (benchmarks/exudyn_speed.py latch3_scene), two cases
SCENE = latch3_toml("scene", outputs=("phi", "energy"))
STUDY = """
[study]
name = "latched"
reference = "full"

{scene}
[models.full]
[models.reduced]

[grid]
"scene.chain.EI" = [1e5, 2e5]

[acceptance]
{acceptance}
"""


def _study(tmp_path, name: str, acceptance: str):
    path = tmp_path / f"{name}.toml"
    path.write_text(STUDY.format(scene=SCENE, acceptance=acceptance))
    return path


def _run(tmp_path, name: str, acceptance: str, out) -> int:
    junit = tmp_path / f"{name}.xml"
    return main(
        [
            "study",
            str(_study(tmp_path, name, acceptance)),
            "--out",
            str(out),
            "--no-progress",
            "--workers",
            "1",
            "--junit",
            str(junit),
        ]
    )


LOOSE = '[[acceptance.event]]\nmodel = "reduced"\nlock_time = 1.0\nimpulse = 10.0\n'


@pytest.fixture(scope="module")
def latched(tmp_path_factory):
    """The study run once (a loose event bound): later runs with other [acceptance] tables
    resume it without rerunning a case."""
    tmp = tmp_path_factory.mktemp("latched")
    assert _run(tmp, "first", LOOSE, tmp / "out") == 0
    return tmp / "out"


def test_a_lock_time_bound_passes_above_the_gap_and_fails_below_it(latched, tmp_path, capsys):
    out = latched
    assert _run(tmp_path, "loose", LOOSE, out) == 0
    capsys.readouterr()
    events = pd.read_csv(out / "events.csv")
    events["case"] = events["case"].astype(str)
    comp = lock_comparison(events, "reduced", "full")
    kept = comp[comp["not_comparable"].fillna("") == ""]
    assert not kept.empty and (comp["t_m"].notna() & comp["t_ref"].notna()).all()
    worst = kept.loc[kept["dt"].abs().idxmax()]
    gap = abs(float(worst["dt"]))
    assert gap > 0
    # the gap is the difference of the two models' recorded lock times
    t = events.set_index(["case", "model", "label"])["t"]
    assert gap == pytest.approx(
        abs(
            t[(worst["case"], "reduced", worst["label"])]
            - t[(worst["case"], "full", worst["label"])]
        )
    )
    ok = ET.parse(tmp_path / "loose.xml").getroot()
    names = [tc.get("name") for tc in ok.findall(".//testcase")]
    assert {tc.get("classname") for tc in ok.findall(".//testcase")} == {"acceptance.events"}
    assert len(names) == 2 and ok.findall(".//failure") == []

    tight = f"{gap * 0.9:.6g}"
    code = _run(
        tmp_path, "tight", f'[[acceptance.event]]\nmodel = "reduced"\nlock_time = {tight}\n', out
    )
    stdout = capsys.readouterr().out
    assert code == 1
    lines = [x for x in stdout.splitlines() if x.startswith("acceptance breached")]
    assert any(
        line.startswith(f"acceptance breached: {worst['case']}: reduced vs full")
        and f"{worst['label']} lock time |dt| = {gap:.3g} s > {float(tight):g} s" in line
        for line in lines
    ), lines
    bad = ET.parse(tmp_path / "tight.xml").getroot()
    assert bad.find(".//failure") is not None
    # not-comparable locks are skipped from the bound and named in the check
    for tc in bad.findall(".//testcase"):
        case = tc.get("name").split(":")[0]
        skipped = comp[(comp["case"] == case) & (comp["not_comparable"].fillna("") != "")]
        if len(skipped):
            assert "not comparable pointwise: skipped" in tc.get("name")


def test_all_latched_and_residuals_are_checked_per_model_and_run(latched, tmp_path, capsys):
    out = latched
    keys = "all_latched = 1.0\nenergy_residual = 1.0\nmomentum_residual = 1.0\n"
    code = _run(tmp_path, "resid", keys, out)
    capsys.readouterr()
    root = ET.parse(tmp_path / "resid.xml").getroot()
    cases = {tc.get("classname") for tc in root.findall(".//testcase")}
    assert cases == {"acceptance.events", "acceptance.residuals"}
    names = [tc.get("name") for tc in root.findall(".//testcase")]
    assert "full: all latched in >= 1 of the cases" in names
    assert "reduced: all latched in >= 1 of the cases" in names
    runtime = pd.read_csv(out / "runtime.csv")
    # 2 cases x 2 models x (energy + momentum) + 2 models all_latched
    assert len(names) == 2 * 2 * 2 + 2
    assert code == 0, [f.get("message") for f in root.findall(".//failure")]
    # a tight energy bound breaks on the run with the largest residual, naming it
    worst = runtime.loc[runtime["energy_residual"].abs().idxmax()]
    tight = f"{abs(float(worst['energy_residual'])) * 0.5:.6g}"
    assert _run(tmp_path, "tight", f"energy_residual = {tight}\n", out) == 1
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("acceptance breached")]
    assert f"acceptance breached: {worst['case']}: {worst['model']} energy_residual: " in "\n".join(
        lines
    )


def _lock(model, t, label="latch hinge 1", **kw):
    return (
        {"case": "c", "model": model},
        [
            {
                "t": t,
                "label": label,
                "impulse": 1.0,
                "kinetic_before": 10.0,
                "kinetic_after": 5.0,
                **kw,
            }
        ],
    )


def _meta(acceptance):
    return {
        "reference": "full",
        "models": [{"label": "full"}, {"label": "reduced"}],
        "acceptance": {"valid": False, "bounds": [], "events": [], **acceptance},
    }


def _tables(runtime=None):
    return {
        "cases": pd.DataFrame({"case": ["c"], "latch_hinges": ["[1, 2]"]}),
        "discrepancies": pd.DataFrame(columns=["case", "model", "quantity", "status"]),
        "runtime": runtime if runtime is not None else pd.DataFrame(columns=["case", "model"]),
    }


def test_missing_and_not_comparable_locks_and_unaudited_runs():
    events = events_frame(
        [
            (
                {"case": "c", "model": "full"},
                [
                    {"t": 0.1, "label": "latch hinge 1", "impulse": 1.0, "kinetic_before": 10.0},
                    {"t": 0.5, "label": "latch hinge 2", "impulse": 1.0, "kinetic_before": 10.0},
                ],
            ),
            (
                {"case": "c", "model": "reduced"},
                [
                    {"t": 0.1005, "label": "latch hinge 1", "impulse": 1.0, "kinetic_before": 30.0},
                ],
            ),
        ]
    )
    meta = _meta({"events": [{"model": "reduced", "lock_time": 1e-3}], "all_latched": 1.0})
    checks = acceptance_checks(meta, _tables(), events)
    ev = [c for c in checks if c.classname == "acceptance.events"]
    # latch 1 is not comparable (kinetic energy 200 % apart): skipped and named; latch 2 missing
    assert ev[0].name == "c: reduced vs full (1 lock not comparable pointwise: skipped)"
    assert ev[0].failure == "latch hinge 2: no lock in reduced"
    latched = {c.name.split(":")[0]: c for c in ev[1:]}
    assert latched["full"].held
    assert latched["reduced"].failure.startswith("every latch locked in 0 of 1 cases (0.0%) < 1")
    # a blank momentum residual is "not audited", not a breach; a blank energy residual breaks
    runtime = pd.DataFrame(
        {
            "case": ["c", "c"],
            "model": ["full", "reduced"],
            "energy_residual": [1e-4, None],
            "momentum_residual": [None, 1e-9],
        }
    )
    checks = acceptance_checks(
        _meta({"energy_residual": 1e-2, "momentum_residual": 1e-6}), _tables(runtime), events
    )
    by = {c.name: c for c in checks}
    assert by["c: full energy_residual"].held
    assert by["c: reduced energy_residual"].failure.startswith("no energy residual recorded (")
    assert by[
        "c: full momentum_residual (not audited: momentum is audited on a free base or a free, "
        "unloaded root only)"
    ].held
    assert by["c: reduced momentum_residual"].held


@pytest.mark.parametrize(
    "table, words",
    [
        (
            '[[acceptance.event]]\nmodel = "full"\nlock_time = 1e-3',
            r"acceptance\.event\[0\]\.model': must be a model label other than the reference",
        ),
        (
            '[[acceptance.event]]\nmodel = "reduced"',
            r"acceptance\.event\[0\]': needs at least one of lock_time, impulse",
        ),
        (
            '[[acceptance.event]]\nmodel = "reduced"\nlock_time = -1.0',
            r"acceptance\.event\[0\]\.lock_time': must be a finite number > 0, got -1\.0",
        ),
        (
            '[[acceptance.event]]\nmodel = "reduced"\nimpulse = inf',
            r"acceptance\.event\[0\]\.impulse': must be a finite number > 0",
        ),
        (
            '[[acceptance.event]]\nmodel = "reduced"\nlock_time = 1e-3\nfoo = 1',
            r"acceptance\.event\[0\]\.foo': unknown key",
        ),
        ("all_latched = 1.5", r"acceptance\.all_latched': must be a number in \(0, 1\], got 1\.5"),
        ("all_latched = 0", r"acceptance\.all_latched': must be a number in \(0, 1\]"),
        ("energy_residual = 0.0", r"acceptance\.energy_residual': must be a finite number > 0"),
        (
            'momentum_residual = "1e-6"',
            r"acceptance\.momentum_residual': must be a finite number > 0",
        ),
    ],
)
def test_bad_event_keys_are_refused_when_the_study_is_read(tmp_path, table, words):
    with pytest.raises(ValueError, match=words):
        load_study(_study(tmp_path, "bad", table))
