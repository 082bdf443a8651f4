"""A light front door (issue 38): ``import rodval``, ``rodval --help`` and ``rodval --version``
import none of numba, scipy, pandas (nor numpy, matplotlib); the public API resolves on first
use; a subcommand's modules are imported only when it runs; numba's cache of rodval's kernels
is still keyed by rodval's sources (rodval/core/jit_cache.py) before any kernel is decorated.
Timings are the benchmark's (benchmarks/startup.py), not these tests'."""

import json
import subprocess
import sys
import textwrap

import pytest

import rodval
from rodval.cli import COMMANDS, SUMMARIES, build_parser, command_of, main

HEAVY = ("numba", "scipy", "pandas", "numpy", "matplotlib")

LOADED = textwrap.dedent(
    """
    import json, sys
    {code}
    print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in {heavy!r}
                            or m.startswith("rodval.") or m == "rodval")))
    """
)


def _modules(code: str) -> list[str]:
    """The heavy packages' and rodval's modules a fresh interpreter holds after ``code``."""
    out = subprocess.run(
        [sys.executable, "-c", LOADED.format(code=code, heavy=HEAVY)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    return json.loads(out.stdout.splitlines()[-1])


def _heavy(modules: list[str]) -> list[str]:
    return [m for m in modules if m.split(".")[0] in HEAVY]


def test_import_rodval_imports_no_heavy_package():
    modules = _modules("import rodval")
    assert _heavy(modules) == []
    assert modules == ["rodval"]


@pytest.mark.parametrize("argv", [["--version"], ["--help"], [], ["bogus"]])
def test_version_and_help_import_no_heavy_package_nor_any_subcommand(argv):
    code = textwrap.dedent(
        f"""
        import contextlib, io
        from rodval.cli import main
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            try:
                main({argv!r})
            except SystemExit:
                pass
        """
    )
    modules = _modules(code)
    assert _heavy(modules) == []
    assert [m for m in modules if m.startswith("rodval.cli.")] == []


@pytest.mark.parametrize("command", ["compare", "reproduce", "report"])
def test_a_light_subcommand_help_imports_its_module_only(command):
    code = textwrap.dedent(
        f"""
        import contextlib, io
        from rodval.cli import main
        with contextlib.redirect_stdout(io.StringIO()):
            try:
                main([{command!r}, "--help"])
            except SystemExit:
                pass
        """
    )
    modules = _modules(code)
    assert _heavy(modules) == []
    assert f"rodval.cli.{command}" in modules
    others = {f"rodval.cli.{c}" for c in COMMANDS} - {f"rodval.cli.{command}"}
    assert others.isdisjoint(modules)


def test_the_top_level_help_is_the_same_whichever_subcommand_is_registered():
    """The summary lines rodval.cli lists without importing a subcommand are the ``help``
    its ``register`` gives."""
    light = build_parser(()).format_help()
    for name in COMMANDS:
        assert build_parser((name,)).format_help() == light, name
    assert build_parser().format_help() == light
    assert set(SUMMARIES) == set(COMMANDS)


def test_the_command_is_found_as_argparse_finds_it():
    assert command_of(["simulate", "paper", "--out", "x"]) == "simulate"
    assert command_of(["--version"]) is None
    assert command_of(["-h", "study", "f"]) == "study"
    assert command_of(["--", "compare", "a"]) == "compare"
    assert command_of(["bogus", "simulate"]) is None
    assert command_of(["-1", "simulate"]) is None
    assert command_of([]) is None


def test_a_subcommand_still_parses_all_its_options(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "paper", "--model", "nope", "--out", "x"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "argument --model: invalid choice: 'nope'" in err


def test_the_public_api_resolves_lazily():
    code = textwrap.dedent(
        """
        import rodval
        assert "simulate" not in vars(rodval)
        from rodval import simulate
        from rodval.models.registry import simulate as real
        assert simulate is real and rodval.simulate is real
        """
    )
    assert "rodval.models.registry" in _modules(code)


def test_every_public_name_is_its_module_object_and_listed():
    from rodval import _LAZY

    assert set(rodval.__all__) == {*_LAZY, "__version__"}
    names = dir(rodval)
    for name, (module, attr) in _LAZY.items():
        assert name in names
        value = getattr(rodval, name)
        assert value is getattr(sys.modules[module], attr), name
    assert rodval.Study.__name__ == "StudySpec"
    assert rodval.compare.__name__ == "discrepancies"
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        rodval.nope  # noqa: B018
    with pytest.raises(ImportError):
        exec("from rodval import nope", {})


KEYED = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    {first}
    import rodval.core.load_table as loads
    from numba.core.registry import CPUDispatcher
    from rodval.core import jit_cache
    stamps = [
        f._cache._cache_file._source_stamp
        for f in vars(loads).values()
        if isinstance(f, CPUDispatcher) and hasattr(f._cache, "_cache_file")
    ]
    assert stamps, "no cached kernel in rodval.core.load_table"
    digest = jit_cache.closure_digest(Path(loads.__file__).resolve())
    assert all(s == ("sources", digest) for s in stamps), stamps
    print("keyed", len(stamps))
    """
)


@pytest.mark.parametrize("first", ["", "import numba", "import rodval"])
def test_kernels_are_keyed_by_rodval_sources_whatever_imports_numba_first(first):
    """numba reads a kernel's stamp when ``@njit(cache=True)`` decorates it: each cached
    kernel of a module imported directly (no ``import rodval.core.jit_cache``) carries the
    digest of rodval's sources, whether numba comes before rodval or through it."""
    out = subprocess.run(
        [sys.executable, "-c", KEYED.format(first=first)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("keyed")
