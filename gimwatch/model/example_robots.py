"""The robots of example-robot-data: their names, their URDF files, and what differs.

gimwatch reads the URDF file a name's loader class points at, as written (no joints locked,
no rotor inertias from the SRDF); `EXAMPLE_ROBOT_NOTES` says where that differs from
what the name or ``example_robot_data.load(name)`` gives.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from gimwatch.errors import RobotError

if TYPE_CHECKING:  # example-robot-data ships no type information: RobotLoader reads as Any
    from example_robot_data.robots_loader import RobotLoader

__all__ = [
    "EXAMPLE_ROBOT_NOTES",
    "example_robot_loaders",
    "example_robot_names",
    "example_robot_urdf",
]


@cache
def example_robot_loaders() -> dict[str, type[RobotLoader]]:
    """example-robot-data's loader classes by robot name (imported on first use)."""
    from example_robot_data.robots_loader import ROBOTS

    return dict(ROBOTS)


#: example-robot-data names whose model, as gimwatch loads it (the URDF file as written, no
#: reduction), is not what the name or ``example_robot_data.load(name)`` suggests.
#: ``load_robot`` issues each as one [`ExampleRobotWarning`][gimwatch.errors.ExampleRobotWarning];
#: the test ``tests/test_example_robot_loader.py`` compares every name with
#: ``example_robot_data.load``.
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
    return tuple(example_robot_loaders())


def example_robot_urdf(name: str) -> Path:
    """The URDF file example-robot-data's loader class for ``name`` points at."""
    from example_robot_data.robots_loader import getModelPath

    loader = example_robot_loaders()[name]
    if not loader.urdf_filename:
        raise RobotError(name, "example-robot-data ships it only as SDF; gimwatch reads URDF")
    relative = str(Path(loader.path) / loader.urdf_subpath / loader.urdf_filename)
    return (Path(getModelPath(relative)) / relative).resolve()
