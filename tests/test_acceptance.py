"""A study as a CI gate (issue 21): an [acceptance] table of bounds per model pair and quantity
(and valid runs) makes `rodval study` and `rodval report` exit 1 with one line per breach, and
--junit writes a JUnit XML report with one test case per case, pair and quantity and a
failure exactly where a bound broke."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pandas as pd
import pytest

from rodval.cli import main
from rodval.study import load_study

STUDY = """
[study]
name = "gate"
reference = "full"

[scene]
based_on = "paper"
n = 2
t_end = 0.2
times = {{ num = 5 }}
outputs = ["phi", "dphi"]

[models.full]
[models.reduced]

[grid]
"scene.chain.EI" = [1e4, 1e5]

[acceptance]
valid = true
[[acceptance.bound]]
model = "reduced"
quantity = "phi"
max_abs = {phi}
[[acceptance.bound]]
model = "reduced"
quantity = "dphi"
max_abs = 1.0
rms = 1.0
"""


def _study(tmp_path, phi: str):
    path = tmp_path / f"gate_{phi}.toml"
    path.write_text(STUDY.format(phi=phi))
    return path


def test_a_study_passes_its_bounds_and_fails_a_tightened_one(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["--no-progress", "--workers", "1"]
    assert (
        main(
            [
                "study",
                str(_study(tmp_path, "1.0")),
                "--out",
                str(out),
                *args,
                "--junit",
                str(tmp_path / "ok.xml"),
            ]
        )
        == 0
    )
    capsys.readouterr()
    disc = pd.read_csv(out / "discrepancies.csv")
    phi = disc[(disc["model"] == "reduced") & (disc["quantity"] == "phi")]
    worst = float(phi["max_abs"].max())
    assert 0 < worst < 1.0
    # tighten the phi bound below the larger of the two cases' max_abs (resumed: no rerun)
    tight = f"{worst * 0.999:.6g}"
    code = main(
        [
            "study",
            str(_study(tmp_path, tight)),
            "--out",
            str(out),
            *args,
            "--junit",
            str(tmp_path / "bad.xml"),
        ]
    )
    stdout = capsys.readouterr().out
    assert code == 1
    lines = [x for x in stdout.splitlines() if x.startswith("acceptance breached")]
    worst_case = phi.loc[phi["max_abs"].idxmax(), "case"]
    assert lines == [
        f"acceptance breached: {worst_case}: reduced vs full: phi: max_abs = {worst:.6g} > {float(tight):g}"
    ]
    # the JUnit files: 2 cases x 2 bounds + 2 cases x 2 runs valid = 8 test cases
    ok = ET.parse(tmp_path / "ok.xml").getroot()
    bad = ET.parse(tmp_path / "bad.xml").getroot()
    assert len(ok.findall(".//testcase")) == len(bad.findall(".//testcase")) == 8
    assert ok.findall(".//failure") == []
    failed = [tc.get("name") for tc in bad.findall(".//testcase") if tc.find("failure") is not None]
    assert failed == [f"{worst_case}: reduced vs full: phi"]
    assert bad.get("failures") == "1"
    # rodval report gives the same verdict from the saved tables
    assert main(["report", str(out), "--junit", str(tmp_path / "again.xml")]) == 1
    assert "acceptance breached" in capsys.readouterr().out
    report = (out / "report.md").read_text()
    assert "## Acceptance" in report and "FAILED (1 of 8 checks)" in report


@pytest.mark.parametrize(
    "table, words",
    [
        ("[acceptance]\nfoo = 1", r"acceptance\.foo': unknown key"),
        ("[acceptance]", r"acceptance': has nothing to check"),
        (
            '[acceptance]\n[[acceptance.bound]]\nmodel = "full"\nquantity = "phi"\nmax_abs = 1.0',
            r"acceptance\.bound\[0\]\.model': must be a model label other than the reference",
        ),
        (
            '[acceptance]\n[[acceptance.bound]]\nmodel = "reduced"\nquantity = "x"\nmax_abs = 1.0',
            r"acceptance\.bound\[0\]\.quantity': must be a quantity the cases output",
        ),
        (
            '[acceptance]\n[[acceptance.bound]]\nmodel = "reduced"\nquantity = "phi"',
            r"acceptance\.bound\[0\]': needs at least one of max_abs, rms",
        ),
        (
            '[acceptance]\n[[acceptance.bound]]\nmodel = "reduced"\nquantity = "phi"\nmax_abs = -1.0',
            r"acceptance\.bound\[0\]\.max_abs': must be a finite number > 0",
        ),
        ("[acceptance]\nvalid = 1", r"acceptance\.valid': must be true or false"),
    ],
)
def test_bad_acceptance_tables_are_refused_when_the_file_is_read(tmp_path, table, words):
    head = STUDY.split("[acceptance]")[0].format(phi="1.0")
    path = tmp_path / "s.toml"
    path.write_text(head + table + "\n")
    with pytest.raises(ValueError, match=words):
        load_study(path)
