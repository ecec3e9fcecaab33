"""A robot spec is parsed once and loaded once per command; a watch sample skips robots.py.

How the passes are counted (a `sys.setprofile` hook, this thread only):

* **an entry into robots.py** is a Python call whose code lives in
  ``gimwatch/model/robots.py`` made from code outside that file (calls nested inside
  robots.py are part of the entry that started them and are not counted again);
* **a spec entry** is an entry whose first argument is a robot's specification: its text
  (``str``), a ``Path``, a `RobotSpec` or a `ChainSpec`. Reading a loaded `Robot` (its
  ``nv``, a new Data, its neutral q) is not the spec passing through: it does not count;
* **a parse** is a call of `RobotSpec.parse` (the one parser), wherever it is called from;
* **a load** is a spec entry into `load_robot` or `chain_robot`.

Each command must parse once, load once and make one spec entry in all. The old code (the
string parsed by ``parse_chain_spec`` in ``choose_path``, ``analyze`` and ``load_robot``,
and ``default_floating`` asked apart; ``analyze --explain`` loading the robot again) made
4 to 6 spec entries per command and had no `RobotSpec`.
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import gimwatch.model.robots as robots_module
from gimwatch.model.chains import ChainSpec
from gimwatch.model.robot_spec import RobotSpec

ROBOTS_PY = str(Path(robots_module.__file__).resolve())
PARSE_CODE = RobotSpec.parse.__func__.__code__
LOADERS = {"load_robot", "chain_robot"}


class Passes:
    """Counts of entries into robots.py, spec entries, parses and loads (module docstring)."""

    def __init__(self) -> None:
        self.entries: Counter[str] = Counter()
        self.spec_entries: Counter[str] = Counter()
        self.parses = 0

    @property
    def loads(self) -> int:
        return sum(self.spec_entries[name] for name in LOADERS)

    def _hook(self, frame, event, arg) -> None:
        if event != "call":
            return
        code = frame.f_code
        if code is PARSE_CODE:
            self.parses += 1
        if code.co_filename != ROBOTS_PY:
            return
        caller = frame.f_back
        if caller is not None and caller.f_code.co_filename == ROBOTS_PY:
            return  # nested inside an entry
        self.entries[code.co_name] += 1
        if code.co_argcount or code.co_kwonlyargcount:
            first = frame.f_locals.get(code.co_varnames[0])
            if isinstance(first, (str, Path, RobotSpec, ChainSpec)):
                self.spec_entries[code.co_name] += 1

    def __enter__(self) -> Passes:
        self._previous = sys.getprofile()
        sys.setprofile(self._hook)
        return self

    def __exit__(self, *exc) -> None:
        sys.setprofile(self._previous)


def _fresh_caches() -> None:
    """Forget robots kept from earlier tests, so that every load is seen."""
    from gimwatch.explain import maps
    from gimwatch.metrics import analyze

    analyze._LOADED.clear()
    for cached in (maps._linear_model, maps._file_robot, maps._lean):
        cached.cache_clear()


def _assert_once(passes: Passes) -> None:
    assert passes.parses == 1, f"parsed {passes.parses} times"
    assert passes.loads == 1, f"loaded {passes.loads} times: {dict(passes.spec_entries)}"
    assert sum(passes.spec_entries.values()) == 1, dict(passes.spec_entries)


def test_spec_equal_for_equal_text() -> None:
    assert RobotSpec.parse("chain:5") == RobotSpec.parse(Path("chain:5"))
    assert RobotSpec.parse("chain:5") == RobotSpec.parse("chain:5", False)
    assert RobotSpec.parse("chain:5") != RobotSpec.parse("chain:5", True)
    assert RobotSpec.parse("chain:5") != RobotSpec.parse("chain:6")
    assert hash(RobotSpec.parse("chain:5")) == hash(RobotSpec.parse("chain:5"))
    spec = RobotSpec.parse("chain:5")
    assert (spec.kind, spec.chain.n, spec.name, str(spec)) == ("chain", 5, "chain_5", "chain:5")


def test_spec_keeps_what_the_parser_decided() -> None:
    """The base example-robot-data gives (free-flyer for solo12) is read once, into the spec."""
    from example_robot_data.robots_loader import ROBOTS

    assert ROBOTS["solo12"].free_flyer
    assert RobotSpec.parse("solo12").floating is True
    assert RobotSpec.parse("solo12", False).floating is False
    assert RobotSpec.parse("ur5").floating is False
    assert RobotSpec.parse("ur5").kind == "example"
    assert RobotSpec.parse("robot.urdf").kind == "file"


def test_loaded_robot_keeps_its_spec() -> None:
    from gimwatch.model.robots import load_robot

    spec = RobotSpec.parse("chain:3")
    robot = load_robot(spec)
    assert robot.robot_spec == spec
    assert robot.spec == "chain:3"
    assert load_robot("chain:3").robot_spec == spec


@pytest.mark.parametrize("explain", [False, True])
def test_analyze_parses_and_loads_once(explain: bool) -> None:
    from gimwatch.explain.modes import gim_modes
    from gimwatch.metrics.analyze import analyze

    _fresh_caches()
    with Passes() as passes:
        analysis = analyze("chain:5")
        if explain:  # the explain code takes the Robot analyze loaded
            gim_modes(analysis.robot, analysis.results[0].q)
    _assert_once(passes)
    assert analysis.robot.nv == 5


def test_analyze_of_a_file_loads_once(tmp_path: Path) -> None:
    """A file is loaded to choose the path (its nv), and that Robot is the one analysed."""
    from gimwatch.metrics.analyze import analyze
    from gimwatch.model.chains import chain_spec, generate_chain_urdf

    path = tmp_path / "arm.urdf"
    path.write_text(generate_chain_urdf(chain_spec(4)))
    _fresh_caches()
    with Passes() as passes:
        analyze(str(path))
    _assert_once(passes)


def test_analyze_takes_a_robot_or_a_spec() -> None:
    from gimwatch.metrics.analyze import analyze
    from gimwatch.model.robots import load_robot

    robot = load_robot("chain:4")
    with Passes() as passes:
        from_robot = analyze(robot)
    assert passes.parses == 0 and passes.loads == 0
    spec = RobotSpec.parse("chain:4")
    with Passes() as passes:
        from_spec = analyze(spec)
    assert passes.parses == 0 and passes.loads == 1
    assert from_robot.results[0].kappa == from_spec.results[0].kappa
    assert from_robot.results[0].kappa == analyze("chain:4").results[0].kappa


def test_conditioning_map_parses_and_loads_once() -> None:
    from gimwatch.explain.maps import conditioning_map

    _fresh_caches()
    with Passes() as passes:
        conditioning_map("chain:5", ["joint_1", "joint_2"], grid=3)
    _assert_once(passes)


def test_stability_parses_and_loads_once() -> None:
    from gimwatch.stability.analysis import stability

    with Passes() as passes:
        stability("chain:5", kp=100.0, kd=10.0)
    _assert_once(passes)


def _cli(argv: list[str], capsys) -> Passes:
    from gimwatch.cli import main

    _fresh_caches()
    with Passes() as passes:
        status = main(argv)
    out = capsys.readouterr()
    assert status in (0, 1), out.err
    return passes


@pytest.mark.parametrize(
    "argv",
    [
        ["analyze", "chain:5"],
        ["analyze", "chain:5", "--explain"],
        ["analyze", "ur5", "--explain"],
        ["stability", "chain:5", "--kp", "100", "--kd", "10"],
        ["crosscheck", "chain:5", "--samples", "1"],
    ],
    ids=" ".join,
)
def test_cli_parses_and_loads_once(argv: list[str], capsys) -> None:
    _assert_once(_cli(argv, capsys))


@pytest.mark.parametrize("with_q", [False, True])
def test_cli_map_parses_and_loads_once(with_q: bool, tmp_path: Path, capsys) -> None:
    argv = ["map", "chain:5", "--joints", "joint_1", "joint_2", "--grid", "3"]
    argv += ["--q", "0", "0", "0.1", "0", "0"] if with_q else []
    _assert_once(_cli([*argv, "-o", str(tmp_path / "map")], capsys))


@pytest.mark.parametrize("first", [True, False])
def test_watch_sample_skips_robots_py(first: bool) -> None:
    """A sample (the first, and one after it) enters robots.py at most once, with no spec."""
    from gimwatch.model.robots import load_robot
    from gimwatch.watch.watch import Watch

    robot = load_robot("chain:5")
    watch = Watch(robot)
    q = np.full(5, 0.3)
    if not first:
        watch.sample(0.0, q)
    with Passes() as passes:
        watch.sample(1.0, q + 0.1)
    assert sum(passes.entries.values()) <= 1, dict(passes.entries)
    assert not passes.spec_entries and passes.parses == 0


@pytest.mark.parametrize("robot", ["ur5", "chain:4"])
def test_scene_robot_parses_and_loads_once(robot: str) -> None:
    """A scene's robot (its text, or a ``chain:N`` the scene reads as a chain) is loaded once."""
    from gimwatch.simulation.scene import parse_scene
    from gimwatch.simulation.scene_robot import load_scene_robot

    scene = parse_scene({"robot": robot, "duration": 0.2, "sample": 0.05}, source="s.toml")
    with Passes() as passes:
        loaded = load_scene_robot(scene)
    assert passes.parses <= 1 and passes.loads == 1, (passes.parses, dict(passes.spec_entries))
    assert sum(passes.spec_entries.values()) == 1
    assert loaded.robot_spec is not None and loaded.robot_spec.text == robot


def test_crosscheck_robot_takes_text_and_loads_once() -> None:
    """The library's cross-check of a robot's text parses and loads it once, like the CLI."""
    from gimwatch.crosscheck import crosscheck_robot
    from gimwatch.model.robots import load_robot

    _fresh_caches()
    with Passes() as passes:
        from_text = crosscheck_robot("chain:4", samples=2)
    _assert_once(passes)
    from_robot = crosscheck_robot(load_robot("chain:4"), samples=2)
    assert from_text.passed and from_text.gim_rel_err == from_robot.gim_rel_err
