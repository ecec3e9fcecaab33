"""Turn a robot specification into a `Robot` (a Pinocchio model plus what it came from).

A specification is one of:

* ``chain:N`` — the paper's chain of N slender rods (2.2 kg, 1 m), generated on the fly;
* a path to a URDF file;
* a path to an MJCF file (``.xml`` whose root element is ``<mujoco>``), compiled by MuJoCo
  and rebuilt in Pinocchio from the compiled model (`gimwatch.model.mjcf_compiled`);
* the name of a robot in example-robot-data (``ur5``, ``panda``, ``talos_arm``, ...).

An MJCF robot keeps its file's text in ``mjcf_xml``; its ``urdf_xml`` is URDF text written
from the compiled model when DeNOC can read the tree (hinges and slides on one tree, at most
a free joint at its root), else "" (docs/robots.md).

The base is the one example-robot-data's loader gives a robot of its own (a free-flyer for
legged robots, humanoids and drones, as ``example_robot_data.load(name)`` builds them; see
`default_floating`), and fixed for chains and files; ``floating=True`` adds Pinocchio's
free-flyer root joint, ``floating=False`` fixes the base.
No `pinocchio.Data` is built here: its memory grows as nv^3 (about 1.8 GB at
nv = 300), so callers ask for it with [`Robot.new_data`][gimwatch.model.robots.Robot.new_data] only
when they need it.
"""

from __future__ import annotations

import difflib
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from gimwatch.errors import ExampleRobotWarning, InputError, RobotError, URDFError
from gimwatch.joint_kinds import JointKind, joint_kind
from gimwatch.model.captured_output import captured_c_output
from gimwatch.model.chains import ChainSpec, chain_spec, generate_chain_urdf
from gimwatch.model.example_robots import (
    EXAMPLE_ROBOT_NOTES,
    example_robot_loaders,
    example_robot_names,
    example_robot_urdf,
)
from gimwatch.model.mjcf_model import is_mjcf
from gimwatch.model.q_checks import UNIT_NORM_TOLERANCE, as_configuration, unit_blocks
from gimwatch.model.robot_files import read_robot_file
from gimwatch.model.sampling import (
    PLACEHOLDER_LIMIT,
    check_random_budget,
    placeholder_limit_joints,
    random_configurations,
)

__all__ = [
    "EXAMPLE_ROBOT_NOTES",
    "PLACEHOLDER_LIMIT",
    "UNIT_NORM_TOLERANCE",
    "Robot",
    "as_configuration",
    "captured_c_output",
    "chain_robot",
    "check_random_budget",
    "default_floating",
    "display_name",
    "example_robot_names",
    "is_mjcf",
    "load_robot",
    "neutral_configuration",
    "parse_chain_spec",
    "placeholder_limit_joints",
    "random_configurations",
    "unit_blocks",
]

_CHAIN_SPEC = re.compile(r"^chain:(\S+)$")
#: Above this many velocity coordinates, a Pinocchio Data would need several GB.
DATA_NV_LIMIT = 400
#: Pinocchio's URDF parser recurses once per link along a branch and overflows the 8 MB
#: C stack (a segmentation fault) between 3500 and 4000 links; deeper trees are refused.
MAX_TREE_DEPTH = 2000


def _own_free_root(model: pin.Model) -> bool:
    """Joint 1 is a free-flyer and every other joint hangs below it (one floating tree)."""
    if model.njoints < 2 or joint_kind(model.joints[1]) is not JointKind.FREE_FLYER:
        return False
    return all(model.parents[k] != 0 for k in range(2, model.njoints))


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
        mjcf_xml: The MJCF text for robots read from MJCF, else "".
        mjcf_body: For MJCF, the body whose subtree was selected ("" for the whole model).
        mjcf_armature: For MJCF, whether MuJoCo's ``dof_armature`` is in M (as in MuJoCo).
        mujoco_joints: For MJCF, MuJoCo's joint id of each Pinocchio joint, else ().
        dof_names: One name per velocity coordinate (``joint[k]`` for a joint of several).
        free_base: Whether the whole tree moves on one free joint at its root: the
            free-flyer gimwatch added (``floating``) or, in an MJCF file, the file's own free
            joint when no other tree hangs from the world (set once: read every sample).
    """

    name: str
    spec: str
    model: pin.Model
    urdf_xml: str
    source: str
    floating: bool = False
    chain: ChainSpec | None = None
    mjcf_xml: str = ""
    mjcf_body: str = ""
    mjcf_armature: bool = True
    mujoco_joints: tuple[int, ...] = ()
    dof_names: tuple[str, ...] = field(init=False)
    free_base: bool = field(init=False)

    def __post_init__(self) -> None:
        names = []
        for joint, joint_name in zip(self.model.joints[1:], self.model.names[1:], strict=True):
            if joint.nv == 1:
                names.append(joint_name)
            else:
                names.extend(f"{joint_name}[{k}]" for k in range(joint.nv))
        object.__setattr__(self, "dof_names", tuple(names))
        object.__setattr__(self, "free_base", self.floating or _own_free_root(self.model))

    def __repr__(self) -> str:  # the model and the URDF text would fill a screen
        base = "floating" if self.free_base else "fixed"
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
        """A fresh `pinocchio.Data`; refuses models whose Data would not fit in memory."""
        if self.nv > DATA_NV_LIMIT:
            raise _too_large(self.spec, self.nv)
        return self.model.createData()


def _build_model(xml: str, source: str, floating: bool) -> tuple[pin.Model, str]:
    """Pinocchio's model of checked URDF text, and the text it read (normalised quirks)."""
    from gimwatch.model.urdf_text import check_urdf_text

    root, xml = check_urdf_text(xml, source, stacklevel=3, floating=floating)
    depth = _tree_depth(root)
    if depth > MAX_TREE_DEPTH:
        raise URDFError(
            source,
            f"a branch of {depth} joints is deeper than Pinocchio's parser can read "
            f"(limit {MAX_TREE_DEPTH}); use the DeNOC path (gimwatch.denoc) instead",
        )
    # check_urdf reads every value urdfdom reads; should urdfdom still complain, its lines
    # become the error message instead of stray output on the user's terminal.
    with captured_c_output() as complaints:
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
    return model, xml


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
        f"limit DATA_NV_LIMIT = {DATA_NV_LIMIT}); the O(n) DeNOC path reads it: "
        "analyze with backend 'denoc' (the default 'auto' takes it above the limit)",
    )


def display_name(text: str) -> str:
    r"""``text`` printable as UTF-8, whatever bytes a file name holds.

    Bytes of a file name that are not UTF-8 (Python keeps them as lone surrogates) become
    ``\xNN``, so figure titles, tables and JSON never fail on them.
    """
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def _too_deep(spec: str) -> RobotError:
    return RobotError(
        spec, f"Pinocchio's URDF parser reads at most {MAX_TREE_DEPTH} links in a chain"
    )


def _mjcf_robot(
    xml: str, source: str, name: str, spec: str, floating: bool, body: str, armature: bool
) -> Robot:
    from gimwatch.model.mjcf_robot import read_mjcf

    model, joint_ids, urdf_xml = read_mjcf(source, floating=floating, body=body, armature=armature)
    return _robot(
        model,
        name=f"{name}[{body}]" if body else name,  # reports say which subtree was read
        spec=spec,
        urdf_xml=urdf_xml,
        source=source,
        floating=floating,
        mjcf_xml=xml,
        mjcf_body=body,
        mjcf_armature=armature,
        mujoco_joints=joint_ids,
    )


def _robot(model: pin.Model, *, spec: str, **fields) -> Robot:
    """The one place a `Robot` is made, from a URDF's or an MJCF's Pinocchio model.

    Raises:
        RobotError: The model has no degree of freedom (a fixed single body).
    """
    if model.nv == 0:
        raise RobotError(
            spec, "has no degree of freedom with a fixed base; load it with a floating base"
        )
    return Robot(model=model, spec=spec, **fields)


def parse_chain_spec(spec: str | Path) -> ChainSpec | None:
    """The `ChainSpec` of a ``chain:N`` specification, or None for other specs."""
    match = _CHAIN_SPEC.match(str(spec))
    if not match:
        return None
    try:
        n = int(match.group(1))
    except ValueError:
        raise InputError("the N of chain:N", "a positive integer", match.group(1)) from None
    return chain_spec(n)


def default_floating(spec: str | Path) -> bool:
    """The base a robot gets when none is asked for: True for a free-flyer.

    An example-robot-data robot gets its loader's (``free_flyer``: legged robots, humanoids,
    drones), so that ``load_robot(name)`` has the nq and nv of ``example_robot_data.load``;
    chains and files get a fixed base.
    """
    loader = example_robot_loaders().get(str(spec))
    return bool(getattr(loader, "free_flyer", False)) if loader is not None else False


def load_robot(
    spec: str | Path,
    floating: bool | None = None,
    *,
    max_nv: int | None = None,
    body: str = "",
    armature: bool = True,
) -> Robot:
    """Load a robot from ``chain:N``, a URDF path or an example-robot-data name.

    Args:
        spec: The robot specification (see the module docstring).
        floating: True adds a free-flyer root joint (6 DoF), False fixes the base; None (the
            default): `default_floating`, example-robot-data's base for its robots
            (a free-flyer for ``anymal``, ``solo12``, ``talos``, ...), fixed otherwise.
        max_nv: Refuse generated chains with more velocity coordinates than this before
            building anything (callers that will need a Pinocchio Data pass DATA_NV_LIMIT).
        body: MJCF only: read the subtree of this body (its ancestors held at ``qpos0``)
            instead of the whole model.
        armature: MJCF only: keep MuJoCo's ``dof_armature`` in M (False leaves it out).

    Returns:
        The loaded [`Robot`][gimwatch.model.robots.Robot].

    Raises:
        RobotError: The spec names nothing loadable, or the model has no degree of freedom.
        URDFError: The URDF file is missing, unreadable or invalid.
    """
    text = str(spec)
    if not text.strip():
        raise InputError("the robot", "chain:N, a URDF path or an example-robot-data name", text)
    chain = parse_chain_spec(text)
    if floating is None:
        floating = chain is None and default_floating(text)
    if chain is not None:
        n = chain.n
        if max_nv is not None and n + 6 * floating > max_nv:
            raise _too_large(text, n + 6 * floating)
        if n > MAX_TREE_DEPTH:
            raise _too_deep(text)
        xml, source, name = generate_chain_urdf(chain), f"<generated {chain.name}>", chain.name
    elif text in example_robot_loaders():
        path = example_robot_urdf(text)
        xml, source, name = read_robot_file(path), str(path), text
        if text in EXAMPLE_ROBOT_NOTES:
            warnings.warn(f"{text}: {EXAMPLE_ROBOT_NOTES[text]}", ExampleRobotWarning, stacklevel=2)
    elif text.lower().endswith((".urdf", ".xml")) or Path(text).exists() or "/" in text:
        path = Path(text)
        xml, source, name = read_robot_file(path), str(path), display_name(path.stem)
        if is_mjcf(xml):
            return _mjcf_robot(xml, source, name, text, floating, body, armature)
    else:
        names = list(example_robot_loaders())
        close = [n for n in names if n.lower() == text.lower()]  # UR5 -> ur5
        close = close or difflib.get_close_matches(text.lower(), names, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise RobotError(
            text, f"not chain:N, a URDF or MJCF file, or an example-robot-data robot{hint}"
        )
    if body:
        raise InputError("body", "given only with an MJCF file", body)
    model, xml = _build_model(xml, source, floating)
    return _robot(
        model, name=name, spec=text, urdf_xml=xml, source=source, floating=floating, chain=chain
    )


def chain_robot(spec: ChainSpec, *, floating: bool = False) -> Robot:
    """A `Robot` for a generated chain of any rods (no Pinocchio Data is built).

    Raises:
        RobotError: The chain is deeper than Pinocchio's URDF parser can read.
    """
    if spec.n > MAX_TREE_DEPTH:
        raise _too_deep(f"chain:{spec.n}")
    xml = generate_chain_urdf(spec)
    source = f"<generated {spec.name}>"
    model, xml = _build_model(xml, source, floating)
    return _robot(
        model,
        name=spec.name,
        spec=f"chain:{spec.n}",
        urdf_xml=xml,
        source=source,
        floating=floating,
        chain=spec,
    )


def neutral_configuration(robot: Robot) -> np.ndarray:
    """Pinocchio's neutral configuration (zero angles, identity quaternions)."""
    return pin.neutral(robot.model)
