"""numba's on-disk cache of rodval's kernels, invalidated by any change of rodval's sources.

numba keys a cached function by its own source file only (the file's stamp: its modification
time and size, or its content hash in recent numba), while the cached machine code contains the
functions it calls from other modules. A kernel whose callee in another file changed (an
upgrade that changes some files and not others, a local edit) keeps running the old callee:
measured here, ``bench.scale._rhs_loop`` cached against the full model's old right-hand side
hung after the kernels' module changed. ``install`` adds a digest of every rodval source file
to the stamp of each function defined in rodval, so any change of rodval's sources recompiles
rodval's cached kernels once (a few seconds) and never runs stale code. Other packages'
caches are untouched.

It patches numba's ``_SourceFileBackedLocatorMixin.get_source_stamp`` (a private API, the
base of numba's in-tree, user-provided and user-wide cache locators since numba 0.4x); with a
numba whose internals differ, ``install`` returns False and numba's own caching applies.
Importing this module installs it (``rodval/__init__`` imports it first; ``INSTALLED``).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

#: The package whose sources key the cache.
PACKAGE_ROOT = Path(__file__).resolve().parents[1]


def source_digest(root: Path = PACKAGE_ROOT) -> str:
    """SHA-256 over the relative paths and contents of every ``*.py`` under ``root``, in a
    fixed order (about 100 files, a few milliseconds)."""
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(b"\0")
        h.update(path.read_bytes())
    return h.hexdigest()


#: The digest of each root installed (its path with a trailing separator -> digest).
_DIGESTS: dict[str, str] = {}


def install(root: Path = PACKAGE_ROOT) -> bool:
    """Key the numba cache of every function defined under ``root`` by ``source_digest``
    (before any of its kernels is decorated; numba's locator is patched once per process).
    Returns whether numba's locator could be patched."""
    try:
        from numba.core import caching

        mixin = caching._SourceFileBackedLocatorMixin
        original = mixin.get_source_stamp
    except (ImportError, AttributeError):
        return False
    _DIGESTS[str(Path(root).resolve()) + os.sep] = source_digest(Path(root))
    if getattr(original, "keyed_by_sources", False):
        return True

    def get_source_stamp(self):
        stamp = original(self)
        path = str(Path(getattr(self, "_py_file", "")).resolve())
        for prefix, digest in _DIGESTS.items():
            if path.startswith(prefix):
                return (stamp, digest)
        return stamp

    get_source_stamp.keyed_by_sources = True  # type: ignore[attr-defined]
    mixin.get_source_stamp = get_source_stamp  # type: ignore[method-assign]
    return True


INSTALLED = install()
