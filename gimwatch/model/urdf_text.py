"""Checks on URDF text made before any parser builds a model from it.

Pinocchio's parser (urdfdom) and yourdfpy both trust their input; this module turns the
common ways a URDF can be broken into one-line :class:`~gimwatch.errors.URDFError` messages that
name the file and the element. It imports no dynamics library, so DeNOC can use it too.
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET

from gimwatch.errors import URDFError, URDFWarning
from gimwatch.model.urdf_values import check_joint_values, check_link_values

__all__ = ["check_urdf", "parse_urdf_xml"]

#: Document-type declarations can define entities (external files, "billion laughs");
#: no URDF needs them, so they are refused before any parser sees the text.
_FORBIDDEN = ("<!DOCTYPE", "<!ENTITY")


def parse_urdf_xml(xml: str, source: str) -> ET.Element:
    """Parse URDF text safely and return its ``<robot>`` element."""
    if not xml.strip():
        raise URDFError(source, "the file is empty")
    head = xml.upper()
    for token in _FORBIDDEN:
        if token in head:
            raise URDFError(source, f"{token.lstrip('<!')} declarations are not allowed in a URDF")
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as exc:
        raise URDFError(source, f"malformed XML ({exc})") from exc
    if root.tag != "robot":
        raise URDFError(source, f"the root element must be <robot>, got <{root.tag}>")
    return root


def check_urdf(xml: str, source: str) -> ET.Element:
    """Check the structure of URDF text and return its ``<robot>`` element.

    Then every value urdfdom reads is checked (see :mod:`gimwatch.model.urdf_values`).

    Raises:
        URDFError: The text is not well-formed XML, not a URDF, its links and joints do
            not form a tree, or a value is missing, malformed or physically impossible.

    Warns:
        URDFWarning: Once per file, naming the links whose principal moments of inertia
            violate the triangle inequality.
    """
    root = parse_urdf_xml(xml, source)
    links = [link.get("name") for link in root.findall("link")]
    if not links:
        raise URDFError(source, "the robot has no <link>")
    seen: set[str] = set()
    for name in links:
        if not name:
            raise URDFError(source, "a <link> has no name attribute")
        if name in seen:
            raise URDFError(source, "duplicate link name", element=f"link {name!r}")
        seen.add(name)
    parent_of: dict[str, str] = {}
    joint_names: set[str] = set()
    for joint in root.findall("joint"):
        name = joint.get("name")
        if not name:
            raise URDFError(source, "a <joint> has no name attribute")
        where = f"joint {name!r}"
        if name in joint_names:
            raise URDFError(source, "duplicate joint name", element=where)
        joint_names.add(name)
        ends = {}
        for end in ("parent", "child"):
            tag = joint.find(end)
            link = tag.get("link") if tag is not None else None
            if not link:
                raise URDFError(source, f"missing <{end} link=...>", element=where)
            if link not in seen:
                raise URDFError(source, f"{end} link {link!r} is not defined", element=where)
            ends[end] = link
        if ends["child"] in parent_of:
            raise URDFError(source, f"link {ends['child']!r} has two parent joints", element=where)
        parent_of[ends["child"]] = ends["parent"]
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        problem = (
            "the links form a cycle"
            if not roots
            else (f"the links are not connected: {len(roots)} root links ({', '.join(roots[:4])})")
        )
        raise URDFError(source, problem)
    children: dict[str, list[str]] = {}
    for child, parent in parent_of.items():
        children.setdefault(parent, []).append(child)
    reached = _reachable(roots[0], children)
    if len(reached) != len(links):
        stray = sorted(seen - reached)[:4]
        raise URDFError(
            source, f"the links form a cycle not attached to the root: {', '.join(stray)}"
        )
    doubtful = [
        link.get("name") for link in root.findall("link") if not check_link_values(link, source)
    ]
    for joint in root.findall("joint"):
        check_joint_values(joint, source)
    if doubtful:
        shown = ", ".join(doubtful[:4]) + (", ..." if len(doubtful) > 4 else "")
        warnings.warn(
            URDFWarning(
                f"{source}: {len(doubtful)} link(s) have principal moments of inertia that "
                f"violate the triangle inequality a + b >= c ({shown}); no rigid body has "
                "such an inertia, so the GIM computed from it is suspect"
            ),
            stacklevel=2,
        )
    return root


def _reachable(root: str, children: dict[str, list[str]]) -> set[str]:
    found, stack = set(), [root]
    while stack:
        link = stack.pop()
        found.add(link)
        stack.extend(children.get(link, ()))
    return found
