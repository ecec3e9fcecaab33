"""The exception tree of gimwatch and its warnings.

Every error gimwatch raises on bad input derives from
[`GimwatchError`][gimwatch.errors.GimwatchError]; the subclasses keep the offending value as
attributes and build a one-line message from them (what was wrong, what was received, and the fix
when it is obvious). The command line prints that line and exits with status 2. Every warning
derives from [`GimwatchWarning`][gimwatch.errors.GimwatchWarning].
"""

from __future__ import annotations

__all__ = [
    "BackendWarning",
    "ConditioningError",
    "GimwatchError",
    "GimwatchWarning",
    "IllConditionedWarning",
    "InputError",
    "OutputError",
    "RobotError",
    "SceneError",
    "SimulationError",
    "URDFError",
    "URDFWarning",
]


class GimwatchError(Exception):
    """Base class of every error gimwatch raises on purpose."""


class InputError(GimwatchError, ValueError):
    """A bad argument: ``name`` must satisfy ``rule``, got ``value``."""

    def __init__(self, name: str, rule: str, value: object = None, *, hint: str = "") -> None:
        self.name = name
        self.rule = rule
        self.value = value
        self.hint = hint
        message = f"{name} must be {rule}, got {value!r}"
        if hint:
            message += f" ({hint})"
        super().__init__(message)

    def renamed(self, name: str) -> InputError:
        """The same error about ``name`` (a CLI flag for a library parameter)."""
        return type(self)(name, self.rule, self.value, hint=self.hint)


class URDFError(GimwatchError):
    """A URDF file (or string) that cannot be used, with the element at fault."""

    def __init__(self, source: str, problem: str, *, element: str = "") -> None:
        self.source = source
        self.problem = problem
        self.element = element
        where = f"{source}: {element}: " if element else f"{source}: "
        super().__init__(where + problem)


class RobotError(GimwatchError):
    """A robot specification that names nothing loadable, or a model gimwatch cannot use."""

    def __init__(self, spec: str, problem: str) -> None:
        self.spec = spec
        self.problem = problem
        super().__init__(f"robot {spec!r}: {problem}")


class SceneError(GimwatchError):
    """A scene file with a bad key: ``source: key: problem``."""

    def __init__(self, source: str, key: str, problem: str) -> None:
        self.source = source
        self.key = key
        self.problem = problem
        super().__init__(f"{source}: {key}: {problem}" if key else f"{source}: {problem}")


class ConditioningError(GimwatchError, ValueError):
    """A matrix that is not a valid GIM (not square, finite, symmetric or positive definite)."""

    def __init__(self, problem: str) -> None:
        self.problem = problem
        super().__init__(problem)


class SimulationError(GimwatchError):
    """A simulation that could not go on (non-finite state, collapsed step size, ...)."""

    def __init__(self, time_s: float, cause: str) -> None:
        self.time_s = time_s
        self.cause = cause
        super().__init__(f"simulation stopped at t = {time_s:.6g} s: {cause}")


class OutputError(GimwatchError):
    """A results file or folder that cannot be written: ``path: problem``."""

    def __init__(self, path: str, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"{path}: {problem}")


class GimwatchWarning(UserWarning):
    """Base class of every warning gimwatch issues.

    Filter all of them at once with ``warnings.simplefilter("ignore", GimwatchWarning)``.
    """


class URDFWarning(GimwatchWarning):
    """A URDF value Pinocchio accepts but no physical body has; results from it are suspect.

    Example: principal moments of inertia that violate the triangle inequality.
    """


class IllConditionedWarning(GimwatchWarning):
    """The GIM's condition number (or its estimate) crossed a threshold."""


class ExampleRobotWarning(GimwatchWarning):
    """An example-robot-data name whose model differs from what its name promises.

    gimwatch reads the URDF as written; ``example_robot_data.load(name)`` may lock joints or
    add rotor inertias, and a few names ship another robot's description.
    """


class BackendWarning(GimwatchWarning):
    """gimwatch chose another dynamics backend than the one asked for, and why."""
