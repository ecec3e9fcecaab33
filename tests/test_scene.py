import tomllib

import pytest

from gimwatch.cli import main
from gimwatch.errors import SceneError
from gimwatch.simulation.scene import load_scene, parse_scene
from gimwatch.simulation.simulate import Simulation

GOOD = """
robot = "chain:3"
duration = 1.0
sample = 0.1
q = [0.1, 0.2, 0.3]
v = { joint_2 = 0.5 }

[effects.gravity]
vector = [0.0, -9.81, 0.0]

[effects.damping]
coefficient = 0.2

[effects.torque]
law = "sinusoid"
amplitude = 1.0
frequency_hz = 2.0

[integrator]
method = "RK4"
dt = 0.01

[dynamics]
backend = "crba-cholesky"

[watch]
metrics = ["kappa", "diagonal_ratio"]
alarm_threshold = 1e3
on_alarm = "stop"
"""


def test_good_scene_parses_into_frozen_records(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(GOOD)
    scene = load_scene(path)
    assert scene.robot.spec == "chain:3" and not scene.robot.floating
    assert scene.effect_names == ("gravity", "damping", "torque")
    assert scene.integrator.method == "RK4" and scene.integrator.dt == 0.01
    assert scene.backend == "crba-cholesky"
    assert scene.watch.alarm_metric == "kappa" and scene.watch.on_alarm == "stop"
    assert scene.q == (0.1, 0.2, 0.3) and scene.v == {"joint_2": 0.5}
    with pytest.raises(AttributeError):
        scene.duration_s = 2.0
    simulation = Simulation(scene)
    assert simulation.v0.tolist() == [0.0, 0.5, 0.0]


def _edit(old: str, new: str) -> dict:
    assert old in GOOD
    return tomllib.loads(GOOD.replace(old, new, 1))


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("duration = 1.0", "duration = 1.0\ncolour = 3", "s.toml: colour: unknown key"),
        ("duration = 1.0", "duration = -1.0", "s.toml: duration: must be > 0, got -1.0"),
        ("duration = 1.0", 'duration = "long"', "s.toml: duration: must be a number, got 'long'"),
        ("[effects.damping]", "[effects.friction]", "s.toml: effects.friction: unknown effect"),
        (
            "coefficient = 0.2",
            "coefficient = -0.2",
            "effects.damping.coefficient: must be finite and >= 0",
        ),
        ("coefficient = 0.2", "coefficient = 0.2\nk = 1", "s.toml: effects.damping.k: unknown key"),
        (
            "frequency_hz = 2.0",
            "",
            "s.toml: effects.torque.frequency_hz: is required by the 'sinusoid'",
        ),
        (
            "vector = [0.0, -9.81, 0.0]",
            "vector = [0.0, -9.81]",
            "effects.gravity.vector: must be a list of 3 numbers",
        ),
        ('method = "RK4"', 'method = "Euler"', "s.toml: integrator.method: must be one of"),
        (
            "dt = 0.01",
            "rtol = 0.01",
            "s.toml: integrator.dt: is required by the fixed-step method RK4",
        ),
        ("dt = 0.01", "dt = 0.03", "s.toml: sample: must be a whole number of integrator.dt"),
        (
            'backend = "crba-cholesky"',
            'backend = "magic"',
            "s.toml: dynamics.backend: must be one of",
        ),
        (
            '"kappa", "diagonal_ratio"',
            '"kappa", "trace"',
            "s.toml: watch.metrics: unknown metric 'trace'",
        ),
        (
            'on_alarm = "stop"',
            'on_alarm = "panic"',
            "s.toml: watch.on_alarm: must be one of warn, stop",
        ),
        ('robot = "chain:3"', "robot = 3", "s.toml: robot: must be a string or a chain table"),
    ],
)
def test_bad_scene_keys_are_named(old, new, message):
    with pytest.raises(SceneError) as info:
        parse_scene(_edit(old, new), source="s.toml")
    assert message in str(info.value), str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "q = [0.1, 0.2, 0.3]",
            "q = [0.1, 0.2]",
            "s.toml: q: must have 3 values (q-coordinates of chain_3), got 2",
        ),
        (
            "v = { joint_2 = 0.5 }",
            "v = { elbow = 0.5 }",
            "s.toml: v.elbow: unknown joint; chain_3 has joint_1",
        ),
        (
            "[effects.gravity]",
            '[effects.wrench]\nlink = "hand"\n[effects.gravity]',
            "s.toml: effects.wrench.link: unknown link 'hand'",
        ),
        ('robot = "chain:3"', 'robot = "chain:0"', "s.toml: robot: the number of links must be"),
        ('robot = "chain:3"', 'robot = "nope.urdf"', "s.toml: robot: nope.urdf: no such file"),
    ],
)
def test_errors_needing_the_robot_are_named_when_the_simulation_is_built(old, new, message):
    scene = parse_scene(_edit(old, new), source="s.toml")
    with pytest.raises(SceneError) as info:
        Simulation(scene)
    assert message in str(info.value), str(info.value)


def test_relative_urdf_paths_resolve_against_the_scene_folder(tmp_path):
    from gimwatch.model.chains import chain_spec, write_chain_urdf

    (tmp_path / "robots").mkdir()
    write_chain_urdf(chain_spec(2), tmp_path / "robots" / "two.urdf")
    path = tmp_path / "s.toml"
    path.write_text('robot = "robots/two.urdf"\nduration = 0.1\nsample = 0.05\n')
    assert Simulation(load_scene(path)).robot.nv == 2


def test_cli_rejects_a_bad_scene_in_one_line_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace("q = [0.1, 0.2, 0.3]", "q = [0.1, 0.2]"))
    out = tmp_path / "out"
    code = main(["simulate", str(path), "-o", str(out)])
    _, err = capsys.readouterr()
    assert code == 2
    assert (
        err == f"gimwatch: error: {path}: q: must have 3 values (q-coordinates of chain_3), got 2\n"
    )
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_missing_and_malformed_files(tmp_path):
    with pytest.raises(SceneError, match=r"none\.toml: no such file"):
        load_scene(tmp_path / "none.toml")
    (tmp_path / "x.toml").write_text("robot = [")
    with pytest.raises(SceneError, match="is not valid TOML"):
        load_scene(tmp_path / "x.toml")
