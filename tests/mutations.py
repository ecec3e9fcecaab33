"""Planted bugs the tests must catch: ``make mutation`` (or ``python tests/mutations.py``).

Each mutant is a small textual patch (file, old text, new text) in one numerical core, with
the fast test subset that should catch it. The runner copies the working tree to a temporary
directory (never touching the real tree), applies one patch at a time there, runs the subset
with that copy first on ``PYTHONPATH``, and reports each mutant as

* ``caught`` — the subset failed (what we want);
* ``MISSED`` — the subset passed with the bug in place (a test to strengthen);
* ``stale`` — the old text is not in the file exactly once (the code moved: update the
  mutant, don't let it pass silently);
* ``timeout`` — the subset did not finish in time (counted as not caught).

Before the mutants, each distinct subset runs once on the unmutated copy and must pass. Exit
status 0 only when every mutant is caught. Not part of ``make test`` (it takes minutes).

Usage: ``python tests/mutations.py [--jobs 2] [--timeout 600] [--list] [--match TEXT] [ID ...]``
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
IGNORED = (".git", ".venv", "site", "demo-output", ".pytest_cache", "__pycache__", "*.egg-info")


@dataclass(frozen=True)
class Mutant:
    """One planted bug: replace ``old`` by ``new`` in ``path``; ``tests`` should catch it.

    ``path`` may list alternatives separated by ``|`` (where the code lives before and after a
    move); the patch goes to the first that holds ``old`` exactly once.
    """

    id: str
    path: str
    old: str
    new: str
    tests: tuple[str, ...]
    why: str = ""

    @property
    def paths(self) -> tuple[str, ...]:
        """The candidate files, in order."""
        return tuple(self.path.split("|"))


DENOC = ("tests/test_denoc.py",)
LONG = ("tests/test_longchain.py",)
STRESS_QUICK = ("tests/test_stress.py", "-m", "not slow")
#: the compiled kernels behind analyze_linear and extreme_eigenvalues (gimwatch/denoc/linear.py,
#: gimwatch/metrics/tracker/extremes.py)
COMPILED_STATE = ("tests/test_longchain.py", "-k", "compiled_state or closed_forms or lanczos")
TRAJECTORY = ("tests/test_trajectory_reference.py",)
URDF_VALUES = (
    "tests/test_bad_inputs.py",
    "-k",
    "bad_urdf_file_raises or warning_cases or library_warning",
)
TRACKER = ("tests/test_tracker.py", "tests/test_tracker_krylov.py")
SWAP = (
    "tests/test_faults_folders.py",
    "tests/test_interrupted_outputs.py",
    "-k",
    # the file-size test fails in a fresh copy: the numba cache write hits RLIMIT_FSIZE first
    "not signal and not file_size_limit",
)
ESTIMATOR = ("tests/test_estimator_quality.py",)
PRECISION = ("tests/test_reference_precision.py", "-k", "keeps_fifty")
#: the stale clean-up beside a results folder (gimwatch/output/swap.py), called directly
HOSTILE = ("tests/test_faults_folders_hostile.py",)
#: atomic writes of single files (gimwatch/output/atomic.py)
ATOMIC = ("tests/test_results.py",)

MUTANTS = (
    # --- DeNOC recursions (numpy, gimwatch/denoc/recursions.py) ---
    Mutant(
        "denoc-composite-half",
        "gimwatch/denoc/recursions.py",
        "accumulate(composite, tree.parent[level], shifted)",
        "accumulate(composite, tree.parent[level], 0.5 * shifted)",
        DENOC,
        "composite mass matrices (Eq. 12) pass half the child's inertia",
    ),
    Mutant(
        "denoc-diagonal-first-moment",
        "gimwatch/denoc/fused.py",
        "p[6] += c[6] + m * (rr - r2 * r2) + 2.0 * (rh - r2 * h2)",
        "p[6] += c[6] + m * (rr - r2 * r2) + 1.0 * (rh - r2 * h2)",
        DENOC,
        "O(n) diagonal (fused): the child's first moment enters the shift once, not twice",
    ),
    Mutant(
        "denoc-prismatic-coriolis",
        "gimwatch/denoc/fused.py",
        "c[3 + a] += 2.0 * t1[a] * qd",
        "c[3 + a] += 1.0 * t1[a] * qd",
        DENOC,
        "Coriolis term of prismatic joints halved (fused forward dynamics)",
    ),
    Mutant(
        "denoc-articulated-pass",
        "gimwatch/denoc/recursions.py",
        "U[level][:, :, None] * U[level][:, None, :] / d[:, None, None]",
        "U[level][:, :, None] * U[level][:, None, :] / (2.0 * d[:, None, None])",
        DENOC,
        "articulated inertia passed to the parent with half the correction",
    ),
    Mutant(
        "denoc-gravity-1e-10",
        "gimwatch/denoc/fused.py",
        "        rate0[3 + a] = -gravity[a]\n    if floating:",
        "        rate0[3 + a] = -gravity[a] * (1.0 + 1e-10)\n    if floating:",
        STRESS_QUICK,
        "gravity 1e-10 too strong in DeNOC's forward dynamics (fused)",
    ),
    Mutant(
        "denoc-factor-1e-12",
        "gimwatch/denoc/fused.py",
        "art[a, b] -= u[a] * u[b] / pivot",
        "art[a, b] -= u[a] * u[b] / (pivot * (1.0 + 1e-12))",
        STRESS_QUICK,
        "articulated-body factor off by 1e-12 relative (fused)",
    ),
    # --- the O(n) state on DeNOC's compiled kernels (gimwatch/denoc/linear.py, fused.py) ---
    Mutant(
        "compiled-diagonal-1e-9",
        "gimwatch/denoc/fused.py",
        "out[index[i, 3]] = (\n                c[4] * e0 * e0",
        "out[index[i, 3]] = (1.0 + 1e-9) * (\n                c[4] * e0 * e0",
        COMPILED_STATE,
        "O(n) diagonal of revolute joints off by 1e-9 relative",
    ),
    Mutant(
        "compiled-factor-1e-9",
        "gimwatch/denoc/fused.py",
        "pivot = _p_dot(kind, e, u) - shift",
        "pivot = _p_dot(kind, e, u) * (1.0 + 1e-9) - shift",
        COMPILED_STATE,
        "articulated-body pivots (matrix-free κ, the tracker's Sylvester check) off by 1e-9",
    ),
    Mutant(
        "compiled-gravity-1e-10",
        "gimwatch/denoc/fused.py",
        "        rate0[3 + a] = -gravity[a]\n    columns = np.empty((6, 6))",
        "        rate0[3 + a] = -gravity[a] * (1.0 + 1e-10)\n    columns = np.empty((6, 6))",
        DENOC,
        "gravity 1e-10 too strong in the compiled inverse dynamics (DeNOC's τ)",
    ),
    Mutant(
        "linear-continuous-as-cos-sin",
        "gimwatch/denoc/linear.py",
        "kind=np.where(tree.kind == _CONTINUOUS, _REVOLUTE, tree.kind)",
        "kind=tree.kind",
        DENOC + LONG,
        "the one-angle-per-body state reads a continuous joint's angle as (cos θ, sin θ)",
    ),
    Mutant(
        "denoc-ball-stand-in-quaternion-order",
        "gimwatch/model/denoc_input.py",
        "x, y, z, w = coordinates",
        "w, x, y, z = coordinates",
        ("tests/test_mjcf_compiled.py",),
        "DeNOC's stand-ins for a ball joint read Pinocchio's (x, y, z, w) as (w, x, y, z)",
    ),
    Mutant(
        "denoc-free-stand-in-angular-first",
        "gimwatch/model/denoc_input.py",
        '    ("tz", "prismatic", 2),\n    *_BALL_PARTS,\n)',
        '    *_BALL_PARTS,\n    ("tz", "prismatic", 2),\n)',
        ("tests/test_mjcf_compiled.py",),
        "a free object's stand-ins turn before their last slide (velocity order wrong)",
    ),
    Mutant(
        "diagonal-without-armature",
        "gimwatch/model/inertia.py",
        "return diagonal + robot.model.armature",
        "return diagonal",
        ("tests/test_mjcf_compiled.py", "-k", "armature"),
        "the O(n) diagonal leaves MuJoCo's armature out of δ",
    ),
    Mutant(
        "denoc-accepts-armature",
        "gimwatch/metrics/denoc_robot.py",
        "if not rigid and np.any(np.asarray(robot.model.armature) != 0):",
        "if False:",
        ("tests/test_mjcf_compiled.py", "-k", "armature"),
        "DeNOC (rigid bodies) watches a robot with armature: δ and κ without it",
    ),
    Mutant(
        "urdf-of-model-continuous-as-revolute",
        "gimwatch/joint_kinds.py",
        '**{f"RUB{a}": JointKind.CONTINUOUS for a in "XYZ"},',
        '**{f"RUB{a}": JointKind.REVOLUTE for a in "XYZ"},',
        ("tests/test_denoc_input.py",),
        "a continuous joint written as a revolute one: DeNOC reads (cos θ, sin θ) as two angles",
    ),
    Mutant(
        "spectrum-solver-unscaled",
        "gimwatch/watch/spectrum_solver.py",
        "M = M * (1.0 / scale)",
        "M = M * scale",
        ("tests/test_spectrum_solver.py",),
        "the watch's LAPACK path (n > 32) scales M the wrong way: overflow on huge entries",
    ),
    # --- mpmath references ---
    Mutant(
        "planar-reference-30-digits",
        "gimwatch/stress/reference_planar.py",
        "REFERENCE_DIGITS = 50",
        "REFERENCE_DIGITS = 30",
        ("tests/test_reference_precision.py",),
        "the planar reference at 30 digits",
    ),
    Mutant(
        "tree-reference-30-digits",
        "gimwatch/stress/reference_tree.py",
        "REFERENCE_DIGITS = 50",
        "REFERENCE_DIGITS = 30",
        ("tests/test_reference_precision.py",),
        "the tree reference at 30 digits",
    ),
    Mutant(
        "tree-reference-15-digits",
        "gimwatch/stress/reference_tree.py",
        "REFERENCE_DIGITS = 50",
        "REFERENCE_DIGITS = 15",
        ("tests/test_reference_precision.py", "tests/test_stress.py", "-m", "not slow"),
        "the tree reference at 15 digits (its default precision is the stress suite's)",
    ),
    Mutant(
        "planar-reference-own-inertia",
        "gimwatch/stress/reference_planar.py",
        "(3 * r[k] ** 2 + l[k] ** 2) / 12",
        "(3 * r[k] ** 2 + l[k] ** 2) / 11.999999",
        ("tests/test_reference.py",),
        "rod inertia about its centre off by 1e-7",
    ),
    Mutant(
        "tree-reference-mass-1e-13",
        "gimwatch/stress/reference_tree.py",
        "out[a + 3][a + 3] = m",
        'out[a + 3][a + 3] = m * (1 + mpmath.mpf("1e-13"))',
        ("tests/test_stress.py", "-k", "tree_reference"),
        "spatial inertia's mass off by 1e-13",
    ),
    # --- conditioning (κ, δ, pivots, αδ) ---
    Mutant(
        "kappa-1e-7",
        "gimwatch/metrics/conditioning.py",
        "return extreme_ratio(_scaled_eigenvalues(matrix)[0])",
        "return extreme_ratio(_scaled_eigenvalues(matrix)[0]) * (1 + 1e-7)",
        ("tests/test_conditioning.py", "tests/test_stress_properties.py"),
        "κ off by 1e-7 relative",
    ),
    Mutant(
        "delta-1e-9",
        "gimwatch/metrics/conditioning.py",
        "return extreme_ratio(_diagonal_of(matrix_or_diagonal))",
        "return extreme_ratio(_diagonal_of(matrix_or_diagonal)) * (1 + 1e-9)",
        ("tests/test_conditioning.py", "tests/test_watch.py"),
        "δ off by 1e-9 relative",
    ),
    Mutant(
        "udut-pivots-order",
        "gimwatch/metrics/conditioning.py",
        "return (np.diag(_cholesky_lower(M[::-1, ::-1])) ** 2)[::-1]",
        "return (np.diag(_cholesky_lower(M)) ** 2)[::-1]",
        ("tests/test_conditioning.py",),
        "backward pivots computed in the forward order",
    ),
    Mutant(
        "alpha-1e-3",
        "gimwatch/metrics/conditioning.py",
        "self._alpha = condition_number(M) / diagonal_ratio(M)",
        "self._alpha = condition_number(M) / diagonal_ratio(M) * 1.001",
        ("tests/test_conditioning.py",),
        "α of αδ (Eq. 15) off by 1e-3",
    ),
    Mutant(
        "linear-pivot-ratio",
        "gimwatch/metrics/registry.py",
        "return conditioning.extreme_ratio(state.udut_pivots)",
        "return conditioning.extreme_ratio(state.udut_pivots) * 1.001",
        LONG,
        "backward (UDUᵀ) pivot ratio off by 1e-3 (the metric of both paths)",
    ),
    Mutant(
        "pinocchio-diagonal-parallel-axis",
        "gimwatch/model/inertia.py",
        "force[3:] += skew @ force[:3]",
        "force[3:] += 0.999 * skew @ force[:3]",
        ("tests/test_inertia.py",),
        "parallel-axis term of the O(n) Pinocchio diagonal off by 1e-3",
    ),
    Mutant(
        "ldlt-pivots-not-squared",
        "gimwatch/metrics/conditioning.py",
        "return np.diag(_cholesky_lower(M)) ** 2\n",
        "return np.diag(_cholesky_lower(M))\n",
        ("tests/test_conditioning.py",),
        "forward pivots are the Cholesky diagonal, not its square",
    ),
    Mutant(
        "symmetry-check-loose",
        "gimwatch/metrics/conditioning.py",
        "SYMMETRY_RTOL = 1e-10",
        "SYMMETRY_RTOL = 1e-2",
        ("tests/test_conditioning.py",),
        "a GIM asymmetric at 1e-3 is accepted",
    ),
    Mutant(
        "estimator-alpha-second-sample",
        "gimwatch/metrics/estimator_quality.py",
        "alpha = kappa[0] / delta[0]",
        "alpha = kappa[1] / delta[1]",
        ("tests/test_watch.py",),
        "α of the estimator quality from the second sample, not t0",
    ),
    Mutant(
        "planar-reference-gravity-sign",
        "gimwatch/stress/reference_planar.py",
        "bias.append(h - (-gx * mp.sin(phi[a]) + gy * mp.cos(phi[a])) * lever)",
        "bias.append(h + (-gx * mp.sin(phi[a]) + gy * mp.cos(phi[a])) * lever)",
        ("tests/test_reference.py",),
        "gravity torque of the planar reference with the wrong sign",
    ),
    # --- energy and drift ---
    Mutant(
        "drift-always-zero",
        "gimwatch/simulation/simulate.py|gimwatch/simulation/trajectory.py",
        "deviation = float(np.max(np.abs(self.energy - self.energy[0])))",
        "deviation = 0.0 * float(np.max(np.abs(self.energy - self.energy[0])))",
        ("tests/test_simulate.py", "-k", "swinging"),
        "a drift function that always returns 0",
    ),
    Mutant(
        "pinocchio-kinetic-energy-1e-9",
        "gimwatch/simulation/backends.py",
        "return float(kinetic), float(pin.computePotentialEnergy(model, data, q))",
        "return float(kinetic) * (1 + 1e-9), float(pin.computePotentialEnergy(model, data, q))",
        ("tests/test_simulate.py", "-k", "swinging"),
        "kinetic energy off by 1e-9 relative",
    ),
    Mutant(
        "denoc-kinetic-energy-1e-9",
        "gimwatch/denoc/model.py",
        "kinetic = 0.5 * float(velocity @ state.matvec(velocity))",
        "kinetic = 0.5 * float(velocity @ state.matvec(velocity)) * (1 + 1e-9)",
        LONG,
        "DeNOC kinetic energy off by 1e-9 relative",
    ),
    Mutant(
        "rk4-third-stage",
        "gimwatch/simulation/simulate.py|gimwatch/simulation/integrators.py",
        "v + 0.5 * dt * a2",
        "v + 0.5 * dt * a1",
        ("tests/test_simulate.py", "-k", "converge"),
        "RK4's third stage from the first slope (order drops)",
    ),
    Mutant(
        "denoc-potential-sign",
        "gimwatch/denoc/model.py",
        "potential = -float(self.tree.mass[1:] @",
        "potential = float(self.tree.mass[1:] @",
        LONG,
        "DeNOC's gravity potential with the wrong sign",
    ),
    # --- Lanczos ---
    Mutant(
        "lanczos-stops-at-1e-3",
        "gimwatch/metrics/tracker/extremes.py",
        "settings = TrackerSettings(rtol=rtol,",
        "settings = TrackerSettings(rtol=max(rtol, 1e-3),",
        ("tests/test_longchain.py", "-k", "lanczos or closed_forms"),
        "the O(n) path's κ (one tracker sample) certified at 1e-3 only",
    ),
    Mutant(
        "lanczos-30-products",
        "gimwatch/metrics/tracker/extremes.py",
        "max_products=max_products,",
        "max_products=30,",
        ("tests/test_longchain.py", "-k", "lanczos or closed_forms"),
        "the O(n) path's κ cut at 30 products per end",
    ),
    Mutant(
        "arpack-tol-1e-3",
        "gimwatch/bench/krylov_peers.py",
        'eigsh(operator, k=1, which="LA", v0=v0, tol=tol)',
        'eigsh(operator, k=1, which="LA", v0=v0, tol=max(tol, 1e-3))',
        ("tests/test_krylov_peers.py",),
        "ARPACK stopping at 1e-3",
    ),
    Mutant(
        "lanczos-projection-asymmetric",
        "gimwatch/metrics/tracker/krylov.py",
        "        H[m, j] = dot\n",
        "        H[m, j] = 0.5 * dot\n",
        (*TRACKER, "tests/test_longchain.py", "-k", "lanczos or closed_forms or tracker"),
        "the engine's projected matrix halved below the diagonal (no longer A's projection)",
    ),
    Mutant(
        "watch-lanczos-tol-1e-1",
        "gimwatch/metrics/registry.py",
        "TOL: ClassVar[float] = 1e-3",
        "TOL: ClassVar[float] = 1e-1",
        ("tests/test_watch.py",),
        "the watch's Lanczos κ at 10 % accuracy",
    ),
    # --- stress bounds ---
    Mutant(
        "stress-constant-1e5",
        "gimwatch/stress/suite.py",
        "return 10.0 * math.sqrt(nv)",
        "return 1e5 * math.sqrt(nv)",
        STRESS_QUICK,
        "C of C·κ·eps made 10⁴ times larger",
    ),
    Mutant(
        "stress-bound-ignored",
        "gimwatch/stress/suite.py",
        "e is not None and np.isfinite(e) and e <= bound",
        "e is not None and np.isfinite(e) and e <= 1e5 * bound",
        STRESS_QUICK,
        "the suite's pass check ignores its bound",
    ),
    Mutant(
        "stress-gim-check-loose",
        "gimwatch/stress/suite.py",
        "GIM_RTOL = 1e-10",
        "GIM_RTOL = 1e-2",
        STRESS_QUICK,
        "the suite accepts a DeNOC M off by 1 %",
    ),
    Mutant(
        "stress-drift-limit-loose",
        "gimwatch/stress/suite.py",
        "ENERGY_DRIFT_LIMIT = 1e-8",
        "ENERGY_DRIFT_LIMIT = 1e-2",
        STRESS_QUICK,
        "the suite accepts a 1 % energy drift",
    ),
    Mutant(
        "stress-simulation-loose",
        "gimwatch/stress/suite.py",
        'table["integrator"] = {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10}',
        'table["integrator"] = {"method": "DOP853", "rtol": 1e-6, "atol": 1e-6}',
        STRESS_QUICK,
        "the suite's 5 s simulations at 1e-6 instead of 1e-10",
    ),
    # --- watch sampling ---
    Mutant(
        "watch-alarm-every-sample",
        "gimwatch/watch/watch.py",
        "if above and not self._alarm_on:",
        "if above:",
        ("tests/test_watch.py",),
        "an alarm on every sample above the threshold, not on the crossing",
    ),
    Mutant(
        "watch-alarm-never-rearms",
        "gimwatch/watch/watch.py",
        "self._alarm_on = above",
        "self._alarm_on = self._alarm_on or above",
        ("tests/test_watch.py",),
        "the alarm never re-arms after the metric falls back below the threshold",
    ),
    Mutant(
        "watch-scaled-recalibrates",
        "gimwatch/metrics/registry.py",
        "        if not self.estimator.calibrated:  # t0",
        "        self.estimator = conditioning.ScaledDiagonalRatio()\n"
        "        if not self.estimator.calibrated:  # t0",
        ("tests/test_watch.py",),
        "αδ recalibrated at every sample (then it equals κ, tuned after the fact)",
    ),
    # --- second round (issue 28): manifold integration, model values, the κ tracker, the
    # watch sources, results folders, estimator statistics. The old text of each is one line
    # (or two) chosen where a rewrite is unlikely; `--list` shows the file of each. ---
    Mutant(
        "manifold-reanchor-forgotten",
        "gimwatch/simulation/integrators.py",
        "                        reanchored = True\n",
        "                        reanchored = False\n",
        TRAJECTORY,
        "a mid-piece re-anchoring ends the piece: the sample gets the state of an earlier time",
    ),
    Mutant(
        "manifold-local-rate-dropped",
        "gimwatch/simulation/integrators.py",
        "return np.concatenate((chart.local_rate(anchor, dq, v_), a))",
        "return np.concatenate((v_, a))",
        TRAJECTORY,
        "adaptive pieces integrate dΔq/dt = v, not J(Δq)⁻¹ v (wrong off the anchor)",
    ),
    Mutant(
        "manifold-reanchor-velocity-stale",
        "gimwatch/simulation/integrators.py",
        "                v = solver.y[nv:].copy()\n",
        "                v = solver.y[nv:].copy() if not reanchored else v\n",
        TRAJECTORY,
        "after a mid-piece re-anchoring the next piece starts from the old velocity",
    ),
    Mutant(
        "manifold-rk4-stage-rate",
        "gimwatch/simulation/integrators.py",
        "d2 = chart.local_rate(q, 0.5 * dt * d1, v2)",
        "d2 = v2",
        ("tests/test_manifold.py", "-k", "rk4"),
        "RK4's second stage takes v as the local rate (second order on SE(3))",
    ),
    Mutant(
        "urdf-negative-mass-accepted",
        "gimwatch/model/urdf_values.py",
        "    if mass < 0:\n",
        "    if mass < -1e3:\n",
        URDF_VALUES,
        "a negative mass passes the URDF value checks",
    ),
    Mutant(
        "urdf-psd-checks-largest-moment",
        "gimwatch/model/urdf_values.py",
        "if moments[0] < -(INERTIA_ATOL_KG_M2",
        "if moments[-1] < -(INERTIA_ATOL_KG_M2",
        URDF_VALUES,
        "the positive semi-definiteness test looks at the largest principal moment",
    ),
    Mutant(
        "urdf-triangle-wrong-pair",
        "gimwatch/model/urdf_values.py",
        "return bool(a + b >= c * (1 - INERTIA_RTOL) - 1e-12)",
        "return bool(a + c >= b * (1 - INERTIA_RTOL) - 1e-12)",
        URDF_VALUES,
        "the triangle inequality tested on the wrong pair (never doubtful)",
    ),
    Mutant(
        "urdf-products-misread",
        "gimwatch/model/urdf_values.py",
        'for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")',
        'for key in ("ixx", "ixy", "ixz", "iyy", "izz", "iyz")',
        URDF_VALUES,
        "iyz and izz swapped when the inertia is read for the checks",
    ),
    Mutant(
        # urdf_values' own lower > upper check is unreachable since urdf_quirks reads a
        # reversed range as "unlimited" first (Bullet's convention): the live code is here
        "urdf-limit-order-ignored",
        "gimwatch/model/urdf_quirks.py",
        "    if not lower <= upper:\n",
        "    if not lower <= upper + 1e3:\n",
        URDF_VALUES,
        "a joint limit with lower > upper is neither read as unlimited nor warned about",
    ),
    Mutant(
        "tracker-kato-temple-loose",
        "gimwatch/metrics/tracker/krylov.py|gimwatch/metrics/tracker_krylov.py",
        "estimate = rnorm2 / (theta * gap) / (1.0 + sigma * theta)",
        "estimate = 1e-4 * rnorm2 / (theta * gap) / (1.0 + sigma * theta)",
        TRACKER,
        "the Kato–Temple error estimate 1e4 too small: the tracker stops before rtol",
    ),
    Mutant(
        "tracker-gap-without-second",
        "gimwatch/metrics/tracker/krylov.py|gimwatch/metrics/tracker_krylov.py",
        "gap = theta - second if m >= 2 else abs(theta)",
        "gap = abs(theta)",
        TRACKER,
        "the gap rule ignores the second Ritz value (optimistic near a crossing)",
    ),
    Mutant(
        "watch-source-free-rotation",
        "gimwatch/watch/sources.py|gimwatch/metrics/watch_sources.py",
        "M[lin, :] = R.T @ M[lin, :]",
        "M[lin, :] = R @ M[lin, :]",
        ("tests/test_watch_sources.py",),
        "a MuJoCo free joint's linear block rotated the wrong way on one side",
    ),
    Mutant(
        "watch-source-armature-kept",
        "gimwatch/watch/sources.py|gimwatch/metrics/watch_sources.py",
        "M[np.diag_indices(self.nv)] -= self._armature",
        "M[np.diag_indices(self.nv)] -= 0.0 * self._armature",
        ("tests/test_watch_sources.py",),
        "armature=False leaves MuJoCo's armature in the full M",
    ),
    Mutant(
        "watch-source-diagonal-sign",
        "gimwatch/watch/sources.py|gimwatch/metrics/watch_sources.py",
        "if not np.all(np.isfinite(d) & (d > 0)):",
        "if not np.all(np.isfinite(d)):",
        ("tests/test_watch_sources.py",),
        "a held diagonal with a zero or negative entry is accepted",
    ),
    Mutant(
        "swap-no-rollback",
        "gimwatch/output/swap.py",
        "            except BaseException:\n"
        "                os.rename(old, target)\n                raise\n",
        "            except BaseException:\n                raise\n",
        SWAP,
        "a failed second rename leaves the previous results folder moved aside",
    ),
    Mutant(
        "swap-stale-takes-user-folders",
        "gimwatch/output/swap.py",
        "or path == keep or not is_temporary(path):",
        "or path == keep:",
        HOSTILE,
        "the clean-up after a killed writer removes a user's folder named like a staging one",
    ),
    Mutant(
        "swap-staging-record-ignored",
        "gimwatch/output/swap.py",
        "return stat.S_ISDIR(os.lstat(path).st_mode) and stat.S_ISREG(",
        "return stat.S_ISDIR(os.lstat(path).st_mode) or stat.S_ISREG(",
        HOSTILE,
        "any folder counts as a writer's temporary, with or without the record",
    ),
    Mutant(
        "swap-stale-name-contains",
        "gimwatch/output/swap.py",
        "if not entry.name.startswith(prefixes) or",
        "if not any(part in entry.name for part in (STAGING, OLD)) or",
        HOSTILE,
        "the clean-up takes any recorded folder whose name contains the parts (another "
        "results folder's live staging folder)",
    ),
    Mutant(
        "swap-stale-old-not-restored",
        "gimwatch/output/swap.py",
        "if complete and not os.path.lexists(target):",
        "if complete and not os.path.lexists(target) and False:",
        HOSTILE,
        "a previous folder a killed writer moved aside is deleted, not put back",
    ),
    Mutant(
        "swap-previous-unrecorded",
        "gimwatch/output/swap.py",
        "    mark_staging(target)\n",
        "",
        ("tests/test_faults_folders_killed.py",),
        "a writer killed after the exchange leaves the previous folder hidden for good",
    ),
    Mutant(
        "swap-restored-keeps-record",
        "gimwatch/output/swap.py",
        "                    (target / STAGING_RECORD).unlink(missing_ok=True)\n",
        "",
        HOSTILE,
        "a previous folder put back keeps the staging record (the next fallback swap fails)",
    ),
    Mutant(
        "atomic-temporary-left",
        "gimwatch/output/atomic.py",
        "            Path(tmp).unlink(missing_ok=True)\n",
        "            pass\n",
        ATOMIC,
        "a failed atomic write leaves its temporary file behind",
    ),
    Mutant(
        "atomic-copy-not-rename",
        "gimwatch/output/atomic.py",
        "            os.replace(tmp, path)\n",
        "            path.write_bytes(Path(tmp).read_bytes())\n",
        ATOMIC,
        "a successful write copies its temporary into place (not atomic) and leaves it behind",
    ),
    Mutant(
        "estimator-pearson-linear",
        "gimwatch/metrics/estimator_quality.py",
        "scipy.stats.pearsonr(np.log(delta), np.log(kappa))",
        "scipy.stats.pearsonr(delta, kappa)",
        ESTIMATOR,
        "Pearson of δ with κ, not of their logarithms",
    ),
    Mutant(
        "estimator-t0-in-errors",
        "gimwatch/metrics/estimator_quality.py",
        "return np.abs(scaled[1:] - kappa[1:]) / kappa[1:]",
        "return np.abs(scaled - kappa) / kappa",
        ESTIMATOR,
        "the relative errors include t0, where αδ = κ by construction",
    ),
    Mutant(
        "estimator-max-scaled-is-delta",
        "gimwatch/metrics/estimator_quality.py",
        "max_scaled_diagonal_ratio=float(np.max(scaled))",
        "max_scaled_diagonal_ratio=float(np.max(delta))",
        ESTIMATOR,
        "the largest αδ reported is the largest δ",
    ),
    Mutant(
        "estimator-correlation-two-samples",
        "gimwatch/metrics/estimator_quality.py",
        "if delta.size < 3 or np.ptp(delta) == 0",
        "if delta.size < 2 or np.ptp(delta) == 0",
        ESTIMATOR,
        "correlations reported from two samples (always ±1)",
    ),
    Mutant(
        "reference-planar-gim-15-digits",
        "gimwatch/stress/reference_planar.py",
        '        with mpmath.workdps(self.dps):\n            D = self._parts(q, None)["D"]',
        '        with mpmath.workdps(15):\n            D = self._parts(q, None)["D"]',
        PRECISION,
        "the planar reference computes M(q) at 15 digits",
    ),
    Mutant(
        "reference-tree-aba-30-digits",
        "gimwatch/stress/reference_tree.py",
        "        with mpmath.workdps(self.dps):\n            X, S = self._joints(q)\n"
        "            twist, bias, _ = self._velocities(X, S, v)\n            U, Dinv",
        "        with mpmath.workdps(30):\n            X, S = self._joints(q)\n"
        "            twist, bias, _ = self._velocities(X, S, v)\n            U, Dinv",
        PRECISION,
        "the tree reference's ABA runs at 30 digits whatever its dps (its 100-digit run too)",
    ),
    Mutant(
        "reference-tree-rnea-30-digits",
        "gimwatch/stress/reference_tree.py",
        "        with mpmath.workdps(self.dps):\n            X, S = self._joints(q)\n"
        "            twist, bias, _ = self._velocities(X, S, v)\n            acc, force",
        "        with mpmath.workdps(30):\n            X, S = self._joints(q)\n"
        "            twist, bias, _ = self._velocities(X, S, v)\n            acc, force",
        PRECISION,
        "the tree reference's RNEA runs at 30 digits whatever its dps",
    ),
)


def _copy_tree(destination: Path) -> Path:
    shutil.copytree(ROOT, destination, ignore=shutil.ignore_patterns(*IGNORED), symlinks=True)
    return destination


def _run_tests(tree: Path, tests: tuple[str, ...], timeout: float) -> tuple[str, float]:
    env = {**os.environ, "PYTHONPATH": str(tree), "PYTHONDONTWRITEBYTECODE": "1"}
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider"]
    command += ["-p", "no:xdist", *tests]
    start = time.perf_counter()
    for _attempt in range(2):  # once more if killed by a signal from outside (shared machine)
        try:
            result = subprocess.run(
                command, cwd=tree, env=env, capture_output=True, text=True, timeout=timeout
            )
        except subprocess.TimeoutExpired:
            return "timeout", time.perf_counter() - start
        if result.returncode >= 0:
            break
    elapsed = time.perf_counter() - start
    if result.returncode == 0:
        return "passed", elapsed
    if result.returncode == 1:
        return "failed", elapsed
    return f"error (pytest exit {result.returncode})", elapsed


def _apply(tree: Path, mutant: Mutant) -> tuple[Path, str] | None:
    """Patch the copy: (the file, its original text), or None when the patch is stale."""
    for candidate in mutant.paths:
        path = tree / candidate
        if not path.exists():
            continue
        text = path.read_text()
        if text.count(mutant.old) == 1:
            path.write_text(text.replace(mutant.old, mutant.new))
            return path, text
    return None


def _run_mutant(tree: Path, mutant: Mutant, timeout: float) -> tuple[str, float]:
    applied = _apply(tree, mutant)
    if applied is None:
        return "stale", 0.0
    path, original = applied
    try:
        outcome, elapsed = _run_tests(tree, mutant.tests, timeout)
    finally:
        path.write_text(original)
    status = {"failed": "caught", "passed": "MISSED", "timeout": "timeout"}.get(outcome, outcome)
    return status, elapsed


def main(argv: list[str] | None = None) -> int:
    """Run the mutants (all, or the named ones) and print caught/missed per mutant."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ids", nargs="*", help="mutant ids (default: all)")
    parser.add_argument("--jobs", type=int, default=2, help="mutants run in parallel")
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds per test run")
    parser.add_argument("--list", action="store_true", help="list the mutants and exit")
    parser.add_argument(
        "--match", default="", help="only the mutants whose id or file contains this text"
    )
    args = parser.parse_args(argv)
    known = {m.id: m for m in MUTANTS}
    if len(known) != len(MUTANTS):
        raise SystemExit("duplicate mutant ids")
    if args.list:
        for m in MUTANTS if not args.match else [m for m in MUTANTS if args.match in m.id]:
            print(f"{m.id:34} {m.paths[0]:40} {m.why}")
        return 0
    unknown = [i for i in args.ids if i not in known]
    if unknown:
        print(f"unknown mutant ids: {', '.join(unknown)}", file=sys.stderr)
        return 2
    selected = [known[i] for i in args.ids] if args.ids else list(MUTANTS)
    selected = [m for m in selected if args.match in m.id or args.match in m.path]
    if not selected:
        print(f"no mutant matches {args.match!r}", file=sys.stderr)
        return 2
    jobs = max(1, min(args.jobs, len(selected)))
    with tempfile.TemporaryDirectory(prefix="gimwatch-mutation-") as scratch:
        trees = [_copy_tree(Path(scratch) / f"tree{k}") for k in range(jobs)]
        subsets = sorted({m.tests for m in selected})
        print(f"baseline: {len(subsets)} test subsets on the unmutated copy", file=sys.stderr)
        with ThreadPoolExecutor(jobs) as pool:
            outcomes = pool.map(
                lambda k: _run_tests(trees[k % jobs], subsets[k], args.timeout),
                range(len(subsets)),
            )
            for tests, (outcome, elapsed) in zip(subsets, outcomes, strict=True):
                print(f"  {' '.join(tests)}: {outcome} in {elapsed:.0f} s", file=sys.stderr)
                if outcome != "passed":
                    print(f"baseline {' '.join(tests)}: {outcome}; fix the tests first")
                    return 1
        queue = list(enumerate(selected))
        results: dict[int, tuple[str, float]] = {}

        def worker(k: int) -> None:
            while queue:
                try:
                    index, mutant = queue.pop(0)
                except IndexError:
                    return
                results[index] = _run_mutant(trees[k], mutant, args.timeout)
                status, elapsed = results[index]
                print(f"  {mutant.id}: {status} ({elapsed:.0f} s)", file=sys.stderr)

        with ThreadPoolExecutor(jobs) as pool:
            list(pool.map(worker, range(jobs)))
    print(f"{'mutant':34} {'file':40} {'status':8} {'s':>5}")
    for index, mutant in enumerate(selected):
        status, elapsed = results[index]
        print(f"{mutant.id:34} {mutant.paths[0]:40} {status:8} {elapsed:5.0f}")
    caught = sum(results[i][0] == "caught" for i in results)
    print(f"caught {caught}/{len(selected)} ({100.0 * caught / len(selected):.0f} %)")
    return 0 if caught == len(selected) else 1


if __name__ == "__main__":
    sys.exit(main())
