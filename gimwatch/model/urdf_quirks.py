"""Real-world URDF conventions that do not change M(q): read with one warning, not refused.

Robot descriptions in the wild are written by xacro, CAD exporters and hand, and read by
lenient parsers (Bullet's, ROS's); urdfdom (Pinocchio's parser) and expat refuse some of what
they accept. What cannot change the mass matrix is normalised here, before the value checks,
and listed in one [`URDFWarning`][gimwatch.errors.URDFWarning] per file:

* text: an XML declaration after comments or blank lines (removed), NUL bytes or other
  control characters after the root element (removed);
* a default namespace on ``<robot xmlns="...">`` or another element (tags read without it,
  as urdfdom reads them; see `gimwatch.model.urdf_namespaces`);
* line breaks or tabs inside number attributes, and padded single numbers (Unitree's
  hands wrap ``ixx`` over lines): read as single spaces (urdfdom cannot read them and
  silently drops that link's whole inertial);
* ``<visual>`` and ``<collision>`` elements that urdfdom cannot read (an unknown geometry such
  as Bullet's ``<plane>``, an empty ``<geometry>``, a four-number mesh scale): removed — shapes
  do not enter M;
* numbers separated by commas (``xyz="0.07, 0, -0.69"``): read as spaces, only where the
  commas are the three numbers' separators (a decimal comma, ``"0,5 0"``, is refused);
* a ``<material>`` without a name attribute (Unitree's H1-2) and a ``<material>`` defined twice
  (pybullet's racecar): removed (colours do not enter M);
* joint limits: a negative ``effort``/``velocity`` ("unlimited", e.g. ``effort="-1"``) or a
  missing one (read as 0), a missing ``<limit>`` on a revolute or prismatic joint, and
  ``lower > upper`` (Bullet's "no limit"): the position range becomes the placeholder
  ±`gimwatch.model.sampling.PLACEHOLDER_LIMIT` (random draws use ±π rad / ±1 m);
* an empty ``<dynamics/>`` (removed; damping and friction do not enter M);
* extension elements with an undeclared namespace prefix (``<sensor:camera>`` in old Gazebo
  blocks; expat refuses the whole file, urdfdom ignores namespaces): removed;
* a ``<robot>`` without a name (urdfdom refuses it): named after the file;
* a ``<mimic>`` of a fixed joint: the follower would stay at its offset; like every mimic
  joint it is modelled as an independent joint, as Pinocchio does;
* a joint whose parent is an undeclared link named ``world`` (Drake's and Gazebo's name for
  the fixed frame, e.g. Drake's ``pr2_simplified.urdf``): ``<link name="world"/>`` is added,
  massless, so the robot is attached to the fixed base as those readers attach it;
* an invalid ``<inertial>`` on a link welded by fixed joints to the root of a fixed-base
  robot (cuRobo's panda): removed, as it never enters M (`gimwatch.model.urdf_text`).

What makes M undefined or wrong is still refused by the value checks
(`gimwatch.model.urdf_values`): non-finite or unparsable numbers in origins, axes and
inertials, negative masses, non-positive-semi-definite inertias, unknown joint types.
Every scan here is linear in the size of the text.
"""

from __future__ import annotations

import re
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from gimwatch.errors import URDFError, URDFWarning

__all__ = [
    "fix_text_quirks",
    "fix_tree_quirks",
    "padded_number_attributes",
    "warn_quirks",
]

#: The placeholder range written for a limit that means "unlimited" (see sampling).
_UNLIMITED = "1000"
_GEOMETRIES = ("box", "cylinder", "sphere", "mesh")
_SHAPE_ATTRIBUTES = {"box": ("size",), "cylinder": ("radius", "length"), "sphere": ("radius",)}
_CONTROL = {chr(c) for c in range(32) if chr(c) not in "\t\n\r"}
#: An attribute and its quoted value, as written (one linear scan of the text).
_ATTRIBUTE = re.compile(r"""(?<![\w:.-])([\w:.-]+)(\s*=\s*)(?:"([^"<]*)"|'([^'<]*)')""")


def fix_text_quirks(xml: str) -> tuple[str, list[str]]:
    """The text without a byte-order mark, a misplaced XML declaration or a control tail."""
    fixes = []
    xml = xml.removeprefix("\ufeff")
    end = len(xml)
    while end and (xml[end - 1] in _CONTROL or xml[end - 1].isspace()):
        end -= 1
    if any(c in _CONTROL for c in xml[end:]):
        fixes.append("control characters (NUL bytes) after the root element removed")
        xml = xml[:end] + "\n"
    declaration = _misplaced_declaration(xml)
    if declaration is not None:
        fixes.append("an XML declaration after comments or blank lines removed")
        xml = xml[: declaration[0]] + xml[declaration[1] :]
    return xml, fixes


def _misplaced_declaration(xml: str) -> tuple[int, int] | None:
    """(start, end) of an ``<?xml ...?>`` preceded only by blank lines and comments."""
    position = 0
    while True:
        while position < len(xml) and xml[position].isspace():
            position += 1
        if not xml.startswith("<!--", position):
            break
        close = xml.find("-->", position + 4)
        if close < 0:
            return None
        position = close + 3
    if position == 0 or not xml.startswith("<?xml", position):
        return None
    close = xml.find("?>", position)
    return None if close < 0 else (position, close + 2)


def _is_number_list(text: str, count: int) -> bool:
    parts = text.split()
    if len(parts) != count:
        return False
    try:
        values = [float(p) for p in parts]
    except ValueError:
        return False
    return all(abs(v) < float("inf") for v in values)


def _bad_shape(shape: ET.Element) -> str:
    """Why urdfdom cannot read a visual/collision element, or "" when it can."""
    geometry = shape.find("geometry")
    kinds = list(geometry) if geometry is not None else []
    if len(kinds) != 1 or kinds[0].tag not in _GEOMETRIES:
        found = ", ".join(f"<{k.tag}>" for k in kinds) or "nothing"
        return f"its <geometry> holds {found}"
    kind = kinds[0]
    if kind.tag == "mesh":
        if not kind.get("filename"):
            return "its <mesh> has no filename"
        scale = kind.get("scale")
        if scale is not None and not _is_number_list(scale, 3):
            return f"its <mesh scale> is {scale!r}"
        return ""
    for attribute in _SHAPE_ATTRIBUTES[kind.tag]:
        text = kind.get(attribute)
        if text is None or not _is_number_list(text, 3 if attribute == "size" else 1):
            return f"its <{kind.tag} {attribute}> is {text!r}"
    origin = shape.find("origin")
    for attribute in ("xyz", "rpy"):
        text = origin.get(attribute) if origin is not None else None
        if text is not None and not _is_number_list(text.replace(",", " "), 3):
            return f"its <origin {attribute}> is {text!r}"
    material = shape.find("material")
    color = material.find("color") if material is not None else None
    if color is not None and not _is_number_list(color.get("rgba") or "", 4):
        return f"its <color rgba> is {color.get('rgba')!r}"
    return ""


def _drop_unreadable_shapes(root: ET.Element) -> list[str]:
    dropped = []
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for shape in link.findall(tag):
                problem = _bad_shape(shape)
                if problem:
                    link.remove(shape)
                    dropped.append(f"{link.get('name')} <{tag}> ({problem})")
    if not dropped:
        return []
    shown = "; ".join(dropped[:3]) + ("; ..." if len(dropped) > 3 else "")
    return [f"{len(dropped)} visual/collision shape(s) urdfdom cannot read removed: {shown}"]


def _commas_as_spaces(root: ET.Element) -> list[str]:
    """Origins and axes whose three numbers are separated by commas (``0.07, 0, -0.69``).

    Only where the commas are the separators: three fields, none holding a space. A decimal
    comma (``0,5 0``, two fields) would change a value and is left to the value checks,
    which refuse it.
    """
    where = []
    for element in root.iter():
        if element.tag not in ("origin", "axis"):
            continue
        for key in ("xyz", "rpy"):
            value = element.get(key)
            if value and "," in value:
                fields = [field.strip() for field in value.split(",")]
                if len(fields) == 3 and all(f and len(f.split()) == 1 for f in fields):
                    element.set(key, " ".join(fields))
                    where.append(f"<{element.tag} {key}={value!r}>")
    if not where:
        return []
    more = ", ..." if len(where) > 2 else ""
    return [f"numbers separated by commas read as spaces ({', '.join(where[:2])}{more})"]


def _is_numbers(text: str) -> bool:
    try:
        return bool(text.split()) and all(abs(float(p)) >= 0 for p in text.split())
    except ValueError:
        return False


def padded_number_attributes(xml: str) -> list[str]:
    r"""Attributes of numbers urdfdom cannot read: split by line breaks or tabs, or padded.

    Read from the text, not the tree: expat turns line breaks and tabs in attributes into
    spaces, while urdfdom refuses ``"0.1\n"`` and then drops the link's whole inertial.
    """
    found = []
    for match in _ATTRIBUTE.finditer(xml):
        value = match.group(3) if match.group(3) is not None else match.group(4)
        unreadable = any(c in value for c in "\t\n\r") or (
            len(value.split()) == 1 and value != value.strip()
        )  # urdfdom splits vectors at single spaces only, and reads a padded scalar as text
        if unreadable and _is_numbers(value):
            found.append(match.group(1))
    return found


def _normalise_number_whitespace(root: ET.Element, padded: list[str]) -> list[str]:
    if not padded:
        return []
    for element in root.iter():
        for key, value in element.attrib.items():
            if value != " ".join(value.split()) and _is_numbers(value):
                element.set(key, " ".join(value.split()))
    shown = ", ".join(dict.fromkeys(padded[:4])) + (", ..." if len(set(padded)) > 4 else "")
    return [f"line breaks, tabs or padding inside numbers read as separators ({shown})"]


def _material_quirks(root: ET.Element) -> list[str]:
    """Visual materials urdfdom refuses: without a name (removed), named twice (later ones)."""
    unnamed = []
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            for material in visual.findall("material"):
                if material.get("name") is None:  # name="" urdfdom reads (Go2 has them)
                    visual.remove(material)
                    unnamed.append(str(link.get("name")))
    seen, duplicates = set(), []
    for material in root.findall("material"):
        name = material.get("name")
        if name is None:
            root.remove(material)
            unnamed.append("robot")
        elif name in seen:
            root.remove(material)
            duplicates.append(name)
        seen.add(name)
    fixes = []
    if unnamed:
        shown = ", ".join(dict.fromkeys(unnamed[:3])) + (", ..." if len(unnamed) > 3 else "")
        fixes.append(f"{len(unnamed)} <material> without a name removed ({shown})")
    if duplicates:
        shown = ", ".join(dict.fromkeys(duplicates[:3]))
        fixes.append(f"{len(duplicates)} repeated <material> definition(s) removed ({shown})")
    return fixes


def _fix_effort_velocity(limit: ET.Element, name: str | None, found: dict[str, list]) -> None:
    """A missing effort/velocity read as 0, a negative or unreadable one as unlimited (0)."""
    for key in ("effort", "velocity"):
        text = limit.get(key)
        if text is None:
            limit.set(key, "0")
            found["missing_value"].append(f"{name}.{key}")
            continue
        try:
            value = float(text)
        except ValueError:
            value = -1.0  # unreadable, as urdfdom would say: read as unlimited too
        if not value >= 0:
            limit.set(key, "0")
            found["negative"].append(f"{name}.{key}={text}")


def _fix_range(limit: ET.Element, name: str | None, found: dict[str, list]) -> None:
    """Limits with lower > upper (or unreadable) read as unlimited."""
    try:
        lower = float(limit.get("lower", "0"))
        upper = float(limit.get("upper", "0"))
    except ValueError:  # e.g. lower="-1.57." (a typo urdfdom refuses)
        lower, upper = 1.0, 0.0
    if not lower <= upper:
        limit.set("lower", "-" + _UNLIMITED)
        limit.set("upper", _UNLIMITED)
        found["reversed_range"].append(name)


#: What each kind of limit quirk is read as, in the order the fixes are listed.
_LIMIT_FIXES = {
    "negative": "negative or unreadable effort/velocity limits read as unlimited",
    "missing_value": "missing <limit> effort/velocity read as 0",
    "missing_limit": "revolute/prismatic joints without <limit> read as unlimited",
    "reversed_range": "limits with lower > upper (or unreadable) read as unlimited",
    "empty_dynamics": "empty <dynamics/> removed",
}


def _limit_quirks(root: ET.Element, kinds: dict[str | None, str | None]) -> list[str]:
    found: dict[str, list] = {key: [] for key in _LIMIT_FIXES}
    for joint in root.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        limit = joint.find("limit")
        if limit is None and kind in ("revolute", "prismatic"):
            bounds = {"lower": "-" + _UNLIMITED, "upper": _UNLIMITED}
            limit = ET.SubElement(joint, "limit", {"effort": "0", "velocity": "0", **bounds})
            found["missing_limit"].append(name)
        if limit is not None:
            _fix_effort_velocity(limit, name, found)
            if kind in ("revolute", "prismatic"):
                _fix_range(limit, name, found)
        dynamics = joint.find("dynamics")
        if dynamics is not None and dynamics.get("damping") is dynamics.get("friction") is None:
            joint.remove(dynamics)
            found["empty_dynamics"].append(name)
    fixes = []
    for key, what in _LIMIT_FIXES.items():
        joints = found[key]
        if joints:
            more = ", ..." if len(joints) > 3 else ""
            fixes.append(f"{what} ({', '.join(joints[:3])}{more})")
    return fixes


def _mimics_of_fixed(root: ET.Element, kinds: dict[str | None, str | None]) -> list[str]:
    followers = [
        f"{joint.get('name')} -> {mimic.get('joint')}"
        for joint in root.findall("joint")
        if (mimic := joint.find("mimic")) is not None and kinds.get(mimic.get("joint")) == "fixed"
    ]
    if not followers:
        return []
    shown = ", ".join(followers[:3]) + (", ..." if len(followers) > 3 else "")
    return [
        f"<mimic> of a fixed joint ({shown}): the follower stays at its offset on the robot; "
        "like every mimic joint it is modelled as an independent joint"
    ]


def _implicit_world(root: ET.Element) -> list[str]:
    """Declare the ``world`` link that joints name as their parent without declaring it."""
    if any(link.get("name") == "world" for link in root.findall("link")):
        return []
    joints = [
        str(joint.get("name"))
        for joint in root.findall("joint")
        if (parent := joint.find("parent")) is not None and parent.get("link") == "world"
    ]
    if not joints:
        return []
    root.insert(0, ET.Element("link", name="world"))
    shown = ", ".join(joints[:3]) + (", ..." if len(joints) > 3 else "")
    return [f"the undeclared parent link 'world' of {shown} added as the fixed base (massless)"]


def fix_tree_quirks(root: ET.Element, source: str, padded: Sequence[str] = ()) -> list[str]:
    """Normalise, in place, what urdfdom would refuse but M does not depend on.

    ``padded``: the attributes `padded_number_attributes` found in the text.
    """
    if root.tag != "robot":
        raise URDFError(source, f"the root element must be <robot>, got <{root.tag}>")
    unnamed = []
    if not (root.get("name") or "").strip():
        name = source.replace("\\", "/").rsplit("/", 1)[-1].rsplit(".", 1)[0].strip("<>")
        root.set("name", name or "robot")
        unnamed = [f"a <robot> without a name named {root.get('name')!r}"]
    kinds = {joint.get("name"): joint.get("type") for joint in root.findall("joint")}
    return [
        *_normalise_number_whitespace(root, list(padded)),
        *_commas_as_spaces(root),
        *_material_quirks(root),
        *_drop_unreadable_shapes(root),
        *_limit_quirks(root, kinds),
        *_mimics_of_fixed(root, kinds),
        *_implicit_world(root),
        *unnamed,
    ]


def warn_quirks(source: str, fixes: list[str], *, stacklevel: int) -> None:
    """One URDFWarning naming what was read leniently; nothing when there was nothing."""
    if fixes:
        warnings.warn(
            URDFWarning(
                f"{source}: read with {len(fixes)} lenient reading(s) that do not change M: "
                + "; ".join(fixes)
            ),
            stacklevel=stacklevel + 1,
        )
