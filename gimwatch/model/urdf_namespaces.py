"""URDF tags read as urdfdom reads them: namespace prefixes kept as written, never resolved.

urdfdom, MuJoCo's URDF importer and Pinocchio use TinyXML, which knows no namespaces: a tag is
the text between ``<`` and the first space, ``<inertial xmlns="http://x">`` is an
``inertial``, and ``<gz:link>`` is not a ``link``. A namespace-aware reading (ElementTree's)
differs in both directions, so a value check on it can miss what urdfdom reads (a negative mass
behind an ``xmlns``), and a document re-serialised from it can lose or gain elements. Every
URDF is therefore read here with the prefixes as written, and what the two readings could
disagree on is refused with one line:

* an element of xacro's namespace (``<xacro:macro>``, ``<xacro:arm/>``): the file was not
  expanded; run xacro first;
* a URDF element written with a prefix (``<gz:link>``, ``<a:inertial>``) where URDF reads
  its elements: urdfdom ignores it, a namespace-aware reader reads it.

Extension elements with an undeclared prefix (old Gazebo ``<sensor:camera>`` blocks), which
expat refuses, are removed (a lenient reading, `gimwatch.model.urdf_quirks`).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from xml.parsers import expat

from gimwatch.errors import URDFError

__all__ = [
    "XACRO_NAMESPACE",
    "check_prefixed_elements",
    "fix_namespace",
    "parse_as_urdfdom",
    "parse_ignoring_prefixes",
]

XACRO_NAMESPACE = "http://www.ros.org/wiki/xacro"
#: URDF's own elements, and the elements whose children urdfdom reads as URDF.
_URDF_TAGS = frozenset(
    (
        "link joint inertial mass inertia origin axis limit parent child visual collision "
        "geometry mimic dynamics material color texture safety_controller calibration "
        "box cylinder sphere mesh"
    ).split()
)
_URDF_PARENTS = frozenset(
    ("robot", "link", "joint", "inertial", "visual", "collision", "geometry", "material")
)


def parse_as_urdfdom(xml: str) -> ET.Element:
    """The element tree with tags and attributes as written (``gz:link``, ``xmlns:gz``).

    Raises:
        ET.ParseError: The text is not well-formed XML even without namespaces.
    """
    builder = ET.TreeBuilder()
    parser = expat.ParserCreate()  # no namespace_separator: prefixes are left in the names
    parser.StartElementHandler = builder.start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    try:
        parser.Parse(xml, True)
    except expat.ExpatError as exc:
        raise ET.ParseError(str(exc)) from None
    return builder.close()


def _xacro_prefixes(root: ET.Element) -> set[str]:
    prefixes = {"xacro"}
    for element in root.iter():
        for key, value in element.attrib.items():
            if key.startswith("xmlns:") and value.rstrip("/#") == XACRO_NAMESPACE:
                prefixes.add(key.split(":", 1)[1])
    return prefixes


def check_prefixed_elements(root: ET.Element, source: str) -> None:
    """Refuse unexpanded xacro and URDF elements with a prefix (see the module docstring)."""
    xacro = _xacro_prefixes(root)
    for parent in root.iter():
        for child in parent:
            if not isinstance(child.tag, str) or ":" not in child.tag:
                continue
            prefix, local = child.tag.split(":", 1)
            if prefix in xacro:
                raise URDFError(
                    source,
                    f"<{child.tag}> is an unexpanded xacro element (a macro call or "
                    "definition): run xacro on the file first",
                )
            if local in _URDF_TAGS and parent.tag in _URDF_PARENTS:
                raise URDFError(
                    source,
                    f"<{child.tag}> in <{parent.tag}> is a URDF element with a namespace prefix: "
                    "urdfdom ignores it while namespace-aware readers read it; remove the prefix "
                    "or the element",
                )


def parse_ignoring_prefixes(xml: str, source: str) -> tuple[ET.Element, list[str]]:
    """Parse a text with undeclared prefixes as urdfdom does, and drop the prefixed parts.

    For texts expat refuses with "unbound prefix": after `check_prefixed_elements`, a
    prefixed element (and a prefixed attribute) is an extension no URDF reader uses.

    Raises:
        ET.ParseError: The text is not well-formed XML even without namespaces.
        URDFError: Unexpanded xacro, or a URDF element with a prefix.
    """
    root = parse_as_urdfdom(xml)
    check_prefixed_elements(root, source)
    removed = []
    for parent in list(root.iter()):
        for child in list(parent):
            if ":" in child.tag:
                parent.remove(child)
                removed.append(f"<{child.tag}>")
        for key in [key for key in parent.attrib if ":" in key or key == "xmlns"]:
            del parent.attrib[key]  # declarations too: the tags are read without namespaces
            if not key.startswith("xmlns"):
                removed.append(f"{key}=")
    shown = ", ".join(dict.fromkeys(removed[:20]))
    return root, [f"elements and attributes with an undeclared namespace prefix removed ({shown})"]


def fix_namespace(root: ET.Element) -> list[str]:
    """Read default namespaces (``<robot xmlns="...">``) as urdfdom does: not at all.

    The declarations are dropped everywhere, so that a namespace-aware reader of the
    normalised text (yourdfpy, for DeNOC) reads the same tags as urdfdom.
    """
    where = []
    for element in root.iter():
        if element.get("xmlns") is not None:
            del element.attrib["xmlns"]
            where.append(f"<{element.tag}>")
    if not where:
        return []
    shown = ", ".join(dict.fromkeys(where[:3]))
    return [f"a default XML namespace on {shown} ignored"]
