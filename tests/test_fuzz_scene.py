"""Hypothesis mutation of a valid scene: every outcome is a result or a GimwatchError.

The seed is a small ``chain:3`` scene (0.05 s) that declares every effect and watches
scalar and vector metrics. Mutations work on the TOML text, line by line: drop a line,
duplicate it (a duplicate key is a TOML error), move it under another table, rename its
key, or give it a hostile value (wrong type, sign, size, NaN, another key's value). Each
mutated scene is loaded, built, run and written; anything but a :class:`GimwatchError` or
a complete run fails the test. A run that goes on past a step budget (e.g. a mutation
made the duration 1e12 s) is interrupted the way Ctrl-C would, and must come back as an
``interrupted`` trajectory that can still be written.
"""

from __future__ import annotations

import json
import re
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gimwatch.errors import GimwatchError
from gimwatch.simulation.results_folder import write_simulation
from gimwatch.simulation.scene import load_scene
from gimwatch.simulation.simulate import STATUSES, Simulation

SEED_SCENE = """robot = "chain:3"
duration = 0.05
sample = 0.01
q = [0.1, -0.2, 0.3]
v = { joint_1 = 0.5 }

[effects.gravity]
vector = [0.0, -9.81, 0.0]

[effects.damping]
coefficient = 0.1

[effects.spring]
stiffness = [1.0, 2.0, 3.0]
rest = 0.05

[effects.torque]
law = "sinusoid"
amplitude = 0.5
frequency_hz = 2.0

[effects.wrench]
link = "link_3"
force = [0.0, 1.0, 0.0]
frame = "local"

[integrator]
method = "DOP853"
rtol = 1e-8
atol = 1e-8

[dynamics]
backend = "aba"

[watch]
metrics = ["kappa", "diagonal_ratio", "pivot_ratio_forward", "eigenvalues"]
alarm_metric = "kappa"
alarm_threshold = 50.0
on_alarm = "warn"
"""
LINES = SEED_SCENE.splitlines()
TABLES = [line for line in LINES if line.startswith("[")]
KEYS = sorted({line.split("=")[0].strip() for line in LINES if "=" in line})
HOSTILE_VALUES = [
    "0",
    "-1",
    "-0.01",
    "1e-9",
    "1e12",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "-inf",
    "true",
    '""',
    '"x"',
    '"chain:0"',
    '"chain:3"',
    '"RK4"',
    '"RK45"',
    '"semi-implicit-euler"',
    '"crba-cholesky"',
    '"denoc"',
    '"stop"',
    '"floating"',
    '"link_1"',
    '"base_link"',
    '"pd"',
    '"constant"',
    "[]",
    "[1.0]",
    "[1.0, 2.0, 3.0]",
    "[1.0, 2.0, 3.0, 4.0]",
    '["kappa", "kappa"]',
    '["rcond"]',
    "{}",
    "{ joint_9 = 1.0 }",
    "{ joint_2 = -1.0 }",
    "{ n = 3 }",
    "0.001",
    "0.05",
    "5",
]
#: Right-hand-side steps after which a run is interrupted (like Ctrl-C) instead of left to
#: run: the seed needs a few dozen; a mutated duration may ask for millions.
STEP_BUDGET = 3000


@st.composite
def mutated_scene(draw) -> str:
    """The seed scene with one to three line mutations."""
    lines = list(LINES)
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, len(lines) - 1))
        kind = draw(st.sampled_from(["drop", "duplicate", "move", "rename", "value", "table"]))
        line = lines[i]
        if kind == "drop":
            del lines[i]
        elif kind == "duplicate":
            lines.insert(draw(st.integers(0, len(lines))), line)
        elif kind == "move":
            del lines[i]
            lines.insert(draw(st.integers(0, len(lines))), line)
        elif kind == "table":
            lines.insert(i, draw(st.sampled_from([*TABLES, "[effects.friction]", "[watch.x]"])))
        elif "=" in line:
            key, value = (part.strip() for part in line.split("=", 1))
            if kind == "rename":
                key = draw(st.sampled_from([*KEYS, "colour", "dt", "max_step", "base"]))
            else:
                value = draw(st.sampled_from(HOSTILE_VALUES))
            lines[i] = f"{key} = {value}"
    return "\n".join(lines) + "\n"


def _outcome(text: str, folder: Path) -> str:
    """Load, build, run and write one scene; the error text, or the run's status."""
    path = folder / "scene.toml"
    path.write_text(text)
    try:
        simulation = Simulation(load_scene(path))
    except GimwatchError as exc:
        assert str(exc) and "\n" not in str(exc)
        return "error"
    calls = 0

    def budget(_: float) -> None:
        nonlocal calls
        calls += 1
        if calls > STEP_BUDGET:
            raise KeyboardInterrupt

    trajectory = simulation.run(progress=budget)
    assert trajectory.status in STATUSES
    assert trajectory.t.size >= 1 and np.all(np.diff(trajectory.t) > 0)
    assert trajectory.q.shape == (trajectory.t.size, simulation.robot.nq)
    assert trajectory.status != "completed" or np.isclose(
        trajectory.t[-1],
        np.floor(simulation.scene.duration_s / simulation.scene.sample_s + 1e-9)
        * simulation.scene.sample_s,
    )
    out = write_simulation(trajectory, folder / "out", plots=False)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == trajectory.status
    assert summary["samples"] == trajectory.t.size
    return trajectory.status


SETTINGS = settings(
    derandomize=True,
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


@SETTINGS
@given(text=mutated_scene())
def test_mutated_scene_is_a_result_or_a_gimwatch_error(text):
    with tempfile.TemporaryDirectory() as tmp:
        _outcome(text, Path(tmp))


def test_the_seed_scene_runs_to_the_end_with_every_effect(tmp_path):
    """The control of the fuzz test: unmutated, the seed completes and declares everything."""
    assert _outcome(SEED_SCENE, tmp_path) == "completed"
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["effects"] == ["gravity", "damping", "spring", "torque", "wrench"]
    assert summary["samples"] == 6


def test_the_mutations_reach_both_outcomes():
    """Hypothesis' examples include valid scenes and several distinct errors."""
    seen: dict[str, int] = {}

    @settings(derandomize=True, max_examples=60, deadline=None, database=None)
    @given(text=mutated_scene())
    def collect(text):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "scene.toml"
            path.write_text(text)
            try:
                load_scene(path)
                kind = "valid"
            except GimwatchError as exc:
                kind = re.sub(r"^.*?scene\.toml: ", "", str(exc)).split(":")[0]
            seen[kind] = seen.get(kind, 0) + 1

    collect()
    assert seen.get("valid", 0) >= 3, seen
    assert len(seen) >= 8, seen
