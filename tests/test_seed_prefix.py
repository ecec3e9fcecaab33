"""``--random K --seed S``: configuration k depends only on (S, k), whatever K is."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gimwatch.metrics.linear_analysis import chain_configurations
from gimwatch.model.robot_spec import parse_chain_spec
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    ("spec", "floating"),
    [("ur5", False), ("solo12", True), ("double_pendulum_continuous", False), ("chain:6", False)],
)
def test_random_configurations_are_prefix_stable(spec, floating):
    robot = load_robot(spec, floating=floating)
    many = random_configurations(robot, 100, seed=0)
    for count in (1, 5, 37):
        np.testing.assert_array_equal(random_configurations(robot, count, seed=0), many[:count])
    assert not np.array_equal(random_configurations(robot, 5, seed=1), many[:5])
    assert len({tuple(q) for q in many}) == 100  # distinct configurations, not one repeated


def test_chain_configurations_are_prefix_stable_and_those_of_the_robot():
    spec = parse_chain_spec("chain:8")
    many = chain_configurations(spec, 50, seed=3)
    np.testing.assert_array_equal(chain_configurations(spec, 1, seed=3), many[:1])
    np.testing.assert_array_equal(many, random_configurations(load_robot("chain:8"), 50, seed=3))


def _analyze_json(*argv: str) -> list[dict]:
    done = subprocess.run(
        [sys.executable, "-m", "gimwatch", "analyze", *argv, "--json"],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    data = json.loads(done.stdout)
    return data if isinstance(data, list) else data["configurations"]


def test_cli_random_one_is_configuration_zero_of_random_hundred():
    one = _analyze_json("ur5", "--random", "1", "--seed", "0")
    hundred = _analyze_json("ur5", "--random", "100", "--seed", "0")
    assert len(one) == 1 and len(hundred) == 100
    assert one[0]["q"] == hundred[0]["q"]
    assert one[0]["kappa"] == hundred[0]["kappa"]
