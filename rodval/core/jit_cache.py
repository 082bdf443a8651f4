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
the analysis recompiles nothing; an edit of the ladder's kernels (``models/ladder_kernels.py``)
recompiles neither the integrators (they take right-hand sides as first-class function
pointers, ``solvers.signature``) nor the paper models' kernels. ``tests/test_jit_cache.py``
counts the compilations on a small package. Other packages' caches are untouched.

Cost: the closure of a module is parsed once per process (``ast``, a few ms per file, memoised);
``import rodval`` does not import this module (the hook in ``rodval/__init__`` installs it on
numba's first import).

It patches numba's ``_SourceFileBackedLocatorMixin.get_source_stamp`` (a private API, the base
of numba's in-tree, user-provided and user-wide cache locators since numba 0.4x); with a numba
whose internals differ, ``install`` returns False and numba's own caching applies.
"""

from __future__ import annotations

import ast
import hashlib
import os
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


@cache
def _imports(path: Path, root: Path) -> frozenset[Path]:
    """The files under ``root`` that the module at ``path`` imports by name (one level)."""
    package = root.name
    here = path.relative_to(root).parts[:-1]  # the package the module is in
    found: set[Path] = set()

    def add(parts: tuple[str, ...]) -> None:
        file = _module_file(root, parts)
        if file is not None:
            found.add(file)

    for node in ast.walk(ast.parse(path.read_bytes(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                names = alias.name.split(".")
                if names[0] == package:
                    add(tuple(names[1:]))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                keep = len(here) - (node.level - 1)
                if keep < 0:
                    continue
                target = here[:keep] + tuple((node.module or "").split(".") if node.module else ())
            elif node.module and node.module.split(".")[0] == package:
                target = tuple(node.module.split(".")[1:])
            else:
                continue
            add(target)
            for alias in node.names:
                add((*target, alias.name))
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


@cache
def closure_digest(path: Path, root: Path = PACKAGE_ROOT) -> str:
    """SHA-256 over the relative paths and contents of ``import_closure(path, root)``."""
    h = hashlib.sha256()
    for file in import_closure(path, root):
        h.update(file.relative_to(root).as_posix().encode())
        h.update(b"\0")
        h.update(file.read_bytes())
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
        original_stamp = mixin.get_source_stamp
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
