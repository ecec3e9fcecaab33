"""The ``gimwatch`` command line: parse, call the library, print.

This package is the only place that prints or exits. Each subcommand lives in its own
module with ``NAME``, ``add_arguments(parser)`` and ``run(args) -> int`` (its docstring is
the command's description); `COMMANDS` maps each name to its module and its one-line help.
Only the module of the command being run is imported (a command's imports cost nothing to
the others, nor to ``gimwatch --help``). Errors gimwatch raises on purpose become one line
on stderr and exit status 2; a mistyped command gets a suggestion. SIGINT and SIGTERM end a
command with one line and exit status 130 or 143 (`gimwatch.cli._signals`).
"""

from __future__ import annotations

import argparse
import re
import sys
import warnings
from collections.abc import Sequence
from importlib import import_module  # bound now: tests may patch importlib
from types import ModuleType
from typing import NoReturn

from gimwatch._version import __version__
from gimwatch.cli._pipe import QuietPipe, discard_stdout
from gimwatch.cli._signals import LATCH
from gimwatch.errors import GimwatchError, InputError
from gimwatch.suggest import did_you_mean

__all__ = ["get_argument_parser", "main"]

EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130
EXIT_TERMINATED = 143  # SIGTERM: 128 + 15, as EXIT_INTERRUPTED is 128 + SIGINT


class UsageError(GimwatchError):
    """A command line argparse rejected."""


#: Command name -> (module, one-line help): the one place a command's help is written, so
#: that listing the commands imports none of them.
COMMANDS: dict[str, tuple[str, str]] = {
    "chain": ("gimwatch.cli.chain", "write the URDF of an n-link chain of homogeneous rods"),
    "analyze": (
        "gimwatch.cli.analyze",
        "conditioning of M(q): kappa, diagonal ratio, pivot ratios, spectrum",
    ),
    "crosscheck": (
        "gimwatch.cli.crosscheck",
        "compare DeNOC with Pinocchio (crba, rnea, aba, cholesky) at random states",
    ),
    "simulate": (
        "gimwatch.cli.simulate",
        "simulate a scene (TOML) and watch the conditioning of M(q)",
    ),
    "survey": (
        "gimwatch.cli.survey",
        "does the diagonal ratio track kappa? a report over many robots and configurations",
    ),
    "stress": (
        "gimwatch.cli.stress",
        "hard cases: is M SPD, DeNOC = CRBA, q̈ within C·kappa·eps of mpmath, simulations finite",
    ),
    "bench": (
        "gimwatch.cli.bench",
        "what accuracy costs in time: tables, plots and a Markdown report",
    ),
    "demo": (
        "gimwatch.cli.demo",
        "the main job: the paper's swinging 4-, 10- and 20-link chains, watched",
    ),
    "explain": (
        "gimwatch.cli.explain",
        "why kappa is what it is: the modes of lambda_min and lambda_max, ranked sensitivities",
    ),
    "map": (
        "gimwatch.cli.map",
        "kappa and delta over a grid of two joints or along a trajectory: CSV and PNG heat map",
    ),
    "armature": (
        "gimwatch.cli.armature",
        "the least joint armature that brings kappa under a target, and what it costs",
    ),
    "stability": (
        "gimwatch.cli.stability",
        "will it explode? the largest stable timestep under the servos and integrator, and why",
    ),
    "robots": ("gimwatch.cli.robots", "list the robots gimwatch can load: name, nv, base, source"),
    "metrics": ("gimwatch.cli.metrics", "list the metrics gimwatch can compute and watch"),
}


#: A float literal as NumPy or Python prints it (``1e-05``, ``.5``, ``1.E+3``, ``inf``, ``nan``).
_NUMBER = r"(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf|infinity|nan)"
#: A word argparse must read as a value, not an option: a negative number, or a
#: comma-separated list of numbers starting with one (``-1e-05``, ``-inf``, ``-1,2``).
NEGATIVE_NUMBER = re.compile(rf"^-{_NUMBER}(?:,[+-]?{_NUMBER})*$", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        # Python 3.11's argparse reads only -1 and -1.5 as numbers: '-1e-05', the way NumPy
        # prints a small negative qpos, was taken for an unknown option.
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:  # one line, no usage dump
        if self.prog == "gimwatch" and "required: command" in message:  # `gimwatch` alone
            message = f"no command given (commands: {', '.join(COMMANDS)})"
        raise UsageError(f"{self.prog}: {message}; `{self.prog} --help` says more")


class HelpFormatter(argparse.HelpFormatter):
    """Shows each option's default, and docstring markup (````x````) as plain text."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        hidden = default is None or default is False or default is argparse.SUPPRESS
        if hidden or default == [] or "default" in text or f"({default})" in text:
            return text
        if action.option_strings or action.nargs in (argparse.OPTIONAL, argparse.ZERO_OR_MORE):
            text += " (default: %(default)s)"
        return text

    def _format_text(self, text: str) -> str:
        return super()._format_text(_plain(text))

    def _expand_help(self, action: argparse.Action) -> str:
        return _plain(super()._expand_help(action))


def _plain(text: str) -> str:
    """Drop markup from docstrings used as help: ``x``, `x`, [`x`][target] and roles become x."""
    text = re.sub(r"\[`([^`]+)`\]\[[\w.]*\]", r"\1", text)  # a mkdocstrings cross-reference
    text = re.sub(r":\w+:`~?([^`]+)`", r"\1", text)  # a Sphinx role
    return text.replace("``", "").replace("`", "")


def _commands() -> dict[str, ModuleType]:
    """Every command's module (imports them all; the command line imports only one)."""
    return {name: import_module(module) for name, (module, _) in COMMANDS.items()}


def get_argument_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser with one subparser per command.

    Args:
        command: Declare only this command's arguments (and import only its module); the
            others are listed with their help. ``None`` declares every command's arguments,
            ``""`` none (enough for ``gimwatch --help``).
    """
    parser = _Parser(
        prog="gimwatch",
        description="Watch the conditioning of a robot's generalized inertia matrix (GIM).",
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"gimwatch {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name, (module_name, summary) in COMMANDS.items():
        if command is not None and name != command:
            sub.add_parser(name, help=summary)
            continue
        module = import_module(module_name)
        parser_ = sub.add_parser(
            name,
            help=summary,
            description=module.__doc__,
            formatter_class=HelpFormatter,
        )
        module.add_arguments(parser_)
        parser_.set_defaults(run=module.run, parameter_options=parameter_options(parser_, module))
    return parser


def _command_in(argv: Sequence[str]) -> str | None:
    """The command named on the command line (the first word that is not an option).

    Raises:
        UsageError: The first word is no command; the message suggests the closest ones.
    """
    for word in argv:
        if word.startswith("-"):
            continue
        if word in COMMANDS:
            return word
        hint = did_you_mean(word, COMMANDS)
        raise UsageError(f"unknown command {word!r}{hint} (commands: {', '.join(COMMANDS)})")
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line and return its exit status.

    Warnings print as one ``gimwatch: warning: ...`` line each; errors gimwatch raises on
    purpose as one ``gimwatch: error: ...`` line, with exit status 2; SIGINT (Ctrl-C) and
    SIGTERM as ``gimwatch: interrupted``, with exit status 130 or 143. A reader that closes
    stdout early (``| head -1``) gets what it read; the command ends with its own status.
    """
    installed = LATCH.install()
    stdout, sys.stdout = sys.stdout, QuietPipe(sys.stdout)
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
        return LATCH.exit_status
    except BrokenPipeError:  # written around sys.stdout (its buffer): the work was done
        discard_stdout(stdout)
        return EXIT_OK
    finally:
        sys.stdout.flush()
        sys.stdout = stdout
        if installed:
            LATCH.uninstall()


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
    # Importing a command's modules runs Python code called from C (Pinocchio's bindings,
    # numba): a KeyboardInterrupt raised there leaves CPython believing it went unhandled
    # (the process then kills itself with SIGINT on exit). Signals are noted, acted on after.
    with LATCH.deferred("hard"):
        from threadpoolctl import threadpool_limits

        argv = sys.argv[1:] if argv is None else list(argv)
        args = get_argument_parser(_command_in(argv) or "").parse_args(argv)
    LATCH.check()
    # GIMs are small dense matrices: multi-threaded OpenBLAS makes their eigen-solves
    # 20-40x slower on 2 cores, so the command line keeps BLAS on one thread.
    with threadpool_limits(limits=1, user_api="blas"):
        try:
            return int(args.run(args))
        except InputError as exc:  # the library names its parameter; the user typed a flag
            flag = getattr(args, "parameter_options", {}).get(exc.name)
            if flag is None:
                raise
            raise exc.renamed(flag) from exc


def parameter_options(parser: argparse.ArgumentParser, module: ModuleType) -> dict[str, str]:
    """Library parameter -> the command's option that sets it (``grid`` -> ``--grid``).

    By destination (``grid``) and its plural (``ranges`` for ``--range``), and whatever the
    command module declares in ``PARAMETER_OPTIONS`` (``path`` -> ``--trajectory``).
    """
    options: dict[str, str] = {}
    for action in parser._actions:  # argparse lists a parser's actions nowhere public
        if action.option_strings and action.dest != "help":
            flag = max(action.option_strings, key=len)
            options.setdefault(f"{action.dest}s", flag)
            options[action.dest] = flag
    return {**options, **getattr(module, "PARAMETER_OPTIONS", {})}
