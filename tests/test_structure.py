"""The shape of the code (issue "one run contract"): small functions and modules, one list of
model names. Each check counts with ``ast`` and names every offender, so it fails on the first
function or module that grows past its bound."""

import ast
from pathlib import Path

import pytest

from rodval.models.registry import MODEL_NAMES

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("rodval", "reference_models")
MAX_FUNCTION_LINES = 70
MAX_MODULE_LINES = 600


def _modules() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def _trees() -> list[tuple[Path, ast.Module]]:
    return [(p, ast.parse(p.read_text(), filename=str(p))) for p in _modules()]


def test_the_packages_are_found():
    assert len(_modules()) > 50


def test_no_module_longer_than_600_lines():
    long = {
        str(p.relative_to(ROOT)): n
        for p in _modules()
        if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
    }
    assert not long, f"modules over {MAX_MODULE_LINES} lines: {long}"


def test_no_function_longer_than_70_lines():
    long = {
        f"{p.relative_to(ROOT)}::{node.name}": node.end_lineno - node.lineno + 1
        for p, tree in _trees()
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES
    }
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"


def _name_lists(tree: ast.Module) -> list[tuple[int, list[str]]]:
    """Tuple, list and set literals of two or more model names (line, names)."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Tuple | ast.List | ast.Set):
            names = [
                e.value for e in node.elts if isinstance(e, ast.Constant) and e.value in MODEL_NAMES
            ]
            if len(names) >= 2 and len(names) == len(node.elts):
                out.append((node.lineno, names))
    return out


def test_the_registry_is_the_only_list_of_model_names():
    registry = ROOT / "rodval" / "models" / "registry.py"
    found = {
        f"{p.relative_to(ROOT)}:{line}": names
        for p, tree in _trees()
        if p != registry
        for line, names in _name_lists(tree)
    }
    assert not found, f"model names listed outside the registry: {found}"


@pytest.mark.parametrize(
    "source, count",
    [
        ("x = ('full', 'reduced')", 1),
        ("x = ['reduced', 'exudyn', 'full']", 1),
        ("x = ('full',)", 0),
    ],
)
def test_the_name_list_check_finds_literals(source, count):
    assert len(_name_lists(ast.parse(source))) == count


def test_no_private_name_is_imported_from_another_module():
    """A module's private names stay in it (issue 41): a name another module imports is part
    of its module's interface and has a public name. Names every import of a private name."""
    private = [
        f"{p.relative_to(ROOT)}: {node.module or '.'}.{alias.name}"
        for p, tree in _trees()
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom)
        and (node.level or (node.module or "").split(".")[0] in PACKAGES)
        for alias in node.names
        if alias.name.startswith("_") and not alias.name.startswith("__")
    ]
    assert not private, f"private names imported from another module: {private}"


#: issue 55: at most this many functions take 10 or more parameters (self and cls not counted)
MAX_WIDE_FUNCTIONS = 10


def test_at_most_ten_functions_take_ten_or_more_parameters():
    wide = []
    for p, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                a = node.args
                k = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                k += (a.vararg is not None) + (a.kwarg is not None)
                k -= bool(a.args) and a.args[0].arg in ("self", "cls")
                if k >= 10:
                    wide.append(f"{p.relative_to(ROOT)}::{node.name} ({k})")
    assert len(wide) <= MAX_WIDE_FUNCTIONS, f"{len(wide)} wide functions: {wide}"


def test_no_import_loop_between_the_model_rooms():
    """The rooms of rodval/models/ (assembly, bending, hinge_items, systems, ...) import one
    another one way only (issue 55): names every pair of rooms that import each other,
    directly or through others."""
    root = ROOT / "rodval" / "models"
    graph: dict[str, set[str]] = {}
    for p in root.rglob("*.py"):
        parts = p.relative_to(root).parts
        here = parts[0] if len(parts) > 1 else "."
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                "rodval.models."
            ):
                there = (node.module or "").split(".")[2]
                if there != here:
                    graph.setdefault(here, set()).add(there)

    def reach(a: str) -> set[str]:
        out, stack = set(), [a]
        while stack:
            for b in graph.get(stack.pop(), ()):
                if b not in out:
                    out.add(b)
                    stack.append(b)
        return out

    loops = sorted({tuple(sorted((a, b))) for a in graph for b in reach(a) if a in reach(b)})
    assert not loops, f"rooms of rodval/models/ that import each other: {loops}"
