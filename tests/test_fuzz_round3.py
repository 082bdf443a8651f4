"""Fuzzing of what issues 40-45 added, and of run-folder links (issue 46, "round three").

Same contract, budgets and counts as ``tests/test_fuzz.py`` (helpers in
``tests/fuzz_helpers.py``; RODVAL_FUZZ_EXAMPLES, RODVAL_FUZZ_STATS): every example ends in
exit 0/1 with a status line and finite outputs, or exit 2 with one line in rodval's words;
never a traceback or a hang. Counted besides: *data loss* (a file rodval did not write changed
or removed, a symbolic link's target included), *silently wrong* (an input a run ignored, a
folder mixing two commands' files, a stale file of an earlier run, a lock table with blanks
and no reason), *late refusals* (an input error reported as a failed run) and *unclear*
refusals (the one line does not name the key, file or option at fault, or contradicts
itself).

The inputs: prescribed bases (every motion law with good and hostile parameters, the
``drive`` output, every method including scipy's), free bases, held latches, damping ratios,
scene arrays of wrong lengths and types at every level, scene files that start from another
(``based_on``), scene files in studies (``[scene] file``: a study file, a missing file, a
folder) with lock gates and acceptance on events, wall budgets, ``rodval modes`` (held
latches, model options, free bases, ``--count``, run.json reruns), ``rodval animate``, lock
tables of ``rodval compare`` over edited events, run folders whose ``run.json``, trajectory
or whole folder is a symbolic link to another run's or a user's file, outputs under missing
parent folders and a second command's output into another command's folder.

``RODVAL_FUZZ_FINDS=FILE`` records every find as a JSON line and goes on (a survey) instead
of failing at the first.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from fuzz_helpers import (
    BUDGET,
    SMALL_STUDY,
    Counts,
    anything,
    budget,
    check_run,
    claims_success,
    lost_files,
    read_record,
    refusal_is_clear,
    refused_late,
    run_api,
    run_cli,
    small_scene,
    snapshot,
    to_toml,
    write_scene,
)
from hypothesis import example, given
from hypothesis import strategies as st

from rodval.cli import main

pytestmark = pytest.mark.fuzz


@pytest.fixture(scope="module")
def counts():
    registry: dict[str, Counts] = {}
    yield lambda name: registry.setdefault(name, Counts(name))
    for c in registry.values():
        c.save()


# ----------------------------------------------------------------------------- checks

#: What a status line must not carry: an exception of Python or numba's compiler reported
#: as a run's end (a bug dumped into stdout and run.json, counted as a traceback).
STATUS_INTERNALS = (
    "Traceback",
    "TypingError",
    "Failed in nopython",
    "NameError",
    "AttributeError",
    "IndexError",
    "UnboundLocalError",
    "AssertionError",
    "TypeError",
    "KeyError",
)


def status_is_clean(stdout: str, c: Counts) -> bool:
    """A run's status line names how it ended, not an exception of rodval's own code."""
    leaked = [p for p in STATUS_INTERNALS if p in stdout]
    if leaked:
        c.fail(
            "tracebacks", f"an internal exception as a run's status ({leaked[0]}): {stdout[:400]}"
        )
        return False
    return True


#: Python's messages beyond ``fuzz_helpers.INTERNAL_PHRASES`` that this round's inputs met
#: (a dict update of a scene table, a dataclass called with the file's keys, numba's
#: compiler): an exit-2 line made of one is a traceback in disguise.
MORE_INTERNAL_PHRASES = (
    "dictionary update sequence",
    "is not iterable",
    "unexpected keyword argument",
    "required positional argument",
    "__init__()",
    "Failed in nopython",
)


def refusal_names(stderr: str, words: tuple[str, ...], c: Counts, what: str) -> bool:
    """An exit-2 line is in rodval's words and names one of ``words`` (the key, file or
    option at fault); a raw OS error is unclear. True when the line passed."""
    refusal_is_clear(stderr, c)
    leaked = [p for p in MORE_INTERNAL_PHRASES if p in stderr]
    low = stderr.lower()
    if leaked:
        c.fail("tracebacks", f"a Python-internal message as refusal ({leaked[0]!r}): {stderr}")
    elif "[errno" in low:
        c.fail("unclear", f"{what}: a raw OS error as refusal: {stderr.strip()}")
    elif words and not any(w.lower() in low for w in words):
        c.fail("unclear", f"{what}: refusal names none of {words}: {stderr.strip()}")
    else:
        return True
    return False


def missing_parent(applies: bool, stderr: str, c: Counts, what: str) -> None:
    """An output under folders that do not exist yet is written there, the folders created
    as users expect (issue 46), not refused (counted once: not after an unclear line)."""
    if applies:
        c.fail("unclear", f"{what} under missing folders refused: {stderr.strip()}")


def finished(out: Path, code: int, stdout: str, stderr: str, c: Counts, what: str):
    """The checks of every `rodval simulate` example; the run record of a run that claims
    success (None otherwise, or when a find was recorded)."""
    if code == 2:
        refusal_names(stderr, (), c, what)
        return None
    if code < 0 or not status_is_clean(stdout, c):
        return None
    if check_run(out, code):
        c.fail("nonfinite", f"success with non-finite outputs: {what}")
        return None
    if "ValueError" in stdout:
        refused_late(stdout, c)
        return None
    rec = read_record(out)
    return rec if rec is not None and claims_success(rec["stats"]) else None


# ----------------------------------------------------------------------------- strategies

HOSTILE_NUMBERS = st.sampled_from(
    [math.nan, math.inf, -math.inf, 0.0, -1.0, 1e300, -1e300, "1.0", True, [1.0], {}]
)
#: each law's parameters: (name, lowest, highest) of a good value
LAWS = {
    "constant": (("value", -0.5, 0.5),),
    "linear": (("value", -0.5, 0.5), ("rate", -2.0, 2.0)),
    "harmonic": (("amplitude", -0.3, 0.3), ("omega", 0.1, 40.0), ("phase", -3.2, 3.2)),
    "spin_up": (("rate", -5.0, 5.0), ("time", 0.01, 2.0)),
}


@st.composite
def motion_law(draw, hostile: bool = True) -> object:
    """One axis of ``[base.motion]``: a law with good parameters, or (``hostile``) one made
    hostile: an unknown law, a parameter missing, an extra one, a bad value, not a table."""
    law = draw(st.sampled_from(sorted(LAWS)))
    spec: dict = {"law": law}
    for name, lo, hi in LAWS[law]:
        spec[name] = draw(st.floats(lo, hi))
    kind = draw(st.sampled_from(["value", "missing", "extra", "law", "raw"])) if hostile else ""
    if kind == "value":
        spec[draw(st.sampled_from([n for n, _, _ in LAWS[law]]))] = draw(HOSTILE_NUMBERS)
    elif kind == "missing":
        del spec[draw(st.sampled_from(sorted(spec)))]
    elif kind == "extra":
        spec[draw(st.sampled_from(["bogus", "amplitude", "time", "Value"]))] = 1.0
    elif kind == "law":
        spec["law"] = draw(st.sampled_from(["Constant", "step", "", 1, "spin-up"]))
    elif kind == "raw":
        return draw(st.one_of(anything, st.sampled_from(["spin_up", [1.0, 2.0]])))
    return spec


VECTORS = st.sampled_from(
    [[1.0], [1.0, 2.0, 3.0], "x", 5, [math.nan, 0.0], [True, 0.0], [[1.0], 2]]
)
GOOD_VECTORS = st.lists(st.floats(-1.0, 1.0), min_size=2, max_size=2)


@st.composite
def base_table(draw) -> object:
    """A ``[base]`` table: a valid prescribed (most) or free base, or one with one to three
    hostile values (a law, a vector, a mass, a key the kind does not take, the kind)."""
    choice = draw(st.integers(0, 9))
    if choice == 9:
        return draw(st.one_of(anything, st.sampled_from([{"kind": "Prescribed"}, "free", []])))
    kind = "free" if choice in (6, 7) else "prescribed"
    hostile = choice == 8
    base: dict = {"kind": kind}
    if draw(st.booleans()):
        base["hinge_offset"] = draw(GOOD_VECTORS)
    if kind == "prescribed":
        axes = draw(st.sets(st.sampled_from(["x", "y", "attitude"]), min_size=1))
        base["motion"] = {a: draw(motion_law(hostile=False)) for a in sorted(axes)}
    else:
        base["mass"] = draw(st.floats(1.0, 1e4))
        base["inertia"] = draw(st.floats(1.0, 1e4))
        for key in draw(st.sets(st.sampled_from(["position", "velocity", "attitude", "rate"]))):
            base[key] = draw(GOOD_VECTORS if key in ("position", "velocity") else st.floats(-1, 1))
    for _ in range(draw(st.integers(1, 3)) if hostile else 0):
        what = draw(st.sampled_from(["law", "law", "vector", "mass", "foreign", "motion"]))
        if what == "law" and isinstance(base.get("motion"), dict):
            base["motion"][draw(st.sampled_from(["x", "y", "attitude", "z"]))] = draw(motion_law())
        elif what == "vector":
            base[draw(st.sampled_from(["hinge_offset", "position"]))] = draw(VECTORS)
        elif what == "mass":
            base[draw(st.sampled_from(["mass", "inertia"]))] = draw(HOSTILE_NUMBERS)
        elif what == "foreign":
            base[draw(st.sampled_from(["mass", "motion", "rate", "bogus"]))] = 1.0
        else:
            base["motion"] = draw(st.one_of(anything, st.just("spin_up")))
    return base


MOVING_OUTPUTS = ["phi", "dphi", "x", "y", "energy", "base", "drive", "momentum",
                  "angular_momentum", "hinge_angle", "hinge_moment"]  # fmt: skip
METHODS = [None, "auto", "RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA", "DOP853-numba",
           "Radau-numba"]  # fmt: skip
#: model options and scene values on the command line (the latter once `--set chain.EI=...`
#: works for a single run: then they must be honoured)
SETS = st.sampled_from([
    [], [], [], [], [], [], ["--set", "shapes=2"], ["--set", "kinematics=exact"],
    ["--set", "shapes=2", "--set", "kinematics=exact"], ["--set", "shapes=0"],
    ["--set", "kinematics=second"], ["--set", "chain.EI=2e4"], ["--set", "chain.EI=x"],
    ["--set", "t_end=0.02"], ["--set", "base.kind=free"],
])  # fmt: skip


@st.composite
def moving_base_doc(draw) -> dict:
    doc = small_scene(draw, n_max=3)
    doc["t_end"] = min(doc["t_end"], 0.1)
    doc["base"] = draw(base_table())
    kind = doc["base"].get("kind") if isinstance(doc["base"], dict) else None
    pool = [o for o in MOVING_OUTPUTS if (o != "drive" or kind == "prescribed" or
                                          not draw(st.integers(0, 5)))]  # fmt: skip
    outputs = draw(st.lists(st.sampled_from(pool), min_size=1, max_size=3, unique=True))
    for name in ("drive", "base", "energy"):  # each often: what the moving bases add
        if name not in outputs and name in pool and draw(st.booleans()):
            outputs.append(name)
    doc["outputs"] = outputs
    if draw(st.integers(0, 3)) == 0:  # the root clamped to the body
        doc.pop("initial", None)
        doc["latches"] = [{"hinge": 0, "angle": 0.0, "held": True}]
    return doc


def honoured(c: Counts, what: str, given_, ran) -> bool:
    """``given_`` ran as given (numbers to the last bit, a bool never equal to a number);
    an ignored or changed input is silently wrong."""
    ok = _same(given_, ran)
    if not ok:
        c.fail("ignored", f"{what}: {given_!r} ran as {ran!r}")
    return ok


def _same(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return all(k in b and _same(v, b[k]) for k, v in a.items())
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return a == b
    return a == b


def check_sets(argv: list, rec: dict, c: Counts) -> None:
    """Every `--set KEY=VALUE` of a run that succeeded is in its run.json."""
    for i, a in enumerate(argv):
        if a != "--set":
            continue
        key, value = str(argv[i + 1]).split("=", 1)
        path = key.split(".")
        where = rec["options"] if len(path) == 1 and path[0] in rec["options"] else rec["scene"]
        for p in path:
            where = where.get(p) if isinstance(where, dict) else None
        try:
            expected: object = json.loads(value)
        except ValueError:
            expected = value
        if isinstance(where, list) and isinstance(expected, (int, float)):
            where = where[0] if len(set(where)) == 1 else where
        honoured(c, f"--set {key}={value}", expected, where)


# ----------------------------------------------------------------------------- tests


#: issue 46's prescribed base with the `drive` output on a scipy method (numba's TypingError)
DRIVEN = {"based_on": "paper", "n": 2, "t_end": 0.02, "times": {"num": 3},
          "outputs": ["phi", "drive"], "base": {"kind": "prescribed", "motion": {
              "attitude": {"law": "spin_up", "rate": 2.0, "time": 0.05}}}}  # fmt: skip


@budget(6)
@example(doc=DRIVEN, model="full", method="Radau", sets=[])
@example(doc=DRIVEN, model="reduced", method=None, sets=[])
@given(doc=moving_base_doc(), model=st.sampled_from(["full", "full", "reduced"]),
       method=st.sampled_from(METHODS), sets=SETS)  # fmt: skip
def test_fuzz_moving_bases(tmp_path_factory, counts, doc, model, method, sets):
    """`rodval simulate` of prescribed bases (every law, good and hostile parameters, the
    `drive` output, every method) and free bases: exit 0/1 with a clean status line and finite
    outputs, or 2 with one line; the reduced model refuses a moving base before any work; a
    run that succeeds ran the base, its laws and every `--set` as given."""
    c = counts("moving_bases")
    tmp = tmp_path_factory.mktemp("base")
    path = write_scene(tmp, doc)
    argv = ["simulate", path, "--model", model, "--out", tmp / "out", *BUDGET, *sets]
    argv += ["--method", method] if method else []
    code, stdout, stderr = run_cli(argv, c)
    rec = finished(tmp / "out", code, stdout, stderr, c, str(doc))
    kind = doc["base"].get("kind") if isinstance(doc["base"], dict) else None
    if model == "reduced" and kind in ("free", "prescribed") and code in (0, 1):
        c.fail("ignored", f"the reduced model ran a {kind} base: {stdout[:200]}")
        return
    if rec is None:
        return
    check_sets(argv, rec, c)
    ran = rec["scene"]["base"]
    honoured(c, "base kind", kind, ran.get("kind"))
    if kind == "prescribed" and isinstance(doc["base"].get("motion"), dict):
        honoured(c, "base.motion", doc["base"]["motion"], ran.get("motion"))


LATCH_HELD = st.sampled_from([True, True, False, "true", 1, 0, [True], {}])
RATIOS = st.one_of(
    st.floats(0.0, 0.2),
    st.lists(st.floats(0.0, 0.2), min_size=1, max_size=4),
    st.sampled_from([1.0, -0.01, math.nan, math.inf, "0.01", True, [], {"ratio": 0.01}]),
)


@st.composite
def held_doc(draw) -> dict:
    """A small chain with held latches (at their initial angle and at rest, or not), damping
    given as a ratio or a coefficient, and its hinge angles among the outputs."""
    n = draw(st.integers(1, 4))
    phi = [0.0] * n if draw(st.integers(0, 4)) else [draw(st.floats(-0.3, 0.3)) for _ in range(n)]
    doc: dict = {"based_on": "paper", "n": n, "t_end": draw(st.floats(0.01, 0.1)),
                 "times": {"num": draw(st.integers(2, 6))}, "outputs": ["phi", "hinge_angle"],
                 "initial": {"phi": phi}}  # fmt: skip
    if draw(st.integers(0, 3)) == 0:
        doc["initial"]["dphi"] = draw(st.floats(-1.0, 1.0))
    latches = []
    for hinge in sorted(draw(st.sets(st.integers(0, n), max_size=n))):
        latch = {"hinge": hinge, "angle": 0.0, "held": draw(LATCH_HELD)}
        if draw(st.integers(0, 4)) == 0:
            latch["angle"] = draw(st.one_of(st.floats(-0.3, 0.3), HOSTILE_NUMBERS))
        if draw(st.integers(0, 6)) == 0:
            latch[draw(st.sampled_from(["direction", "window"]))] = draw(st.sampled_from([1, 0.01]))
        latches.append(latch)
    doc["latches"] = latches
    bd = draw(st.integers(0, 3))
    if bd:
        doc["chain"] = {"bending_damping": {"ratio": draw(RATIOS)} if bd > 1 else draw(RATIOS)}
        if draw(st.integers(0, 6)) == 0:
            doc["chain"]["bending_damping"] = {"ratio": 0.01, "c": 1.0}
    return doc


def hinge_angles(doc: dict) -> list[float]:
    """The initial hinge angles D_k = phi_k+1 - phi_k (D_0 = phi_1) of a straight chain."""
    phi = doc["initial"]["phi"]
    return [phi[0], *(b - a for a, b in zip(phi, phi[1:], strict=False))]


@budget(6)
@given(doc=held_doc(), model=st.sampled_from(["full", "reduced"]),
       method=st.sampled_from([None, "RK45", "Radau", "DOP853-numba", "Radau-numba"]))  # fmt: skip
def test_fuzz_held_latches_and_damping_ratios(tmp_path_factory, counts, doc, model, method):
    """Held latches (`held = true`, at or off their angle, moving, of the wrong type) and
    bending damping as a ratio: exit 0/1 or 2 with one line; a run that succeeds kept every
    held hinge at its angle (to 1e-6 rad) and turned a ratio > 0 into damping > 0."""
    c = counts("held_latches_ratios")
    tmp = tmp_path_factory.mktemp("held")
    path = write_scene(tmp, doc)
    argv = ["simulate", path, "--model", model, "--out", tmp / "out", *BUDGET]
    argv += ["--method", method] if method else []
    code, stdout, stderr = run_cli(argv, c)
    rec = finished(tmp / "out", code, stdout, stderr, c, str(doc))
    if rec is None:
        return
    from rodval.report.run_files import read_run

    traj = read_run(tmp / "out")
    angles = np.asarray(traj["hinge_angle"], float)
    for latch in doc["latches"]:
        if latch.get("held") is True and latch["hinge"] < doc["n"]:
            drift = float(np.max(np.abs(angles[:, latch["hinge"]] - latch["angle"])))
            if drift > 1e-6:
                c.fail("ignored", f"held hinge {latch['hinge']} moved {drift:.3g} rad: {doc}")
    bd = doc.get("chain", {}).get("bending_damping")
    if isinstance(bd, dict) and isinstance(bd.get("ratio"), float) and bd["ratio"] > 0:
        c_ran = np.asarray(rec["scene"]["chain"]["bending_damping"], float)
        if not np.all(c_ran > 0):
            c.fail("ignored", f"bending_damping ratio {bd['ratio']} ran as {c_ran}")


#: Values of a wrong type or length for any table or array of a scene file.
WRONG = st.sampled_from([5, [1, 2], True, "x", 1.5, [], {}, [[1.0]], [{"a": 1}], {"first": "x"},
                         {"at": [0, 1]}, {"first": [1.0], "rest": "x"}, [True, 1.0], "1e5"])  # fmt: skip
#: Where a wrong value goes: (dotted path, words a refusal may name it by).
SPOTS = (
    ("chain", ("chain",)),
    ("initial", ("initial",)),
    ("loads", ("loads",)),
    ("latches", ("latches",)),
    ("stops", ("stops",)),
    ("times", ("times",)),
    ("outputs", ("outputs",)),
    ("base", ("base",)),
    ("name", ("name",)),
    ("chain.l", ("l", "length")),
    ("chain.EI", ("EI",)),
    ("chain.mu", ("mu",)),
    ("chain.kappa", ("kappa",)),
    ("chain.rest_angle", ("rest_angle",)),
    ("chain.bending_damping", ("bending_damping",)),
    ("initial.phi", ("phi",)),
    ("initial.dbeta", ("dbeta",)),
    ("times.num", ("num",)),
    ("base.motion", ("motion",)),
    ("base.hinge_offset", ("hinge_offset",)),
    ("base.motion.attitude", ("attitude",)),
    ("latches.0", ("latches",)),
    ("latches.0.held", ("held",)),
    ("loads.0.node", ("node",)),
    ("chain.bending_damping.ratio", ("ratio", "bending_damping")),
    ("based_on", ("based_on",)),
)


def put(doc: dict, dotted: str, value) -> None:
    """Set ``doc[a][b]...`` along a dotted path (list indices as digits), replacing whatever
    on the way is not a table (or a list long enough) by one."""
    parts = dotted.split(".")
    where: Any = doc
    for part, nxt in zip(parts, parts[1:], strict=False):
        key: Any = int(part) if isinstance(where, list) else part
        child = (
            where[key] if key in (range(len(where)) if isinstance(where, list) else where) else None
        )
        if nxt.isdigit() and not (isinstance(child, list) and len(child) > int(nxt)):
            child = [{} for _ in range(int(nxt) + 1)]
        elif not nxt.isdigit() and not isinstance(child, dict):
            child = {}
        where[key] = child
        where = child
    where[int(parts[-1]) if isinstance(where, list) else parts[-1]] = value


@st.composite
def wrong_array_doc(draw, tmp_scene: str) -> tuple[dict, tuple[str, ...]]:
    """A small scene with one to three values of a wrong type or length anywhere (or a
    `based_on` naming another file: itself, a scene file, a folder, a missing file)."""
    doc = small_scene(draw, n_max=3)
    n = doc["n"]
    doc["base"] = {"kind": "prescribed", "motion": {"attitude": {"law": "constant", "value": 0.0}}}
    doc["latches"] = [{"hinge": 0, "angle": 0.0, "held": True}]
    doc.pop("initial", None)
    words: tuple[str, ...] = ()
    for _ in range(draw(st.integers(1, 3))):
        spot, names = draw(st.sampled_from(SPOTS))
        if spot == "based_on":
            value = draw(st.sampled_from([tmp_scene, "scene.toml", ".", "missing.toml", "paper",
                                          "Paper", 5]))  # fmt: skip
        elif spot.startswith(("chain.", "initial.")) and draw(st.booleans()):
            value = [1.0] * draw(st.sampled_from([n - 1, n + 1, 2 * n + 3]))  # wrong length
        else:
            value = draw(WRONG)
        put(doc, spot, value)
        words += (*names, *(p for p in spot.split(".") if not p.isdigit()))
    return doc, words


@budget(10)
@given(data=st.data())
def test_fuzz_scene_arrays(tmp_path_factory, counts, data):
    """Scene files with values of a wrong type or length at every level (`chain = 5`,
    `chain = [1, 2]`, `chain = true`, `chain = "x"`, profiles with bad members, arrays of n - 1
    or n + 1) and `based_on` another file: exit 0 (only for a `based_on` that resolves), or 2
    with one line in rodval's words naming the key at fault."""
    c = counts("scene_arrays")
    tmp = tmp_path_factory.mktemp("arrays")
    other = tmp / "other.toml"
    other.write_text(to_toml({"n": 2, "t_end": 0.05, "chain": {"l": 1.0, "m": 1.0, "EI": 1e4}}))
    doc, words = data.draw(wrong_array_doc(str(other)))
    path = write_scene(tmp, doc)
    argv = ["simulate", path, "--model", "full", "--out", tmp / "out", *BUDGET]
    code, stdout, stderr = run_cli(argv, c)
    if code == 2:
        refusal_names(stderr, (*words, "scene.toml", "other.toml"), c, str(doc))
    elif code in (0, 1):
        finished(tmp / "out", code, stdout, stderr, c, str(doc))


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    """Scenes and finished outputs to point commands at: run folders of a latched 3-rod
    deployment (full: `A`, reduced: `B`), of a pinned 2-rod chain (full `P`, reduced `Q`, full
    with shapes = 2 `S2`), of a free base with x, y (`F`) and with phi only (`G`), of a
    prescribed base (`R`); a finished study; a compare folder (`C`) and a modes folder (`M`)."""
    tmp = tmp_path_factory.mktemp("world")
    latch = {"n": 3, "t_end": 0.5, "times": {"num": 11}, "outputs": ["phi", "x", "y"],
             "chain": {"l": 1.5, "m": 3.0, "EI": 1e5, "mu": 0.5, "kappa": [0.0, 50.0, 50.0]},
             "initial": {"phi": [0.0, 3.0915926535897933, 0.0]},
             "latches": [{"hinge": 1, "angle": 0.0}, {"hinge": 2, "angle": 0.0}]}  # fmt: skip
    pinned = {"based_on": "paper", "n": 2, "t_end": 0.05, "times": {"num": 3},
              "outputs": ["phi", "x", "y"]}  # fmt: skip
    free = {**pinned, "base": {"kind": "free", "mass": 100.0, "inertia": 50.0}}
    free_phi = {**free, "outputs": ["phi"]}
    driven = {**pinned, "outputs": ["phi", "base", "drive"], "base": {"kind": "prescribed",
              "motion": {"attitude": {"law": "spin_up", "rate": 2.0, "time": 0.05}}}}  # fmt: skip
    scenes = {}
    for name, doc in (("latch", latch), ("pinned", pinned), ("free", free),
                      ("free_phi", free_phi), ("driven", driven)):  # fmt: skip
        scenes[name] = tmp / f"{name}.toml"
        scenes[name].write_text(to_toml(doc))
    runs = {}
    for label, scene, model, extra in (
        ("A", "latch", "full", []), ("B", "latch", "reduced", []), ("P", "pinned", "full", []),
        ("Q", "pinned", "reduced", []), ("S2", "pinned", "full", ["--set", "shapes=2"]),
        ("F", "free", "full", []), ("G", "free_phi", "full", []), ("R", "driven", "full", []),
    ):  # fmt: skip
        argv = ["simulate", scenes[scene], "--model", model, "--out", tmp / label, *extra]
        assert main([str(a) for a in argv]) == 0, label
        runs[label] = tmp / label
    study = tmp / "study.toml"
    study.write_text(to_toml(SMALL_STUDY))
    done = tmp / "done"
    argv = ["study", study, "--out", done, "--workers", "1", "--no-progress"]
    assert main([str(a) for a in argv]) == 0
    assert main([str(a) for a in ["compare", runs["B"], runs["A"], "--out", tmp / "C"]]) == 0
    assert main([str(a) for a in ["modes", scenes["pinned"], "--model", "reduced", "--out",
                                  tmp / "M"]]) == 0  # fmt: skip
    return {"tmp": tmp, "scenes": scenes, "runs": runs, "study": study, "done": done,
            "C": tmp / "C", "M": tmp / "M"}  # fmt: skip


@st.composite
def study_source_doc(draw, w: dict, tmp: Path) -> tuple[dict, tuple[str, ...]]:
    """A study whose `[scene]` names a file (a good scene, a study file, a missing file, a
    folder, not a string, with `based_on`), with overrides, acceptance tables on events
    (good and hostile), and sometimes a prescribed base for the reduced model."""
    target = draw(st.sampled_from(["latch", "latch", "pinned", "driven", "study", "missing",
                                   "folder", "self", 5, ["x"], ""]))  # fmt: skip
    files = {"study": str(w["study"]), "missing": str(tmp / "missing.toml"), "folder": str(tmp),
             "self": str(tmp / "mine.toml")}  # fmt: skip
    named = isinstance(target, str) and target in w["scenes"]
    scene: dict = {"file": str(w["scenes"][target]) if named else
                   files.get(target, target) if isinstance(target, str) else target}  # fmt: skip
    words: tuple[str, ...] = (Path(str(scene["file"])).name,)
    if not isinstance(target, str) or not target:
        words += ("scene.file",)  # not a path: the key names it
    for key in draw(st.sets(st.sampled_from(["t_end", "chain", "based_on", "latches", "n",
                                             "base", "bogus"]), max_size=2)):  # fmt: skip
        scene[key] = draw(st.sampled_from({
            "t_end": [0.05, 0.0, "x"], "chain": [{"EI": 2e5}, {"EI": "x"}, 5],
            "based_on": ["paper"], "latches": [[], 5, [{"hinge": 1, "angle": 0.0, "held": True}]],
            "n": [2, 0], "base": [{"kind": "prescribed"}, "free"], "bogus": [1],
        }[key]))  # fmt: skip
        words += (key,)
    models = draw(st.sampled_from([{"full": {}, "reduced": {}}, {"full": {}, "exact": {
        "model": "full", "kinematics": "exact"}}, {"reduced": {}, "full": {}}]))  # fmt: skip
    doc: dict = {
        "study": {"name": "fz", "reference": next(iter(models))},
        "scene": scene,
        "integrator": {"max_evaluations": 50000, "max_wall_s": 10.0},
        "models": models,
    }
    if draw(st.booleans()):
        other = [m for m in models if m != doc["study"]["reference"]][0]
        event = {"model": other, "lock_time": 2e-3, "impulse": 0.05}
        bad = draw(st.sampled_from([None, "lock_time", "impulse", "model", "extra", "empty"]))
        if bad in ("lock_time", "impulse"):
            event[bad] = draw(HOSTILE_NUMBERS)
        elif bad == "model":
            event["model"] = doc["study"]["reference"]
        elif bad == "extra":
            event["dt"] = 1.0
        elif bad == "empty":
            event = {"model": other}
        acc: dict = {"event": [event]}
        for key in draw(st.sets(st.sampled_from(["all_latched", "energy_residual",
                                                 "momentum_residual", "valid"]))):  # fmt: skip
            acc[key] = draw(st.sampled_from([0.95, 1.0, 1e-2, 0.0, 2.0, math.nan, "x", True]))
        doc["acceptance"] = acc
        words += ("acceptance",)
    if draw(st.integers(0, 3)) == 0:
        doc["grid"] = draw(st.sampled_from([{"scene.chain.EI": [1e4, 1e5]}, {"scene.file": ["a"]},
                                            {"scene.t_end": [0.05, 0.1]}]))  # fmt: skip
        words += ("grid",)
    return doc, words


#: A model run's end that is an input the study could have refused before any work.
LATE = ("ValueError", "has no prescribed base", "has no free base", "refuse", "not built")


@budget(3, share=10)
@given(data=st.data())
def test_fuzz_study_scene_files(tmp_path_factory, counts, world, data):
    """Studies whose `[scene]` names a scene file (a study file, a missing file, a folder,
    itself, not a string, overrides good and bad, `based_on`) with acceptance on lock events
    (good and hostile bounds), run on a short horizon: exit 0/1 with tables, or 2 with one
    line naming the key or file at fault; no model run fails for an input the study could have
    refused before any work (a prescribed base given to the reduced model: late)."""
    c = counts("study_scene_files")
    tmp = tmp_path_factory.mktemp("studyscene")
    doc, words = data.draw(study_source_doc(world, tmp))
    if isinstance(doc["scene"], dict) and "t_end" not in doc["scene"]:
        doc["scene"].update(t_end=0.02, times={"num": 3})
    path = tmp / "mine.toml"
    path.write_text(to_toml(doc))
    argv = ["study", path, "--out", tmp / "out", "--workers", "1", "--no-progress",
            "--no-report", "--case-timeout", "30"]  # fmt: skip
    code, _, stderr = run_cli(argv, c)
    if code == 2:
        refusal_names(stderr, words, c, str(doc))
        return
    runtime = tmp / "out" / "runtime.csv"
    if code < 0 or not runtime.is_file():
        return
    table = pd.read_csv(runtime)
    failed = table[table["status"].astype(str) != "success"]
    text = " ".join(str(v) for v in failed["message"])
    if any(w in text for w in LATE):
        c.fail("late", f"a study ran and failed runs for its input: {text[:300]}")


WALLS = st.sampled_from(["inf", "Infinity", "nan", "0", "-1", "-inf", "x", "", "1e-9", "2", "1e308",
                         "0x10", "1_0", "2s"])  # fmt: skip


@budget(8)
@example(wall="inf", where="simulate")
@given(wall=WALLS, where=st.sampled_from(["simulate"] * 3 + ["run.json"] * 2 + ["study"]))
def test_fuzz_wall_budgets(tmp_path_factory, counts, world, wall, where):
    """`--max-wall` (and a study's `max_wall_s`, a run.json's `settings.max_wall_s`) with inf,
    nan, 0, negative, strings: a finite budget > 0 or inf runs (exit 0/1); anything else is
    refused in one line naming it; a refusal of inf (documented as allowed) or a line that
    contradicts itself is unclear."""
    c = counts("wall_budgets")
    tmp = tmp_path_factory.mktemp("wall")
    if where == "simulate":
        argv = ["simulate", world["scenes"]["pinned"], "--model", "reduced", "--out", tmp / "o",
                "--max-wall", wall]  # fmt: skip
    elif where == "run.json":
        rec = json.loads((world["runs"]["Q"] / "run.json").read_text())
        rec["settings"]["max_wall_s"] = float(wall) if _number(wall) else wall
        (tmp / "run.json").write_text(json.dumps(rec))
        argv = ["simulate", tmp / "run.json", "--out", tmp / "o"]
    else:
        doc = {**SMALL_STUDY, "integrator": {"max_wall_s": float(wall) if _number(wall) else wall}}
        (tmp / "study.toml").write_text(to_toml(doc))
        argv = ["study", tmp / "study.toml", "--out", tmp / "o", "--no-progress", "--no-report",
                "--workers", "1"]  # fmt: skip
    code, stdout, stderr = run_cli(argv, c)
    good = _number(wall) and float(wall) > 0 and not math.isnan(float(wall))
    if code == 2:
        refusal_names(stderr, ("max-wall", "max_wall"), c, f"{where} {wall!r}")
        if good and float(wall) > 1e-3:
            c.fail("unclear", f"{where}: budget {wall!r} refused: {stderr.strip()}")
    elif code in (0, 1):
        if not good:
            c.fail("ignored", f"{where}: budget {wall!r} accepted: {stdout[:200]}")
        if where != "study":
            finished(tmp / "o", code, stdout, stderr, c, f"{where} {wall}")


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return text.strip() == text


@st.composite
def modes_case(draw, w: dict, tmp: Path) -> tuple[list, dict]:
    """A `rodval modes` command line and what it must honour: a small chain (springs on every
    hinge) with held latches, on a pinned or free base, model options, --count, or a run.json
    of a shapes = 2 run."""
    n = draw(st.integers(1, 4))
    doc: dict = {"based_on": "paper", "n": n, "t_end": 0.1}
    held = sorted(draw(st.sets(st.integers(0, n - 1), max_size=n)))
    doc["latches"] = [{"hinge": k, "angle": 0.0, "held": True} for k in held]
    if draw(st.integers(0, 3)) == 0:
        doc["base"] = {"kind": "free", "mass": draw(st.floats(10.0, 1e3)), "inertia": 50.0}
    scene = tmp / "scene.toml"
    scene.write_text(to_toml(doc))
    source = scene if draw(st.integers(0, 4)) else w["runs"]["S2"] / "run.json"
    argv: list = ["modes", source, "--out", tmp / "out"]
    model = draw(st.sampled_from(["full", "full", "reduced", None]))
    argv += ["--model", model] if model else []
    sets = draw(st.sampled_from([[], [], ["shapes=2"], ["kinematics=exact"], ["shapes=3"],
                                 ["shapes=9"]]))  # fmt: skip
    for s in sets:
        argv += ["--set", s]
    count = draw(st.sampled_from([None, "3", "6", "1", "0", "-1", "1.5", "x", "100"]))
    argv += ["--count", count] if count else []
    if draw(st.integers(0, 4)) == 0:
        argv += ["--compare", draw(st.sampled_from(["full,reduced", "full", "nope"]))]
    return argv, {"doc": doc, "held": held, "sets": sets, "count": count, "source": source}


def _modes_api(doc: dict, model: str, options: dict):
    """The frequencies (rad/s) of a scene document through the Python API."""
    import rodval
    from rodval.core.scene_file import scene_from_dict

    return rodval.modes(scene_from_dict(doc), model, **options).omega


@budget(4)
@given(data=st.data())
def test_fuzz_modes(tmp_path_factory, counts, world, data):
    """`rodval modes` with held latches, free bases, shapes/kinematics options, --count and
    run.json reruns: exit 0 or 2 with one line; the modes of a chain with held hinges are not
    those of the chain without them (a held latch ignored), a run.json's model options are the
    modes' (modes.json), and --count bounds the flexible modes written."""
    c = counts("modes")
    tmp = tmp_path_factory.mktemp("modes")
    argv, want = data.draw(modes_case(world, tmp))
    code, stdout, stderr = run_cli(argv, c)
    if code == 2:
        refusal_names(stderr, (), c, str(argv))
        return
    if code != 0:
        if code > 0:
            c.fail("tracebacks", f"modes exit {code}: {stdout[:200]} {stderr[:200]}")
        return
    rec = json.loads((tmp / "out" / "modes.json").read_text())
    freq = pd.read_csv(tmp / "out" / "frequencies.csv")
    omega = freq["omega_rad_s"].to_numpy(float)
    flexible = int(np.sum(omega > 1e-6 * max(float(np.max(omega, initial=0.0)), 1.0)))
    count = want["count"]
    if count and count.isdigit() and int(count) > 0 and flexible > int(count):
        c.fail("ignored", f"--count {count} wrote {flexible} flexible modes: {argv}")
    if want["source"] != tmp / "scene.toml":  # the run.json of a shapes = 2 run
        if rec.get("model") == "full":
            given_ = 3 if "shapes=3" in want["sets"] else 2
            honoured(c, "the run's shapes", given_, rec.get("options", {}).get("shapes"))
        return
    # each --set key ran in every model that takes it (--model's options, --compare's)
    ran = [rec.get("options", {}), *rec.get("compared", {}).values()]
    for s in want["sets"]:
        key, value = s.split("=")
        for options in [o for o in ran if key in o] or [{}]:
            honoured(c, f"--set {s}", int(value) if value.isdigit() else value,
                     options.get(key))  # fmt: skip
    if want["held"] and rec.get("model") in ("full", "reduced"):
        free = {**want["doc"], "latches": []}
        opts = {k: int(v) if v.isdigit() else v for k, v in (s.split("=") for s in want["sets"])}
        try:
            base = _modes_api(free, rec["model"], opts)
        except ValueError:
            return
        m = min(len(base), len(omega))
        if m and np.allclose(omega[:m], base[:m], rtol=1e-9, atol=1e-9):
            c.fail("ignored", f"modes with held hinges {want['held']} = those without: {argv}")


@budget(2, share=5)
@given(data=st.data())
def test_fuzz_animate(tmp_path_factory, counts, world, data):
    """`rodval animate` of run folders (pinned, free with and without x, y, prescribed,
    latched) to new files, files under missing folders, a user's file, a link to a user's
    file, a file of a run folder, with hostile --fps/--frames: exit 0 or 2 with one line (no
    raw OS error); no file rodval did not write changes; a free-base run with neither x, y nor
    `base` is refused (docs), not drawn from a pinned root."""
    c = counts("animate")
    tmp = tmp_path_factory.mktemp("animate")
    runs = {k: tmp / k for k in ("A", "P", "F", "G", "R")}
    for k, p in runs.items():
        shutil.copytree(world["runs"][k], p)
    user = tmp / "user"
    user.mkdir()
    (user / "movie.gif").write_bytes(b"GIF89a my own")
    (user / "notes.txt").write_text("mine")
    picked = data.draw(st.lists(st.sampled_from(sorted(runs)), min_size=1, max_size=2, unique=True))
    target = data.draw(st.sampled_from(["new", "missing parents", "user's file", "link",
                                        "run file", "into run", "bad suffix"]))  # fmt: skip
    out = {"new": tmp / "a.gif", "missing parents": tmp / "anim" / "deep" / "a.gif",
           "user's file": user / "movie.gif", "link": tmp / "l.gif",
           "run file": runs["P"] / "run.json", "into run": runs["P"] / "a.gif",
           "bad suffix": tmp / "a.txt"}[target]  # fmt: skip
    if target == "link":
        out.symlink_to(user / "movie.gif")
    frames = data.draw(st.sampled_from(["3"] * 6 + ["2", "1", "0", "x", "1e9"]))
    fps = data.draw(st.sampled_from(["5"] * 6 + ["0", "-1", "1000", "nan"]))
    argv = ["animate", *(runs[k] for k in picked), "--out", out, "--frames", frames, "--fps", fps]
    before = snapshot(user, *runs.values())
    code, _, stderr = run_cli(argv, c)
    lost = [p for p in lost_files(before, snapshot(user, *runs.values())) if p != str(out)]
    if lost:
        c.fail("lost", f"rodval animate changed or removed {lost}: {argv}")
    if code == 2:
        words = ("--out", "--fps", "--frames", str(out), out.name, *(str(runs[k]) for k in picked))
        if refusal_names(stderr, words, c, str(argv)):
            good = frames in ("2", "3") and fps == "5" and "G" not in picked
            missing_parent(target == "missing parents" and good, stderr, c, "animate --out")
    elif code == 0 and "G" in picked:
        c.fail("ignored", f"a free-base run without x, y or base animated: {argv}")
    elif code == 0 and target == "into run":
        c.fail("ignored", f"an animation written into a run folder: {argv}")


#: Files that tell which command wrote a folder.
SIGNATURES = {
    "simulate": {"run.json", "trajectory.csv", "trajectory.npz"},
    "compare": {"discrepancies.csv", "histories.png", "events.csv"},
    "modes": {"frequencies.csv", "modes.json", "modes.csv"},
}
SETUPS = ("run.json -> other run's", "run.json -> user's file", "trajectory.csv -> user's file",
          "folder -> other run", "folder -> user's folder", "missing parents",
          "other command's folder", "a file of a run", "earlier run of the same command",
          "rodval.json -> other's", "user's folder")  # fmt: skip


def _link_target(setup: str, command: str, tmp: Path, v: dict[str, Path]) -> Path:
    """Build the output folder of ``setup`` under ``tmp`` (victims in ``v``)."""
    out = tmp / "out"
    own = {"simulate": v["A"], "compare": v["C"], "modes": v["M"]}[command]
    if setup == "run.json -> other run's":
        shutil.copytree(v["A"], out)
        (out / "run.json").unlink()
        (out / "run.json").symlink_to(v["B"] / "run.json")
    elif setup == "run.json -> user's file":
        shutil.copytree(v["A"], out)
        (out / "run.json").unlink()
        (out / "run.json").symlink_to(v["user"] / "notes.txt")
    elif setup == "trajectory.csv -> user's file":
        shutil.copytree(own, out)
        name = "trajectory.csv" if command == "simulate" else "discrepancies.csv" \
            if command == "compare" else "frequencies.csv"  # fmt: skip
        (out / name).unlink()
        (out / name).symlink_to(v["user"] / "data.csv")
    elif setup == "rodval.json -> other's":
        shutil.copytree(own, out)
        marker = "run.json" if command == "simulate" else "rodval.json"
        (out / marker).unlink()
        (out / marker).symlink_to((v["C"] if command != "compare" else v["M"]) / "rodval.json")
    elif setup == "folder -> other run":
        out.symlink_to(v["B"] if command == "simulate" else v["C"] if command == "compare"
                       else v["M"], target_is_directory=True)  # fmt: skip
    elif setup == "folder -> user's folder":
        out.symlink_to(v["user"], target_is_directory=True)
    elif setup == "user's folder":
        out = v["user"]
    elif setup == "missing parents":
        out = tmp / "missing" / "deeper" / "out"
    elif setup == "other command's folder":
        out = {"simulate": v["C"], "compare": v["M"], "modes": v["C"]}[command]
    elif setup == "a file of a run":
        out = v["A"] / "run.json"
    return out


def _command(command: str, out: Path, w: dict, v: dict[str, Path], second: bool) -> list:
    """The command line; ``second``: the later of two runs into one folder (a pair without
    lock events, modes without --compare, a pinned scene after a latched one)."""
    if command == "simulate":
        scene = w["scenes"]["pinned" if second else "latch"]
        return ["simulate", scene, "--model", "reduced", "--out", out, *BUDGET]
    if command == "compare":
        pair = (v["Q"], v["P"]) if second else (v["B"], v["A"])
        return ["compare", *pair, "--out", out]
    extra = [] if second else ["--compare", "full,reduced"]
    return ["modes", w["scenes"]["pinned"], "--model", "reduced", "--out", out, *extra]


@budget(6)
@example(setup="run.json -> other run's", command="simulate", junit=False)
@example(setup="earlier run of the same command", command="compare", junit=True)
@given(setup=st.sampled_from(SETUPS), command=st.sampled_from(["simulate", "compare", "modes"]),
       junit=st.booleans())  # fmt: skip
def test_fuzz_run_folder_links(tmp_path_factory, counts, world, setup, command, junit):
    """simulate, compare and modes into folders whose run.json, table or marker is a link to
    another run's or a user's file, a folder that is a link (to another run, a user's folder),
    a folder under missing parents, another command's folder, a file of a run, an earlier run
    of the same command; `rodval report --junit` under missing parents and through a link: no
    file rodval did not write changes (through a link included); exit 0 or 2 with one line; a
    folder that ends with two commands' files, or with a file of an earlier run this run does
    not write (events.csv, compare.csv), is silently wrong."""
    c = counts("run_folder_links")
    tmp = tmp_path_factory.mktemp("links")
    v = {k: tmp / k for k in ("A", "B", "P", "Q")}
    for k, p in v.items():
        shutil.copytree(world["runs"][k], p)
    v["C"], v["M"] = tmp / "C", tmp / "M"
    shutil.copytree(world["C"], v["C"])
    shutil.copytree(world["M"], v["M"])
    v["user"] = tmp / "user"
    v["user"].mkdir()
    (v["user"] / "notes.txt").write_text("my own notes\n")
    (v["user"] / "data.csv").write_text("t,x\n0,1\n")
    (v["user"] / "gate.xml").write_text("<?xml version='1.0'?><mine/>")
    out = _link_target(setup, command, tmp, v)
    if setup == "earlier run of the same command":
        assert main([str(a) for a in _command(command, out, world, v, second=False)]) == 0
    victims = [p for k, p in v.items() if p != out or k == "user"]
    before = snapshot(*victims)
    argv = _command(command, out, world, v, second=setup == "earlier run of the same command")
    code, _, stderr = run_cli(argv, c)
    lost = lost_files(before, snapshot(*victims))
    if lost:
        c.fail("lost", f"rodval {command} into {setup}: changed or removed {lost}")
    if junit:
        _junit_case(tmp, world, v, c)
    if code == 2:
        words = ("--out", str(out), out.name, "run.json", "link", "folder")
        if refusal_names(stderr, words, c, f"{command} into {setup}"):
            missing_parent(setup == "missing parents", stderr, c, f"{command} --out")
        return
    if code != 0:
        return
    _mixed_or_stale(out, command, setup, c)


def _mixed_or_stale(out: Path, command: str, setup: str, c: Counts) -> None:
    names = {p.name for p in out.iterdir()} if out.is_dir() else set()
    owners = [k for k, sig in SIGNATURES.items() if names & sig]
    if len(owners) > 1:
        c.fail("ignored", f"{command} into {setup}: the folder mixes {owners}: {sorted(names)}")
    if setup == "earlier run of the same command":
        stale = {"compare": "events.csv", "modes": "compare.csv"}.get(command)
        if stale and stale in names:
            c.fail("ignored", f"{command} rerun left the earlier run's {stale}")


def _junit_case(tmp: Path, w: dict, v: dict[str, Path], c: Counts) -> None:
    """`rodval report --junit` to a path under missing folders, and to a link to a user's
    file: the first is written (or refused naming it), the user's file is never written."""
    done = tmp / "done"
    shutil.copytree(w["done"], done)
    link = tmp / "gate-link.xml"
    link.symlink_to(v["user"] / "gate.xml")
    before = snapshot(v["user"])
    for target in (tmp / "reports" / "ci" / "gate.xml", link):
        code, _, stderr = run_cli(["report", done, "--junit", target], c)
        if code == 2:
            if refusal_names(stderr, ("--junit", str(target)), c, f"--junit {target}"):
                missing_parent(target != link, stderr, c, "report --junit")
    lost = lost_files(before, snapshot(v["user"]))
    if lost:
        c.fail("lost", f"rodval report --junit through a link changed {lost}")


EVENT_EDITS = ("none", "none", "nan time", "string time", "no time", "nan impulse", "no events",
               "swap labels")  # fmt: skip


@budget(4)
@example(pair=("B", "A"), edit="nan time", side=0)
@given(pair=st.sampled_from([("B", "A"), ("A", "B"), ("A", "A"), ("Q", "P"), ("B", "P")]),
       edit=st.sampled_from(EVENT_EDITS), side=st.integers(0, 1))  # fmt: skip
def test_fuzz_compare_events(tmp_path_factory, counts, world, pair, edit, side):
    """`rodval compare` of latched runs whose run.json events were edited (a NaN or text lock
    time, a lock time removed, a NaN impulse, events removed, labels swapped): exit 0 or 2 with
    one line; a lock table whose lock time or impulse is blank or NaN gives the reason in
    `not_comparable` (a blank without a word is silently wrong)."""
    c = counts("compare_events")
    tmp = tmp_path_factory.mktemp("events")
    folders = []
    for i, label in enumerate(pair):
        folder = tmp / f"{'AB'[i]}-{label}"
        shutil.copytree(world["runs"][label], folder)
        folders.append(folder)
    rec_path = folders[side] / "run.json"
    rec = json.loads(rec_path.read_text())
    events = rec.get("events") or []
    if edit != "none" and events:
        if edit == "nan time":
            events[0]["t"] = math.nan
        elif edit == "string time":
            events[0]["t"] = "0.3"
        elif edit == "no time":
            del events[0]["t"]
        elif edit == "nan impulse":
            events[0]["impulse"] = math.nan
        elif edit == "no events":
            rec["events"] = []
        elif edit == "swap labels" and len(events) > 1:
            events[0]["label"], events[1]["label"] = events[1]["label"], events[0]["label"]
        rec_path.write_text(json.dumps(rec))
    scenes_differ = {p in ("A", "B") for p in pair} == {True, False}
    argv = ["compare", *folders, "--out", tmp / "out"]
    argv += ["--allow-different-scenes"] if scenes_differ else []
    code, _, stderr = run_cli(argv, c)
    if code == 2:
        refusal_names(stderr, (), c, str(argv))
        return
    if code != 0:
        return
    table = tmp / "out" / "events.csv"
    if not table.is_file():
        return
    df = pd.read_csv(table)
    cells = df[[k for k in ("t_A", "t_B", "impulse_A", "impulse_B") if k in df.columns]]
    numbers = cells.apply(pd.to_numeric, errors="coerce").to_numpy(float)
    blank = pd.Series(~np.isfinite(numbers).all(axis=1), index=df.index)
    given = df["not_comparable"] if "not_comparable" in df else pd.Series(index=df.index)
    reason = given.astype(object).where(given.notna(), "").astype(str)
    silent = df[blank & (reason.str.strip() == "")]
    if len(silent):
        c.fail("ignored", f"lock table blanks without a reason ({edit}, {pair}): "
                          f"{silent.to_dict('records')}")  # fmt: skip


BAD_PARAMS = st.sampled_from([1.0, None, "1.0", (), (1.0, 2.0, 3.0, 4.0), (math.nan,),
                              (math.inf, 1.0), ("x", 1.0), (True,), [1.0], (1.0, -1.0),
                              (1.0, 0.0), (0.0, 0.0, 0.0), np.array([1.0]), (None,)])  # fmt: skip


@budget(15)
@given(which=st.sampled_from(["Motion", "Motion", "Base", "Latch"]), data=st.data())
def test_fuzz_base_api(counts, which, data):
    """`Motion(law, params)`, `Base(kind="prescribed"/"free", ...)` and `Latch(..., held=...)`
    with values of a wrong type or range: a ValueError (the README's promise; a TypeError
    counts as a traceback) in one line naming the parameter, or an object that holds what it
    was given."""
    import rodval
    from rodval.core.hinges import Latch

    c = counts("base_api")
    if which == "Motion":
        law = data.draw(st.sampled_from(["constant", "linear", "harmonic", "spin_up", "step", 1]))
        kwargs = {"law": law, "params": data.draw(BAD_PARAMS)}
        names = ("motion", "law", "params", "value", "rate", "omega", "time", "amplitude")
        run_api(rodval.Motion, kwargs, c, names, refusals=(ValueError,))
    elif which == "Base":
        kind = data.draw(st.sampled_from(["prescribed", "free"]))
        key = data.draw(st.sampled_from(["motion", "hinge_offset", "mass", "inertia", "position"]))
        value = data.draw(st.one_of(BAD_PARAMS, st.sampled_from([{"z": 1}, {"x": 1.0}, "spin_up",
                                                                  {"attitude": (1.0,)}])))  # fmt: skip
        kwargs = {"kind": kind, key: value}
        if kind == "free" and key not in ("mass", "inertia"):
            kwargs.update(mass=1.0, inertia=1.0)
        run_api(rodval.Base, kwargs, c, ("base", key), refusals=(ValueError,))
    else:
        held = data.draw(st.sampled_from([1, 0, "true", None, [True], np.bool_(True), 1.0]))
        made = run_api(Latch, {"hinge": 1, "angle": 0.0, "held": held}, c, ("held", "latch"),
                       refusals=(ValueError,))  # fmt: skip
        if made is not None and not isinstance(held, (bool, np.bool_)):
            c.fail("ignored", f"Latch(held={held!r}) accepted as held={made.held!r}")


def test_the_links_property_has_a_control(world, tmp_path):
    """The property's control: a rerun into rodval's own run folder (a copy, no links) and a
    compare into a new folder succeed, so the fuzz above does not pass by refusing all."""
    out = tmp_path / "again"
    shutil.copytree(world["runs"]["Q"], out)
    argv = ["simulate", world["scenes"]["pinned"], "--model", "reduced", "--out", out, *BUDGET]
    assert main([str(a) for a in argv]) == 0
    argv = ["compare", world["runs"]["B"], world["runs"]["A"], "--out", tmp_path / "cmp"]
    assert main([str(a) for a in argv]) == 0
    assert (tmp_path / "cmp" / "events.csv").is_file()
    assert os.path.isfile(out / "run.json")
