"""A study's output folder: where each file lives, atomic writes, one writer, one study.

Layout of ``OUT``: ``study.json`` (the study's description, ``study_meta``), ``study.toml``
(the study file), ``provenance.json``, ``cases/<file>.json`` (one verified case record per
finished case, ``rodval.study.records``), the tables (``rodval.study.tables``), ``report.md``
and ``figures/``.

* One writer: ``lock()`` holds ``OUT/.lock`` (an exclusive ``fcntl`` lock, released by the
  kernel when the process dies, so a killed run never leaves it stuck); a second run on the
  same folder is refused with a ``FolderBusy`` naming the holder's pid.
* Killed at any point, a run leaves a folder the next run takes: ``claim`` writes study.json
  (atomically) before any other file of the study and ``--fresh`` replaces it last, so the
  folder never holds a study's files without the study.json that makes it a study folder.
* One study: a folder that holds another study (``study.json`` with a different name or
  source, or a different grid), or this study when the scene file its [scene] names has
  changed (``scene_file_change``), is refused unless ``fresh=True`` (``--fresh``), which first
  removes what the study wrote (``study_files``) and nothing else.
* rodval's folders only: a folder is a study folder when its ``study.json`` carries rodval's
  schema and checksum (``rodval.core.out_paths.stamp``). Any other folder that holds files
  (a user's ``report.md``, a foreign ``study.json``) is refused before work, with or without
  ``--fresh``, naming what it holds (``check_folder``); files a user put into a study folder
  are kept.
* Case file names are bounded (``MAX_NAME``) whatever the grid: a readable prefix of the case
  id and a hash of the full id; the full parameters live in the record.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from rodval.core.out_paths import (
    HOUSEKEEPING,
    STUDY_SCHEMA,
    TEMPORARY,
    inside,
    is_stamped,
    read_json,
    refuse_foreign,
    stamp,
    write_file,
)
from rodval.report.tables import ALL_TABLES, FIGURES, MANIFEST

#: Longest case file name (characters, with ".json"): well below every file system's 255.
MAX_NAME = 120


#: The files a study writes at the top of its folder besides its tables.
TOP_FILES = ("study.json", "study.toml", "provenance.json", "report.md", MANIFEST)
#: Those and its tables (``<name>.csv`` and ``.md``).
STUDY_TOP_FILES = (*TOP_FILES, *(f"{t}.{e}" for t in ALL_TABLES for e in ("csv", "md")))


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


def write_json_atomic(path: Path, obj: Any) -> None:
    """``obj`` as JSON, written atomically, never through a link (``write_file``)."""
    write_file(path, json.dumps(obj, indent=1, default=repr))


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
        """The saved study.json, or None when there is none (a new folder); ValueError when
        it is not rodval's (no rodval schema and checksum: foreign, edited or damaged)."""
        path = self.out / "study.json"
        if not path.is_file():
            return None
        doc = read_json(path)
        if not is_stamped(doc, STUDY_SCHEMA):
            raise ValueError(
                f"--out {self.out}: its study.json was not written by rodval (no rodval schema "
                "and checksum: another program's file, edited, damaged or from an older rodval), "
                "so rodval will not write there; use a new or empty --out"
            )
        return dict(doc)

    def owned(self) -> bool:
        """Whether the folder is a study folder of rodval (a stamped study.json)."""
        try:
            return self.meta() is not None
        except ValueError:
            return False

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

    def check_folder(self) -> None:
        """Refuse, before the lock or any write, a folder rodval may not write into: one that
        holds files but is not a study folder of rodval (``refuse_foreign``), or whose
        study.json is not rodval's (``meta``)."""
        self.meta()
        refuse_foreign(self.out, "--out", lambda f: StudyStore(f).owned(), "study", "study.json")

    def reserved(self, path: Path) -> str | None:
        """Why ``path`` is not free for another output (a file the study writes, or one in
        its cases/ or figures/), or None."""
        rel = inside(path, self.out)
        if rel is None:
            return None
        if str(rel) in {*STUDY_TOP_FILES, *HOUSEKEEPING} or rel.parts[0] in ("cases", FIGURES):
            return f"a file of the study in {self.out}"
        return None

    def study_files(self, meta: dict[str, Any]) -> list[Path]:
        """The files the study described by ``meta`` (its study.json) wrote into the folder:
        study.json, study.toml, provenance.json, the tables (``<name>.csv`` and ``.md``) and
        their manifest, report.md, the figures report.md links, the records of its cases and the temporary
        files of interrupted atomic writes. ``--fresh`` removes these and nothing else."""
        files = [self.out / name for name in STUDY_TOP_FILES]
        report = self.out / "report.md"
        if report.is_file():
            linked = re.findall(rf"\]\({FIGURES}/([^)/]+\.png)\)", report.read_text())
            files += [self.out / FIGURES / name for name in linked]
        cases = meta.get("cases")
        if isinstance(cases, list):
            ids = [c["id"] for c in cases if isinstance(c, dict) and "id" in c]
            files += [self.case_path(str(cid)) for cid in ids]
        for folder in (self.out, self.cases_dir):
            if folder.is_dir():
                files += [p for p in folder.glob(".*.tmp*") if TEMPORARY.fullmatch(p.name)]
        return files

    def claim(self, meta: dict[str, Any], *, fresh: bool) -> None:
        """Make the folder this study's: refuse a folder holding another study, or this
        study with a changed scene file (``scene_file_change``), unless ``fresh`` (then
        remove what that study wrote, ``study_files``, its study.json last: replaced by this
        study's); write study.json, then make cases/. A run killed at any point of this
        leaves a folder the next run takes: it holds a study.json whenever it holds any
        other file of a study."""
        old = self.meta()
        changed = None if old is None or fresh else scene_file_change(old, meta)
        if changed:
            raise ValueError(f"{self.out}: {changed}; use --fresh to run the study again there")
        if old is not None and not fresh and not same_study(old, meta):
            raise ValueError(
                f"{self.out} holds another study ({old.get('name')!r} from "
                f"{old.get('source')!r}); use another --out, or --fresh to start over there"
            )
        marker = self.out / "study.json"
        if fresh and old is not None:
            for path in self.study_files(old):
                if path != marker:
                    path.unlink(missing_ok=True)
            figures = self.out / FIGURES
            if figures.is_dir() and not any(figures.iterdir()):
                figures.rmdir()
        write_json_atomic(marker, stamp(meta, STUDY_SCHEMA))
        self.cases_dir.mkdir(exist_ok=True)


def same_study(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether two study descriptions are of the same study: same name, models and reference
    (its grid may grow: new cases are added, finished ones reused)."""
    keys = ("name", "reference", "models")
    return all(
        json.dumps(a.get(k), sort_keys=True) == json.dumps(b.get(k), sort_keys=True) for k in keys
    )


def scene_file_change(old: dict[str, Any], new: dict[str, Any]) -> str | None:
    """Why two study descriptions are not of the same study because the scene file their
    [scene] names changed (its SHA-256 differs), or None (same file content, or no file)."""
    a, b = old.get("scene_file"), new.get("scene_file")
    if not isinstance(a, dict) or not isinstance(b, dict) or a.get("sha256") == b.get("sha256"):
        return None
    return (
        f"the scene file {b.get('path')!r} of study {new.get('name')!r} changed since the "
        "study last ran in this folder (its records are of the old scene)"
    )
