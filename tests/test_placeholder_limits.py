"""Placeholder joint limits (|limit| >= 1e3 or none): replaced in random draws, and said so."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from gimwatch.cli import main
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.survey.run import run_survey

SLIDER_ARM = Path(__file__).parent / "data" / "mjcf" / "slider_arm.xml"


def test_analyze_random_says_which_limits_it_replaced(capsys):
    assert main(["analyze", str(SLIDER_ARM), "--random", "3", "--json"]) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if "placeholder limits" in line]
    assert len(notes) == 1 and notes[0].startswith("gimwatch: note: ")
    assert "±π rad / ±1 m: slide, shoulder, elbow" in notes[0]
    record = json.loads(captured.out)
    assert record["placeholder_limits"] == ["slide", "shoulder", "elbow"]
    q = np.array([c["q"] for c in record["configurations"]])
    assert np.all(np.abs(q[:, 0]) <= 1.0)  # the slide: ±1 m, not its ±1e3+ placeholder


def test_analyze_at_given_configurations_draws_nothing_and_says_nothing(capsys):
    assert main(["analyze", str(SLIDER_ARM), "--json"]) == 0
    captured = capsys.readouterr()
    assert "placeholder" not in captured.err and "placeholder_limits" not in captured.out


def test_survey_lists_the_replaced_limits_per_robot():
    result = run_survey([str(SLIDER_ARM), "ur5"], samples=3, seed=0)
    by_name = {r.name: r for r in result.robots}
    assert by_name["slider_arm"].placeholder_limits == ("slide", "shoulder", "elbow")
    assert by_name["ur5"].placeholder_limits == ()  # real limits of ±2π
    robot = load_robot("ur5")
    drawn = random_configurations(robot, 200, seed=0)
    assert np.all(drawn <= robot.model.upperPositionLimit) and np.all(
        drawn >= robot.model.lowerPositionLimit
    )


def test_a_map_replaces_exactly_the_limits_random_draws_replace():
    # one rule: a joint whose limits random_configurations replaces gets ±π / ±1 m in a map
    from gimwatch.explain.maps import map_axes
    from gimwatch.model.sampling import placeholder_limit_joints

    cases = (
        (str(SLIDER_ARM), ("slide", "shoulder")),
        ("ur5", ("shoulder_pan_joint", "elbow_joint")),
    )
    seen = set()
    for spec, pair in cases:
        robot = load_robot(spec)
        replaced = set(placeholder_limit_joints(robot))
        _, index, units, limits, _ = map_axes(spec, "dense", pair)
        for joint, unit, (lo, hi), i in zip(pair, units, limits, index, strict=True):
            low, high = robot.model.lowerPositionLimit[i], robot.model.upperPositionLimit[i]
            if joint in replaced:
                assert (lo, hi) == ((-1.0, 1.0) if unit == "m" else (-np.pi, np.pi)), joint
            else:
                assert (lo, hi) == (low, high), joint
            seen.add(joint in replaced)
    assert seen == {True, False}  # both sides of the rule were exercised
