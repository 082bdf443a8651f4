"""numba's cache of a kernel follows every source it depends on (rodval/core/jit_cache.py).

numba keys a cached function by its own file only; a cached caller keeps the machine code of a
callee in another module after that module changed (measured in rodval: a stale benchmark loop
hung after the kernels' module changed). Here a two-module package is compiled and cached in
one process, the callee's module is edited, and a second process must run the new callee.
"""

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


def _run(root: Path) -> str:
    env_path = f"{root}:{Path(rodval.__file__).resolve().parents[1]}"
    out = subprocess.run(
        [sys.executable, "-c", RUN, str(root)],
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": env_path, "OMP_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"},
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


def test_rodval_installs_it_for_its_own_kernels():
    assert jit_cache.INSTALLED
    root = str(jit_cache.PACKAGE_ROOT) + "/"
    assert root in jit_cache._DIGESTS
    assert jit_cache._DIGESTS[root] == jit_cache.source_digest()
