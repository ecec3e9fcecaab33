"""A writer killed with SIGKILL at the moment of the swap: nothing stays hidden for good.

After ``renameat2(RENAME_EXCHANGE)`` the staging path holds the previous folder. It used to
carry no staging record, so the next writer's clean-up skipped it and the previous results
stayed under ``.NAME.gimwatch-staging-*`` forever. Now it carries the record: the next writer
removes it (the swap was complete), or puts it back when nothing is at the folder's name.
The moment is reached by running the command under ``tests/fault_pause.py`` (phase ``swap``).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

import gimwatch
from gimwatch.cli import main
from gimwatch.output.folders import MARKER
from gimwatch.output.swap import STAGING_RECORD, remove_stale

ROOT = Path(gimwatch.__file__).resolve().parents[1]
SCENE = """robot = "chain:2"
duration = {duration}
sample = 0.01
q = 0.1

[integrator]
method = "RK4"
dt = 0.005
"""


def _tree(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def _hidden(parent: Path) -> list[str]:
    kinds = (".out.gimwatch-staging-", ".out.gimwatch-old-")
    return sorted(p.name for p in parent.iterdir() if p.name.startswith(kinds))


def _killed_at_swap(scene: Path, out: Path) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    launcher = Path(__file__).with_name("fault_pause.py")
    process = subprocess.Popen(
        [sys.executable, str(launcher), "swap", "simulate", str(scene), "-o", str(out)],
        cwd=scene.parent,
        env=env,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
    )
    while (line := process.stderr.readline()) != "gimwatch: paused at swap\n":
        if not line:
            process.kill()
            pytest.fail("the writer never reached the swap: " + process.communicate()[1])
    process.send_signal(signal.SIGKILL)
    process.communicate(timeout=120)
    assert process.returncode == -signal.SIGKILL


@pytest.fixture
def killed(tmp_path, capsys):
    """A previous folder, then a writer killed between the exchange and the deletion."""
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.format(duration=0.02), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["simulate", str(scene), "-o", str(out)]) == 0
    (out / "my_notes.txt").write_text("the user's", encoding="utf-8")
    previous = _tree(out)
    scene.write_text(SCENE.format(duration=0.05), encoding="utf-8")
    _killed_at_swap(scene, out)
    capsys.readouterr()
    return scene, out, previous


def test_the_killed_writers_new_folder_is_complete_and_the_previous_one_findable(killed):
    _, out, previous = killed
    (hidden,) = _hidden(out.parent)  # the previous results, under the staging name
    left = _tree(out.parent / hidden)
    assert left.pop(STAGING_RECORD) and left == previous  # recognisable as a writer's
    assert (out / MARKER).is_file() and not (out / STAGING_RECORD).exists()
    assert (out / "my_notes.txt").read_text(encoding="utf-8") == "the user's"
    assert _tree(out) != previous


def test_the_next_writer_clears_what_the_killed_one_left(killed, capsys):
    scene, out, _ = killed
    assert main(["simulate", str(scene), "-o", str(out)]) == 0, capsys.readouterr().err
    assert _hidden(out.parent) == [], "the previous results stayed hidden"
    assert (out / MARKER).is_file() and not (out / STAGING_RECORD).exists()
    assert (out / "my_notes.txt").read_text(encoding="utf-8") == "the user's"


def test_the_previous_folder_is_put_back_when_nothing_took_its_place(killed):
    _, out, previous = killed
    for path in out.iterdir():
        path.unlink()
    out.rmdir()
    remove_stale(out, keep=out.parent / "none", marker=MARKER)  # as the next writer does
    assert _tree(out) == previous and _hidden(out.parent) == []
