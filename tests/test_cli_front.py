"""The command line's front door: listing commands, help text, data out, lazy imports."""

import argparse
import csv
import importlib
import io
import json
import subprocess
import sys

import pytest

import gimwatch
from gimwatch.cli import COMMANDS, _commands, get_argument_parser, main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_command_table_matches_the_modules():
    for name, module in _commands().items():
        assert module.NAME == name
        assert COMMANDS[name][0] == module.__name__
        assert not hasattr(module, "HELP"), f"{name}: its help is written in COMMANDS only"


def test_the_one_line_help_is_the_command_tables(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    listing = " ".join(capsys.readouterr().out.split())
    for name, (_, summary) in COMMANDS.items():
        assert f"{name} {' '.join(summary.split())}" in listing, name


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_help_shows_defaults_and_no_markup(capsys, name):
    with pytest.raises(SystemExit) as exit_info:
        main([name, "--help"])
    out = capsys.readouterr().out
    assert exit_info.value.code == 0
    assert "``" not in out and ":data:`" not in out and ":func:`" not in out, out
    parser = get_argument_parser(name)
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    for action in sub.choices[name]._actions:
        default = action.default
        if not action.option_strings or default in (None, False, argparse.SUPPRESS):
            continue
        if "default" in action.help or f"({default})" in action.help:
            continue  # the help states it already
        assert f"(default: {default})" in " ".join(out.split()), (name, action.dest)


def test_unknown_command_suggests_and_top_help_imports_no_command(capsys):
    code, out, err = run(capsys, "crosschek", "ur5")
    assert code == 2 and out == ""
    assert err.startswith("gimwatch: error: unknown command 'crosschek'; did you mean 'crosscheck'")
    code = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from gimwatch.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "prefixes = ('gimwatch.cli.', 'scipy', 'numba')\n"
            "helpers = ('gimwatch.cli._signals', 'gimwatch.cli._pipe')\n"
            "print([m for m in sys.modules if m.startswith(prefixes) and m not in helpers])",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert code.stdout.strip().splitlines()[-1] == "[]", code.stdout


def test_import_gimwatch_is_lazy_and_every_public_name_resolves():
    done = subprocess.run(
        [
            sys.executable,
            "-W",
            "error",
            "-c",
            "import sys, gimwatch\n"
            "print(sorted(m for m in sys.modules if m.startswith("
            "('gimwatch.', 'scipy', 'numba', 'matplotlib', 'pinocchio'))))",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert done.stdout.strip() == "['gimwatch._version']", done.stdout
    assert gimwatch.__all__ == sorted(gimwatch.__all__)
    for name in gimwatch.__all__:
        assert getattr(gimwatch, name) is not None, name
    assert set(gimwatch.__all__) <= set(dir(gimwatch))
    assert gimwatch.load_robot is importlib.import_module("gimwatch.model.robots").load_robot
    with pytest.raises(AttributeError, match="no attribute 'lod_robot'"):
        gimwatch.lod_robot  # noqa: B018


def test_the_public_api_holds_the_entry_points_the_docs_use():
    # analyze and the tracker are documented and used from Python; they are public names
    for name in ("analyze", "KappaTracker", "TrackedKappa", "track_kappa"):
        assert name in gimwatch.__all__, name
    assert gimwatch.analyze is importlib.import_module("gimwatch.metrics.analyze").analyze
    tracker = importlib.import_module("gimwatch.metrics.tracker")
    assert gimwatch.KappaTracker is tracker.KappaTracker
    assert gimwatch.track_kappa is tracker.track_kappa


def test_robots_lists_every_example_robot(capsys):
    code, out, _ = run(capsys, "robots", "--json")
    rows = {r["name"]: r for r in json.loads(out)["robots"]}
    assert code == 0 and set(rows) == set(gimwatch.example_robot_names())
    assert rows["ur5"]["nv"] == 6 and rows["ur5"]["base"] == "fixed"
    assert rows["ur5"]["source"].endswith(".urdf")
    assert rows["iris"]["base"] == "floating"  # a drone: no joint with a fixed base
    assert rows["cassie"]["nv"] is None and "SDF" in rows["cassie"]["problem"]
    code, out, _ = run(capsys, "robots", "--csv")
    table = list(csv.DictReader(io.StringIO(out)))
    assert code == 0 and len(table) == len(rows) and table[0].keys() >= {"name", "nv", "base"}
    code, out, _ = run(capsys, "robots")
    assert code == 0 and out.splitlines()[0].split() == [
        "name",
        "nv",
        "base",
        "source",
        "/",
        "problem",
    ]


def test_metrics_lists_the_watch_metrics(capsys):
    from gimwatch.watch.watch import METRICS

    code, out, _ = run(capsys, "metrics", "--json")
    rows = json.loads(out)["metrics"]
    assert code == 0 and [r["name"] for r in rows] == list(METRICS)
    kappa = next(r for r in rows if r["name"] == "kappa")
    delta = next(r for r in rows if r["name"] == "diagonal_ratio")
    assert kappa["needs_M"] is True and delta["needs_M"] is False
    assert all("``" not in r["description"] and r["description"] for r in rows)
    code, out, _ = run(capsys, "metrics")
    assert code == 0 and "diagonal_ratio" in out


def test_crosscheck_and_stress_csv(capsys):
    code, out, _ = run(capsys, "crosscheck", "chain:3", "--samples", "2", "--csv")
    (row,) = csv.DictReader(io.StringIO(out))
    assert code == 0 and row["robot"] == "chain_3" and float(row["gim_rel_err"]) < 1e-12
    code, out, _ = run(capsys, "stress", "ur5-wrist-aligned", "--no-simulate", "--csv")
    (row,) = csv.DictReader(io.StringIO(out))
    assert code == 0 and row["case"] == "ur5-wrist-aligned" and row["passed"] == "True"
    assert float(row["error_aba"]) < 1e-12


def test_mistyped_metric_names_get_a_suggestion(capsys):
    from gimwatch.suggest import did_you_mean

    assert did_you_mean("kapa", ["kappa", "rcond"]) == "; did you mean 'kappa'?"
    assert did_you_mean("frobnicate", ["kappa", "rcond"]) == ""
    # case is not a typo: UR5 is ur5, and the suggestion keeps the choice's own spelling
    assert did_you_mean("UR5", ["ur5", "ur10"]) == "; did you mean 'ur5'?"
    assert did_you_mean("Chain_10", ["chain_10", "chain_20"]).startswith(
        "; did you mean 'chain_10'"
    )
    with pytest.raises(gimwatch.SceneError) as error:
        gimwatch.parse_scene(
            {"robot": "chain:3", "duration": 1, "sample": 0.1, "watch": {"metrics": ["kapa"]}},
            source="s.toml",
        )
    assert str(error.value).endswith("; did you mean 'kappa'?")
    argv = ["analyze", "chain:500", "--backend", "denoc", "--metrics", "diagonal_ratoi"]
    code, _, err = run(capsys, *argv)
    assert code == 2 and err.rstrip().endswith("(did you mean 'diagonal_ratio'?)"), err
