"""numba's cache of a kernel follows every source it depends on (rodval/core/jit_cache.py).

numba keys a cached function by its own file only; a cached caller keeps the machine code of a
callee in another module after that module changed (measured in rodval: a stale benchmark loop
hung after the kernels' module changed). Here a two-module package is compiled and cached in
one process, the callee's module is edited, and a second process must run the new callee.
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import rodval
from rodval.core import jit_cache

CALLEE = "from numba import njit\n\n\n@njit(cache=True)\ndef value():\n    return {}\n"
CALLER = textwrap.dedent(
    """
    from numba import njit

    from kernels.callee import value


    @njit(cache=True)
    def twice():
        return 2 * value()
    """
)
RUN = textwrap.dedent(
    """
    import sys
    from pathlib import Path

    from rodval.core import jit_cache

    assert jit_cache.install(Path(sys.argv[1]) / "kernels")
    from kernels.caller import twice

    print(twice())
    """
)


def _run(root: Path, code: str = RUN, bytecode: bool = False) -> str:
    """``code`` run by a fresh Python with ``root`` (holding the package ``kernels``) and
    rodval importable; its stdout. Without ``bytecode`` Python writes no compiled copies
    (``.pyc``): it checks them by whole-second modification time and size, so a same-size edit
    in the second of the first run would run the old code (this test failed about half its
    runs that way)."""
    env = {"PYTHONPATH": f"{root}:{Path(rodval.__file__).resolve().parents[1]}"}
    env.update(OMP_NUM_THREADS="1", PATH="/usr/bin:/bin")
    if not bytecode:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    out = subprocess.run(
        [sys.executable, "-c", code, str(root)],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        check=True,
    )
    return out.stdout.strip()


def test_a_cached_kernel_runs_the_new_code_of_a_callee_in_another_module(tmp_path):
    pkg = tmp_path / "kernels"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "callee.py").write_text(CALLEE.format(1))
    (pkg / "caller.py").write_text(CALLER)
    assert _run(tmp_path) == "2"
    assert list(pkg.glob("__pycache__/caller.twice-*.nbi"))  # cached by the first process
    (pkg / "callee.py").write_text(CALLEE.format(5))
    assert _run(tmp_path) == "10"


def _set_mtime(path: Path, seconds: float) -> None:
    """Give ``path`` the modification time ``seconds`` (explicit: no dependence on the clock)."""
    ns = int(seconds * 1e9)
    os.utime(path, ns=(ns, ns))


def test_a_kernel_compiled_from_stale_bytecode_is_not_served_after_python_recompiles(tmp_path):
    """A same-size edit in the second Python wrote the callee's ``.pyc`` (stamps set
    explicitly): Python loads the old bytecode (its own rule: whole-second mtime and size), so
    that run computes 2. Once the source is touched Python compiles it again, and the kernels
    must run the new callee (10), not the machine code compiled from the stale copy, which a
    key of the sources' contents alone served again."""
    pkg = tmp_path / "kernels"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "caller.py").write_text(CALLER)
    callee = pkg / "callee.py"
    callee.write_text(CALLEE.format(1))
    second = 1_700_000_000
    _set_mtime(callee, second + 0.1)
    assert _run(tmp_path, bytecode=True) == "2"
    (pyc,) = pkg.glob("__pycache__/callee.*.pyc")
    _set_mtime(pyc, second + 0.2)  # the copy written at 0.2 s
    callee.write_text(CALLEE.format(5))  # same size
    _set_mtime(callee, second + 0.6)  # edited at 0.6 s, the same second
    assert _run(tmp_path, bytecode=True) == "2"  # Python's stale copy (not rodval's doing)
    _set_mtime(callee, second + 5.0)  # touched: Python compiles the source again
    assert _run(tmp_path, bytecode=True) == "10"


def test_rodval_installs_it_for_its_own_kernels():
    assert jit_cache.INSTALLED
    assert str(jit_cache.PACKAGE_ROOT) + "/" in jit_cache._ROOTS
    kernels = jit_cache.PACKAGE_ROOT / "models" / "assembly" / "kernels.py"
    closure = {
        p.relative_to(jit_cache.PACKAGE_ROOT).as_posix() for p in jit_cache.import_closure(kernels)
    }
    # the full model's kernels reach the load kernels they call, not the CLI
    assert {"models/assembly/kernels.py", "core/load_table.py"} <= closure
    assert not any(p.startswith(("cli/", "report/", "study/")) for p in closure)


MODULES = {
    "a.py": "from numba import njit\n\n\n@njit(cache=True)\ndef value():\n    return {a}\n",
    "b.py": "from numba import njit\n\n\n@njit(cache=True)\ndef value():\n    return 3\n",
    "use_a.py": "from numba import njit\n\nfrom kernels import a\n\n\n"
    "@njit(cache=True)\ndef twice():\n    return 2 * a.value()\n",
    "use_b.py": "from numba import njit\n\nfrom kernels.b import value\n\n\n"
    "@njit(cache=True)\ndef twice():\n    return 2 * value()\n",
    "loop.py": "from numba import njit\n\n\n@njit(cache=True)\ndef call(f):\n    return f() + 1\n",
}
COUNT = textwrap.dedent(
    """
    import json, sys
    from pathlib import Path

    from rodval.core import jit_cache

    assert jit_cache.install(Path(sys.argv[1]) / "kernels")
    from kernels import a, b, loop, use_a, use_b

    values = [use_a.twice(), use_b.twice(), loop.call(use_a.twice), loop.call(use_b.twice)]
    counts = {}
    for name, mod in (("a", a), ("b", b), ("use_a", use_a), ("use_b", use_b)):
        f = mod.value if name in "ab" else mod.twice
        counts[name] = sum(f.stats.cache_misses.values())
    print(json.dumps({"values": values, "compiled": counts}))
    """
)


def test_an_edit_recompiles_only_the_kernels_that_reach_the_edited_file(tmp_path):
    """Per-kernel keys: after ``a.py`` changes, a second process compiles again only what
    reaches it by imports (``a``, ``use_a``); ``b`` and ``use_b`` load from the cache. ``loop``
    takes a kernel as an argument: numba compiles such a specialization in every process, and
    it runs the new ``a`` (11)."""
    pkg = tmp_path / "kernels"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    for name, text in MODULES.items():
        (pkg / name).write_text(text.format(a=1) if name == "a.py" else text)

    def run() -> dict:
        return json.loads(_run(tmp_path, COUNT))

    first = run()
    assert first["values"] == [2, 6, 3, 7]
    assert all(n == 1 for n in first["compiled"].values()), first
    (pkg / "a.py").write_text(MODULES["a.py"].format(a=5))
    second = run()
    assert second["values"] == [10, 6, 11, 7]
    assert second["compiled"] == {"a": 1, "b": 0, "use_a": 1, "use_b": 0}, second


def _ast_imports(path: Path, root: Path) -> set[Path]:
    """An independent reading of the rodval modules ``path`` imports: Python's own parser."""
    import ast

    here = path.relative_to(root).parts[:-1]
    found = set()

    def add(parts):
        base = root.joinpath(*parts)
        for cand in (base.with_suffix(".py"), base / "__init__.py") if parts else ():
            if cand.is_file():
                found.add(cand)
                break

    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == root.name:
                    add(tuple(a.name.split(".")[1:]))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                target = here[: len(here) - node.level + 1] + tuple(filter(None, [node.module]))
            elif (node.module or "").split(".")[0] == root.name:
                target = tuple(node.module.split(".")[1:])
            else:
                continue
            add(target)
            for a in node.names:
                add((*target, a.name))
    found.discard(path)
    return found


def test_the_import_scanner_reads_every_module_as_pythons_parser_does():
    """The cache key's dependencies come from a regular expression (fast at start-up); on
    every rodval module it must find each rodval module Python's parser finds (a missed one
    would let a kernel run a stale callee) and may only add ones named in strings."""
    root = jit_cache.PACKAGE_ROOT
    for path in sorted(root.rglob("*.py")):
        path = path.resolve()
        expected = _ast_imports(path, root)
        found = set(jit_cache._imports(path, root))
        assert expected <= found, (path, expected - found)
