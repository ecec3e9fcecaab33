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

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from gimwatch.errors import ExampleRobotWarning, InputError, RobotError, URDFError
from gimwatch.joint_kinds import JointKind, joint_kind
from gimwatch.model.captured_output import captured_c_output
from gimwatch.model.chains import ChainSpec, generate_chain_urdf
from gimwatch.model.example_robots import EXAMPLE_ROBOT_NOTES, example_robot_urdf
from gimwatch.model.mjcf_model import is_mjcf
from gimwatch.model.robot_files import read_robot_file
from gimwatch.model.robot_spec import RobotSpec, robot_spec

__all__ = [
    "DATA_NV_LIMIT",
    "MAX_TREE_DEPTH",
    "Robot",
    "chain_robot",
    "load_robot",
    "neutral_configuration",
]

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
        robot_spec: The parsed [`RobotSpec`][gimwatch.model.robot_spec.RobotSpec] it was
            loaded from (None for a Robot made by hand).
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
    robot_spec: RobotSpec | None = None
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


def _too_deep(spec: str) -> RobotError:
    return RobotError(
        spec, f"Pinocchio's URDF parser reads at most {MAX_TREE_DEPTH} links in a chain"
    )


def _mjcf_robot(xml: str, parsed: RobotSpec) -> Robot:
    from gimwatch.model.mjcf_robot import read_mjcf

    body = parsed.body
    model, joint_ids, urdf_xml = read_mjcf(
        parsed.text, floating=parsed.floating, body=body, armature=parsed.armature
    )
    return _robot(
        model,
        parsed,
        name=f"{parsed.name}[{body}]" if body else parsed.name,  # reports name the subtree
        urdf_xml=urdf_xml,
        source=parsed.text,
        floating=parsed.floating,
        mjcf_xml=xml,
        mjcf_body=body,
        mjcf_armature=parsed.armature,
        mujoco_joints=joint_ids,
    )


def _robot(model: pin.Model, parsed: RobotSpec, **fields) -> Robot:
    """The one place a `Robot` is made, from a URDF's or an MJCF's Pinocchio model.

    Raises:
        RobotError: The model has no degree of freedom (a fixed single body).
    """
    if model.nv == 0:
        raise RobotError(
            parsed.text, "has no degree of freedom with a fixed base; load it with a floating base"
        )
    return Robot(model=model, spec=parsed.text, robot_spec=parsed, **fields)


def load_robot(
    spec: RobotSpec | str | Path,
    floating: bool | None = None,
    *,
    max_nv: int | None = None,
    body: str | None = None,
    armature: bool | None = None,
) -> Robot:
    """Load a robot from its `RobotSpec`, or from ``chain:N``, a URDF path or a robot's name.

    Args:
        spec: A parsed [`RobotSpec`][gimwatch.model.robot_spec.RobotSpec], or its text (parsed
            here, once: see the module docstring).
        floating: True adds a free-flyer root joint (6 DoF), False fixes the base; None (the
            default): the spec's (`default_floating`: example-robot-data's base for its
            robots, a free-flyer for ``anymal``, ``solo12``, ``talos``, ...), fixed otherwise.
        max_nv: Refuse generated chains with more velocity coordinates than this before
            building anything (callers that will need a Pinocchio Data pass DATA_NV_LIMIT).
        body: MJCF only: read the subtree of this body (its ancestors held at ``qpos0``)
            instead of the whole model; None: the spec's ("" when parsed here).
        armature: MJCF only: keep MuJoCo's ``dof_armature`` in M (False leaves it out);
            None: the spec's (True when parsed here).

    Returns:
        The loaded [`Robot`][gimwatch.model.robots.Robot], which keeps its `RobotSpec`.

    Raises:
        RobotError: The spec names nothing loadable, or the model has no degree of freedom.
        URDFError: The URDF file is missing, unreadable or invalid.
    """
    parsed = robot_spec(spec, floating=floating, body=body, armature=armature)
    text, chain = parsed.text, parsed.chain
    if chain is not None:
        n = chain.n
        if max_nv is not None and n + 6 * parsed.floating > max_nv:
            raise _too_large(text, n + 6 * parsed.floating)
        if n > MAX_TREE_DEPTH:
            raise _too_deep(text)
        xml, source = generate_chain_urdf(chain), f"<generated {chain.name}>"
    elif parsed.kind == "example":
        path = example_robot_urdf(text)
        xml, source = read_robot_file(path), str(path)
        if text in EXAMPLE_ROBOT_NOTES:
            warnings.warn(f"{text}: {EXAMPLE_ROBOT_NOTES[text]}", ExampleRobotWarning, stacklevel=2)
    else:
        xml, source = read_robot_file(Path(text)), text
        if is_mjcf(xml):
            return _mjcf_robot(xml, parsed)
    if parsed.body:
        raise InputError("body", "given only with an MJCF file", parsed.body)
    model, xml = _build_model(xml, source, parsed.floating)
    return _robot(
        model,
        parsed,
        name=parsed.name,
        urdf_xml=xml,
        source=source,
        floating=parsed.floating,
        chain=chain,
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
    text = f"chain:{spec.n}"
    parsed = RobotSpec(text, "chain", floating, spec)
    return _robot(
        model, parsed, name=spec.name, urdf_xml=xml, source=source, floating=floating, chain=spec
    )


def neutral_configuration(robot: Robot) -> np.ndarray:
    """Pinocchio's neutral configuration (zero angles, identity quaternions)."""
    return pin.neutral(robot.model)
