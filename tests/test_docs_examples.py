"""Every example of README.md and docs/*.md runs as written, so a document cannot drift from
the code.

The examples are the fenced blocks: ```python blocks run as a script, the ``rodval ...``
lines of ```bash blocks as commands, ```toml blocks are read as scene files (a block whose
first line is ``# NAME.toml ...`` is saved as NAME.toml beside every example of its document,
so that a command or another block may read it). Each runs in a fresh working folder holding
a copy of the repository's ``studies/`` and ``benchmarks/`` (what the documents' relative
paths start from: the repository root), never in the repository itself. A block preceded by
``<!-- not run: REASON -->`` is not run (the reason is listed by
``test_skipped_examples_give_a_reason``); one preceded by ``<!-- slow -->`` runs under
``-m slow`` only.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: The kinds of fenced block that are examples; other kinds (text, diagrams) are not run.
KINDS = ("python", "bash", "toml")
FENCE = re.compile(r"^```([\w-]*)[ \t]*\n(.*?)^```[ \t]*$", re.M | re.S)
MARK = re.compile(r"<!--\s*(not run|slow)\s*:?\s*(.*?)\s*-->\s*$")
#: The folders of the repository a working folder holds (what the examples read).
DATA = ("studies", "benchmarks")
TIMEOUT_S = 900


@dataclass(frozen=True)
class Example:
    """One fenced block of a document: where it is, its kind and code, and its marker."""

    document: Path
    line: int
    kind: str
    code: str
    mark: str  # "", "not run" or "slow"
    reason: str

    @property
    def name(self) -> str:
        return f"{self.document.relative_to(ROOT)}:{self.line}"


def blocks(text: str) -> list[tuple[int, str, str, str, str]]:
    """The fenced example blocks of a document's ``text``: (line, kind, code, marker,
    reason), the marker being the one on the line right before the block, if any."""
    found = []
    for match in FENCE.finditer(text):
        if match.group(1) not in KINDS:
            continue
        before = text[: match.start()].rstrip("\n").rsplit("\n", 1)[-1]
        marker = MARK.search(before)
        line = text.count("\n", 0, match.start()) + 1
        mark, reason = (marker.group(1), marker.group(2)) if marker else ("", "")
        found.append((line, match.group(1), match.group(2), mark, reason))
    return found


def examples(document: Path) -> list[Example]:
    """The fenced example blocks of ``document``."""
    return [Example(document, *block) for block in blocks(document.read_text(encoding="utf-8"))]


ALL = [example for document in DOCUMENTS for example in examples(document)]


def _params() -> list:
    return [
        pytest.param(e, id=e.name, marks=[pytest.mark.slow] if e.mark == "slow" else [])
        for e in ALL
        if e.mark != "not run"
    ]


def _workdir(tmp_path: Path) -> Path:
    """A working folder standing for the repository root: a copy of its data folders."""
    work = tmp_path / "work"
    work.mkdir()
    for name in DATA:
        shutil.copytree(ROOT / name, work / name)
    return work


def _run(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    return subprocess.run(
        argv, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S, env=env, check=False
    )


def _commands(code: str) -> list[list[str]]:
    """The ``rodval ...`` commands of a bash block (continuation lines joined), each as the
    installed ``rodval`` would be called: ``python -m rodval ...``."""
    lines = code.replace("\\\n", " ").splitlines()
    commands = []
    for line in lines:
        words = shlex.split(line, comments=True)
        if words and words[0] in ("rodval", ".venv/bin/rodval"):
            commands.append([sys.executable, "-m", "rodval", *words[1:]])
    return commands


#: A toml block's first line naming its file: ``# NAME.toml`` (and anything after).
NAMED = re.compile(r"#\s*([\w.-]+\.toml)\b")


def _save_named_scenes(document: Path, work: Path) -> None:
    """Every toml block of ``document`` that names its file, saved under that name in
    ``work``: the files its commands and later blocks read ("run in a folder holding ...")."""
    for example in examples(document):
        named = NAMED.match(example.code) if example.kind == "toml" else None
        if named:
            (work / named.group(1)).write_text(example.code)


@pytest.mark.parametrize("example", _params())
def test_the_example_runs_as_written(example: Example, tmp_path):
    work = _workdir(tmp_path)
    _save_named_scenes(example.document, work)
    if example.kind == "toml":
        from rodval import load_scene

        named = NAMED.match(example.code)
        path = work / (named.group(1) if named else "example.toml")
        path.write_text(example.code)
        load_scene(str(path))
        return
    if example.kind == "python":
        done = _run([sys.executable, "-c", example.code], work)
        assert done.returncode == 0, f"{example.name}:\n{done.stderr[-3000:]}"
        return
    commands = _commands(example.code)
    assert commands, f"{example.name}: a bash block with no rodval command must be marked"
    for argv in commands:
        done = _run(argv, work)
        assert done.returncode == 0, f"{example.name}: {argv[3:]}\n{done.stderr[-3000:]}"


def test_skipped_examples_give_a_reason():
    """Every example not run says why (listed with ``-rA`` / in the assertion message)."""
    skipped = [(e.name, e.reason) for e in ALL if e.mark == "not run"]
    assert all(reason for _, reason in skipped), skipped
    print("\n".join(f"not run: {name}: {reason}" for name, reason in skipped))


def test_the_extraction_finds_the_examples():
    """The fenced examples are found where they are (README's Python example among them), a
    marker applies to the block right after it only, and a bash block's commands are its
    ``rodval`` lines."""
    python = [e for e in examples(ROOT / "README.md") if e.kind == "python"]
    assert python and "simulate(scene" in python[0].code
    text = (
        "a\n<!-- not run: needs a network -->\n```bash\nrodval x\n```\n\n```bash\nrodval y\n```\n"
    )
    assert blocks(text) == [
        (3, "bash", "rodval x\n", "not run", "needs a network"),
        (7, "bash", "rodval y\n", "", ""),
    ]
    assert blocks("<!-- slow -->\n```python\nprint(1)\n```\n```text\nrodval z\n```\n") == [
        (2, "python", "print(1)\n", "slow", "")
    ]
    assert _commands("rodval study f.toml \\\n  --out d  # comment\npip install x\n") == [
        [sys.executable, "-m", "rodval", "study", "f.toml", "--out", "d"]
    ]
