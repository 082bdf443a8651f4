"""numba's on-disk cache of rodval's kernels, keyed by the sources each kernel depends on.

numba keys a cached function by its own source file only (the file's stamp: its modification
time and size), while the cached machine code contains the functions it calls from other
modules and the module-level constants it reads from them. A kernel whose callee in another
file changed (an upgrade that changes some files and not others, a local edit) would keep
running the old callee: measured here, ``bench.scale._rhs_loop`` cached against the full
model's old right-hand side hung after the kernels' module changed.

``install`` keys each cached function defined under a package root by a digest of the sources
its module can reach (in place of the file's stamp: a checkout or copy that changes
modification times and no content keeps the cache): the module itself and every module of the
package it imports, directly or through others (``import_closure``; imports inside functions
and ``TYPE_CHECKING`` blocks count too, which can only over-invalidate). (A specialization for
a jitted function passed as an argument, ``bench.scale._rhs_loop(rhs, ...)``, is compiled in
each process: numba 0.68 does not find it in its cache again.) So an edit recompiles exactly
the kernels whose closure holds the edited file: an edit of the CLI, the report, the studies or
the analysis recompiles nothing; an edit of the ladder's kernels (``models/kinematics/ladder_kernels.py``)
recompiles neither the integrators (they take right-hand sides as first-class function
pointers, ``solvers.signature``) nor the paper models' kernels. ``tests/test_jit_cache.py``
counts the compilations on a small package. Other packages' caches are untouched.

numba compiles the bytecode Python loaded, which is not always the source's: Python reuses a
compiled copy (``.pyc``) whose whole-second modification time and size match the source, so a
same-size edit within the second of the copy runs the old code. Such a copy goes into the key
too (``_stale_bytecode``): the kernel compiled from it is never served for the source once
Python compiles the source again (it would have been, keyed by the source's content alone).

Cost: the closures are read once per process (a regular expression over each file's import
statements, memoised: 0.09 s for every kernel module of rodval);
``import rodval`` does not import this module (the hook in ``rodval/__init__`` installs it on
numba's first import).

It patches numba's ``_SourceFileBackedLocatorMixin.get_source_stamp`` (a private API, the base
of numba's in-tree, user-provided and user-wide cache locators since numba 0.4x); with a numba
whose internals differ, ``install`` returns False and numba's own caching applies.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import re
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

#: The package whose sources key the cache.
PACKAGE_ROOT = Path(__file__).resolve().parents[1]

#: Each installed package root (resolved, with a trailing separator).
_ROOTS: list[str] = []


def _module_file(root: Path, parts: tuple[str, ...]) -> Path | None:
    """The file of module ``root.name + parts`` under ``root``, or None if there is none."""
    base = root.joinpath(*parts)
    candidates = (
        (base / "__init__.py",) if not parts else (base.with_suffix(".py"), base / "__init__.py")
    )
    return next((path for path in candidates if path.is_file()), None)


#: ``from X import names`` (names possibly parenthesised over lines) and ``import X, Y``
#: statements, anywhere in a file (inside functions and ``TYPE_CHECKING`` blocks too; a match
#: in a string only adds a dependency, which is safe). A regular expression, not ``ast``: the
#: closure of a kernel module is read on every run's first import of numba (ast: 0.3 s).
_FROM = re.compile(r"^[ \t]*from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)", re.M)
_IMPORT = re.compile(r"^[ \t]*import[ \t]+([^\n]+)", re.M)


@cache
def _imports(path: Path, root: Path) -> frozenset[Path]:
    """The files under ``root`` that the module at ``path`` imports by name (one level)."""
    package = root.name
    here = path.relative_to(root).parts[:-1]  # the package the module is in
    text = path.read_text(encoding="utf-8", errors="replace").replace("\\\n", " ")
    found: set[Path] = set()

    def add(parts: tuple[str, ...]) -> None:
        file = _module_file(root, parts)
        if file is not None:
            found.add(file)

    for match in _IMPORT.finditer(text):
        for item in match.group(1).split(","):
            names = item.split(" as ")[0].strip().split(".")
            if names[0] == package:
                add(tuple(names[1:]))
    for dots, module, what in _FROM.findall(text):
        if dots:
            keep = len(here) - (len(dots) - 1)
            if keep < 0:
                continue
            target = here[:keep] + (tuple(module.split(".")) if module else ())
        elif module.split(".")[0] == package:
            target = tuple(module.split(".")[1:])
        else:
            continue
        add(target)
        for item in what.strip("()").replace("\n", " ").split(","):
            name = item.split(" as ")[0].split("#")[0].strip()
            if name.isidentifier():
                add((*target, name))
    found.discard(path)
    return frozenset(found)


@cache
def import_closure(path: Path, root: Path = PACKAGE_ROOT) -> tuple[Path, ...]:
    """The module at ``path`` and every module under ``root`` it reaches by imports, sorted."""
    seen = {path}
    todo = [path]
    while todo:
        for dep in _imports(todo.pop(), root):
            if dep not in seen:
                seen.add(dep)
                todo.append(dep)
    return tuple(sorted(seen))


def _stale_bytecode(file: Path) -> bytes | None:
    """The compiled copy (``.pyc``) Python may load for ``file`` although it may not be the
    compiled source, else None.

    Python checks a timestamp ``.pyc`` by the source's modification time in whole seconds and
    its size only: a same-size edit within the second the copy was written leaves a copy that
    Python keeps loading. Flagged: a timestamp copy whose header matches the source's stamp but
    that was written before the source's last change, or a hash-based copy whose hash is not
    the source's (loaded when unchecked)."""
    try:
        pyc = Path(importlib.util.cache_from_source(str(file)))
        with pyc.open("rb") as stream:
            head = stream.read(16)
        source = file.stat()
        written = pyc.stat().st_mtime_ns
    except (OSError, ValueError, NotImplementedError):  # no copy, or no cache tag
        return None
    if len(head) < 16 or head[:4] != importlib.util.MAGIC_NUMBER:
        return None
    if int.from_bytes(head[4:8], "little") & 1:  # hash-based
        stale = head[8:16] != importlib.util.source_hash(file.read_bytes())
    else:
        stamp = (int(source.st_mtime) & 0xFFFFFFFF, source.st_size & 0xFFFFFFFF)
        header = (int.from_bytes(head[8:12], "little"), int.from_bytes(head[12:16], "little"))
        stale = header == stamp and written < source.st_mtime_ns
    try:
        return pyc.read_bytes() if stale else None
    except OSError:
        return None


@cache
def closure_digest(path: Path, root: Path = PACKAGE_ROOT) -> str:
    """SHA-256 over the relative paths and contents of ``import_closure(path, root)``, and
    over the compiled copy Python may load in place of a source (``_stale_bytecode``): numba
    compiles the bytecode Python loaded, so a kernel compiled from a stale copy is cached
    under a key of its own, never under the source's (where it would outlive the copy)."""
    h = hashlib.sha256()
    for file in import_closure(path, root):
        h.update(file.relative_to(root).as_posix().encode())
        h.update(b"\0")
        h.update(file.read_bytes())
        stale = _stale_bytecode(file)
        if stale is not None:
            h.update(b"\0stale bytecode\0")
            h.update(stale)
    return h.hexdigest()


def _digest_of(py_file: str) -> str | None:
    """The closure digest of a file under an installed root, else None."""
    path = Path(py_file).resolve()
    for prefix in _ROOTS:
        if str(path).startswith(prefix):
            return closure_digest(path, Path(prefix))
    return None


def install(root: Path = PACKAGE_ROOT) -> bool:
    """Key the numba cache of every function defined under ``root`` by the closure digest of
    its module (before any of its kernels is decorated; numba is patched once per process).
    Returns whether numba could be patched."""
    try:
        from numba.core import caching

        mixin = caching._SourceFileBackedLocatorMixin
        original_stamp: Callable[[Any], Any] = mixin.get_source_stamp  # numba: untyped
    except (ImportError, AttributeError):
        return False
    prefix = str(Path(root).resolve()) + os.sep
    if prefix not in _ROOTS:
        _ROOTS.append(prefix)
    if getattr(original_stamp, "keyed_by_sources", False):
        return True

    def get_source_stamp(self: Any) -> Any:
        digest = _digest_of(getattr(self, "_py_file", ""))
        return original_stamp(self) if digest is None else ("sources", digest)

    get_source_stamp.keyed_by_sources = True  # type: ignore[attr-defined]
    mixin.get_source_stamp = get_source_stamp  # type: ignore[method-assign]
    return True


INSTALLED = install()
