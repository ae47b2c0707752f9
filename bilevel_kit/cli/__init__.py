"""Command-line interface: ``bilevel-kit solve | compare | simulate | ... | methods``.

Each command is a module with ``HELP`` (its line in ``bilevel-kit --help``), ``DESCRIPTION`` (its
``--help`` text), ``add_arguments(parser)`` and ``run(args) -> int`` that reads its inputs, calls
the library and prints or writes the result. Exit codes: 0 ok, 1 the solution is
invalid, 2 bad input or usage (a one-line message on stderr, no traceback), 3 a definite answer
could not be reached within the time limit, 4 ``pack`` found no layout on a grid that is not
exact (not a proof), 5 a sweep finished but some of its cells failed (docs/cluster.md), 130
interrupted (Ctrl-C; a sweep keeps its finished cells). Every output path is checked before any
work (:mod:`bilevel_kit.paths`). Heavy back-ends are imported inside the commands, so
``bilevel-kit --help`` stays fast.
"""

from __future__ import annotations

import argparse
import functools
import sys
from collections.abc import Callable, Sequence
from typing import Protocol

from ..interrupt import (
    checkpoint,
    exit_now,
    forget_unhandled_interrupt,
    report,
    signal_guard,
)
from . import (
    bench,
    check,
    compare,
    execute,
    generate,
    methods,
    pack,
    reach,
    repro,
    schema,
    simulate,
    solve,
)
from .common import (
    EXIT_CODES,
    EXIT_INTERRUPTED,
    EXIT_INVALID,
    EXIT_OK,
    EXIT_UNKNOWN,
    EXIT_USAGE,
    Parser,
    options_epilog,
    run_command,
)

__all__ = [
    "COMMANDS",
    "EXIT_CODES",
    "EXIT_INVALID",
    "EXIT_OK",
    "EXIT_UNKNOWN",
    "EXIT_USAGE",
    "build_parser",
    "main",
]


class Command(Protocol):
    """What a command module provides."""

    @property
    def HELP(self) -> str: ...  # noqa: N802 (a module constant)

    @property
    def DESCRIPTION(self) -> str | None: ...  # noqa: N802

    def add_arguments(self, p: argparse.ArgumentParser) -> None: ...

    def run(self, args: argparse.Namespace) -> int: ...


#: Command name -> its module, in the order ``--help`` lists them.
COMMANDS: dict[str, Command] = {
    "solve": solve,
    "compare": compare,
    "bench": bench,
    "simulate": simulate,
    "repro": repro,
    "pack": pack,
    "reach": reach,
    "execute": execute,
    "generate": generate,
    "check": check,
    "schema": schema,
    "methods": methods,
}


def _param_epilog(command: Command) -> Callable[[], str] | None:
    """The ``-p`` keys of every method (policy) after a command's help, built only when the
    help is printed (``PARAM_USAGE``/``PARAM_POLICIES`` of the command module)."""
    usage = getattr(command, "PARAM_USAGE", None)
    if usage is None:
        return None
    return functools.partial(options_epilog, usage, getattr(command, "PARAM_POLICIES", False))


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__
    from ..methods import REGISTRY

    listing = "\n".join(f"  {s.name:<16} {s.summary}" for s in REGISTRY.values())
    parser = Parser(
        prog="bilevel-kit",
        description="Just-in-time robotic kitting: solve, compare and check kitting plans.",
        epilog="exit codes:\n"
        + "\n".join(f"  {code:<4} {meaning}" for code, meaning in EXIT_CODES.items())
        + "\n\nmethods:\n"
        + listing,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--version",
        action="version",
        version=f"bilevel-kit {__version__}",
        help="print the version",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for name, command in COMMANDS.items():
        p = sub.add_parser(
            name,
            help=command.HELP,
            description=command.DESCRIPTION,
            lazy_epilog=_param_epilog(command),
        )
        command.add_arguments(p)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """The command line; ``argv`` None: ``sys.argv`` (the process is this command, so after a
    signal the guard's deadline also covers the interpreter's exit)."""
    try:
        with signal_guard(linger=argv is None):  # Ctrl-C and SIGTERM at any moment
            try:
                code = _parse_and_run(argv)
            except Exception:
                checkpoint()  # a signal's exception turned into another one: interrupted
                raise
            if code != EXIT_INTERRUPTED:
                checkpoint()  # a signal's exception lost on its way up: still interrupted
    except KeyboardInterrupt as exc:  # while starting, before the command runs, or lost
        report(exc, sys.stderr)
        code = EXIT_INTERRUPTED
    if code == EXIT_INTERRUPTED:
        forget_unhandled_interrupt()
        if argv is None:  # the process is this command: it ends now (exit_now)
            exit_now(code)
    return code


def _parse_and_run(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, or a usage error already printed on one line
        return int(exc.code or 0)
    return run_command(args.command, COMMANDS[args.command].run, args)
