"""`gimwatch.joint_kinds` against Pinocchio's own joint models, one joint type at a time.

Each joint type Pinocchio builds is put alone on a one-body model; what `joint_kind` and its
helpers say is checked against what Pinocchio computes for that model: the joint's motion
subspace (which velocity coordinates translate, which rotate, along which axis), its
configurations (which q coordinates move the body without turning it, which block has unit
norm), nq and nv.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.joint_kinds import (
    JointKind,
    joint_axis,
    joint_kind,
    joint_type_name,
    length_positions,
    length_velocities,
)

_AXIS = np.array([0.36, 0.48, 0.8])  # a unit axis off the coordinate axes


def _composite() -> pin.JointModelComposite:
    composite = pin.JointModelComposite()
    composite.addJoint(pin.JointModelRX())
    composite.addJoint(pin.JointModelPY())
    return composite


#: (Pinocchio joint model, expected kind, nq, nv)
JOINTS = [
    (pin.JointModelRX(), JointKind.REVOLUTE, 1, 1),
    (pin.JointModelRY(), JointKind.REVOLUTE, 1, 1),
    (pin.JointModelRZ(), JointKind.REVOLUTE, 1, 1),
    (pin.JointModelRevoluteUnaligned(_AXIS), JointKind.REVOLUTE, 1, 1),
    (pin.JointModelRUBX(), JointKind.CONTINUOUS, 2, 1),
    (pin.JointModelRUBY(), JointKind.CONTINUOUS, 2, 1),
    (pin.JointModelRUBZ(), JointKind.CONTINUOUS, 2, 1),
    (pin.JointModelRevoluteUnboundedUnaligned(), JointKind.CONTINUOUS, 2, 1),
    (pin.JointModelPX(), JointKind.PRISMATIC, 1, 1),
    (pin.JointModelPY(), JointKind.PRISMATIC, 1, 1),
    (pin.JointModelPZ(), JointKind.PRISMATIC, 1, 1),
    (pin.JointModelPrismaticUnaligned(_AXIS), JointKind.PRISMATIC, 1, 1),
    (pin.JointModelHX(0.1), JointKind.HELICAL, 1, 1),
    (pin.JointModelHY(0.1), JointKind.HELICAL, 1, 1),
    (pin.JointModelHZ(0.1), JointKind.HELICAL, 1, 1),
    (pin.JointModelHelicalUnaligned(_AXIS, 0.1), JointKind.HELICAL, 1, 1),
    (pin.JointModelSpherical(), JointKind.SPHERICAL, 4, 3),
    (pin.JointModelSphericalZYX(), JointKind.SPHERICAL_ZYX, 3, 3),
    (pin.JointModelFreeFlyer(), JointKind.FREE_FLYER, 7, 6),
    (pin.JointModelPlanar(), JointKind.PLANAR, 4, 3),
    (pin.JointModelTranslation(), JointKind.TRANSLATION, 3, 3),
    (
        pin.JointModelUniversal(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])),
        JointKind.UNIVERSAL,
        2,
        2,
    ),
    (pin.JointModelEllipsoid(0.1, 0.2, 0.3), JointKind.ELLIPSOID, 3, 3),
    (_composite(), JointKind.COMPOSITE, 2, 2),
]
IDS = [f"{joint_type_name(joint)}-{i}" for i, (joint, *_) in enumerate(JOINTS)]
#: The joints with blocks of their own (a composite's coordinates are its parts'; gimwatch
#: reads no composite joint, so its kind is all it is asked)
SIMPLE = [row for row in JOINTS if row[1] is not JointKind.COMPOSITE]
SIMPLE_IDS = [i for i, row in zip(IDS, JOINTS, strict=True) if row in SIMPLE]


def _one_joint_model(joint) -> pin.Model:
    model = pin.Model()
    model.addJoint(0, joint, pin.SE3.Identity(), "j")
    model.appendBodyToJoint(1, pin.Inertia.Random(), pin.SE3.Identity())
    return model


def _configuration(model: pin.Model, seed: int = 0) -> np.ndarray:
    """A valid configuration away from neutral (integrate a random velocity)."""
    v = np.random.default_rng(seed).uniform(-0.7, 0.7, model.nv)
    return pin.integrate(model, pin.neutral(model), v)


def _subspace(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """The joint's motion subspace S (6 × nv, linear rows first), in the joint frame."""
    data = model.createData()
    return np.asarray(pin.computeJointJacobian(model, data, q, 1)).reshape(6, model.nv)


def test_every_joint_type_pinocchio_exports_is_in_the_table():
    exported = {n.removeprefix("JointModel") for n in dir(pin) if n.startswith("JointModel")}
    exported -= {"", "Mimic"}  # the generic wrapper; a mimic needs a second joint to follow
    exported = {n for n in exported if not n.startswith(("Vector", "List"))}
    tested = {joint_type_name(joint) for joint, *_ in JOINTS}
    assert exported <= tested, f"joint types without a test: {sorted(exported - tested)}"


@pytest.mark.parametrize(("joint", "kind", "nq", "nv"), JOINTS, ids=IDS)
def test_kind_and_sizes(joint, kind, nq, nv):
    assert joint_kind(joint) is kind
    assert joint_kind(pin.JointModel(joint)) is kind  # the generic wrapper a model holds
    model = _one_joint_model(joint)
    assert joint_kind(model.joints[1]) is kind
    assert (model.joints[1].nq, model.joints[1].nv) == (nq, nv)


@pytest.mark.parametrize(("joint", "kind", "nq", "nv"), SIMPLE, ids=SIMPLE_IDS)
def test_unit_block_has_unit_norm_and_the_rest_is_free(joint, kind, nq, nv):
    model = _one_joint_model(joint)
    unit = kind.unit_block
    assert nq - nv == (1 if unit else 0)  # a quaternion or (cos, sin): one extra number
    for seed in range(3):
        q = _configuration(model, seed)
        if unit:
            assert np.linalg.norm(q[nq - unit :]) == pytest.approx(1.0, abs=1e-12)
        else:
            assert nq == nv  # no unit block: q is a vector space


@pytest.mark.parametrize(("joint", "kind", "nq", "nv"), SIMPLE, ids=SIMPLE_IDS)
def test_length_velocities_are_the_columns_that_do_not_rotate(joint, kind, nq, nv):
    model = _one_joint_model(joint)
    S = _subspace(model, _configuration(model))
    translating = np.linalg.norm(S[3:], axis=0) < 1e-12
    lengths = length_velocities(model.joints[1])
    assert translating.tolist() == [True] * lengths + [False] * (nv - lengths)


@pytest.mark.parametrize(("joint", "kind", "nq", "nv"), SIMPLE, ids=SIMPLE_IDS)
def test_length_positions_move_the_body_without_turning_it(joint, kind, nq, nv):
    model = _one_joint_model(joint)
    data = model.createData()
    q = _configuration(model)
    pin.forwardKinematics(model, data, q)
    before = data.oMi[1].copy()
    lengths = length_positions(model.joints[1])
    free = nq - kind.unit_block  # coordinates that may be perturbed alone
    for i in range(free):
        dq = np.zeros(nq)
        dq[i] = 0.05
        pin.forwardKinematics(model, data, q + dq)
        turned = not np.allclose(data.oMi[1].rotation, before.rotation, atol=1e-12)
        assert turned == (i >= lengths), f"q[{i}]"
        if i < lengths:  # a length: the body moves by exactly the perturbation, in metres
            moved = np.linalg.norm(data.oMi[1].translation - before.translation)
            assert moved == pytest.approx(0.05, rel=1e-12)


@pytest.mark.parametrize(("joint", "kind", "nq", "nv"), JOINTS, ids=IDS)
def test_axis_of_one_axis_joints(joint, kind, nq, nv):
    model = _one_joint_model(joint)
    if not kind.one_axis:
        with pytest.raises(ValueError, match="no single axis"):
            joint_axis(model.joints[1])
        return
    S = _subspace(model, pin.neutral(model))[:, 0]
    turning = kind is not JointKind.PRISMATIC
    expected = S[3:] if turning else S[:3]
    assert joint_axis(model.joints[1]) == pytest.approx(expected, abs=1e-12)
    assert joint_axis(joint) == pytest.approx(expected, abs=1e-12)  # the typed model too


def test_only_joint_kinds_reads_pinocchio_joint_class_names():
    """One answer to "what kind of joint?": no other module calls ``shortname()``."""
    root = Path(__file__).resolve().parents[1] / "gimwatch"
    callers = [
        f"{path.relative_to(root.parent)}:{node.lineno}"
        for path in sorted(root.rglob("*.py"))
        if path.name != "joint_kinds.py"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.Attribute) and node.attr == "shortname"
    ]
    assert not callers, "ask gimwatch.joint_kinds instead:\n  " + "\n  ".join(callers)
