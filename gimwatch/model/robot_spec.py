"""A robot specification parsed once: what a ``chain:N``, a path or a robot's name stands for.

The one parser, [`RobotSpec.parse`][gimwatch.model.robot_spec.RobotSpec.parse], turns the text
a user writes (and the choice of base) into a frozen `RobotSpec`: its kind (a generated chain,
an example-robot-data robot, a URDF or MJCF file), its `ChainSpec` for chains, the base it gets
and the MJCF options. Every later step reads these fields instead of parsing the text again;
`gimwatch.model.robots.load_robot` turns a `RobotSpec` into a `Robot`.

Two specs are equal when they stand for the same robot: ``RobotSpec.parse("chain:5")`` equals
``RobotSpec.parse(Path("chain:5"))``, so a spec is a dictionary key for loaded robots.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, TypedDict

from gimwatch.errors import InputError, RobotError
from gimwatch.model.chains import ChainSpec, chain_spec
from gimwatch.model.example_robots import example_robot_loaders

__all__ = [
    "RobotSpec",
    "SpecOptions",
    "default_floating",
    "display_name",
    "parse_chain_spec",
    "robot_spec",
]

_CHAIN_SPEC = re.compile(r"^chain:(\S+)$")
#: What a spec names: a generated chain, an example-robot-data robot, a URDF or MJCF file.
Kind = Literal["chain", "example", "file"]


class SpecOptions(TypedDict, total=False):
    """The options a spec is parsed with (keyword arguments of `RobotSpec.parse`)."""

    floating: bool | None
    body: str
    armature: bool


def parse_chain_spec(spec: str | Path) -> ChainSpec | None:
    """The `ChainSpec` of a ``chain:N`` specification, or None for other specs."""
    match = _CHAIN_SPEC.match(str(spec))
    if not match:
        return None
    try:
        n = int(match.group(1))
    except ValueError:
        raise InputError("the N of chain:N", "a positive integer", match.group(1)) from None
    return chain_spec(n)


def default_floating(spec: str | Path) -> bool:
    """The base a robot gets when none is asked for: True for a free-flyer.

    An example-robot-data robot gets its loader's (``free_flyer``: legged robots, humanoids,
    drones), so that ``load_robot(name)`` has the nq and nv of ``example_robot_data.load``;
    chains and files get a fixed base.
    """
    loader = example_robot_loaders().get(str(spec))
    return bool(getattr(loader, "free_flyer", False)) if loader is not None else False


def display_name(text: str) -> str:
    r"""``text`` printable as UTF-8, whatever bytes a file name holds.

    Bytes of a file name that are not UTF-8 (Python keeps them as lone surrogates) become
    ``\xNN``, so figure titles, tables and JSON never fail on them.
    """
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def _kind(text: str) -> Kind:
    """What ``text`` names, or a RobotError with the closest example-robot-data names."""
    if text in example_robot_loaders():
        return "example"
    if text.lower().endswith((".urdf", ".xml")) or Path(text).exists() or "/" in text:
        return "file"
    names = list(example_robot_loaders())
    close = [n for n in names if n.lower() == text.lower()]  # UR5 -> ur5
    close = close or difflib.get_close_matches(text.lower(), names, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise RobotError(
        text, f"not chain:N, a URDF or MJCF file, or an example-robot-data robot{hint}"
    )


@dataclass(frozen=True)
class RobotSpec:
    """A robot specification, parsed once (see the module docstring).

    Attributes:
        text: The specification as written (``chain:5``, a path, ``ur5``).
        kind: ``"chain"``, ``"example"`` (example-robot-data) or ``"file"`` (URDF or MJCF).
        floating: The base: True adds a free-flyer root joint (as asked, or the robot's
            default, `default_floating`).
        chain: The `ChainSpec` of a ``chain:N``, else None.
        body: MJCF only: the body whose subtree is read ("" for the whole model).
        armature: MJCF only: keep MuJoCo's ``dof_armature`` in M.
    """

    text: str
    kind: Kind
    floating: bool = False
    chain: ChainSpec | None = None
    body: str = ""
    armature: bool = True

    @classmethod
    def parse(
        cls,
        spec: str | Path,
        floating: bool | None = None,
        *,
        body: str = "",
        armature: bool = True,
    ) -> RobotSpec:
        """The `RobotSpec` of ``spec``: the one place a robot's text is parsed.

        Args:
            spec: ``chain:N``, a URDF or MJCF path, or an example-robot-data name.
            floating: True: a free-flyer base; False: fixed; None: the robot's default
                (`default_floating`: example-robot-data's base for its robots, else fixed).
            body: MJCF only: read the subtree of this body.
            armature: MJCF only: keep MuJoCo's ``dof_armature`` in M.

        Raises:
            InputError: An empty spec, a bad N, or ``body`` given for a chain or a named robot.
            RobotError: The spec names nothing loadable (with the closest robot names).
        """
        text = str(spec)
        if not text.strip():
            raise InputError(
                "the robot", "chain:N, a URDF path or an example-robot-data name", text
            )
        chain = parse_chain_spec(text)
        kind: Kind = "chain" if chain is not None else _kind(text)
        if body and kind != "file":
            raise InputError("body", "given only with an MJCF file", body)
        if floating is None:
            floating = kind == "example" and default_floating(text)
        return cls(text, kind, bool(floating), chain, body, armature)

    @property
    def name(self) -> str:
        """The robot's short name before loading: ``chain_N``, the robot's name or file stem."""
        if self.chain is not None:
            return self.chain.name
        if self.kind == "example":
            return self.text
        return display_name(Path(self.text).stem)

    def with_options(self, **options: bool | str | None) -> RobotSpec:
        """This spec with the options of `SpecOptions` given (None: unchanged).

        Raises:
            InputError: An option that a robot's kind does not take (``body`` of a chain).
        """
        given = {k: v for k, v in options.items() if v is not None}
        for key in given:
            if key not in SpecOptions.__annotations__:
                raise InputError("option", f"one of {', '.join(SpecOptions.__annotations__)}", key)
        if not given or all(getattr(self, k) == v for k, v in given.items()):
            return self
        if given.get("body") and self.kind != "file":
            raise InputError("body", "given only with an MJCF file", given["body"])
        fields = {**self.__dict__, **given}
        return RobotSpec(**fields)

    def __str__(self) -> str:
        return self.text


def robot_spec(spec: RobotSpec | str | Path, **options: bool | str | None) -> RobotSpec:
    """``spec`` parsed (a string or a path) or as given (a `RobotSpec`), with ``options``.

    ``options`` are those of `SpecOptions`; None leaves one as the spec has it.
    """
    if isinstance(spec, RobotSpec):
        return spec.with_options(**options)
    given = {k: v for k, v in options.items() if v is not None}
    return RobotSpec.parse(spec, **given)  # type: ignore[arg-type]
