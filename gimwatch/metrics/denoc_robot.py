"""DeNOC's model of a gimwatch robot, its coordinates in Pinocchio's order."""

from __future__ import annotations

import numpy as np

from gimwatch.denoc import DenocModel
from gimwatch.denoc.tree import FREE_FLYER_NAME, body_tree
from gimwatch.errors import InputError
from gimwatch.model.denoc_input import tree_arrays
from gimwatch.model.robots import Robot

__all__ = ["denoc_model"]


def denoc_model(robot: Robot, *, parse: bool = False, rigid: bool = False) -> DenocModel:
    """DeNOC's model of ``robot`` (fixed or floating base, as loaded).

    A generated fixed-base chain is built from its spec unless ``parse`` (then, as for every
    other robot, from its URDF text through yourdfpy). A free joint at the root of the whole
    tree, gimwatch's or an MJCF file's own, is DeNOC's free-flyer. A model whose tree has no
    URDF form (an MJCF file's several free joints, several trees) is read from its Pinocchio
    Model (`tree_arrays`: its Model only, no Data): free joints on any body, many trees.

    DeNOC models rigid bodies only: a robot whose M has joint armature (MuJoCo's
    ``dof_armature``, kept by default) is refused unless ``rigid`` says the caller compares
    with M without it (as `gimwatch.crosscheck` does).

    Raises:
        URDFError: DeNOC cannot read the robot's URDF (a joint type it lacks).
        RobotError: A joint DeNOC has no recursion for (a planar or composite joint), named.
        InputError: The robot has armature and ``rigid`` is False.
    """
    if not rigid and np.any(np.asarray(robot.model.armature) != 0):
        raise InputError(
            f"{robot.name}'s armature",
            "zero for DeNOC (rigid bodies only)",
            "nonzero",
            hint="load it without armature (--no-armature) or use Pinocchio",
        )
    if robot.chain is not None and not robot.floating and not parse:
        return DenocModel.from_chain(robot.chain)  # no URDF parsing for chain:N
    if not robot.urdf_xml:
        tree = body_tree(tree_arrays(robot.model, source=robot.source))
        return DenocModel(tree, robot.joint_names)
    order = list(robot.joint_names)
    if robot.free_base:
        order[0] = FREE_FLYER_NAME  # an MJCF file names its own free joint
    return DenocModel.from_urdf(
        robot.urdf_xml, floating=robot.free_base, source=robot.source, joint_order=order
    )
