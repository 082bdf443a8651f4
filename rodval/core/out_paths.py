"""Where rodval may write: output folders it owns, output files it may create, never over a
file it did not write.

An output folder is rodval's only when its marker (a study's ``study.json``, a run's
``run.json``) carries rodval's schema and a checksum of its content (``stamp`` /
``is_stamped``). A folder without such a marker must be empty (or not yet exist): rodval
refuses any other folder before work, naming what it holds (``refuse_foreign``). An output
file named on the command line (``--junit``) is checked before work: a writable place, not a
folder, not an input of the command nor a file of its output folder, and not an existing file
rodval did not write (``check_output_file``).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

#: The keys ``stamp`` adds to a record: its schema name and the checksum of the rest.
SCHEMA_KEY, CHECKSUM_KEY = "rodval_schema", "rodval_checksum"
#: The schemas of rodval's markers: a study folder's study.json, a run folder's run.json.
STUDY_SCHEMA, RUN_SCHEMA = "rodval-study", "rodval-run"
#: Entries of a folder that rodval itself keeps there while it works (its writer lock).
HOUSEKEEPING = (".lock",)


def _digest(record: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON of ``record`` without its checksum key."""
    body = {k: v for k, v in record.items() if k != CHECKSUM_KEY}
    text = json.dumps(body, sort_keys=True, default=repr, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def stamp(record: dict[str, Any], schema: str) -> dict[str, Any]:
    """``record`` with rodval's marker: ``rodval_schema`` = ``schema`` and the checksum of
    the whole (canonical JSON, SHA-256)."""
    out = {k: v for k, v in record.items() if k not in (SCHEMA_KEY, CHECKSUM_KEY)}
    out[SCHEMA_KEY] = schema
    out[CHECKSUM_KEY] = _digest(out)
    return out


def is_stamped(record: Any, schema: str) -> bool:
    """Whether ``record`` (a parsed JSON value) carries rodval's marker for ``schema`` and
    its checksum matches its content."""
    return (
        isinstance(record, dict)
        and record.get(SCHEMA_KEY) == schema
        and record.get(CHECKSUM_KEY) == _digest(record)
    )


def read_json(path: Path) -> Any:
    """The JSON value in ``path``, or None when it cannot be read as JSON."""
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def _named(entries: list[str]) -> str:
    first = ", ".join(repr(e) for e in entries[:3])
    return first + (f" and {len(entries) - 3} more" if len(entries) > 3 else "")


def refuse_foreign(
    folder: Path, flag: str, owned: Callable[[Path], bool], kind: str, marker: str
) -> None:
    """ValueError naming ``flag`` unless ``folder`` is missing, empty, or rodval's
    (``owned(folder)``): rodval writes into no folder that holds files it did not write.
    ``kind`` ("study", "run") and ``marker`` (its file, e.g. "study.json") name the folder
    rodval looked for in the refusal."""
    if not folder.exists():
        return
    if not folder.is_dir():
        raise ValueError(f"{flag} {folder}: is a file, not a folder")
    if owned(folder):
        return
    entries = sorted(p.name for p in folder.iterdir() if p.name not in HOUSEKEEPING)
    if entries:
        raise ValueError(
            f"{flag} {folder}: not a {kind} folder of rodval (no {marker} with rodval's schema "
            f"and checksum) and it holds {_named(entries)}, which rodval did not write, so "
            "rodval will not write there; use a new or empty folder"
        )


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except (OSError, RuntimeError):
        return False


def check_output_file(
    path: Any,
    flag: str,
    *,
    protected: Iterable[Path] = (),
    reserved: Callable[[Path], str | None] = lambda p: None,
    ours: Callable[[Path], bool] = lambda p: False,
) -> Path:
    """``path`` as a Path when rodval may write a file there, else ValueError naming
    ``flag``, before any work: a non-empty path, not a folder, under an existing folder
    where a file can be created, none of the ``protected`` files (the command's inputs), not
    a file ``reserved`` for another purpose (it returns why, e.g. "a file of the study in
    out/"), and, when the file exists, one rodval wrote (``ours(path)``)."""
    if not isinstance(path, str | os.PathLike) or str(path).strip() == "":
        raise ValueError(f"{flag}: needs a file path, got {str(path)!r}")
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{flag} {p}: is a folder; name a file")
    for other in protected:
        if _same_file(p, Path(other)):
            raise ValueError(f"{flag} {p}: is an input of this command; name another file")
    why = reserved(p)
    if why:
        raise ValueError(f"{flag} {p}: is {why}; name another file")
    parent = p.parent
    if not parent.is_dir():
        raise ValueError(f"{flag} {p}: its folder {parent} does not exist (or is a file)")
    if p.exists():
        if not p.is_file() or not ours(p):
            raise ValueError(
                f"{flag} {p}: exists and was not written by rodval, so rodval will not "
                "overwrite it; name a new file"
            )
        if not os.access(p, os.W_OK):
            raise ValueError(f"{flag} {p}: cannot be written (permission denied)")
        return p
    try:
        with open(p, "x"):
            pass
    except OSError as exc:
        raise ValueError(f"{flag} {p}: cannot be written ({exc.strerror or exc})") from None
    p.unlink()
    return p


def inside(path: Path, folder: Path) -> Path | None:
    """``path`` relative to ``folder`` when it lies inside it (both resolved), else None."""
    try:
        return path.resolve().relative_to(folder.resolve())
    except (ValueError, OSError, RuntimeError):
        return None


#: The marker of a plain output folder (``rodval compare``, ``modes``, ``reproduce``,
#: ``bench``): ``rodval.json``, stamped with ``OUTPUT_SCHEMA``, naming the command.
OUTPUT_MARKER, OUTPUT_SCHEMA = "rodval.json", "rodval-output"


def output_folder_owned(folder: Path) -> bool:
    """Whether ``folder`` carries rodval's output marker (``mark_output_folder``)."""
    return is_stamped(read_json(folder / OUTPUT_MARKER), OUTPUT_SCHEMA)


def claim_output_folder(folder: Path, flag: str = "--out") -> None:
    """Refuse, before work, an output folder that holds files rodval did not write."""
    refuse_foreign(folder, flag, output_folder_owned, "output", OUTPUT_MARKER)


def mark_output_folder(folder: Path, command: str) -> None:
    """Mark ``folder`` (when the command made or wrote it) as rodval's output folder."""
    if folder.is_dir() and not output_folder_owned(folder):
        record = stamp({"command": command}, OUTPUT_SCHEMA)
        (folder / OUTPUT_MARKER).write_text(json.dumps(record, indent=1))
