"""The stress suite, one test per hard case; the mpmath tree reference; the command."""

import json

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.cli import main
from gimwatch.denoc.tree import read_body_tree
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import chain_robot, load_robot, random_configurations
from gimwatch.stress.cases import CASES
from gimwatch.stress.reference_planar import PlanarChainReference
from gimwatch.stress.reference_tree import TreeReference
from gimwatch.stress.suite import METHODS, run_case

#: Cases whose 5 s simulation is cheap enough for every test run (the rest: slow marker).
SIMULATED = {
    "heavy-root-20",
    "mixed-spatial-24",
    "ur5-wrist-aligned",
    "ur5-elbow-straight",
    "panda-zero",
    "talos-arm-zero",
    "talos-floating",
    "g1-hands-floating",
}


def _params():
    for name, case in CASES.items():
        marks = [] if case.quick or name in SIMULATED else [pytest.mark.slow]
        yield pytest.param(name, marks=marks, id=name)


@pytest.mark.parametrize("name", list(_params()))
def test_hard_case_stays_numerically_stable(name):
    case = CASES[name]
    result = run_case(case, simulate=name in SIMULATED)
    assert result.cholesky_ok, result.note
    assert result.estimators_finite
    if result.gim_error is not None:
        assert result.gim_error <= 1e-10, result.gim_error
    computed = {m: e for m, e in result.errors.items() if e is not None}
    assert "denoc" in computed
    if result.nv <= 400:
        assert set(computed) == set(METHODS)
    for method, error in computed.items():
        assert np.isfinite(error) and error <= result.bound, (method, error, result.bound)
    if name in SIMULATED:
        assert result.sim_status == "completed"
        assert result.sim_energy_drift <= 1e-4
    assert result.passed, result.note


def _indices(robot):
    model = robot.model
    q_index = {model.names[j]: model.joints[j].idx_q for j in range(1, model.njoints)}
    v_index = {model.names[j]: model.joints[j].idx_v for j in range(1, model.njoints)}
    return q_index, v_index


def test_tree_reference_equals_the_planar_closed_form():
    spec = chain_spec(8, mass_kg=np.geomspace(2.2, 0.01, 8), length_m=np.geomspace(1, 0.1, 8))
    robot = chain_robot(spec)
    rng = np.random.default_rng(3)
    q, v, tau = rng.uniform(-2, 2, 8), rng.uniform(-1, 1, 8), rng.uniform(-10, 10, 8)
    tree = read_body_tree(robot.urdf_xml)
    ref = TreeReference(tree, *_indices(robot), gravity=(0.0, -9.81, 0.0))
    closed = PlanarChainReference(spec).forward_dynamics(q, v, tau)
    np.testing.assert_allclose(ref.forward_dynamics(q, v, tau), closed, rtol=1e-14, atol=0)


@pytest.mark.parametrize(
    ("robot_name", "floating"), [("talos_arm", False), ("ur5", True), ("panda", False)]
)
def test_tree_reference_inverts_its_own_rnea_and_agrees_with_pinocchio(robot_name, floating):
    robot = load_robot(robot_name, floating=floating)
    rng = np.random.default_rng(1)
    q = random_configurations(robot, 1, seed=2)[0]
    v, tau = rng.standard_normal(robot.nv), rng.standard_normal(robot.nv)
    tree = read_body_tree(robot.urdf_xml, floating=floating)
    ref = TreeReference(tree, *_indices(robot))
    a = ref.forward_dynamics(q, v, tau)
    back = np.array([float(x) for x in ref.inverse_dynamics(q, v, a)])
    np.testing.assert_allclose(back, tau, rtol=0, atol=1e-12 * np.abs(tau).max())
    model = pin.Model(robot.model)
    expected = pin.aba(model, model.createData(), q, v, tau)
    np.testing.assert_allclose(a, expected, rtol=1e-11, atol=1e-11 * np.abs(expected).max())


def test_stress_command_prints_the_table_and_json(capsys):
    assert main(["stress", "ur5-wrist-aligned", "panda-zero", "--no-simulate"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split()[:3] == ["case", "nv", "kappa"]
    assert "ur5-wrist-aligned" in out and "panda-zero" in out
    assert main(["stress", "talos-arm-zero", "--no-simulate", "--json"]) == 0
    (record,) = json.loads(capsys.readouterr().out)["cases"]
    assert record["case"] == "talos-arm-zero" and record["passed"] is True
    assert set(record["errors"]) == set(METHODS)


def test_stress_command_refuses_an_unknown_case(capsys):
    assert main(["stress", "nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gimwatch: error: the stress case must be one of")
