"""The checks on a configuration q handed to the library: length, finiteness, unit blocks.

A continuous joint's (cos θ, sin θ) and a quaternion must have norm 1: Pinocchio would use a
zero block as is, freezing the joint (a zero rotation matrix) and giving a wrong M(q). The
blocks are found once per robot and kept on it; a q is checked by one gather and one
segmented sum, without a loop over joints.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from gimwatch.errors import InputError
from gimwatch.model.sampling import Robot, unit_block_size

__all__ = ["UNIT_NORM_TOLERANCE", "as_configuration", "as_configurations", "unit_blocks"]


#: |‖block‖ − 1| allowed for the unit blocks of a q given to the library functions.
UNIT_NORM_TOLERANCE = 1e-6


def unit_blocks(robot: Robot) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Where q's unit blocks end, their sizes and joints: computed once per robot, kept on it."""
    blocks = robot.__dict__.get("_unit_blocks")
    if blocks is None:
        found = [
            (joint.idx_q + joint.nq, unit_block_size(joint), name)
            for joint, name in zip(robot.model.joints[1:], robot.model.names[1:], strict=True)
            if unit_block_size(joint)
        ]
        blocks = (
            np.array([b[0] for b in found], dtype=np.int64),
            np.array([b[1] for b in found], dtype=np.int64),
            tuple(b[2] for b in found),
        )
        object.__setattr__(robot, "_unit_blocks", blocks)  # frozen: a cache, not state
    return blocks


def _unit_norms(robot: Robot, qs: np.ndarray) -> np.ndarray:
    """The norm of every unit block of each row of ``qs`` (K, nq): (K, blocks), no joint loop."""
    gather = robot.__dict__.get("_unit_gather")
    if gather is None:
        stops, sizes, _ = unit_blocks(robot)
        index = np.concatenate(
            [np.arange(stop - size, stop) for stop, size in zip(stops, sizes, strict=True)]
        )
        gather = (index, np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.intp))
        object.__setattr__(robot, "_unit_gather", gather)  # frozen: a cache, not state
    index, offsets = gather
    return np.sqrt(np.add.reduceat(qs[:, index] ** 2, offsets, axis=1))


def as_configuration(robot: Robot, q: npt.ArrayLike) -> np.ndarray:
    """Check that ``q`` is a finite real vector of length nq and return it as an array.

    Each unit block (a continuous joint's (cos θ, sin θ), a quaternion) must have norm 1
    within `UNIT_NORM_TOLERANCE`: Pinocchio would use a zero block as is, freezing
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
    return as_configurations(robot, array[None, :])[0]


def as_configurations(robot: Robot, qs: npt.ArrayLike, *, name: str = "q") -> np.ndarray:
    """`as_configuration` for every row of ``qs`` (K, nq) at once; errors name the row.

    Every q a library function, a trajectory file or a map receives goes through here, so a
    (cos θ, sin θ) of norm 2 is refused wherever it comes from.
    """
    array = np.asarray(qs, dtype=float)
    if array.ndim != 2 or array.shape[1] != robot.nq:
        raise InputError(name, f"rows of {robot.nq} numbers for {robot.name}", array.shape)
    finite = np.isfinite(array).all(axis=1)
    if not finite.all():
        row = int(np.flatnonzero(~finite)[0])
        raise InputError(_row(name, row, len(array)), "finite", array[row].tolist())
    stops, sizes, names = unit_blocks(robot)
    if stops.size and len(array):
        norms = _unit_norms(robot, array)
        bad = ~(np.abs(norms - 1.0) <= UNIT_NORM_TOLERANCE)
        if bad.any():
            row, k = (int(i) for i in np.argwhere(bad)[0])
            what = "quaternion" if sizes[k] == 4 else "(cos θ, sin θ)"
            raise InputError(
                f"the {what} of joint {names[k]!r} in {_row(name, row, len(array))}",
                f"of norm 1 (within {UNIT_NORM_TOLERANCE:g})",
                round(float(norms[row, k]), 9),
            )
    return array


def _row(name: str, row: int, rows: int) -> str:
    return name if rows == 1 else f"{name} (row {row + 1})"
