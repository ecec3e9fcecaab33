"""Configurations drawn at random within a robot's joint limits, and the limits' placeholders.

A joint limit of |limit| >= `PLACEHOLDER_LIMIT` (or infinite) is a URDF writer's way of
saying "unlimited"; such coordinates are drawn in ±π rad (angles) or ±1 m (translations).
Quaternions and the unit complex numbers of continuous joints are drawn uniformly on their
sphere.
"""

from __future__ import annotations

import os
from typing import Protocol

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.joint_kinds import joint_kind, length_positions

__all__ = [
    "DEFAULT_MAX_RANDOM_WORK",
    "MAX_RANDOM_NUMBERS",
    "MAX_RANDOM_WORK_VARIABLE",
    "PLACEHOLDER_LIMIT",
    "check_random_budget",
    "configuration_draws",
    "is_real_limit",
    "placeholder_limit_joints",
    "placeholder_note",
    "random_configurations",
    "unit_block_size",
]

_DEFAULT_ANGLE_RAD = np.pi
_DEFAULT_TRANSLATION_M = 1.0
#: random_configurations refuses to allocate more numbers than this (400 MB).
MAX_RANDOM_NUMBERS = 50_000_000
#: The most random configurations x velocity coordinates the command line analyses in one
#: call (each an O(nv) to O(nv^3) analysis); ``$GIMWATCH_MAX_RANDOM_WORK`` overrides it.
DEFAULT_MAX_RANDOM_WORK = 2_000_000
MAX_RANDOM_WORK_VARIABLE = "GIMWATCH_MAX_RANDOM_WORK"


class Robot(Protocol):
    """What sampling reads of a `gimwatch.model.robots.Robot` (no import: no cycle)."""

    # read-only members: the Robot record is a frozen dataclass
    @property
    def name(self) -> str: ...
    @property
    def nq(self) -> int: ...
    @property
    def model(self) -> pin.Model: ...


def unit_block_size(joint: pin.JointModel) -> int:
    """Size of the unit-norm part of a joint's q (4 for quaternions, 2 for unit complex)."""
    return joint_kind(joint).unit_block


#: A joint limit this large (or infinite) is a placeholder for "unlimited" (URDF writers put
#: 1e3 ... 1e16 there); random configurations then use ±π rad / ±1 m instead.
PLACEHOLDER_LIMIT = 1e3


def is_real_limit(limit: npt.ArrayLike) -> np.ndarray:
    """True where a joint limit is real: finite and below `PLACEHOLDER_LIMIT` in magnitude."""
    limit = np.asarray(limit, dtype=float)
    return np.isfinite(limit) & (np.abs(limit) < PLACEHOLDER_LIMIT)


def placeholder_limit_joints(robot: Robot) -> tuple[str, ...]:
    """Joints with a coordinate whose limit is a placeholder (|limit| >= 1e3 or infinite).

    [`random_configurations`][gimwatch.model.sampling.random_configurations] draws those coordinates
    in ±π rad (angles) or ±1 m (translations, the free-flyer's position included) instead.
    Continuous joints and quaternions have no limit to read and are not listed.
    """
    model = robot.model
    lower, upper = np.array(model.lowerPositionLimit), np.array(model.upperPositionLimit)
    names = []
    for joint, name in zip(model.joints[1:], model.names[1:], strict=True):
        box = slice(joint.idx_q, joint.idx_q + joint.nq - unit_block_size(joint))
        if not (np.all(is_real_limit(lower[box])) and np.all(is_real_limit(upper[box]))):
            names.append(name)
    return tuple(names)


def check_random_budget(count: int, nv: int, *, option: str = "random") -> None:
    """Refuse ``count`` random configurations of ``nv`` coordinates beyond the work budget.

    The budget is count x nv <= 2,000,000 (``$GIMWATCH_MAX_RANDOM_WORK`` overrides it); it
    is checked before anything is drawn or allocated.

    Raises:
        InputError: Over the budget, or the variable is not a positive integer.
    """
    text = os.environ.get(MAX_RANDOM_WORK_VARIABLE, "").strip()
    budget = DEFAULT_MAX_RANDOM_WORK
    if text:
        if not text.isdigit() or int(text) < 1:
            raise InputError(f"${MAX_RANDOM_WORK_VARIABLE}", "a positive integer", text)
        budget = int(text)
    if count * nv > budget:
        raise InputError(
            option,
            f"at most {max(budget // nv, 1)} for nv = {nv} (count x nv <= {budget}; set "
            f"${MAX_RANDOM_WORK_VARIABLE} to allow more)",
            count,
        )


def random_configurations(robot: Robot, count: int = 1, *, seed: int | None = None) -> np.ndarray:
    """Configurations drawn uniformly within the joint limits, shape ``(count, nq)``.

    Unbounded coordinates, and those whose limit is a placeholder (|limit| >= 1e3, see
    [`placeholder_limit_joints`][gimwatch.model.sampling.placeholder_limit_joints]), are drawn in ±π
    rad (angles) or ±1 m (translations); quaternions
    and the unit complex numbers of continuous joints are drawn uniformly on their sphere.

    Args:
        robot: The robot.
        count: Number of configurations, >= 1.
        seed: Seed of NumPy's generator; the same seed gives the same configurations, and
            configuration k depends only on (seed, k): a longer run extends a shorter one.
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
    lower = np.array(model.lowerPositionLimit, dtype=float)
    upper = np.array(model.upperPositionLimit, dtype=float)
    boxes: list[int] = []  # the coordinates drawn in a box
    units: list[slice] = []  # the unit blocks
    lows: list[np.ndarray] = []
    highs: list[np.ndarray] = []
    for joint in model.joints[1:]:
        start, stop = joint.idx_q, joint.idx_q + joint.nq
        unit = unit_block_size(joint)
        box = slice(start, stop - unit)
        default = _DEFAULT_TRANSLATION_M if length_positions(joint) else _DEFAULT_ANGLE_RAD
        boxes += range(start, stop - unit)
        lows.append(np.where(is_real_limit(lower[box]), lower[box], -default))
        highs.append(np.where(is_real_limit(upper[box]), upper[box], default))
        if unit:
            units.append(slice(stop - unit, stop))
    width_normal = sum(block.stop - block.start for block in units)
    uniform, normal = configuration_draws(seed, count, len(boxes), width_normal)
    qs = np.empty((count, model.nq))
    if boxes:
        qs[:, boxes] = in_limits(np.concatenate(lows), np.concatenate(highs), uniform)
    column = 0
    for block in units:
        width = block.stop - block.start
        drawn = normal[:, column : column + width]
        qs[:, block] = drawn / np.linalg.norm(drawn, axis=1, keepdims=True)
        column += width
    return qs


def uniform_in_limits(
    lower: npt.ArrayLike, upper: npt.ArrayLike, count: int, seed: int | None
) -> np.ndarray:
    """``count`` configurations uniform in the box [lower, upper], shape ``(count, width)``.

    The boxed coordinates of `random_configurations`, and the whole of a robot without unit
    blocks (a generated chain, from its `ChainSpec.position_limits`): row k depends only on
    (seed, k).
    """
    lo = np.asarray(lower, dtype=float)
    uniform, _ = configuration_draws(seed, count, lo.size, 0)
    return in_limits(lo, upper, uniform)


def in_limits(lower: npt.ArrayLike, upper: npt.ArrayLike, uniform: np.ndarray) -> np.ndarray:
    """Uniforms in [0, 1) mapped to [lower, upper), coordinate by coordinate."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    return lo + (hi - lo) * uniform


def configuration_draws(
    seed: int | None, count: int, width_uniform: int, width_normal: int
) -> tuple[np.ndarray, np.ndarray]:
    """The random numbers behind ``count`` configurations: uniforms in [0, 1) and normals.

    Row k of each array depends only on (seed, k): the numbers are drawn configuration by
    configuration (row-major) from two streams spawned from ``seed``, so that
    ``--random 1 --seed 0`` gives configuration 0 of ``--random 100 --seed 0``.

    Returns:
        Uniforms of shape ``(count, width_uniform)``, standard normals of shape
        ``(count, width_normal)``.
    """
    uniform_stream, normal_stream = np.random.SeedSequence(seed).spawn(2)
    uniform = np.random.default_rng(uniform_stream).random((count, width_uniform))
    normal = np.random.default_rng(normal_stream).standard_normal((count, width_normal))
    return uniform, normal


def placeholder_note(joints: tuple[str, ...]) -> str:
    """The one-line note that says which joints' placeholder limits were replaced, or ""."""
    if not joints:
        return ""
    shown = ", ".join(joints[:4]) + (", ..." if len(joints) > 4 else "")
    return (
        f"placeholder limits (|limit| >= {PLACEHOLDER_LIMIT:g} or none) sampled in ±π rad / "
        f"±1 m: {shown}"
    )
