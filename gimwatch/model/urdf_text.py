"""Checks on URDF text made before any parser builds a model from it.

Pinocchio's parser (urdfdom) and yourdfpy both trust their input; this module turns the
common ways a URDF can be broken into one-line [`URDFError`][gimwatch.errors.URDFError] messages
that name the file and the element. It imports no dynamics library, so DeNOC can use it too.
"""

from __future__ import annotations

import os
import re
import warnings
import xml.etree.ElementTree as ET

from gimwatch.errors import URDFError, URDFWarning
from gimwatch.model.urdf_namespaces import (
    check_prefixed_elements,
    fix_namespace,
    parse_as_urdfdom,
    parse_ignoring_prefixes,
)
from gimwatch.model.urdf_quirks import (
    fix_text_quirks,
    fix_tree_quirks,
    padded_number_attributes,
    warn_quirks,
)
from gimwatch.model.urdf_values import (
    check_inertial_values,
    check_joint_values,
    check_link_values,
    warn_doubtful_inertias,
)

__all__ = [
    "DEFAULT_MAX_LINKS",
    "MAX_ELEMENT_DEPTH",
    "MAX_TAG_CHARS",
    "check_urdf",
    "check_urdf_text",
    "max_links",
    "parse_urdf_xml",
    "without_comments",
]

#: Document-type declarations can define entities (external files, "billion laughs");
#: no URDF needs them, so they are refused before any parser sees the text.
_FORBIDDEN = ("<!DOCTYPE", "<!ENTITY")
#: The most <link> (and <joint>) elements read by default; ``$GIMWATCH_MAX_LINKS`` overrides
#: it. Counted in the text before any parser runs: a 20,000-link URDF would otherwise take
#: minutes and gigabytes of Pinocchio's and yourdfpy's time before any other limit applies.
DEFAULT_MAX_LINKS = 5000
MAX_LINKS_VARIABLE = "GIMWATCH_MAX_LINKS"
#: The longest tag (``<`` to ``>``, attributes included) read: expat slows down
#: quadratically, without answering Ctrl-C, on tags with 100,000 attributes.
MAX_TAG_CHARS = 65_536
_LONG_TAG = re.compile(f"<[^<>]{{{MAX_TAG_CHARS}}}")


#: The deepest element nesting read: URDF needs about 6 (robot/link/visual/geometry/mesh);
#: every recursive reader downstream (yourdfpy, ElementTree's writer) fails on 10^4.
MAX_ELEMENT_DEPTH = 64


def _element_depth(root: ET.Element) -> int:
    """The nesting depth of an element tree, without recursion."""
    deepest, stack = 0, [(root, 1)]
    while stack:
        element, depth = stack.pop()
        deepest = max(deepest, depth)
        if depth <= MAX_ELEMENT_DEPTH:  # deeper is refused anyway: stop counting there
            stack.extend((child, depth + 1) for child in element)
    return deepest


def max_links() -> int:
    """The link budget: ``$GIMWATCH_MAX_LINKS`` when set (a positive integer), else 5000."""
    text = os.environ.get(MAX_LINKS_VARIABLE, "").strip()
    if not text:
        return DEFAULT_MAX_LINKS
    if not text.isdigit() or int(text) < 1:
        raise URDFError(f"${MAX_LINKS_VARIABLE}", f"must be a positive integer, got {text!r}")
    return int(text)


def _check_budget(xml: str, source: str) -> None:
    """Refuse, before parsing, texts with more links or joints, or longer tags, than read."""
    limit = max_links()
    for tag in ("link", "joint"):
        count = sum(1 for _ in re.finditer(rf"<{tag}[\s/>]", xml))
        if count > limit:
            raise URDFError(
                source,
                f"has {count} <{tag}> elements, more than the {limit} gimwatch reads "
                f"(set ${MAX_LINKS_VARIABLE} to read more)",
            )
    if _LONG_TAG.search(xml):
        raise URDFError(
            source,
            f"has a tag longer than {MAX_TAG_CHARS} characters (too many or too long attributes)",
        )


def without_comments(xml: str) -> str:
    """The text with its comments removed, by one linear scan.

    (``re.sub(r"<!--.*?-->", ...)`` rescans the rest of the text from every unclosed
    ``<!--``: quadratic, minutes for a file of them.) An unclosed comment runs to the end.
    """
    pieces, position = [], 0
    while True:
        start = xml.find("<!--", position)
        if start < 0:
            pieces.append(xml[position:])
            return "".join(pieces)
        pieces.append(xml[position:start])
        end = xml.find("-->", start + 4)
        if end < 0:
            return "".join(pieces)
        position = end + 3


def parse_urdf_xml(xml: str, source: str) -> ET.Element:
    """Parse URDF text safely and return its ``<robot>`` element."""
    return _parse(xml, source)[0]


def _read_tree(xml: str, source: str) -> tuple[ET.Element, list[str]]:
    """The element tree as urdfdom reads it (`gimwatch.model.urdf_namespaces`)."""
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as exc:
        if "unbound prefix" not in str(exc):
            raise
        return parse_ignoring_prefixes(xml, source)
    if any(isinstance(e.tag, str) and e.tag.startswith("{") for e in root.iter()):
        root = parse_as_urdfdom(xml)  # namespaces in use: read the tags as written
        check_prefixed_elements(root, source)
    return root, []


def _parse(xml: str, source: str) -> tuple[ET.Element, list[str], list[str]]:
    """The ``<robot>`` element, the quirks fixed on the way, and padded number attributes.

    The attributes are those whose numbers are padded or split by line breaks or tabs in the
    text (see urdf_quirks). Comments are set aside first: a comment may mention
    ``<!DOCTYPE`` or be megabytes long without counting against the file.
    """
    if not xml.strip():
        raise URDFError(source, "the file is empty")
    xml, fixes = fix_text_quirks(xml)
    text = without_comments(xml)
    head = text.upper()
    for token in _FORBIDDEN:
        if token in head:
            raise URDFError(source, f"{token.lstrip('<!')} declarations are not allowed in a URDF")
    _check_budget(text, source)
    try:
        root, prefixed = _read_tree(xml, source)
        fixes += prefixed
    except ET.ParseError as exc:
        raise URDFError(source, f"malformed XML ({exc})") from exc
    depth = _element_depth(root)
    if depth > MAX_ELEMENT_DEPTH:
        raise URDFError(
            source,
            f"has elements nested {depth} deep, more than the {MAX_ELEMENT_DEPTH} read "
            "(a URDF needs about 6)",
        )
    fixes += fix_namespace(root)
    if root.tag != "robot":
        raise URDFError(source, f"the root element must be <robot>, got <{root.tag}>")
    return root, fixes, padded_number_attributes(text)


def check_urdf(xml: str, source: str, *, floating: bool = True) -> ET.Element:
    """Check the structure of URDF text and return its ``<robot>`` element.

    Then every value urdfdom reads is checked (see `gimwatch.model.urdf_values`).

    Raises:
        URDFError: The text is not well-formed XML, not a URDF, its links and joints do
            not form a tree, or a value is missing, malformed or physically impossible.

    Warns:
        URDFWarning: Once per file, naming the links whose principal moments of inertia
            violate the triangle inequality.
    """
    return check_urdf_text(xml, source, stacklevel=2, floating=floating)[0]


def check_urdf_text(
    xml: str, source: str, *, stacklevel: int = 1, floating: bool = True
) -> tuple[ET.Element, str]:
    """`check_urdf`, and the text for parsers.

    That is ``xml`` itself or, when real-world conventions were normalised
    (`gimwatch.model.urdf_quirks`, one warning), the normalised document, so that
    Pinocchio, DeNOC and MuJoCo read the same robot. With ``floating=False`` (the robot's
    root link is fixed to the world), an invalid inertial of a link welded to the root by
    fixed joints is removed with the warning instead of refused: it never enters M.
    """
    root, fixes, padded = _parse(xml, source)
    fixes += fix_tree_quirks(root, source, padded)
    links = _link_names(root, source)
    base, children = _tree(links, _parent_of(root, source, set(links)), source)
    welded = set() if floating else _welded_to_root(root, base, children)
    fixes += _drop_invalid_welded_inertials(root, welded, source)
    doubtful = [
        str(link.get("name"))  # every link is named by now (_link_names)
        for link in root.findall("link")
        if not check_link_values(link, source) and link.get("name") not in welded
    ]
    for joint in root.findall("joint"):
        check_joint_values(joint, source)
    _check_mimics(root, source)
    warn_quirks(source, fixes, stacklevel=stacklevel + 1)
    warn_doubtful_inertias(source, doubtful, kind="link", stacklevel=stacklevel + 1)
    return root, (ET.tostring(root, encoding="unicode") if fixes else xml)


def _link_names(root: ET.Element, source: str) -> list[str]:
    """The names of the links, in file order: at least one, each named, none twice."""
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
    return [name for name in links if name]


def _joint_ends(joint: ET.Element, where: str, seen: set[str], source: str) -> dict[str, str]:
    """The parent and child links of one joint, each declared."""
    ends = {}
    for end in ("parent", "child"):
        tag = joint.find(end)
        link = tag.get("link") if tag is not None else None
        if not link:
            raise URDFError(source, f"missing <{end} link=...>", element=where)
        if link not in seen:
            raise URDFError(source, f"{end} link {link!r} is not defined", element=where)
        ends[end] = link
    return ends


def _parent_of(root: ET.Element, source: str, seen: set[str]) -> dict[str, str]:
    """Each child link's parent link: joints named once, one parent joint per link."""
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
        ends = _joint_ends(joint, where, seen, source)
        if ends["child"] in parent_of:
            raise URDFError(source, f"link {ends['child']!r} has two parent joints", element=where)
        parent_of[ends["child"]] = ends["parent"]
    return parent_of


def _tree(
    links: list[str], parent_of: dict[str, str], source: str
) -> tuple[str, dict[str, list[str]]]:
    """The root link and each link's children: one root, every link reached from it."""
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
        stray = sorted(set(links) - reached)[:4]
        raise URDFError(
            source, f"the links form a cycle not attached to the root: {', '.join(stray)}"
        )
    return roots[0], children


def _check_mimics(root: ET.Element, source: str) -> None:
    """A mimic joint follows another moving joint, not itself, and not in a cycle.

    A mimic naming a joint the file does not have is a [`URDFWarning`][gimwatch.errors.URDFWarning]
    (real robots ship such files when a hand is cut from its arm); Pinocchio then moves the joint
    freely.
    """
    kinds = {joint.get("name"): joint.get("type") for joint in root.findall("joint")}
    follows: dict[str | None, str | None] = {}
    ghosts = []
    for joint in root.findall("joint"):
        mimic = joint.find("mimic")
        if mimic is None:
            continue
        name, target = joint.get("name"), mimic.get("joint")
        where = f"joint {name!r}"
        if target == name:
            raise URDFError(source, "<mimic> names the joint itself", element=where)
        if target not in kinds:
            ghosts.append(f"{name} -> {target}")
            continue
        if kinds[target] != "fixed":  # a mimic of a fixed joint is a quirk (urdf_quirks)
            follows[name] = target
    for start in follows:
        path, followed = [start], follows[start]
        while followed in follows and followed not in path:
            path.append(followed)
            followed = follows[followed]
        if followed == start:
            cycle = " -> ".join(str(name) for name in [*path, start])
            raise URDFError(
                source, f"<mimic> joints form a cycle ({cycle})", element=f"joint {start!r}"
            )
    if ghosts:
        shown = ", ".join(ghosts[:4]) + (", ..." if len(ghosts) > 4 else "")
        warnings.warn(
            URDFWarning(
                f"{source}: {len(ghosts)} <mimic> joint(s) name a joint the file does not have "
                f"({shown}); they are modelled as independent joints"
            ),
            stacklevel=3,
        )


def _welded_to_root(root: ET.Element, top: str, children: dict[str, list[str]]) -> set[str]:
    """The root link and the links joined to it by fixed joints only (fixed base)."""
    fixed = {
        child.get("link")
        for joint in root.findall("joint")
        if joint.get("type") == "fixed" and (child := joint.find("child")) is not None
    }
    found, stack = set(), [top]
    while stack:
        link = stack.pop()
        found.add(link)
        stack.extend(child for child in children.get(link, ()) if child in fixed)
    return found


def _drop_invalid_welded_inertials(root: ET.Element, welded: set[str], source: str) -> list[str]:
    """Remove the invalid ``<inertial>`` of links welded to a fixed root (never in M)."""
    dropped = []
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None or link.get("name") not in welded:
            continue
        try:
            check_inertial_values(inertial, source, where=f"link {link.get('name')!r}")
        except URDFError as exc:
            link.remove(inertial)
            dropped.append(f"{link.get('name')}: {exc.problem}")
    if not dropped:
        return []
    shown = "; ".join(dropped[:2]) + ("; ..." if len(dropped) > 2 else "")
    return [
        f"{len(dropped)} invalid <inertial> on link(s) welded to the fixed root removed, as "
        f"it never enters M ({shown})"
    ]


def _reachable(root: str, children: dict[str, list[str]]) -> set[str]:
    found, stack = set(), [root]
    while stack:
        link = stack.pop()
        found.add(link)
        stack.extend(children.get(link, ()))
    return found
