"""Real description files: a prolog of any length is read in linear time."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from gimwatch.model.mjcf_model import is_mjcf, root_element_name

XACRO_HEADER = "".join(f"<!-- line {i} of the header xacro writes -->\n" for i in range(40))


@pytest.mark.parametrize(
    ("text", "root"),
    [
        (XACRO_HEADER + "<robot name='iiwa'></robot>", "robot"),
        ('<?xml version="1.0"?>\n' + XACRO_HEADER + "<mujoco model='m'/>", "mujoco"),
        ("\ufeff<mujoco model='bom'/>", "mujoco"),
        ("<!DOCTYPE robot [<!ENTITY a 'b'>]>\r\n<robot name='x'/>", "robot"),
        ("<!-- never closed " + "<!-- " * 1000, None),
        ("plain text", None),
        ("<mujocox/>", "mujocox"),
    ],
)
def test_root_element_name(text, root):
    assert root_element_name(text) == root
    assert is_mjcf(text) == (root == "mujoco")


def test_prolog_scan_is_linear_not_exponential():
    # 100,000 leading comments and a 10 MB comment: the old nested regex never returned.
    many = "<!-- c -->\n" * 100_000 + "<robot name='x'/>"
    huge = "<!--" + "x" * 10_000_000 + "-->\n<robot name='x'/>"
    start = time.perf_counter()
    assert root_element_name(many) == "robot"
    assert root_element_name(huge) == "robot"
    assert time.perf_counter() - start < 60  # a generous bound: linear takes ~0.1 s


# --- real-world conventions: read with one warning, M unchanged ---------------------------

import subprocess  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from real_shapes import arm  # noqa: E402

from gimwatch.crosscheck import crosscheck_robot  # noqa: E402
from gimwatch.errors import URDFError, URDFWarning  # noqa: E402
from gimwatch.model.robots import load_robot  # noqa: E402

QUIRKS = [
    "header",
    "crlf",
    "bom",
    "late_declaration",
    "namespace",
    "unlimited_effort",
    "missing_limit",
    "reversed_limit",
    "comma_origins",
    "bad_shapes",
    "empty_dynamics",
    "nul_tail",
    "implicit_world",
    "unnamed",
    "unbound_prefix",
    "unnamed_material",
    "duplicate_material",
    "multiline_numbers",
    "welded_bad_inertia",
]
#: Read with one "lenient" warning (the others are plain XML that every parser reads).
WARNED = set(QUIRKS) - {"header", "crlf", "bom"}
#: Refused (or complained about) by urdfdom, Pinocchio's parser, given the raw text.
REFUSED_RAW = {
    "missing_limit",
    "comma_origins",
    "bad_shapes",
    "empty_dynamics",
    "implicit_world",
    "unnamed",
    "unnamed_material",
    "duplicate_material",
    "multiline_numbers",
}


def _write(tmp_path, name: str, text: str):
    path = tmp_path / f"{name}.urdf"
    path.write_bytes(text.encode("utf-8"))
    return path


def _gims(robot, count: int = 4) -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    data = robot.model.createData()
    return [
        pin.crba(robot.model, data, rng.uniform(-2.9, 2.9, robot.nq)).copy() for _ in range(count)
    ]


@pytest.fixture(scope="module")
def clean_gims(tmp_path_factory):
    path = _write(tmp_path_factory.mktemp("clean"), "clean", arm())
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the clean arm is read without any warning
        return _gims(load_robot(path))


@pytest.mark.parametrize("quirk", [*QUIRKS, "all"])
def test_a_convention_that_does_not_change_m_is_read_with_one_warning(quirk, tmp_path, clean_gims):
    flags = dict.fromkeys(QUIRKS, True) if quirk == "all" else {quirk: True}
    path = _write(tmp_path, quirk, arm(**flags))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_robot(path)
    lenient = [w for w in caught if "lenient" in str(w.message)]
    expected = 1 if (quirk == "all" or quirk in WARNED) else 0
    assert len(lenient) == expected, [str(w.message) for w in caught]
    assert all(issubclass(w.category, URDFWarning) for w in lenient)
    assert all(str(path) in str(w.message) for w in lenient)
    # the same arm: M(q) entry by entry against the clean file's, through Pinocchio
    for M, reference in zip(_gims(robot), clean_gims, strict=True):
        np.testing.assert_allclose(M, reference, rtol=0, atol=1e-14 * np.abs(reference).max())


@pytest.mark.parametrize("quirk", sorted(REFUSED_RAW))
def test_pinocchio_alone_refuses_the_raw_file(quirk, tmp_path):
    """The control: without the normalisation, urdfdom refuses these files or prints errors."""
    path = _write(tmp_path, quirk, arm(**{quirk: True}))
    code = f"import pinocchio; pinocchio.buildModelFromXML(open({str(path)!r}).read())"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode != 0 or "Error" in done.stderr, quirk


def test_mimic_of_a_fixed_joint_is_read_and_cross_checked(tmp_path):
    path = _write(tmp_path, "eve_like", arm(mimic_of_fixed=True, unlimited_effort=True, bom=True))
    with pytest.warns(URDFWarning, match="mimic> of a fixed joint .finger_joint -> flange_joint"):
        robot = load_robot(path)
    assert robot.nv == 8 and "finger_joint" in robot.joint_names
    result = crosscheck_robot(robot, samples=3, peer="mujoco")  # DeNOC and MuJoCo against CRBA
    assert result.passed and result.mujoco_gim_rel_err is not None, result


def test_declared_latin1_is_read_and_undeclared_is_refused(tmp_path):
    text = arm().replace('encoding="utf-8"', 'encoding="ISO-8859-1"')
    text = text.replace("<robot", "<!-- Auteur : Hélène Müller -->\n<robot", 1)
    path = tmp_path / "latin1.urdf"
    path.write_bytes(text.encode("latin-1"))
    assert load_robot(path).nv == 7
    path.write_bytes(text.replace('encoding="ISO-8859-1"', 'encoding="utf-8"').encode("latin-1"))
    with pytest.raises(URDFError, match="is not UTF-8 text"):
        load_robot(path)


def test_an_unexpanded_xacro_expression_is_refused_with_a_hint(tmp_path):
    text = arm().replace('xyz="0 0 0.1575"', 'xyz="$(optenv IIWA_XYZ 0 0 0.1575)"')
    with pytest.raises(URDFError, match="unexpanded xacro or roslaunch expression"):
        load_robot(_write(tmp_path, "xacro_left", text))


def test_the_cli_reads_every_quirk_with_one_warning_line(tmp_path):
    path = _write(tmp_path, "everything", arm(**dict.fromkeys(QUIRKS, True)))
    for command in ("analyze", "crosscheck"):
        done = subprocess.run(
            [sys.executable, "-m", "gimwatch", command, str(path)],
            capture_output=True,
            text=True,
            cwd=tmp_path,
            check=False,
        )
        assert done.returncode == 0, done.stderr
        lines = [line for line in done.stderr.splitlines() if line.startswith("gimwatch:")]
        assert lines and all(line.startswith("gimwatch: warning: ") for line in lines), lines
        assert "lenient" in lines[0] and str(path) in lines[0]


# --- every loader answers in time proportional to the size of its input -------------------

HOSTILE = {
    "100k_leading_comments": "<!-- c -->\n" * 100_000 + arm(),
    "10MB_comment": "<!--" + "x" * 10_000_000 + "-->\n" + arm().split("?>", 1)[1],
    "unclosed_comments": arm().replace("</robot>", "<!-- " * 200_000 + "</robot>"),
    "nested_declarations": "<?xml version='1.0'?>" + "<?pi x?>" * 100_000 + arm().split("?>", 1)[1],
    "deep_nesting": arm().replace("</robot>", "<a>" * 50_000 + "</a>" * 50_000 + "</robot>"),
    "long_number": arm().replace('value="5"', 'value="' + "1" * 60_000 + 'x"'),
}
_LOADERS = """
import sys, time, warnings
warnings.simplefilter("ignore")
from gimwatch.errors import GimwatchError
from gimwatch.model.robots import load_robot
from gimwatch.denoc import DenocModel
path = sys.argv[1]
text = open(path, encoding="utf-8").read()
for name, load in (("load_robot", lambda: load_robot(path)),
                   ("denoc", lambda: DenocModel.from_urdf(text, source=path))):
    start = time.perf_counter()
    try:
        load()
        outcome = "loaded"
    except GimwatchError as exc:
        outcome = "refused: " + str(exc).splitlines()[0][:80]
    print(name, outcome, round(time.perf_counter() - start, 3))
"""


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_every_loader_answers_hostile_text_in_linear_time(case, tmp_path):
    """A load or a one-line refusal, never a hang (the bound is generous: ~100x the time)."""
    path = tmp_path / f"{case}.urdf"
    path.write_text(HOSTILE[case], encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-c", _LOADERS, str(path)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert [line.split()[0] for line in lines] == ["load_robot", "denoc"], done.stdout


# --- batches report per file; nothing compared is not a pass -------------------------------

MASSLESS = (
    "<robot name='massless'><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
    "<parent link='a'/><child link='b'/><axis xyz='0 0 1'/>"
    "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>"
)


@pytest.fixture(scope="module")
def batch_folder(tmp_path_factory):
    """30 files: 27 good arms and chains, 3 bad (malformed XML, a zero axis, a cycle)."""
    folder = tmp_path_factory.mktemp("batch")
    for i in range(27):
        text = arm(header=i % 2 == 0, crlf=i % 3 == 0) if i % 3 else _chain_text(2 + i % 4)
        (folder / f"good_{i:02d}.urdf").write_text(text, encoding="utf-8")
    (folder / "bad_xml.urdf").write_text("<robot name='x'><link name='a'>", encoding="utf-8")
    (folder / "bad_axis.urdf").write_text(arm().replace('xyz="0 1 0"', 'xyz="0 0 0"', 1))
    (folder / "bad_cycle.urdf").write_text(
        arm().replace('<child link="base"/>', '<child link="link_3"/>', 1)
    )
    return folder


def _chain_text(n: int) -> str:
    from gimwatch.model.chains import chain_spec, generate_chain_urdf

    return generate_chain_urdf(chain_spec(n))


def _gimwatch(*args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "gimwatch", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        check=False,
        timeout=600,
    )


def test_crosscheck_of_a_folder_reports_27_results_and_3_refusals(batch_folder, tmp_path):
    import json

    done = _gimwatch("crosscheck", str(batch_folder), "--samples", "2", "--json", cwd=tmp_path)
    assert done.returncode == 2, done.stderr[-3000:]
    robots = json.loads(done.stdout)["robots"]
    assert len(robots) == 30
    statuses = [r["status"] for r in robots]
    assert statuses.count("passed") == 27 and statuses.count("refused") == 3
    refused = {Path(r["robot"]).name: r["note"] for r in robots if r["status"] == "refused"}
    assert set(refused) == {"bad_xml.urdf", "bad_axis.urdf", "bad_cycle.urdf"}
    assert "non-zero vector" in refused["bad_axis.urdf"]
    text = _gimwatch("crosscheck", str(batch_folder), "--samples", "2", cwd=tmp_path)
    assert text.returncode == 2 and "27/30 passed (tolerance 1e-10), 3 refused" in text.stdout


def test_analyze_and_survey_go_on_past_a_refused_file(batch_folder, tmp_path):
    import csv
    import io

    files = [str(batch_folder / name) for name in ("good_01.urdf", "bad_xml.urdf", "good_02.urdf")]
    done = _gimwatch("analyze", *files, "--csv", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    rows = list(csv.DictReader(io.StringIO(done.stdout)))
    assert [bool(r["refused"]) for r in rows] == [False, True, False]
    assert "malformed XML" in rows[1]["refused"] and rows[0]["kappa"]
    survey = _gimwatch("survey", *files, "--samples", "3", "-o", str(tmp_path / "s"), cwd=tmp_path)
    assert survey.returncode == 2, survey.stderr
    assert "refused: " + files[1] in survey.stdout and (tmp_path / "s" / "survey.json").is_file()


def test_a_crosscheck_that_compares_nothing_is_not_a_pass(tmp_path):
    path = tmp_path / "massless.urdf"
    path.write_text(MASSLESS, encoding="utf-8")
    result = crosscheck_robot(load_robot(path), samples=3)
    assert result.status == "not compared" and not result.passed
    assert result.note.startswith("not compared: M(q) ≡ 0")
    done = _gimwatch("crosscheck", str(path), cwd=tmp_path)
    assert done.returncode == 1
    assert "0/1 passed" in done.stdout and "1 not compared" in done.stdout
    assert "passed" not in done.stdout.split("\n")[2]  # the row is labelled, not passed
