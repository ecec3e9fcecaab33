"""Scene files: what is in the world, how to integrate it and what to watch.

A scene is a TOML file read with `tomllib` and validated once, into frozen
dataclasses. Unknown keys, wrong types, wrong lengths, negative durations, unknown effect,
metric, joint or link names are [`SceneError`][gimwatch.errors.SceneError] naming the file and
the key (``scene.toml: effects.spring.stiffness: ...``). The schema is documented in the
docs (``docs/scenes.md``, generated from the registries). Names are looked up in the live
registries at parse time; `EFFECT_KEYS`, `METRIC_NAMES` and the other tuples
are the names registered at import.

Joint-indexed values (``q``, ``v``, damping, stiffness, torques, targets) are given as a
number (broadcast to every coordinate), a list (one per coordinate) or a table keyed by
joint name (coordinates not named keep the default). They are resolved against the robot
by `joint_vector` when the simulation is built, because the names are the robot's.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gimwatch.errors import SceneError
from gimwatch.model.robot_files import path_problem
from gimwatch.simulation.alarm_actions import ALARM_ACTIONS
from gimwatch.simulation.backends import BACKENDS as BACKEND_CLASSES
from gimwatch.simulation.bundled_scenes import missing_scene_hint, resolve_scene
from gimwatch.simulation.effects import EFFECTS
from gimwatch.simulation.integrators import INTEGRATORS
from gimwatch.simulation.parameters import Parameter
from gimwatch.simulation.scene_integrator import (
    DEFAULT_MAX_STEPS,
    MAX_DURATION_S,
    IntegratorSpec,
    check_steps,
    read_integrator,
)
from gimwatch.simulation.scene_reader import JointValues, TableReader
from gimwatch.simulation.torque_laws import TORQUE_LAWS
from gimwatch.suggest import did_you_mean
from gimwatch.watch.watch import METRICS

__all__ = [
    "BACKENDS",
    "DEFAULT_MAX_STEPS",
    "EFFECT_KEYS",
    "FIXED_STEP_METHODS",
    "METRIC_NAMES",
    "ON_ALARM_ACTIONS",
    "SCIPY_METHODS",
    "TORQUE_LAW_NAMES",
    "EffectSpec",
    "IntegratorSpec",
    "RobotSpec",
    "Scene",
    "WatchSpec",
    "load_scene",
    "parse_scene",
]

# The names below are read from the live registries (one source per family): adding an
# effect, torque law, integrator, backend or on-alarm action there adds it here.
SCIPY_METHODS = tuple(name for name, cls in INTEGRATORS.items() if not cls.fixed_step)
FIXED_STEP_METHODS = tuple(name for name, cls in INTEGRATORS.items() if cls.fixed_step)
BACKENDS = tuple(BACKEND_CLASSES)
METRIC_NAMES = tuple(METRICS)
#: What to do when the alarm metric crosses its threshold (gimwatch.simulation.alarm_actions).
ON_ALARM_ACTIONS = tuple(ALARM_ACTIONS)
TORQUE_LAW_NAMES = tuple(TORQUE_LAWS)


def _effect_keys(name: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """An effect's (required, optional) keys, from the live registries."""
    parameters = EFFECTS[name].parameters
    optional = tuple(p.name for p in parameters if not p.required)
    if name == "torque":  # every law's keys; the law's own are checked once it is known
        optional += tuple(sorted({p.name for law in TORQUE_LAWS.values() for p in law.parameters}))
    return tuple(p.name for p in parameters if p.required), optional


#: Each effect's keys: name -> (required keys, optional keys), as registered at import.
EFFECT_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    name: _effect_keys(name) for name in EFFECTS
}
_TOP_KEYS = {
    "robot",
    "base",
    "body",
    "armature",
    "q",
    "v",
    "duration",
    "sample",
    "effects",
    "integrator",
    "dynamics",
    "watch",
}

#: Size limits checked before anything runs, so an absurd scene fails at once instead of
#: exhausting memory or running for years: samples kept (each a q, v and watch row),
#: fixed integrator steps, initial |q| (rad or m) and |v| (rad/s or m/s; a larger speed
#: shrinks an adaptive step towards zero), and the bytes of a scene file.
MAX_SAMPLES = 1_000_000
MAX_INITIAL_STATE = 1e6
MAX_SCENE_BYTES = 1024 * 1024
#: The most dotted parts a TOML key is read with: tomllib's time grows with the square of
#: a key's parts (18 s for ``a.a.a...`` of 20,000, hours for a 1 MB one); scene keys have 3.
MAX_KEY_PARTS = 64
# Possessive quantifiers and the look-behind (a key starts where no word or dot precedes)
# keep this scan linear: each attempt reads at most MAX_KEY_PARTS parts.
_PART = r"""(?:[\w-]++|"[^"\n]*+"|'[^'\n]*+')"""
_LONG_KEY = re.compile(rf"(?<![\w.-])(?:{_PART}[ \t]*+\.[ \t]*+){{{MAX_KEY_PARTS}}}")


@dataclass(frozen=True)
class RobotSpec:
    """Which robot: a ``chain:N`` / example-robot-data / URDF path string, or a chain table."""

    spec: str
    floating: bool | None = None  # None: no ``base`` key, the robot's default base
    chain: dict[str, Any] | None = None
    body: str = ""  # MJCF: the subtree of this body ("" the whole model)
    armature: bool = True  # MJCF: MuJoCo's dof_armature in M, as MuJoCo has it


@dataclass(frozen=True)
class EffectSpec:
    """One declared effect: its registry name and its validated parameters."""

    name: str
    params: dict[str, Any]


@dataclass(frozen=True)
class WatchSpec:
    """Metrics to compute at each sample, and the alarm on one of them."""

    metrics: tuple[str, ...] = ()
    alarm_metric: str | None = None
    alarm_threshold: float | None = None
    on_alarm: str = "warn"


@dataclass(frozen=True)
class Scene:
    """A validated scene. Times in seconds; joint values in the robot's SI units."""

    source: str
    robot: RobotSpec
    duration_s: float
    sample_s: float
    q: JointValues | None = None
    v: JointValues = 0.0
    effects: tuple[EffectSpec, ...] = ()
    integrator: IntegratorSpec = field(default_factory=IntegratorSpec)
    backend: str = "aba"
    watch: WatchSpec = field(default_factory=WatchSpec)
    raw: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def effect_names(self) -> tuple[str, ...]:
        """Names of the declared effects, in file order."""
        return tuple(effect.name for effect in self.effects)

    def error(self, key: str, problem: str) -> SceneError:
        """A [`SceneError`][gimwatch.errors.SceneError] about ``key`` in this scene's file."""
        return SceneError(self.source, key, problem)


def _robot(reader: TableReader, base_dir: Path | None) -> RobotSpec:
    floating = None  # no base key: the robot's default (example-robot-data's, else fixed)
    if "base" in reader.table:
        floating = reader.string("base", "fixed", choices=("fixed", "floating")) == "floating"
    if "robot" not in reader.table:
        raise reader.fail("robot", "is required")
    value = reader.table["robot"]
    if isinstance(value, dict):
        for key in ("body", "armature"):
            if key in reader.table:
                raise reader.fail(key, "is for an MJCF robot, not a chain table")
        chain = reader.sub("robot")
        chain.check_keys(
            {"n", "mass_kg", "length_m", "radius_m", "axes", "joint_types"}, required=("n",)
        )
        n = chain.table["n"]
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise chain.fail("n", f"must be a positive integer, got {n!r}")
        params = dict(value)
        for key in ("mass_kg", "length_m", "radius_m"):  # numbers or lists, read as floats
            if not isinstance(params.get(key), (dict, type(None))):
                values = chain.joint_values(key)
                params[key] = list(values) if isinstance(values, tuple) else values
        return RobotSpec(spec=f"chain:{n}", floating=floating, chain=params)
    if not isinstance(value, str) or not value:
        raise reader.fail("robot", f"must be a string or a chain table, got {value!r}")
    if base_dir is not None and _is_path(value, base_dir):
        path = Path(value)
        value = str(path if path.is_absolute() else base_dir / path)
    body = reader.string("body", "")
    armature = reader.table.get("armature", True)
    if not isinstance(armature, bool):
        raise reader.fail("armature", f"must be true or false, got {armature!r}")
    return RobotSpec(spec=value, floating=floating, body=body, armature=armature)


def _is_path(value: str, base_dir: Path) -> bool:
    """Whether a scene's ``robot`` string names a file (resolved against the scene's folder).

    ``chain:N`` is not; a value with a folder separator or a ``.urdf``/``.xml`` suffix is; a
    bare name is a file when the scene's folder holds one by that name, else an
    example-robot-data name.
    """
    if value.startswith("chain:"):
        return False
    if "/" in value or value.lower().endswith((".urdf", ".xml")):
        return True
    return (base_dir / value).exists()


def _parameter(table: TableReader, parameter: Parameter) -> Any:
    """Read one declared parameter (absent: its default, or None)."""
    name, kind = parameter.name, parameter.kind
    if kind == "number":
        return table.number(name, parameter.default, positive=parameter.positive)
    if kind in ("joint", "configuration"):
        return table.joint_values(name, parameter.default, nonnegative=parameter.nonnegative)
    if kind == "vector3":
        return table.vector3(name, parameter.default)
    return table.string(name, parameter.default, choices=tuple(parameter.choices))


def _effects(reader: TableReader) -> tuple[EffectSpec, ...]:
    effects = []
    for name in reader.table:
        if name not in EFFECTS:
            raise reader.fail(name, f"unknown effect; expected one of {', '.join(EFFECTS)}")
        table = reader.sub(name)
        required, optional = _effect_keys(name)
        table.check_keys(set(required) | set(optional), required)
        params: dict[str, Any] = {}
        for parameter in EFFECTS[name].parameters:
            value = _parameter(table, parameter)
            if value is not None:
                params[parameter.name] = value
        if name == "torque":
            law = params["law"]
            declared = {p.name: p for p in TORQUE_LAWS[law].parameters}
            must = {key for key, p in declared.items() if p.required}
            present = set(table.table) - {"law"}
            for key in sorted(present - set(declared)):
                raise table.fail(key, f"is not a parameter of the {law!r} torque law")
            for key in sorted(must - present):
                raise table.fail(key, f"is required by the {law!r} torque law")
            for key in present:
                params[key] = _parameter(table, declared[key])
        effects.append(EffectSpec(name=name, params=params))
    return tuple(effects)


def _watch(reader: TableReader) -> WatchSpec:
    reader.check_keys({"metrics", "alarm_metric", "alarm_threshold", "on_alarm"})
    metrics = reader.table.get("metrics", [])
    if not isinstance(metrics, list) or not all(isinstance(m, str) for m in metrics):
        raise reader.fail("metrics", f"must be a list of metric names, got {metrics!r}")
    for metric in metrics:
        if metric not in METRICS:
            raise reader.fail(
                "metrics",
                f"unknown metric {metric!r}; expected one of {', '.join(METRICS)}"
                + did_you_mean(metric, tuple(METRICS)),
            )
    if len(set(metrics)) != len(metrics):
        raise reader.fail("metrics", f"lists a metric twice: {metrics!r}")
    threshold = reader.number("alarm_threshold", positive=True)
    scalar = [m for m in metrics if m not in ("eigenvalues", "diagonal")]
    if threshold is not None and not scalar and "alarm_metric" not in reader.table:
        raise reader.fail(
            "alarm_threshold",
            "has no metric to watch: list a scalar metric in watch.metrics "
            f"(one of {', '.join(m for m in METRICS if m not in ('eigenvalues', 'diagonal'))})",
        )
    alarm_metric = reader.string("alarm_metric", scalar[0] if scalar and threshold else None)
    if alarm_metric is not None:
        if alarm_metric not in scalar:
            raise reader.fail(
                "alarm_metric", f"must be a watched scalar metric, got {alarm_metric!r}"
            )
        if threshold is None:
            raise reader.fail("alarm_threshold", "is required when alarm_metric is given")
    on_alarm = reader.string("on_alarm", "warn", choices=tuple(ALARM_ACTIONS))
    return WatchSpec(tuple(metrics), alarm_metric, threshold, on_alarm)


def parse_scene(
    table: dict[str, Any], *, source: str = "<scene>", base_dir: Path | None = None
) -> Scene:
    """Validate a scene given as a TOML-like table.

    Args:
        table: The parsed TOML document.
        source: Name used in error messages (the file path).
        base_dir: Folder that relative URDF paths are resolved against.

    Raises:
        SceneError: The first bad key, as ``source: key: problem``.
    """
    reader = TableReader(source, table)
    reader.check_keys(_TOP_KEYS, required=("robot", "duration", "sample"))
    robot = _robot(reader, base_dir)
    duration = reader.number("duration", positive=True, maximum=MAX_DURATION_S)
    sample = reader.number("sample", positive=True)
    if sample > duration:
        raise reader.fail("sample", f"must be <= duration ({duration} s), got {sample}")
    if duration / sample > MAX_SAMPLES:
        raise reader.fail(
            "sample",
            f"duration / sample must be at most {MAX_SAMPLES} samples, got {duration / sample:.3g}",
        )
    dynamics = reader.sub("dynamics")
    dynamics.check_keys({"backend"})
    integrator = read_integrator(reader.sub("integrator"))
    check_steps(source, integrator, duration)
    if integrator.fixed_step and integrator.dt is not None:  # a fixed step always has its dt
        ratio = sample / integrator.dt
        if abs(ratio - round(ratio)) > 1e-9 * ratio:
            raise SceneError(
                source,
                "sample",
                f"must be a whole number of integrator.dt ({integrator.dt} s), got {sample}",
            )
    return Scene(
        source=source,
        robot=robot,
        duration_s=duration,
        sample_s=sample,
        q=reader.joint_values("q", None, bound=MAX_INITIAL_STATE),
        v=reader.joint_values("v", 0.0, bound=MAX_INITIAL_STATE),
        effects=_effects(reader.sub("effects")),
        integrator=integrator,
        backend=dynamics.string("backend", "aba", choices=tuple(BACKEND_CLASSES)),
        watch=_watch(reader.sub("watch")),
        raw=table,
    )


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file (TOML), or a bundled scene named without a path.

    ``load_scene("chain_10")`` reads the scene shipped with gimwatch
    (``gimwatch/scenes/chain_10.toml``) when no file ``chain_10`` exists in the working folder.

    Raises:
        SceneError: Missing or unreadable file, TOML syntax error, or a bad key.
    """
    path = resolve_scene(path)
    try:
        if not path.exists():  # also a path through a file (NotADirectoryError)
            problem = path_problem(path)
            if problem == "no such file":
                problem += f"; {missing_scene_hint(path)}"
            raise SceneError(str(path), "", problem)
        if path.is_dir():
            raise SceneError(str(path), "", "is a directory, not a scene file")
        if not path.is_file():  # a FIFO or device could block forever
            raise SceneError(str(path), "", "is not a regular file (a device, FIFO or socket)")
        if path.stat().st_size > MAX_SCENE_BYTES:
            raise SceneError(str(path), "", f"is larger than {MAX_SCENE_BYTES} bytes")
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError as exc:
        raise SceneError(str(path), "", "no such file") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), "", f"cannot be read ({exc.__class__.__name__})") from exc
    return parse_scene(_read_toml(text, str(path)), source=str(path), base_dir=path.parent)


def _read_toml(text: str, source: str) -> dict[str, Any]:
    """The TOML table of a scene's text, in time linear in its length, or a SceneError."""
    if _LONG_KEY.search(text):
        raise SceneError(source, "", f"has a dotted key of more than {MAX_KEY_PARTS} parts")
    try:
        return tomllib.loads(text)
    except RecursionError:  # tomllib recurses once per level of nested arrays/tables
        raise SceneError(source, "", "has arrays or inline tables nested too deeply") from None
    except ValueError as exc:  # TOMLDecodeError, or an integer of more than 4300 digits
        raise SceneError(source, "", f"is not valid TOML ({exc})") from exc
