"""The shape of the code, as issue 55's table measures it: rerun it to see where the redesign
stands.

    .venv/bin/python benchmarks/code_shape.py            # every row (mypy and the trace: ~1 min)
    .venv/bin/python benchmarks/code_shape.py --quick    # without mypy, the trace, duplicates

Rows: the longest chain of project classes in the MRO of any system class (a subclass of
``rodval.solvers.system.OdeSystem``), "product" classes (bodies made only of
``name = staticmethod(kernel)`` lines), files naming the latch, the run path before the
integration (``../shared/tools/trace_run.py``: stops, returns, parameters checked more than
once), ``update_status`` calls, functions with >= 10 parameters (self and cls not counted) and
over 70 lines, ``duplicates`` pairs in rodval/, physics modules left in core/, import loops
between the sub-folders of rodval/models/, ``mypy --strict`` errors on rodval/, and the lines
of rodval/.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import json
import os
import pkgutil
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("rodval", "reference_models")
#: the modules issue 55 names as physics that core held
PHYSICS = ("rigid", "lock_window", "eigen", "damping", "modal", "root_momentum")
WIDE = 10
LONG = 70


def _trees(pkg: str = "rodval") -> list[tuple[Path, ast.Module]]:
    return [(p, ast.parse(p.read_text())) for p in sorted((ROOT / pkg).rglob("*.py"))]


def class_chains() -> tuple[int, str]:
    """The longest chain of rodval classes in a system class's MRO, and that class."""
    import rodval
    from rodval.solvers.system import OdeSystem

    for info in pkgutil.walk_packages(rodval.__path__, "rodval."):
        if info.name.startswith("rodval.cli") or info.name.endswith("__main__"):
            continue
        importlib.import_module(info.name)
    best = (0, "")
    stack = [OdeSystem]
    seen: set[type] = set()
    while stack:
        cls = stack.pop()
        if cls in seen:
            continue
        seen.add(cls)
        stack.extend(cls.__subclasses__())
        depth = sum(1 for c in inspect.getmro(cls) if c.__module__.startswith("rodval"))
        best = max(best, (depth, f"{cls.__module__}.{cls.__qualname__}"))
    return best


def product_classes() -> list[str]:
    """Classes whose body (docstring aside) is only ``name = staticmethod(...)`` lines."""
    out = []
    for pkg in PACKAGES:
        for p, tree in _trees(pkg):
            for node in ast.walk(tree):
                if not isinstance(node, ast.ClassDef):
                    continue
                body = [
                    s
                    for s in node.body
                    if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant))
                ]
                if body and all(
                    isinstance(s, ast.Assign)
                    and isinstance(s.value, ast.Call)
                    and getattr(s.value.func, "id", "") == "staticmethod"
                    for s in body
                ):
                    out.append(f"{p.relative_to(ROOT)}::{node.name}")
    return out


def functions() -> tuple[list[str], list[str]]:
    """Functions with >= WIDE parameters and functions over LONG lines."""
    wide, long = [], []
    for pkg in PACKAGES:
        for p, tree in _trees(pkg):
            for n in ast.walk(tree):
                if not isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef):
                    continue
                a = n.args
                params = [*a.posonlyargs, *a.args, *a.kwonlyargs]
                k = len(params) + (a.vararg is not None) + (a.kwarg is not None)
                k -= bool(a.args) and a.args[0].arg in ("self", "cls")
                where = f"{p.relative_to(ROOT)}:{n.lineno} {n.name}"
                if k >= WIDE:
                    wide.append(f"{where} ({k})")
                if (lines := (n.end_lineno or n.lineno) - n.lineno + 1) > LONG:
                    long.append(f"{where} ({lines} lines)")
    return wide, long


def folder_loops() -> list[list[str]]:
    """Strongly connected groups (> 1) of rodval/models/ sub-folders by their imports."""
    root = ROOT / "rodval" / "models"
    graph: dict[str, set[str]] = {}
    for p in root.rglob("*.py"):
        parts = p.relative_to(root).parts
        here = parts[0] if len(parts) > 1 else "."
        for n in ast.walk(ast.parse(p.read_text())):
            if isinstance(n, ast.ImportFrom) and (n.module or "").startswith("rodval.models."):
                there = (n.module or "").split(".")[2]
                if there != here:
                    graph.setdefault(here, set()).add(there)
    loops = []
    for a in graph:
        group = {a} | {b for b in _reach(graph, a) if a in _reach(graph, b)}
        if len(group) > 1 and sorted(group) not in loops:
            loops.append(sorted(group))
    return loops


def _reach(graph: dict[str, set[str]], a: str) -> set[str]:
    out, stack = set(), [a]
    while stack:
        for b in graph.get(stack.pop(), ()):
            if b not in out:
                out.add(b)
                stack.append(b)
    return out


def _run(args: list[str], cwd: Path = ROOT) -> str:
    """The command's standard output."""
    return subprocess.run(args, cwd=cwd, capture_output=True, text=True, check=False).stdout


def slow_rows() -> dict[str, object]:
    """The rows that run tools: the trace, duplicates and mypy."""
    py = sys.executable
    tracer = Path(os.environ.get("RODVAL_TRACER", ROOT.parent / "shared/tools/trace_run.py"))
    out: dict[str, object] = {}
    if tracer.exists():
        text = _run([py, str(tracer), "--", "simulate", "paper", "--model", "full", "--t-end",
                     "1.0", "--out", tempfile.mkdtemp()])  # fmt: skip
        trace = json.loads([line for line in text.splitlines() if line.startswith("{")][-1])
        out["trace stops / returns"] = f"{trace['stops_before_integration']} / {trace['returns']}"
        out["parameters checked more than once"] = trace["checked_more_than_once"]
    dup = _run(["duplicates", "--seconds", "120"], cwd=ROOT / "rodval").splitlines()
    out["duplicates pairs in rodval/"] = dup[0] if dup else "duplicates not found"
    mypy = _run([str(Path(py).parent / "mypy"), "--strict", "rodval"]).strip().splitlines()
    out["mypy --strict on rodval/"] = mypy[-1] if mypy else ""
    return out


def main(quick: bool) -> None:
    depth, deepest = class_chains()
    wide, long = functions()
    latch = [
        str(p.relative_to(ROOT))
        for pkg in PACKAGES
        for p, _ in _trees(pkg)
        if re.search(r"\bLatch\b", p.read_text())
    ]
    rows: dict[str, object] = {
        "longest chain of project classes (system class)": f"{depth} ({deepest})",
        "product classes": product_classes(),
        "source files naming the Latch class": len(latch),
        "update_status calls": sum(
            p.read_text().count("update_status(") for pkg in PACKAGES for p, _ in _trees(pkg)
        ),
        f"functions with >= {WIDE} parameters": len(wide),
        f"functions over {LONG} lines": long,
        "physics modules in core/": [m for m in PHYSICS if (ROOT / f"rodval/core/{m}.py").exists()],
        "folder loops in rodval/models/": folder_loops(),
        "lines of rodval/": sum(
            len(p.read_text().splitlines()) for p in (ROOT / "rodval").rglob("*.py")
        ),
    }
    if not quick:
        rows.update(slow_rows())
    for key, value in rows.items():
        print(f"{key}: {value}")
    print("wide functions:", *wide, sep="\n  ")


if __name__ == "__main__":
    main("--quick" in sys.argv)
