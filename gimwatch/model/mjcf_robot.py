"""Read an MJCF file into gimwatch: budgets first, MuJoCo's compiler, then the Pinocchio model.

1. A linear scan of the file and of the files it includes (no parser) refuses, before MuJoCo
   runs, more bytes, ``<body>`` elements or body nesting than gimwatch reads (the URDF
   budgets: `MAX_MJCF_BYTES`, ``$GIMWATCH_MAX_LINKS`` bodies)
   and bodies nested deeper than `MAX_BODY_DEPTH` (MuJoCo's XML reader stops at about
   500 nested elements).
2. MuJoCo compiles the file in a child process bounded in time and memory
   (`gimwatch.model.mjcf_sandbox`); a refusal is one line with MuJoCo's message (element,
   line). The compiled body count is held to the same budget as the text's.
3. `build_pinocchio_model` builds the robot; a moving
   subtree without mass is refused; what changes MuJoCo's dynamics but not M (equality
   constraints, tendon armature) is named in one `URDFWarning`.
4. DeNOC's input: URDF text of the same tree when DeNOC can read it (hinges and slides,
   one tree, at most a free joint at its root), else "".
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pinocchio as pin

from gimwatch.errors import URDFError, URDFWarning
from gimwatch.model.denoc_input import urdf_of_model
from gimwatch.model.mjcf_compiled import build_pinocchio_model, compile_mjcf, subtree_joints
from gimwatch.model.urdf_text import max_links

__all__ = ["MAX_BODY_DEPTH", "MAX_MJCF_BYTES", "check_mjcf_budget", "read_mjcf"]

#: The largest MJCF text read, included files counted (as a URDF file: 64 MiB).
MAX_MJCF_BYTES = 64 * 1024 * 1024
#: The deepest nesting of ``<body>`` read (tinyxml2, MuJoCo's XML reader, refuses about 500
#: nested elements with a less clear message).
MAX_BODY_DEPTH = 400


def _attribute(tag: str, key: str) -> str | None:
    for quote in ('"', "'"):
        start = tag.find(f"{key}={quote}")
        if start >= 0 and (start == 0 or tag[start - 1] in " \t\r\n"):
            start += len(key) + 2
            end = tag.find(quote, start)
            return tag[start:end] if end >= 0 else None
    return None


def check_mjcf_budget(path: str) -> None:
    """Refuse, by a linear scan before MuJoCo runs, MJCF beyond gimwatch's budgets.

    Counts bytes, ``<body>`` elements and body nesting over the file and the files its
    ``<include file=...>`` elements name (relative to the main file's folder, as in MuJoCo).

    Raises:
        URDFError: Too many bytes, bodies or levels, naming the file and the limit, or an
            include that is not a regular file (a FIFO, a device), refused before it is opened.
    """
    limit, bodies, total = max_links(), 0, 0
    pending, seen = [Path(path)], set()
    while pending:
        current = pending.pop()
        if current in seen or not current.exists():
            continue  # MuJoCo names a missing or repeated include itself
        if not current.is_file():  # stat only: opening a FIFO would wait for a writer
            raise URDFError(
                path, f"includes {current.name!r}, which is not a regular file (a FIFO or device?)"
            )
        seen.add(current)
        total += current.stat().st_size
        if total > MAX_MJCF_BYTES:
            raise URDFError(path, f"is more than {MAX_MJCF_BYTES} bytes with its includes")
        text = current.read_text(encoding="utf-8", errors="replace")
        bodies = _count_bodies(path, text, bodies, limit, pending.append)


def _tags(text: str) -> Iterator[str]:
    """The text inside each ``<...>`` of ``text``, comments skipped; stops at an unclosed one."""
    position = text.find("<")
    while position >= 0:
        if text.startswith("<!--", position):
            end = text.find("-->", position + 4)
            position = -1 if end < 0 else text.find("<", end + 3)
            continue
        end = text.find(">", position)
        if end < 0:
            return
        yield text[position + 1 : end]
        position = text.find("<", end + 1)


def _count_bodies(
    path: str, text: str, bodies: int, limit: int, include: Callable[[Path], None]
) -> int:
    """``bodies`` plus the ``<body>`` elements of one file, its depth checked; includes queued.

    Raises:
        URDFError: More than ``limit`` bodies or MAX_BODY_DEPTH levels, naming ``path``.
    """
    folder, depth = Path(path).parent, 0
    for tag in _tags(text):
        name = tag.split(None, 1)[0] if tag.strip() else ""
        if name == "body":
            bodies += 1
            if bodies > limit:
                raise URDFError(
                    path,
                    f"has more than {limit} <body> elements, more than gimwatch reads "
                    "(set $GIMWATCH_MAX_LINKS to read more)",
                )
            if not tag.endswith("/"):
                depth += 1
                if depth > MAX_BODY_DEPTH:
                    raise URDFError(path, f"nests <body> more than {MAX_BODY_DEPTH} levels deep")
        elif name == "/body":
            depth -= 1
        elif name == "include":
            included = _attribute(tag, "file")
            if included:
                include(folder / included)
    return bodies


def _ignored_dynamics(mj_model) -> str:
    parts = []
    if mj_model.neq:
        parts.append(f"{mj_model.neq} equality constraint(s)")
    if mj_model.ntendon and np.any(np.asarray(mj_model.tendon_armature) != 0):
        parts.append("tendon armature")
    return ", ".join(parts)


def _name(mj_model, kind: str, index: int) -> str:
    import mujoco

    obj = mujoco.mjtObj.mjOBJ_BODY if kind == "body" else mujoco.mjtObj.mjOBJ_JOINT
    return mujoco.mj_id2name(mj_model, obj, index) or f"{kind}{index}"


#: Beyond this size (m, kg, kg m²) a product in M(q) (m·r², sums over bodies) may overflow.
MAX_MAGNITUDE = 1e100


def _check_values(mj_model, joints: list[int], source: str) -> None:
    """Refuse compiled values that would make M(q) inf or NaN, naming the body or joint."""
    for j in joints:
        axis = np.asarray(mj_model.jnt_axis[j], dtype=float)
        if mj_model.jnt_type[j] >= 2 and not abs(float(np.linalg.norm(axis)) - 1.0) < 1e-9:
            raise URDFError(
                source,
                "<joint axis> cannot be normalised (a component overflows or underflows)",
                element=f"joint {_name(mj_model, 'joint', j)!r}",
            )
    fields = ("body_pos", "body_ipos", "body_mass", "body_inertia")
    for b in range(1, mj_model.nbody):
        for key in fields:
            values = np.asarray(getattr(mj_model, key)[b], dtype=float)
            if not np.all(np.abs(values) < MAX_MAGNITUDE):
                what = key.removeprefix("body_")
                raise URDFError(
                    source,
                    f"its compiled {what} {values.tolist()} is not finite or beyond "
                    f"{MAX_MAGNITUDE:g} (M(q) would overflow)",
                    element=f"body {_name(mj_model, 'body', b)!r}",
                )


def _check_masses(mj_model, joints: list[int], source: str) -> None:
    for j in joints:
        b = int(mj_model.jnt_bodyid[j])
        if not float(mj_model.body_subtreemass[b]) > 0:
            name = _name(mj_model, "body", b)
            raise URDFError(
                source,
                "moves no mass (it and its children have zero mass); give it a <geom> or an "
                "<inertial>",
                element=f"body {name!r}",
            )


def read_mjcf(path: str, *, floating: bool = False, body: str = "", armature: bool = True):
    """Compile the MJCF file and build gimwatch's model of it (see the module docstring).

    Returns:
        ``(model, mujoco_joint_ids, urdf_xml)``.

    Raises:
        URDFError: Over a budget, refused by MuJoCo, or a moving body without mass.
    """
    check_mjcf_budget(path)
    mj_model = compile_mjcf(path, floating=floating)
    if mj_model.nbody - 1 > max_links():  # <replicate> and <flexcomp> expand past the text
        raise URDFError(
            path,
            f"compiles to {mj_model.nbody - 1} bodies, more than gimwatch reads ({max_links()}; "
            "set $GIMWATCH_MAX_LINKS to read more)",
        )
    joints = subtree_joints(mj_model, body, path)
    _check_values(mj_model, joints, path)
    _check_masses(mj_model, joints, path)
    model, joint_ids = build_pinocchio_model(mj_model, body=body, armature=armature, source=path)
    _set_limits(model, mj_model, joint_ids)
    ignored = _ignored_dynamics(mj_model)
    if ignored:
        warnings.warn(
            f"{path}: {ignored} change MuJoCo's dynamics but not M(q); gimwatch leaves them out",
            URDFWarning,
            stacklevel=4,  # the caller of load_robot
        )
    return model, joint_ids, urdf_of_model(model)


def _set_limits(model: pin.Model, mj_model, joint_ids) -> None:
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    for joint, j in zip(model.joints[1:], joint_ids, strict=True):
        if mj_model.jnt_limited[j] and joint.nq == 1:
            lower[joint.idx_q], upper[joint.idx_q] = mj_model.jnt_range[j]
    model.lowerPositionLimit, model.upperPositionLimit = lower, upper
