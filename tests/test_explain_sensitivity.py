"""κ sensitivities against central finite differences, mpmath references and exact identities."""

from __future__ import annotations

import dataclasses

import mpmath
import numpy as np
import pinocchio as pin
import pytest

from gimwatch.denoc import read_body_tree
from gimwatch.explain.bodies import body_names
from gimwatch.explain.sensitivity import (
    kappa_sensitivities,
    parameter_table,
    spatial_inertia_derivatives,
)
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import Robot, chain_robot, load_robot
from gimwatch.stress.reference_planar import PlanarChainReference
from gimwatch.stress.reference_tree import TreeReference

ROBOTS = ("ur5", "panda", "talos_arm")
INERTIA = {"Ixx": (0, 0), "Ixy": (0, 1), "Ixz": (0, 2), "Iyy": (1, 1), "Iyz": (1, 2), "Izz": (2, 2)}


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request) -> Robot:
    with pytest.warns() if request.param == "talos_arm" else _nothing():
        return load_robot(request.param)


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def _q(robot: Robot, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lower = np.maximum(robot.model.lowerPositionLimit, -2.0)
    upper = np.minimum(robot.model.upperPositionLimit, 2.0)
    return rng.uniform(lower, upper)


def _perturbed(model: pin.Model, names: tuple, owner: str, parameter: str, value: float):
    """A copy of ``model`` with one parameter set to ``value`` (independent of the module)."""
    model = pin.Model(model)
    if parameter.startswith("armature"):
        joint = model.getJointId(owner)
        k = int(parameter[9:-1]) if "[" in parameter else 0
        armature = np.array(model.armature)
        armature[model.joints[joint].idx_v + k] = value
        model.armature = armature
    elif parameter.startswith("offset_"):
        joint = model.getJointId(owner)
        placement = model.jointPlacements[joint].copy()
        t = placement.translation.copy()
        t["xyz".index(parameter[-1])] = value
        placement.translation = t
        model.jointPlacements[joint] = placement
    else:
        joint = names.index(owner) + 1
        inertia = model.inertias[joint]
        m, c, Ic = inertia.mass, inertia.lever.copy(), inertia.inertia.copy()
        if parameter == "mass":
            m = value
        elif parameter.startswith("com_"):
            c["xyz".index(parameter[-1])] = value
        else:
            a, b = INERTIA[parameter]
            Ic[a, b] = Ic[b, a] = value
        model.inertias[joint] = pin.Inertia(m, c, Ic)
    return model


def _kappa(model: pin.Model, q: np.ndarray) -> float:
    w = np.linalg.eigvalsh(pin.crba(model, model.createData(), q))
    return w[-1] / w[0]


def test_spatial_inertia_derivatives_match_pinocchio():
    rng = np.random.default_rng(3)
    m, c = 1.7, rng.normal(size=3)
    A = rng.normal(size=(3, 3))
    Ic = A @ A.T + np.eye(3)
    names, dI = spatial_inertia_derivatives(pin.Inertia(m, c, Ic))
    for k, name in enumerate(names):  # the spatial inertia is at most quadratic: h = 1 is exact
        args = {"mass": m, "c": c.copy(), "Ic": Ic.copy()}
        plus, minus = dict(args, c=c.copy(), Ic=Ic.copy()), dict(args, c=c.copy(), Ic=Ic.copy())
        if name == "mass":
            plus["mass"], minus["mass"] = m + 1, m - 1
        elif name.startswith("com"):
            plus["c"][k - 1] += 1
            minus["c"][k - 1] -= 1
        else:
            a, b = INERTIA[name]
            for d, s in ((plus, 1), (minus, -1)):
                d["Ic"][a, b] += s
                if a != b:
                    d["Ic"][b, a] += s
        fd = (
            pin.Inertia(plus["mass"], plus["c"], plus["Ic"]).matrix()
            - pin.Inertia(minus["mass"], minus["c"], minus["Ic"]).matrix()
        ) / 2
        np.testing.assert_allclose(dI[k], fd, atol=1e-12, err_msg=name)


def test_every_sensitivity_matches_central_differences(robot):
    """∂κ/∂p of every parameter vs central differences of κ (Pinocchio CRBA + eigvalsh).

    Relative 1e-6, with an absolute floor of 1e-9 κ/scale for derivatives near zero (the
    differences' round-off is ~eps κ / h).
    """
    q = _q(robot, 1)
    result = kappa_sensitivities(robot, q)
    assert not result.clustered
    names = body_names(robot)
    kappa = result.kappa
    assert kappa == pytest.approx(_kappa(robot.model, q), rel=1e-12)
    for s in result.sensitivities:
        scale = max(abs(s.value), 0.1 if s.unit == "m" else 1e-2)
        if s.parameter in INERTIA:  # keep I_c positive definite
            inertia = robot.model.inertias[names.index(s.owner) + 1].inertia
            scale = min(scale, np.linalg.eigvalsh(inertia)[0])
        h = 1e-4 * scale
        plus = _kappa(_perturbed(robot.model, names, s.owner, s.parameter, s.value + h), q)
        minus = _kappa(_perturbed(robot.model, names, s.owner, s.parameter, s.value - h), q)
        fd = (plus - minus) / (2 * h)
        assert s.dkappa == pytest.approx(fd, rel=1e-6, abs=1e-9 * kappa / scale), (
            f"{s.owner}.{s.parameter}: exact {s.dkappa!r} vs differences {fd!r}"
        )


def _kappa_s(model: pin.Model, q: np.ndarray) -> float:
    M = pin.crba(model, model.createData(), q)
    M = np.triu(M) + np.triu(M, 1).T
    r = 1 / np.sqrt(np.diag(M))
    w = np.linalg.eigvalsh(M * np.outer(r, r))
    return w[-1] / w[0]


def test_every_kappa_s_sensitivity_matches_central_differences(robot):
    """∂κ_S/∂p (κ_S = κ of D^-1/2 M D^-1/2) vs central differences of NumPy's κ_S."""
    q = _q(robot, 4)
    result = kappa_sensitivities(robot, q, metric="kappa_equilibrated")
    assert result.metric == "kappa_equilibrated" and not result.clustered
    names = body_names(robot)
    kappa = result.kappa
    assert kappa == pytest.approx(_kappa_s(robot.model, q), rel=1e-10)
    for s in result.sensitivities:
        scale = max(abs(s.value), 0.1 if s.unit == "m" else 1e-2)
        if s.parameter in INERTIA:
            inertia = robot.model.inertias[names.index(s.owner) + 1].inertia
            scale = min(scale, np.linalg.eigvalsh(inertia)[0])
        h = 1e-4 * scale
        plus = _kappa_s(_perturbed(robot.model, names, s.owner, s.parameter, s.value + h), q)
        minus = _kappa_s(_perturbed(robot.model, names, s.owner, s.parameter, s.value - h), q)
        fd = (plus - minus) / (2 * h)
        assert s.dkappa == pytest.approx(fd, rel=1e-6, abs=1e-9 * kappa / scale), (
            f"{s.owner}.{s.parameter}: exact {s.dkappa!r} vs differences {fd!r}"
        )


def test_mass_and_inertia_elasticities_sum_to_zero(robot):
    """M is linear and homogeneous in (m, I_c) at fixed c: scaling them all leaves κ."""
    result = kappa_sensitivities(robot, _q(robot, 2))
    inertial = [s.elasticity for s in result.sensitivities if s.parameter in {"mass", *INERTIA}]
    assert abs(sum(inertial)) < 1e-10 * max(1.0, max(map(abs, inertial)))
    assert max(map(abs, inertial)) > 1e-3  # the identity is not vacuous


@pytest.mark.parametrize("spec", ["ur5", "chain_spatial"])
def test_length_elasticities_balance_inertia_ones(spec):
    """All-revolute robots: lengths × s and I_c × s² scale M by s², so κ is unchanged:
    Σ e(offset) + Σ e(com) + 2 Σ e(I) = 0."""
    robot = load_robot("ur5") if spec == "ur5" else chain_robot(chain_spec(5, axes="spatial"))
    result = kappa_sensitivities(robot, _q(robot, 4))
    total = 0.0
    for s in result.sensitivities:
        if s.parameter.startswith(("offset", "com")):
            total += s.elasticity
        elif s.parameter in INERTIA:
            total += 2 * s.elasticity
    assert abs(total) < 1e-10


def test_paper_chain_kappa_is_free_of_mass_and_length_scale():
    """κ ≈ 4n⁴ of the paper's chain depends on n only: its mass-type and length-type
    elasticities (rod mass m enters mass and I = m l²/12; length l enters offsets, COM, I)
    each sum to zero, while single links' elasticities do not vanish."""
    for n in (4, 10):
        robot = chain_robot(chain_spec(n))
        result = kappa_sensitivities(robot, np.zeros(n))
        assert result.kappa == pytest.approx(4 * n**4, rel=0.5)
        mass = sum(s.elasticity for s in result.sensitivities if s.parameter in {"mass", *INERTIA})
        length = sum(
            s.elasticity * (2 if s.parameter in INERTIA else 1)
            for s in result.sensitivities
            if s.parameter in INERTIA or s.parameter.startswith(("offset", "com"))
        )
        assert abs(mass) < 1e-9 and abs(length) < 1e-9
        assert max(abs(s.elasticity) for s in result.sensitivities) > 0.05


def _rod_derivatives(result, n: int, masses, lengths) -> tuple[np.ndarray, np.ndarray]:
    """dκ/dm_k and dκ/dl_k of rod k by the chain rule over the reported parameters."""
    d = {(s.owner, s.parameter): s.dkappa for s in result.sensitivities}
    width = len(str(n))
    dm, dl = np.zeros(n), np.zeros(n)
    for k in range(n):
        link, m, l = f"link_{k + 1:0{width}d}", masses[k], lengths[k]
        dm[k] = d[link, "mass"] + l * l / 12 * (d[link, "Iyy"] + d[link, "Izz"])
        dl[k] = d[link, "com_x"] / 2 + m * l / 6 * (d[link, "Iyy"] + d[link, "Izz"])
        if k + 1 < n:
            dl[k] += d[f"joint_{k + 2:0{width}d}", "offset_x"]
    return dm, dl


def _mp_kappa_derivative(M, dM) -> mpmath.mpf:
    E, Q = mpmath.eigsy(M)
    order = sorted(range(M.rows), key=lambda i: E[i])
    lo, hi = order[0], order[-1]
    vmin, vmax = Q[:, lo], Q[:, hi]
    dmin = (vmin.T * dM * vmin)[0, 0]
    dmax = (vmax.T * dM * vmax)[0, 0]
    return (dmax - E[hi] / E[lo] * dmin) / E[lo]


def test_planar_chain_rod_derivatives_match_mpmath():
    """The planar rod chain in mpmath (50 digits): M is quadratic in each rod's m and l, so
    a central difference of M is exact; the reference ∂κ is then vᵀ∂Mv at 50 digits."""
    masses, lengths = (2.2, 1.3, 0.7, 1.9), (1.0, 0.6, 1.4, 0.8)
    spec = chain_spec(4, mass_kg=masses, length_m=lengths)
    q = np.array([0.3, -1.1, 0.8, 2.0])
    result = kappa_sensitivities(chain_robot(spec), q)
    dm, dl = _rod_derivatives(result, 4, masses, lengths)
    with mpmath.workdps(50):
        M = PlanarChainReference(spec).gim(q)
        for k in range(4):
            for which, exact in (("m", dm[k]), ("l", dl[k])):
                h = 0.125
                vals = {"m": list(masses), "l": list(lengths)}
                up, down = dict(vals), dict(vals)
                up[which] = [x + h * (i == k) for i, x in enumerate(vals[which])]
                down[which] = [x - h * (i == k) for i, x in enumerate(vals[which])]
                Mp = PlanarChainReference(chain_spec(4, mass_kg=up["m"], length_m=up["l"])).gim(q)
                Mm = PlanarChainReference(chain_spec(4, mass_kg=down["m"], length_m=down["l"])).gim(
                    q
                )
                ref = float(_mp_kappa_derivative(M, (Mp - Mm) / (2 * h)))
                assert exact == pytest.approx(ref, rel=1e-10), f"rod {k} d{which}"


def _tree_gim(reference: TreeReference, q: np.ndarray) -> mpmath.matrix:
    n = reference.nv
    M = mpmath.matrix(n, n)
    for i in range(n):
        column = reference.inverse_dynamics(q, np.zeros(n), np.eye(n)[i])
        for r in range(n):
            M[r, i] = column[r]
    return M


def test_robot_sensitivities_match_mpmath_tree_reference(robot):
    """Against the mpmath ABA/RNEA of the same URDF (50 digits, no gravity): M columns by
    RNEA; M is at most quadratic in a mass, COM, inertia entry or link offset, so central
    differences of M with a binary step are exact and ∂κ = (vmaxᵀ∂M vmax − κ vminᵀ∂M vmin)/λmin."""
    model = robot.model
    q = _q(robot, 5)
    q_index = {model.names[j]: model.joints[j].idx_q for j in range(1, model.njoints)}
    v_index = {model.names[j]: model.joints[j].idx_v for j in range(1, model.njoints)}
    tree = read_body_tree(robot.urdf_xml, source=robot.source)
    result = kappa_sensitivities(robot, q)
    d = {(s.owner, s.parameter): s.dkappa for s in result.sensitivities}
    names = body_names(robot)
    with mpmath.workdps(50):
        M = _tree_gim(TreeReference(tree, q_index, v_index, gravity=(0, 0, 0)), q)
        assert float(mpmath.norm(M - mpmath.matrix(pin.crba(model, model.createData(), q)))) < 1e-9
        for b in (1, 3, len(names) - 1):
            joint = model.names[b + 1]
            i = tree.joint_names.index(joint)
            cases = (
                ("mass", names[b], "mass", None),
                ("com", names[b], "com_y", 1),
                ("inertia", names[b], "Ixz", (0, 2)),
                ("placement_translation", joint, "offset_z", 2),
            )
            for field, owner, parameter, where in cases:
                h = 2.0**-8
                up, down = (np.array(getattr(tree, field)) for _ in range(2))
                if field == "mass":
                    up[i] += h
                    down[i] -= h
                elif field == "inertia":
                    up[i][where] += h
                    up[i][where[::-1]] += h
                    down[i][where] -= h
                    down[i][where[::-1]] -= h
                else:
                    up[i][where] += h
                    down[i][where] -= h
                refs = [
                    TreeReference(
                        dataclasses.replace(tree, **{field: x}), q_index, v_index, gravity=(0, 0, 0)
                    )
                    for x in (up, down)
                ]
                dM = (_tree_gim(refs[0], q) - _tree_gim(refs[1], q)) / (2 * h)
                ref = float(_mp_kappa_derivative(M, dM))
                exact = d[owner, parameter]
                assert exact == pytest.approx(ref, rel=1e-10, abs=1e-10 * result.kappa), (
                    f"{robot.name} {owner}.{parameter}: {exact!r} vs mpmath {ref!r}"
                )


CLUSTER_URDF = """<robot name="three_pendulums"><link name="base"/>
{}</robot>"""
PENDULUM = """<joint name="j{k}" type="revolute"><parent link="base"/><child link="l{k}"/>
<origin xyz="{x} 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/>
</joint><link name="l{k}"><inertial><origin xyz="0 0 -0.5"/><mass value="{m}"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
"""


def test_clustered_lambda_min_gives_the_one_sided_derivative(tmp_path):
    """Two identical pendulums on a fixed base: λmin is double. Raising one's mass leaves
    λmin where it is (the other pendulum keeps it), lowering it lowers λmin: κ has a kink,
    and the reported derivative is the one-sided one as p increases."""
    body = "".join(PENDULUM.format(k=k, x=k, m=m) for k, m in ((1, 1.0), (2, 1.0), (3, 3.0)))
    path = tmp_path / "three.urdf"
    path.write_text(CLUSTER_URDF.format(body))
    robot = load_robot(path)
    q = np.zeros(3)
    result = kappa_sensitivities(robot, q)
    assert (result.clustered_min, result.clustered_max) == (2, 1) and result.clustered
    d = {(s.owner, s.parameter): s.dkappa for s in result.sensitivities}
    names = body_names(robot)
    h = 1e-6
    up = _kappa(_perturbed(robot.model, names, "l1", "mass", 1.0 + h), q)
    down = _kappa(_perturbed(robot.model, names, "l1", "mass", 1.0 - h), q)
    forward, backward = (up - result.kappa) / h, (result.kappa - down) / h
    assert d["l1", "mass"] == pytest.approx(forward, abs=1e-6)
    assert abs(backward - forward) > 0.1  # a genuine kink: the two-sided derivative is not it
    heavy = (_kappa(_perturbed(robot.model, names, "l3", "mass", 3.0 + h), q) - result.kappa) / h
    assert d["l3", "mass"] == pytest.approx(heavy, rel=1e-5)


def test_parameter_table_units_and_armature():
    robot = load_robot("ur5")
    rows = parameter_table(robot)
    assert len(rows) == 13 * 6 + 6
    assert {unit for *_, unit in rows} == {"kg", "m", "kg*m^2"}
    assert [r[1] for r in rows if r[0] == "elbow_joint"] == [
        "offset_x",
        "offset_y",
        "offset_z",
        "armature",
    ]
