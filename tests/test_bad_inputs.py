"""The bad-input corpus: every command, every bad file or argument -> one line, exit 2.

Cases come from three places:

* files under ``tests/data/bad/`` with their expected message in ``MANIFEST.toml``;
* paths made at test time (missing file, directory, FIFO, device, oversized file);
* bad command lines (:data:`BAD_ARGUMENTS`).

A command that takes a ROBOT or a SCENE joins the corpus with one line in
:data:`ROBOT_COMMANDS` or :data:`SCENE_COMMANDS`; ``test_every_command_is_in_the_corpus``
fails until it does.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import tomllib
import warnings
from collections.abc import Callable
from pathlib import Path

import pytest

from gimwatch.cli import _commands, get_argument_parser, main
from gimwatch.errors import GimwatchError, URDFWarning
from gimwatch.metrics.dense_analysis import analyze_configuration
from gimwatch.model.chains import chain_spec, generate_chain_urdf
from gimwatch.model.robot_files import MAX_URDF_BYTES
from gimwatch.model.robots import MAX_TREE_DEPTH, load_robot, neutral_configuration
from gimwatch.output.folders import write_marker
from gimwatch.simulation.scene import MAX_SCENE_BYTES

BAD = Path(__file__).parent / "data" / "bad"
MANIFEST = tomllib.loads((BAD / "MANIFEST.toml").read_text())
REPO = Path(__file__).parent.parent

#: How each command is called on one bad ROBOT (or SCENE) with an output folder ``out``
#: that must not be created. Commands not registered yet in the CLI are left out.
_ROBOT_ARGV: dict[str, Callable[[str, Path], list[str]]] = {
    "analyze": lambda robot, out: ["analyze", robot],
    "crosscheck": lambda robot, out: ["crosscheck", robot],
    "survey": lambda robot, out: ["survey", robot, "-o", str(out)],
    "explain": lambda robot, out: ["explain", robot],
    "armature": lambda robot, out: ["armature", robot, "--target", "2", "--samples", "2"],
    "stability": lambda robot, out: ["stability", robot, "--kp", "100", "--kd", "1"],
    "map": lambda robot, out: [
        *("map", robot, "--joints", "shoulder", "elbow", "--grid", "3", "-o", str(out))
    ],
}
_SCENE_ARGV: dict[str, Callable[[str, Path], list[str]]] = {
    "simulate": lambda scene, out: ["simulate", scene, "-o", str(out)],
}
ROBOT_COMMANDS = {name: argv for name, argv in _ROBOT_ARGV.items() if name in _commands()}
SCENE_COMMANDS = {name: argv for name, argv in _SCENE_ARGV.items() if name in _commands()}

#: Seconds after which a case counts as a hang (a guard, not a timing).
HANG_LIMIT_S = 240  # generous: the shared 2-core machines run several suites at once


def _cases(folder: str) -> list[pytest.param]:
    return [
        pytest.param(key, entry, id=key.removeprefix(f"{folder}/"))
        for key, entry in sorted(MANIFEST.items())
        if key.startswith(f"{folder}/")
    ]


def _subcommand_positionals() -> dict[str, set[str]]:
    parser = get_argument_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return {
        name: {a.dest for a in command._actions if not a.option_strings}
        for name, command in sub.choices.items()
    }


@pytest.fixture
def hang_guard():
    """Turn a hang into a test failure after HANG_LIMIT_S (SIGALRM, main thread only)."""

    def alarm(signum, frame):
        raise TimeoutError(f"still running after {HANG_LIMIT_S} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, HANG_LIMIT_S)
    yield
    signal.setitimer(signal.ITIMER_REAL, 0)
    signal.signal(signal.SIGALRM, previous)


def _snapshot(folder: Path) -> dict[str, tuple[int, bytes]]:
    return {
        str(p.relative_to(folder)): (p.stat().st_mtime_ns, p.read_bytes() if p.is_file() else b"")
        for p in sorted(folder.rglob("*"))
    }


def _run_in(
    folder: Path, argv: list[str], capsys, monkeypatch, *, fails: bool = True
) -> tuple[int, str, str]:
    """Run ``main(argv)`` in ``folder`` (holding a good result); a failing run writes nothing."""
    monkeypatch.chdir(folder)
    good = folder / "good.json"
    good.write_text('{"kappa": 1.0}\n')
    before = _snapshot(folder)
    code = main(argv)
    out, err = capsys.readouterr()
    if fails:
        assert _snapshot(folder) == before, "a failed run created or changed a file"
    return code, out, err


def _assert_one_error_line(code: int, out: str, err: str, *fragments: str) -> None:
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and err.startswith("gimwatch: error: "), err
    assert "Traceback" not in err and out == "", (out, err)
    for fragment in fragments:
        assert fragment in err, (fragment, err)


def test_manifest_lists_every_file_and_every_entry_exists():
    on_disk = {
        str(p.relative_to(BAD))
        for p in BAD.rglob("*")
        if p.is_file() and p.name not in ("MANIFEST.toml", "README.md", ".gitkeep")
    }
    assert on_disk == set(MANIFEST)
    for key, entry in MANIFEST.items():
        assert set(entry) <= {"expect", "outcome", "valid_for"} and entry["expect"], key
        assert entry.get("outcome", "error") in ("error", "warning"), key
        assert key.split("/")[0] in ("urdf", "scenes"), key


def test_every_command_is_in_the_corpus():
    for name, positionals in _subcommand_positionals().items():
        if positionals & {"robot", "robots"}:
            assert name in ROBOT_COMMANDS, f"add {name} to _ROBOT_ARGV"
        if positionals & {"scene", "scenes"}:
            assert name in SCENE_COMMANDS, f"add {name} to _SCENE_ARGV"
    assert "analyze" in ROBOT_COMMANDS


def _file_cases() -> list[pytest.param]:
    """Every (command, corpus file) pair: robot commands x urdf/, scene commands x scenes/."""
    return [
        pytest.param(name, argv, key, entry, id=f"{name}-{key}")
        for folder, commands in (("urdf", ROBOT_COMMANDS), ("scenes", SCENE_COMMANDS))
        for name, argv in sorted(commands.items())
        for key, entry in sorted(MANIFEST.items())
        if key.startswith(f"{folder}/")
    ]


@pytest.mark.usefixtures("hang_guard")
@pytest.mark.filterwarnings("default::gimwatch.errors.GimwatchWarning")  # the CLI shows them
@pytest.mark.parametrize(("command", "make_argv", "key", "entry"), _file_cases())
def test_bad_file(command, make_argv, key, entry, tmp_path, capsys, monkeypatch):
    path = str(BAD / key)
    argv = make_argv(path, tmp_path / "out")
    fails = command not in entry.get("valid_for", []) and entry.get("outcome") != "warning"
    code, out, err = _run_in(tmp_path, argv, capsys, monkeypatch, fails=fails)
    if command in entry.get("valid_for", []):
        assert code == 0 and "error" not in err, (code, err)
        return
    if entry.get("outcome") == "warning":
        assert code == 0, err
        warnings = [line for line in err.splitlines() if line.startswith("gimwatch: warning: ")]
        assert len(warnings) == 1 and "error" not in err, err
        assert path in err and entry["expect"] in err, err
        return
    _assert_one_error_line(code, out, err, path, entry["expect"])


@pytest.mark.usefixtures("hang_guard")
@pytest.mark.parametrize(("key", "entry"), _cases("urdf"))
def test_bad_urdf_file_raises_a_gimwatch_error_for_library_users(key, entry, capsys):
    path = BAD / key
    if entry.get("outcome") == "warning":
        with pytest.warns(URDFWarning, match=re.escape(entry["expect"])):
            robot = load_robot(path)
        assert analyze_configuration(robot, neutral_configuration(robot)).kappa > 1
        return
    with pytest.raises(GimwatchError) as info:
        robot = load_robot(path)
        analyze_configuration(robot, neutral_configuration(robot))
    main(["analyze", str(path)])
    assert capsys.readouterr().err == f"gimwatch: error: {info.value}\n"
    assert entry["expect"] in str(info.value)


def _good_results(folder: Path) -> None:
    """A results folder as a previous good run left it."""
    folder.mkdir()
    (folder / "summary.json").write_text('{"status": "completed"}\n')
    (folder / "trajectory.csv").write_text("t,q:joint_1\n0.0,0.1\n")
    write_marker(folder, "simulate")


@pytest.mark.usefixtures("hang_guard")
@pytest.mark.parametrize(
    ("command", "make_argv", "key", "entry"),
    [case for case in _file_cases() if case.values[2].startswith("scenes/")],
)
def test_bad_scene_keeps_a_previous_good_results_folder(
    command, make_argv, key, entry, tmp_path, capsys, monkeypatch
):
    _good_results(tmp_path / "out")
    argv = make_argv(str(BAD / key), tmp_path / "out")
    code, out, err = _run_in(tmp_path, argv, capsys, monkeypatch)  # snapshot covers out/
    _assert_one_error_line(code, out, err, str(BAD / key), entry["expect"])


def _fifo(tmp: Path) -> str:
    os.mkfifo(tmp / "pipe.urdf")
    return str(tmp / "pipe.urdf")


def _sparse(tmp: Path) -> str:
    with open(tmp / "huge.urdf", "wb") as handle:
        handle.truncate(MAX_URDF_BYTES + 1)
    return str(tmp / "huge.urdf")


def _write(path: Path, text: str) -> str:
    path.write_text(text)
    return str(path)


def _under_a_file(tmp: Path) -> str:
    (tmp / "plain.urdf").write_text("<robot/>")
    return str(tmp / "plain.urdf" / "robot.urdf")


#: Robot paths made at test time: (id, maker(tmp folder) -> path, expected fragment).
BAD_PATHS = [
    ("missing_file", lambda tmp: str(tmp / "missing.urdf"), "missing.urdf: no such file"),
    ("missing_folder", lambda tmp: str(tmp / "nowhere/"), "nowhere: no such file"),
    ("directory", lambda tmp: str(tmp), "is a directory, not a URDF file"),
    (
        "directory_named_urdf",
        lambda tmp: str((tmp / "d.urdf").mkdir() or tmp / "d.urdf"),
        "d.urdf: is a directory",
    ),
    ("fifo", _fifo, "pipe.urdf: is not a regular file"),
    ("device", lambda tmp: "/dev/zero", "/dev/zero: is not a regular file"),
    ("oversized", _sparse, f"more than {MAX_URDF_BYTES} for a URDF"),
    ("path_under_a_file", _under_a_file, "robot.urdf: no such file"),
    ("empty_spec", lambda tmp: "", "the robot must be chain:N, a URDF path"),
    (
        "deeper_than_pinocchio_parses",
        lambda tmp: _write(tmp / "deep.urdf", generate_chain_urdf(chain_spec(MAX_TREE_DEPTH + 1))),
        f"a branch of {MAX_TREE_DEPTH + 1} joints is deeper than Pinocchio's parser can read",
    ),
    # analyze reads chain:N on the O(n) path up to 200,000 links; the others need Pinocchio
    ("chain_deeper_than_pinocchio_parses", lambda tmp: "chain:300000", "300000"),
    ("blank_spec", lambda tmp: "  ", "the robot must be chain:N, a URDF path"),
]


@pytest.mark.usefixtures("hang_guard")
@pytest.mark.parametrize("command", sorted(ROBOT_COMMANDS))
@pytest.mark.parametrize(("maker", "expect"), [pytest.param(m, e, id=i) for i, m, e in BAD_PATHS])
def test_bad_robot_path(command, maker, expect, tmp_path, capsys, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    target = maker(tmp_path)
    argv = ROBOT_COMMANDS[command](target, work / "out")
    code, out, err = _run_in(work, argv, capsys, monkeypatch)
    _assert_one_error_line(code, out, err, expect)


#: The chain:3 scene the scene corpus varies (one thing wrong in each file).
GOOD_SCENE = """robot = "chain:3"
duration = 0.05
sample = 0.01
q = 0.1

[effects.gravity]
vector = [0.0, -9.81, 0.0]

[watch]
metrics = ["kappa", "diagonal_ratio"]
"""


def _sparse_scene(tmp: Path) -> str:
    with open(tmp / "huge.toml", "wb") as handle:
        handle.truncate(MAX_SCENE_BYTES + 1)
    return str(tmp / "huge.toml")


def _fifo_scene(tmp: Path) -> str:
    os.mkfifo(tmp / "pipe.toml")
    return str(tmp / "pipe.toml")


def _deep_scene(tmp: Path) -> str:
    _write(tmp / "deep.urdf", generate_chain_urdf(chain_spec(MAX_TREE_DEPTH + 1)))
    return _write(tmp / "deep.toml", GOOD_SCENE.replace('"chain:3"', '"deep.urdf"'))


#: Scene paths made at test time: (id, maker(tmp folder) -> path, expected fragment).
BAD_SCENE_PATHS = [
    ("fifo", _fifo_scene, "pipe.toml: is not a regular file"),
    ("oversized", _sparse_scene, f"huge.toml: is larger than {MAX_SCENE_BYTES} bytes"),
    (
        "directory_named_toml",
        lambda tmp: str((tmp / "d.toml").mkdir() or tmp / "d.toml"),
        "d.toml: is a directory",
    ),
    ("scene_naming_a_deep_urdf", _deep_scene, "deep.urdf: a branch of"),
]


@pytest.mark.usefixtures("hang_guard")
@pytest.mark.parametrize("command", sorted(SCENE_COMMANDS))
@pytest.mark.parametrize(
    ("maker", "expect"), [pytest.param(m, e, id=i) for i, m, e in BAD_SCENE_PATHS]
)
def test_bad_scene_path(command, maker, expect, tmp_path, capsys, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    _good_results(work / "out")
    target = maker(tmp_path)
    argv = SCENE_COMMANDS[command](target, work / "out")
    code, out, err = _run_in(work, argv, capsys, monkeypatch)
    _assert_one_error_line(code, out, err, expect)


def test_the_good_scene_runs(tmp_path, capsys, monkeypatch):
    """The control of the scene corpus: the scene it varies is valid and writes its folder."""
    scene = _write(tmp_path / "good.toml", GOOD_SCENE)
    code, _, err = _run_in(
        tmp_path, ["simulate", scene, "-o", "out"], capsys, monkeypatch, fails=False
    )
    assert code == 0, err
    assert (tmp_path / "out" / "summary.json").is_file()


#: Bad command lines; ``{tmp}`` is the test's folder, which holds ``good.json``.
BAD_ARGUMENTS = [
    (["explain", "ur5", "--q", "0.1"], "--q: must have 6 values (q-coordinates of ur5), got 1"),
    (["explain", "nope"], "robot 'nope': not chain:N"),
    (["explain", "chain:3", "--top", "0"], "argument --top: must be a positive integer"),
    (["explain", "chain:401"], "nv = 401 is too large for Pinocchio's Data"),
    (["analyze", "chain:3", "--explain", "--csv"], "--explain must be used on the dense path"),
    (["analyze", "chain:3", "--explain", "--backend", "denoc"], "--explain must be used on"),
    (["armature", "chain:3", "--target", "1"], "--target must be a number > 1"),
    (["armature", "chain:3", "--target", "0.5"], "--target must be a number > 1"),
    (["armature", "chain:3", "--target", "nan"], "--target must be a number > 1"),
    (["armature", "chain:3", "--target", "x"], "argument --target: invalid float value: 'x'"),
    (["armature", "chain:3"], "one of the arguments --target --timestep is required"),
    (["armature", "chain:3", "--target", "9", "--samples", "0"], "argument --samples: must be"),
    (["armature", "chain:3", "--target", "9", "--samples", "10**9"], "argument --samples"),
    (["armature", "chain:3", "--target", "9", "--samples", "999999"], "--samples must be at most"),
    (["armature", "chain:3", "--target", "9", "--floating"], "unrecognized arguments: --floating"),
    (["map", "chain:3", "--joints", "joint_1", "nope", "-o", "{tmp}/m"], "got 'nope'"),
    (["map", "chain:3", "--joints", "joint_1", "joint_1", "-o", "{tmp}/m"], "two different"),
    (["map", "chain:3", "--joints", "joint_1", "-o", "{tmp}/m"], "argument --joints: expected 2"),
    (["map", "chain:3", "-o", "{tmp}/m"], "--joints and --trajectory must be given one at a time"),
    (
        ["map", "chain:3", "--joints", "joint_1", "joint_2", "--grid", "1", "-o", "{tmp}/m"],
        "--grid must be an integer from 2 to 2000, got 1",
    ),
    (
        ["map", "chain:3", "--joints", "joint_1", "joint_2", "--grid", "0", "-o", "{tmp}/m"],
        "argument --grid: must be a positive integer",
    ),
    (
        ["map", "chain:3", "--joints", "joint_1", "joint_2", "--grid", "9999", "-o", "{tmp}/m"],
        "got 9999",
    ),
    (
        ["map", "chain:3", "--joints", "joint_1", "joint_2", "--metrics", "kapa", "-o", "{tmp}/m"],
        "--metrics must be among",
    ),
    (
        [
            "map",
            "chain:3",
            "--joints",
            "joint_1",
            "joint_2",
            "--range",
            "1",
            "0",
            "0",
            "1",
            "-o",
            "{tmp}/m",
        ],
        "--range must be finite lower < upper",
    ),
    (
        ["map", "chain:3", "--joints", "joint_1", "joint_2", "--q", "0", "-o", "{tmp}/m"],
        "--q: must have 3 values",
    ),
    (
        ["map", "chain:3", "--joints", "joint_1", "joint_2", "-o", "{tmp}/good.json"],
        "good.json: is a file, not a folder",
    ),
    (
        ["map", "chain:3", "--trajectory", "{tmp}/missing.csv", "-o", "{tmp}/m"],
        "--trajectory must be a readable CSV file",
    ),
    (
        ["map", "chain:3", "--trajectory", "{tmp}/good.json", "-o", "{tmp}/m"],
        "good.json:1 must be column names",
    ),
    (
        ["map", "chain:3", "--trajectory", "{tmp}", "-o", "{tmp}/m"],
        "--trajectory must be a readable CSV file",
    ),
    (
        ["map", "chain:3", "--joints", "joint_1", "joint_2"],
        "the following arguments are required: -o",
    ),
    (["chain", "0"], "argument n: must be a positive integer, got '0'"),
    (["chain", "-1"], "argument n: must be a positive integer, got '-1'"),
    (["chain", "two"], "argument n: must be a positive integer, got 'two'"),
    (["chain", "1.5"], "argument n: must be a positive integer, got '1.5'"),
    (["chain", "10000000"], "the number of links must be an integer between 1 and 1000000"),
    (["chain", "3", "--mass", "-1"], "masses_kg[0] must be finite and > 0, got -1.0"),
    (["chain", "3", "--mass", "nan"], "masses_kg[0] must be finite and > 0, got nan"),
    (["chain", "3", "--mass", "heavy"], "argument --mass: must be a number or a comma-separated"),
    (
        ["chain", "3", "--mass", "1,2"],
        "mass_kg must be a number or a list of 3 numbers, got [1.0, 2.0]",
    ),
    (["chain", "3", "--length", "0"], "lengths_m[0] must be finite and > 0, got 0.0"),
    (["chain", "3", "--radius", "-0.1"], "radii_m[0] must be finite and >= 0, got -0.1"),
    (["chain", "3", "--axes", "w"], "axes must be a list of 3 axes, got ['w']"),
    (["chain", "3", "--joint-types", "hinge"], "joint_types[0] must be one of"),
    (["chain", "0", "-o", "{tmp}/good.json"], "must be a positive integer"),
    (["chain", "3", "-o", "{tmp}"], "is a directory; give a file name"),
    (["chain", "3", "-o", "{tmp}/good.json/c.urdf"], "c.urdf: cannot be written"),
    (["analyze", "ur5", "--q", "0.1"], "--q must be 6 numbers for ur5, got 1"),
    (["analyze", "chain:2", "--q", "0.1", "nan"], "q must be finite"),
    (["analyze", "chain:2", "--q", "0.1", "1e400"], "q must be finite"),
    (["analyze", "chain:2", "--q", "a", "b"], "argument --q: invalid float value: 'a'"),
    (["analyze", "chain:2", "--random", "0"], "argument --random: must be a positive integer"),
    (["analyze", "chain:2", "--random", "-1"], "argument --random: must be a positive integer"),
    (["analyze", "chain:2", "--random", "1000000000"], "--random must be at most 100000"),
    (
        ["analyze", "chain:2", "--random", "2", "--seed", "-1"],
        "argument --seed: must be an integer >= 0",
    ),
    (["analyze", "chain:2", "--seed", "x"], "argument --seed: must be an integer >= 0"),
    (
        ["analyze", "ur5", "--q", "1", "--random", "2"],
        "--q and --random must be used one at a time",
    ),
    (["analyze", "chain:0"], "the number of links must be an integer between 1"),
    (["analyze", "chain:-3"], "the number of links must be an integer between 1"),
    (["analyze", "chain:abc"], "the N of chain:N must be a positive integer, got 'abc'"),
    (["analyze", "chain:10000000"], "the number of links must be an integer between 1"),
    (["analyze", "chain:401", "--backend", "crba"], "nv = 401 is too large for Pinocchio's Data"),
    (["analyze", "chain:1000000"], "the N of chain:N must be at most 200000, got 1000000"),
    (["analyze", "chain:4", "--backend", "denoc", "--metrics", "kappa,x"], "metrics must be among"),
    (["analyze", "chain:4", "--metrics", "kappa"], "--metrics must be used with the O(n) path"),
    (
        ["analyze", "chain:396", "--floating", "--backend", "crba"],
        "nv = 402 is too large for Pinocchio's Data",
    ),
    (["analyze", "nope"], "robot 'nope': not chain:N"),
    (["analyze"], "the following arguments are required: ROBOT"),
    ([], "no command given (commands: chain, analyze"),
    ([], "`gimwatch --help` says more"),
    (["frobnicate"], "unknown command 'frobnicate'"),
    (["analyze", "chain:2", "--bogus"], "unrecognized arguments: --bogus"),
    (["demo", "-o", "{tmp}/good.json"], "good.json: is a file, not a folder"),
    (["crosscheck", "chain:2", "--samples", "-1"], "argument --samples: must be a positive"),
    (["crosscheck", "chain:2", "--samples", "0"], "argument --samples: must be a positive"),
    (["crosscheck", "chain:2", "--samples", "abc"], "argument --samples: must be a positive"),
    (["crosscheck", "chain:2", "--samples", "10**9"], "argument --samples: must be a positive"),
    (["crosscheck", "chain:2", "--samples", "100000000000"], "count must be at most 25000000"),
    (["crosscheck", "chain:2", "--tolerance", "-1"], "--tolerance must be a number > 0 and < 1"),
    (["crosscheck", "chain:2", "--tolerance", "0"], "must be a number > 0 and < 1, got 0.0"),
    (["crosscheck", "chain:2", "--tolerance", "nan"], "must be a number > 0 and < 1, got nan"),
    (["crosscheck", "chain:2", "--tolerance", "inf"], "must be a number > 0 and < 1, got inf"),
    (["crosscheck", "chain:2", "--tolerance", "1"], "must be a number > 0 and < 1, got 1.0"),
    (["crosscheck", "chain:2", "--tolerance", "x"], "argument --tolerance: invalid float value"),
    (["crosscheck", "chain:2", "--seed", "-1"], "argument --seed: must be an integer >= 0"),
    (["crosscheck"], "the following arguments are required: ROBOT"),
    (["survey", "chain:2", "--samples", "-1"], "argument --samples: must be a positive integer"),
    (["survey", "chain:2", "--samples", "0"], "argument --samples: must be a positive integer"),
    (["survey", "chain:2", "--chunk-size", "0"], "argument --chunk-size: must be a positive"),
    (["survey", "chain:2", "--workers", "0"], "argument --workers: must be a positive integer"),
    (["survey", "chain:2", "--seed", "-5"], "argument --seed: must be an integer >= 0"),
    (["survey", "chain:2", "--scheduler", "nonsense"], "--scheduler must be 'local' or a Dask"),
    (["survey", "chain:2", "--scheduler", "tcp://h:99999"], "got 'tcp://h:99999'"),
    (["survey", "chain:2", "--scheduler", "http://h:8786"], "got 'http://h:8786'"),
    (["survey", "chain:2", "--scheduler", "tcp://"], "got 'tcp://'"),
    (["survey", "chain:2", "-o", "{tmp}/good.json"], "good.json: is a file, not a folder"),
    (["bench", "nosuchsection"], "the bench section must be one of"),
    (["bench", "--quick", "conditioning", "-o", "{tmp}/good.json"], "good.json: is a file"),
    (["bench", "--seed", "-1"], "argument --seed: must be an integer >= 0"),
    (["simulate", "{tmp}/missing.toml"], "missing.toml: no such file"),
    (["simulate", "{tmp}"], "is a directory, not a scene file"),
    (["simulate", "{tmp}/good.json/scene.toml"], "scene.toml: no such file"),
    (["simulate", "/dev/zero"], "/dev/zero: is not a regular file"),
    (["simulate", "{good_scene}", "-o", "{tmp}/good.json"], "good.json: is a file, not a folder"),
    (["simulate", "{good_scene}", "-o", "{tmp}/good.json/out"], "good.json: is a file"),
    (["simulate"], "the following arguments are required: scene"),
]


@pytest.mark.usefixtures("hang_guard")
@pytest.mark.parametrize(
    ("argv", "expect"), BAD_ARGUMENTS, ids=lambda v: " ".join(v) if isinstance(v, list) else ""
)
def test_bad_arguments(argv, expect, tmp_path, capsys, monkeypatch):
    scenes = tmp_path.parent / f"{tmp_path.name}-scenes"
    scenes.mkdir()
    good_scene = _write(scenes / "good.toml", GOOD_SCENE)
    argv = [a.replace("{tmp}", str(tmp_path)).replace("{good_scene}", good_scene) for a in argv]
    code, out, err = _run_in(tmp_path, argv, capsys, monkeypatch)
    _assert_one_error_line(code, out, err, expect)


#: Cases urdfdom would complain about on stderr (checked in a real subprocess).
SUBPROCESS_CASES = [
    "urdf/mass_nan.urdf",
    "urdf/mass_not_a_number.urdf",
    "urdf/axis_two_components.urdf",
    "urdf/axis_zero.urdf",
    "urdf/joint_type_unknown.urdf",
    "urdf/duplicate_link.urdf",
    "urdf/billion_laughs.urdf",
    "urdf/not_utf8.urdf",
]


def _python(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run(
        [sys.executable, *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=HANG_LIMIT_S,
    )


@pytest.mark.parametrize("key", SUBPROCESS_CASES)
def test_no_stray_stderr_in_a_real_process(key, tmp_path):
    done = _python("-m", "gimwatch", "analyze", str(BAD / key), cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("gimwatch: error: ")
    assert MANIFEST[key]["expect"] in done.stderr and done.stdout == ""
    assert list(tmp_path.iterdir()) == []


def test_urdfdom_would_print_without_the_checks(tmp_path):
    """The control of the test above: Pinocchio's parser alone writes to stderr."""
    code = (
        "import pinocchio, sys; "
        f"pinocchio.buildModelFromXML(open({str(BAD / 'urdf/mass_nan.urdf')!r}).read())"
    )
    done = _python("-c", code, cwd=tmp_path)
    assert "Error:" in done.stderr and "mass [nan] is not a float" in done.stderr


@pytest.mark.parametrize(
    "key",
    [
        "urdf/inertia_triangle_inequality.urdf",
        "urdf/limit_missing_effort.urdf",  # real-world conventions read leniently: urdfdom,
        "urdf/visual_box_size_two_numbers.urdf",  # given the raw file, would print and refuse
    ],
)
def test_warning_cases_print_one_line_in_a_real_process(key, tmp_path):
    done = _python("-m", "gimwatch", "analyze", str(BAD / key), "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("gimwatch: warning: ")


def test_library_warning_is_a_warning_not_an_error():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(URDFWarning):
            load_robot(BAD / "urdf/inertia_triangle_inequality.urdf")
