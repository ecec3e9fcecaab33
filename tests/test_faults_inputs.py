"""Hostile input that the file corpus (tests/data/bad/) cannot hold: too large, made at test
time, or library calls. Each gives one error line naming the file, key, link or joint (exit
2), or a correct result; never a traceback, never stray output from a third-party parser.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from gimwatch.cli import main
from gimwatch.crosscheck import check_tolerance, crosscheck_robot
from gimwatch.errors import ConditioningError, GimwatchError, InputError, URDFError
from gimwatch.metrics.conditioning import condition_number, diagonal_ratio
from gimwatch.metrics.dense_analysis import analyze_configuration
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import load_robot
from gimwatch.model.urdf_text import DEFAULT_MAX_LINKS, MAX_TAG_CHARS

REPO = Path(__file__).resolve().parents[1]
GOOD = (
    (REPO / "tests/data/bad/urdf/zero_mass_leaf.urdf")
    .read_text()
    .replace(
        '<mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>',
        '<mass value="1.0"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.084" iyz="0" izz="0.084"/>',
    )
)
#: Longer than lxml's 10,000,000-character limit on one text node (its "Comment too big").
BIG_COMMENT = 10_500_000
#: κ of GOOD at q = 0 (two 1 m rods of 1 kg, centres at 0.5 m; checked against crba below).
GOOD_KAPPA = 44.06


def _run(argv: list[str], capture) -> tuple[int, str, str]:
    """``main(argv)`` with capsys or capfd (which also sees C libraries' output)."""
    code = main(argv)
    out, err = capture.readouterr()
    return code, out, err


def _one_error(code: int, out: str, err: str, *fragments: str) -> None:
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and err.startswith("gimwatch: error: "), err
    assert "Traceback" not in err and out == "", (out, err)
    for fragment in fragments:
        assert fragment in err, (fragment, err)


def _star(n_links: int) -> str:
    """A URDF whose n_links - 1 leaves all hang from the base (a star)."""
    inertial = (
        '<inertial><mass value="1"/>'
        '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'
    )
    links = ['<link name="base"/>'] + [
        f'<link name="l{i}">{inertial}</link>' for i in range(n_links - 1)
    ]
    joints = [
        f'<joint name="j{i}" type="continuous"><parent link="base"/><child link="l{i}"/></joint>'
        for i in range(n_links - 1)
    ]
    return '<robot name="star">' + "".join(links + joints) + "</robot>"


# --- URDF text: comments, declarations, budgets, paths -----------------------------------


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_the_good_urdf_has_the_expected_kappa(tmp_path):
    """The control of the cases below that must give a correct result."""
    import pinocchio as pin

    robot = load_robot(_write(tmp_path / "good.urdf", GOOD))
    M = pin.crba(robot.model, robot.new_data(), np.zeros(2))
    M = np.triu(M) + np.triu(M, 1).T
    assert analyze_configuration(robot, np.zeros(2)).kappa == pytest.approx(np.linalg.cond(M))
    assert np.linalg.cond(M) == pytest.approx(GOOD_KAPPA, rel=1e-3)


def test_a_comment_mentioning_doctype_is_not_a_declaration(tmp_path, capsys):
    text = GOOD.replace("<robot name", "<!-- no <!DOCTYPE or <!ENTITY here -->\n<robot name")
    code, out, err = _run(["analyze", str(_write(tmp_path / "c.urdf", text))], capsys)
    assert code == 0 and err == "", err
    assert "44.06" in out


def test_a_doctype_outside_comments_is_still_refused(tmp_path, capsys):
    text = GOOD.replace("<robot name", "<!-- a comment -->\n<!DOCTYPE robot>\n<robot name")
    code, out, err = _run(["analyze", str(_write(tmp_path / "d.urdf", text))], capsys)
    _one_error(code, out, err, "d.urdf", "DOCTYPE declarations are not allowed")


@pytest.mark.parametrize(
    ("name", "change"),
    [
        (
            "utf16_declared",
            lambda t: t.replace('<?xml version="1.0"?>', '<?xml version="1.0" encoding="UTF-16"?>'),
        ),
        (
            "big_comment",
            lambda t: t.replace("<robot name", "<!-- " + "x" * BIG_COMMENT + " -->\n<robot name"),
        ),
    ],
)
def test_third_party_parsers_print_nothing(name, change, tmp_path, capfd):
    """crosscheck and the denoc backend read the file through yourdfpy and lxml, silently.

    capfd sees file descriptor 2, so C libraries' and the logging module's lines count.
    """
    path = _write(tmp_path / f"{name}.urdf", change(GOOD))
    code, out, err = _run(["crosscheck", str(path), "--samples", "2"], capfd)
    assert code == 0 and err == "", err
    assert "1/1 passed" in out
    code, out, err = _run(["analyze", str(path), "--backend", "denoc"], capfd)
    assert code == 0 and err == "", err


def test_a_bad_value_behind_a_big_comment_names_the_file(tmp_path, capfd):
    text = GOOD.replace("<robot name", "<!-- " + "x" * BIG_COMMENT + " -->\n<robot name")
    text = text.replace('<mass value="1.0"/>', '<mass value="nan"/>', 1)
    path = _write(tmp_path / "big.urdf", text)
    for argv in (["crosscheck", str(path)], ["analyze", str(path), "--backend", "denoc"]):
        code, out, err = _run(argv, capfd)
        _one_error(code, out, err, f"{path}: link 'upper': <mass value> must be finite")
        assert "<string>" not in err


def test_a_symlink_loop_is_named(tmp_path, capsys):
    loop = tmp_path / "loop.urdf"
    loop.symlink_to(loop)
    code, out, err = _run(["analyze", str(loop)], capsys)
    _one_error(code, out, err, "loop.urdf: is a symbolic link loop")


def test_too_many_links_are_refused_before_parsing(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("GIMWATCH_MAX_LINKS", raising=False)
    path = _write(tmp_path / "star.urdf", _star(DEFAULT_MAX_LINKS + 1))
    code, out, err = _run(["analyze", str(path)], capsys)
    _one_error(
        code,
        out,
        err,
        f"star.urdf: has {DEFAULT_MAX_LINKS + 1} <link> elements, more than the "
        f"{DEFAULT_MAX_LINKS}",
        "$GIMWATCH_MAX_LINKS",
    )


def test_the_link_budget_is_overridden_by_the_environment(tmp_path, monkeypatch):
    path = _write(tmp_path / "star.urdf", _star(4))
    monkeypatch.setenv("GIMWATCH_MAX_LINKS", "3")
    with pytest.raises(URDFError, match="has 4 <link> elements, more than the 3"):
        load_robot(path)
    monkeypatch.setenv("GIMWATCH_MAX_LINKS", "4")
    assert load_robot(path).nv == 3
    monkeypatch.setenv("GIMWATCH_MAX_LINKS", "many")
    with pytest.raises(URDFError, match=r"\$GIMWATCH_MAX_LINKS: must be a positive integer"):
        load_robot(path)


def test_a_tag_with_100000_attributes_is_refused_before_parsing(tmp_path, capsys):
    attributes = " ".join(f'a{i}="x"' for i in range(100_000))
    path = _write(tmp_path / "attrs.urdf", f'<robot name="r" {attributes}><link name="b"/></robot>')
    code, out, err = _run(["analyze", str(path)], capsys)
    _one_error(code, out, err, f"attrs.urdf: has a tag longer than {MAX_TAG_CHARS} characters")


# --- Configurations and matrices given to the library ------------------------------------


def test_a_zero_cos_sin_pair_is_refused_naming_the_joint(tmp_path):
    robot = load_robot(_write(tmp_path / "c.urdf", GOOD.replace('"revolute"', '"continuous"')))
    assert robot.nq == 4
    with pytest.raises(InputError, match=r"\(cos θ, sin θ\) of joint 'shoulder' in q must be"):
        analyze_configuration(robot, np.zeros(4))
    q = np.array([1.0, 0.0, 1.0, 0.0])  # the control: θ = 0 for both joints
    assert analyze_configuration(robot, q).kappa == pytest.approx(GOOD_KAPPA, rel=1e-3)


def test_a_zero_quaternion_is_refused_naming_the_joint(tmp_path):
    robot = load_robot(_write(tmp_path / "f.urdf", GOOD), floating=True)
    q = np.zeros(robot.nq)
    with pytest.raises(InputError, match="quaternion of joint 'root_joint' in q must be of norm 1"):
        analyze_configuration(robot, q)
    q[6] = 1.0  # the control: the identity quaternion is accepted
    assert as_configuration(robot, q)[6] == 1.0


def test_complex_hermitian_matrix_is_refused():
    hermitian = np.array([[2.0, 1j], [-1j, 2.0]])  # κ = 3, which a float cast would make 1
    with pytest.raises(ConditioningError, match="must hold real numbers, got complex128"):
        condition_number(hermitian)
    with pytest.raises(ConditioningError, match="must hold real numbers"):
        diagonal_ratio(np.array([2.0 + 1j, 1.0]))
    with pytest.raises(ConditioningError, match="must hold real numbers"):
        condition_number([["a", "b"], ["c", "d"]])
    assert condition_number(np.array([[2.0, 1.0], [1.0, 2.0]])) == pytest.approx(3.0)


# --- crosscheck: NaN never passes, tolerances in (0, 1) ----------------------------------


@pytest.mark.parametrize("tolerance", [0.0, -1e-3, 1.0, float("inf"), float("nan"), "1e-3", True])
def test_tolerances_outside_zero_one_are_refused(tolerance):
    with pytest.raises(InputError, match="tolerance must be a number > 0 and < 1"):
        check_tolerance(tolerance)


def test_a_nan_error_fails_the_crosscheck(tmp_path, monkeypatch):
    from gimwatch.denoc import DenocModel

    robot = load_robot(_write(tmp_path / "g.urdf", GOOD))
    assert crosscheck_robot(robot, samples=2).passed  # the control
    monkeypatch.setattr(DenocModel, "gim", lambda self, q: np.full((2, 2), np.nan))
    result = crosscheck_robot(robot, samples=2)
    assert np.isnan(result.gim_rel_err) and not result.passed


def test_public_functions_raise_gimwatch_errors_on_non_numeric_q(tmp_path):
    robot = load_robot(_write(tmp_path / "g.urdf", GOOD))
    for q in (np.array([1j, 0]), ["a", "b"]):
        with pytest.raises(GimwatchError, match="q must be a vector of real numbers"):
            analyze_configuration(robot, q)


# --- Scenes: paths, the step budget --------------------------------------------------------

SCENE = """robot = "{robot}"
duration = 0.05
sample = 0.01
q = 0.1
"""


def test_a_robot_path_without_suffix_is_relative_to_the_scene(tmp_path, capsys, monkeypatch):
    folder = tmp_path / "scenes"
    (folder / "models").mkdir(parents=True)
    _write(folder / "arm", GOOD)
    _write(folder / "models" / "arm", GOOD)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    _write(elsewhere / "arm", "not a URDF")  # what the working directory would give
    monkeypatch.chdir(elsewhere)
    for robot in ("arm", "models/arm"):
        scene = _write(folder / "s.toml", SCENE.format(robot=robot))
        code, out, err = _run(["simulate", str(scene), "-o", str(tmp_path / "out")], capsys)
        assert code == 0, err
        assert out.startswith("arm: completed"), out


def test_a_bare_name_not_in_the_scene_folder_is_an_example_robot(tmp_path):
    from gimwatch.simulation.scene import parse_scene

    scene = parse_scene({"robot": "ur5", "duration": 1.0, "sample": 0.1}, base_dir=tmp_path)
    assert scene.robot.spec == "ur5"


def test_a_scene_symlink_loop_is_named(tmp_path, capsys):
    (tmp_path / "loop.toml").symlink_to(tmp_path / "loop.toml")
    code, out, err = _run(["simulate", str(tmp_path / "loop.toml")], capsys)
    _one_error(code, out, err, "loop.toml: is a symbolic link loop")
    (tmp_path / "loop.urdf").symlink_to(tmp_path / "loop.urdf")
    scene = _write(tmp_path / "s.toml", SCENE.format(robot="loop.urdf"))
    code, out, err = _run(["simulate", str(scene), "-o", str(tmp_path / "out")], capsys)
    _one_error(code, out, err, "s.toml: robot:", "loop.urdf: is a symbolic link loop")


STIFF = """robot = "chain:2"
duration = 1.0
sample = 0.1
q = 0.5

[integrator]
method = "RK45"
max_steps = {max_steps}

[effects.spring]
stiffness = 1e4
"""


def test_an_adaptive_run_stops_when_its_step_budget_is_spent(tmp_path, capsys):
    scene = _write(tmp_path / "stiff.toml", STIFF.format(max_steps=50))
    code, out, err = _run(["simulate", str(scene), "-o", str(tmp_path / "out")], capsys)
    assert code == 1, err
    assert "gimwatch: error: step budget spent: 50 RK45 steps reached t = " in err
    assert "raise [integrator] max_steps" in err and "Traceback" not in err
    assert "chain_2: failed" in out and (tmp_path / "out" / "summary.json").is_file()
    scene = _write(tmp_path / "stiff.toml", STIFF.format(max_steps=100_000))  # the control
    code, out, err = _run(["simulate", str(scene), "-o", str(tmp_path / "out2")], capsys)
    assert code == 0 and "chain_2: completed" in out, err


def test_a_spec_built_in_python_keeps_the_fixed_step_budget():
    from gimwatch.simulation.integrators import INTEGRATORS
    from gimwatch.simulation.scene_integrator import IntegratorSpec

    class Problem:  # a run that would need 1e6 steps
        duration_s, sample_s = 1.0, 0.5

    integrator = INTEGRATORS["RK4"](IntegratorSpec(method="RK4", dt=1e-6, max_steps=10))
    status, message = integrator.run(Problem(), record=None)
    assert status == "failed" and message.startswith("step budget spent: 10 RK4 steps")
    assert integrator.steps == 0


# --- Command-line budgets ------------------------------------------------------------------


def test_analyze_random_work_budget(capsys, monkeypatch):
    monkeypatch.delenv("GIMWATCH_MAX_RANDOM_WORK", raising=False)
    code, out, err = _run(["analyze", "chain:5000", "--random", "100000"], capsys)
    _one_error(code, out, err, "--random must be at most 400 for nv = 5000", "count x nv")
    monkeypatch.setenv("GIMWATCH_MAX_RANDOM_WORK", "4")
    code, out, err = _run(["analyze", "chain:2", "--random", "3"], capsys)
    _one_error(code, out, err, "--random must be at most 2 for nv = 2")
    monkeypatch.setenv("GIMWATCH_MAX_RANDOM_WORK", "6")
    code, out, err = _run(["analyze", "chain:2", "--random", "3", "--json"], capsys)
    assert code == 0 and err == "", err


def test_survey_workers_are_capped_at_the_cores(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("GIMWATCH_MAX_WORKERS", raising=False)
    cores = len(os.sched_getaffinity(0))
    argv = ["survey", "chain:2", "--samples", "2", "-o", str(tmp_path / "out")]
    code, out, err = _run([*argv, "--workers", str(cores + 1)], capsys)
    _one_error(code, out, err, f"--workers must be at most {cores}, the cores", "GIMWATCH_MAX")
    assert not (tmp_path / "out").exists()
    monkeypatch.setenv("GIMWATCH_MAX_WORKERS", "1")
    code, out, err = _run([*argv, "--workers", "2"], capsys)
    _one_error(code, out, err, "--workers must be at most 1")
    code, out, err = _run([*argv, "--workers", "1"], capsys)
    assert code == 0, err


def test_survey_trajectory_duration_is_within_the_step_budget(tmp_path, capsys):
    argv = ["survey", "chain:2", "--samples", "2", "-o", str(tmp_path / "out"), "--trajectory"]
    code, out, err = _run([*argv, "--duration", "1e300"], capsys)
    _one_error(code, out, err, "--duration must be at most 100 s (the step budget of 100000")
    assert not (tmp_path / "out").exists()


def test_bench_page_without_markers_is_refused_before_running(tmp_path, capsys):
    page = _write(tmp_path / "page.md", "# no markers here\n")
    argv = ["bench", "--quick", "conditioning", "-o", str(tmp_path / "out"), "--readme"]
    code, out, err = _run([*argv, str(page)], capsys)
    _one_error(code, out, err, "page.md must be a file with <!-- bench:start -->")
    assert not (tmp_path / "out").exists()
    code, out, err = _run([*argv, str(tmp_path / "missing.md")], capsys)
    _one_error(code, out, err, "missing.md: cannot be read")
