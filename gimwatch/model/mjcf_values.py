"""Checks of an MJCF file's values before Pinocchio's MJCF parser reads it.

Pinocchio's parser is lenient where a wrong number changes M(q) silently: a negative mass
becomes 0, an axis of ``"0 one 0"`` becomes a zero axis, an ``<include>`` is skipped (or,
when the file exists, leaves an empty tree). These checks refuse such files with one line
naming the file, the body or joint, and the attribute; principal moments of inertia that
violate the triangle inequality (a body no rigid material can make, which MuJoCo itself
refuses) give one [`URDFWarning`][gimwatch.errors.URDFWarning], as for URDF.

Attributes set through ``<default>`` classes are not resolved: an attribute absent from an
element is left to the parser.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

import numpy as np

from gimwatch.errors import URDFError
from gimwatch.model.urdf_values import check_principal_moments, warn_doubtful_inertias

__all__ = ["MJCF_JOINT_TYPES", "check_mjcf"]

#: Joint types of MJCF that Pinocchio's parser turns into joints.
MJCF_JOINT_TYPES = ("hinge", "slide", "ball", "free")

_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")  # unambiguous: linear
#: Attribute -> how many numbers it holds, for the elements whose values reach M(q).
_COUNTS = {
    "body": {"pos": 3, "quat": 4, "euler": 3},
    "joint": {"pos": 3, "axis": 3, "armature": 1},
    "inertial": {"pos": 3, "quat": 4, "euler": 3, "mass": 1, "diaginertia": 3, "fullinertia": 6},
}


def _numbers(element: ET.Element, attribute: str, count: int, source: str, where: str):
    text = element.get(attribute)
    if text is None:
        return None
    parts = text.split()
    what = f"<{element.tag} {attribute}>"
    if len(parts) != count or not all(_NUMBER.fullmatch(p) for p in parts):
        rule = "a number" if count == 1 else f"{count} numbers separated by spaces"
        raise URDFError(source, f"{what} must be {rule}, got {text!r}", element=where)
    values = np.array([float(p) for p in parts])
    if not np.all(np.isfinite(values)):
        raise URDFError(source, f"{what} must be finite, got {text!r}", element=where)
    return values


def _where(element: ET.Element, body: ET.Element | None) -> str:
    if element.tag == "joint":
        return f"joint {element.get('name', '(unnamed)')!r}"
    name = (body if body is not None else element).get("name", "(unnamed)")
    return f"body {name!r}"


def _check_inertial(values: dict, source: str, where: str) -> bool:
    """Mass >= 0 and a positive semi-definite inertia; False if the triangle inequality fails."""
    mass = values.get("mass")
    if mass is not None and mass[0] < 0:
        raise URDFError(source, f"mass must be >= 0 kg, got {float(mass[0])!r}", element=where)
    if values.get("fullinertia") is not None:
        xx, yy, zz, xy, xz, yz = values["fullinertia"]
        moments = np.linalg.eigvalsh(np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
    elif values.get("diaginertia") is not None:
        moments = np.sort(values["diaginertia"])
    else:
        return True
    return check_principal_moments(moments, source=source, where=where)


def check_mjcf(xml: str, source: str) -> None:
    """Refuse MJCF values that Pinocchio's parser would silently change; warn on doubtful ones.

    Raises:
        URDFError: Not well-formed XML, an ``<include>``, an unknown joint type, a value
            that is not the expected count of finite numbers, a zero axis, a negative mass
            or an inertia with a negative principal moment — naming the body or joint.
    """
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as exc:
        raise URDFError(source, f"not well-formed XML ({exc})") from None
    if root.find(".//include") is not None:
        included = root.find(".//include").get("file", "")
        raise URDFError(
            source,
            f"<include file={included!r}> is not read by Pinocchio's MJCF parser; "
            "give the included file itself, or merge it into this one",
        )
    doubtful = []
    for body in root.iter("body"):
        if body.find("inertial") is None and body.find("geom") is None:
            raise URDFError(
                source,
                "has neither <inertial> nor <geom>, so Pinocchio cannot give it a mass",
                element=f"body {body.get('name', '(unnamed)')!r}",
            )
        for element in (body, *body.findall("joint"), *body.findall("inertial")):
            where = _where(element, body)
            values = {
                attribute: _numbers(element, attribute, count, source, where)
                for attribute, count in _COUNTS[element.tag].items()
            }
            if element.tag == "joint":
                kind = element.get("type")
                if kind is not None and kind not in MJCF_JOINT_TYPES:
                    raise URDFError(
                        source,
                        f"<joint type> must be one of {', '.join(MJCF_JOINT_TYPES)}, got {kind!r}",
                        element=where,
                    )
                axis = values.get("axis")
                if axis is not None and kind in (None, "hinge", "slide"):
                    scale = float(np.max(np.abs(axis)))  # scaled norm: no over- or underflow
                    if scale == 0 or not math.isfinite(scale * np.linalg.norm(axis / scale)):
                        raise URDFError(
                            source,
                            f"<joint axis> must be a non-zero vector, got {element.get('axis')!r}",
                            element=where,
                        )
            elif element.tag == "inertial" and not _check_inertial(values, source, where):
                doubtful.append(body.get("name", "(unnamed)"))
    warn_doubtful_inertias(source, doubtful, kind="body", stacklevel=3)
