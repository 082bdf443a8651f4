"""A study's ``[scene]`` that names a scene file: ``[scene] file = "wing.toml"`` and overrides.

The file (a path relative to the study file's folder, or absolute) is read with
``scene_file_document``, so its tabulated loads' CSV files are found relative to the scene
file, and a file ``based_on`` another is resolved. The other keys of ``[scene]`` override the
file's as a later file does (``rodval.core.scene_keys.merge_documents``): the sections
(``chain``, ``initial``, ``base``, ``base.motion``) are merged key by key (a ``base`` of
another ``kind`` replaces the file's base whole), any other value (a number, a list:
``latches``, ``stops``, ``loads``, ``times``) replaces the file's whole. The
resolved table, not the path, is what the cases build, run and record; the file's SHA-256
(with those of the files it is based on) goes into study.json so that a later run in the same
folder notices that a file changed (``rodval.study.store``). Every error is one line naming
``scene.file``, before any case runs; a study file named there is refused as one.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rodval.core.scene_file import TOP_KEYS as SCENE_TOP_KEYS
from rodval.core.scene_file import scene_file_document
from rodval.core.scene_keys import merge_documents
from rodval.study.document import key_error
from rodval.study.toml_text import toml_text


@dataclass(frozen=True)
class SceneFile:
    """The scene file a study's [scene] names: its path as read and its SHA-256 (hex) at
    that time."""

    path: str
    sha256: str

    def as_dict(self) -> dict[str, str]:
        """The form study.json holds."""
        return {"path": self.path, "sha256": self.sha256}


def resolve_scene(
    table: Any, folder: Path, where: str, study_keys: Iterable[str] = ()
) -> tuple[Any, SceneFile | None]:
    """The [scene] ``table`` of the study ``where`` with its ``file`` (relative to
    ``folder``) read and the table's other keys laid over it as a later scene file's are
    (``merge_documents``: neither is changed), and the file
    read; ``table`` itself and None when it names no file. ``study_keys``: the top-level keys
    of a study file; a file holding one that no scene file has is refused as a study file."""
    if not isinstance(table, dict) or "file" not in table:
        return table, None
    path = _scene_path(table, folder, where)
    document, digest = _read(path, where)
    study = sorted((set(document) & set(study_keys)) - SCENE_TOP_KEYS)
    if study:
        raise key_error(
            where,
            "scene.file",
            f"{str(path)!r} is a study file (it has [{study[0]}]), not a scene file; name a "
            "scene file (docs/scene_file.md)",
        )
    overrides = {k: v for k, v in table.items() if k != "file"}
    return merge_documents(document, overrides), SceneFile(str(path), digest)


def _scene_path(table: dict[str, Any], folder: Path, where: str) -> Path:
    """The path of the scene file ``table["file"]`` names (``folder`` / a relative one),
    checked: a string, no ``based_on`` beside it, an existing file."""
    file = table["file"]
    if not isinstance(file, str) or not file:
        raise key_error(
            where, "scene.file", f"must be the path of a scene file (a string), got {file!r:.60}"
        )
    if "based_on" in table:
        raise key_error(
            where,
            "scene.file",
            "cannot be combined with based_on in [scene]; write based_on in the scene file",
        )
    path = folder / file
    if not path.exists():
        raise key_error(
            where,
            "scene.file",
            f"{str(path)!r} does not exist (a relative path is taken from the study file's folder)",
        )
    if not path.is_file():
        raise key_error(where, "scene.file", f"{str(path)!r} is not a file")
    return path


def _read(path: Path, where: str) -> tuple[dict[str, Any], str]:
    """The scene document of the file ``path`` (``scene_file_document``: its load files
    anchored at its folder, its ``based_on`` file resolved) and the SHA-256 (hex) of its bytes
    (followed, for a file based on others, by theirs)."""
    try:
        document, files = scene_file_document(path.absolute())
        digest = hashlib.sha256(b"".join(f.read_bytes() for f in files)).hexdigest()
    except OSError as exc:
        raise key_error(where, "scene.file", f"cannot read {str(path)!r}: {exc.strerror}") from None
    except ValueError as exc:
        raise key_error(where, "scene.file", str(exc)) from None
    document.setdefault("name", path.stem)
    return document, digest


def resolved_text(doc: dict[str, Any], where: str, scene_file: SceneFile) -> str:
    """The study document ``doc`` (its [scene] resolved) as TOML, the text copied beside the
    results as study.toml: it reruns the same study without the scene file."""
    return f"# {where}, its [scene] file {scene_file.path} resolved\n{toml_text(doc)}"
