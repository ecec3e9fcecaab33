"""The watch follows the stability margin h/h* and alarms when it crosses 1 (issue 36)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from mujoco_divergence import diverges, load

from gimwatch.errors import InputError
from gimwatch.metrics.registry import METRICS
from gimwatch.model.robots import load_robot
from gimwatch.stability import stability
from gimwatch.watch import Watch

ARMS = Path(__file__).parent / "data" / "mjcf" / "servo_arms"


def _euler_arm(tmp_path) -> Path:
    """general_arm under MuJoCo's default Euler: 100 times past its h* at 2 ms."""
    path = tmp_path / "euler_arm.xml"
    path.write_text((ARMS / "general_arm.xml").read_text().replace("implicitfast", "Euler"))
    return path


@pytest.mark.parametrize("arm", ["ur5e", "geared_arm", "euler_arm"])
def test_margin_along_a_path_is_the_records_and_mujocos_verdict(arm, tmp_path):
    path = _euler_arm(tmp_path) if arm == "euler_arm" else ARMS / f"{arm}.xml"
    robot = load_robot(str(path))
    model = load(str(path))
    qs = model.key_qpos[0] + np.outer(np.linspace(0.0, 0.3, 3), np.ones(robot.nq))
    watch = Watch(
        robot,
        ("stability_margin",),
        alarm_metric="stability_margin",
        alarm_threshold=1.0,
        warn=False,
    )
    for k, q in enumerate(qs):
        watch.sample(0.1 * k, q)
    records = stability(robot, qs)  # gravity in, as the watch
    margins = [r.margin for r in records]
    assert watch.series["stability_margin"] == pytest.approx(margins, rel=1e-6)
    # at keyframe 0 with gravity off, MuJoCo's own run agrees with margin < 1
    (flat,) = stability(robot, gravity=False)
    assert (flat.margin > 1) == diverges(model)
    assert bool(watch.alarms) == (max(margins) > 1)
    assert bool(watch.alarms) == (arm == "euler_arm")


def test_the_metric_is_refused_without_an_mjcf_robot():
    assert "stability_margin" in METRICS
    watch = Watch(load_robot("ur5"), ("stability_margin",))
    with warnings.catch_warnings(), pytest.raises(InputError, match="stability_margin"):
        watch.sample(0.0, np.zeros(6))
