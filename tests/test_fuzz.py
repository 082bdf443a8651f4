"""Fuzzing the command line (hypothesis): random scene files, study files, argument lists,
damaged case records and damaged tables.

Every example runs ``rodval.cli.main`` in this process and must end in one of two ways:

* exit 0 (or 1: `rodval simulate` of a run that failed) with a status line, and a run that
  reports success has finite outputs only;
* exit 2 with exactly one line on stderr, a user error (never "internal error");

never a traceback and never a hang: each example has a time limit (``LIMIT_S``, a SIGALRM
for Python code and a check of the wall time afterwards for compiled loops, which the runs'
own --max-wall budget ends). Scenes are small (n <= 6, t_end <= 0.5 s) with tight budgets.

Default budget: a few dozen examples per test, about a minute in all. More on demand::

    RODVAL_FUZZ_EXAMPLES=2000 RODVAL_FUZZ_STATS=/tmp/fuzz.json OMP_NUM_THREADS=1 \\
        python -m pytest tests/test_fuzz.py -m fuzz -q -p no:cacheprovider

``RODVAL_FUZZ_EXAMPLES`` is the number of examples of each cheap test (scene files, argument
lists, study files); the tests that run a study or build a report (damaged case records,
study runs, damaged tables) take a fortieth of it. ``RODVAL_FUZZ_STATS`` appends the counts
of each test (examples, tracebacks, hangs, silent non-finite successes, wall time) as JSON
lines. The helpers every fuzz file shares (budgets, counts, ``run_cli``, ``run_api``) are in
``tests/fuzz_helpers.py``.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from fuzz_helpers import (
    BUDGET,
    RUN_SCENE,
    SMALL_STUDY,
    Counts,
    anything,
    budget,
    check_run,
    claims_success,
    read_record,
    refusal_is_clear,
    refused_late,
    run_api,
    run_cli,
    small_scene,
    to_toml,
    write_scene,
)
from hypothesis import given
from hypothesis import strategies as st

from rodval.cli import main

pytestmark = pytest.mark.fuzz


@pytest.fixture(scope="module")
def counts(request):
    registry: dict[str, Counts] = {}
    yield lambda name: registry.setdefault(name, Counts(name))
    for c in registry.values():
        c.save()


# ----------------------------------------------------------------------------- TOML writing


# ----------------------------------------------------------------------------- strategies


@st.composite
def per_rod(draw, n, lo, hi):
    """A chain value: a good scalar or list, or anything."""
    kind = draw(st.integers(0, 4))
    if kind == 0:
        return draw(anything)
    if kind == 1:
        return [draw(st.floats(lo, hi)) for _ in range(max(min(n, 6), 1))]
    return draw(st.floats(lo, hi))


@st.composite
def scene_doc(draw, *, valid_bias: bool = True) -> dict:
    n = draw(st.one_of(st.integers(1, 5), st.integers(1, 5), anything))
    nn = n if isinstance(n, int) and not isinstance(n, bool) else 3
    # mostly the paper's scene with changes (every key optional); sometimes a file of its own
    doc: dict = {"based_on": "paper"} if draw(st.integers(0, 9)) else {}
    if draw(st.booleans()) or valid_bias:
        doc["n"] = n
    if draw(st.booleans()):
        doc["t_end"] = draw(st.one_of(st.floats(0.01, 0.5), anything))
    t_end = doc.get("t_end", 2.0)
    if draw(st.booleans()) or t_end == 2.0:
        doc["times"] = draw(
            st.one_of(
                st.fixed_dictionaries({"num": st.one_of(st.integers(1, 30), anything)}),
                st.lists(st.floats(0.0, 0.5), min_size=1, max_size=5).map(sorted),
                anything,
            )
        )
    if draw(st.booleans()):
        doc["outputs"] = draw(
            st.one_of(
                st.lists(
                    st.sampled_from(["phi", "dphi", "alpha", "beta", "x", "y", "energy", "z"]),
                    min_size=0,
                    max_size=4,
                ),
                anything,
            )
        )
    if draw(st.booleans()):
        chain = {}
        for key, lo, hi in (
            ("l", 0.1, 5),
            ("m", 0.1, 10),
            ("EI", 1e2, 1e6),
            ("mu", 0, 10),
            ("kappa", 0, 1e3),
            ("nu", 0, 1),
        ):
            if draw(st.integers(0, 3)) == 0:
                chain[key] = draw(per_rod(nn, lo, hi))
        if draw(st.integers(0, 9)) == 0:
            chain["bogus"] = 1
        doc["chain"] = chain
    if draw(st.booleans()):
        doc["initial"] = {
            k: draw(st.one_of(st.floats(-1, 1), anything))
            for k in draw(st.sets(st.sampled_from(["phi", "dphi", "alpha", "beta", "gamma"])))
        }
    if draw(st.booleans()):
        loads = []
        for _ in range(draw(st.integers(0, 3))):
            kind = draw(st.sampled_from(["pulse", "constant", "ramp", "harmonic", "bad"]))
            load = {"type": kind, "node": draw(st.one_of(st.just("last"), st.integers(0, 6)))}
            for key in draw(
                st.sets(st.sampled_from(["Xbar", "Ybar", "T", "X", "Y", "t_on", "t_off"]))
            ):
                load[key] = draw(st.one_of(st.floats(-500, 500), anything))
            loads.append(load)
        doc["loads"] = draw(st.one_of(st.just(loads), st.just(loads), anything))
    if draw(st.integers(0, 9)) == 0:
        doc[draw(st.sampled_from(["base", "based_on", "name", "extra"]))] = draw(anything)
    return doc


@st.composite
def valid_scene_doc(draw) -> dict:
    """A scene file of valid values only (small, short): these run."""
    n = draw(st.integers(1, 6))
    doc: dict = {
        "based_on": "paper",
        "n": n,
        "t_end": draw(st.floats(0.01, 0.5)),
        "times": {"num": draw(st.integers(1, 20))},
    }
    chain = {}
    for key, lo, hi in (("l", 0.1, 5.0), ("m", 0.1, 10.0), ("EI", 1e2, 1e6), ("mu", 0.0, 10.0),
                        ("kappa", 0.0, 1e3), ("nu", 0.0, 1.0)):  # fmt: skip
        if draw(st.booleans()):
            chain[key] = draw(
                st.one_of(st.floats(lo, hi), st.lists(st.floats(lo, hi), min_size=n, max_size=n))
            )
    doc["chain"] = chain
    doc["outputs"] = draw(
        st.lists(
            st.sampled_from(["phi", "dphi", "alpha", "beta", "x", "y", "energy"]),
            min_size=1,
            max_size=4,
            unique=True,
        )  # fmt: skip
    )
    doc["initial"] = {
        k: draw(st.floats(-1, 1)) for k in draw(st.sets(st.sampled_from(["phi", "dphi", "alpha"])))
    }
    doc["loads"] = [
        {
            "type": "pulse",
            "node": draw(st.integers(1, n)),
            "Xbar": draw(st.floats(-1e3, 1e3)),
            "Ybar": draw(st.floats(-1e3, 1e3)),
            "T": draw(st.floats(0.05, 1.0)),
        }  # fmt: skip
        for _ in range(draw(st.integers(0, 2)))
    ]
    return doc


# ----------------------------------------------------------------------------- tests


@budget(15)
@given(
    doc=st.one_of(scene_doc(), valid_scene_doc()),
    model=st.sampled_from(["full", "reduced"]),
    raw=st.one_of(st.none(), st.none(), st.none(), st.binary(max_size=40)),
    method=st.sampled_from([None, "auto", "RK45", "RK23", "DOP853", "DOP853-numba", "Radau"]),
)
def test_fuzz_scene_files(tmp_path_factory, counts, doc, model, raw, method):
    """`rodval simulate FILE`: exit 0/1 with a status line, or 2 with one line."""
    c = counts("scene_files")
    tmp = tmp_path_factory.mktemp("scene")
    path = write_scene(tmp, doc, raw)
    argv = ["simulate", path, "--model", model, "--out", tmp / "out", *BUDGET]
    if method:
        argv += ["--method", method]
    code, stdout, stderr = run_cli(argv, c)
    if code in (0, 1):
        assert stdout.strip(), stderr
        bad = check_run(tmp / "out", code)
        c.nonfinite += bad
        assert not bad, f"success with non-finite outputs: {doc}"


OPTION_POOL = {
    "simulate": [
        ["--model", st.sampled_from(["full", "reduced", "nope", ""])],
        ["--t-end", st.one_of(st.sampled_from(["0.1", "-1", "0", "inf", "nan", "x", "1e9"]))],
        ["--times", st.sampled_from(["0,0.1", "0.1,0.05", "", "a", "-1,2", "0.05", "1e9"])],
        ["--method", st.sampled_from(["RK45", "DOP853-numba", "Radau", "LSODA", "euler"])],
        ["--rtol", st.sampled_from(["1e-6", "0", "1", "-1e-3", "nan", "x"])],
        ["--atol", st.sampled_from(["1e-8", "0", "inf", "x"])],
        ["--max-step", st.sampled_from(["0.01", "0", "inf", "-1"])],
        ["--max-evaluations", st.sampled_from(["100", "0", "1.5", "1e9"])],
        ["--max-wall", st.sampled_from(["0.5", "0", "inf", "-2"])],
        ["--coefficients", st.sampled_from(["published", "derived", "x"])],
        ["--set", st.sampled_from(["kernel=numpy", "kernel=x", "rtol=1e-3", "foo=1", "noequals"])],
        [st.sampled_from(["--bogus", "-x", "--", "--help"])],
    ],
    "report": [[st.sampled_from(["--bogus", "extra-arg"])]],
    "nope": [[st.sampled_from(["--help", "x"])]],
    "study": [
        ["--workers", st.sampled_from(["1", "0", "x"])],
        ["--case-timeout", st.sampled_from(["30", "0", "-1", "x"])],
        [st.sampled_from(["--no-resume", "--fresh", "--resume", "--bogus"])],
        ["--backend", st.sampled_from(["processes", "dask", "mpi"])],
    ],
}


@st.composite
def argument_list(draw, tmp: Path):
    command = draw(st.sampled_from(["simulate", "simulate", "report", "study", "nope"]))
    argv: list = [command]
    if command == "simulate":
        argv.append(draw(st.sampled_from(["paper", str(tmp / "missing.toml"), "", "x.json"])))
        if draw(st.integers(0, 5)):
            argv += ["--out", str(tmp / "out")]
        argv += ["--t-end", "0.1", "--model", "reduced", *BUDGET]
    elif command == "report":
        argv.append(draw(st.sampled_from([str(tmp), str(tmp / "missing"), "", "/"])))
    elif command == "study":
        argv.append(draw(st.sampled_from([str(tmp / "missing.toml"), str(tmp), ""])))
        if draw(st.booleans()):
            argv += ["--out", str(tmp / "study-out")]
    for option in draw(st.lists(st.sampled_from(OPTION_POOL[command]), max_size=4)):
        argv += [draw(x) if not isinstance(x, str) else x for x in option]
    return argv


@budget(40)
@given(data=st.data())
def test_fuzz_argument_lists(tmp_path_factory, counts, data):
    """Random argument lists to simulate, report and study: never a traceback or a hang."""
    c = counts("argument_lists")
    tmp = tmp_path_factory.mktemp("args")
    argv = data.draw(argument_list(tmp))
    code, _, _ = run_cli(argv, c)
    c.nonfinite += check_run(tmp / "out", code)
    assert not c.nonfinite


@st.composite
def study_doc(draw) -> dict:
    doc: dict = {}
    models = draw(
        st.one_of(
            st.just({"reduced": {}}),
            st.just({"reduced": {}, "pub": {"model": "reduced", "coefficients": "published"}}),
            st.just({"full": {"method": "DOP853-numba"}, "reduced": {}}),
            st.just({"x": {"model": "nope"}}),
            st.just({"reduced": {"rtol": "a"}}),
            anything,
        )
    )
    if draw(st.integers(0, 7)):
        doc["models"] = models
    doc["study"] = draw(
        st.one_of(
            st.just({"name": "fz"}),
            st.just({"name": "fz", "reference": "reduced"}),
            st.just({"reference": "missing"}),
            anything,
        )
    )
    scene = draw(scene_doc())
    scene.setdefault("n", 2)
    scene.setdefault("t_end", 0.05)
    scene.setdefault("times", {"num": 3})
    doc["scene"] = scene
    doc["integrator"] = {"max_evaluations": 20000, "max_wall_s": 5.0}
    if draw(st.booleans()):
        doc["integrator"] = draw(
            st.one_of(
                st.just({"max_evaluations": 20000, "max_wall_s": 5.0}),
                st.just({"rtol": 1e-6}),
                st.just({"bogus": 1}),
                st.just({"max_evaluations": 1.5}),
                anything,
            )
        )
    if draw(st.booleans()):
        doc["grid"] = draw(
            st.one_of(
                st.just({"scene.n": [2, 3]}),
                st.just({"scene.t_end": [0.05, 0.1]}),
                st.just({"scene.chain.EI": [1e3, 1e4]}),
                st.just({"scene.n": [2, 2]}),
                st.just({"scene.bogus": [1]}),
                st.just({"integrator.rtol": [1e-6, -1.0]}),
                st.just({"scene.n": []}),
                anything,
            )
        )
    if draw(st.integers(0, 4)) == 0:
        doc["report"] = draw(
            st.one_of(st.just({"rods": [1, "last"]}), st.just({"cases": ["nope"]}), anything)
        )
    return doc


@budget(30)
@given(doc=study_doc(), raw=st.one_of(st.none(), st.none(), st.binary(max_size=30)))
def test_fuzz_study_files(tmp_path_factory, counts, doc, raw):
    """Random study files, checked before any work (``rodval study`` with a folder that is a
    file, so that a valid study stops at the folder and never runs): exit 2, one line."""
    c = counts("study_files")
    tmp = tmp_path_factory.mktemp("studyfile")
    path = tmp / "study.toml"
    path.write_bytes(raw) if raw is not None else path.write_text(to_toml(doc))
    (tmp / "busy").write_text("a file, not a folder")
    code, _, stderr = run_cli(["study", path, "--out", tmp / "busy", "--no-progress"], c)
    assert code == 2, stderr


@st.composite
def valid_study_doc(draw) -> dict:
    """A small study file of valid values (these run)."""
    scene = draw(valid_scene_doc())
    scene.update(n=draw(st.integers(1, 3)), t_end=draw(st.floats(0.01, 0.1)))
    scene["times"] = {"num": draw(st.integers(1, 5))}
    scene["loads"] = [dict(ld, node="last") for ld in scene["loads"]]
    models = draw(
        st.sampled_from(
            [
                {"reduced": {}},
                {"reduced": {}, "pub": {"model": "reduced", "coefficients": "published"}},
                {"full": {"method": "DOP853-numba"}, "reduced": {}},
                {"full": {"method": "RK45"}, "reduced": {"method": "Radau"}},
            ]
        )
    )
    grid = draw(
        st.sampled_from(
            [
                {},
                {"scene.n": [1, 2]},
                {"scene.chain.EI": [1e3, 1e5]},
                {"integrator.rtol": [1e-6, 1e-8]},
            ]
        )
    )
    doc = {
        "study": {"name": "fz", "reference": next(iter(models))},
        "scene": scene,
        "integrator": {"max_evaluations": 20000, "max_wall_s": 5.0},
        "models": models,
    }
    if grid:
        doc["grid"] = grid
    return doc


@budget(4, expensive=True)
@given(doc=st.one_of(study_doc(), valid_study_doc(), valid_study_doc()))
def test_fuzz_study_runs(tmp_path_factory, counts, doc):
    """Random small studies run to the end: exit 0 with finished tables, or 2 with one line;
    every successful run in the tables has finite values."""
    c = counts("study_runs")
    tmp = tmp_path_factory.mktemp("studyrun")
    path = tmp / "study.toml"
    path.write_text(to_toml(doc))
    argv = ["study", path, "--out", tmp / "out", "--workers", "1", "--no-progress"]
    code, _, stderr = run_cli([*argv, "--case-timeout", "20", "--no-report"], c)
    if code == 0:
        traj = pd.read_csv(tmp / "out" / "trajectories.csv")
        runtime = pd.read_csv(tmp / "out" / "runtime.csv")
        ok = runtime[runtime["status"] == 0][["case", "model"]]
        good = traj.merge(ok, on=["case", "model"])
        bad = int(not np.all(np.isfinite(good["value"].to_numpy(float))))
        c.nonfinite += bad
        assert not bad


@pytest.fixture(scope="module")
def finished_study(tmp_path_factory):
    """A finished two-case study folder (run once per module)."""
    tmp = tmp_path_factory.mktemp("finished")
    path = tmp / "study.toml"
    path.write_text(to_toml(SMALL_STUDY))
    out = tmp / "out"
    code = main(["study", str(path), "--out", str(out), "--workers", "1", "--no-progress"])
    assert code == 0
    return path, out


def damage_record(path: Path, kind: str, data) -> None:
    text = path.read_text()
    doc = json.loads(text)
    if kind == "empty list":
        path.write_text("[]")
    elif kind == "null":
        path.write_text("null")
    elif kind == "no runs":
        doc.pop("runs")
        path.write_text(json.dumps(doc))
    elif kind == "random bytes":
        path.write_bytes(data.draw(st.binary(min_size=0, max_size=200)))
    elif kind == "truncated":
        path.write_text(text[: data.draw(st.integers(0, len(text) - 1))])
    elif kind == "wrong-shaped array":
        values = doc["runs"][0]["trajectory"]["values"]
        q = next(iter(values))
        values[q] = [[1.0, 2.0, 3.0]]
        path.write_text(json.dumps(doc))
    elif kind == "run deleted":
        doc["runs"] = doc["runs"][1:]
        path.write_text(json.dumps(doc))
    elif kind == "value edited":
        values = doc["runs"][0]["trajectory"]["values"]
        q = next(iter(values))
        values[q][-1][-1] = data.draw(st.floats(allow_nan=False, allow_infinity=False))
        path.write_text(json.dumps(doc))
    elif kind == "schema":
        doc["schema"] = data.draw(st.one_of(st.integers(), st.text(max_size=3), st.none()))
        path.write_text(json.dumps(doc))
    elif kind == "key edited":
        key = data.draw(st.sampled_from(sorted(doc)))
        doc[key] = data.draw(anything)
        path.write_text(json.dumps(doc))
    elif kind == "deleted":
        path.unlink()


DAMAGES = (
    "empty list",
    "null",
    "no runs",
    "random bytes",
    "truncated",
    "wrong-shaped array",
    "run deleted",
    "value edited",
    "schema",
    "key edited",
    "deleted",
)


@budget(4, expensive=True)
@given(data=st.data())
def test_fuzz_damaged_case_records(tmp_path_factory, counts, finished_study, data):
    """A resume over damaged case records: exit 0, a warning naming each damaged file, the
    damaged cases recomputed, tables complete and finite."""
    c = counts("damaged_case_records")
    study, done = finished_study
    tmp = tmp_path_factory.mktemp("damaged")
    out = tmp / "out"
    shutil.copytree(done, out)
    files = sorted((out / "cases").glob("*.json"))
    victims = data.draw(st.lists(st.sampled_from(files), min_size=1, max_size=2, unique=True))
    changed, deleted = [], []
    for path in victims:
        before = path.read_bytes()
        damage_record(path, data.draw(st.sampled_from(DAMAGES)), data)
        if not path.is_file():
            deleted.append(path)
        elif path.read_bytes() != before:
            changed.append(path)
    argv = ["study", study, "--out", out, "--no-progress", "--no-report", "--workers", "1"]
    code, stdout, stderr = run_cli(argv, c)
    assert code == 0, stderr
    assert stdout.startswith(f"fz: {len(changed) + len(deleted)} cases run"), stdout
    for path in changed + deleted:
        assert path.is_file(), f"{path.name} was not recomputed"
    for path in changed:  # a deleted file is simply missing; a damaged one is named
        assert str(path) in stderr and "recomputing" in stderr, stderr
    cases = pd.read_csv(out / "cases.csv")
    assert sorted(cases["case"]) == ["n=2", "n=3"]
    traj = pd.read_csv(out / "trajectories.csv")
    assert set(traj["case"]) == {"n=2", "n=3"}
    assert set(traj["model"]) == {"reduced", "pub"}
    assert np.all(np.isfinite(traj["value"].to_numpy(float)))


TABLE_DAMAGES = (
    "delete",
    "empty",
    "random bytes",
    "drop column",
    "truncate",
    "unknown case",
    "nan metric",
    "truncate",
)
#: Numeric columns of each table where a NaN is injected ("nan metric").
METRIC_COLUMNS = {
    "discrepancies": ("max_abs", "rms", "final_abs", "max_rel"),
    "runtime": ("wall_s", "nfev", "t_reached"),
    "trajectories": ("value",),
    "cases": ("horizon",),
}


@budget(6, expensive=True)
@given(data=st.data())
def test_fuzz_damaged_tables(tmp_path_factory, counts, finished_study, data):
    """`rodval report` over damaged tables (deleted, empty, random bytes, a column dropped,
    truncated at a random byte offset, an unknown case, NaN injected in a metric column of a
    run that succeeded): exit 0, or exit 2 with one line naming the file; a report built
    over a table that lost data (truncated) or holds a NaN metric of a successful run without
    a word naming the file is silently wrong."""
    c = counts("damaged_tables")
    _, done = finished_study
    tmp = tmp_path_factory.mktemp("tables")
    out = tmp / "out"
    shutil.copytree(done, out)
    name = data.draw(st.sampled_from(["cases", "trajectories", "discrepancies", "runtime"]))
    path = out / f"{name}.csv"
    kind = data.draw(st.sampled_from(TABLE_DAMAGES))
    df = pd.read_csv(path)
    lost = False  # data a report cannot show faithfully
    if kind == "delete":
        path.unlink()
    elif kind == "empty":
        path.write_text("")
    elif kind == "random bytes":
        path.write_bytes(data.draw(st.binary(max_size=100)))
    elif kind == "drop column":
        df.drop(columns=[data.draw(st.sampled_from(list(df.columns)))]).to_csv(path, index=False)
    elif kind == "truncate":
        text = path.read_text()
        cut = data.draw(st.integers(0, len(text)))
        path.write_text(text[:cut])
        lost = cut <= len(text) - 2  # at least one character of data gone
    elif kind == "unknown case":
        df.loc[0, "case"] = "ghost"
        df.to_csv(path, index=False)
    elif kind == "nan metric":
        row = data.draw(st.integers(0, len(df) - 1))
        df.loc[row, data.draw(st.sampled_from(METRIC_COLUMNS[name]))] = math.nan
        df.to_csv(path, index=False)
        lost = "status" not in df.columns or df.loc[row, "status"] in ("ok", 0, "0")
    code, _, stderr = run_cli(["report", out], c)
    if code == 2:
        assert f"{name}.csv" in stderr or str(out) in stderr, stderr
        refusal_is_clear(stderr, c)
    elif lost and f"{name}.csv" not in stderr:
        c.ignored += 1
        raise AssertionError(f"report over a {kind} {name}.csv without a word: exit {code}")


# ----------------------------------------------------------------------------- trust review
# Inputs a trust review found broken: stops and latches, tabulated-load CSV files, edited
# run.json files, the Python API, `rodval compare` and `rodval report` over damaged inputs.
# Besides tracebacks and hangs these count *silently wrong* results: a run that claims
# success (``claims_success``) with non-finite outputs, or one that ignored an input.


BAD_HINGES = st.sampled_from([-1, 1.0, 0.5, "1", True, 1e300, -1.0, [1]])
BAD_ANGLES = st.sampled_from([math.nan, math.inf, -math.inf, 1e300, "0.1", True, [0.1]])
GOOD_ANGLES = st.one_of(st.floats(-3.2, 3.2), st.sampled_from([0.0, 0.01, -0.01]))


@st.composite
def table_spec(draw, good: dict, bad: dict, extra: str) -> dict:
    """A table of good values, or one with a few bad values, missing keys, a foreign key."""
    spec = {k: draw(v) for k, v in good.items()}
    if draw(st.booleans()):
        return spec
    for key in draw(st.sets(st.sampled_from(sorted(bad)), min_size=1, max_size=2)):
        spec[key] = draw(bad[key])
    for key in list(spec):
        if draw(st.integers(0, 6)) == 0:  # a missing key
            del spec[key]
    if draw(st.integers(0, 9)) == 0:
        spec[extra] = 1
    return spec


def latch_table(n):
    good = {
        "hinge": st.integers(0, n - 1),
        "angle": GOOD_ANGLES,
        "direction": st.sampled_from([1, -1]),
    }
    bad = {
        "hinge": st.one_of(st.integers(n, n + 2), BAD_HINGES),
        "angle": BAD_ANGLES,
        "direction": st.sampled_from([-1.0, 1.0, 0, 2, "up", "+1", True, False, 1e300, [1]]),
    }
    return table_spec(good, bad, "stiffness")


def stop_table(n):
    good = {
        "hinge": st.integers(0, n - 1),
        "angle": GOOD_ANGLES,
        "side": st.sampled_from(["upper", "lower"]),
        "stiffness": st.floats(1e-3, 1e7),
        "damping": st.floats(0.0, 1e3),
    }
    bad = {
        "hinge": st.one_of(st.integers(n, n + 2), BAD_HINGES),
        "angle": BAD_ANGLES,
        "side": st.sampled_from(["UPPER", "", "up", 1, -1.0, True]),
        "stiffness": st.sampled_from([1e300, 1e200, 0.0, -1.0, math.nan, math.inf, "1e4", True]),
        "damping": st.sampled_from([-1.0, 1e300, math.nan, math.inf, "0", False]),
    }
    return table_spec(good, bad, "direction")


@st.composite
def stops_latches_doc(draw) -> dict:
    doc = small_scene(draw)
    n = doc["n"]
    doc["latches"] = draw(st.lists(latch_table(n), max_size=2))
    doc["stops"] = draw(st.lists(stop_table(n), max_size=3))
    if draw(st.integers(0, 9)) == 0:
        doc[draw(st.sampled_from(["latches", "stops"]))] = draw(anything)
    return doc


@budget(4)
@given(
    doc=stops_latches_doc(),
    model=st.sampled_from(["full", "reduced"]),
    method=st.sampled_from([None, None, "RK45", "Radau", "DOP853-numba"]),
)
def test_fuzz_stops_and_latches(tmp_path_factory, counts, doc, model, method):
    """Random [[stops]] / [[latches]] (valid and invalid hinges, angles, sides, directions,
    stiffness, damping, missing keys) through `rodval simulate`: exit 0/1 with a status line
    and finite outputs, or 2 with one clear line; a run keeps every stop and latch it was
    given, on the hinge it was given."""
    c = counts("stops_and_latches")
    tmp = tmp_path_factory.mktemp("stops")
    path = write_scene(tmp, doc)
    argv = ["simulate", path, "--model", model, "--out", tmp / "out", *BUDGET]
    if method:
        argv += ["--method", method]
    code, stdout, stderr = run_cli(argv, c)
    if code == 2:
        refusal_is_clear(stderr, c)
        return
    assert stdout.strip(), stderr
    bad = check_run(tmp / "out", code)
    c.nonfinite += bad
    assert not bad, f"success with non-finite outputs: {doc}"
    refused_late(stdout, c)
    rec = read_record(tmp / "out")
    if rec is None or not claims_success(rec["stats"]):
        return
    for key in ("latches", "stops"):
        given_ = doc.get(key, [])
        kept = rec["scene"].get(key, [])
        lost = len(kept) != len(given_) or any(
            not isinstance(s, dict) or s.get("hinge") != g.get("hinge") or s["hinge"] >= doc["n"]
            for s, g in zip(kept, given_, strict=False)
        )
        if lost:
            c.ignored += 1
            raise AssertionError(f"success that dropped or moved {key}: {given_} -> {kept}")
        for s, g in zip(kept, given_, strict=False):
            for k, v in g.items():
                if type(s.get(k)) is not type(v) or s.get(k) != v:
                    c.ignored += 1
                    raise AssertionError(f"{key} {k} = {v!r} ran as {s.get(k)!r}: {doc}")


@st.composite
def history_csv(draw) -> tuple[bytes, str, dict | None]:
    """(bytes of a tabulated-load CSV file, what was done to it, its columns when they are
    all valid: what a run must use)."""
    kind = draw(
        st.sampled_from(
            [
                "good",
                "good",
                "good",
                "empty",
                "binary",
                "header only",
                "ragged",
                "duplicate",
                "non-monotonic",
                "non-finite",
                "text cell",
                "huge",
                "bad header",
                "blank lines",
            ]
        )  # fmt: skip
    )
    if kind == "empty":
        return b"", kind, None
    if kind == "binary":
        return draw(st.binary(min_size=1, max_size=60)), kind, None
    head = draw(st.sampled_from([["t", "X", "Y"], ["t", "X"], ["t", "Y"], ["Y", "t", "X"]]))
    if kind == "duplicate":
        head = draw(st.sampled_from([["t", "X", "X"], ["t", "Y", "Y"], ["t", "t", "X"]]))
    elif kind == "bad header":
        head = draw(st.sampled_from([["T", "X"], ["t", "X", "Z"], ["t", ""], [" t ", " X "]]))
    rows = draw(st.integers(2, 12)) if kind != "huge" else draw(st.integers(10_000, 200_000))
    if kind == "header only":
        rows = 0
    t = np.cumsum(np.full(rows, 0.3 / max(rows - 1, 1))) - 0.3 / max(rows - 1, 1)
    if kind != "huge":
        t = np.cumsum(draw(st.lists(st.floats(1e-3, 0.1), min_size=rows, max_size=rows)))
        t -= t[0] if rows and draw(st.booleans()) else 0.0
    cols = {name: t if name == "t" else np.sin(5 * t) * draw(st.floats(-500, 500)) for name in head}
    table = np.column_stack([cols[h] for h in head]) if rows else np.zeros((0, len(head)))
    cells = [[repr(float(v)) for v in row] for row in table]
    if kind == "non-monotonic" and rows >= 2:
        i, j = draw(st.integers(1, rows - 1)), head.index("t")
        if draw(st.booleans()):
            cells[i][j] = cells[i - 1][j]  # a repeated time
        else:
            cells[i], cells[i - 1] = cells[i - 1], cells[i]  # times out of order
    elif kind == "non-finite" and rows:
        i, j = draw(st.integers(0, rows - 1)), draw(st.integers(0, len(head) - 1))
        cells[i][j] = draw(st.sampled_from(["nan", "inf", "-inf", "NaN", "1e999"]))
    elif kind == "text cell" and rows:
        i, j = draw(st.integers(0, rows - 1)), draw(st.integers(0, len(head) - 1))
        cells[i][j] = draw(st.sampled_from(["", "x", "1,5", "0x10", " ", "1_0"]))
    elif kind == "ragged" and rows:
        i = draw(st.integers(0, rows - 1))
        cells[i] = cells[i][:-1] if draw(st.booleans()) else [*cells[i], "1.0"]
    lines = [",".join(head)] + [",".join(r) for r in cells]
    if kind == "blank lines":
        lines.insert(draw(st.integers(1, len(lines))), draw(st.sampled_from(["", ",,", " "])))
    expected = cols if kind in ("good", "huge", "blank lines") and rows >= 2 else None
    return ("\n".join(lines) + "\n").encode(), kind, expected


@budget(4)
@given(
    doc=st.composite(lambda draw: small_scene(draw, n_max=3))(),
    history=history_csv(),
    node=st.sampled_from(["last", 1, 1]),
    model=st.sampled_from(["full", "reduced"]),
)
def test_fuzz_tabulated_load_files(tmp_path_factory, counts, doc, history, node, model):
    """A scene whose [[loads]] is a tabulated load read from a random CSV file (ragged rows,
    duplicate or unknown headers, binary garbage, non-monotonic t, NaN/inf, text cells, up to
    200 000 rows, empty files): exit 0/1 with finite outputs, or 2 with one clear line; a run
    that succeeds used every sample of the file (the run record holds them) and a file with a
    duplicated column (which one is the force?) is never accepted."""
    c = counts("tabulated_load_files")
    tmp = tmp_path_factory.mktemp("tabulated")
    raw, kind, expected = history
    csv_path = tmp / "history.csv"
    csv_path.write_bytes(raw)
    doc = {**doc, "loads": [{"type": "tabulated", "node": node, "file": str(csv_path)}]}
    path = write_scene(tmp, doc)
    argv = ["simulate", path, "--model", model, "--out", tmp / "out", *BUDGET]
    code, stdout, stderr = run_cli(argv, c)
    if code == 2:
        refusal_is_clear(stderr, c)
        return
    assert stdout.strip(), stderr
    bad = check_run(tmp / "out", code)
    c.nonfinite += bad
    assert not bad, f"success with non-finite outputs: {kind}"
    refused_late(stdout, c)
    rec = read_record(tmp / "out")
    if rec is None:
        return
    if kind == "duplicate":
        c.ignored += 1
        raise AssertionError(f"a file with a duplicated column ran: {raw[:40]!r}")
    load = rec["scene"]["loads"][0]
    for name, given_ in (expected or {}).items():
        used = np.asarray(load.get(name, []), float)
        if used.shape != given_.shape or not np.array_equal(used, given_):
            c.ignored += 1
            raise AssertionError(f"column {name} of a {kind} file not used as given")


@pytest.fixture(scope="module")
def finished_runs(tmp_path_factory):
    """Run folders of `rodval simulate` (made once per module): the tiny scene with the
    reduced model, with its published coefficients, and with the full model; the same
    scene with another EI; a scene with another n."""
    tmp = tmp_path_factory.mktemp("runs")
    scenes = {
        "base": RUN_SCENE,
        "other_EI": {**RUN_SCENE, "chain": {"EI": 1e3}},
        "other_n": {**RUN_SCENE, "n": 3},
    }
    runs = {}
    for label, doc, extra in (
        ("reduced", "base", []),
        ("published", "base", ["--coefficients", "published"]),
        ("other_EI", "other_EI", []),
        ("other_n", "other_n", []),
    ):
        path = tmp / f"{doc}.toml"
        path.write_text(to_toml(scenes[doc]))
        out = tmp / label
        argv = ["simulate", path, "--model", "reduced", "--out", out, *BUDGET, *extra]
        assert main([str(a) for a in argv]) == 0
        runs[label] = out
    return runs


#: Sections of run.json that are inputs of a rerun (the others record how a run ended).
RUN_INPUTS = ("scene", "model", "options", "settings")
#: Inputs a rerun derives rather than reads: the method that ran (the rerun asks for
#: ``requested_method`` again).
DERIVED = {("settings", "method")}


def leaves(doc, prefix=()):
    """Paths of every value in a JSON document (dict keys and list indices)."""
    if isinstance(doc, dict) and doc:
        for k, v in doc.items():
            yield from leaves(v, (*prefix, k))
    elif isinstance(doc, list) and doc:
        for i, v in enumerate(doc):
            yield from leaves(v, (*prefix, i))
    else:
        yield prefix


def containers(doc, prefix=()):
    """Paths of every dict in a JSON document."""
    if isinstance(doc, dict):
        yield prefix
        for k, v in doc.items():
            yield from containers(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from containers(v, (*prefix, i))


def at(doc, path):
    for p in path:
        doc = doc[p]
    return doc


def same(a, b) -> bool:
    """JSON values equal, NaN equal to NaN, a bool never equal to a number or a string."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return a == b or (math.isnan(a) and math.isnan(b))
    return type(a) is type(b) and a == b


@st.composite
def leaf_value(draw, old):
    """A new value for a leaf: a nearby value of its own type, or anything."""
    if draw(st.booleans()):
        return draw(anything)
    if isinstance(old, bool):
        return not old
    if isinstance(old, (int, float)):
        return type(old)(old * draw(st.sampled_from([0.5, 2, -1, 0, 1e6])))
    if isinstance(old, str):
        return draw(st.sampled_from([old.upper(), old + " ", "", "RK45", "published", "numpy"]))
    return draw(anything)


@st.composite
def run_record_edit(draw, rec: dict, text: str):
    """(edited run.json text, what was done, the edited path or None, the value put there)."""
    kind = draw(st.sampled_from(["unknown key", "value", "value", "delete", "truncate", "record"]))
    if kind == "truncate":
        return text[: draw(st.integers(0, len(text) - 2))], kind, None, None
    doc = json.loads(text)
    section = draw(st.sampled_from(RUN_INPUTS if kind != "record" else ("stats", "events")))
    if kind == "unknown key":
        where = draw(st.sampled_from([(), *containers(rec[section], (section,))]))
        key = draw(st.sampled_from(["rtoll", "bogus", "Rtol", "kernal", "EI_"]))
        value = draw(st.sampled_from([1, 1e-3, "x", True]))
        at(doc, where)[key] = value
        return json.dumps(doc), kind, (*where, key), value
    paths = [p for p in leaves(rec[section], (section,)) if p]
    if kind == "delete":
        path = draw(st.sampled_from(paths))
        parent = at(doc, path[:-1])
        if isinstance(parent, dict):
            del parent[path[-1]]
        else:
            parent.pop(path[-1])
        return json.dumps(doc), kind, None, None
    path = draw(st.sampled_from(paths))
    value = draw(leaf_value(at(rec, path)))
    at(doc, path[:-1])[path[-1]] = value
    return json.dumps(doc), kind, path, value


@budget(5)
@given(data=st.data())
def test_fuzz_edited_run_records(tmp_path_factory, counts, finished_runs, data):
    """`rodval simulate RUN/run.json` over a run.json with random edits (unknown keys such as
    "rtoll" anywhere, wrong types, out-of-range values, deleted keys, truncation, edited
    stats): exit 0/1 with finite outputs, or 2 with one clear line; a rerun that succeeds
    used every input it was given (an edited input is in its own run.json as edited, an
    unknown key is refused rather than dropped)."""
    c = counts("edited_run_records")
    tmp = tmp_path_factory.mktemp("rerun")
    text = (finished_runs["reduced"] / "run.json").read_text()
    rec = json.loads(text)
    edited, kind, path, value = data.draw(run_record_edit(rec, text))
    (tmp / "run.json").write_text(edited)
    code, stdout, stderr = run_cli(["simulate", tmp / "run.json", "--out", tmp / "out"], c)
    if code == 2:
        refusal_is_clear(stderr, c)
        return
    assert stdout.strip(), stderr
    bad = check_run(tmp / "out", code)
    c.nonfinite += bad
    assert not bad, f"success with non-finite outputs: {kind} {path} = {value!r}"
    refused_late(stdout, c)
    new = read_record(tmp / "out")
    if new is None or path is None or path[0] not in RUN_INPUTS or path[:2] in DERIVED:
        return
    if kind == "unknown key" or path[0] not in RUN_INPUTS:
        c.ignored += 1
        raise AssertionError(f"unknown key {'.'.join(map(str, path))} = {value!r} ignored")
    try:
        ran = at(new, path)
    except (KeyError, IndexError, TypeError):
        ran = "<missing>"
    if not same(ran, value):
        c.ignored += 1
        raise AssertionError(f"{'.'.join(map(str, path))} = {value!r} ran as {ran!r}")


BAD_VALUES = st.sampled_from(
    [
        None,
        True,
        0,
        -1,
        1.5,
        math.nan,
        math.inf,
        1e300,
        "",
        "x",
        "phi",
        b"x",
        [],
        [1, 2],
        {},
        {"a": 1},
        object(),
        np.float64(math.nan),
        np.array([1.0, 2.0]),
        np.int64(2),
        1j,
        slice(None),
        ("phi", 1),
    ]  # fmt: skip
)

#: Words a message may use for a parameter (besides its name).
ALIASES = {
    "traj": ("trajector",),
    "reference": ("trajector",),
    "quantities": ("quantit",),
    "quantity": ("quantit",),
    "path": ("study", "file"),
    "out": ("folder", "director", "study"),
    "spec": ("study",),
    "name": ("model",),
    "model": ("model",),
}


@pytest.fixture(scope="module")
def api_objects(tmp_path_factory, finished_study):
    import rodval

    scene = rodval.paper_scene(2, t_end=0.05, times=[0.0, 0.025, 0.05], outputs=("phi", "dphi"))
    settings_ = rodval.IntegratorSettings(max_evaluations=50000, max_wall_s=2.0)
    other = rodval.paper_scene(2, t_end=0.05, times=[0.0, 0.025, 0.05], outputs=("phi", "dphi"),
                               EI=1e3)  # fmt: skip
    study_path, study_out = finished_study
    junk = tmp_path_factory.mktemp("junk") / "junk.bin"
    junk.write_bytes(b"\x80\x00garbage")
    return {
        "rodval": rodval,
        "scene": scene,
        "settings": settings_,
        "traj": rodval.simulate(scene, "reduced", settings=settings_),
        "traj_pub": rodval.simulate(scene, "reduced", settings=settings_, coefficients="published"),
        "traj_other": rodval.simulate(other, "reduced", settings=settings_),
        "study_path": study_path,
        "study_out": study_out,
        "junk": junk,
        "tmp": tmp_path_factory.mktemp("api"),
    }


def api_call(o: dict, name: str):
    """(function, good keyword arguments, pools of values per parameter, keywords the
    function does not know) of one public entry point."""
    rv = o["rodval"]
    paths = st.sampled_from([str(o["junk"]), o["junk"].parent, "missing.toml", o["study_out"]])
    fields = ("chain", "loads", "t_end", "times", "outputs", "initial", "name", "latches", "stops")
    table = {
        "simulate": (
            rv.simulate,
            {"scene": o["scene"], "model": "reduced", "settings": o["settings"]},
            {"model": st.sampled_from(["nope", "Full", "exudyn "]), "kernel": st.just("x"),
             "coefficients": st.just("x"), "rtol": st.just(1e-3), "settings": st.just({})},
            ("bogus",),
        ),
        "compare": (
            rv.compare,
            {"traj": o["traj"], "reference": o["traj_pub"]},
            {"reference": st.just(o["traj_other"]),
             "quantities": st.sampled_from([["z"], "phi", ["phi", "phi"], [1], ()])},
            (),
        ),
        "modes": (
            rv.modes,
            {"scene": o["scene"], "model": "reduced"},
            {"about": st.sampled_from(["x", "final"]), "count": st.sampled_from([0, 100, 2.0]),
             "coefficients": st.just("x")},
            ("bogus",),
        ),
        "Scene.with_": (o["scene"].with_, {}, {k: BAD_VALUES for k in fields}, ("n", "bogus")),
        "Trajectory.__getitem__": (
            lambda quantity: o["traj"][quantity],
            {"quantity": "phi"},
            {"quantity": st.sampled_from(["z", "PHI", "alpha", "energy"])},
            (),
        ),
        "load_study": (rv.load_study, {"path": o["study_path"]}, {"path": paths}, ()),
        "read_study_tables": (rv.read_study_tables, {"out": o["study_out"]}, {"out": paths}, ()),
        "run_study": (
            rv.run_study,
            {"spec": rv.load_study(o["study_path"]), "out": o["tmp"] / "study", "workers": 1,
             "progress": False, "report": False},
            {"workers": st.sampled_from([0, 2.5]), "case_timeout": st.sampled_from([0, -1.0]),
             "backend": st.sampled_from(["mpi", "dask "]), "out": st.just(o["junk"])},
            ("bogus",),
        ),
        "paper_scene": (
            rv.paper_scene,
            {"n": 2, "t_end": 0.05},
            {"times": st.just([0.1, 0.0]), "load_node": st.sampled_from([0, 3]),
             "outputs": st.just(["z"])},
            ("bogus", "rtol"),
        ),
        "IntegratorSettings": (
            rv.IntegratorSettings,
            {},
            {k: BAD_VALUES for k in ("method", "rtol", "atol", "max_step", "first_step",
                                      "max_evaluations", "max_wall_s", "blowup_factor",
                                      "min_step_fraction", "stall_steps")},
            ("rtoll",),
        ),
        "get_model": (
            rv.get_model, {"name": "reduced"}, {"name": st.just("nope")}, ("bogus", "rtoll")
        ),
    }  # fmt: skip
    return table[name]


API_NAMES = ("simulate", "compare", "modes", "Scene.with_", "Trajectory.__getitem__",
             "load_study", "read_study_tables", "run_study", "paper_scene",
             "IntegratorSettings", "get_model")  # fmt: skip


@budget(25)
@given(name=st.sampled_from(API_NAMES), data=st.data())
def test_fuzz_python_api(counts, api_objects, name, data):
    """The public API (`rodval.__all__`) called with one or two parameters of a wrong type or
    value (or an unknown keyword): it succeeds, or raises ValueError/TypeError/KeyError with a
    one-line message naming the parameter (anything else, e.g. AttributeError or IndexError
    from deep inside, counts as a traceback), never hangs; a success with an unknown keyword
    (ignored), a comparison of two different scenes, or a run claiming success with
    non-finite values is silently wrong."""
    c = counts("python_api")
    fn, kwargs, pools, unknown = api_call(api_objects, name)
    kwargs = dict(kwargs)
    params = sorted(set(pools) | set(kwargs) - {"progress", "report"})
    changed = []
    for _ in range(data.draw(st.integers(1, 2))):
        key = data.draw(st.sampled_from([*params, *unknown]))
        pool = pools.get(key, BAD_VALUES)
        kwargs[key] = data.draw(st.one_of(pool, BAD_VALUES) if key in pools else BAD_VALUES)
        changed.append(key)
    names = tuple(n for k in changed for n in (k, *ALIASES.get(k, ())))
    if name == "Trajectory.__getitem__":  # a mapping's KeyError names the key itself
        names += (repr(kwargs["quantity"]),)
    names += tuple(  # a message may name a path or name by its value
        str(v) for k in changed if isinstance(v := kwargs[k], (str, Path)) and len(str(v)) >= 3
    )
    shown = ", ".join(f"{k}={kwargs[k]!r:.60}" for k in changed)
    result = run_api(fn, kwargs, c, names, shown)
    if result is None:
        return
    if any(k in unknown for k in changed):
        c.ignored += 1
        raise AssertionError(f"{name}: unknown keyword accepted: {shown}")
    if name == "compare" and kwargs["reference"] is api_objects["traj_other"]:
        c.ignored += 1
        raise AssertionError("compare: runs of two different scenes compared without a word")
    stats = getattr(result, "stats", None)
    if stats is not None and claims_success(stats):
        values = [np.asarray(v, float) for v in result.values.values()]
        bad = int(not all(np.all(np.isfinite(v)) for v in values))
        c.nonfinite += bad
        assert not bad, f"{name}({shown}): success with non-finite values"


RUN_DAMAGES = ("none", "none", "truncate", "nan value", "delete table", "edit run.json")


def damage_run(folder: Path, kind: str, data) -> bool:
    """Damage a run folder in place; True when its trajectory lost or changed data."""
    table = folder / "trajectory.csv"
    if kind == "truncate":
        text = table.read_text()
        table.write_text(text[: data.draw(st.integers(0, len(text) - 2))])
        return True
    if kind == "nan value":
        df = pd.read_csv(table)
        df.loc[data.draw(st.integers(0, len(df) - 1)), "value"] = math.nan
        df.to_csv(table, index=False)
        return True
    if kind == "delete table":
        table.unlink()
    elif kind == "edit run.json":
        rec_path = folder / "run.json"
        text = rec_path.read_text()
        edited, *_ = data.draw(run_record_edit(json.loads(text), text))
        rec_path.write_text(edited)
    return False


@budget(5)
@given(data=st.data())
def test_fuzz_compare_inputs(tmp_path_factory, counts, finished_runs, data):
    """`rodval compare A B` over pairs of run folders, damaged (trajectory.csv truncated at a
    random byte offset, a NaN value, the table deleted, run.json edited) or of different
    scenes (another EI, another n): exit 0 or 2 with one clear line; a comparison of two
    different scenes, or over a damaged trajectory without a word naming it, or with
    non-finite metrics, is silently wrong."""
    c = counts("compare_inputs")
    tmp = tmp_path_factory.mktemp("compare")
    labels = data.draw(st.lists(st.sampled_from(sorted(finished_runs)), min_size=2, max_size=2))
    folders, damaged = [], []
    for i, label in enumerate(labels):
        folder = tmp / f"{'AB'[i]}-{label}"
        shutil.copytree(finished_runs[label], folder)
        if damage_run(folder, data.draw(st.sampled_from(RUN_DAMAGES)), data):
            damaged.append(folder)
        folders.append(folder)
    code, _, stderr = run_cli(["compare", *folders, "--out", tmp / "out"], c)
    if code == 2:
        refusal_is_clear(stderr, c)
        return
    assert code == 0, stderr
    scenes = {"other_EI" if "other_EI" in lb else "other_n" if "other_n" in lb else "base"
              for lb in labels}  # fmt: skip
    if len(scenes) > 1:
        c.ignored += 1
        raise AssertionError(f"compare of two different scenes {labels} succeeded")
    for folder in damaged:
        if str(folder) not in stderr:
            c.ignored += 1
            raise AssertionError(f"compare over a damaged {folder.name}/trajectory.csv: {stderr}")
    table = pd.read_csv(tmp / "out" / "discrepancies.csv")
    bad = int(not np.all(np.isfinite(table.select_dtypes("number").to_numpy(float))))
    c.nonfinite += bad
    assert not bad, f"compare {labels}: non-finite metrics"
