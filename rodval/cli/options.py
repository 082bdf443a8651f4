"""Option parsers shared by subcommands: each rejects bad values with a message naming them."""

from __future__ import annotations

import argparse
import math
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rodval.core.scene_keys import scene_path
from rodval.core.settings import (
    COUNT_RANGE,
    DEFAULTS,
    MAX_COUNT,
    METHODS,
    MIN_RTOL,
    RTOL_RANGE,
    SETTING_NAMES,
    IntegratorSettings,
)


def positive_float(
    name: str,
    *,
    finite: bool = True,
    below: float = math.inf,
    least: float = 0.0,
    allowed: str | None = None,
) -> Callable[[str], float]:
    """Parser of a number > 0, >= ``least`` and < ``below`` for option ``name``; finite unless
    ``finite=False``. ``allowed`` words the range in messages (default: from the bounds)."""
    if allowed is None:
        allowed = "a finite number > 0" if finite else "a number > 0 (inf allowed)"
        if below < math.inf:
            allowed = f"a number in (0, {below:g})"

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be {allowed}, got {text!r}") from None
        inside = v < below or v == below == math.inf  # "inf allowed" when not finite
        if not (0 < v and inside and v >= least) or (finite and math.isinf(v)):
            raise argparse.ArgumentTypeError(f"{name} must be {allowed}, got {text!r}")
        return v

    return parse


def positive_int(name: str) -> Callable[[str], int]:
    """A parser of an integer count (``COUNT_RANGE``) for option ``name``."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            v = 0
        if not 1 <= v <= MAX_COUNT:
            raise argparse.ArgumentTypeError(f"{name} must be {COUNT_RANGE}, got {text!r}")
        return v

    return parse


def time_list(text: str) -> list[float]:
    """--times t1,t2,...: seconds, finite, >= 0, strictly increasing; no empty item."""
    items = [t.strip() for t in text.split(",")]
    if not any(items):
        raise argparse.ArgumentTypeError("--times must list at least one time")
    if not all(items):
        raise argparse.ArgumentTypeError(
            f"--times must be comma-separated seconds like 0.5,1,2 with no empty item, got {text!r}"
        )
    try:
        values = [float(t) for t in items]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--times must be comma-separated seconds like 0.5,1,2, got {text!r}"
        ) from None
    if any(v < 0 or not math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"--times must be finite and >= 0 s, got {text!r}")
    if any(b <= a for a, b in zip(values, values[1:])):
        raise argparse.ArgumentTypeError(f"--times must be strictly increasing, got {text!r}")
    return values


#: The integrator settings that have a flag of their own (``add_integrator_options``):
#: setting name -> flag. Every setting (``SETTING_NAMES``) is also ``--set NAME=VALUE``.
SETTING_FLAGS = {
    "method": "--method",
    "rtol": "--rtol",
    "atol": "--atol",
    "max_step": "--max-step",
    "max_evaluations": "--max-evaluations",
    "max_wall_s": "--max-wall",
}
#: The openings of a TOML string, array or table: a ``--set`` VALUE that starts with one
#: must be that whole TOML value; a VALUE that is no TOML value is otherwise taken as text
#: when it is one line (a bare word: ``kinematics=exact``, ``method=Radau-numba``).
TOML_OPENERS = ('"', "'", "[", "{")


def set_value(key: str, raw: str) -> object:
    """The VALUE of ``--set KEY=VALUE`` (scene value, model option or integrator setting):
    exactly one TOML value (``2e8``, ``[1, 2]``, ``true``, ``{ ratio = 0.01 }``,
    ``"auto"``), or the text itself when it is a bare word (``kinematics=exact``); what it
    sets checks it like the file's. ArgumentTypeError naming ``--set KEY`` for anything else:
    more than one TOML value (``2e8`` and a newline with more TOML), a string, array or
    table left open, text over several lines, or nothing."""
    if not raw:
        raise argparse.ArgumentTypeError(_not_one_value(key, raw, "empty"))
    try:
        doc = tomllib.loads(f"value = {raw}")
    except tomllib.TOMLDecodeError as exc:
        if "\n" in raw or "\r" in raw or raw.startswith(TOML_OPENERS):
            raise argparse.ArgumentTypeError(_not_one_value(key, raw, str(exc))) from None
        return raw
    if set(doc) != {"value"}:
        raise argparse.ArgumentTypeError(_not_one_value(key, raw, "more than one value"))
    return doc["value"]


def _not_one_value(key: str, raw: str, why: str) -> str:
    """The one-line message of a --set VALUE that is not one TOML value."""
    return (
        f"--set {key}: VALUE must be one TOML value (2e8, [1, 2], true, {{ ratio = 0.01 }}, "
        f'"text") or a bare word, got {raw!r} ({why})'
    )


def key_value(text: str) -> tuple[str, object]:
    """KEY=VALUE: a scene key's dotted path (``scene_path``: ``chain.EI=2e8``), a model
    option or an integrator setting (``SETTING_NAMES``), with its VALUE read by
    ``set_value``."""
    key, equals, raw = text.partition("=")
    if not equals or not key.strip():
        raise argparse.ArgumentTypeError(f"--set expects KEY=VALUE, got {text!r}")
    return key.strip(), set_value(key.strip(), raw.strip())


def add_integrator_options(p: argparse.ArgumentParser) -> None:
    """--method, --rtol, --atol, --max-step, --max-evaluations, --max-wall (``SETTING_FLAGS``),
    each None when not given (``integrator_settings``); their defaults are
    ``rodval.core.settings.DEFAULTS`` (the same as the Python API and study files)."""
    d = DEFAULTS
    p.add_argument(
        "--method",
        choices=METHODS,
        help="auto (default: the compiled DOP853 where the model and scene have a "
        "compiled form, going on with the compiled Radau IIA when stiffness limits its "
        "steps; scipy's DOP853 otherwise), a scipy solve_ivp method, or DOP853-numba / "
        "Radau-numba (native models)",
    )
    for flag, parse, what in (
        (
            "--rtol",
            positive_float("--rtol", below=1.0, least=MIN_RTOL, allowed=RTOL_RANGE),
            f"relative tolerance: {RTOL_RANGE} (default {d['rtol']:g})",
        ),
        ("--atol", positive_float("--atol"), f"absolute tolerance > 0 (default {d['atol']:g})"),
        (
            "--max-step",
            positive_float("--max-step", finite=False),
            "largest step, s (default unbounded)",
        ),
        (
            "--max-evaluations",
            positive_int("--max-evaluations"),
            f"right-hand-side evaluations a run may use (default {d['max_evaluations']})",
        ),
        (
            "--max-wall",
            positive_float("--max-wall", finite=False),
            "wall-clock seconds a run may use (default: no limit)",
        ),
    ):
        p.add_argument(flag, type=parse, help=what)


def integrator_settings(args: argparse.Namespace) -> dict[str, object]:
    """The integrator settings given on the command line: the flags given
    (``SETTING_FLAGS``; one given at its default value too) and ``--set NAME=VALUE`` of any
    setting (``SETTING_NAMES``: ``error_control``, ``first_step``, ...), checked by
    ``IntegratorSettings`` like a study file's [integrator]. A setting given both by its flag
    and by --set is refused (ValueError naming both), never one of them winning silently, and
    so is a --set value its setting refuses (ValueError naming ``--set NAME``)."""
    given: dict[str, object] = {}
    for name, flag in SETTING_FLAGS.items():
        value = getattr(args, flag.removeprefix("--").replace("-", "_"))
        if value is not None:
            given[name] = value
    for name, value in set_options(args.options).items():
        if name in SETTING_NAMES:
            if name in given:
                raise ValueError(
                    f"--set {name}={value!r} and {SETTING_FLAGS[name]} {given[name]!r} both "
                    f"given; give {name} once"
                )
            try:
                IntegratorSettings().with_(**{name: value})  # its check, as [integrator]'s
            except ValueError as exc:
                raise ValueError(f"--set {name}: {exc}") from None
            given[name] = value
    return given


def add_model_options(
    p: argparse.ArgumentParser, *, coefficients_default: str | None, settings: bool = True
) -> None:
    """--coefficients (the native models' variant) and --set KEY=VALUE (a model option, a
    scene value or, with ``settings``, an integrator setting)."""
    p.add_argument(
        "--coefficients",
        choices=("printed", "published"),
        default=coefficients_default,
        help="coefficient variant of the native models (default printed)",
    )
    setting = ", an integrator setting, e.g. error_control=per-block" if settings else ""
    add_set_option(
        p,
        "a model option, e.g. elements=8 for exudyn, a scene value by its dotted "
        f"key, e.g. chain.EI=2e8 or latches.*.angle=0.4{setting}; the keys: "
        "docs/scene_file.md",
    )


def add_set_option(p: argparse.ArgumentParser, what: str) -> None:
    """--set KEY=VALUE (repeatable, ``key_value``; the pairs in ``args.options``), ``what``
    saying what KEY may be."""
    p.add_argument(
        "--set",
        dest="options",
        type=key_value,
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help=f"{what} (VALUE: one TOML value or a bare word, checked like the file's; repeatable)",
    )


def set_options(pairs: list[tuple[str, object]]) -> dict[str, object]:
    """The ``--set KEY=VALUE`` pairs as a dict; a key given twice is refused (ValueError), never
    one of its values winning silently."""
    out: dict[str, object] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(
                f"--set {key} given twice ({key}={out[key]!r} and {key}={value!r}); give it once"
            )
        out[key] = value
    return out


def model_options(args: argparse.Namespace) -> dict[str, object]:
    """The model options of ``add_model_options``: the --set pairs that are neither a scene
    value (``scene_overrides``) nor an integrator setting (``integrator_settings``), and
    --coefficients (when given); --coefficients together with --set coefficients=... is
    refused (ValueError)."""
    options = {
        k: v
        for k, v in set_options(args.options).items()
        if scene_path(k) is None and k not in SETTING_NAMES
    }
    if args.coefficients is not None:
        if "coefficients" in options:
            raise ValueError(
                f"--coefficients {args.coefficients} and --set coefficients="
                f"{options['coefficients']} conflict: give the coefficient variant once"
            )
        options["coefficients"] = args.coefficients
    return options


def scene_overrides(args: argparse.Namespace) -> dict[str, object]:
    """The scene values of ``--set PATH=VALUE`` (path -> value, ``scene.`` dropped), a path
    given twice refused (``set_options``)."""
    paths = {k: scene_path(k) for k, _ in args.options}
    out: dict[str, object] = {}
    for key, value in set_options(args.options).items():
        path = paths[key]
        if path is not None:
            if path in out:
                raise ValueError(f"--set {path} given twice (as {key} and {path}); give it once")
            out[path] = value
    return out


def with_scene_values(doc: dict[str, Any], args: argparse.Namespace) -> tuple[dict[str, Any], str]:
    """The scene document ``doc`` (of SCENE, ``args.scene``) with the scene values of ``--set
    PATH=VALUE`` set (``scene_overrides``, ``with_overrides``: a study grid's paths), and the
    name its errors go by: SCENE, with the --set keys. ``doc`` is not changed. --set t_end
    beside --t-end, or times beside --times, is refused: one value each."""
    from rodval.core.scene_file import with_overrides

    overrides = scene_overrides(args)
    for path in ("t_end", "times"):
        if path in overrides and getattr(args, path, None) is not None:
            flag = "--" + path.replace("_", "-")
            raise ValueError(f"--set {path} and {flag} both given; give the value once")
    if not overrides:
        return doc, str(args.scene)
    return with_overrides(doc, overrides), f"{args.scene} (with --set {', '.join(overrides)})"


def add_junit_option(p: argparse.ArgumentParser) -> None:
    """--junit FILE (rodval study, rodval report)."""
    p.add_argument(
        "--junit",
        type=Path,
        metavar="FILE",
        help="write a JUnit XML report of the study's [acceptance] checks (one test case per "
        "case, model pair and quantity) for CI systems",
    )


def check_junit(junit: Path | None, out: Path, inputs: tuple[Path, ...] = ()) -> Path | None:
    """The --junit file, checked before any work (``check_output_file``): writable, none of
    the command's ``inputs``, none of the study's own files in ``out``, and, if it exists, a
    JUnit report rodval wrote."""
    if junit is None:
        return None
    from rodval.core.out_paths import check_output_file
    from rodval.report.acceptance import is_junit_report
    from rodval.study.store import StudyStore

    return check_output_file(
        junit,
        "--junit",
        protected=inputs,
        reserved=StudyStore(out).reserved,
        ours=is_junit_report,
    )


def acceptance_exit(out: Path, junit: Path | None) -> int:
    """Print one line per breach of the study's [acceptance] in ``out`` (writing the JUnit
    file when asked); exit code 1 when any bound broke, else 0."""
    from rodval.report.acceptance import gate

    broken = gate(out, junit)
    for line in broken:
        print(line)
    return 1 if broken else 0
