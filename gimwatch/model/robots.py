"""Turn a robot specification into a :class:`Robot` (a Pinocchio model plus what it came from).

A specification is one of:

* ``chain:N`` — the paper's chain of N slender rods (2.2 kg, 1 m), generated on the fly;
* a path to a URDF file;
* a path to an MJCF file (``.xml`` whose root element is ``<mujoco>``), read by
  Pinocchio's MJCF parser (``pinocchio.buildModelFromMJCF``);
* the name of a robot in example-robot-data (``ur5``, ``panda``, ``talos_arm``, ...).

DeNOC reads URDF only: an MJCF robot has ``urdf_xml == ""`` and its text in ``mjcf_xml``;
``gimwatch crosscheck`` then compares Pinocchio with MuJoCo (docs/robots.md).

The base is fixed unless ``floating=True``, which adds Pinocchio's free-flyer root joint.
No :class:`pinocchio.Data` is built here: its memory grows as nv^3 (about 1.8 GB at
nv = 300), so callers ask for it with :meth:`Robot.new_data` only when they need it.
"""

from __future__ import annotations

import contextlib
import difflib
import errno
import os
import re
import sys
import tempfile
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import ExampleRobotWarning, InputError, RobotError, URDFError
from gimwatch.model.chains import ChainSpec, chain_spec, generate_chain_urdf
from gimwatch.model.mjcf_values import check_mjcf

__all__ = [
    "EXAMPLE_ROBOT_NOTES",
    "Robot",
    "captured_c_output",
    "chain_robot",
    "example_robot_names",
    "is_mjcf",
    "load_robot",
    "neutral_configuration",
    "parse_chain_spec",
    "placeholder_limit_joints",
    "random_configurations",
]

_CHAIN_SPEC = re.compile(r"^chain:(\S+)$")
#: Above this many velocity coordinates, a Pinocchio Data would need several GB.
DATA_NV_LIMIT = 400
_DEFAULT_ANGLE_RAD = np.pi
_DEFAULT_TRANSLATION_M = 1.0
#: The largest URDF file read (the biggest example-robot-data URDF is under 1 MB).
MAX_URDF_BYTES = 64 * 1024 * 1024
#: random_configurations refuses to allocate more numbers than this (400 MB).
MAX_RANDOM_NUMBERS = 50_000_000
#: Pinocchio's URDF parser recurses once per link along a branch and overflows the 8 MB
#: C stack (a segmentation fault) between 3500 and 4000 links; deeper trees are refused.
MAX_TREE_DEPTH = 2000


@dataclass(frozen=True, eq=False)
class Robot:
    """A kinematic tree ready for dynamics.

    Attributes:
        name: Short name (the example-robot-data name, the URDF's robot name, ``chain_N``).
        spec: The specification it was loaded from.
        model: The Pinocchio model (free-flyer root first when ``floating``).
        urdf_xml: The URDF text the model was built from (DeNOC re-reads it independently).
        source: Where the URDF came from (a path, or ``"<generated chain_N>"``).
        floating: Whether a free-flyer root joint was added.
        chain: The chain spec for generated chains, else None.
        mjcf_xml: The MJCF text for robots read from MJCF (then ``urdf_xml`` is ""), else "".
    """

    name: str
    spec: str
    model: pin.Model
    urdf_xml: str
    source: str
    floating: bool = False
    chain: ChainSpec | None = None
    mjcf_xml: str = ""
    dof_names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        names = []
        for joint, joint_name in zip(self.model.joints[1:], self.model.names[1:], strict=True):
            if joint.nv == 1:
                names.append(joint_name)
            else:
                names.extend(f"{joint_name}[{k}]" for k in range(joint.nv))
        object.__setattr__(self, "dof_names", tuple(names))

    def __repr__(self) -> str:  # the model and the URDF text would fill a screen
        base = "floating" if self.floating else "fixed"
        return (
            f"Robot(name={self.name!r}, spec={self.spec!r}, nq={self.nq}, nv={self.nv}, "
            f"base={base!r}, source={self.source!r})"
        )

    @property
    def nq(self) -> int:
        """Number of configuration coordinates."""
        return self.model.nq

    @property
    def nv(self) -> int:
        """Number of velocity coordinates (the size of the GIM)."""
        return self.model.nv

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the moving joints in Pinocchio's order (the free-flyer is ``root_joint``)."""
        return tuple(self.model.names[1:])

    def new_data(self) -> pin.Data:
        """A fresh :class:`pinocchio.Data`; refuses models whose Data would not fit in memory."""
        if self.nv > DATA_NV_LIMIT:
            raise _too_large(self.spec, self.nv)
        return self.model.createData()


@cache
def _example_robots() -> dict[str, type]:
    from example_robot_data.robots_loader import ROBOTS

    return dict(ROBOTS)


#: example-robot-data names whose model, as gimwatch loads it (the URDF file as written, no
#: reduction), is not what the name or ``example_robot_data.load(name)`` suggests.
#: ``load_robot`` issues each as one :class:`~gimwatch.errors.ExampleRobotWarning`; the test
#: ``tests/test_example_robot_loader.py`` compares every name with ``example_robot_data.load``.
_UR5_AS_UR3 = "example-robot-data 5.0.0 ships a UR5 description under the name ur3"
_TALOS_ROTORS = (
    "example_robot_data.load adds rotor inertias from the SRDF (armature = rotor inertia x "
    "gear ratio^2) to M's diagonal; gimwatch reads the URDF as written, without them"
)
EXAMPLE_ROBOT_NOTES = {
    "ur3": _UR5_AS_UR3,
    "ur3_gripper": _UR5_AS_UR3,
    "ur3_limited": _UR5_AS_UR3,
    "talos": _TALOS_ROTORS,
    "talos_box": _TALOS_ROTORS,
    "talos_arm": _TALOS_ROTORS,
    "talos_full": _TALOS_ROTORS,
    "talos_full_box": _TALOS_ROTORS,
    "talos_legs": (
        "the full 32-DoF Talos URDF; example_robot_data.load locks the upper body (18 DoF) "
        "and adds rotor inertias from the SRDF"
    ),
}


def example_robot_names() -> tuple[str, ...]:
    """Names of the robots example-robot-data knows, in its own order."""
    return tuple(_example_robots())


def _example_robot_urdf(name: str) -> Path:
    from example_robot_data.robots_loader import getModelPath

    loader = _example_robots()[name]
    if not loader.urdf_filename:
        raise RobotError(name, "example-robot-data ships it only as SDF; gimwatch reads URDF")
    relative = str(Path(loader.path) / loader.urdf_subpath / loader.urdf_filename)
    return (Path(getModelPath(relative)) / relative).resolve()


def _read_urdf(path: Path) -> str:
    """Read a URDF file; FIFOs and devices are refused (they could block or never end)."""
    try:
        if not path.exists():
            raise URDFError(str(path), path_problem(path))
        if path.is_dir():
            raise URDFError(str(path), "is a directory, not a URDF file")
        if not path.is_file():
            raise URDFError(str(path), "is not a regular file (a device, FIFO or socket)")
        size = path.stat().st_size
        if size > MAX_URDF_BYTES:
            raise URDFError(str(path), f"is {size} bytes, more than {MAX_URDF_BYTES} for a URDF")
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise URDFError(str(path), f"is not UTF-8 text ({exc.reason} at byte {exc.start})") from exc
    except OSError as exc:
        raise URDFError(str(path), f"cannot be read ({exc.strerror or exc})") from exc


def path_problem(path: Path) -> str:
    """Why a path that does not exist cannot be opened: a symbolic-link loop, or no file."""
    try:
        os.stat(path)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link loop (too many levels of symbolic links)"
    return "no such file"


@contextlib.contextmanager
def captured_c_output(fd: int = 2) -> Iterator[list[str]]:
    """Capture what C/C++ code (urdfdom, MuJoCo's compiler) writes to file descriptor ``fd``.

    Yields a list that holds the captured lines once the block has ended.
    """
    lines: list[str] = []
    stream = sys.stdout if fd == 1 else sys.stderr
    try:
        stream.flush()
        saved = os.dup(fd)
    except (OSError, ValueError, AttributeError):  # no such stream to protect
        yield lines
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), fd)
        try:
            yield lines
        finally:
            os.dup2(saved, fd)
            os.close(saved)
            sink.seek(0)
            text = sink.read().decode("utf-8", "replace")
            lines.extend(line.strip() for line in text.splitlines() if line.strip())


_captured_stderr_fd = captured_c_output


def _build_model(xml: str, source: str, floating: bool) -> pin.Model:
    from gimwatch.model.urdf_text import check_urdf

    root = check_urdf(xml, source)
    depth = _tree_depth(root)
    if depth > MAX_TREE_DEPTH:
        raise URDFError(
            source,
            f"a branch of {depth} joints is deeper than Pinocchio's parser can read "
            f"(limit {MAX_TREE_DEPTH}); use the DeNOC path (gimwatch.denoc) instead",
        )
    # check_urdf reads every value urdfdom reads; should urdfdom still complain, its lines
    # become the error message instead of stray output on the user's terminal.
    with _captured_stderr_fd() as complaints:
        try:
            if floating:
                model = pin.buildModelFromXML(xml, pin.JointModelFreeFlyer())
            else:
                model = pin.buildModelFromXML(xml)
        except (RuntimeError, ValueError) as exc:
            model, failure = None, exc
    errors = [line for line in complaints if line.startswith("Error:")]
    if model is None or errors:
        detail = errors[0].removeprefix("Error:").strip() if errors else str(failure)
        raise URDFError(source, f"Pinocchio cannot build a model: {detail}")
    return model


def _tree_depth(root) -> int:
    """Joints on the longest root-to-leaf path of a URDF tree (check_urdf made it a tree)."""
    children: dict[str, list[str]] = {}
    child_links = set()
    for joint in root.findall("joint"):
        parent, child = joint.find("parent").get("link"), joint.find("child").get("link")
        children.setdefault(parent, []).append(child)
        child_links.add(child)
    (top,) = (
        link.get("name") for link in root.findall("link") if link.get("name") not in child_links
    )
    deepest, stack = 0, [(top, 0)]
    while stack:
        link, depth = stack.pop()
        deepest = max(deepest, depth)
        stack.extend((child, depth + 1) for child in children.get(link, ()))
    return deepest


def _too_large(spec: str, nv: int) -> RobotError:
    return RobotError(
        spec,
        f"nv = {nv} is too large for Pinocchio's Data (its memory grows as nv^3; "
        f"limit {DATA_NV_LIMIT}); use the O(n) DeNOC path instead",
    )


def _too_deep(spec: str) -> RobotError:
    return RobotError(
        spec, f"Pinocchio's URDF parser reads at most {MAX_TREE_DEPTH} links in a chain"
    )


def is_mjcf(xml: str) -> bool:
    """Whether an XML text's root element is ``<mujoco>`` (after comments and declarations)."""
    return re.match(r"^\s*(<\?[^>]*\?>\s*|<!--.*?-->\s*)*<mujoco\b", xml, re.DOTALL) is not None


def with_free_joint(mjcf_xml: str, source: str) -> str:
    """The MJCF text with ``<freejoint name="root_joint"/>`` in the first body of the world.

    Pinocchio 4's ``buildModelFromMJCF(path, root_joint, name)`` ignores the root joint,
    and MuJoCo's bodies are fixed unless they have a joint, so a floating base is written
    into the text for both.
    """
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(mjcf_xml)
    except ET.ParseError as exc:
        raise URDFError(source, f"is not well-formed XML ({exc})") from exc
    world = root.find("worldbody")
    body = None if world is None else world.find("body")
    if body is None:
        raise URDFError(source, "has no <body> in <worldbody> to put a floating base on")
    if body.find("freejoint") is not None or body.find("joint[@type='free']") is not None:
        return mjcf_xml
    if body.find("joint") is not None:
        raise URDFError(
            source,
            f"its first body '{body.get('name', '')}' already has a joint, so there is no "
            "base body to float; add a <freejoint/> body around it in the MJCF",
        )
    body.insert(0, ET.Element("freejoint", name="root_joint"))
    return ET.tostring(root, encoding="unicode")


def _build_mjcf_model(source: str, floating: bool, xml: str) -> pin.Model:
    """Pinocchio's MJCF parser on the file ``source``; its complaints become one error."""
    with _captured_stderr_fd() as complaints, tempfile.TemporaryDirectory() as folder:
        path = source
        if floating:
            path = str(Path(folder) / Path(source).name)
            Path(path).write_text(with_free_joint(xml, source), encoding="utf-8")
        try:
            model = pin.buildModelFromMJCF(path)
        except Exception as exc:  # boost.python raises RuntimeError, ValueError, ...
            model, failure = None, exc
    if model is None:
        # Pinocchio's message starts with its C++ source location; keep what follows.
        detail = " ".join(str(failure).split("message:")[-1].split()) or type(failure).__name__
        if complaints:
            detail += f" ({complaints[0]})"
        raise URDFError(source, f"Pinocchio cannot read this MJCF: {detail}")
    return model


def _mjcf_robot(xml: str, source: str, name: str, spec: str, floating: bool) -> Robot:
    check_mjcf(xml, source)
    model = _build_mjcf_model(source, floating, xml)
    if model.nv == 0:
        raise RobotError(
            spec, "has no degree of freedom with a fixed base; load it with a floating base"
        )
    return Robot(
        name=name,
        spec=spec,
        model=model,
        urdf_xml="",
        source=source,
        floating=floating,
        mjcf_xml=xml,
    )


def parse_chain_spec(spec: str | Path) -> ChainSpec | None:
    """The :class:`ChainSpec` of a ``chain:N`` specification, or None for other specs."""
    match = _CHAIN_SPEC.match(str(spec))
    if not match:
        return None
    try:
        n = int(match.group(1))
    except ValueError:
        raise InputError("the N of chain:N", "a positive integer", match.group(1)) from None
    return chain_spec(n)


def load_robot(spec: str | Path, floating: bool = False, *, max_nv: int | None = None) -> Robot:
    """Load a robot from ``chain:N``, a URDF path or an example-robot-data name.

    Args:
        spec: The robot specification (see the module docstring).
        floating: Add a free-flyer root joint (6 DoF) instead of fixing the base.
        max_nv: Refuse generated chains with more velocity coordinates than this before
            building anything (callers that will need a Pinocchio Data pass DATA_NV_LIMIT).

    Returns:
        The loaded :class:`Robot`.

    Raises:
        RobotError: The spec names nothing loadable, or the model has no degree of freedom.
        URDFError: The URDF file is missing, unreadable or invalid.
    """
    text = str(spec)
    if not text.strip():
        raise InputError("the robot", "chain:N, a URDF path or an example-robot-data name", text)
    chain = parse_chain_spec(text)
    if chain is not None:
        n = chain.n
        if max_nv is not None and n + 6 * floating > max_nv:
            raise _too_large(text, n + 6 * floating)
        if n > MAX_TREE_DEPTH:
            raise _too_deep(text)
        xml, source, name = generate_chain_urdf(chain), f"<generated {chain.name}>", chain.name
    elif text in _example_robots():
        path = _example_robot_urdf(text)
        xml, source, name = _read_urdf(path), str(path), text
        if text in EXAMPLE_ROBOT_NOTES:
            warnings.warn(f"{text}: {EXAMPLE_ROBOT_NOTES[text]}", ExampleRobotWarning, stacklevel=2)
    elif text.lower().endswith((".urdf", ".xml")) or Path(text).exists() or "/" in text:
        path = Path(text)
        xml, source, name = _read_urdf(path), str(path), path.stem
        if is_mjcf(xml):
            return _mjcf_robot(xml, source, name, text, floating)
    else:
        close = difflib.get_close_matches(text, _example_robots(), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise RobotError(text, f"not chain:N, a URDF file, or an example-robot-data robot{hint}")
    model = _build_model(xml, source, floating)
    if model.nv == 0:
        raise RobotError(
            text, "has no degree of freedom with a fixed base; load it with a floating base"
        )
    return Robot(
        name=name,
        spec=text,
        model=model,
        urdf_xml=xml,
        source=source,
        floating=floating,
        chain=chain,
    )


def chain_robot(spec: ChainSpec, *, floating: bool = False) -> Robot:
    """A :class:`Robot` for a generated chain of any rods (no Pinocchio Data is built).

    Raises:
        RobotError: The chain is deeper than Pinocchio's URDF parser can read.
    """
    if spec.n > MAX_TREE_DEPTH:
        raise _too_deep(f"chain:{spec.n}")
    xml = generate_chain_urdf(spec)
    source = f"<generated {spec.name}>"
    model = _build_model(xml, source, floating)
    return Robot(spec.name, f"chain:{spec.n}", model, xml, source, floating, spec)


def neutral_configuration(robot: Robot) -> np.ndarray:
    """Pinocchio's neutral configuration (zero angles, identity quaternions)."""
    return pin.neutral(robot.model)


def _unit_block_size(joint: pin.JointModel) -> int:
    """Size of the unit-norm part of a joint's q (4 for quaternions, 2 for unit complex)."""
    if joint.nq == joint.nv:
        return 0
    kind = joint.shortname()
    return 4 if ("Spherical" in kind or "FreeFlyer" in kind) else 2


#: A joint limit this large (or infinite) is a placeholder for "unlimited" (URDF writers put
#: 1e3 ... 1e16 there); random configurations then use ±π rad / ±1 m instead.
PLACEHOLDER_LIMIT = 1e3


def _is_real_limit(limit: np.ndarray) -> np.ndarray:
    return np.isfinite(limit) & (np.abs(limit) < PLACEHOLDER_LIMIT)


def placeholder_limit_joints(robot: Robot) -> tuple[str, ...]:
    """Joints with a coordinate whose limit is a placeholder (|limit| >= 1e3 or infinite).

    :func:`random_configurations` draws those coordinates in ±π rad (angles) or ±1 m
    (translations, the free-flyer's position included) instead. Continuous joints and
    quaternions have no limit to read and are not listed.
    """
    model = robot.model
    lower, upper = np.array(model.lowerPositionLimit), np.array(model.upperPositionLimit)
    names = []
    for joint, name in zip(model.joints[1:], model.names[1:], strict=True):
        box = slice(joint.idx_q, joint.idx_q + joint.nq - _unit_block_size(joint))
        if not (np.all(_is_real_limit(lower[box])) and np.all(_is_real_limit(upper[box]))):
            names.append(name)
    return tuple(names)


def random_configurations(robot: Robot, count: int = 1, *, seed: int | None = None) -> np.ndarray:
    """Configurations drawn uniformly within the joint limits, shape ``(count, nq)``.

    Unbounded coordinates, and those whose limit is a placeholder (|limit| >= 1e3, see
    :func:`placeholder_limit_joints`), are drawn in ±π rad (angles) or ±1 m (translations);
    quaternions
    and the unit complex numbers of continuous joints are drawn uniformly on their sphere.

    Args:
        robot: The robot.
        count: Number of configurations, >= 1.
        seed: Seed of NumPy's generator; the same seed gives the same configurations.
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InputError("count", "a positive integer", count)
    if count * robot.nq > MAX_RANDOM_NUMBERS:
        limit = MAX_RANDOM_NUMBERS // robot.nq
        raise InputError("count", f"at most {limit} for {robot.name} (nq = {robot.nq})", count)
    if seed is not None and (
        isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0
    ):
        raise InputError("seed", "None or an integer >= 0", seed)
    model = robot.model
    rng = np.random.default_rng(seed)
    lower = np.array(model.lowerPositionLimit, dtype=float)
    upper = np.array(model.upperPositionLimit, dtype=float)
    qs = np.empty((count, model.nq))
    for joint in model.joints[1:]:
        start, stop = joint.idx_q, joint.idx_q + joint.nq
        unit = _unit_block_size(joint)
        box = slice(start, stop - unit)
        default = (
            _DEFAULT_ANGLE_RAD
            if joint.shortname().startswith("JointModelR")
            else (_DEFAULT_TRANSLATION_M)
        )
        lo = np.where(_is_real_limit(lower[box]), lower[box], -default)
        hi = np.where(_is_real_limit(upper[box]), upper[box], default)
        qs[:, box] = rng.uniform(lo, hi, size=(count, stop - unit - start))
        if unit:
            block = rng.standard_normal((count, unit))
            qs[:, stop - unit : stop] = block / np.linalg.norm(block, axis=1, keepdims=True)
    return qs


#: |‖block‖ − 1| allowed for the unit blocks of a q given to the library functions.
UNIT_NORM_TOLERANCE = 1e-6


def as_configuration(robot: Robot, q: npt.ArrayLike) -> np.ndarray:
    """Check that ``q`` is a finite real vector of length nq and return it as an array.

    Each unit block (a continuous joint's (cos θ, sin θ), a quaternion) must have norm 1
    within :data:`UNIT_NORM_TOLERANCE`: Pinocchio would use a zero block as is, freezing
    the joint (a zero rotation matrix) and giving a wrong M(q).
    """
    try:
        array = np.asarray(q)
        if array.dtype.kind not in "biuf":
            raise TypeError(f"{array.dtype.name} entries")
        array = array.astype(float)
    except (TypeError, ValueError) as exc:
        raise InputError("q", "a vector of real numbers", str(exc)) from None
    if array.shape != (robot.nq,):
        raise InputError("q", f"a vector of {robot.nq} numbers for {robot.name}", array.shape)
    if not np.all(np.isfinite(array)):
        raise InputError("q", "finite", array.tolist())
    for joint, name in zip(robot.model.joints[1:], robot.model.names[1:], strict=True):
        unit = _unit_block_size(joint)
        if unit:
            stop = joint.idx_q + joint.nq
            norm = float(np.linalg.norm(array[stop - unit : stop]))
            if not abs(norm - 1.0) <= UNIT_NORM_TOLERANCE:
                what = "quaternion" if unit == 4 else "(cos θ, sin θ)"
                raise InputError(
                    f"the {what} of joint {name!r} in q",
                    f"of norm 1 (within {UNIT_NORM_TOLERANCE:g})",
                    round(norm, 9),
                )
    return array
