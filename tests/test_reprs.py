"""The records a user prints in a session have one-line reprs that say what they hold."""

from __future__ import annotations

from types import SimpleNamespace

import gimwatch as gw
from gimwatch.survey.records import SurveyResult


def test_trajectory_repr_is_one_short_line():
    scene = gw.parse_scene(
        {"robot": "chain:3", "duration": 0.2, "sample": 0.1, "watch": {"metrics": ["kappa"]}}
    )
    trajectory = gw.run_scene(scene)
    text = repr(trajectory)
    assert "\n" not in text and len(text) < 200, text
    assert text.startswith("Trajectory(robot='chain_3', status='completed', t = 0..0.2 s")
    assert "3 samples" in text and "watched=['kappa']" in text and "alarms=0" in text


def test_watch_repr_names_robot_metrics_samples_and_alarm():
    robot = gw.load_robot("chain:4")
    watch = gw.Watch(
        robot, ("diagonal_ratio",), alarm_metric="diagonal_ratio", alarm_threshold=1e9, warn=False
    )
    watch.sample(0.0, gw.neutral_configuration(robot))
    assert repr(watch) == (
        "Watch(robot='chain_4', metrics=['diagonal_ratio'], samples=1, alarms=0, "
        "alarm=diagonal_ratio > 1e+09)"
    )


def test_survey_result_repr_lists_a_few_robots():
    robots = tuple(SimpleNamespace(name=f"robot_{k}") for k in range(7))
    result = SurveyResult(robots=robots, failures=(), samples=20, seed=0)
    assert repr(result) == (
        "SurveyResult(7 robots [robot_0, robot_1, robot_2, robot_3, robot_4, ... (2 more)], "
        "0 failures, 20 random samples each, seed 0)"
    )
