"""Hypothesis mutation of valid URDFs: every outcome is a result or a GimwatchError.

Mutations drop, duplicate, move or rename elements, drop attributes, give them hostile
values, and truncate the text. A second property checks that the validation in
``gimwatch/model/urdf_text.py`` is complete: whatever it lets through, Pinocchio's parser (urdfdom)
builds without complaint, so no urdfdom message ever reaches the user.
"""

from __future__ import annotations

import copy
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gimwatch.errors import GimwatchError
from gimwatch.metrics.dense_analysis import analyze_configuration
from gimwatch.model.chains import chain_spec, generate_chain_urdf
from gimwatch.model.example_robots import example_robot_urdf
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot, neutral_configuration

SEEDS = {
    "chain": generate_chain_urdf(chain_spec(3, axes="spatial", joint_types="revolute")),
    "two_link": (
        Path(__file__).parent / "data" / "bad" / "urdf" / "inertia_triangle_inequality.urdf"
    )
    .read_text()
    .replace('ixx="0.001" ixy="0" ixz="0" iyy="0.001"', 'ixx="0.084" ixy="0" ixz="0" iyy="0.084"'),
    "ur5": example_robot_urdf("ur5").read_text(),
}
HOSTILE_VALUES = [
    "",
    " ",
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "1e400",
    "1e-320",
    "abc",
    "1 2",
    "0 0 0",
    "1 2 3 4",
    "1,2,3",
    "0x10",
    "1_0",
    "base_link",
    "world",
    "revolute",
    "prismatic",
    "continuous",
    "fixed",
    "planar",
    "floating",
    "-0",
    "+1",
    ".5",
    "5.",
    "1e3",
    "\u00e9",
]
SETTINGS = settings(
    derandomize=True,
    max_examples=200,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@st.composite
def mutated_urdf(draw) -> str:
    """A seed URDF with one to three mutations."""
    root = ET.fromstring(SEEDS[draw(st.sampled_from(sorted(SEEDS)))])
    for _ in range(draw(st.integers(1, 3))):
        pairs = [(parent, child) for parent in root.iter() for child in parent]
        parent, element = draw(st.sampled_from(pairs))
        action = draw(
            st.sampled_from(["drop", "duplicate", "move", "retag", "drop_attr", "set_attr"])
        )
        if action == "drop":
            parent.remove(element)
        elif action == "duplicate":
            parent.insert(list(parent).index(element), copy.deepcopy(element))
        elif action == "move":
            parent.remove(element)
            target = draw(st.sampled_from(list(root.iter())))
            target.append(element)
        elif action == "retag":
            element.tag = draw(st.sampled_from(sorted({e.tag for e in root.iter()})))
        else:
            attributes = sorted(element.attrib)
            if not attributes:
                continue
            name = draw(st.sampled_from(attributes))
            if action == "drop_attr":
                del element.attrib[name]
            else:
                element.set(name, draw(st.sampled_from(HOSTILE_VALUES) | st.text(max_size=8)))
    text = ET.tostring(root, encoding="unicode")
    if draw(st.booleans()) and draw(st.booleans()):
        text = text[: draw(st.integers(0, len(text)))]
    return text


def _outcome(text: str) -> str:
    """Load and analyse; return "ok" or the GimwatchError's message (others propagate)."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.urdf"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        try:
            robot = load_robot(path)
            if robot.nv <= DATA_NV_LIMIT:
                analyze_configuration(robot, neutral_configuration(robot))
        except GimwatchError as exc:
            return str(exc)
    return "ok"


@pytest.mark.filterwarnings("ignore::UserWarning")
@SETTINGS
@given(text=mutated_urdf())
def test_mutated_urdf_gives_a_result_or_a_gimwatch_error(text):
    message = _outcome(text)
    assert "\n" not in message
    # The validation must catch everything urdfdom would complain about.
    assert "Pinocchio cannot build a model" not in message, message


def test_the_seeds_are_valid():
    for text in SEEDS.values():
        assert _outcome(text) == "ok"
