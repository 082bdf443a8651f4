"""The ``rodval`` command. Each subcommand lives in its own module exposing
``register(subparsers)``; bad options exit with status 2 and a one-line message."""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
import time
import traceback
import warnings
from collections.abc import Collection, Sequence
from typing import Any, NoReturn

#: Each subcommand (its module) in the order ``rodval --help`` lists them, and its line there,
#: the ``help`` its module's ``register`` gives (tests/test_startup.py checks they agree):
#: ``rodval --help`` and ``--version`` list the subcommands without importing their modules,
#: whose options name constants of the heavy modules (the registry's model names, the
#: study's limits, the animation's).
SUMMARIES = {
    "reproduce": "reproduce the paper's example (Table 1, Fig. 3, cross-check)",
    "simulate": "run one scene with one model",
    "reference": "refine the exudyn reference until it converges, with its error bar",
    "compare": "compare two runs of the same scene",
    "study": "run a study (grid of scenes x models) and write tables and a report",
    "report": "rebuild a study's report from its saved tables",
    "bench": "performance benchmarks (work-precision, cost vs n, ...)",
    "modes": "natural frequencies and mode shapes about a configuration",
    "animate": "animate runs (GIF or MP4)",
}
#: Subcommand modules, in the order ``rodval --help`` lists them.
COMMANDS = tuple(SUMMARIES)


#: An argument argparse reads as a value, not an option (``OneLineParser``).
NEGATIVE_NUMBER = re.compile(r"^-[\d.]")


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (no usage block), exit status 2, and which
    reads any argument that starts with '-' and a digit or '.' as a value (``--times -1,2``,
    ``--rtol -1e-3``) so that its parser can say what is allowed. Subparsers inherit it."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(full: Collection[str] = COMMANDS) -> argparse.ArgumentParser:
    """The ``rodval`` parser. The subcommands in ``full`` are registered by their modules
    (``register``: all their options); the others only by name and summary line, which is
    all ``rodval --help`` shows, so that their modules are not imported."""
    parser = OneLineParser(
        prog="rodval",
        description="Cross-validate plane rod-chain models: the paper's full and reduced\n"
        "models against each other and an independent exudyn beam model.",
        epilog="examples:\n"
        "  rodval reproduce paper --out out/paper\n"
        "  rodval simulate paper --model reduced --out out/paper-reduced\n"
        "  rodval study studies/paper.toml --out out/paper\n"
        "  rodval report out/paper\n"
        "Run `rodval COMMAND --help` for the options of a command.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    from rodval import __version__

    parser.add_argument("--version", action="version", version=f"rodval {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        if name in full:
            importlib.import_module(f"{__name__}.{name}").register(sub)
        else:
            sub.add_parser(name, help=SUMMARIES[name])
    return parser


def command_of(argv: Sequence[str]) -> str | None:
    """The subcommand ``argv`` names, as argparse finds it: its first word that is not an
    option (the top-level options take no value) or the word after ``--``, if it is one of
    ``COMMANDS``."""
    words = iter(argv)
    for word in words:
        if word == "--":
            word = next(words, "")
        elif word.startswith("-") and not NEGATIVE_NUMBER.match(word):
            continue
        return word if word in COMMANDS else None
    return None


def one_line(exc: BaseException) -> str:
    """An exception's message on one line (its lines joined by " | ")."""
    text = " | ".join(line.strip() for line in str(exc).splitlines() if line.strip())
    return text or type(exc).__name__


def _run(args: argparse.Namespace) -> int:
    """Run the subcommand. A command that writes a plain output folder (``out_folder`` set
    by its parser) is refused, before any work, one that is or holds a link, holds files
    rodval did not write or is another command's output folder, and the folder is marked
    the command's, listing its files, once the command has written into it
    (``rodval.core.out_paths``)."""
    command = getattr(args, "out_folder", None)
    if command is None:
        return int(args.func(args) or 0)
    from rodval.core.out_paths import claim_output_folder, mark_output_folder

    claim_output_folder(args.out, command=command)
    try:
        return int(args.func(args) or 0)
    finally:
        mark_output_folder(args.out, command)


def main(argv: list[str] | None = None) -> int:
    """Run a subcommand. A user error (bad option, file, value) is one line on stderr and exit
    status 2; anything unexpected is one line too, exit 2, naming the exception's type and
    message as an internal error (a bug to report, never hidden); no traceback is printed
    (``RODVAL_TRACEBACK=1`` prints it for debugging). Numerical RuntimeWarnings (overflow in
    a diverging run) are not printed: the run's status reports how it ended.

    ``args.started`` (``time.perf_counter`` clock) is when the command started, from which
    its wall-clock budget counts: the process start for the ``rodval`` command itself (argv
    None: its interpreter start-up and imports are the command's), the call otherwise (a
    host process that calls ``main`` has its own age)."""
    started = time.perf_counter()
    if argv is None:
        from rodval.core.clock import process_age_s

        argv, started = sys.argv[1:], started - process_age_s()
    command = command_of(argv)
    parser = build_parser(full=() if command is None else (command,))
    args = parser.parse_args(argv)
    args.started = started
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return _run(args)
    except (CliError, ValueError, OSError) as exc:
        print(f"rodval {args.command}: error: {one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"rodval {args.command}: interrupted", file=sys.stderr)
        return 130
    except MemoryError:
        print(
            f"rodval {args.command}: error: out of memory (ask for fewer output times, "
            "quantities or rods)",
            file=sys.stderr,
        )
        return 2
    except Exception as exc:  # noqa: BLE001 - one line, never a traceback, never hidden
        if os.environ.get("RODVAL_TRACEBACK"):
            traceback.print_exc()
        print(
            f"rodval {args.command}: internal error: {type(exc).__name__}: {one_line(exc)} "
            "(a bug in rodval: please report it with the command; RODVAL_TRACEBACK=1 shows "
            "where)",
            file=sys.stderr,
        )
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
