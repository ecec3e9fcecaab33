"""``analyze``: conditioning of a robot's GIM at configurations, on the path that fits it.

The dense path forms M with Pinocchio's CRBA and gives every metric and the whole spectrum;
the O(n) path (`gimwatch.metrics.linear_analysis`) never forms M nor builds a Pinocchio
Data, whose memory grows as nv³. `choose_path` picks it: above `DATA_NV_LIMIT` (400)
coordinates a robot goes the O(n) way — a generated chain, a URDF or MJCF file, fixed or
floating, with ball and free joints on any body and several trees — everything else the dense way,
unless the caller asks for one.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Unpack

import numpy as np

from gimwatch.errors import InputError
from gimwatch.joint_kinds import length_velocities
from gimwatch.metrics.dense_analysis import GimAnalysis, analyze_configuration
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robot_spec import RobotSpec, SpecOptions, robot_spec
from gimwatch.model.robots import (
    DATA_NV_LIMIT,
    Robot,
    load_robot,
    neutral_configuration,
)
from gimwatch.model.sampling import (
    check_random_budget,
    placeholder_limit_joints,
    random_configurations,
)

__all__ = [
    "LINEAR_NV_LIMIT",
    "PATHS",
    "Analysis",
    "Draws",
    "RobotLike",
    "analyze",
    "choose_path",
    "resolve_robot",
    "robot_for_path",
    "spec_of",
    "velocity_units",
]

#: ``backend`` values: ``auto`` lets `choose_path` decide.
PATHS = ("auto", "crba", "denoc")
#: The O(n) path's largest chain: diag, pivots and κ stay O(n) (about 1 kB per link).
LINEAR_NV_LIMIT = 200_000


@dataclass(frozen=True)
class Analysis:
    """The analyses of one robot, and the path that made them.

    Attributes:
        results: One [`GimAnalysis`][gimwatch.metrics.dense_analysis.GimAnalysis] per configuration.
        path: ``"crba"`` (dense M) or ``"denoc"`` (O(n), no M).
        chosen: True when ``auto`` chose the path (the caller may want to say why).
        placeholder_limits: Joints whose placeholder limits (|limit| >= 1e3 or none) random
            configurations replaced by ±π rad / ±1 m; empty when none were drawn.
        floating: Whether the base was a free-flyer (as asked, or the robot's default).
        units: How many velocity coordinates are lengths (m) and how many angles (rad); when
            both are present, κ and δ depend on the unit of length and κ_S does not.
        robot: The `Robot` analysed, loaded once (None for a fixed generated chain on the O(n)
            path, which never builds one).
    """

    results: tuple[GimAnalysis, ...]
    path: str
    chosen: bool
    placeholder_limits: tuple[str, ...] = ()
    floating: bool = False
    units: tuple[int, int] = (0, 0)
    robot: Robot | None = field(default=None, compare=False, repr=False)

    @property
    def mixed_units(self) -> bool:
        """Whether lengths and angles mix among the coordinates (κ, δ then unit-dependent)."""
        return min(self.units) > 0


def velocity_units(model) -> tuple[int, int]:
    """(coordinates in m, coordinates in rad) of a Pinocchio model's velocity vector."""
    lengths = angles = 0
    for joint in model.joints[1:]:
        in_metres = length_velocities(joint)
        lengths, angles = lengths + in_metres, angles + joint.nv - in_metres
    return lengths, angles


#: What the library's entry points take as a robot: loaded, parsed, or its text.
RobotLike = Robot | RobotSpec | str | Path


def choose_path(
    robot: RobotLike,
    *,
    floating: bool | None = None,
    backend: str = "auto",
    body: str | None = None,
    armature: bool | None = None,
) -> str:
    """``"denoc"`` for the O(n) path, ``"crba"`` for the dense one (see the module docstring).

    Under ``auto`` a file or a named robot is loaded (`robot_for_path`: its Pinocchio Model,
    never a Data) to learn its nv; a generated chain is not. `resolve_robot` also returns
    what it loaded.
    """
    options = SpecOptions(floating=floating)
    if body is not None:
        options["body"] = body
    if armature is not None:
        options["armature"] = armature
    return _chosen(_subject(robot, backend, options), backend)


def resolve_robot(
    robot: RobotLike, backend: str = "auto", **options: Unpack[SpecOptions]
) -> tuple[str, Robot | RobotSpec]:
    """The path (`choose_path`) and what is analysed on it, parsed and loaded once.

    Returns:
        The path, and the loaded `Robot`, or the `RobotSpec` of a fixed generated chain on
        the O(n) path (DeNOC builds it from its `ChainSpec`, without URDF or Pinocchio).

    Raises:
        InputError: An unknown ``backend``, or spec options given with a loaded `Robot`.
    """
    subject = _subject(robot, backend, options)
    path = _chosen(subject, backend)
    if isinstance(subject, Robot):
        return path, subject
    if subject.chain is None:  # a path asked for: the robot is loaded now, once
        return path, robot_for_path(subject)
    if path == "crba":  # refused before building anything above DATA_NV_LIMIT
        loaded = load_robot(subject, max_nv=DATA_NV_LIMIT)
        _remember(loaded)
        return path, loaded
    return path, subject if not subject.floating else robot_for_path(subject)


def _subject(robot: RobotLike, backend: str, options: SpecOptions) -> Robot | RobotSpec:
    """A loaded robot as given, else the spec parsed, a file's or a named robot loaded."""
    if backend not in PATHS:
        raise InputError("backend", f"one of {', '.join(PATHS)}", backend)
    if isinstance(robot, Robot):
        for name, value in options.items():
            if value is not None:
                raise InputError(name, "given with the robot's text or RobotSpec", value)
        _remember(robot)
        return robot
    spec = robot_spec(robot, **options)
    if spec.chain is not None or backend != "auto":
        return spec  # a chain's nv is known; a path asked for needs no nv
    return robot_for_path(spec)  # its Pinocchio Model, never a Data


def _chosen(subject: Robot | RobotSpec, backend: str) -> str:
    if backend != "auto":
        return backend
    if isinstance(subject, Robot):
        nv = subject.nv
    else:
        assert subject.chain is not None  # _subject loads every other spec under auto
        nv = subject.chain.n + 6 * subject.floating
    return "denoc" if nv > DATA_NV_LIMIT else "crba"


def robot_for_path(spec: RobotLike) -> Robot:
    """`load_robot` without a Data limit (the Model is O(nv)), kept for the next call.

    `choose_path` and the path it chooses read the robot once: the last few loads (and
    robots given loaded) are kept, keyed by the spec and the file's size and modification
    time.
    """
    if isinstance(spec, Robot):
        _remember(spec)
        return spec
    parsed = robot_spec(spec)
    key = (parsed, _version(parsed))
    robot = _LOADED.get(key)
    if robot is None:
        robot = load_robot(parsed)
        _remember(robot, key)
    return robot


def spec_of(robot: RobotLike) -> RobotSpec:
    """The `RobotSpec` of ``robot``; a loaded `Robot` is kept for `robot_for_path`."""
    if isinstance(robot, Robot):
        if robot.robot_spec is None:
            raise InputError("robot", "a Robot made by load_robot (it keeps its spec)", robot)
        _remember(robot)
        return robot.robot_spec
    return robot_spec(robot)


#: The last few robots `robot_for_path` loaded or was given, by (spec, file version).
_LOADED: dict[tuple[RobotSpec, tuple[int, int] | None], Robot] = {}
_LOADED_KEPT = 4


def _version(spec: RobotSpec) -> tuple[int, int] | None:
    try:
        stat = Path(spec.text).stat()
    except (OSError, ValueError):
        return None
    return (stat.st_size, stat.st_mtime_ns)


def _remember(robot: Robot, key=None) -> None:
    if key is None:
        if robot.robot_spec is None:
            return
        key = (robot.robot_spec, _version(robot.robot_spec))
    _LOADED.pop(key, None)
    _LOADED[key] = robot
    while len(_LOADED) > _LOADED_KEPT:
        del _LOADED[next(iter(_LOADED))]


@dataclass(frozen=True)
class Draws:
    """The configurations asked for: one ``q``, ``random`` draws with ``seed``, or neutral.

    Attributes:
        q: One configuration as a user writes it, or None.
        random: How many random configurations within the joint limits, or None.
        seed: Seed of the random draws (and of Lanczos on the O(n) path).
        key: The name of ``q`` in error messages.
    """

    q: Sequence[float] | None = None
    random: int | None = None
    seed: int = 0
    key: str = "q"

    def configurations(
        self,
        nq: int,
        neutral,
        draw: Callable[[int, int], Any],
        robot: Robot | None = None,
        label: str = "",
    ) -> list:
        """The configurations: drawn by ``draw(k, seed)``, ``q`` checked, or ``neutral``."""
        if self.q is not None and self.random is not None:
            raise InputError(f"{self.key} and random", "used one at a time", "both")
        if self.random is not None:
            check_random_budget(self.random, nq)  # before anything is drawn
            return list(draw(self.random, self.seed))
        if self.q is None:
            return [neutral]
        q = [float(x) for x in self.q]
        if robot is not None and robot.nq != robot.nv:  # continuous joints by angle, units
            if not all(math.isfinite(x) for x in q):
                raise InputError(self.key, "finite", q)
            return [user_configuration(robot, q, key=self.key)]
        if len(q) != nq:
            what = robot.spec if robot is not None else label
            raise InputError(self.key, f"{nq} numbers for {what}", len(q))
        return [q]

    def on_robot(self, robot: Robot) -> list:
        """The configurations of a loaded robot (random ones within its joint limits)."""
        draw = lambda k, s: random_configurations(robot, k, seed=s)  # noqa: E731
        return self.configurations(robot.nq, neutral_configuration(robot), draw, robot)


def _linear(subject: Robot | RobotSpec, draws: Draws, metrics: Sequence[str] | None):
    """The O(n) DeNOC path: generated chains never build a URDF or a Pinocchio model.

    Returns:
        The analyses, and (coordinates in m, coordinates in rad).
    """
    from gimwatch.denoc import DenocModel
    from gimwatch.metrics.denoc_robot import denoc_model
    from gimwatch.metrics.linear_analysis import (
        LINEAR_METRICS,
        analyze_linear,
        chain_configurations,
    )

    metrics = LINEAR_METRICS if metrics is None else tuple(metrics)
    if isinstance(subject, RobotSpec):
        chain = subject.chain
        assert chain is not None  # resolve_robot gives a spec only for a fixed chain
        if chain.n > LINEAR_NV_LIMIT:
            raise InputError("the N of chain:N", f"at most {LINEAR_NV_LIMIT}", chain.n)
        model, name = DenocModel.from_chain(chain), chain.name
        slides = sum(kind == "prismatic" for kind in chain.joint_types)
        units = (slides, chain.n - slides)
        draw = lambda k, s: chain_configurations(chain, k, seed=s)  # noqa: E731
        qs = draws.configurations(chain.n, [0.0] * chain.n, draw, label=subject.text)
    else:
        if subject.nv > LINEAR_NV_LIMIT:
            raise InputError("the robot's nv", f"at most {LINEAR_NV_LIMIT}", subject.nv)
        model, name = denoc_model(subject), subject.name
        units = velocity_units(subject.model)
        qs = draws.on_robot(subject)
    results = [analyze_linear(model, x, name=name, metrics=metrics, seed=draws.seed) for x in qs]
    return results, units


def analyze(
    robot: RobotLike,
    q: Sequence[float] | None = None,
    *,
    random: int | None = None,
    seed: int = 0,
    backend: str = "auto",
    metrics: Sequence[str] | None = None,
    key: str = "q",
    **options: Unpack[SpecOptions],
) -> Analysis:
    """Analyse a robot: loaded, its `RobotSpec`, or its text (parsed and loaded once).

    Args:
        robot: A `Robot`, a `RobotSpec`, or ``chain:N``, a URDF or MJCF path, an
            example-robot-data name.
        q: One configuration as a user writes it (a continuous joint by its angle), or None.
        random: Analyse this many random configurations within the joint limits instead.
        seed: Seed of the random configurations (and of Lanczos on the O(n) path).
        backend: ``auto``, ``crba`` (dense) or ``denoc`` (O(n)); see `choose_path`.
        metrics: On the O(n) path, a subset of its metrics; the dense path computes all.
        key: The name of ``q`` in error messages (``--q`` for the CLI).
        **options: With a robot's text or `RobotSpec`, those of
            [`RobotSpec.parse`][gimwatch.model.robot_spec.RobotSpec.parse]: ``floating``
            (True: a free-flyer base; False: fixed; None: the robot's default,
            `default_floating`), ``body`` (MJCF only: the subtree of this body) and
            ``armature`` (MJCF only: keep MuJoCo's ``dof_armature`` in M).

    Returns:
        The `Analysis`: the results and the path taken.
    """
    path, subject = resolve_robot(robot, backend, **options)
    if metrics is not None and path != "denoc":
        raise InputError("metrics", "chosen on the O(n) path (backend denoc)", list(metrics))
    draws = Draws(q, random, seed, key)
    if path == "denoc":
        results, units = _linear(subject, draws, metrics)
    else:
        assert isinstance(subject, Robot)  # the dense path always loads
        data = subject.new_data()  # refused above DATA_NV_LIMIT, naming the O(n) path
        qs = draws.on_robot(subject)
        results = [analyze_configuration(subject, np.asarray(x), data=data) for x in qs]
        units = velocity_units(subject.model)
    loaded = subject if isinstance(subject, Robot) else None
    return Analysis(
        results=tuple(results),
        path=path,
        chosen=backend == "auto",
        placeholder_limits=placeholder_limit_joints(loaded)
        if loaded and random is not None
        else (),
        floating=loaded.free_base if loaded is not None else False,  # an MJCF may float itself
        units=units,
        robot=loaded,
    )
