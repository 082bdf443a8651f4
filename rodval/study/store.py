"""A study's output folder: where each file lives, atomic writes, one writer, one study.

Layout of ``OUT``: ``study.json`` (the study's description, ``study_meta``), ``study.toml``
(the study file), ``provenance.json``, ``cases/<file>.json`` (one verified case record per
finished case, ``rodval.study.records``), the tables (``rodval.study.tables``), ``report.md``
and ``figures/``.

* One writer: ``lock()`` holds ``OUT/.lock`` (an exclusive ``fcntl`` lock, released by the
  kernel when the process dies, so a killed run never leaves it stuck); a second run on the
  same folder is refused with a ``FolderBusy`` naming the holder's pid.
* One study: a folder that holds another study (``study.json`` with a different name or
  source, or a different grid) is refused unless ``fresh=True`` (``--fresh``), which empties
  it first.
* Case file names are bounded (``MAX_NAME``) whatever the grid: a readable prefix of the case
  id and a hash of the full id; the full parameters live in the record.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

#: Longest case file name (characters, with ".json"): well below every file system's 255.
MAX_NAME = 120


class FolderBusy(ValueError):
    """Another run holds the study folder's lock."""


def case_file_name(case_id: str) -> str:
    """``<readable id>.json``, or ``<prefix>~<hash>.json`` when the id is long or has
    characters a file name should not."""
    safe = re.sub(r"[^A-Za-z0-9._,=+-]", "-", case_id)
    if safe == case_id and len(safe) + 5 <= MAX_NAME:
        return f"{safe}.json"
    digest = hashlib.sha256(case_id.encode()).hexdigest()[:16]
    return f"{safe[: MAX_NAME - 5 - 17]}~{digest}.json"


def write_text_atomic(path: Path, text: str) -> None:
    """Write to a temporary file beside ``path`` and rename it over ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def write_json_atomic(path: Path, obj: Any) -> None:
    write_text_atomic(path, json.dumps(obj, indent=1, default=repr))


class StudyStore:
    """Paths and writes of one study folder."""

    def __init__(self, out: str | Path):
        self.out = Path(out)

    @property
    def cases_dir(self) -> Path:
        return self.out / "cases"

    def case_path(self, case_id: str) -> Path:
        return self.cases_dir / case_file_name(case_id)

    def meta(self) -> dict[str, Any] | None:
        """The saved study.json, or None when there is none (a new folder)."""
        path = self.out / "study.json"
        if not path.is_file():
            return None
        try:
            return json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise ValueError(f"{path}: unreadable study description ({exc})") from None

    @contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the folder's writer lock (FolderBusy if another process holds it)."""
        self.out.mkdir(parents=True, exist_ok=True)
        fh = open(self.out / ".lock", "a+")
        try:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                fh.seek(0)
                holder = fh.read().strip() or "another process"
                raise FolderBusy(
                    f"{self.out} is in use by another rodval study (pid "
                    f"{holder}); wait for it to finish or use another --out"
                ) from None
            fh.seek(0)
            fh.truncate()
            fh.write(str(os.getpid()))
            fh.flush()
            yield
        finally:
            fh.close()

    def claim(self, meta: dict[str, Any], *, fresh: bool) -> None:
        """Make the folder this study's: refuse a folder holding another study unless
        ``fresh`` (then empty it); write study.json."""
        old = self.meta()
        if old is not None and not fresh and not same_study(old, meta):
            raise ValueError(
                f"{self.out} holds another study ({old.get('name')!r} from "
                f"{old.get('source')!r}); use another --out, or --fresh to start over there"
            )
        if fresh:
            for item in self.out.iterdir():
                if item.name == ".lock":
                    continue
                shutil.rmtree(item) if item.is_dir() else item.unlink()
        self.cases_dir.mkdir(parents=True, exist_ok=True)
        write_json_atomic(self.out / "study.json", meta)


def same_study(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether two study descriptions are of the same study: same name, models and reference
    (its grid may grow: new cases are added, finished ones reused)."""
    keys = ("name", "reference", "models")
    return all(
        json.dumps(a.get(k), sort_keys=True) == json.dumps(b.get(k), sort_keys=True) for k in keys
    )
