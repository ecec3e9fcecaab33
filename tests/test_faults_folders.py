"""Faults while results folders are written: signals, concurrent writers, foreign folders.

Every case ends in one of two ways: exit status 2 and one line naming the path, or the
previous or the new result intact (its marker lists exactly its entries), with nothing else
beside it (no staging folder, no lock file) and nothing of the user's deleted.

Signals are sent at chosen moments: the command runs under ``tests/fault_pause.py``, which
makes it print ``gimwatch: paused at PHASE`` and wait for the signal, so no test depends on
timing.
"""

from __future__ import annotations

import fcntl
import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gimwatch
import gimwatch.survey.report
from gimwatch.cli import main
from gimwatch.cli._signals import SignalLatch
from gimwatch.output.folders import MARKER, ResultsFolder

ROOT = Path(gimwatch.__file__).resolve().parents[1]
FAULT_PAUSE = Path(__file__).with_name("fault_pause.py")  # python -m gimwatch, paused at a phase
SCENE = """robot = "chain:3"
duration = {duration}
sample = 0.01
q = 0.1

[effects.gravity]
vector = [0.0, -9.81, 0.0]

[integrator]
method = "RK4"
dt = 0.002

[dynamics]
backend = "{backend}"

[watch]
metrics = ["kappa", "diagonal_ratio"]
"""
SURVEY = ["survey", "chain:2", "chain:3", "--samples", "4", "--chunk-size", "2", "--workers", "1"]


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def _complete(folder: Path) -> dict:
    """The marker of a complete results folder (its entries are exactly those it lists)."""
    marker = json.loads((folder / MARKER).read_text())
    assert sorted(p.name for p in folder.iterdir() if p.name != MARKER) == marker["files"]
    return marker


def _scene(tmp_path: Path, duration: float = 0.2, backend: str = "aba") -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(duration=duration, backend=backend))
    return path


@pytest.fixture(autouse=True)
def _sigint_not_ignored():
    """Run as if from a terminal even when started in the background (``cmd &`` in a script,
    nohup, some CI runners), where SIGINT arrives ignored: Python then installs no
    KeyboardInterrupt handler, and the commands started here would inherit the SIG_IGN (a
    caught signal is reset to the default across exec, an ignored one is not)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.fixture
def old_simulation(tmp_path, capsys):
    """A scene (longer than the previous run's) and the results folder of a previous run."""
    scene = _scene(tmp_path, duration=0.04)
    assert main(["simulate", str(scene), "-o", str(tmp_path / "out")]) == 0
    capsys.readouterr()
    _scene(tmp_path, duration=0.3)
    return scene, tmp_path / "out", _tree(tmp_path / "out")


def _start(args: list[str], phase: str, cwd: Path) -> subprocess.Popen:
    """``python -m gimwatch ARGS`` paused at ``phase`` (returns once it says so)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    process = subprocess.Popen(
        [sys.executable, str(FAULT_PAUSE), phase, *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    # wait for the state, not a time: read stderr up to the pause line (a loaded machine may
    # let a progress bar or a warning come first); end of stream means it never paused
    before = []
    while (line := process.stderr.readline()) != f"gimwatch: paused at {phase}\n":
        if not line:
            process.kill()
            _, rest = process.communicate()
            pytest.fail(f"no pause at {phase}: {''.join(before) + rest}")
        before.append(line)
    return process


def _signalled(process: subprocess.Popen, signum: int) -> tuple[int, list[str]]:
    process.send_signal(signum)
    _, err = process.communicate(timeout=300)
    return process.returncode, err.splitlines()


STATUS = {signal.SIGINT: 130, signal.SIGTERM: 143}


@pytest.mark.parametrize(
    ("phase", "signum"),
    [
        ("compute", signal.SIGINT),
        ("compute", signal.SIGTERM),
        ("write", signal.SIGTERM),
        ("swap", signal.SIGINT),
    ],
)
def test_signal_during_simulate_leaves_a_complete_new_folder(old_simulation, phase, signum):
    scene, out, before = old_simulation
    process = _start(["simulate", str(scene), "-o", str(out)], phase, scene.parent)
    code, err = _signalled(process, signum)
    assert code == STATUS[signum], err
    assert err[-1] == "gimwatch: interrupted; results so far were written", err
    assert not any("Traceback" in line for line in err), err
    assert _complete(out)["writer"] == "simulate" and _tree(out) != before
    summary = json.loads((out / "summary.json").read_text())
    # at "compute" the run stopped after its first step (t = 0 kept); later, it had completed
    assert (summary["status"], summary["samples"]) == (
        ("interrupted", 1) if phase == "compute" else ("completed", 31)
    )
    with np.load(out / "trajectory.npz", allow_pickle=False) as arrays:
        assert arrays["t"].size == summary["samples"]
    assert sorted(p.name for p in out.parent.iterdir()) == ["out", "scene.toml"]


def test_ctrl_c_in_a_compiled_denoc_simulation_stops_cleanly(tmp_path):
    scene = _scene(tmp_path, duration=0.3, backend="denoc")
    process = _start(["simulate", str(scene), "-o", "out"], "compute", tmp_path)
    code, err = _signalled(process, signal.SIGINT)
    assert code == 130 and err[-2:] == [
        f"wrote {tmp_path.resolve() / 'out'}",
        "gimwatch: interrupted; results so far were written",
    ], err
    assert not any("Error" in line or "Traceback" in line for line in err), err
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["status"] == "interrupted"


@pytest.mark.parametrize(
    ("phase", "signum"), [("startup", signal.SIGTERM), ("import", signal.SIGINT)]
)
def test_signal_during_start_up_is_one_line(tmp_path, phase, signum):
    scene = _scene(tmp_path)
    process = _start(["simulate", str(scene), "-o", "out"], phase, tmp_path)
    code, err = _signalled(process, signum)
    assert (code, err) == (STATUS[signum], ["gimwatch: interrupted"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


@pytest.fixture
def old_survey(tmp_path, capsys):
    out = tmp_path / "survey"
    assert main([*SURVEY[:2], *SURVEY[3:], "-o", str(out)]) == 0  # chain:2 only
    capsys.readouterr()
    return out, _tree(out)


@pytest.mark.parametrize(
    ("phase", "signum", "robots"),
    [("compute", signal.SIGTERM, ["chain_2"]), ("write", signal.SIGINT, ["chain_2", "chain_3"])],
)
def test_signal_during_survey_leaves_a_complete_new_folder(old_survey, phase, signum, robots):
    out, before = old_survey
    process = _start([*SURVEY, "-o", str(out)], phase, out.parent)
    code, err = _signalled(process, signum)
    assert code == STATUS[signum] and err[-1] == "gimwatch: interrupted; partial results written"
    assert not any("Traceback" in line for line in err), err
    assert _complete(out)["writer"] == "survey"
    record = json.loads((out / "survey.json").read_text())
    assert [r["robot"] for r in record["robots"]] == robots
    assert record["interrupted"] == (phase == "compute")
    assert (out / "report.md").read_bytes() != before["report.md"]
    assert sorted(p.name for p in out.parent.iterdir()) == ["survey"]


def test_full_disk_while_writing_a_survey_keeps_the_old_one(old_survey, monkeypatch, capsys):
    out, before = old_survey

    def full(path, text):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(gimwatch.survey.report, "write_text_atomic", full)
    assert main([*SURVEY, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == f"gimwatch: error: {out}: cannot be written (No space left on device)\n"
    assert _tree(out) == before
    assert sorted(p.name for p in out.parent.iterdir()) == ["survey"]


def test_file_size_limit_while_writing_keeps_the_old_folder(old_simulation):
    """RLIMIT_FSIZE: the write fails with EFBIG (Python ignores SIGXFSZ) part way through."""
    scene, out, before = old_simulation
    limit = 8000  # the new trajectory.npz is larger; the marker and summary are not

    def small_disk():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    done = subprocess.run(
        [sys.executable, "-m", "gimwatch", "simulate", str(scene), "-o", str(out)],
        env=dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_CACHE_DIR=str(scene.parent / "nb")),
        preexec_fn=small_disk,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2, done.stderr
    # a first run may note that it compiles (its cache file is skipped under the limit)
    lines = [x for x in done.stderr.splitlines() if not x.startswith("gimwatch: compiling")]
    assert lines == [f"gimwatch: error: {out}: cannot be written (File too large)"]
    assert _tree(out) == before
    assert sorted(p.name for p in out.parent.iterdir() if p.name != "nb") == ["out", "scene.toml"]


def test_a_second_writer_refuses_while_the_first_one_runs(old_simulation, capsys):
    scene, out, _ = old_simulation
    first = _start(["simulate", str(scene), "-o", str(out)], "compute", scene.parent)
    try:
        assert main(["simulate", str(scene), "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert err == (
            f"gimwatch: error: {out}: is being written by another gimwatch process "
            f"(pid {first.pid}); nothing was written: wait for it to finish or give another "
            "folder\n"
        )
    finally:
        code, _ = _signalled(first, signal.SIGINT)
    assert code == 130
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    _complete(out)
    assert sorted(p.name for p in out.parent.iterdir()) == ["out", "scene.toml"]


def test_a_killed_writer_leaves_nothing_the_next_one_keeps(old_simulation, capsys):
    scene, out, _ = old_simulation
    process = _start(["simulate", str(scene), "-o", str(out)], "write", scene.parent)
    process.kill()  # SIGKILL: no clean-up possible
    process.communicate()
    left = sorted(p.name for p in out.parent.iterdir() if p.name.startswith(".out."))
    assert [n.split("gimwatch-")[1][:4] for n in left] == ["lock", "stag"], left
    assert main(["simulate", str(scene), "-o", str(out)]) == 0
    capsys.readouterr()
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"
    assert sorted(p.name for p in out.parent.iterdir()) == ["out", "scene.toml"]


def test_a_lock_held_by_hand_is_respected(tmp_path, capsys):
    scene = _scene(tmp_path)
    with open(tmp_path / ".out.gimwatch-lock", "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        assert main(["simulate", str(scene), "-o", str(tmp_path / "out")]) == 2
    assert "is being written by another gimwatch process; " in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("where", ["named", "cwd"])
def test_a_folder_of_user_files_is_refused_and_kept(tmp_path, monkeypatch, capsys, where):
    scene = _scene(tmp_path)
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "thesis.tex").write_text("years of work")
    monkeypatch.chdir(notes)
    target = "." if where == "cwd" else str(notes)
    assert main(["simulate", str(scene), "-o", target]) == 2
    assert capsys.readouterr().err == (
        f"gimwatch: error: {target}: is a folder that is not empty and not a gimwatch results "
        f"folder (no {MARKER}); nothing was written: give a new or empty folder\n"
    )
    assert _tree(notes) == {"thesis.tex": b"years of work"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes", "scene.toml"]


def test_user_files_added_to_a_results_folder_are_kept(old_simulation, capsys):
    scene, out, _ = old_simulation
    (out / "my_notes.md").write_text("mine")
    (out / "extra").mkdir()
    (out / "extra" / "data.txt").write_text("also mine")
    assert main(["simulate", str(scene), "-o", str(out)]) == 0
    capsys.readouterr()
    assert (out / "my_notes.md").read_text() == "mine"
    assert (out / "extra" / "data.txt").read_text() == "also mine"
    marker = json.loads((out / MARKER).read_text())
    assert "my_notes.md" not in marker["files"] and "summary.json" in marker["files"]


@pytest.mark.parametrize("command", ["chain", "simulate"])
def test_a_fifo_is_never_replaced(tmp_path, capsys, command):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    args = ["chain", "2"] if command == "chain" else ["simulate", str(_scene(tmp_path))]
    assert main([*args, "-o", str(fifo)]) == 2
    what = "not a regular file; refusing to replace it: give a file name"
    if command == "simulate":
        what = "not a folder; give a folder name"
    assert capsys.readouterr().err == f"gimwatch: error: {fifo}: is a FIFO (named pipe), {what}\n"
    assert fifo.is_fifo()


def test_a_symbolic_link_is_followed_not_replaced(tmp_path, capsys):
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "chain.urdf").write_text("old")
    link = tmp_path / "work" / "chain.urdf"
    link.parent.mkdir()
    link.symlink_to(outside / "chain.urdf")
    assert main(["chain", "2", "-o", str(link)]) == 0
    capsys.readouterr()
    assert link.is_symlink() and "<robot" in (outside / "chain.urdf").read_text()
    assert sorted(p.name for p in outside.iterdir()) == ["chain.urdf"]


def test_a_folder_under_a_regular_file_is_one_line_and_leaves_nothing(tmp_path, capsys):
    scene = _scene(tmp_path)
    (tmp_path / "a").write_text("a file")
    assert main(["simulate", str(scene), "-o", str(tmp_path / "a" / "b" / "out")]) == 2
    err = capsys.readouterr().err
    assert (
        err == f"gimwatch: error: {tmp_path / 'a'}: is a file, not a folder; give a folder name\n"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "scene.toml"]
    assert (tmp_path / "a").read_text() == "a file"


def test_parents_made_for_a_survey_that_wrote_nothing_are_removed(tmp_path, capsys):
    out = tmp_path / "new" / "deeper" / "survey"
    assert main(["survey", "no-such-robot", "--samples", "2", "-o", str(out)]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_read_only_parent_leaves_nothing(tmp_path, capsys):
    """Where permissions bind (not as root): a read-only parent is one line, no stray folder."""
    if os.geteuid() == 0:
        pytest.skip("root writes into read-only folders; the test above covers root")
    scene = _scene(tmp_path)
    parent = tmp_path / "ro"
    parent.mkdir()
    parent.chmod(0o555)
    try:
        assert main(["simulate", str(scene), "-o", str(parent / "x" / "out")]) == 2
        assert "cannot be written (Permission denied)" in capsys.readouterr().err
        assert list(parent.iterdir()) == []
    finally:
        parent.chmod(0o755)


def test_results_folder_without_commit_leaves_nothing(tmp_path):
    with ResultsFolder(tmp_path / "a" / "out", writer="test") as folder:
        (folder.staging / "x.txt").write_text("x")
    assert list(tmp_path.iterdir()) == []


def test_latch_notes_signals_while_deferred_and_raises_at_the_check():
    latch = SignalLatch()
    assert latch.install()
    try:
        with latch.deferred("hard"):
            signal.raise_signal(signal.SIGTERM)
            signal.raise_signal(signal.SIGINT)
            assert latch.pending and latch.signum == signal.SIGTERM
            with pytest.raises(KeyboardInterrupt):
                latch.check()
            assert not latch.pending
            with pytest.raises(KeyboardInterrupt):
                signal.raise_signal(signal.SIGINT)  # a third signal: the user insists
        assert latch.exit_status == 143
    finally:
        latch.uninstall()
    assert latch.install()
    try:
        with latch.deferred("soft"):
            signal.raise_signal(signal.SIGINT)  # the first one is noted
            with pytest.raises(KeyboardInterrupt):
                signal.raise_signal(signal.SIGINT)  # the second one stops the write
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)
        assert latch.exit_status == 130
    finally:
        latch.uninstall()
