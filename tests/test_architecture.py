"""The layers contract (import-linter) and the absence of import cycles.

``lint-imports`` checks the contract in pyproject.toml ([tool.importlinter]); these tests show
that it is in force (it fails on a reversed import in a copy of the package) and that no
module of rodval or reference_models takes part in an import cycle.
"""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

grimp = pytest.importorskip("grimp")

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")


def _lint(cwd: Path) -> subprocess.CompletedProcess:
    env = {"PYTHONPATH": str(cwd), "PATH": str(LINT.parent)}
    return subprocess.run(
        [str(LINT), "--no-cache"], cwd=cwd, capture_output=True, text=True, env=env, timeout=300
    )


@pytest.mark.skipif(not LINT.exists(), reason="import-linter is not installed")
def test_layers_contract_holds_and_fails_on_a_reversed_import(tmp_path):
    for item in ("rodval", "reference_models", "pyproject.toml"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(
            src,
            tmp_path / item,
            **({"ignore": shutil.ignore_patterns("__pycache__")} if src.is_dir() else {}),
        )
    ok = _lint(tmp_path)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    scene = tmp_path / "rodval" / "core" / "scene.py"
    scene.write_text(scene.read_text() + "\nimport rodval.report.figures  # reversed\n")
    broken = _lint(tmp_path)
    assert broken.returncode != 0
    assert (
        "BROKEN" in broken.stdout and "rodval.core.scene -> rodval.report.figures" in broken.stdout
    )


def test_no_import_cycles():
    graph = grimp.build_graph("rodval", "reference_models", cache_dir=None)
    modules = sorted(graph.modules)
    index = {m: i for i, m in enumerate(modules)}
    edges = {
        m: [d for d in graph.find_modules_directly_imported_by(m) if d in index] for m in modules
    }
    # Tarjan's strongly connected components: a component of two or more modules is a cycle.
    counter, stack, on_stack, low, num, cycles = [0], [], set(), {}, {}, []

    def visit(v):
        num[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in edges[v]:
            if w not in num:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], num[w])
        if low[v] == num[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    sys.setrecursionlimit(10_000)
    for m in modules:
        if m not in num:
            visit(m)
    assert not cycles, cycles
