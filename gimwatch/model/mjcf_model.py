"""Recognising MJCF files: the root element of an XML text, by a linear scan.

MJCF is read by MuJoCo's compiler (`gimwatch.model.mjcf_robot`).
"""

from __future__ import annotations

__all__ = ["is_mjcf", "root_element_name"]


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
