"""The ``gimwatch`` command line: parse, call the library, print.

This package is the only place that prints or exits. Each subcommand lives in its own
module with ``add_arguments(parser)`` and ``run(args) -> int``; :data:`COMMANDS` lists
them. Errors gimwatch raises on purpose become one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence
from types import ModuleType

from gimwatch._version import __version__
from gimwatch.errors import GimwatchError

__all__ = ["get_argument_parser", "main"]

EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


class UsageError(GimwatchError):
    """A command line argparse rejected."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, no usage dump
        raise UsageError(f"{self.prog}: {message}")


def _commands() -> dict[str, ModuleType]:
    from gimwatch.cli import analyze, bench, chain, crosscheck, demo, simulate, stress, survey

    modules = (chain, analyze, crosscheck, simulate, survey, stress, bench, demo)
    return {module.NAME: module for module in modules}


def get_argument_parser() -> argparse.ArgumentParser:
    """The argument parser with one subparser per command."""
    parser = _Parser(
        prog="gimwatch",
        description="Watch the conditioning of a robot's generalized inertia matrix (GIM).",
    )
    parser.add_argument("--version", action="version", version=f"gimwatch {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name, module in _commands().items():
        command = sub.add_parser(name, help=module.HELP, description=module.__doc__)
        module.add_arguments(command)
        command.set_defaults(run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line and return its exit status.

    Warnings print as one ``gimwatch: warning: ...`` line each; errors gimwatch raises on
    purpose as one ``gimwatch: error: ...`` line, with exit status 2.
    """
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            _shown.clear()
            return _run(argv)
    except GimwatchError as exc:
        print(f"gimwatch: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("gimwatch: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


_shown: set[str] = set()


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Print a warning as one line on stderr (no source location: users did not write it).

    The same text is printed once per run: the URDF checks run again when DeNOC reads the
    file that Pinocchio read.
    """
    text = f"gimwatch: warning: {message}"
    if text not in _shown:
        _shown.add(text)
        print(text, file=sys.stderr)


def _run(argv: Sequence[str] | None) -> int:
    from threadpoolctl import threadpool_limits

    args = get_argument_parser().parse_args(argv)
    # GIMs are small dense matrices: multi-threaded OpenBLAS makes their eigen-solves
    # 20-40x slower on 2 cores, so the command line keeps BLAS on one thread.
    with threadpool_limits(limits=1, user_api="blas"):
        return int(args.run(args))


def _entry_point() -> None:  # console script
    sys.exit(main())
