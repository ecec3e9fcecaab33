"""Checks on the values of a URDF: numbers, masses, inertias, axes, limits and joint types.

urdfdom (Pinocchio's parser) prints its complaints to stderr and, for several of them, still
builds a model from what it could read: a mass of ``nan`` or ``abc`` silently becomes a
massless body, a zero joint axis a joint that moves nothing, a negative mass a GIM of
-1e62. This module reads every value urdfdom would read and raises a one-line
[`URDFError`][gimwatch.errors.URDFError] naming the file, the link or joint, and the value.

What real robots do is the yardstick (measured on the 71 URDFs of example-robot-data):

* inertias with slightly negative principal moments (down to -3.5e-8 kg m^2 on TIAGo's
  antennas, from CAD round-off) load; only moments below ``-(INERTIA_ATOL_KG_M2 +
  INERTIA_RTOL * largest moment)`` are errors;
* principal moments that violate the triangle inequality (a + b >= c, required of any
  mass distribution) appear in 16 robots (ANYmal, Go1, Allegro, ...): Pinocchio computes a
  positive definite GIM from them, so they are a [`URDFWarning`][gimwatch.errors.URDFWarning];
* zero masses and zero inertias are common (frames, sensors) and left alone; a moving
  joint that carries no mass at all is reported when the GIM is computed (it is singular).

It imports only NumPy, so DeNOC can use it too.
"""

from __future__ import annotations

import math
import re
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from gimwatch.errors import URDFError, URDFWarning

__all__ = [
    "INERTIA_ATOL_KG_M2",
    "INERTIA_RTOL",
    "MAX_MAGNITUDE",
    "SUPPORTED_JOINT_TYPES",
    "check_inertial_values",
    "check_joint_values",
    "check_link_values",
    "check_principal_moments",
    "warn_doubtful_inertias",
]

#: Joint types gimwatch models (Pinocchio and DeNOC alike).
SUPPORTED_JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
_UNSUPPORTED_JOINT_TYPES = {
    "planar": "use two prismatic joints and a revolute one",
    "floating": "remove it and add a free base with --floating",
}
_LIMITED = ("revolute", "prismatic")
#: Negative principal moments of inertia smaller than this (plus the relative part) are
#: taken as round-off; TIAGo's antennas reach -3.5e-8 kg m^2.
INERTIA_ATOL_KG_M2 = 1e-6
INERTIA_RTOL = 1e-6
#: The largest magnitude of a length, angle, mass, inertia or damping in a URDF. A GIM entry
#: is about mass x length^2, so values beyond it overflow to inf or NaN in the dynamics;
#: no real robot comes near (joint limits, often 1e16 placeholders for "none", are exempt).
MAX_MAGNITUDE = 1e15
#: A joint axis is normalised by its length; components of magnitude outside this range
#: make that length overflow (1e200) or underflow (1e-300) in double precision.
AXIS_RANGE = (1e-100, 1e100)
#: A number as urdfdom reads one; unambiguous (``\d+(?:\.\d*)?``, not ``\d+\.?\d*``) so that a
#: failing match backtracks in linear, not quadratic, time on a 65,536-digit attribute.
_NUMBER = re.compile(
    r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:nan|inf|infinity)", re.I
)
_GEOMETRY = {"box": ("size",), "cylinder": ("radius", "length"), "sphere": ("radius",)}


def _floats(
    text: str | None,
    count: int,
    *,
    what: str,
    source: str,
    where: str,
    bound: float = MAX_MAGNITUDE,
) -> list[float]:
    """Parse ``count`` finite numbers of magnitude <= ``bound``, as urdfdom reads a value."""
    parts = (text or "").split()
    if len(parts) != count or not all(_NUMBER.fullmatch(p) for p in parts):
        rule = "a number" if count == 1 else f"{count} numbers separated by spaces"
        hint = (
            " (an unexpanded xacro or roslaunch expression: run xacro on the file first)"
            if "$(" in (text or "") or "${" in (text or "")
            else " (a decimal comma? write numbers with a decimal point, separated by spaces)"
            if re.search(r"\d,\d", text or "")
            else ""
        )
        raise URDFError(source, f"{what} must be {rule}, got {text!r}{hint}", element=where)
    values = [float(p) for p in parts]
    if not all(math.isfinite(v) for v in values):
        raise URDFError(source, f"{what} must be finite, got {text!r}", element=where)
    if any(abs(v) > bound for v in values):
        raise URDFError(source, f"{what} must be within ±{bound:g}, got {text!r}", element=where)
    return values


def _number(
    element: ET.Element,
    attribute: str,
    *,
    source: str,
    where: str,
    default: float | None = None,
    bound: float = MAX_MAGNITUDE,
) -> float:
    text = element.get(attribute)
    what = f"<{element.tag} {attribute}>"
    if text is None:
        if default is None:
            raise URDFError(source, f"{what} is missing", element=where)
        return default
    return _floats(text, 1, what=what, source=source, where=where, bound=bound)[0]


def _check_origin(parent: ET.Element, *, source: str, where: str) -> None:
    origin = parent.find("origin")
    if origin is None:
        return
    for attribute in ("xyz", "rpy"):
        if origin.get(attribute) is not None:
            _floats(
                origin.get(attribute),
                3,
                what=f"<{parent.tag}><origin {attribute}>",
                source=source,
                where=where,
            )


def _check_shapes(link: ET.Element, *, source: str, where: str) -> None:
    """Visual and collision shapes: urdfdom refuses the whole model when one is malformed."""
    for tag in ("visual", "collision"):
        for shape in link.findall(tag):
            _check_origin(shape, source=source, where=where)
            geometry = shape.find("geometry")
            kinds = list(geometry) if geometry is not None else []
            if len(kinds) != 1 or kinds[0].tag not in (*_GEOMETRY, "mesh"):
                raise URDFError(
                    source,
                    f"<{tag}><geometry> must hold one of <box>, <cylinder>, <sphere>, <mesh>",
                    element=where,
                )
            kind = kinds[0]
            if kind.tag == "mesh":
                if not kind.get("filename"):
                    raise URDFError(source, "<mesh> has no filename", element=where)
                if kind.get("scale") is not None:
                    _floats(kind.get("scale"), 3, what="<mesh scale>", source=source, where=where)
                continue
            for attribute in _GEOMETRY[kind.tag]:
                count = 3 if attribute == "size" else 1
                what = f"<{kind.tag} {attribute}>"
                _floats(kind.get(attribute), count, what=what, source=source, where=where)
            material = shape.find("material")
            color = material.find("color") if material is not None else None
            if color is not None:
                _floats(color.get("rgba"), 4, what="<color rgba>", source=source, where=where)


def check_link_values(link: ET.Element, source: str) -> bool:
    """Check a ``<link>``'s inertial values and shapes.

    The inertia tensor ``I`` about the centre of mass must be symmetric positive
    semi-definite, and its principal moments ``a <= b <= c`` should satisfy the triangle
    inequality ``a + b >= c`` (``c = ∫(x² + y²) dm <= ∫(x² + z²) dm + ∫(y² + z²) dm``).

    Returns:
        False when the principal moments violate the triangle inequality (a doubtful but
        usable inertia, see the module docstring), True otherwise.

    Raises:
        URDFError: A missing or non-finite value, a negative mass, or an inertia with a
            clearly negative principal moment.
    """
    where = f"link {link.get('name')!r}"
    _check_shapes(link, source=source, where=where)
    inertial = link.find("inertial")
    if inertial is None:
        return True
    return check_inertial_values(inertial, source, where=where)


def check_inertial_values(inertial: ET.Element, source: str, *, where: str) -> bool:
    """Check an ``<inertial>``: origin, mass >= 0, a positive semi-definite inertia.

    Returns and raises as `check_link_values`.
    """
    _check_origin(inertial, source=source, where=where)
    mass_tag = inertial.find("mass")
    if mass_tag is None:
        raise URDFError(source, "<inertial> has no <mass value=...>", element=where)
    mass = _number(mass_tag, "value", source=source, where=where)
    if mass < 0:
        raise URDFError(source, f"mass must be >= 0 kg, got {mass!r}", element=where)
    tag = inertial.find("inertia")
    if tag is None:
        raise URDFError(source, "<inertial> has no <inertia ixx=... izz=...>", element=where)
    xx, xy, xz, yy, yz, zz = (
        _number(tag, key, source=source, where=where)
        for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    )
    moments = np.linalg.eigvalsh(np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
    return check_principal_moments(moments, source=source, where=where)


def check_principal_moments(moments: np.ndarray, *, source: str, where: str) -> bool:
    """Principal moments ``a <= b <= c`` (kg m²) of a body's inertia about its centre of mass.

    Returns:
        False when they violate the triangle inequality ``a + b >= c`` (doubtful, usable).

    Raises:
        URDFError: A clearly negative moment (the inertia is not positive semi-definite).
    """
    if moments[0] < -(INERTIA_ATOL_KG_M2 + INERTIA_RTOL * abs(moments[-1])):
        shown = ", ".join(f"{m:.4g}" for m in moments)
        raise URDFError(
            source,
            f"inertia is not positive semi-definite: principal moments {shown} kg m^2",
            element=where,
        )
    a, b, c = moments
    return bool(a + b >= c * (1 - INERTIA_RTOL) - 1e-12)


def warn_doubtful_inertias(source: str, names: list[str], *, kind: str, stacklevel: int) -> None:
    """Issue one [`URDFWarning`][gimwatch.errors.URDFWarning] naming the doubtful bodies.

    ``names`` are the links or bodies (``kind``) whose principal moments of inertia violate
    the triangle inequality; nothing is issued when there are none.
    """
    if not names:
        return
    shown = ", ".join(names[:4]) + (", ..." if len(names) > 4 else "")
    warnings.warn(
        URDFWarning(
            f"{source}: {len(names)} {kind}(s) have principal moments of inertia that "
            f"violate the triangle inequality a + b >= c ({shown}); no rigid body has "
            "such an inertia, so the GIM computed from it is suspect"
        ),
        stacklevel=stacklevel + 1,
    )


def check_joint_values(joint: ET.Element, source: str) -> None:
    """Check a ``<joint>``'s type, origin, axis, limits, dynamics and mimic values.

    Raises:
        URDFError: An unknown or unsupported type, a non-finite value, a zero axis on a
            moving joint, a missing ``<limit>`` on a revolute or prismatic joint, or limits
            with ``lower > upper`` or a negative effort or velocity.
    """
    where = f"joint {joint.get('name')!r}"
    kind = joint.get("type")
    if kind in _UNSUPPORTED_JOINT_TYPES:
        raise URDFError(
            source,
            f"joint type {kind!r} is not supported by gimwatch ({_UNSUPPORTED_JOINT_TYPES[kind]})",
            element=where,
        )
    if kind not in SUPPORTED_JOINT_TYPES:
        raise URDFError(
            source,
            f"type must be one of {', '.join(SUPPORTED_JOINT_TYPES)}, got {kind!r}",
            element=where,
        )
    _check_origin(joint, source=source, where=where)
    axis = joint.find("axis")
    if kind != "fixed" and axis is not None:
        _check_axis(axis.get("xyz", "1 0 0"), source=source, where=where)
    _check_limit(joint, kind, source=source, where=where)
    dynamics = joint.find("dynamics")
    if dynamics is not None:
        if dynamics.get("damping") is None and dynamics.get("friction") is None:
            raise URDFError(source, "<dynamics> has neither damping nor friction", element=where)
        for key in ("damping", "friction"):
            _number(dynamics, key, source=source, where=where, default=0.0)
    mimic = joint.find("mimic")
    if mimic is not None:
        if not mimic.get("joint"):
            raise URDFError(source, "<mimic> has no joint attribute", element=where)
        for key in ("multiplier", "offset"):
            _number(mimic, key, source=source, where=where, default=0.0)


def _check_axis(text: str, *, source: str, where: str) -> None:
    """A non-zero axis whose length can be computed: its largest component within AXIS_RANGE.

    The length is computed after scaling by the largest component, so it cannot over- or
    underflow here; the range keeps it from doing so in urdfdom and Pinocchio, which do not
    scale.
    """
    vector = _floats(text, 3, what="<axis xyz>", source=source, where=where, bound=math.inf)
    largest = max(abs(x) for x in vector)
    if largest == 0:
        problem = f"<axis xyz> must be a non-zero vector, got {text!r}"
        raise URDFError(source, problem, element=where)
    length = largest * math.sqrt(sum((x / largest) ** 2 for x in vector))
    low, high = AXIS_RANGE
    if not low <= largest <= high:
        raise URDFError(
            source,
            f"<axis xyz> must have its largest component within {low:g} .. {high:g} "
            f"(a length of {length:.3g} over- or underflows when normalised; write a unit "
            f"vector), got {text!r}",
            element=where,
        )


def _check_limit(joint: ET.Element, kind: str, *, source: str, where: str) -> None:
    limit = joint.find("limit")
    if limit is None:
        if kind in _LIMITED:
            raise URDFError(
                source,
                f"a {kind} joint needs <limit lower=... upper=... effort=... velocity=...>",
                element=where,
            )
        return
    for key in ("effort", "velocity"):
        value = _number(limit, key, source=source, where=where, bound=math.inf)
        if value < 0:
            raise URDFError(source, f"<limit {key}> must be >= 0, got {value!r}", element=where)
    lower = _number(limit, "lower", source=source, where=where, default=0.0, bound=math.inf)
    upper = _number(limit, "upper", source=source, where=where, default=0.0, bound=math.inf)
    if kind in _LIMITED and lower > upper:
        raise URDFError(
            source,
            f"<limit> lower = {lower!r} must be <= upper = {upper!r}",
            element=where,
        )
