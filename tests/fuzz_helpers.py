"""Shared helpers of the fuzz suite (``tests/test_fuzz*.py``, marker ``fuzz``): budgets, the
counts each test appends to RODVAL_FUZZ_STATS, running ``rodval`` and the Python API under a
time limit while checking their contract, and the scenes and studies several tests use.

No test module imports another: every fuzz test file takes these from here.

``RODVAL_FUZZ_EXAMPLES`` is the number of examples of each cheap test; the tests that run a
study, build a report or write animations take a fortieth of it (``budget(..., expensive=
True)``). ``RODVAL_FUZZ_STATS`` appends the counts of each test as one JSON line.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import signal
import time
import warnings
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from rodval.cli import main
from rodval.study.toml_text import toml_text

EXAMPLES = int(os.environ.get("RODVAL_FUZZ_EXAMPLES", "0") or 0)
#: Time limit of one example (s).
LIMIT_S = 60.0
#: Budgets given to every run (the fuzzed options may come after them and override them).
#: The wall budget is the whole command's (reading, loading the compiled loop: about 2 s on a
#: loaded machine, set-up, writing), which rodval refuses before work when its estimate does
#: not fit: 10 s leaves a loaded machine room and still ends every example well within LIMIT_S.
BUDGET = ["--max-wall", "10", "--max-evaluations", "50000"]


def budget(default: int, *, expensive: bool = False, share: int = 1) -> settings:
    """Hypothesis settings of a fuzz test: ``default`` examples, or RODVAL_FUZZ_EXAMPLES
    divided by ``share`` (40 for an ``expensive`` test), at least 1."""
    share = 40 if expensive else share
    n = default if not EXAMPLES else max(EXAMPLES // share, 1)
    return settings(
        max_examples=n,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )


class Counts:
    """Counts of one fuzz test, appended to RODVAL_FUZZ_STATS at the end."""

    def __init__(self, name: str):
        self.name = name
        self.examples = self.tracebacks = self.hangs = self.nonfinite = self.ignored = 0
        self.late = self.lost = self.unclear = 0
        self.exits: dict[int, int] = {}
        self.start = self.last = time.perf_counter()

    def fail(self, kind: str, message: str) -> None:
        """Count a find of ``kind`` (an attribute: tracebacks, hangs, nonfinite, ignored,
        late, lost, unclear) and fail the example; with RODVAL_FUZZ_FINDS set, append it to
        that file as a JSON line and go on instead (a survey of every find in one run)."""
        setattr(self, kind, getattr(self, kind) + 1)
        path = os.environ.get("RODVAL_FUZZ_FINDS")
        if not path:
            raise AssertionError(message)
        with open(path, "a") as fh:
            fh.write(json.dumps({"test": self.name, "kind": kind, "find": message}) + "\n")

    def save(self) -> None:
        path = os.environ.get("RODVAL_FUZZ_STATS")
        if not path:
            return
        row = {
            "test": self.name,
            "examples": self.examples,
            "tracebacks": self.tracebacks,
            "hangs": self.hangs,
            "nonfinite_successes": self.nonfinite,
            "ignored_inputs": self.ignored,
            "silent_wrong": self.nonfinite + self.ignored,
            "late_refusals": self.late,
            "data_loss": self.lost,
            "unclear": self.unclear,
            "exit_codes": {str(k): v for k, v in sorted(self.exits.items())},
            "wall_s": round(self.last - self.start, 1),
        }
        with open(path, "a") as fh:
            fh.write(json.dumps(row) + "\n")


class Hang(Exception):
    pass


def _alarm(signum, frame):
    raise Hang(f"example exceeded {LIMIT_S:g} s")


def run_cli(argv: list, c: Counts) -> tuple[int, str, str]:
    """(exit code, stdout, stderr) of ``rodval ARGV``, checking the contract: exit 0/1, or 2
    with one line; never a traceback or a hang. A find under RODVAL_FUZZ_FINDS (recorded, not
    raised) returns exit code -1."""
    c.examples += 1
    out, err = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, LIMIT_S)
    start = time.perf_counter()
    shown = " ".join(str(a) for a in argv)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main([str(a) for a in argv])
            except SystemExit as exc:  # argparse: bad option, --help
                code = exc.code if isinstance(exc.code, int) else 2
    except Hang:
        c.fail("hangs", f"hang: rodval {shown}")
        return -1, out.getvalue(), err.getvalue()
    except Exception as exc:  # noqa: BLE001 - counted, then reported
        c.fail("tracebacks", f"exception escaped: rodval {shown}: {exc!r}")
        return -1, out.getvalue(), err.getvalue()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    wall = time.perf_counter() - start
    c.last = time.perf_counter()
    stderr = err.getvalue()
    if wall > LIMIT_S:
        c.fail("hangs", f"hang ({wall:.0f} s): rodval {shown}")
        return -1, out.getvalue(), stderr
    c.exits[code] = c.exits.get(code, 0) + 1
    lines = [line for line in stderr.splitlines() if line.strip()]
    if "Traceback" in stderr or "internal error" in stderr or code not in (0, 1, 2):
        c.fail("tracebacks", f"rodval {shown}: exit {code}: {stderr[-600:]}")
        return -1, out.getvalue(), stderr
    log = os.environ.get("RODVAL_FUZZ_LOG")
    if log:  # every example's command line, exit code and last line (a survey's trail)
        last = (lines or [out.getvalue().strip()[:300]])[-1]
        with open(log, "a") as fh:
            fh.write(json.dumps({"test": c.name, "argv": shown, "exit": code, "line": last}) + "\n")
    if code == 2 and len(lines) != 1:
        c.fail("tracebacks", f"rodval {shown}: exit 2 with {len(lines)} lines: {stderr[-600:]}")
        return -1, out.getvalue(), stderr
    return code, out.getvalue(), stderr


#: the library's own writer (study.toml of a Python study): one TOML writer
to_toml = toml_text


numbers = st.one_of(
    st.integers(-3, 10),
    st.floats(-2.0, 10.0),
    st.sampled_from([0.0, -1.0, 1e-300, 1e-15, 1e13, 1e160, 1e305, math.inf, -math.inf, math.nan]),
)
junk = st.one_of(
    st.text(max_size=5),
    st.booleans(),
    st.just([]),
    st.just({}),
    st.lists(st.integers(), max_size=3),
)
anything = st.one_of(numbers, numbers, junk)


def write_scene(tmp: Path, doc: dict, raw: bytes | None = None) -> Path:
    path = tmp / "scene.toml"
    if raw is not None:
        path.write_bytes(raw)
    else:
        path.write_text(to_toml(doc))
    return path


def claims_success(stats) -> bool:
    """A run's stats (SolverStats or run.json's dict) claim a correct result: status 0 and
    not ``valid = false`` (a missing ``valid`` is unknown: the status alone counts)."""
    get = stats.get if isinstance(stats, dict) else lambda k, d=None: getattr(stats, k, d)
    return get("status") == 0 and get("valid", None) is not False


def check_run(out: Path, code: int) -> int:
    """A run that reports success has finite outputs only; returns 1 for a silent
    non-finite success."""
    run = out / "run.json"
    if code not in (0, 1) or not run.is_file():
        return 0
    rec = json.loads(run.read_text())
    if not claims_success(rec["stats"]):
        return 0
    from rodval.report.run_files import read_run

    values = read_run(out).values.values()
    return 0 if all(np.all(np.isfinite(v)) for v in values) else 1


SMALL_STUDY = {
    "study": {"name": "fz", "reference": "reduced"},
    "scene": {"based_on": "paper", "n": 2, "t_end": 0.05, "times": {"num": 3}},
    "integrator": {"max_evaluations": 50000, "max_wall_s": 10.0},
    "models": {"reduced": {}, "pub": {"model": "reduced", "coefficients": "published"}},
    "grid": {"scene.n": [2, 3]},
}


#: Python's own messages: an exit-2 line made of one of them is an exception that slipped
#: past the checks (counted as a traceback), not a refusal naming the key.
INTERNAL_PHRASES = (
    "Unknown format code",
    "inhomogeneous",
    "unsupported operand",
    "not subscriptable",
    "has no attribute",
    "object is not",
    "codec can't decode",
    "math domain error",
    "division by zero",
    "index out of",
    "NoneType",
    "argument must be",
)


def refusal_is_clear(stderr: str, c: Counts) -> None:
    """An exit-2 line says what is wrong in rodval's words, not Python's."""
    leaked = [p for p in INTERNAL_PHRASES if p in stderr]
    if leaked:
        c.fail("tracebacks", f"a Python-internal message as refusal ({leaked[0]!r}): {stderr}")


def refused_late(stdout: str, c: Counts) -> None:
    """A ValueError about the input is raised before any work (exit 2), not reported as a
    run that failed at set-up or at its first observation (exit 1, "ValueError" in the
    status line: the check ran inside the model, naming the model's parameter)."""
    if "ValueError" in stdout:
        c.fail("late", f"input error reported as a failed run, not refused: {stdout}")


def read_record(out: Path) -> dict | None:
    """The run record of ``out`` as rodval reads it (large scene arrays put back from
    scene_arrays.npz), or None when the run wrote none."""
    from rodval.report.run_files import read_run_record

    path = out / "run.json"
    return read_run_record(path) if path.is_file() else None


RUN_SCENE = {
    "based_on": "paper",
    "n": 2,
    "t_end": 0.05,
    "times": {"num": 3},
    "outputs": ["phi", "dphi"],
    "initial": {"dphi": 0.5},
    "stops": [{"hinge": 1, "angle": 0.02, "side": "upper", "stiffness": 1e3, "damping": 1.0}],
}


def run_api(
    fn,
    kwargs: dict,
    c: Counts,
    names: tuple[str, ...],
    shown: str = "",
    refusals: tuple[type[Exception], ...] = (ValueError, TypeError, KeyError),
):
    """``fn(**kwargs)`` under the time limit: its result, or None when it raised one of
    ``refusals`` (by default ValueError/TypeError/KeyError) whose message is one line naming
    the parameter (one of ``names``); any other exception is a traceback."""
    c.examples += 1
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, LIMIT_S)
    start = time.perf_counter()
    call = f"{getattr(fn, '__qualname__', fn)}({shown or kwargs!r})"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fn(**kwargs)
    except Hang:
        c.fail("hangs", f"hang: {call}")
        return None
    except refusals as exc:
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        msg = str(msg)
        named = any(n.lower() in msg.lower().replace(" ", "_") for n in names)
        if len(msg.strip().splitlines()) != 1 or not (named or any(n in msg for n in names)):
            c.fail(
                "tracebacks",
                f"{call}: {type(exc).__name__} not naming {names[0]!r} on one line: {msg!r}",
            )
            return None
        c.exits[2] = c.exits.get(2, 0) + 1
        return None
    except Exception as exc:  # noqa: BLE001 - counted, then reported
        c.fail("tracebacks", f"{call}: {type(exc).__name__}: {str(exc)[:300]}")
        return None
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
        c.last = time.perf_counter()
    if time.perf_counter() - start > LIMIT_S:
        c.fail("hangs", f"hang: {call}")
        return None
    c.exits[0] = c.exits.get(0, 0) + 1
    return result


def small_scene(draw, *, n_max: int = 4) -> dict:
    """A small valid scene document (n <= n_max, t_end <= 0.3 s) that moves."""
    n = draw(st.integers(1, n_max))
    doc = {
        "based_on": "paper",
        "n": n,
        "t_end": draw(st.floats(0.01, 0.3)),
        "times": {"num": draw(st.integers(1, 6))},
        "outputs": ["phi", "dphi"],
    }
    if draw(st.booleans()):
        doc["initial"] = {"dphi": draw(st.floats(-3.0, 3.0))}
    return doc


def snapshot(*roots: Path) -> dict[str, bytes | str]:
    """Every file under ``roots`` (folders or files) by absolute path: a regular file's bytes,
    a symbolic link's target (``-> target``; links are not followed, so a file written
    through a link shows at the link's target, itself a root or under one)."""
    found: dict[str, bytes | str] = {}
    for root in roots:
        paths = [root] if not root.is_dir() or root.is_symlink() else sorted(root.rglob("*"))
        for p in paths:
            if p.is_symlink():
                found[str(p)] = f"-> {os.readlink(p)}"
            elif p.is_file():
                found[str(p)] = p.read_bytes()
    return found


def lost_files(before: dict[str, bytes | str], after: dict[str, bytes | str]) -> list[str]:
    """The files of ``before`` changed or removed in ``after``."""
    return [name for name, data in before.items() if after.get(name) != data]
