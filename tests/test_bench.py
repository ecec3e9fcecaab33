import csv
import importlib
import importlib.util
import io
import json

import pytest

from gimwatch.bench import SECTIONS, Table, run_bench, section_status
from gimwatch.bench.report import README_END, README_START, update_readme
from gimwatch.bench.timing import time_call
from gimwatch.cli import main
from gimwatch.errors import InputError

RUNNABLE = [name for name in SECTIONS if section_status(name) is None]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    code = main(["bench", "all", "--quick", "-o", str(out)])
    return code, out


def test_quick_run_writes_every_file(quick_run):
    code, out = quick_run
    assert code == 0
    assert set(RUNNABLE) == set(SECTIONS)  # simulation, watch and DeNOC have landed
    for name in RUNNABLE:
        module = importlib.import_module(SECTIONS[name].module)
        if not hasattr(module, "COLUMNS"):  # sections with several tables of their own
            assert list(out.glob(f"{name}_*.csv")), name
            continue
        rows = list(csv.DictReader(io.StringIO((out / f"{name}.csv").read_text())))
        assert tuple(rows[0]) == module.COLUMNS
        record = json.loads((out / f"{name}.json").read_text())
        assert record["columns"] == list(module.COLUMNS) and len(record["rows"]) == len(rows)
    pngs = ("conditioning_cost", "estimators_pareto", "accuracy_vs_kappa", "dynamics_cost")
    pngs += ("work_precision", "watch_cost", "denoc_cost")
    for png in (f"{name}.png" for name in pngs):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (out / "report.md").read_text()
    for needle in ("Pinocchio", "NumPy", "SciPy", "CPU:", "date:", "BLAS", "quick run"):
        assert needle in report
    summary = json.loads((out / "summary.json").read_text())
    assert summary["environment"]["blas_threads"]["ratio"] > 0
    for name, reason in summary["skipped"].items():
        assert name not in RUNNABLE and reason.startswith("not available")


def test_quick_run_measures_what_it_claims(quick_run):
    _, out = quick_run
    rows = list(csv.DictReader(io.StringIO((out / "conditioning.csv").read_text())))
    exact = [r for r in rows if r["method"] == "kappa_crba_eigvalsh"]
    assert all(float(r["rel_error"]) == 0 for r in exact)
    for r in rows:  # δ is a lower bound of κ; Lanczos at 1e-10 finds κ
        if r["method"].startswith("delta"):
            assert float(r["ratio_to_kappa"]) <= 1
        if r["method"] == "kappa_lanczos_1e-10":
            assert float(r["rel_error"]) < 1e-6
    accuracy = list(csv.DictReader(io.StringIO((out / "accuracy.csv").read_text())))
    assert all(float(r["rel_error"]) < 1e-10 for r in accuracy)


def _rows(out, name):
    return list(csv.DictReader(io.StringIO((out / f"{name}.csv").read_text())))


def test_quick_simulation_sections_measure_what_they_claim(quick_run):
    _, out = quick_run
    from gimwatch.simulation.backends import BACKENDS
    from gimwatch.watch.watch import METRICS

    assert {r["backend"] for r in _rows(out, "dynamics")} == set(BACKENDS)
    watches = {r["watch"]: r for r in _rows(out, "watch")}
    assert set(watches) == {"none", "delta", "alpha_delta", "kappa_eig", "kappa_lanczos"}
    assert "kappa_lanczos" in METRICS and float(watches["none"]["sample_us"]) == 0
    assert all(float(r["sample_us"]) > 0 for k, r in watches.items() if k != "none")
    swing = [r for r in _rows(out, "estimators") if r["sweep"] == "swing"]
    assert swing and all(float(r["median_ratio"]) <= 1 for r in swing if r["estimator"] == "delta")
    assert {r["quantity"] for r in _rows(out, "denoc")} >= {"gim", "forward_dynamics"}
    runs = _rows(out, "integrators")
    assert {r["simulator"] for r in runs} == {"gimwatch", "mujoco"}
    # Same URDF, same RK4, same steps: gimwatch and MuJoCo land on the same final state,
    # and halving the step shrinks RK4's error about 16x.
    rk4 = {
        (r["simulator"], float(r["dt_s"])): float(r["error_rad"])
        for r in runs
        if r["method"] == "RK4"
    }
    for (_, dt), error in rk4.items():
        assert error == pytest.approx(rk4[("mujoco", dt)], rel=1e-3)
    assert 8 < rk4[("gimwatch", 0.01)] / rk4[("gimwatch", 0.005)] < 32


def test_unknown_section_is_one_line_exit_2(capsys):
    assert main(["bench", "nonsense", "--quick"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nonsense" in err[0] and "conditioning" in err[0]


def test_unavailable_section_is_refused_by_name(tmp_path):
    missing = [name for name in SECTIONS if section_status(name) is not None]
    if not missing:  # every section has landed: nothing left to refuse
        assert RUNNABLE == list(SECTIONS)
        return
    with pytest.raises(InputError, match=rf"^bench section '{missing[0]}' must be available"):
        run_bench([missing[0]], tmp_path, quick=True)


def test_a_section_whose_package_is_missing_is_skipped_and_refused(monkeypatch, tmp_path):
    # MuJoCo hidden from the finder, as on an install without the [peers] extra
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "mujoco" else real(name, *a)
    )
    needs = {name for name in SECTIONS if section_status(name) is not None}
    assert needs == {"watch_mujoco", "watch_overhead"}
    assert "mujoco" in section_status("watch_mujoco")
    with pytest.raises(InputError, match=r"^bench section 'watch_mujoco' must be available"):
        run_bench(["watch_mujoco"], tmp_path / "out", quick=True)
    assert not (tmp_path / "out").exists()


def test_every_section_needing_mujoco_imports_it():
    # the declared requirement is the truth: a section that imports MuJoCo declares it
    for name, section in SECTIONS.items():
        source = importlib.util.find_spec(section.module).origin
        text = open(source, encoding="utf-8").read()
        uses = "import mujoco" in text or "from gimwatch.model.mujoco_model" in text
        peer_optional = "mujoco_peer.available()" in text
        assert uses == ("mujoco" in section.requires) or peer_optional, name


def test_table_rejects_rows_without_its_columns():
    table = Table("t", ("a", "b"))
    table.add(b=2, a=1)
    assert table.rows == [{"a": 1, "b": 2}]
    with pytest.raises(KeyError, match="missing"):
        table.add(a=1)


def test_time_call_counts_calls():
    calls = []
    timing = time_call(lambda: calls.append(1), warmup=2, repeats=3, min_round_s=0.0)
    assert timing.number == 1 and len(calls) == 2 + 1 + 3
    assert timing.median_s >= timing.min_s >= 0


def test_readme_block_is_replaced_between_markers(tmp_path, quick_run):
    _, out = quick_run
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\n{README_START}\nold\n{README_END}\n\nafter\n")
    env = json.loads((out / "summary.json").read_text())["environment"]
    update_readme(readme, env, [], out)
    text = readme.read_text()
    assert "old" not in text and "after" in text and "make bench" in text
    readme.write_text("no markers")
    with pytest.raises(InputError, match="markers"):
        update_readme(readme, env, [], out)
