"""Where rodval may write: output folders it owns, output files it may create, never over a
file it did not write.

An output folder is rodval's only when its marker (a study's ``study.json``, a run's
``run.json``) carries rodval's schema and a checksum of its content (``stamp`` /
``is_stamped``). A folder without such a marker must be empty (or not yet exist): rodval
refuses any other folder before work, naming what it holds (``refuse_foreign``). An output
file named on the command line (``--junit``) is checked before work: a writable place, not a
folder, not an input of the command nor a file of its output folder, and not an existing file
rodval did not write (``check_output_file``).

Nothing is written through a symbolic link: rodval makes none, so an output folder that is a
link, or holds one anywhere below it, is refused before work (``refuse_links``, part of
``refuse_foreign``, which every folder claim goes through), and every file rodval writes goes
through ``write_file`` / ``write_with`` (a temporary file beside it renamed over it, the target
refused when it is a link) and every figure through ``write_figure``. A plain output folder
(``rodval.json``) belongs to one command and lists the files it wrote: another command's output
is refused there, a file it does not list (the user's) too, and ``clear_previous`` removes the
listed files of the command's earlier run just before the new run writes (nothing else).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import re
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

#: The keys ``stamp`` adds to a record: its schema name and the checksum of the rest.
SCHEMA_KEY, CHECKSUM_KEY = "rodval_schema", "rodval_checksum"
#: The schemas of rodval's markers: a study folder's study.json, a run folder's run.json.
STUDY_SCHEMA, RUN_SCHEMA = "rodval-study", "rodval-run"
#: Entries of a folder that rodval itself keeps there while it works (its writer lock).
HOUSEKEEPING = (".lock",)
#: Name of the temporary file of an atomic write (``write_with``): ``.<name>.<pid>.tmp``.
TEMPORARY = re.compile(r"\..+\.\d+\.tmp(\.\w+)?")


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


def _link_refusal(flag: str, link: Path, what: str) -> ValueError:
    return ValueError(
        f"{flag} {link}: {what} a symbolic link, which rodval did not make; rodval writes "
        "through no link (it could overwrite another folder's files): remove the link or use "
        "a new folder"
    )


def refuse_links(folder: Path, flag: str) -> None:
    """ValueError naming ``flag`` and the link when ``folder`` is a symbolic link or holds one
    anywhere below it (links are not followed): rodval makes no link, so writing there could
    go into a file or folder of another (a run.json linked to another run's)."""
    if folder.is_symlink():
        raise _link_refusal(flag, folder, "is")
    pending = [folder] if folder.is_dir() else []
    while pending:
        with os.scandir(pending.pop()) as entries:
            for entry in entries:
                if entry.is_symlink():
                    raise _link_refusal(flag, Path(entry.path), "is")
                if entry.is_dir(follow_symlinks=False):
                    pending.append(Path(entry.path))


def write_with(path: Path, produce: Callable[[Path], object], flag: str = "--out") -> Path:
    """Write ``path`` by ``produce(tmp)`` (which writes the file it is given, a temporary
    file beside ``path`` of the same suffix), then rename it over ``path``: never through a
    link (ValueError naming ``flag`` when ``path`` is one), never half-written. Creates the
    missing parent folders (as ``mkdir -p``)."""
    path = Path(path)
    if path.is_symlink():
        raise _link_refusal(flag, path, "is")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
    try:
        produce(tmp)
        if path.is_symlink():  # made while the file was produced
            raise _link_refusal(flag, path, "is")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def write_file(path: Path, data: bytes | str, flag: str = "--out") -> Path:
    """Write ``data`` (text as UTF-8) to ``path`` through ``write_with``: the one way rodval
    writes a file."""
    raw = data.encode() if isinstance(data, str) else data
    return write_with(path, lambda tmp: tmp.write_bytes(raw), flag)


def write_figure(fig: Any, path: Path, flag: str = "--out", **savefig: Any) -> Path:
    """Save a matplotlib figure to ``path`` (its format from the suffix) through
    ``write_file``; ``savefig``: keyword arguments of ``Figure.savefig``."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format=Path(path).suffix.lstrip(".") or "png", **savefig)
    return write_file(path, buffer.getvalue(), flag)


def refuse_foreign(
    folder: Path, flag: str, owned: Callable[[Path], bool], kind: str, marker: str
) -> None:
    """ValueError naming ``flag`` unless ``folder`` is missing, empty, or rodval's
    (``owned(folder)``): rodval writes into no folder that holds files it did not write.
    ``kind`` ("study", "run") and ``marker`` (its file, e.g. "study.json") name the folder
    rodval looked for in the refusal; its housekeeping and the temporary file of an atomic
    write killed before its rename (of the marker itself) are rodval's. A folder that is or
    holds a symbolic link is refused first (``refuse_links``)."""
    refuse_links(folder, flag)
    if not folder.exists():
        return
    if not folder.is_dir():
        raise ValueError(f"{flag} {folder}: is a file, not a folder")
    if owned(folder):
        return
    entries = sorted(
        p.name
        for p in folder.iterdir()
        if p.name not in HOUSEKEEPING and not TEMPORARY.fullmatch(p.name)
    )
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
    ``flag``, before any work: a non-empty path, not a folder, where a file can be created,
    none of the ``protected`` files (the command's inputs), not
    a file ``reserved`` for another purpose (it returns why, e.g. "a file of the study in
    out/"), not a symbolic link, and, when the file exists, one rodval wrote (``ours(path)``).
    Missing folders above it are fine when they can be made (``write_with`` makes them)."""
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
    if p.is_symlink():
        raise _link_refusal(flag, p, "is")
    parent = _existing_folder(p, flag)
    if parent != p.parent:  # its missing folders are made when the file is written
        return p
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


def _existing_folder(p: Path, flag: str) -> Path:
    """The nearest existing folder above file ``p``: ValueError naming ``flag`` when it is a
    file (no folder can be made there) or cannot be written into (its missing folders are
    made as ``mkdir -p`` does when the file is written)."""
    parent = p.parent
    while not parent.exists() and not parent.is_symlink() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"{flag} {p}: {parent} is a file, so no folder can hold {p.name} there")
    if parent != p.parent and not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(
            f"{flag} {p}: its folder {p.parent} does not exist and cannot be made in {parent} "
            "(permission denied)"
        )
    return parent


def owner_command(folder: Path) -> str | None:
    """The rodval command whose output folder ``folder`` is (a stamped ``study.json``:
    "study", ``run.json``: "simulate", ``rodval.json``: its command), or None."""
    record = _marker(folder)
    if record is not None:
        return str(record.get("command"))
    for marker, schema, command in (
        ("study.json", STUDY_SCHEMA, "study"),
        ("run.json", RUN_SCHEMA, "simulate"),
    ):
        if is_stamped(read_json(folder / marker), schema):
            return command
    return None


def in_command_folder(path: Path) -> str | None:
    """Why file ``path`` is not free for a command without a folder of its own (``rodval
    animate --out``): it lies in the output folder of a rodval command (its folder or one
    above), which holds that command's files only; else None."""
    for folder in Path(os.path.abspath(path)).parents:
        command = owner_command(folder)
        if command is not None:
            return f"in {folder}, the output folder of rodval {command} (its files only)"
    return None


def inside(path: Path, folder: Path) -> Path | None:
    """``path`` relative to ``folder`` when it lies inside it (both resolved), else None."""
    try:
        return path.resolve().relative_to(folder.resolve())
    except (ValueError, OSError, RuntimeError):
        return None


#: The marker of a plain output folder (``rodval compare``, ``modes``, ``reproduce``,
#: ``bench``): ``rodval.json``, stamped with ``OUTPUT_SCHEMA``, naming the command that owns
#: the folder and the files it wrote there (``FILES_KEY``: paths relative to the folder).
OUTPUT_MARKER, OUTPUT_SCHEMA = "rodval.json", "rodval-output"
FILES_KEY = "files"


def output_folder_owned(folder: Path) -> bool:
    """Whether ``folder`` carries rodval's output marker (``mark_output_folder``)."""
    return is_stamped(read_json(folder / OUTPUT_MARKER), OUTPUT_SCHEMA)


def _marker(folder: Path) -> dict[str, Any] | None:
    record = read_json(folder / OUTPUT_MARKER)
    return record if is_stamped(record, OUTPUT_SCHEMA) else None


def folder_files(folder: Path) -> list[str]:
    """The files below ``folder`` (paths relative to it, '/'-separated, sorted) but its
    marker, rodval's housekeeping and the temporary files of atomic writes."""
    if not folder.is_dir():
        return []
    return sorted(
        p.relative_to(folder).as_posix()
        for p in folder.rglob("*")
        if p.is_file()
        and p.name not in (OUTPUT_MARKER, *HOUSEKEEPING)
        and not TEMPORARY.fullmatch(p.name)
    )


def listed_files(folder: Path) -> list[str] | None:
    """The files the marker of output folder ``folder`` lists as rodval's (None: a marker
    of an older rodval, which lists none: every file there was taken as rodval's)."""
    record = _marker(folder) or {}
    files = record.get(FILES_KEY)
    if not isinstance(files, list):
        return None
    return [f for f in files if isinstance(f, str) and ".." not in Path(f).parts]


def claim_output_folder(folder: Path, flag: str = "--out", command: str | None = None) -> None:
    """Refuse, before work, an output folder rodval may not write into: one that is or holds
    a link, holds files rodval did not write (no marker, or files its marker does not
    list), or, given ``command``, is the output folder of another command (each command's
    folder holds its files only)."""
    refuse_foreign(folder, flag, output_folder_owned, "output", OUTPUT_MARKER)
    record = _marker(folder)
    if record is None:
        return
    owner = record.get("command")
    if command is not None and owner != command:
        raise ValueError(
            f"{flag} {folder}: is the output folder of rodval {owner}; rodval {command} keeps "
            "its files apart from another command's: use another folder"
        )
    listed = listed_files(folder)
    unlisted = [f for f in folder_files(folder) if listed is not None and f not in listed]
    if unlisted:
        raise ValueError(
            f"{flag} {folder}: holds {_named(unlisted)}, which its {OUTPUT_MARKER} does not "
            "list among the files rodval wrote, so rodval will not write there; use a new or "
            "empty folder"
        )


def clear_previous(folder: Path, command: str, keep: Iterable[str] = ()) -> list[str]:
    """Remove the files the earlier run of ``command`` wrote into output folder ``folder``
    (those its marker lists; nothing else) but those in ``keep`` (paths relative to the
    folder: the files this run takes over, ``rodval reference``'s finished levels): called by
    the command just before it writes its own, so that the folder holds this run's files
    only (no events.csv of an earlier compare whose runs locked). Returns the removed files."""
    record = _marker(folder)
    listed = listed_files(folder) if record and record.get("command") == command else None
    removed, kept = [], set(keep)
    for name in [f for f in listed or [] if f not in kept]:
        path = folder / name
        if path.is_file() and not path.is_symlink():
            path.unlink()
            removed.append(name)
    return removed


def mark_output_folder(folder: Path, command: str, coming: Iterable[str] = ()) -> None:
    """Mark ``folder`` (when the command made or wrote it) as the output folder of
    ``command``, listing the files there (``claim_output_folder`` let in no other) and the
    files ``coming`` (paths relative to the folder) that the command will write: listed
    before they are written, a file a killed command leaves is never one rodval disowns."""
    if not folder.is_dir() or folder.is_symlink():
        return
    files = sorted({*folder_files(folder), *coming})
    record = stamp({"command": command, FILES_KEY: files}, OUTPUT_SCHEMA)
    write_file(folder / OUTPUT_MARKER, json.dumps(record, indent=1))
