"""The first run's background compilation (issue 50, ``rodval.solvers.signature``): the cache
probe reads numba's index without compiling, a background process fills the cache its parent
then loads from, a failed one leaves the parent to compile, and the compiled loop keeps its
one signature. No timing here: ``benchmarks/first_run.py`` measures."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from rodval.solvers import signature

#: A kernel module on its own, so that each scenario compiles on an empty cache of its own.
KERNEL = """
from numba import njit, types

SIG = types.float64(types.float64)


@njit(cache=True)
def twice(x):
    return 2.0 * x
"""

#: In a fresh process with NUMBA_CACHE_DIR empty: probe, compile in the background, wait,
#: probe again, and count this process's own compilations (0: loaded from the cache).
SCENARIO = """
import sys
sys.path.insert(0, {folder!r})
from rodval.solvers import signature
import kern

before = signature.in_cache(kern.twice, kern.SIG)
assert not kern.twice.signatures  # probing compiled nothing
signature.compile_in_background("twice", {code!r})
ok = signature.wait_for("twice")
after = signature.in_cache(kern.twice, kern.SIG)
kern.twice.compile(kern.SIG)
misses = sum(kern.twice.stats.cache_misses.values())
print(before, ok, after, misses, kern.twice(1.5))
"""


def _scenario(tmp_path: Path, code: str) -> list[str]:
    (tmp_path / "kern.py").write_text(KERNEL)
    script = SCENARIO.format(folder=str(tmp_path), code=code)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    env.pop(signature.BACKGROUND_ENV, None)
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(script)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    return done.stdout.split()


def test_background_compilation_fills_the_cache_the_parent_loads(tmp_path: Path) -> None:
    code = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); import kern; kern.twice.compile(kern.SIG)"
    before, ok, after, misses, value = _scenario(tmp_path, code)
    assert (before, ok, after) == ("False", "True", "True")
    assert misses == "0"  # the parent compiled nothing itself
    assert value == "3.0"


def test_a_failed_background_compilation_leaves_the_parent_to_compile(tmp_path: Path) -> None:
    before, ok, after, misses, value = _scenario(tmp_path, "raise SystemExit(1)")
    assert (before, ok, after) == ("False", "False", "False")
    assert misses == "1"  # compiled here instead
    assert value == "3.0"


def test_wait_for_a_compilation_never_started() -> None:
    assert signature.wait_for("never started") is False


def test_background_switched_off_by_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(signature.BACKGROUND_ENV, "0")
    assert signature.background_allowed() is False


def test_the_loop_keeps_its_one_signature() -> None:
    from rodval.solvers import dop853

    run = dop853.loop()
    assert len(run.signatures) == 1
    assert signature.in_cache(run, dop853._RUN_SIGNATURE) is True
    with pytest.raises(TypeError):  # other argument types are refused, not compiled
        run(np.zeros(3))
