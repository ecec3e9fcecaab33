"""The hard cases of the stress suite, each a robot plus one configuration.

Long, tapered, lopsided and mixed chains, robots at singular poses, floating humanoids.

Chains come from the generator
([`chain_spec`][gimwatch.model.chains.chain_spec]); robots from
example-robot-data. A case is built lazily (`StressCase.build`), so listing the cases costs nothing
and a 500-link chain is only generated when it is run.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from gimwatch.model.chains import ChainSpec, chain_spec
from gimwatch.model.robots import Robot, chain_robot, load_robot, neutral_configuration

__all__ = ["CASES", "CHAIN_GRAVITY_M_S2", "ROBOT_GRAVITY_M_S2", "StressCase"]

#: Chains lie in the xy-plane at q = 0 (joints about z), gravity in that plane.
CHAIN_GRAVITY_M_S2 = (0.0, -9.81, 0.0)
ROBOT_GRAVITY_M_S2 = (0.0, 0.0, -9.81)


@dataclass(frozen=True)
class StressCase:
    """One hard case.

    Attributes:
        name: Short unique name (``straight-100``).
        family: The group it belongs to (``straight``, ``tapered``, ``robot-singular``, ...).
        description: What makes it hard, one line.
        make: Builds (robot, q).
        gravity_m_s2: Gravity in the world.
        quick: Part of ``gimwatch stress --quick`` and of the default test run.
        spec: The chain spec for generated chains (the planar closed-form reference uses it).
        no_simulation: Why the 5 s simulation is not run on this case ("" = it is run).
    """

    name: str
    family: str
    description: str
    make: Callable[[], tuple[Robot, np.ndarray]]
    gravity_m_s2: tuple[float, float, float] = CHAIN_GRAVITY_M_S2
    quick: bool = False
    spec: ChainSpec | None = field(default=None, repr=False)
    no_simulation: str = ""

    def build(self) -> tuple[Robot, np.ndarray]:
        """The robot and the configuration q of this case."""
        return self.make()


def _chain_case(name, family, description, spec, q_of_n, *, quick=False, no_sim="") -> StressCase:
    def make():
        return chain_robot(spec), q_of_n(spec.n)

    return StressCase(name, family, description, make, CHAIN_GRAVITY_M_S2, quick, spec, no_sim)


def _geometric(n: int, first: float, last: float) -> list[float]:
    return np.geomspace(first, last, n).tolist()


def _robot_case(name, family, description, robot_name, q_update, *, floating=False, quick=False):
    def make():
        robot = load_robot(robot_name, floating=floating)
        q = neutral_configuration(robot)
        for index, value in q_update(robot).items():
            q[index] = value
        return robot, q

    return StressCase(name, family, description, make, ROBOT_GRAVITY_M_S2, quick)


def _joint_q(robot: Robot, values: dict[str, float]) -> dict[int, float]:
    model = robot.model
    return {model.joints[model.getJointId(name)].idx_q: value for name, value in values.items()}


_UR5_WRIST = {"shoulder_lift_joint": -np.pi / 2, "elbow_joint": np.pi / 2, "wrist_2_joint": 0.0}
_UR5_ELBOW = {"shoulder_lift_joint": -np.pi / 2, "elbow_joint": 0.0, "wrist_1_joint": -np.pi / 2}


def _cases() -> list[StressCase]:
    cases = []
    for n in (100, 200, 500):
        cases.append(
            _chain_case(
                f"straight-{n}",
                "straight",
                f"paper chain of {n} rods, stretched out (q = 0)",
                chain_spec(n),
                np.zeros,
                quick=n == 100,
            )
        )
        cases.append(
            _chain_case(
                f"curled-{n}",
                "curled",
                f"paper chain of {n} rods curled into a spiral (q_i = {6.0 / n:.3g} rad)",
                chain_spec(n),
                lambda n: np.full(n, 6.0 / n),
                quick=n == 100,
            )
        )
    n = 30
    cases += [
        _chain_case(
            "tapered-30",
            "tapered",
            "mass and length fall geometrically to 1e-6 of the root link's (2.2 kg, 1 m)",
            chain_spec(n, mass_kg=_geometric(n, 2.2, 2.2e-6), length_m=_geometric(n, 1.0, 1e-6)),
            lambda n: np.full(n, 0.2),
            quick=True,
            no_sim="stiff: the 1 µm tip swings on a ~1e-4 s time scale, so 5 s of an explicit "
            "integrator would take hours; its M is numerically singular anyway (κ > 1/eps)",
        ),
        _chain_case(
            "tapered-mass-30",
            "tapered",
            "mass falls geometrically to 1e-6 of the root's, lengths equal (1 m)",
            chain_spec(n, mass_kg=_geometric(n, 2.2, 2.2e-6)),
            lambda n: np.full(n, 0.2),
            quick=True,
        ),
        _chain_case(
            "heavy-root-20",
            "lopsided",
            "1000 kg root link, 2.2 kg middle, 1 g tip on a 1 cm rod",
            chain_spec(
                20,
                mass_kg=[1000.0] + [2.2] * 18 + [1e-3],
                length_m=[1.0] * 19 + [0.01],
            ),
            lambda n: np.full(n, 0.3),
            quick=True,
        ),
        _chain_case(
            "feather-root-20",
            "lopsided",
            "the reverse: 1 g root on a 1 cm rod, 2.2 kg middle, 1000 kg tip",
            chain_spec(
                20,
                mass_kg=[1e-3] + [2.2] * 18 + [1000.0],
                length_m=[0.01] + [1.0] * 19,
            ),
            lambda n: np.full(n, 0.3),
            quick=True,
        ),
        _chain_case(
            "mixed-spatial-24",
            "mixed",
            "spatial chain, axes z, y, x in turn, every third joint prismatic",
            chain_spec(
                24,
                axes=["z", "y", "x"] * 8,
                joint_types=["revolute", "revolute", "prismatic"] * 8,
                radius_m=0.05,
            ),
            lambda n: np.tile([0.4, -0.3, 0.1], n // 3),
            quick=True,
        ),
        _chain_case(
            "mixed-spatial-90",
            "mixed",
            "spatial chain of 90, axes z, y, x in turn, every third joint prismatic",
            chain_spec(
                90,
                axes=["z", "y", "x"] * 30,
                joint_types=["revolute", "revolute", "prismatic"] * 30,
                radius_m=0.05,
            ),
            lambda n: np.tile([0.2, -0.1, 0.05], n // 3),
        ),
    ]
    cases += [
        _robot_case(
            "ur5-wrist-aligned",
            "robot-singular",
            "UR5 with wrist_2 = 0: wrist_1 and wrist_3 axes aligned",
            "ur5",
            lambda r: _joint_q(r, _UR5_WRIST),
            quick=True,
        ),
        _robot_case(
            "ur5-near-wrist",
            "robot-singular",
            "UR5 1e-6 rad from the aligned wrist",
            "ur5",
            lambda r: _joint_q(r, {**_UR5_WRIST, "wrist_2_joint": 1e-6}),
        ),
        _robot_case(
            "ur5-elbow-straight",
            "robot-singular",
            "UR5 with the elbow straight (elbow = 0): boundary singularity",
            "ur5",
            lambda r: _joint_q(r, _UR5_ELBOW),
            quick=True,
        ),
        _robot_case(
            "panda-zero",
            "robot-singular",
            "Panda at q = 0: joints 1, 3, 5 and 7 aligned",
            "panda",
            lambda r: {},
            quick=True,
        ),
        _robot_case(
            "panda-near-zero",
            "robot-singular",
            "Panda 1e-6 rad from q = 0",
            "panda",
            lambda r: dict.fromkeys(range(7), 1e-6),
        ),
        _robot_case(
            "talos-arm-zero",
            "robot-singular",
            "Talos arm stretched (q = 0), with its gripper",
            "talos_arm",
            lambda r: {},
            quick=True,
        ),
        _robot_case(
            "talos-floating",
            "floating",
            "Talos humanoid on a free-flyer (light grippers, 1 body of 95 kg total)",
            "talos",
            lambda r: {},
            floating=True,
        ),
        _robot_case(
            "g1-hands-floating",
            "floating",
            "Unitree G1 with dexterous hands on a free-flyer (finger links of a few grams)",
            "g1_with_hands",
            lambda r: {},
            floating=True,
        ),
    ]
    return cases


#: Every case, by name, in table order.
CASES: dict[str, StressCase] = {case.name: case for case in _cases()}
