"""``analyze``: conditioning of a robot's GIM at configurations, on the path that fits it.

The dense path forms M with Pinocchio's CRBA and gives every metric and the whole spectrum;
the O(n) path (`gimwatch.metrics.linear_analysis`) never forms M nor builds a Pinocchio
Data, whose memory grows as nv³. `choose_path` picks it: above `DATA_NV_LIMIT` (400)
coordinates a robot goes the O(n) way — a generated chain, a URDF or MJCF file, fixed or
floating, with ball and free joints on any body and several trees — everything else the dense way,
unless the caller asks for one.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gimwatch.errors import InputError
from gimwatch.joint_kinds import length_velocities
from gimwatch.metrics.dense_analysis import GimAnalysis, analyze_configuration
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robots import (
    DATA_NV_LIMIT,
    check_random_budget,
    default_floating,
    load_robot,
    neutral_configuration,
    parse_chain_spec,
    placeholder_limit_joints,
    random_configurations,
)

__all__ = [
    "LINEAR_NV_LIMIT",
    "PATHS",
    "Analysis",
    "analyze",
    "choose_path",
    "robot_for_path",
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
    """

    results: tuple[GimAnalysis, ...]
    path: str
    chosen: bool
    placeholder_limits: tuple[str, ...] = ()
    floating: bool = False
    units: tuple[int, int] = (0, 0)

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


def choose_path(
    spec: str,
    *,
    floating: bool | None = None,
    backend: str = "auto",
    body: str = "",
    armature: bool = True,
) -> str:
    """``"denoc"`` for the O(n) path, ``"crba"`` for the dense one (see the module docstring).

    Under ``auto`` a file or a named robot is loaded (`robot_for_path`: its Pinocchio Model,
    never a Data) to learn its nv; a generated chain is not.
    """
    if backend not in PATHS:
        raise InputError("backend", f"one of {', '.join(PATHS)}", backend)
    if backend != "auto":
        return backend
    chain = parse_chain_spec(spec)
    if chain is not None:
        return "denoc" if chain.n + 6 * bool(floating) > DATA_NV_LIMIT else "crba"
    robot = robot_for_path(spec, floating=floating, body=body, armature=armature)
    return "denoc" if robot.nv > DATA_NV_LIMIT else "crba"


def robot_for_path(
    spec: str, *, floating: bool | None = None, body: str = "", armature: bool = True
):
    """`load_robot` without a Data limit (the Model is O(nv)), kept for the next call.

    `choose_path` and the path it chooses read the robot once: the last few loads are
    kept, keyed by the file's size and modification time as well as the arguments.
    """
    try:
        stat = Path(spec).stat()
        version = (stat.st_size, stat.st_mtime_ns)
    except (OSError, ValueError):
        version = None
    return _load(str(spec), floating, body, armature, version)


@functools.lru_cache(maxsize=4)
def _load(spec, floating, body, armature, version):
    return load_robot(spec, floating=floating, body=body, armature=armature)


def _configurations(q, random, seed, nq, neutral, draw, robot=None, key="q", spec="") -> list:
    if q is not None and random is not None:
        raise InputError(f"{key} and random", "used one at a time", "both")
    if random is not None:
        check_random_budget(random, nq)  # before anything is drawn
        return list(draw(random, seed))
    if q is None:
        return [neutral]
    q = [float(x) for x in q]
    if robot is not None and robot.nq != robot.nv:  # continuous joints by angle, unit checks
        if not all(math.isfinite(x) for x in q):
            raise InputError(key, "finite", q)
        return [user_configuration(robot, q, key=key)]
    if len(q) != nq:
        raise InputError(key, f"{nq} numbers for {spec}", len(q))
    return [q]


def _robot_configurations(robot, q, random, seed, key, spec) -> list:
    draw = lambda k, s: random_configurations(robot, k, seed=s)  # noqa: E731
    neutral = neutral_configuration(robot)
    return _configurations(q, random, seed, robot.nq, neutral, draw, robot, key=key, spec=spec)


def _linear(spec, q, random, seed, metrics, floating, key, body, armature):
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
    chain = parse_chain_spec(spec)
    if chain is not None and not floating:
        if chain.n > LINEAR_NV_LIMIT:
            raise InputError("the N of chain:N", f"at most {LINEAR_NV_LIMIT}", chain.n)
        model, name = DenocModel.from_chain(chain), chain.name
        slides = sum(kind == "prismatic" for kind in chain.joint_types)
        units = (slides, chain.n - slides)
        qs = _configurations(
            q,
            random,
            seed,
            chain.n,
            [0.0] * chain.n,
            lambda k, s: chain_configurations(chain, k, seed=s),
            key=key,
            spec=spec,
        )
    else:
        robot = robot_for_path(spec, floating=floating, body=body, armature=armature)
        if robot.nv > LINEAR_NV_LIMIT:
            raise InputError("the robot's nv", f"at most {LINEAR_NV_LIMIT}", robot.nv)
        model, name = denoc_model(robot), robot.name
        units = velocity_units(robot.model)
        qs = _robot_configurations(robot, q, random, seed, key, spec)
    return [analyze_linear(model, x, name=name, metrics=metrics, seed=seed) for x in qs], units


def analyze(
    spec: str,
    q: Sequence[float] | None = None,
    *,
    random: int | None = None,
    seed: int = 0,
    floating: bool | None = None,
    backend: str = "auto",
    metrics: Sequence[str] | None = None,
    key: str = "q",
    body: str = "",
    armature: bool = True,
) -> Analysis:
    """Analyse ``spec`` (``chain:N``, a URDF or MJCF path, an example-robot-data name).

    Args:
        spec: The robot.
        q: One configuration as a user writes it (a continuous joint by its angle), or None.
        random: Analyse this many random configurations within the joint limits instead.
        seed: Seed of the random configurations (and of Lanczos on the O(n) path).
        floating: True: a free-flyer base; False: fixed; None: the robot's
            default (`default_floating`: example-robot-data's base for its robots).
        backend: ``auto``, ``crba`` (dense) or ``denoc`` (O(n)); see `choose_path`.
        metrics: On the O(n) path, a subset of its metrics; the dense path computes all.
        key: The name of ``q`` in error messages (``--q`` for the CLI).
        body: MJCF only: analyse the subtree of this body (see `load_robot`).
        armature: MJCF only: keep MuJoCo's ``dof_armature`` in M.

    Returns:
        The `Analysis`: the results and the path taken.
    """
    if floating is None:
        floating = parse_chain_spec(spec) is None and default_floating(spec)
    path = choose_path(spec, floating=floating, backend=backend, body=body, armature=armature)
    if metrics is not None and path != "denoc":
        raise InputError("metrics", "chosen on the O(n) path (backend denoc)", list(metrics))
    placeholders: tuple[str, ...] = ()
    chain = parse_chain_spec(spec)
    if path == "denoc":
        results, units = _linear(spec, q, random, seed, metrics, floating, key, body, armature)
        if chain is None or floating:  # an MJCF file may float its robot itself
            robot = robot_for_path(spec, floating=floating, body=body, armature=armature)
            floating = robot.free_base
            if random is not None:
                placeholders = placeholder_limit_joints(robot)
    else:
        robot = (
            load_robot(spec, floating=floating, max_nv=DATA_NV_LIMIT)
            if chain is not None
            else robot_for_path(spec, floating=floating, body=body, armature=armature)
        )
        data = robot.new_data()  # refused above DATA_NV_LIMIT, naming the O(n) path
        qs = _robot_configurations(robot, q, random, seed, key, spec)
        results = [analyze_configuration(robot, np.asarray(x), data=data) for x in qs]
        if random is not None:
            placeholders = placeholder_limit_joints(robot)
        floating = robot.free_base  # an MJCF file may float its robot itself
        units = velocity_units(robot.model)
    return Analysis(
        results=tuple(results),
        path=path,
        chosen=backend == "auto",
        placeholder_limits=placeholders,
        floating=floating,
        units=units,
    )
