"""Hostile input, fourth round (issue 40, the MuJoCo/MJCF side and the command line).

Each case gives one ``gimwatch: error:`` line and exit 2, or a correct result checked against
an independent reference (MuJoCo's ``mj_fullM``, Python's ``float``); never a traceback.
"""

from __future__ import annotations

import argparse

import pytest

from gimwatch.cli import COMMANDS, UsageError, get_argument_parser, main


def _run(argv: list[str], capture) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capture.readouterr()
    return code, out, err


def _one_error(code: int, out: str, err: str, *fragments: str) -> None:
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and err.startswith("gimwatch: error: "), err
    assert "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)


# --- every numeric option reads every float literal NumPy prints --------------------------


def _subparser(command: str) -> argparse.ArgumentParser:
    parser = get_argument_parser(command)
    (commands,) = (a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return commands.choices[command]


def _numeric_options() -> list[tuple[str, argparse.Action]]:
    cases = []
    for command in COMMANDS:
        for action in _subparser(command)._actions:
            if action.option_strings and action.type not in (None, str):
                cases.append((command, action.option_strings[-1]))
    return cases


def _filler(command: str, skip: str) -> list[str]:
    """Positionals and required options of ``command`` other than ``skip``, with values."""
    words = []
    for action in _subparser(command)._actions:
        if not action.option_strings:
            if action.nargs not in ("*", "?", argparse.PARSER):
                words.append("2")
        elif action.required and action.option_strings[-1] != skip:
            words += [action.option_strings[-1], "10"]
    for group in _subparser(command)._mutually_exclusive_groups:  # one of them is required
        options = [a.option_strings[-1] for a in group._group_actions]
        if group.required and skip not in options:
            words += [options[0], "10"]
    return words


NUMERIC = _numeric_options()


def test_the_commands_have_numeric_options():
    """The parametrised test below covers something: the options the issue names."""
    names = {(command, option) for command, option in NUMERIC}
    assert {("analyze", "--q"), ("map", "--range"), ("armature", "--target")} <= names
    assert len(NUMERIC) >= 20


@pytest.mark.parametrize("literal", ["-1e-05", "-1E+3", "-.5e-2", "-1.e-3", "-inf", "-1e-05,2"])
@pytest.mark.parametrize(("command", "option"), NUMERIC)
def test_a_negative_float_literal_is_a_value_not_an_option(command, option, literal):
    """argparse reads the literal as the option's value: parsed as Python's float reads it,
    or refused by the option's own type check, which quotes it; never "unrecognized"."""
    sub = _subparser(command)
    (action,) = (a for a in sub._actions if option in a.option_strings)
    count = action.nargs if isinstance(action.nargs, int) else 2 if action.nargs == "+" else 1
    words = ["0.5"] * (count - 1) + [literal]
    argv = [command, *_filler(command, option), option, *words]
    try:
        args = get_argument_parser(command).parse_args(argv)
    except UsageError as exc:
        message = str(exc)
        assert "unrecognized" not in message and "expected" not in message, message
        assert literal in message, message
        return
    value = getattr(args, action.dest)
    expected = [float(x) for x in literal.split(",")]
    if action.nargs is None and isinstance(value, list):  # one comma-separated list
        assert value == expected
    else:
        last = value[-1] if isinstance(value, list) else value
        assert last == expected[0]


@pytest.mark.parametrize("q", [["0.1", "-1e-05"], ["-1e-3", "2.5E-1"]])
def test_analyze_reads_numpy_printed_q(q, capsys):
    code, out, err = _run(["analyze", "chain:2", "--q", *q, "--json"], capsys)
    assert code == 0 and err == "", err
    import json

    import numpy as np

    from gimwatch.metrics.conditioning import condition_number
    from gimwatch.model.robots import load_robot

    robot = load_robot("chain:2")
    q_float = np.array([float(x) for x in q])
    import pinocchio as pin

    M = pin.crba(robot.model, robot.model.createData(), q_float)
    M = np.triu(M) + np.triu(M, 1).T
    record = json.loads(out)["configurations"][0]
    assert record["q"] == [float(x) for x in q]
    assert record["kappa"] == pytest.approx(condition_number(M), rel=1e-12)


# --- M from MuJoCo without mj_forward: a self-colliding flex in a tiny arena ---------------

#: A 5 x 5 cloth (75 slide DoFs) whose self-collision overflows a 20 KB arena at random poses.
FLEX_MJCF = """<mujoco model="flexself">
  <size memory="{memory}"/>
  <worldbody>
    <flexcomp name="cloth" type="grid" count="5 5 1" spacing="0.05 0.05 0.05" radius="0.01"
              dim="2" mass="1">
      <contact selfcollide="bvh"/>
      <edge equality="false"/>
    </flexcomp>
  </worldbody>
</mujoco>
"""


def _random_qpos(mj_model, seed: int):
    import numpy as np

    rng = np.random.default_rng(seed)
    return mj_model.qpos0 + rng.uniform(-0.05, 0.05, mj_model.nq)


def test_mujoco_m_of_a_self_colliding_flex_needs_no_collision(tmp_path):
    """mj_forward fails (arena overflow in the collision stage); gimwatch's M does not, and
    equals mj_fullM after mj_forward on the same model given a large arena."""
    import mujoco
    import numpy as np

    from gimwatch.model.mujoco_model import mass_matrix

    small = mujoco.MjModel.from_xml_string(FLEX_MJCF.format(memory="20K"))
    large = mujoco.MjModel.from_xml_string(FLEX_MJCF.format(memory="50M"))
    qpos = _random_qpos(small, 0)
    data = mujoco.MjData(small)
    data.qpos[:] = qpos
    with pytest.raises(mujoco.FatalError, match="out of memory"):
        mujoco.mj_forward(small, data)  # the control: the failure the issue reports
    reference = mujoco.MjData(large)
    reference.qpos[:] = qpos
    mujoco.mj_forward(large, reference)
    expected = np.zeros((large.nv, large.nv))
    mujoco.mj_fullM(large, reference, expected)
    assert small.nv == 75
    np.testing.assert_array_equal(mass_matrix(small, qpos), expected)


def test_crosscheck_of_a_self_colliding_flex_has_no_traceback(tmp_path, capfd):
    path = tmp_path / "flex.xml"
    path.write_text(FLEX_MJCF.format(memory="20K"))
    code, out, err = _run(["crosscheck", str(path), "--peer", "mujoco", "--samples", "3"], capfd)
    assert "Traceback" not in err and code == 0, err
    assert "1/1 passed" in out + err


def test_mujoco_m_with_tendon_and_actuator_armature_equals_mj_forward(tmp_path):
    """The stages gimwatch runs (tendon, transmission, makeM) give mj_forward's M exactly
    when tendons and actuators add armature to M."""
    import mujoco
    import numpy as np

    from gimwatch.model.mujoco_model import mass_matrix

    xml = """<mujoco><worldbody>
      <body><joint name="j1" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -1" size=".05"/>
        <body pos="0 0 -1"><joint name="j2" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -1" size=".05"/></body></body></worldbody>
      <tendon><fixed armature="0.3"><joint joint="j1" coef="1"/><joint joint="j2" coef="-0.5"/>
      </fixed></tendon>
      <actuator><motor joint="j2" armature="0.7" gear="2"/></actuator></mujoco>"""
    mj_model = mujoco.MjModel.from_xml_string(xml)
    qpos = np.array([0.3, -0.7])
    data = mujoco.MjData(mj_model)
    data.qpos[:] = qpos
    mujoco.mj_forward(mj_model, data)
    expected = np.zeros((2, 2))
    mujoco.mj_fullM(mj_model, data, expected)
    np.testing.assert_array_equal(mass_matrix(mj_model, qpos), expected)


def test_a_mujoco_failure_computing_m_is_one_line(tmp_path, monkeypatch):
    import mujoco

    from gimwatch.errors import RobotError
    from gimwatch.model import mujoco_model

    def fail(*args):
        raise mujoco.FatalError("mj_stackAlloc: out of memory\\n  max = 1")

    monkeypatch.setattr(mujoco, "mj_makeM", fail)
    small = mujoco.MjModel.from_xml_string(FLEX_MJCF.format(memory="20K"))
    with pytest.raises(RobotError, match=r"robot 'flex.xml': MuJoCo fails computing M: mj_stack"):
        mujoco_model.mass_matrix(small, small.qpos0, spec="flex.xml")


# --- MuJoCo's compile bounded in time and memory; includes that are not files ---------------

#: 296 bytes that MuJoCo expands into 64,000 free bodies, parsed for minutes.
REPLICATED_MJCF = """<mujoco>
  <worldbody>
    <replicate count="40" euler="0 0 0.1">
      <replicate count="40" offset="0.1 0 0">
        <replicate count="40" offset="0 0.1 0">
          <body><freejoint/><geom size=".01"/></body>
        </replicate>
      </replicate>
    </replicate>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def private_tmp(tmp_path, monkeypatch):
    """tempfile's folder, to see that a compile leaves nothing behind."""
    import tempfile

    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    return folder


def test_an_expanding_replicate_is_stopped_at_the_time_bound(
    tmp_path, private_tmp, monkeypatch, capfd
):
    import time

    path = tmp_path / "replicate.xml"
    path.write_text(REPLICATED_MJCF)
    assert path.stat().st_size < 400
    monkeypatch.setenv("GIMWATCH_MJCF_SECONDS", "1.5")
    start = time.monotonic()
    code, out, err = _run(["analyze", str(path)], capfd)
    assert time.monotonic() - start < 15
    _one_error(code, out, err, str(path), "ran past 1.5 s", "GIMWATCH_MJCF_SECONDS")
    assert list(private_tmp.iterdir()) == []


def test_an_expanding_replicate_is_stopped_at_the_memory_bound(
    tmp_path, private_tmp, monkeypatch, capfd
):
    path = tmp_path / "replicate.xml"
    path.write_text(REPLICATED_MJCF)
    monkeypatch.setenv("GIMWATCH_MJCF_MEMORY_MB", "64")
    monkeypatch.setenv("GIMWATCH_MJCF_SECONDS", "30")
    code, out, err = _run(["analyze", str(path)], capfd)
    _one_error(code, out, err, str(path), "memory bound of 64 MiB", "GIMWATCH_MJCF_MEMORY_MB")
    assert list(private_tmp.iterdir()) == []


def test_a_compiled_body_count_is_held_to_the_link_budget(tmp_path, monkeypatch, capfd):
    path = tmp_path / "replicate.xml"
    path.write_text(
        '<mujoco><worldbody><replicate count="60" offset="0.1 0 0">'
        '<body><joint/><geom size=".01"/></body></replicate></worldbody></mujoco>'
    )
    monkeypatch.setenv("GIMWATCH_MAX_LINKS", "50")
    code, out, err = _run(["analyze", str(path)], capfd)
    _one_error(code, out, err, str(path), "compiles to 60 bodies", "GIMWATCH_MAX_LINKS")


def test_a_compiled_model_equals_mujocos_own_compile(tmp_path, private_tmp):
    """The child's MJB round trip changes nothing: same nv and M as MuJoCo in-process."""
    import mujoco
    import numpy as np

    from gimwatch.model.mjcf_compiled import compile_mjcf
    from gimwatch.model.mujoco_model import mass_matrix

    path = tmp_path / "flex.xml"
    path.write_text(FLEX_MJCF.format(memory="20K"))
    ours = compile_mjcf(str(path))
    theirs = mujoco.MjModel.from_xml_path(str(path))
    qpos = _random_qpos(theirs, 1)
    assert ours.nv == theirs.nv == 75
    np.testing.assert_array_equal(mass_matrix(ours, qpos), mass_matrix(theirs, qpos))
    assert list(private_tmp.iterdir()) == []


def test_a_mujoco_refusal_from_the_child_is_mujocos_line(tmp_path, capfd):
    path = tmp_path / "bad.xml"
    path.write_text('<mujoco><worldbody><body><joint type="bogus"/></body></worldbody></mujoco>')
    code, out, err = _run(["analyze", str(path)], capfd)
    _one_error(code, out, err, str(path), "MuJoCo refuses this MJCF", "bogus")


def test_an_include_naming_a_fifo_is_refused_before_it_is_opened(tmp_path, monkeypatch, capfd):
    import os
    import time

    os.mkfifo(tmp_path / "fifo")
    path = tmp_path / "robot.xml"
    path.write_text(
        '<mujoco><include file="fifo"/><worldbody><body><joint/><geom size=".1"/></body>'
        "</worldbody></mujoco>"
    )
    monkeypatch.setenv("GIMWATCH_MJCF_SECONDS", "20")
    start = time.monotonic()
    code, out, err = _run(["analyze", str(path)], capfd)
    assert time.monotonic() - start < 10  # refused, not waited for until the time bound
    _one_error(code, out, err, str(path), "'fifo'", "not a regular file")


# --- armature: a file's own free joint, no configurations, a bad margin, the K·nv² budget ----

FREE_BODY_MJCF = """<mujoco><worldbody>
  <body name="base"><freejoint name="float"/><geom size=".1" mass="2"/>
    <body pos="0 0 -.5"><joint name="hinge" axis="0 1 0"/><geom size=".05" mass="1"/></body>
  </body></worldbody></mujoco>"""


def test_armature_refuses_an_mjcf_files_own_free_joint(tmp_path, capfd):
    path = tmp_path / "free.xml"
    path.write_text(FREE_BODY_MJCF)
    code, out, err = _run(["armature", str(path), "--target", "5"], capfd)
    _one_error(code, out, err, "joint 'float'", "not a free joint")


@pytest.mark.parametrize(
    ("configurations", "target", "margin", "fragment"),
    [
        ("none", 10.0, 1e-9, "at least one configuration"),
        ("one", 10.0, -0.5, "margin must be a finite number >= 0"),
        ("one", 10.0, float("nan"), "margin must be a finite number >= 0"),
        ("one", float("nan"), 1e-9, "target must be a number > 1"),
    ],
)
def test_minimal_armature_refuses_what_gives_no_valid_plan(
    configurations, target, margin, fragment
):
    import numpy as np

    from gimwatch.errors import InputError
    from gimwatch.explain.armature import minimal_armature
    from gimwatch.model.robots import load_robot

    robot = load_robot("chain:3")
    qs = np.zeros((0, 3)) if configurations == "none" else np.full((1, 3), 0.3)
    with pytest.raises(InputError, match=fragment):
        minimal_armature(robot, qs, target, margin=margin)


def test_a_negative_margin_would_miss_the_target():
    """The control of the refusal above: with the margin at -0.5 the plan's κ after exceeds
    the target (computed from Pinocchio's M + diag(a), NumPy's eigenvalues)."""
    import numpy as np
    import pinocchio as pin

    from gimwatch.model.robots import load_robot

    robot = load_robot("chain:3")
    q = np.full(3, 0.3)
    M = pin.crba(robot.model, robot.model.createData(), q)
    M = np.triu(M) + np.triu(M, 1).T
    w = np.linalg.eigvalsh(M)
    target = 10.0
    a = (w[-1] - target * w[0]) / (target - 1) * (1 - 0.5)
    w_after = np.linalg.eigvalsh(M + a * np.eye(3))
    assert w_after[-1] / w_after[0] > target


def test_armature_samples_beyond_the_matrix_budget_are_refused_before_drawing(capfd):
    from gimwatch.explain.armature import MAX_MATRIX_BYTES, max_configurations

    assert max_configurations(200) == MAX_MATRIX_BYTES // (8 * 200 * 200) == 3355
    code, out, err = _run(
        ["armature", "chain:200", "--target", "1e4", "--samples", "100000"], capfd
    )
    _one_error(code, out, err, "--samples must be at most 3355", "1024 MiB budget", "100000")


def test_minimal_armature_refuses_more_configurations_than_fit():
    import numpy as np

    from gimwatch.errors import InputError
    from gimwatch.explain.armature import max_configurations, minimal_armature
    from gimwatch.model.robots import load_robot

    robot = load_robot("chain:200")
    qs = np.zeros((max_configurations(200) + 1, 200))
    with pytest.raises(InputError, match="at most 3355 for nv = 200"):
        minimal_armature(robot, qs, 1e4)


# --- Watch.from_mujoco(robot=...): joint types must match, not only names -----------------


def test_from_mujoco_refuses_a_slide_for_a_hinge_of_the_same_name():
    import mujoco

    from gimwatch.errors import InputError
    from gimwatch.model.robots import load_robot
    from gimwatch.watch import Watch

    robot = load_robot("chain:2")  # joints joint_1, joint_2: revolute
    xml = """<mujoco><worldbody>
      <body><joint name="joint_1" type="slide" axis="1 0 0"/><geom size=".1"/>
        <body pos="0 0 -1"><joint name="joint_2" axis="0 1 0"/><geom size=".1"/></body>
      </body></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    with pytest.raises(
        InputError, match=r"joint 'joint_1' must be a MuJoCo hinge joint .* got 'slide'"
    ):
        Watch.from_mujoco(model, data, robot=robot)
    hinge = mujoco.MjModel.from_xml_string(xml.replace('type="slide" axis="1 0 0"', 'axis="0 1 0"'))
    Watch.from_mujoco(hinge, mujoco.MjData(hinge), robot=robot)  # the control: accepted


# --- network handshakes: silent ports, HTTP servers, malformed URLs ------------------------


@pytest.fixture
def local_server():
    """A TCP server on 127.0.0.1 that stays silent, or answers every connection like HTTP."""
    import socket
    import threading

    servers = []

    def start(answer: bytes | None) -> str:
        listener = socket.socket()
        listener.bind(("127.0.0.1", 0))
        listener.listen(8)
        accepted = []

        def serve():
            while True:
                try:
                    conn, _ = listener.accept()
                except OSError:
                    return
                accepted.append(conn)
                if answer is not None:
                    conn.sendall(answer)

        threading.Thread(target=serve, daemon=True).start()
        servers.append((listener, accepted))
        return f"tcp://127.0.0.1:{listener.getsockname()[1]}"

    yield start
    for listener, accepted in servers:
        listener.close()
        for conn in accepted:
            conn.close()


HTTP_ANSWER = b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nok"


@pytest.mark.parametrize(
    ("answer", "fragment"),
    [(None, "no Dask handshake within 1 s"), (HTTP_ANSWER, "not a Dask scheduler")],
)
@pytest.mark.parametrize("command", ["survey", "map"])
def test_a_scheduler_address_that_is_no_scheduler_is_one_line(
    command, answer, fragment, local_server, monkeypatch, tmp_path, capfd
):
    import time

    from gimwatch.survey import scheduler_address

    monkeypatch.setattr(scheduler_address, "HANDSHAKE_SECONDS", 1.0)
    address = local_server(answer)
    argv = {
        "survey": ["survey", "chain:2", "--samples", "4"],
        "map": ["map", "chain:2", "--joints", "joint_1", "joint_2", "--grid", "3"],
    }[command] + ["--scheduler", address, "-o", str(tmp_path / "out")]
    start = time.monotonic()
    code, out, err = _run(argv, capfd)
    assert time.monotonic() - start < 30
    _one_error(code, out, err, address, fragment)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "address", ["tcp://[::1", "tcp://host:99999", "tcp://h:1/x?y#z", "http//x"]
)
def test_a_malformed_scheduler_url_is_one_line(address, capfd):
    code, out, err = _run(["survey", "chain:2", "--samples", "4", "--scheduler", address], capfd)
    _one_error(code, out, err, "--scheduler must be", repr(address))


def test_a_real_dask_scheduler_passes_the_probe():
    """The control: a Dask scheduler's first frame is read as a handshake and accepted."""
    distributed = pytest.importorskip("distributed")

    from gimwatch.survey.scheduler_address import probe_scheduler

    with distributed.LocalCluster(
        n_workers=0, processes=False, dashboard_address=None, protocol="tcp"
    ) as cluster:
        probe_scheduler(cluster.scheduler_address, seconds=10)


# --- library calls with malformed ranges; map --workers capped as survey --------------------


@pytest.mark.parametrize(
    ("keyword", "value", "fragment"),
    [
        ("ranges", [(0, 1)], "two (lower, upper) pairs"),
        ("ranges", [(0, 1, 2), (0, 1)], "ranges must be numbers"),
        ("ranges", [("a", 1), (0, 1)], "ranges must be numbers"),
        ("ranges", 3.0, "two (lower, upper) pairs"),
        ("ranges", [(float("nan"), 1), (0, 1)], "finite lower < upper"),
        ("q", ["a", "b", "c"], "q must be numbers"),
        ("ranges", [(-1e308, 1e308), (0, 1)], "span upper - lower below 1.8e308"),
    ],
)
def test_conditioning_map_refuses_malformed_input_in_one_line(keyword, value, fragment):
    from gimwatch.errors import InputError
    from gimwatch.explain.maps import conditioning_map

    with pytest.raises(InputError, match=fragment.replace("(", r"\(").replace(")", r"\)")):
        conditioning_map("chain:3", ["joint_1", "joint_2"], grid=3, **{keyword: value})


def test_map_workers_are_capped_as_survey_caps_them(monkeypatch, tmp_path, capfd):
    monkeypatch.setenv("GIMWATCH_MAX_WORKERS", "2")
    argv = ["map", "chain:2", "--joints", "joint_1", "joint_2", "--grid", "3"]
    code, out, err = _run([*argv, "--workers", "64", "-o", str(tmp_path / "m")], capfd)
    _one_error(code, out, err, "--workers must be at most 2", "GIMWATCH_MAX_WORKERS", "64")
    assert not (tmp_path / "m").exists()
    code, out, err = _run(
        ["survey", "chain:2", "--workers", "64", "-o", str(tmp_path / "s")], capfd
    )
    _one_error(code, out, err, "--workers must be at most 2")  # the same rule, the same line


# --- trajectory CSVs: the row limit checked while the file streams ---------------------------


def test_the_trajectory_row_limit_is_checked_before_the_file_is_read_whole(tmp_path, monkeypatch):
    """A writer that sends 6 rows and never closes: streamed, the sixth row is refused at
    once (a limit of 5); read whole, the reader would wait for the end of the file."""
    import os
    import threading

    from gimwatch.errors import InputError
    from gimwatch.explain import trajectory

    monkeypatch.setattr(trajectory, "MAX_SAMPLES", 5)
    fifo = tmp_path / "q.csv"
    os.mkfifo(fifo)
    release = threading.Event()

    def write():
        with open(fifo, "w") as stream:
            stream.write("0.1,0.2\n" * 6)
            stream.flush()
            release.wait(30)

    writer = threading.Thread(target=write, daemon=True)
    writer.start()
    outcome = []

    def read():
        try:
            trajectory.read_trajectory_csv(fifo, ["joint_1", "joint_2"])
        except InputError as exc:
            outcome.append(str(exc))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(10)
    refused_while_open = list(outcome)  # before the writer closes the file
    release.set()
    reader.join(10)
    writer.join(10)
    assert refused_while_open and "at most 5 rows" in refused_while_open[0], outcome


def test_a_trajectory_line_too_long_is_refused_as_it_streams(tmp_path):
    from gimwatch.errors import InputError
    from gimwatch.explain.trajectory import MAX_LINE_CHARS, max_columns, read_trajectory_csv

    path = tmp_path / "q.csv"
    path.write_text("0.1,0.2\n" + "1" * 5_000_000 + "\n")
    with pytest.raises(
        InputError, match=rf"q.csv:2 must be a line of at most {max_columns(2) * MAX_LINE_CHARS}"
    ):
        read_trajectory_csv(path, ["joint_1", "joint_2"])


def test_a_streamed_trajectory_equals_numpys_reading(tmp_path):
    """The control: more rows than one block, a header and a time column, read as NumPy does."""
    import numpy as np

    from gimwatch.explain.trajectory import read_trajectory_csv

    rng = np.random.default_rng(3)
    table = rng.normal(size=(70_000, 3))
    path = tmp_path / "q.csv"
    np.savetxt(path, table, delimiter=",", header="t,joint_1,joint_2", comments="")
    time, qs = read_trajectory_csv(path, ["joint_1", "joint_2"])
    expected = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(time, expected[:, 0])
    np.testing.assert_array_equal(qs, expected[:, 1:])


# --- a robot file whose name is not UTF-8 ---------------------------------------------------


@pytest.fixture
def non_utf8_robot(tmp_path):
    """A folder with ok.urdf and rob\\xffot.urdf (the same 3-link chain)."""
    import os

    from gimwatch.model.chains import chain_spec, generate_chain_urdf

    folder = tmp_path / "robots"
    folder.mkdir()
    text = generate_chain_urdf(chain_spec(3))
    (folder / "ok.urdf").write_text(text)
    with open(os.fsencode(folder) + b"/rob\xffot.urdf", "w") as stream:
        stream.write(text)
    return folder, os.fsdecode(os.fsencode(folder) + b"/rob\xffot.urdf")


def test_a_non_utf8_file_name_draws_its_map(non_utf8_robot, tmp_path, capfd):
    _, path = non_utf8_robot
    out_dir = tmp_path / "map"
    argv = ["map", path, "--joints", "joint_1", "joint_2", "--grid", "3", "-o", str(out_dir)]
    code, _out, err = _run(argv, capfd)
    assert code == 0 and "Traceback" not in err, err
    assert (out_dir / "map_kappa.png").stat().st_size > 0


def test_a_non_utf8_file_name_loses_no_survey_batch(non_utf8_robot, tmp_path, capfd):
    import csv

    folder, _ = non_utf8_robot
    out_dir = tmp_path / "survey"
    code, _out, err = _run(["survey", str(folder), "--samples", "5", "-o", str(out_dir)], capfd)
    assert code == 0 and "Traceback" not in err, err
    with open(out_dir / "survey.csv", encoding="utf-8") as stream:
        robots = {row["robot"] for row in csv.DictReader(stream)}
    assert robots == {"ok", "rob\\xffot"}


# --- docs/limits.md states each limit with the code's number -------------------------------


def test_limits_page_states_the_numbers_the_code_holds():
    from pathlib import Path

    from gimwatch.explain import maps, trajectory
    from gimwatch.explain.armature import MAX_MATRIX_BYTES, max_configurations
    from gimwatch.model import mjcf_sandbox
    from gimwatch.model.urdf_text import DEFAULT_MAX_LINKS
    from gimwatch.survey import scheduler_address

    page = (Path(__file__).resolve().parents[1] / "docs/limits.md").read_text(encoding="utf-8")
    section = page[page.index("## MuJoCo's compile, the command line, the network") :]
    expected = [
        f"| {mjcf_sandbox.DEFAULT_COMPILE_SECONDS:g} s |",
        f"| {mjcf_sandbox.DEFAULT_COMPILE_MEMORY_MB} MiB of address space",
        f"| {DEFAULT_MAX_LINKS:,} (the `<body>` budget",
        f"| {scheduler_address.HANDSHAKE_SECONDS:g} s; a first frame of at most "
        f"{scheduler_address.MAX_HANDSHAKE_BYTES >> 20} MiB |",
        f"| {trajectory.MAX_SAMPLES:,} rows, {trajectory.MAX_LINE_CHARS} characters per column",
        f"| {MAX_MATRIX_BYTES >> 30} GiB: K ≤ {max_configurations(200):,} at nv = 200 |",
        f"| {maps.MATRIX_BLOCK_BYTES >> 20} MiB: blocks of at most "
        f"{maps.MATRIX_BLOCK_BYTES // (8 * 200**2):,} configurations at nv = 200 |",
        f"(a chunk is up to {maps.CHUNK_POINTS:,} configurations)",
    ]
    for text in expected:
        assert text in section, text


# --- a survey of many robots: the per-robot grid is bounded -----------------------------------


def test_the_survey_grid_draws_at_most_grid_panels_the_worst_tracked_first():
    import dataclasses

    from matplotlib.figure import Figure

    from gimwatch.survey.plots import GRID_PANELS, grid_figsize, plot_kappa_vs_delta_grid
    from gimwatch.survey.run import run_survey

    base = run_survey(["chain:2"], samples=6, seed=0, workers=1)
    count = 3 * GRID_PANELS
    robots = tuple(
        dataclasses.replace(base.robots[0], name=f"r{i}", pearson_log=1.0 - i / count)
        for i in range(count)
    )
    result = dataclasses.replace(base, robots=robots)
    assert grid_figsize(count) == grid_figsize(GRID_PANELS)
    fig = plot_kappa_vs_delta_grid(result, fig=Figure(figsize=grid_figsize(count)))
    titles = [ax.get_title() for ax in fig.axes if ax.axison]
    assert len(titles) == GRID_PANELS
    worst = [f"r{i} " for i in range(count - 1, count - 1 - GRID_PANELS, -1)]  # lowest r
    assert [t.split("(")[0] for t in titles] == worst
    assert f"the {GRID_PANELS} of {count} robots" in fig.get_suptitle()


def test_a_range_whose_span_overflows_is_one_line_not_numpys_warning(tmp_path, capfd):
    """Before: NumPy's "overflow encountered in subtract" naming nothing, then a matplotlib
    traceback on the non-finite grid."""
    import warnings

    argv = ["map", "chain:2", "--joints", "joint_1", "joint_2", "--grid", "3"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        code, out, err = _run(
            [*argv, "--range", "-1e308", "1e308", "0", "1", "-o", str(tmp_path / "m")], capfd
        )
    _one_error(code, out, err, "--range", "joint_1", "1.8e308")
    assert not (tmp_path / "m").exists()


def test_map_metrics_hold_a_bounded_block_of_matrices(monkeypatch):
    """K configurations of a 100-DoF chain: 32 MB of M(q) if held at once; with a 1 MiB
    block the peak stays near it, and κ and δ equal NumPy's on Pinocchio's M."""
    import tracemalloc

    import numpy as np
    import pinocchio as pin

    from gimwatch.explain import maps
    from gimwatch.model.robots import load_robot

    monkeypatch.setattr(maps, "MATRIX_BLOCK_BYTES", 1 << 20)
    robot = load_robot("chain:100")
    qs = np.random.default_rng(0).uniform(-1, 1, (400, 100))
    maps.metrics_at("chain:100", "crba", qs[:2], ("kappa",))  # warm the robot cache
    tracemalloc.start()
    values = maps.metrics_at("chain:100", "crba", qs, ("kappa", "diagonal_ratio"))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 8 << 20, peak
    data = robot.model.createData()
    for k in (0, 199, 399):
        M = pin.crba(robot.model, data, qs[k])
        M = np.triu(M) + np.triu(M, 1).T
        w = np.linalg.eigvalsh(M)
        assert values[0, k] == pytest.approx(w[-1] / w[0], rel=1e-9)
        assert values[1, k] == pytest.approx(M.diagonal().max() / M.diagonal().min(), rel=1e-15)


# --- the round's hostile command lines, one table: one line and exit 2, or a correct exit 0 --

#: (case id, argv with {dir} for the case's folder, environment, expected exit status).
#: Files named in argv are written by `make_hostile_files`; servers by `_hostile_servers`.
HOSTILE_CASES = [
    ("q-negative-exponent", ["analyze", "chain:2", "--q", "0.1", "-1e-05"], {}, 0),
    ("q-negative-exponent-only", ["analyze", "chain:2", "--q", "-1e-3", "-2E-1"], {}, 0),
    ("explain-q-negative-exponent", ["explain", "chain:2", "--q", "-1e-05", "0.1"], {}, 0),
    ("target-negative-exponent", ["armature", "chain:2", "--target", "-1e-3"], {}, 2),
    (
        "flex-arena-crosscheck",
        ["crosscheck", "{dir}/flex.xml", "--peer", "mujoco", "--samples", "2"],
        {},
        0,
    ),
    ("replicate-time", ["analyze", "{dir}/replicate.xml"], {"GIMWATCH_MJCF_SECONDS": "2"}, 2),
    (
        "replicate-memory",
        ["analyze", "{dir}/replicate.xml"],
        {"GIMWATCH_MJCF_MEMORY_MB": "64", "GIMWATCH_MJCF_SECONDS": "30"},
        2,
    ),
    ("include-fifo", ["analyze", "{dir}/include_fifo.xml"], {}, 2),
    ("scheduler-silent", ["survey", "chain:2", "--samples", "4", "--scheduler", "{silent}"], {}, 2),
    ("scheduler-http", ["survey", "chain:2", "--samples", "4", "--scheduler", "{http}"], {}, 2),
    (
        "map-scheduler-http",
        [
            "map",
            "chain:2",
            "--joints",
            "joint_1",
            "joint_2",
            "--scheduler",
            "{http}",
            "-o",
            "{dir}/m",
        ],
        {},
        2,
    ),
    ("scheduler-bad-url", ["survey", "chain:2", "--scheduler", "tcp://[::1"], {}, 2),
    (
        "non-utf8-map",
        ["map", "{nonutf8}", "--joints", "joint_1", "joint_2", "--grid", "3", "-o", "{dir}/m8"],
        {},
        0,
    ),
    ("non-utf8-survey", ["survey", "{dir}/robots", "--samples", "4", "-o", "{dir}/s8"], {}, 0),
    (
        "trajectory-long-line",
        ["map", "chain:2", "--trajectory", "{dir}/long.csv", "-o", "{dir}/mt"],
        {},
        2,
    ),
    ("armature-32-GB", ["armature", "chain:200", "--target", "1e4", "--samples", "100000"], {}, 2),
    ("armature-own-free-joint", ["armature", "{dir}/free.xml", "--target", "5"], {}, 2),
    (
        "map-range-overflow",
        [
            "map",
            "chain:2",
            "--joints",
            "joint_1",
            "joint_2",
            "--range",
            "-1e308",
            "1e308",
            "0",
            "1",
            "-o",
            "{dir}/mr",
        ],
        {},
        2,
    ),
    (
        "map-workers-64",
        ["map", "chain:2", "--joints", "joint_1", "joint_2", "--workers", "64", "-o", "{dir}/mw"],
        {"GIMWATCH_MAX_WORKERS": "2"},
        2,
    ),
]


def make_hostile_files(folder) -> dict[str, str]:
    """Write the files the hostile cases name into ``folder``; the argv placeholders."""
    import os
    from pathlib import Path

    from gimwatch.model.chains import chain_spec, generate_chain_urdf

    folder = Path(folder)
    (folder / "flex.xml").write_text(FLEX_MJCF.format(memory="20K"))
    (folder / "replicate.xml").write_text(REPLICATED_MJCF)
    os.mkfifo(folder / "fifo")
    (folder / "include_fifo.xml").write_text(
        '<mujoco><include file="fifo"/><worldbody><body><joint/><geom size=".1"/></body>'
        "</worldbody></mujoco>"
    )
    (folder / "free.xml").write_text(FREE_BODY_MJCF)
    (folder / "long.csv").write_text("0.1,0.2\n" + "1" * 1_000_000 + "\n")
    robots = folder / "robots"
    robots.mkdir()
    text = generate_chain_urdf(chain_spec(3))
    (robots / "ok.urdf").write_text(text)
    with open(os.fsencode(robots) + b"/rob\xffot.urdf", "w") as stream:
        stream.write(text)
    return {"dir": str(folder), "nonutf8": os.fsdecode(os.fsencode(robots) + b"/rob\xffot.urdf")}


@pytest.mark.parametrize(
    ("argv", "env", "expected"),
    [pytest.param(argv, env, expected, id=name) for name, argv, env, expected in HOSTILE_CASES],
)
def test_hostile_case(argv, env, expected, tmp_path, local_server, monkeypatch, capfd):
    from gimwatch.survey import scheduler_address

    monkeypatch.setattr(scheduler_address, "HANDSHAKE_SECONDS", 2.0)
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    places = make_hostile_files(tmp_path)
    places["silent"] = local_server(None)
    places["http"] = local_server(HTTP_ANSWER)
    code, out, err = _run([word.format(**places) for word in argv], capfd)
    assert "Traceback" not in err, err
    if expected == 2:
        _one_error(code, out, err)
    else:
        assert code == 0, err
