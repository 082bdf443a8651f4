"""Fuzzing of output paths (issue 36): every command that writes (study, report, simulate,
compare, modes) pointed at folders that hold a user's files, files that look like rodval's
but are not (a foreign or edited study.json, run.json or rodval.json, a forged stamp, random
bytes) and --junit targets of every kind. The property: a file rodval did not write is never
changed or removed, and every refusal is one line. Counted as "data loss" beside the counts
of ``tests/test_fuzz.py`` (``tests/fuzz_helpers.py``; same budgets: RODVAL_FUZZ_EXAMPLES, RODVAL_FUZZ_STATS).
"""

from __future__ import annotations

import json
import shutil

import pytest
from fuzz_helpers import (
    BUDGET,
    RUN_SCENE,
    SMALL_STUDY,
    Counts,
    budget,
    lost_files,
    refusal_is_clear,
    run_cli,
    snapshot,
)
from hypothesis import given
from hypothesis import strategies as st

from rodval.cli import main
from rodval.core.out_paths import (
    CHECKSUM_KEY,
    OUTPUT_SCHEMA,
    RUN_SCHEMA,
    SCHEMA_KEY,
    STUDY_SCHEMA,
)
from rodval.study.toml_text import toml_text

pytestmark = pytest.mark.fuzz

#: Names a user's folder may hold: those rodval's outputs use, and one of the user's own.
NAMES = (
    "report.md",
    "cases.csv",
    "study.toml",
    "study.json",
    "run.json",
    "trajectory.csv",
    "tables.json",
    "provenance.json",
    "rodval.json",
    "discrepancies.csv",
    "frequencies.csv",
    "notes.txt",
    "cases/x.json",
    "figures/a.png",
)
#: What a look-alike marker may be: foreign JSON, a real marker edited, a forged stamp.
LOOKS = ("text", "bytes", "foreign json", "edited stamp", "forged stamp")


@pytest.fixture(scope="module")
def counts():
    registry: dict[str, Counts] = {}
    yield lambda name: registry.setdefault(name, Counts(name))
    for c in registry.values():
        c.save()


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A study file, a scene file, two finished run folders and a finished study's markers
    (to edit into look-alikes)."""
    tmp = tmp_path_factory.mktemp("inputs")
    study = tmp / "study.toml"
    study.write_text(toml_text(SMALL_STUDY))
    scene = tmp / "scene.toml"
    scene.write_text(toml_text(RUN_SCENE))
    runs = []
    for label in ("A", "B"):
        argv = ["simulate", scene, "--model", "reduced", "--out", tmp / label, *BUDGET]
        assert main([str(a) for a in argv]) == 0
        runs.append(tmp / label)
    done = tmp / "done"
    argv = ["study", study, "--out", done, "--workers", "1", "--no-progress", "--no-report"]
    assert main([str(a) for a in argv]) == 0
    markers = {
        "study.json": json.loads((done / "study.json").read_text()),
        "run.json": json.loads((runs[0] / "run.json").read_text()),
        "rodval.json": {SCHEMA_KEY: OUTPUT_SCHEMA, "command": "compare"},
    }
    return {"study": study, "scene": scene, "runs": runs, "markers": markers}


SCHEMAS = {"study.json": STUDY_SCHEMA, "run.json": RUN_SCHEMA, "rodval.json": OUTPUT_SCHEMA}


def content(draw, name: str, markers: dict) -> bytes:
    """The bytes of a user's file called ``name``: text, random bytes, or for a marker's name
    foreign JSON, rodval's own marker with one field edited, or a forged stamp."""
    look = draw(st.sampled_from(LOOKS))
    if look == "bytes":
        return draw(st.binary(max_size=64))
    if name not in markers or look == "text":
        return f"my own {name}\n".encode()
    if look == "foreign json":
        return json.dumps({"name": "my survey"}).encode()
    doc = dict(markers[name])
    if look == "edited stamp":
        doc["command" if name == "rodval.json" else "model"] = "edited"
    else:
        doc[SCHEMA_KEY], doc[CHECKSUM_KEY] = SCHEMAS[name], "0" * 64
    return json.dumps(doc).encode()


@budget(5, expensive=True)
@given(data=st.data())
def test_fuzz_output_folders(tmp_path_factory, counts, inputs, data):
    """A command writing into a folder of the user's (or a --junit path among the user's
    files): the user's files come out byte for byte the same; exit 0/1, or 2 with one line."""
    c = counts("output_folders")
    tmp = tmp_path_factory.mktemp("outputs")
    folder = tmp / "mine"
    folder.mkdir()
    for name in data.draw(st.lists(st.sampled_from(NAMES), max_size=4, unique=True)):
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content(data.draw, name, inputs["markers"]))
    (tmp / "user.xml").write_text("<?xml version='1.0'?><mine/>")
    (tmp / "plain").write_text("x")
    command = data.draw(st.sampled_from(("study", "report", "simulate", "compare", "modes")))
    argv: list = {
        "study": ["study", inputs["study"], "--out", folder, "--workers", "1", "--no-progress"],
        "report": ["report", folder],
        "simulate": ["simulate", inputs["scene"], "--model", "reduced", "--out", folder, *BUDGET],
        "compare": ["compare", *inputs["runs"], "--out", folder],
        "modes": ["modes", inputs["scene"], "--model", "reduced", "--out", folder],
    }[command]
    if command == "study":
        argv += data.draw(st.sampled_from([[], ["--fresh"], ["--no-report"]]))
    if command in ("study", "report"):
        junit = data.draw(
            st.sampled_from(
                [None, "", folder, tmp / "plain" / "j.xml", tmp / "user.xml", tmp / "new.xml"]
                + [folder / n for n in NAMES[:6]]
                + [inputs["study"]]
            )
        )
        argv += [] if junit is None else ["--junit", junit]
    if command == "simulate" and data.draw(st.booleans()):
        argv.append("--wide")
    before = snapshot(folder)
    own = {p: p.read_bytes() for p in (tmp / "user.xml", tmp / "plain", inputs["study"])}
    code, _, stderr = run_cli(argv, c)
    lost = lost_files(before, snapshot(folder))
    lost += [str(p) for p, data_ in own.items() if p.read_bytes() != data_]
    if lost:
        c.fail("lost", f"rodval {argv} changed or removed the user's {lost}")
    if code == 2:
        refusal_is_clear(stderr, c)


def test_a_real_rodval_folder_is_not_a_user_folder(inputs, tmp_path):
    """The property's control: rodval rewrites its own folders (a copy of a finished run
    folder is rerun into, exit 0), so the fuzz above does not pass by refusing everything."""
    out = tmp_path / "again"
    shutil.copytree(inputs["runs"][0], out)
    argv = ["simulate", inputs["scene"], "--model", "reduced", "--out", out, *BUDGET]
    assert main([str(a) for a in argv]) == 0
