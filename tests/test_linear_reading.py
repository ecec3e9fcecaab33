"""Every reader of user files answers hostile text with a load or a one-line refusal, never a
hang or a crash: MJCF through load_robot, URDF through the MuJoCo peer of crosscheck, scenes
through tomllib (tests/test_real_files.py covers load_robot and DeNOC on URDF).

Each case runs in a child process with a generous bound (300 s; each takes under a second):
a super-linear step would take minutes or hours at these sizes, a crash kills the child.
The cost per byte is measured by ``benchmarks/linear_reading.py``, not here.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from real_shapes import arm

MJCF = (
    '<mujoco model="m"><worldbody><body name="a"><joint name="j" type="hinge" axis="0 0 1"/>'
    '<geom type="capsule" size="0.05" fromto="0 0 0 1 0 0" mass="1"/></body></worldbody>'
    "</mujoco>\n"
)
URDF = arm().split("?>", 1)[1]

MJCF_CASES = {
    "100k_leading_comments": "<!-- c -->\n" * 100_000 + MJCF,
    "10MB_comment": "<!--" + "x" * 10_000_000 + "-->\n" + MJCF,
    "unclosed_comments": MJCF.replace("</mujoco>", "<!-- " * 200_000 + "</mujoco>"),
    "nested_declarations": "<?xml version='1.0'?>" + "<?pi x?>" * 100_000 + MJCF,
    "deep_elements": MJCF.replace("</mujoco>", "<a>" * 50_000 + "</a>" * 50_000 + "</mujoco>"),
    "deep_bodies": MJCF.replace(
        "</worldbody>", "<body>" * 5000 + "</body>" * 5000 + "</worldbody>"
    ),
    "long_number": MJCF.replace('mass="1"', 'mass="' + "1" * 60_000 + 'x"'),
}
#: Texts load_robot reads (and refuses nothing of): the MuJoCo peer then compiles them.
PEER_CASES = {
    "100k_leading_comments": "<!-- c -->\n" * 100_000 + URDF,
    "10MB_comment": "<!--" + "x" * 10_000_000 + "-->\n" + URDF,
    "comment_naming_robot": "<!--" + " <robot" * 100_000 + " -->\n" + URDF,
    "nested_declarations": "<?xml version='1.0'?>" + "<?pi x?>" * 100_000 + URDF,
}
SCENE_CASES = {
    "deep_arrays": "robot = 'chain:4'\nq = " + "[" * 400_000 + "]" * 400_000 + "\n",
    "deep_inline_tables": "q = " + "{a=" * 100_000 + "1" + "}" * 100_000 + "\n",
    "long_dotted_key": "a" + ".a" * 400_000 + " = 1\n",
    "long_quoted_dotted_key": '"a"' + '."a"' * 200_000 + " = 1\n",
    "many_short_dotted_keys": ("a." * 63 + "a = 1\n") * 7000,
    "long_integer": "duration = " + "1" * 900_000 + "\n",
    "100k_comments": "# c\n" * 100_000 + "robot = 'chain:4'\n",
    "unclosed_strings": '"""' * 300_000,
}

_RUN = """
import sys, time, warnings
warnings.simplefilter("ignore")
from gimwatch.errors import GimwatchError
kind, path = sys.argv[1], sys.argv[2]
def run():
    if kind == "scene":
        from gimwatch.simulation.scene import load_scene
        load_scene(path)
        return
    from gimwatch.model.robots import load_robot
    robot = load_robot(path)
    if kind == "peer":
        from gimwatch.model.mujoco_model import compile_robot
        compile_robot(robot)
try:
    run()
    print("loaded")
except GimwatchError as exc:
    print("refused:", str(exc).splitlines()[0])
"""


def _answer(kind: str, path) -> str:
    done = subprocess.run(
        [sys.executable, "-c", _RUN, kind, str(path)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]  # no traceback, no crash
    lines = done.stdout.splitlines()
    assert len(lines) == 1, done.stdout[-2000:]
    return lines[0]


@pytest.mark.parametrize("case", sorted(MJCF_CASES))
def test_the_mjcf_loader_answers_hostile_text(case, tmp_path):
    path = tmp_path / f"{case}.xml"
    path.write_text(MJCF_CASES[case], encoding="utf-8")
    answer = _answer("robot", path)
    if case in ("100k_leading_comments", "10MB_comment", "nested_declarations"):
        assert answer == "loaded"
    else:
        assert answer.startswith(f"refused: {path}"), answer


@pytest.mark.parametrize("case", sorted(PEER_CASES))
def test_the_mujoco_peer_compiles_what_load_robot_read(case, tmp_path):
    path = tmp_path / f"{case}.urdf"
    path.write_text(PEER_CASES[case], encoding="utf-8")
    assert _answer("peer", path) == "loaded"


@pytest.mark.parametrize("case", sorted(SCENE_CASES))
def test_the_scene_reader_answers_hostile_toml(case, tmp_path):
    path = tmp_path / f"{case}.toml"
    path.write_text(SCENE_CASES[case], encoding="utf-8")
    assert path.stat().st_size < 1024 * 1024  # under the size cap: the parser reads it all
    answer = _answer("scene", path)
    assert answer.startswith(f"refused: {path}"), answer
    if "dotted" in case:
        assert ("more than 64 parts" in answer) == (case != "many_short_dotted_keys"), answer
    if case.startswith("deep"):
        assert "nested too deeply" in answer


def test_a_scene_with_a_few_dotted_keys_is_read(tmp_path):
    path = tmp_path / "dotted.toml"
    path.write_text(
        "robot = 'chain:4'\nduration = 0.1\nsample = 0.01\nwatch.metrics = ['kappa']\n",
        encoding="utf-8",
    )
    assert _answer("scene", path) == "loaded"
