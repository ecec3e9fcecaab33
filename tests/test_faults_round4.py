"""Hostile input, fourth round (issue 40, the MuJoCo/MJCF side and the command line).

Each case gives one ``gimwatch: error:`` line and exit 2, or a correct result checked against
an independent reference (MuJoCo's ``mj_fullM``, Python's ``float``); never a traceback.
"""

from __future__ import annotations

import argparse

import pytest

from gimwatch.cli import COMMANDS, UsageError, get_argument_parser, main


def _run(argv: list[str], capture) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capture.readouterr()
    return code, out, err


def _one_error(code: int, out: str, err: str, *fragments: str) -> None:
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and err.startswith("gimwatch: error: "), err
    assert "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)


# --- every numeric option reads every float literal NumPy prints --------------------------


def _subparser(command: str) -> argparse.ArgumentParser:
    parser = get_argument_parser(command)
    (commands,) = (a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return commands.choices[command]


def _numeric_options() -> list[tuple[str, argparse.Action]]:
    cases = []
    for command in COMMANDS:
        for action in _subparser(command)._actions:
            if action.option_strings and action.type not in (None, str):
                cases.append((command, action.option_strings[-1]))
    return cases


def _filler(command: str, skip: str) -> list[str]:
    """Positionals and required options of ``command`` other than ``skip``, with values."""
    words = []
    for action in _subparser(command)._actions:
        if not action.option_strings:
            if action.nargs not in ("*", "?", argparse.PARSER):
                words.append("2")
        elif action.required and action.option_strings[-1] != skip:
            words += [action.option_strings[-1], "10"]
    return words


NUMERIC = _numeric_options()


def test_the_commands_have_numeric_options():
    """The parametrised test below covers something: the options the issue names."""
    names = {(command, option) for command, option in NUMERIC}
    assert {("analyze", "--q"), ("map", "--range"), ("armature", "--target")} <= names
    assert len(NUMERIC) >= 20


@pytest.mark.parametrize("literal", ["-1e-05", "-1E+3", "-.5e-2", "-1.e-3", "-inf", "-1e-05,2"])
@pytest.mark.parametrize(("command", "option"), NUMERIC)
def test_a_negative_float_literal_is_a_value_not_an_option(command, option, literal):
    """argparse reads the literal as the option's value: parsed as Python's float reads it,
    or refused by the option's own type check, which quotes it; never "unrecognized"."""
    sub = _subparser(command)
    (action,) = (a for a in sub._actions if option in a.option_strings)
    count = action.nargs if isinstance(action.nargs, int) else 2 if action.nargs == "+" else 1
    words = ["0.5"] * (count - 1) + [literal]
    argv = [command, *_filler(command, option), option, *words]
    try:
        args = get_argument_parser(command).parse_args(argv)
    except UsageError as exc:
        message = str(exc)
        assert "unrecognized" not in message and "expected" not in message, message
        assert literal in message, message
        return
    value = getattr(args, action.dest)
    expected = [float(x) for x in literal.split(",")]
    if action.nargs is None and isinstance(value, list):  # one comma-separated list
        assert value == expected
    else:
        last = value[-1] if isinstance(value, list) else value
        assert last == expected[0]


@pytest.mark.parametrize("q", [["0.1", "-1e-05"], ["-1e-3", "2.5E-1"]])
def test_analyze_reads_numpy_printed_q(q, capsys):
    code, out, err = _run(["analyze", "chain:2", "--q", *q, "--json"], capsys)
    assert code == 0 and err == "", err
    import json

    import numpy as np

    from gimwatch.metrics.conditioning import condition_number
    from gimwatch.model.robots import load_robot

    robot = load_robot("chain:2")
    q_float = np.array([float(x) for x in q])
    import pinocchio as pin

    M = pin.crba(robot.model, robot.model.createData(), q_float)
    M = np.triu(M) + np.triu(M, 1).T
    record = json.loads(out)["configurations"][0]
    assert record["q"] == [float(x) for x in q]
    assert record["kappa"] == pytest.approx(condition_number(M), rel=1e-12)
