"""The κ tracker at crossings of the two smallest eigenvalues: exact, or saying so.

The hard case is a tree whose softest modes live in different branches: along a path that
straightens one branch while curling the other, the lowest mode moves from one branch to the
other. The warm Ritz block (localised in the first branch) has no component on the new
lowest mode, Lanczos converges to the old one, and the Sylvester check at the previous shift
passes (the shift lies below both). Each sample's λmin is now certified by a factorization
of M − λ(1 − rtol)·1 (all pivots positive: no eigenvalue below), and recovered by
Sylvester bisection when it fails.

Reference at every sample, independent of the tracker and of DeNOC: λmax(M)·λmax(M⁻¹) from
Pinocchio's ``crba`` and ``computeMinverse`` (the largest eigenvalue of each is computed to
relative round-off, where eigvalsh's λmin of M is only good to κ·eps).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from threadpoolctl import threadpool_limits

from gimwatch.denoc import DenocModel
from gimwatch.metrics.tracker import KappaTracker
from gimwatch.model.robots import load_robot

#: The tracker's documented accuracy is rtol = 1e-10 per end (κ to about 2e-10): κ is held to
#: 5e-10, a margin of 2.5 for the reference's round-off (measured errors up to 8.7e-11 on
#: these trees, κ up to 4e8, crossings included).
BOUND = 5e-10
#: Each end is certified within rtol (Sylvester): κ's bound is (1 + rtol)/(1 − rtol) − 1.
ESTIMATE_BOUND = 2 * 1e-10 / (1 - 1e-10)


def y_tree_urdf(links_per_branch: int, mass_kg: float = 2.2, length_m: float = 1.0) -> str:
    """Two planar rod chains hanging from one base 1 m apart (continuous joints about z)."""
    inertia = mass_kg * length_m**2 / 12
    parts = [
        "<robot name='y_tree'><link name='base'><inertial><mass value='5'/>"
        "<inertia ixx='0.5' ixy='0' ixz='0' iyy='0.5' iyz='0' izz='0.5'/></inertial></link>"
    ]
    for branch, offset in (("a", 0.5), ("b", -0.5)):
        parent = "base"
        for i in range(1, links_per_branch + 1):
            name = f"{branch}{i}"
            xyz = f"0 {offset} 0" if i == 1 else f"{length_m} 0 0"
            parts.append(
                f"<link name='{name}'><inertial><origin xyz='{length_m / 2} 0 0'/>"
                f"<mass value='{mass_kg}'/><inertia ixx='1e-4' ixy='0' ixz='0' "
                f"iyy='{inertia}' iyz='0' izz='{inertia}'/></inertial></link>"
                f"<joint name='j{name}' type='continuous'><parent link='{parent}'/>"
                f"<child link='{name}'/><origin xyz='{xyz}'/><axis xyz='0 0 1'/></joint>"
            )
            parent = name
    return "".join(parts) + "</robot>"


def _reference(model, data, q) -> float:
    M = pin.crba(model, data, q)
    inverse = pin.computeMinverse(model, data, q)
    inverse = np.triu(inverse) + np.triu(inverse, 1).T
    return float(np.linalg.eigvalsh(M)[-1] * np.linalg.eigvalsh(inverse)[-1])


@pytest.mark.parametrize(
    ("links", "samples", "floating"),
    [(30, 41, False), (100, 21, False), (30, 31, True)],
    ids=["60dof", "200dof", "66dof-floating"],
)
def test_kappa_is_exact_at_every_sample_through_a_branch_crossing(
    tmp_path, links, samples, floating
):
    path = tmp_path / "y_tree.urdf"
    path.write_text(y_tree_urdf(links), encoding="utf-8")
    robot = load_robot(path, floating=floating)
    model, data = robot.model, robot.model.createData()
    lean = DenocModel.from_urdf(
        robot.urdf_xml, floating=floating, joint_order=robot.joint_names
    ).lean()
    names = robot.dof_names
    branch_a = np.array([i for i, name in enumerate(names) if name.startswith("ja")])
    branch_b = np.array([i for i, name in enumerate(names) if name.startswith("jb")])
    rng = np.random.default_rng(0)
    crossings_caught = 0
    with threadpool_limits(1):
        for amplitude in (0.1, 0.3, 1.0):
            shape = rng.uniform(0.2, 1.0, links) * amplitude
            tracker = KappaTracker(lean, robot.nv)
            for s in np.linspace(0.0, 1.0, samples):
                motion = np.zeros(robot.nv)
                motion[branch_a], motion[branch_b] = s * shape, (1 - s) * shape
                q = pin.integrate(model, pin.neutral(model), motion)
                tracked = tracker.sample(q)
                reference = _reference(model, data, q)
                error = abs(tracked.kappa - reference) / reference
                assert error <= BOUND, (amplitude, s, error, tracked.fallback)
                crossings_caught += tracked.fallback == "cold"
    if not floating:  # fixed base: the branches' modes are decoupled, and do cross unseen
        assert crossings_caught >= 1


def test_each_samples_fallback_and_error_bound_reach_the_series_and_results(tmp_path):
    import json

    from gimwatch.cli import main
    from gimwatch.watch import Watch

    path = tmp_path / "y_tree.urdf"
    path.write_text(y_tree_urdf(30), encoding="utf-8")
    robot = load_robot(path)
    watch = Watch(robot, ("kappa_tracked",))
    names = robot.dof_names
    branch_a = np.array([i for i, name in enumerate(names) if name.startswith("ja")])
    branch_b = np.array([i for i, name in enumerate(names) if name.startswith("jb")])
    shape = np.random.default_rng(0).uniform(0.2, 1.0, 30) * 0.3
    for k, s in enumerate(np.linspace(0.0, 1.0, 41)):
        motion = np.zeros(robot.nv)
        motion[branch_a], motion[branch_b] = s * shape, (1 - s) * shape
        watch.sample(0.01 * k, pin.integrate(robot.model, pin.neutral(robot.model), motion))
    arrays = watch.arrays()
    labels = list(arrays["watch_kappa_tracked_fallback"])
    assert labels[0] == "start" and set(labels) <= {"start", "", "cold", "dense"}
    bounds = arrays["watch_kappa_tracked_error_estimate"]
    assert bounds.shape == (41,) and np.all((bounds >= 0) & (bounds <= ESTIMATE_BOUND))
    scene = tmp_path / "scene.toml"
    scene.write_text(
        'robot = "chain:12"\nduration = 0.1\nsample = 0.02\nq = 0.1\n'
        '[integrator]\nmethod = "RK4"\ndt = 0.005\n[watch]\nmetrics = ["kappa_tracked"]\n',
        encoding="utf-8",
    )
    assert main(["simulate", str(scene), "-o", str(tmp_path / "out")]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    assert summary["kappa_tracked_fallbacks"] == {"start": 1, "warm": 5}
    header = (tmp_path / "out" / "watch.csv").read_text(encoding="utf-8").splitlines()[0]
    assert header == "t,kappa_tracked,kappa_tracked_fallback,kappa_tracked_error_estimate"
