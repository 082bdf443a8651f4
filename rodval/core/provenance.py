"""Where a result came from: package versions and the machine, recorded beside outputs."""

from __future__ import annotations

import os
import platform
from importlib import metadata

PACKAGES = ("rodval", "numpy", "scipy", "pandas", "matplotlib", "numba", "exudyn", "dask")


def package_versions() -> dict[str, str | None]:
    out: dict[str, str | None] = {}
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def machine() -> dict[str, object]:
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
    }


def provenance() -> dict[str, object]:
    return {"machine": machine(), "packages": package_versions()}
