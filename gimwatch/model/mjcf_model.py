"""MJCF files read by Pinocchio's MJCF parser: recognising them, and a floating base for them.

The values are checked first (`gimwatch.model.mjcf_values`); Pinocchio's complaints
become one [`URDFError`][gimwatch.errors.URDFError] naming the file.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pinocchio as pin

from gimwatch.errors import URDFError
from gimwatch.model.captured_output import captured_c_output

__all__ = ["build_mjcf_model", "is_mjcf", "root_element_name", "with_free_joint"]


def root_element_name(xml: str) -> str | None:
    """The name of an XML text's root element, or None if none is found before other text.

    A linear scan: a byte-order mark, whitespace, ``<?...?>`` declarations, comments and a
    ``<!DOCTYPE ...>`` are skipped with ``str.find``, each character looked at a bounded
    number of times. (A regular expression with nested repetition over the prolog
    backtracked exponentially on xacro's 30-line comment headers.)
    """
    position, size = 0, len(xml)
    if xml.startswith("\ufeff"):
        position = 1
    while position < size:
        while position < size and xml[position] in " \t\r\n":
            position += 1
        if xml.startswith("<?", position):
            end = xml.find("?>", position + 2)
            position = size if end < 0 else end + 2
        elif xml.startswith("<!--", position):
            end = xml.find("-->", position + 4)
            position = size if end < 0 else end + 3
        elif xml.startswith("<!", position):
            position = _after_declaration(xml, position)
        elif xml.startswith("<", position):
            start = position + 1
            stop = start
            while stop < size and xml[stop] not in " \t\r\n/>":
                stop += 1
            return xml[start:stop] or None
        else:
            return None
    return None


def _after_declaration(xml: str, position: int) -> int:
    """The index after a ``<!DOCTYPE ...>``, internal subset ``[...]`` included."""
    close = xml.find(">", position)
    bracket = xml.find("[", position)
    if bracket < 0 or (0 <= close < bracket):
        return len(xml) if close < 0 else close + 1
    end = xml.find("]", bracket)
    close = -1 if end < 0 else xml.find(">", end)
    return len(xml) if close < 0 else close + 1


def is_mjcf(xml: str) -> bool:
    """Whether an XML text's root element is ``<mujoco>`` (after comments and declarations)."""
    return root_element_name(xml) == "mujoco"


def with_free_joint(mjcf_xml: str, source: str) -> str:
    """The MJCF text with ``<freejoint name="root_joint"/>`` in the first body of the world.

    Pinocchio 4's ``buildModelFromMJCF(path, root_joint, name)`` ignores the root joint,
    and MuJoCo's bodies are fixed unless they have a joint, so a floating base is written
    into the text for both.
    """
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(mjcf_xml)
    except ET.ParseError as exc:
        raise URDFError(source, f"is not well-formed XML ({exc})") from exc
    world = root.find("worldbody")
    body = None if world is None else world.find("body")
    if body is None:
        raise URDFError(source, "has no <body> in <worldbody> to put a floating base on")
    if body.find("freejoint") is not None or body.find("joint[@type='free']") is not None:
        return mjcf_xml
    if body.find("joint") is not None:
        raise URDFError(
            source,
            f"its first body '{body.get('name', '')}' already has a joint, so there is no "
            "base body to float; add a <freejoint/> body around it in the MJCF",
        )
    body.insert(0, ET.Element("freejoint", name="root_joint"))
    return ET.tostring(root, encoding="unicode")


def build_mjcf_model(source: str, floating: bool, xml: str) -> pin.Model:
    """Pinocchio's MJCF parser on the file ``source``; its complaints become one error."""
    with captured_c_output() as complaints, tempfile.TemporaryDirectory() as folder:
        path = source
        if floating:
            path = str(Path(folder) / Path(source).name)
            Path(path).write_text(with_free_joint(xml, source), encoding="utf-8")
        try:
            model = pin.buildModelFromMJCF(path)
        except Exception as exc:  # boost.python raises RuntimeError, ValueError, ...
            model, failure = None, exc
    if model is None:
        # Pinocchio's message starts with its C++ source location; keep what follows.
        detail = " ".join(str(failure).split("message:")[-1].split()) or type(failure).__name__
        if complaints:
            detail += f" ({complaints[0]})"
        raise URDFError(source, f"Pinocchio cannot read this MJCF: {detail}")
    return model
