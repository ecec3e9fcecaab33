import numpy as np
import pytest
from closed_forms import straight_chain_extreme_eigenvalues
from conftest import EXAMPLE_ROBOTS, NO_DOF_WHEN_FIXED, planar_rod_chain_gim

from gimwatch.metrics.conditioning import condition_number, diagonal_ratio
from gimwatch.model.chains import chain_spec, generate_chain_urdf
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.model.robots import load_robot, neutral_configuration
from gimwatch.model.sampling import random_configurations


def test_straight_paper_chain_matches_closed_form_and_paper_numbers():
    robot = load_robot("chain:4")
    M = gim(robot, neutral_configuration(robot))
    np.testing.assert_allclose(M, planar_rod_chain_gim(np.zeros(4), 2.2, 1.0), rtol=1e-12)
    assert condition_number(M) == pytest.approx(1074.4, abs=0.1)
    assert diagonal_ratio(M) == pytest.approx(64.0, rel=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_planar_chain_matches_closed_form_at_random_configurations(seed, tmp_path):
    rng = np.random.default_rng(seed)
    masses, lengths = rng.uniform(0.5, 3.0, 5), rng.uniform(0.2, 2.0, 5)
    path = tmp_path / "chain.urdf"
    path.write_text(generate_chain_urdf(chain_spec(5, mass_kg=masses, length_m=lengths)))
    robot = load_robot(path)
    q = rng.uniform(-np.pi, np.pi, 5)
    expected = planar_rod_chain_gim(q, masses, lengths)
    np.testing.assert_allclose(gim(robot, q), expected, rtol=1e-12, atol=1e-12 * expected.max())


@pytest.mark.parametrize("n", [4, 10, 20, 50])
def test_straight_chain_diagonal_ratio_is_n_cubed(n):
    robot = load_robot(f"chain:{n}")
    assert diagonal_ratio(gim_diagonal(robot, neutral_configuration(robot))) == pytest.approx(
        n**3, rel=1e-12
    )


#: κ/4n⁴ of the straight chain as published (docs/findings/claims.md).
PUBLISHED_KAPPA_OVER_4N4 = {10: 1.088, 20: 1.047}


@pytest.mark.parametrize("n", [10, 20, 50])
def test_straight_chain_condition_number_near_4n4(n):
    robot = load_robot(f"chain:{n}")
    kappa = condition_number(gim(robot, neutral_configuration(robot)))
    # against the banded closed form (tests/closed_forms.py); eigvalsh's λmin: ~eps·κ relative
    lambda_min, lambda_max = straight_chain_extreme_eigenvalues(n)
    assert kappa == pytest.approx(lambda_max / lambda_min, rel=1e-8)
    if n in PUBLISHED_KAPPA_OVER_4N4:
        assert round(kappa / (4 * n**4), 3) == PUBLISHED_KAPPA_OVER_4N4[n]


@pytest.mark.parametrize("spec", ["chain:1", "chain:7", "chain:60"])
def test_linear_time_diagonal_equals_crba_on_chains(spec):
    robot = load_robot(spec)
    for q in random_configurations(robot, 3, seed=11):
        np.testing.assert_allclose(gim_diagonal(robot, q), np.diag(gim(robot, q)), rtol=1e-12)


def test_linear_time_diagonal_on_spatial_mixed_chain(tmp_path):
    spec = chain_spec(
        9, axes="spatial", radius_m=0.03, joint_types=["revolute", "prismatic", "revolute"] * 3
    )
    path = tmp_path / "mixed.urdf"
    path.write_text(generate_chain_urdf(spec))
    robot = load_robot(path, floating=True)
    for q in random_configurations(robot, 3, seed=5):
        np.testing.assert_allclose(gim_diagonal(robot, q), np.diag(gim(robot, q)), rtol=1e-12)


@pytest.mark.parametrize("floating", [False, True], ids=["fixed", "floating"])
@pytest.mark.parametrize("name", EXAMPLE_ROBOTS)
def test_linear_time_diagonal_equals_crba_on_example_robots(name, floating):
    if name in NO_DOF_WHEN_FIXED and not floating:
        return  # no joint: covered by the CLI error test
    robot = load_robot(name, floating=floating)
    data = robot.new_data()
    for q in random_configurations(robot, 2, seed=1):
        M = gim(robot, q, data=data)
        np.testing.assert_allclose(gim_diagonal(robot, q, data=data), np.diag(M), rtol=1e-12)
        np.testing.assert_allclose(M, M.T, rtol=0, atol=0)


def test_gim_without_data_reuses_one_data_per_robot(monkeypatch):
    """`gw.gim(robot, q)` in a loop builds one Pinocchio Data, and its M is Pinocchio's."""
    import pinocchio as pin

    from gimwatch.model.robots import Robot

    made = []
    original = Robot.new_data

    def counting(self):
        made.append(self.name)
        return original(self)

    monkeypatch.setattr(Robot, "new_data", counting)
    ur5, panda = load_robot("ur5"), load_robot("panda")
    qs = random_configurations(ur5, 3, seed=5)
    for q in qs:
        fresh = pin.crba(ur5.model, ur5.model.createData(), q)
        np.testing.assert_array_equal(gim(ur5, q), np.triu(fresh) + np.triu(fresh, 1).T)
    gim_diagonal(ur5, qs[0])
    assert made == ["ur5"]
    gim(panda, neutral_configuration(panda))
    assert made == ["ur5", "panda"]
