"""Ctrl-C at the worst moment: the previous good result, or a complete new one; never half.

* ``simulate`` interrupted while integrating writes a complete folder of what it computed
  (status ``interrupted``) in place of the previous one;
* ``simulate`` interrupted while writing leaves the previous folder byte for byte, and no
  staging folder behind;
* ``bench`` interrupted in its second section keeps the first section's tables and a
  report of it.

(``survey``: ``tests/test_cli_survey.py::test_interrupted_survey...`` checks the same.)
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import gimwatch.bench
import gimwatch.simulation.results_folder
from gimwatch.bench import SectionResult, Table
from gimwatch.cli import main
from gimwatch.output import folders, swap
from gimwatch.simulation.simulate import Simulation

SCENE = """robot = "chain:3"
duration = 0.2
sample = 0.01
q = 0.1

[effects.gravity]
vector = [0.0, -9.81, 0.0]

[integrator]
method = "RK4"
dt = 0.001

[watch]
metrics = ["kappa", "diagonal_ratio"]
"""


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


@pytest.fixture
def previous(tmp_path, capsys):
    """A scene file and the good results folder a previous complete run wrote."""
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.replace("duration = 0.2", "duration = 0.05"))
    assert main(["simulate", str(scene), "-o", str(tmp_path / "out")]) == 0
    capsys.readouterr()
    scene.write_text(SCENE)
    return scene, tmp_path / "out", _tree(tmp_path / "out")


def _interrupt_after(monkeypatch, calls: int) -> None:
    original = Simulation.acceleration
    count = 0

    def acceleration(self, t, q, v):
        nonlocal count
        count += 1
        if count > calls:
            raise KeyboardInterrupt
        return original(self, t, q, v)

    monkeypatch.setattr(Simulation, "acceleration", acceleration)


def test_simulate_interrupted_while_integrating_writes_a_complete_folder(
    previous, monkeypatch, capsys
):
    scene, out, before = previous
    assert json.loads(before["summary.json"])["samples"] == 6
    _interrupt_after(monkeypatch, 4 * 95)  # RK4: 4 evaluations a step -> 95 steps, 9 samples
    code = main(["simulate", str(scene), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 130 and "interrupted; results so far were written" in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["samples"] == 10
    with np.load(out / "trajectory.npz", allow_pickle=False) as arrays:
        np.testing.assert_allclose(arrays["t"], np.arange(10) * 0.01, rtol=0, atol=1e-12)
        assert arrays["q"].shape == (10, 3) and arrays["watch_kappa"].shape == (10,)
    csv = (out / "trajectory.csv").read_text().splitlines()
    assert len(csv) == 1 + 10
    assert [p.name for p in out.parent.iterdir() if p.name.startswith(".out")] == []


@pytest.mark.parametrize("stage", ["npz", "plots"])
def test_simulate_interrupted_while_writing_keeps_the_previous_folder(
    previous, monkeypatch, capsys, stage
):
    scene, out, before = previous

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    target = "write_npz_atomic" if stage == "npz" else "_plots"
    monkeypatch.setattr(gimwatch.simulation.results_folder, target, interrupted)
    code = main(["simulate", str(scene), "-o", str(out)])
    assert code == 130 and capsys.readouterr().err.endswith("gimwatch: interrupted\n")
    assert _tree(out) == before
    assert sorted(p.name for p in out.parent.iterdir()) == ["out", "scene.toml"]


@pytest.mark.parametrize("call", ["chmod", "rename"])
def test_simulate_failing_to_write_keeps_the_previous_folder(previous, monkeypatch, capsys, call):
    """A full disk while writing a file, or a refused rename: one line, the old folder stays."""
    scene, out, before = previous
    original = getattr(folders.os, call)

    def broken(*args, **kwargs):
        if call == "rename" and ".gimwatch-staging-" not in Path(args[0]).name:
            # only the rename of the new folder into place fails, not putting the old one back
            return original(*args, **kwargs)
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(swap, "exchange", lambda a, b: False)  # the two-rename fallback
    monkeypatch.setattr(folders.os, call, broken)
    code = main(["simulate", str(scene), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.endswith(f"gimwatch: error: {out}: cannot be written (No space left on device)\n")
    assert _tree(out) == before
    assert sorted(p.name for p in out.parent.iterdir()) == ["out", "scene.toml"]


def test_bench_interrupted_in_a_section_keeps_the_finished_ones(tmp_path, monkeypatch, capsys):
    table = Table("fake_timings", ("n", "seconds"))
    table.add(n=4, seconds=1.5e-6)
    finished = SectionResult(
        name="conditioning",
        title="Conditioning cost vs n",
        tables=[table],
        figures=[],
        markdown="the finished section",
        headline="",
        summary={},
    )

    class FakeSection:
        def __init__(self, outcome):
            self.outcome = outcome

        def run(self, context):
            if isinstance(self.outcome, BaseException):
                raise self.outcome
            return self.outcome

    modules = {
        "gimwatch.bench.conditioning_cost": FakeSection(finished),
        "gimwatch.bench.estimators": FakeSection(KeyboardInterrupt()),
    }
    monkeypatch.setattr(gimwatch.bench.importlib, "import_module", modules.__getitem__)
    out = tmp_path / "bench"
    code = main(["bench", "conditioning", "estimators", "--quick", "-o", str(out)])
    assert code == 130 and capsys.readouterr().err.endswith("gimwatch: interrupted\n")
    assert (out / "fake_timings.csv").read_text().splitlines() == ["n,seconds", "4,1.5e-06"]
    report = (out / "report.md").read_text()
    assert "the finished section" in report and "Estimator quality" not in report
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == [folders.MARKER]


def test_demo_interrupted_keeps_the_finished_chains_and_says_so(tmp_path):
    from gimwatch.demo import run_demo

    def progress(n):
        if n == 3:

            def interrupt(fraction):
                raise KeyboardInterrupt

            return interrupt
        return None

    out = tmp_path / "demo"
    report = run_demo(out, lengths=(2, 3, 4), duration_s=0.1, animate=None, progress=progress)
    text = report.read_text()
    assert "**Stopped early**: chain_3 ended as `interrupted` at t = 0 s" in text
    assert json.loads((out / "chain_2" / "summary.json").read_text())["status"] == "completed"
    assert json.loads((out / "chain_3" / "summary.json").read_text())["status"] == "interrupted"
    assert not (out / "chain_4").exists() and (out / "fig2_chain_2.png").exists()
    marker = json.loads((out / folders.MARKER).read_text())
    assert {"chain_2", "chain_3", "report.md", "fig2_chain_2.png"} <= set(marker["files"])


def test_bench_keeps_the_files_it_does_not_rewrite(tmp_path, monkeypatch, capsys):
    """The folder's README and the tables of sections not run this time stay."""
    out = tmp_path / "bench"
    out.mkdir()
    (out / "README.md").write_text("about these benchmarks")
    (out / "other_section.csv").write_text("n\n1\n")
    folders.write_marker(out, "bench", {"other_section.csv"})
    table = Table("fake_timings", ("n", "seconds"))
    table.add(n=4, seconds=1.5e-6)
    result = SectionResult(name="conditioning", title="Conditioning cost vs n", tables=[table])

    class FakeSection:
        @staticmethod
        def run(context):
            assert context.output != out  # sections write into the staging folder
            return result

    monkeypatch.setattr(
        gimwatch.bench.importlib,
        "import_module",
        {"gimwatch.bench.conditioning_cost": FakeSection}.__getitem__,
    )
    assert main(["bench", "conditioning", "--quick", "-o", str(out)]) == 0
    capsys.readouterr()
    assert (out / "README.md").read_text() == "about these benchmarks"
    assert (out / "other_section.csv").read_text() == "n\n1\n"
    marker = json.loads((out / folders.MARKER).read_text())
    assert "README.md" not in marker["files"] and "other_section.csv" in marker["files"]
    assert {"fake_timings.csv", "report.md", "summary.json"} <= set(marker["files"])
