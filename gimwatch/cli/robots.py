"""List the robots gimwatch can load by name: every example-robot-data robot, with nv.

Each robot is loaded (a fraction of a second for all of them) to report its number of
velocity coordinates nv with the base every command gives it by default: example-robot-data's
(a free-flyer for legged robots, humanoids and drones, as ``example_robot_data.load`` builds
them; ``--fixed`` fixes it), fixed for the others. Robots with no joint when fixed are listed
with a floating base; robots that cannot be loaded are listed with the reason.
``chain:N`` (the paper's rod chain) and URDF or MJCF paths are accepted wherever a ROBOT is.
"""

from __future__ import annotations

import argparse
import warnings

from gimwatch.cli._format import table
from gimwatch.cli._records import add_output_arguments, csv_text, json_text

NAME = "robots"
#: ``--csv`` columns.
CSV_COLUMNS = ("name", "nv", "base", "source", "problem")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    add_output_arguments(parser, what="robots")


def robot_rows() -> list[dict]:
    """One row per example-robot-data robot: name, nv, base, source, problem ("" if none)."""
    from gimwatch.errors import GimwatchError
    from gimwatch.model.example_robots import example_robot_names
    from gimwatch.model.robots import load_robot

    rows = []
    for name in example_robot_names():
        row: dict[str, object] = {"name": name, "nv": None, "base": "", "source": ""}
        row["problem"] = ""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # suspicious inertias are analyze's business
            for floating in (None, True):  # the default base; a free-flyer if it has no joint
                try:
                    robot = load_robot(name, floating=floating)
                except GimwatchError as exc:
                    row["problem"] = str(exc)
                    continue
                row.update(
                    nv=robot.nv,
                    base="floating" if robot.free_base else "fixed",
                    source=robot.source,
                    problem="" if floating is None else "no joint with a fixed base",
                )
                break
        rows.append(row)
    return rows


def run(args: argparse.Namespace) -> int:
    """Load every robot and print the list."""
    rows = robot_rows()
    if args.json:
        print(json_text({"robots": rows}))
    elif args.csv:
        print(csv_text(rows, CSV_COLUMNS))
    else:
        headers = ["name", "nv", "base", "source / problem"]
        print(
            table(
                headers,
                [
                    [r["name"], r["nv"], r["base"], r["problem"] or _short(r["source"])]
                    for r in rows
                ],
            )
        )
        print(
            f"\n{sum(r['nv'] is not None for r in rows)} of {len(rows)} robots load; "
            "also accepted: chain:N (the paper's rod chain) and URDF or MJCF paths"
        )
    return 0


def _short(source: str) -> str:
    """The path below example-robot-data's ``robots/`` folder, when it is there."""
    marker = "/robots/"
    return source.split(marker, 1)[1] if marker in source else source
