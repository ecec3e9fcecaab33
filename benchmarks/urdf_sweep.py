"""A sweep over every URDF on this machine: loaded, exact against MuJoCo, or refused and why.

Run: ``python benchmarks/urdf_sweep.py [FOLDER ...]`` -> benchmarks/urdf_sweep.csv and a
count per outcome on stdout. Without folders it reads the URDFs that installed packages ship
(example-robot-data's robots, MuJoCo's test data) under the running Python's prefix.

Each file is read by ``load_robot`` (fixed base). A loaded robot's M(q), Pinocchio's CRBA,
is compared at 3 seeded random q with MuJoCo's ``mj_fullM`` of its own URDF import of the
*raw* file (shapes stripped, exact inertias; `gimwatch.model.mujoco_model.compile_urdf`);
where MuJoCo's importer refuses the raw file, of gimwatch's normalised text (column
``mujoco_input``). "exact" is a worst relative error ≤ 1e-12. A refused file gets a reason
class a user can act on (`REASONS`); "other" would be a class to add.
"""

from __future__ import annotations

import csv
import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin

from gimwatch.errors import GimwatchError
from gimwatch.model.mujoco_model import MujocoRefusal, compile_urdf, pinocchio_mass_matrix
from gimwatch.model.robot_files import read_robot_file
from gimwatch.model.robots import load_robot

EXACT = 1e-12
#: (pattern in the one-line error, the class: what the user does about it)
REASONS = [
    (r"no degree of freedom|nv = 0", "no moving joint with a fixed base: load it with --floating"),
    (r"xacro", "unexpanded xacro: run xacro first"),
    (r"is not defined|cycle|not connected|two parent", "links and joints not a tree: fix the link"),
    (r"has no <link>", "no <link> at all: not a robot description"),
    (r"not supported by gimwatch", "unsupported joint type (planar/floating): rewrite the joint"),
    (
        r"not positive semi-definite|mass must be >= 0",
        "impossible inertia on a moving link: fix its <inertial>",
    ),
    (r"namespace prefix", "a URDF element with a namespace prefix: remove the prefix"),
    (r"decimal comma", "decimal comma in a number: write a decimal point"),
    (r"deeper than Pinocchio", "a chain too deep for Pinocchio's parser: use DeNOC"),
    (r"more than the \d+ gimwatch reads", "too many links: raise $GIMWATCH_MAX_LINKS"),
    (r"Pinocchio cannot build", "urdfdom refuses the file: the reason is quoted"),
    (r"must be|is missing|has no", "a malformed or missing value: the element is named"),
]


def reason_class(message: str) -> str:
    for pattern, kind in REASONS:
        if re.search(pattern, message):
            return kind
    return "other"


def default_files() -> list[Path]:
    site = Path(np.__file__).resolve().parents[1]
    return sorted(site.rglob("*.urdf"))


def _worst_error(robot, mj_model) -> float:
    rng = np.random.default_rng(0)
    data, worst = robot.model.createData(), 0.0
    for _ in range(3):
        q = pin.randomConfiguration(
            robot.model, -np.pi * np.ones(robot.nq), np.pi * np.ones(robot.nq)
        )
        q = np.where(np.isfinite(q), q, rng.uniform(-1, 1, robot.nq))
        M = pin.crba(robot.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        M_mj = pinocchio_mass_matrix(robot, mj_model, q)
        worst = max(worst, float(np.abs(M_mj - M).max() / np.abs(M).max()))
    return worst


def sweep_one(path: Path) -> dict:
    row = {
        "file": str(path),
        "outcome": "",
        "nv": "",
        "warnings": 0,
        "mujoco_input": "",
        "mujoco_rel_err": "",
        "reason": "",
        "message": "",
    }
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            robot = load_robot(path)
        except GimwatchError as exc:
            message = str(exc).replace(str(path), "FILE")
            row.update(outcome="refused", reason=reason_class(message), message=message[:160])
            return row
    row.update(nv=robot.nv, warnings=len(caught))
    if robot.nv == 0:
        row.update(outcome="refused", reason=reason_class("nv = 0"))
        return row
    for kind, text in (("raw", read_robot_file(path)), ("normalised", robot.urdf_xml)):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                mj_model = compile_urdf(text, spec=str(path))
        except (MujocoRefusal, Exception) as exc:  # MuJoCo's importer may refuse the raw text
            row["message"] = f"MuJoCo ({kind}): {str(exc).replace(str(path), 'FILE')[:160]}"
            continue
        if mj_model.nv != robot.nv:
            row["message"] = f"MuJoCo ({kind}) nv = {mj_model.nv}, gimwatch nv = {robot.nv}"
            continue
        error = _worst_error(robot, mj_model)
        row.update(mujoco_input=kind, mujoco_rel_err=f"{error:.3g}")
        row["outcome"] = "exact" if error <= EXACT else "differs"
        return row
    why = "triangle inequality" if "A + B >= C" in row["message"] else "its inertia check"
    row["outcome"] = f"loaded; MuJoCo's importer refuses ({why})"
    return row


def main(folders: list[str]) -> None:
    files = (
        sorted({p for f in folders for p in Path(f).rglob("*.urdf")})
        if folders
        else default_files()
    )
    rows = [sweep_one(path) for path in files]
    site = Path(np.__file__).resolve().parents[1]
    for row in rows:  # machine-independent names: relative to site-packages where inside it
        if Path(row["file"]).is_relative_to(site):
            row["file"] = str(Path(row["file"]).relative_to(site))
    out = Path(__file__).with_suffix(".csv")
    with out.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.DictWriter(stream, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    counts: dict[str, int] = {}
    for row in rows:
        key = row["outcome"] + (f" ({row['reason']})" if row["reason"] else "")
        counts[key] = counts.get(key, 0) + 1
    print(f"{len(rows)} URDF files")
    for key, count in sorted(counts.items(), key=lambda item: -item[1]):
        print(f"{count:4d}  {key}")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
