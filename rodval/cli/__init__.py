"""The ``rodval`` command. Each subcommand lives in its own module exposing
``register(subparsers)``; bad options exit with status 2 and a one-line message."""

from __future__ import annotations

import argparse
import importlib
import re
import sys

#: Subcommand modules, in the order ``rodval --help`` lists them.
COMMANDS = ("reproduce", "simulate", "compare", "study", "report", "bench", "modes")


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (no usage block), exit status 2, and which
    reads any argument that starts with '-' and a digit or '.' as a value (``--times -1,2``,
    ``--rtol -1e-3``) so that its parser can say what is allowed. Subparsers inherit it."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-[\d.]")

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
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
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (CliError, ValueError, OSError) as exc:
        print(f"rodval {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
