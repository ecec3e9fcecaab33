"""Many robots in one command: folders expanded, each robot loaded on its own, refusals kept.

``analyze``, ``crosscheck`` and ``survey`` given several robots go on past a robot that is
refused (bad input, one line naming the file) and report it as a row ``refused: <reason>``;
the command's exit status is then 2, after every other robot was reported.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

from gimwatch.errors import GimwatchError
from gimwatch.model.robots import Robot, load_robot

__all__ = ["ROBOT_FILE_SUFFIXES", "expand_specs", "load_each"]

#: The files of a folder given as ROBOT (URDF and MJCF).
ROBOT_FILE_SUFFIXES = (".urdf", ".xml", ".mjcf")


def expand_specs(specs: Sequence[str]) -> list[str]:
    """The specs with each folder replaced by its robot files (sorted, not recursive)."""
    expanded = []
    for spec in specs:
        path = Path(spec)
        if spec not in ("all",) and path.is_dir():
            files = sorted(
                str(p) for p in path.iterdir() if p.suffix.lower() in ROBOT_FILE_SUFFIXES
            )
            expanded.extend(files or [spec])  # an empty folder is refused by load_robot
        else:
            expanded.append(spec)
    return expanded


def load_each(
    specs: Sequence[str], *, floating: bool | None, **options
) -> Iterator[tuple[str, Robot | None, GimwatchError | None]]:
    """(spec, robot, None) for each robot that loads, (spec, None, error) for each refused.

    ``options``: further arguments of `load_robot` (MJCF ``body``, ``armature``).
    """
    for spec in specs:
        try:
            yield spec, load_robot(spec, floating=floating, **options), None
        except GimwatchError as exc:
            yield spec, None, exc
