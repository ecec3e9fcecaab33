"""Numbers in README.md and docs/ come from a committed file or from a test's constants.

Generated blocks (the bench block, the survey table, the stress table) must be what their
generator makes of the committed files; quoted figures are looked up in the file they come
from (benchmarks/*.csv, *.json) or in the constants of the test that checks them. A figure
that moved or changed fails here with the page and the text it looked for: update the page,
the file, or this test — never only one of them.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import test_longchain
import test_simulate
import test_stress

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"


def _text(page: str) -> str:
    return (ROOT / page).read_text(encoding="utf-8")


def _find(page: str, pattern: str) -> re.Match:
    """The first match of ``pattern`` (whitespace-tolerant) in ``page``, or a clear failure."""
    flexible = re.sub(r"(\\ )+|\s+", r"\\s+", pattern)
    match = re.search(flexible, _text(page))
    assert match, f"{page}: no text matching {pattern!r} (the figure moved: update this test)"
    return match


def _csv(name: str) -> list[dict]:
    with (BENCH / name).open(newline="") as handle:
        return list(csv.DictReader(handle))


def _figure(text: str) -> float:
    return float(text.replace(",", "").replace("−", "-"))


# --- generated blocks -------------------------------------------------------------------------


def _table_rows(text: str, first_cells: set[str]) -> list[str]:
    return [
        line.strip()
        for line in text.splitlines()
        if line.startswith("| ") and line.split("|")[1].strip() in first_cells
    ]


def test_stress_table_in_the_docs_is_the_committed_one():
    committed = _text("benchmarks/stress.md")
    cases = set(test_stress.PUBLISHED_ERRORS)
    rows = _table_rows(committed, cases)
    assert len(rows) == len(cases)
    assert _table_rows(_text("docs/findings/hard-cases.md"), cases) == rows
    # and the q̈ errors the stress tests hold the code to are the committed ones
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        published = tuple(None if c == "–" else float(c) for c in cells[3:6])
        assert published == test_stress.PUBLISHED_ERRORS[cells[0]], cells[0]
        drift = test_stress.PUBLISHED_DRIFT.get(cells[0])
        if drift is not None:
            assert float(cells[8]) == drift, cells[0]


def test_survey_block_is_generated_from_the_committed_survey(tmp_path):
    spec = importlib.util.spec_from_file_location(
        "update_survey_page", BENCH / "survey" / "update_readme.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    (tmp_path / "docs" / "findings").mkdir(parents=True)
    shutil.copytree(BENCH / "survey", tmp_path / "benchmarks" / "survey")
    page = "docs/findings/survey.md"
    shutil.copy(ROOT / page, tmp_path / page)
    assert module.main(tmp_path) == 0
    assert (tmp_path / page).read_text() == _text(page), "run `make survey` or its update step"


def test_bench_block_comes_from_the_committed_bench_run():
    env = json.loads((BENCH / "summary.json").read_text())["environment"]
    header = _find("docs/findings/accuracy-costs.md", r"Measured by `make bench` \(([^;]+);")
    assert header.group(1) == env["date"]
    block = _text("docs/findings/accuracy-costs.md")
    for name in ("pinocchio", "numpy", "scipy"):
        assert f"{env[name]}" in block.split("<!-- bench:end -->")[0], name


# --- quoted figures ---------------------------------------------------------------------------


def _kappa_over_4n4(n: int) -> float:
    rows = [r for r in _csv("longchain_kappa.csv") if r["route"] == "matrix_free_lanczos"]
    (row,) = [r for r in rows if int(r["n"]) == n]
    return float(row["kappa_over_4n4"])


def test_long_chain_kappa_figures_are_the_committed_ones():
    # n = 100 and 1,000 from the bench CSV; 10,000 is not in it: the value the Lanczos test
    # checks against the banded closed form (tests/test_longchain.py)
    expected = [round(_kappa_over_4n4(n), 3) for n in (100, 1_000)]
    expected.append(test_longchain.PUBLISHED_KAPPA_OVER_4N4[10_000])
    assert expected[1] == test_longchain.PUBLISHED_KAPPA_OVER_4N4[1_000]
    claims = _find(
        "docs/findings/claims.md",
        r"down to ([\d.]+) \(n = 100\), ([\d.]+) \(1,000\) and ([\d.]+)",
    )
    assert [float(x) for x in claims.groups()] == expected
    long_chains = _find(
        "docs/findings/long-chains.md",
        r"straight chain is ([\d.]+), ([\d.]+), ([\d.]+) at n = 100, 1,000, 10,000",
    )
    assert [float(x) for x in long_chains.groups()] == expected
    readme = _find("README.md", r"… ([\d.]+) \(n = 10,000\)")
    assert float(readme.group(1)) == round(expected[2], 2)


def _numbers(match: re.Match) -> list[float]:
    return [float(x) for x in match.groups()]


def test_simulation_figures_are_the_ones_the_tests_check():
    demo = test_simulate.PUBLISHED_DEMO
    sizes = (4, 10, 20)

    def column(name):
        return [demo[n][name] for n in sizes]

    page = "docs/guide/simulate.md"
    number = r"(\d+(?:\.\d+)?(?:e-\d+)?)"
    three = rf"{number}, {number},\s+{number}"
    assert _numbers(_find(page, rf"relative energy drift {three} \(n = 4, 10, 20\)")) == column(
        "drift"
    )
    assert _numbers(_find(page, rf"worst κ / 4n⁴ = {three}")) == column("worst")
    assert _numbers(_find(page, rf"Pearson\(log δ, log κ\) = {three}")) == column("pearson")
    estimator = _numbers(_find(page, rf"median \|αδ − κ\|/κ = {three} and max {three}"))
    assert estimator == column("median") + column("max")
    claims = "docs/findings/claims.md"
    assert _numbers(_find(claims, rf"κ/4n⁴ = {three} for n = 4, 10, 20")) == column("worst")
    assert _numbers(_find(claims, rf"Pearson\(log δ, log κ\) = {three}")) == column("pearson")
    assert _numbers(
        _find(claims, rf"median\s+\|αδ − κ\|/κ is {number} \(max {number}\) for the swinging")
    ) == [demo[4]["median"], demo[4]["max"]]
    readme = _numbers(_find("README.md", rf"median error {number} % \(20 links\) to {number} %"))
    assert readme == [100 * demo[20]["median"], 100 * demo[4]["median"]]
    orders = _find(page, r"RK4 (\d+\.\d+)–(\d+\.\d+),\s+semi-implicit Euler (\d+\.\d+)")
    published = test_simulate.PUBLISHED_ORDERS
    rk4, euler = published["RK4"], published["semi-implicit-euler"]
    assert (float(orders.group(1)), float(orders.group(2))) == rk4
    assert float(orders.group(3)) == euler[0] == euler[1]


def test_watch_cost_figures_are_the_committed_ones():
    rows = {r["watch"]: r for r in _csv("cost/watch.csv") if r["n"] == "20"}
    match = _find(
        "docs/guide/simulate.md",
        r"δ costs about (\d+) µs per sample, ([\d.]+) % of a bare step amortized \(κ: ([\d.]+) %",
    )
    sample_us, delta_percent, kappa_percent = (float(x) for x in match.groups())
    assert sample_us == round(float(rows["delta"]["sample_us"]))
    assert delta_percent == round(100 * float(rows["delta"]["amortized"]), 1)
    assert kappa_percent == round(100 * float(rows["kappa_eig"]["amortized"]))


def test_survey_figures_are_the_committed_ones():
    survey = json.loads((BENCH / "survey" / "survey.json").read_text())
    robots = {r["robot"]: r for r in survey["robots"]}
    page = "docs/findings/survey.md"
    wall = _find(page, r"took (\d+) s wall on this 2-core machine \((\d+) runs, (\d+) completed")
    runs = sum(r["trajectories"]["runs"] for r in survey["robots"])
    completed = sum(r["trajectories"]["completed"] for r in survey["robots"])
    assert [int(x) for x in wall.groups()] == [round(survey["wall_time_s"]), runs, completed]
    kinova = _find(page, r"Kinova's zero pose has κ/δ = ([\d.]+) against a median of ([\d.]+)")
    alphas = [r["alpha"] for r in survey["robots"] if r["alpha"] is not None]
    assert float(kinova.group(1)) == round(robots["kinova"]["alpha"])
    assert float(kinova.group(2)) == round(float(np.median(alphas)), 1)


def test_long_chain_simulation_figures_are_the_committed_run():
    summary = json.loads((BENCH / "chain_1000" / "summary.json").read_text())
    match = _find(
        "docs/findings/long-chains.md",
        r"1,000-link swinging chain in ([\d.]+) s wall: ([\d,]+) steps, ([\d,]+) right-hand sides, "
        r"relative energy\s+drift ([\d.e-]+)",
    )
    wall, steps, rhs, drift = (_figure(x) for x in match.groups())
    assert wall == pytest.approx(summary["wall_time_s"], abs=0.05)
    assert steps == summary["steps"] and rhs == summary["rhs_evaluations"]
    assert drift == pytest.approx(summary["energy_drift_relative"], rel=0.05)


def test_dependency_lower_bounds_are_the_pinned_tested_versions():
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            name, version = line.split("==")
            pins[name.lower().replace("_", "-")] = version
    requirements = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        requirements += extra
    for requirement in requirements:
        match = re.fullmatch(r"([A-Za-z0-9_.-]+)(\[[a-z,]+\])?>=([\w.]+)", requirement)
        assert match, f"{requirement}: expected name>=version"
        name = match.group(1).lower().replace("_", "-")
        assert pins.get(name) == match.group(3), (requirement, pins.get(name))


def test_survey_headlines_are_the_committed_survey():
    survey = json.loads((BENCH / "survey" / "survey.json").read_text())
    robots = survey["robots"]
    pearson = [r["pearson_log_delta_log_kappa"] for r in robots]
    pearson = [x for x in pearson if x is not None and np.isfinite(x)]
    below = sum(x < 0.5 for x in pearson)
    readme = _find("README.md", r"\((\d+) of (\d+) below 0\.5\)")
    assert [int(x) for x in readme.groups()] == [below, len(pearson)]
    assert int(_find("README.md", r"on the paper's chains and on (\d+) real robots").group(1)) == (
        len(robots)
    )
    claims = "docs/findings/claims.md"
    match = _find(
        claims,
        r"Across random configurations of (\d+) real robots the median Pearson\s+correlation is "
        r"([\d.]+) \((\d+) above 0\.9\), but (\d+) branched robots",
    )
    assert _numbers(match) == [
        len(pearson),
        round(float(np.median(pearson)), 2),
        sum(x > 0.9 for x in pearson),
        below,
    ]
    errors = [r["alpha_delta_rel_error_median"] for r in robots]
    errors = [x for x in errors if x is not None and np.isfinite(x)]
    match = _find(
        claims,
        r"median error\s+is ([\d.]+) \(median over robots\), but (\d+) of (\d+) robots have median "
        r"errors above 100 %",
    )
    assert _numbers(match) == [
        round(float(np.median(errors)), 2),
        sum(x > 1 for x in errors),
        len(robots),
    ]


def test_cost_and_long_chain_tables_are_the_committed_runs():
    summary = json.loads((BENCH / "summary.json").read_text())
    speedup = summary["sections"]["conditioning"]["speedup_delta_on_vs_kappa_eig"]
    match = _find(
        "docs/findings/claims.md",
        r"The O\(n\) diagonal costs (\d+)× less than κ at n = 200 and (\d+)× less at n = 500",
    )
    assert _numbers(match) == [round(speedup["200"]), round(speedup["500"])]
    page = _text("docs/findings/long-chains.md")
    for row in _csv("longchain_analyze.csv"):
        n = int(row["n"])
        pattern = (
            rf"\| {n:,} \| [^|]+ \| {float(row['wall_s']):.1f} \| "
            rf"{round(float(row['peak_rss_mb']))} \|"
        )
        assert re.search(pattern, page), f"long-chains.md: no row {pattern!r}"


def test_crosscheck_table_is_the_committed_run():
    runs = {
        base: json.loads((BENCH / "crosscheck" / f"{base}.json").read_text())
        for base in ("fixed", "floating")
    }
    page = "docs/guide/crosscheck.md"
    counts = _find(page, r"(\d+) fixed-base and (\d+) floating-base robots, all passed")
    assert _numbers(counts) == [len(runs["fixed"]), len(runs["floating"])]
    assert all(r["passed"] for rows in runs.values() for r in rows)

    def worst(base, key):
        values = [r[key] for r in runs[base] if r[key] is not None]
        return f"{max(values):.2g}"

    rows = {
        r"\| GIM \| `crba` \|": "gim_rel_err",
        r"\| diag GIM, O\(n\) \| diag `crba` \|": "gim_diagonal_rel_err",
        r"\| τ \| `rnea` \|": "tau_rel_err",
        r"\| q̈ backward error [^|]+ \| `aba` \|": "qdd_backward_err",
        r"\| UDUᵀ pivots \| `cholesky.decompose` D \|": "pivots_rel_err",
    }
    for label, key in rows.items():
        match = _find(page, label + r" ([\d.e+-]+) \| ([\d.e+-]+) \|")
        assert list(match.groups()) == [worst("fixed", key), worst("floating", key)], key
    forward = _find(page, r"\| q̈ forward error \| `aba` \| ([\d.e-]+) \((\w+), κ = ([\d.e+]+)\)")
    value, robot, kappa = max(
        (r["qdd_rel_err"], r["robot"], r["kappa_max"])
        for r in runs["fixed"]
        if r["qdd_rel_err"] is not None
    )
    assert forward.groups() == (f"{value:.2g}", robot, f"{kappa:.2g}".replace("+0", ""))


def test_long_chain_step_costs_are_the_committed_run():
    rows = {(int(r["n"]), r["method"]): r for r in _csv("longchain_step.csv")}

    def ratio(n):
        return float(rows[(n, "denoc_compiled")]["ratio_to_aba"])

    def ms(n):
        return 1e3 * float(rows[(n, "denoc_compiled")]["median_s"])

    match = _find(
        "docs/findings/long-chains.md",
        r"Pinocchio ABA = ([\d.]+) at n = 10, ([\d.]+) at n = 100, ([\d.]+) at "
        r"n = 400 \(the\s+largest Pinocchio Data allowed here\); DeNOC alone ([\d.]+) ms at "
        r"n = 1,000 and ([\d.]+) ms at\s+n = 10,000",
    )
    assert _numbers(match) == [
        round(ratio(10), 1),
        round(ratio(100), 1),
        round(ratio(400), 2),
        round(ms(1000), 2),
        round(ms(10000), 1),
    ]


def test_claims_quote_the_stress_table():
    crba_200 = test_stress.PUBLISHED_ERRORS["straight-200"][1]
    match = _find("docs/findings/claims.md", r"\(([\d.e-]+) on a 200-link chain\)")
    assert float(match.group(1)) == float(f"{crba_200:.0e}")
    kappa = max(
        float(row.split("|")[3])
        for row in _table_rows(_text("benchmarks/stress.md"), set(test_stress.PUBLISHED_ERRORS))
        if float(row.split("|")[3]) < 1e15  # tapered-30 (8e19) is past float64's reach
    )
    worst = max(e for row in test_stress.PUBLISHED_ERRORS.values() for e in row[::2] if e)
    straight = max(
        e
        for name, row in test_stress.PUBLISHED_ERRORS.items()
        if name.startswith("straight")
        for e in row[::2]
        if e
    )
    match = _find(
        "docs/findings/claims.md",
        r"stay within\s+([\d.e-]+) \(([\d.e-]+) on straight chains\) up to κ ≈ ([\d.e+]+)",
    )
    assert _numbers(match) == [
        float(f"{worst:.0e}"),
        float(f"{10 ** np.ceil(np.log10(straight)):.0e}"),
        float(f"{kappa:.0e}"),
    ]


def _stress_rows() -> list[str]:
    return _table_rows(_text("benchmarks/stress.md"), set(test_stress.PUBLISHED_ERRORS))


def cell(row: str, index: int) -> float | None:
    """Cell ``index`` of a stress-table row as a float (None for "–")."""
    text = row.strip("|").split("|")[index].strip()
    return None if text == "–" else float(text)


# --- the sample output and robot counts -------------------------------------------------------

SAMPLE_OUTPUT_PAGES = ("README.md", "docs/getting-started.md", "docs/guide/analyze.md")


@pytest.mark.parametrize("page", SAMPLE_OUTPUT_PAGES)
def test_analyze_sample_output_is_what_the_command_prints(page, capsys):
    from gimwatch.cli import main

    assert main(["analyze", "ur5"]) == 0
    printed = capsys.readouterr().out.rstrip("\n")
    block = re.search(r"```text\n\$ gimwatch analyze ur5\n(.*?)\n```", _text(page), re.DOTALL)
    assert block, f"{page}: no `gimwatch analyze ur5` sample output"
    assert block.group(1) == printed, f"{page}:\n{block.group(1)}\n!=\n{printed}"


def test_readme_quotes_the_sample_output():
    from gimwatch.cli import main

    rows = json.loads(_run_json(main, ["analyze", "ur5", "--json"]))["configurations"]
    match = _find("README.md", r"κ is ([\d.]+); δ = ([\d.]+) is a lower bound")
    assert _numbers(match) == [
        round(rows[0]["kappa"], 1),
        round(rows[0]["diagonal_ratio"], 1),
    ]


def _run_json(main, argv) -> str:
    import contextlib
    import io

    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        assert main(argv) == 0
    return buffer.getvalue()


def _urdf_robots() -> list[str]:
    from gimwatch.errors import RobotError
    from gimwatch.model.example_robots import example_robot_names, example_robot_urdf

    names = []
    for name in example_robot_names():
        try:
            example_robot_urdf(name)
        except RobotError:
            continue
        names.append(name)
    return names


def test_robot_counts_are_the_library_and_survey_counts():
    from gimwatch.model.example_robots import example_robot_names

    everything = len(example_robot_names())
    readme = _find("README.md", r"one of the\s+(\d+) robots of example-robot-data")
    assert int(readme.group(1)) == everything
    analyze = _find("docs/guide/analyze.md", r"\((\d+) names in [\d.]+\)[^.]*\. (\d+) load;")
    assert _numbers(analyze) == [everything, len(_urdf_robots())]
    bad = _find("docs/guide/bad-input.md", r"calibrated on the (\d+) URDFs of example-robot-data")
    assert int(bad.group(1)) == len(_urdf_robots())
    surveyed = len(json.loads((BENCH / "survey" / "survey.json").read_text())["robots"])
    for page, pattern in (
        ("README.md", r"\[(\d+) real robots\]\(docs/findings/survey.md\)"),
        ("docs/index.md", r"(\d+) real robots, chains of"),
        ("docs/guide/survey.md", r"What it found on (\d+) robots"),
        ("docs/findings/claims.md", r"but \d+ of (\d+) robots have median"),
    ):
        assert int(_find(page, pattern).group(1)) == surveyed, page
    longest = max(int(r["n"]) for r in _csv("longchain_analyze.csv"))
    assert _figure(_find("docs/index.md", r"chains of ([\d,]+) links").group(1)) == longest


def test_triangle_inequality_warning_count_is_the_robots_that_warn():
    import warnings

    from gimwatch.errors import URDFWarning
    from gimwatch.model.example_robots import example_robot_urdf
    from gimwatch.model.robot_files import read_robot_file
    from gimwatch.model.urdf_text import check_urdf

    warned = []
    for name in _urdf_robots():
        path = example_robot_urdf(name)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            check_urdf(read_robot_file(path), str(path))
        if any(issubclass(w.category, URDFWarning) for w in caught):
            warned.append(name)
    match = _find(
        "docs/guide/bad-input.md", r"a \+ b ≥ c — (\d+) real robots do \(ANYmal, Go1, Allegro"
    )
    assert int(match.group(1)) == len(warned), warned
    for family in ("anymal", "go1", "allegro_right_hand", "tiago"):
        assert family in warned


def test_stated_thresholds_are_the_code_constants():
    from gimwatch.cli._progress import ProgressBar
    from gimwatch.crosscheck import DEFAULT_TOLERANCE
    from gimwatch.model import urdf_values
    from gimwatch.model.robot_files import MAX_URDF_BYTES
    from gimwatch.model.robots import DATA_NV_LIMIT, MAX_TREE_DEPTH
    from gimwatch.simulation.alarm_actions import RTOL_FLOOR
    from gimwatch.simulation.integrators import MIN_STEP_FRACTION
    from gimwatch.stress import reference_planar, reference_tree, suite

    hard = "docs/findings/hard-cases.md"
    assert float(_find(hard, r"CRBA \(relative error ≤ ([\d.e-]+)\)").group(1)) == suite.GIM_RTOL
    assert suite.error_constant(49) == 10 * 7  # "C = 10·√nv"
    (digits,) = {reference_planar.REFERENCE_DIGITS, reference_tree.REFERENCE_DIGITS}
    match = _find(hard, r"C·κ·eps, C = 10·√nv\*\*, of an mpmath reference at (\d+)\s+digits")
    assert int(match.group(1)) == digits
    for page in ("docs/guide/bench.md", "docs/findings/accuracy-costs.md", "README.md"):
        assert int(_find(page, r"against a (\d+)-digit mpmath reference").group(1)) == digits
    drift = _find(hard, r"relative energy drift ≤ ([\d.e-]+) \(10× the worst measured\)")
    assert float(drift.group(1)) == suite.ENERGY_DRIFT_LIMIT
    worst = max(cell(row, 8) for row in _stress_rows() if cell(row, 8) is not None)
    assert round(np.log10(suite.ENERGY_DRIFT_LIMIT / worst)) == 1, worst
    assert int(_find(hard, r"\(the limit is `DATA_NV_LIMIT` = (\d+)\)").group(1)) == DATA_NV_LIMIT
    assert (
        int(_find("docs/findings/long-chains.md", r"Above nv = (\d+) \(`DATA_NV_LIMIT`\)").group(1))
        == DATA_NV_LIMIT
    )
    assert int(_find("docs/guide/analyze.md", r"above nv = (\d+), or with").group(1)) == (
        DATA_NV_LIMIT
    )
    floor = _find(hard, r"rtol ← max\(rtol₀ · threshold / estimate, ([\d.e-]+)\)")
    assert float(floor.group(1)) == RTOL_FLOOR
    collapse = _find(hard, r"size collapses below ([\d.e-]+) × duration")
    assert float(collapse.group(1)) == MIN_STEP_FRACTION
    depth = _find("docs/findings/long-chains.md", r"chains deeper than\s+([\d,]+) links")
    assert _figure(depth.group(1)) == MAX_TREE_DEPTH
    crosscheck = _find("docs/guide/crosscheck.md", r"within the tolerance\s+\(([\d.e-]+)\)")
    assert float(crosscheck.group(1)) == DEFAULT_TOLERANCE
    assert f"[--tolerance {DEFAULT_TOLERANCE:.0e}]" in _text("docs/guide/cli.md")
    inertia = _find(
        "docs/guide/bad-input.md", r"below −\(([\d.e-]+) kg m² \+ ([\d.e-]+) · largest\)"
    )
    assert _numbers(inertia) == [urdf_values.INERTIA_ATOL_KG_M2, urdf_values.INERTIA_RTOL]
    size = _find("docs/guide/bad-input.md", r"files over (\d+) MB")
    assert int(size.group(1)) * 1024 * 1024 == MAX_URDF_BYTES
    delay = _find("docs/guide/simulate.md", r"A progress bar appears on stderr after (\d+) s")
    import inspect

    default = inspect.signature(ProgressBar).parameters["delay_s"].default
    assert float(delay.group(1)) == default


# --- prose around the stress table and the tighten run ----------------------------------------


def _one_digit_up(value: float) -> float:
    """``value`` rounded up to one significant digit (2.4e-12 → 3e-12), as "within" quotes it."""
    exponent = np.floor(np.log10(value))
    return float(f"{np.ceil(value / 10**exponent - 1e-9):.0f}e{exponent:.0f}")


def test_hard_cases_prose_quotes_the_stress_table():
    page = "docs/findings/hard-cases.md"
    rows = {r.strip("|").split("|")[0].strip(): r for r in _stress_rows()}
    aba, crba, denoc, drift = 3, 4, 5, 8
    resolved = [r for r in rows.values() if cell(r, 2) < 1e15]
    recursions = [cell(r, i) for r in rows.values() for i in (aba, denoc) if cell(r, i)]
    match = _find(page, r"both stay within ([\d.e-]+) of the reference up to κ ≈ ([\d.e+]+)")
    assert _numbers(match) == [
        float(f"{max(recursions):.0e}"),
        float(f"{max(cell(r, 2) for r in resolved):.0e}"),
    ]
    match = _find(page, r"\(([\d.e-]+) curled, ([\d.e-]+) straight;")
    assert _numbers(match) == [
        float(f"{cell(rows['curled-500'], denoc):.0e}"),
        float(f"{cell(rows['straight-500'], denoc):.0e}"),
    ]
    match = _find(page, r"O\(n\) path with energy drift below ([\d.e-]+)\)")
    longest = max(cell(rows[c], drift) for c in ("curled-500", "straight-500"))
    assert float(match.group(1)) == _one_digit_up(longest)
    match = _find(page, r"in proportion to κ \(([\d.e-]+) on the 200-link chain\)")
    assert float(match.group(1)) == float(f"{cell(rows['straight-200'], crba):.0e}")
    match = _find(page, r"every method\s+lands within ([\d.e-]+) of mpmath")
    tapered = max(cell(rows["tapered-30"], i) for i in (aba, crba, denoc))
    assert float(match.group(1)) == _one_digit_up(tapered)
    _find(page, r"`tapered-30` \(masses and lengths falling to 1e-6 of the root's\)")
    from gimwatch.stress.cases import CASES

    spec = CASES["tapered-30"].spec
    assert spec.masses_kg[-1] / spec.masses_kg[0] == pytest.approx(1e-6)
    assert spec.lengths_m[-1] / spec.lengths_m[0] == pytest.approx(1e-6)
    properties = (ROOT / "tests" / "test_stress_properties.py").read_text()
    examples = re.search(r"max_examples=(\d+)", properties).group(1)
    chains = _find(page, r"the O\(n\) diagonal on (\d+) random chains")
    assert chains.group(1) == examples


def test_tighten_figures_are_the_committed_run():
    from gimwatch.bench import tighten as tighten_section

    rows = _csv("tighten.csv")
    pairs, ratios = {}, []
    for case in dict.fromkeys(r["case"] for r in rows):
        fixed = sorted(
            (float(r["wall_time_s"]), float(r["error_rad"]))
            for r in rows
            if r["case"] == case and r["mode"] == "fixed"
        )
        (tight,) = [r for r in rows if r["case"] == case and r["mode"] == "tighten"]
        times, errors = np.log([f[0] for f in fixed]), np.log([f[1] for f in fixed])
        same_time = float(np.exp(np.interp(np.log(float(tight["wall_time_s"])), times, errors)))
        pairs[case] = (float(tight["error_rad"]), same_time)
        ratios.append(float(tight["error_rad"]) / same_time)
        assert float(tight["rtol0"]) == tighten_section._START
    page = "docs/findings/hard-cases.md"
    match = _find(page, r"\*\*([\d.]+)–(\d+)× that of a fixed tolerance")
    assert _numbers(match) == [round(min(ratios), 1), round(max(ratios))]
    match = _find(
        page,
        r"\(straight-20: ([\d.e-]+) rad vs ([\d.e-]+); feather root: ([\d.e-]+) vs ([\d.e-]+);\s+"
        r"heavy root: ([\d.e-]+) vs ([\d.e-]+)\)",
    )
    quoted = [(match.group(i), match.group(i + 1)) for i in (1, 3, 5)]
    cases = ("straight-20", "feather-root-12", "heavy-root-12")
    for (tight, fixed), case in zip(quoted, cases, strict=True):
        assert float(tight) == float(f"{pairs[case][0]:.1e}"), case
        assert float(fixed) == float(f"{pairs[case][1]:.1e}"), case
    assert len(pairs) == 3 and "on three hard chains" in " ".join(_text(page).split())
    match = _find(page, r"`tighten` from rtol ([\d.e-]+) with the threshold")
    assert float(match.group(1)) == tighten_section._START


def test_claims_figures_are_the_library_and_demo_values():
    import gimwatch as gw

    demo = test_simulate.PUBLISHED_DEMO
    claims = "docs/findings/claims.md"
    worst = max(abs(demo[n]["worst"] - 1) for n in (10, 20))
    match = _find(claims, r"swinging 10- and 20-link chains is within (\d+) % of 4n⁴")
    assert int(match.group(1)) == round(100 * worst)
    forward, backward = [], []
    for n in (4, 10, 20):
        robot = gw.load_robot(f"chain:{n}")
        record = gw.analyze_configuration(robot, gw.neutral_configuration(robot))
        assert record.diagonal_ratio == pytest.approx(n**3, rel=1e-14)  # "δ = n³ exactly"
        forward.append(record.pivot_ratio_forward)
        backward.append(record.pivot_ratio_backward)
    match = _find(claims, r"grow with κ \(([\d,]+), ([\d,]+), ([\d,]+) for straight n = 4, 10, 20")
    assert [_figure(x) for x in match.groups()] == [
        float(f"{x:.4g}") if x > 1e4 else round(x) for x in forward
    ]
    match = _find(claims, r"gives ([\d.]+) \(n = 4\) to ([\d.]+) for\s+every straight chain")
    assert _numbers(match) == [round(min(backward), 3), round(max(backward), 3)]
    _find(claims, r"δ = n³ exactly for straight")
    readme = _find("README.md", r"κ/4n⁴ = ([\d.]+) \(n = 4\) …")
    assert float(readme.group(1)) == round(demo[4]["worst"], 2)
    serial = _find("README.md", r"\*\*on serial chains\*\*: Pearson\(log δ, log κ\) ≈ ([\d.]+);")
    assert {round(demo[n]["pearson"], 1) for n in (4, 10, 20)} == {float(serial.group(1))}


# --- survey prose -------------------------------------------------------------------------------

SERIAL_ARMS = ("ur3", "ur5", "ur10", "panda", "xarm7", "z1", "bravo7_no_ee", "talos_arm")
BRANCHED = (  # r < 0.5 in the committed survey (baxter's 0.50 is just above)
    "anymal",
    "anymal_c",
    "human",
    "icub",
    "icub_reduced",
    "simple_humanoid",
    "simple_humanoid_classical",
)


def test_survey_prose_is_the_committed_survey():
    from gimwatch.survey.trajectory import TrajectorySettings

    survey = json.loads((BENCH / "survey" / "survey.json").read_text())
    robots = {r["robot"]: r for r in survey["robots"]}
    page = "docs/findings/survey.md"

    def runs(key):
        values = [(r["trajectories"] or {}).get(key) for r in survey["robots"]]
        return [v for v in values if v is not None]

    budget = sorted(
        r["robot"]
        for r in survey["robots"]
        if any(p["status"] == "step-budget" for p in (r["trajectories"] or {}).get("per_run", []))
    )
    match = _find(page, r"(\d+) completed; (\w+), (\w+) and\s+(\w+) hit the step budget")
    assert sorted(match.groups()[1:]) == budget
    match = _find(page, r"r\(log δ, log κ\) ([\d.]+), αδ error median ([\d.]+)\)")
    assert _numbers(match) == [
        round(float(np.median(runs("pearson_log_delta_log_kappa_median"))), 2),
        round(float(np.median(runs("alpha_delta_rel_error_median"))), 3),
    ]
    negative = {
        r["robot"]
        for r in survey["robots"]
        if ((r["trajectories"] or {}).get("pearson_log_delta_log_kappa_median") or 0) < 0
    }
    _find(page, r"\(anymal_c,\s+icub_reduced, simple_humanoid: r < 0;")
    assert negative == {"anymal_c", "icub_reduced", "simple_humanoid"}

    arms = [robots[name] for name in SERIAL_ARMS]
    pearson = min(r["pearson_log_delta_log_kappa"] for r in arms)
    match = _find(page, r"Talos arm\): Pearson r\(log δ, log κ\) ≥ ([\d.]+),")
    assert float(match.group(1)) == np.floor(100 * pearson) / 100
    assert all(r["extreme_dofs"]["min_diagonal_dof"]["frequency"] == 1.0 for r in arms)
    shares = [r["lambda_min_on_min_diagonal"] for r in arms]
    match = _find(page, r"smallest M_ii, in ([\d.]+)–(\d+)% of samples")
    assert _numbers(match) == [np.floor(1000 * min(shares)) / 10, 100 * max(shares)]
    errors = [r["alpha_delta_rel_error_median"] for r in arms]
    match = _find(page, r"αδ is\s+within (\d+)–(\d+)% \(median relative error\)")
    assert _numbers(match) == [round(100 * min(errors)), round(100 * max(errors))]

    below = {
        r["robot"]
        for r in survey["robots"]
        if r["pearson_log_delta_log_kappa"] is not None and r["pearson_log_delta_log_kappa"] < 0.5
    }
    assert below == set(BRANCHED)
    _find(page, r"r < 0.5 for anymal, anymal_c, human, icub,\s+icub_reduced and both")
    _find(page, r"baxter's 0.5 is just above")
    assert (
        round(robots["baxter"]["pearson_log_delta_log_kappa"], 2) == 0.5 and "baxter" not in below
    )
    lowest = min(robots[n]["pearson_log_delta_log_kappa"] for n in BRANCHED)
    assert _figure(_find(page, r"\(down to r = (−[\d.]+)\)").group(1)) == round(lowest, 2)
    shares = [robots[n]["lambda_min_on_min_diagonal"] for n in BRANCHED]
    match = _find(page, r"smallest-M_ii coordinate in only (\d+)–(\d+)% of samples")
    assert _numbers(match) == [round(100 * min(shares)), round(100 * max(shares))]

    icub = robots["icub"]
    match = _find(
        page, r"icub's is numerically singular \(κ = ([\d.e]+)\),\s+so its αδ is off by ([\d.e]+);"
    )
    assert float(match.group(1)) == float(f"{icub['quantiles']['kappa']['max']:.1e}")
    assert float(match.group(2)) == 10 ** np.floor(np.log10(icub["alpha_delta_rel_error_median"]))
    kinova = _find(page, r"\(αδ error\s+×(\d+) median\)")
    assert int(kinova.group(1)) == round(robots["kinova"]["alpha_delta_rel_error_median"])
    _find(page, r"a finger: PR2, TIAGo\), r is undefined")
    assert robots["pr2"]["pearson_log_delta_log_kappa"] is None
    assert robots["tiago"]["pearson_log_delta_log_kappa"] is None

    settings = TrajectorySettings()
    match = _find(page, r"N short simulated runs \(default (\d+) of (\d+) s\)")
    assert _numbers(match) == [settings.count, settings.duration_s]
    match = _find(page, r"c_i = ([\d.]+)/s · M_ii\(q0\)")
    assert float(match.group(1)) == settings.damping_per_s
    match = _find(page, r"DOP853 at rtol ([\d.e-]+), or RK4")
    assert float(match.group(1)) == settings.rtol
    match = _find(page, r"a stiff run stops after (\d+) steps")
    assert int(match.group(1)) == settings.max_steps
    match = _find(page, r"the watch samples κ\s+and δ every ([\d.]+) s")
    assert float(match.group(1)) == settings.sample_s
    from gimwatch.survey.run import DEFAULT_CHUNK_SIZE as chunk

    assert int(_find(page, r"cut into chunks of (\d+)\)").group(1)) == chunk
    assert (
        int(_find(page, r"survey all --fixed --samples (\d+) --trajectory").group(1))
        == (survey["samples_per_robot"])
    )


# --- very long chains ---------------------------------------------------------------------------


def test_ten_thousand_links_are_the_committed_run():
    run = json.loads((BENCH / "straight_10000" / "kappa.json").read_text())
    assert run["n"] == 10_000
    lanczos = run["lanczos"]
    assert lanczos["kappa_over_4n4"] == pytest.approx(lanczos["kappa"] / (4 * 10_000**4))
    # the committed run, the test constant and the pages agree
    assert round(lanczos["kappa_over_4n4"], 3) == test_longchain.PUBLISHED_KAPPA_OVER_4N4[10_000]
    assert float(_find("README.md", r"… ([\d.]+) \(n = 10,000\)").group(1)) == round(
        lanczos["kappa_over_4n4"], 2
    )
    page = "docs/findings/long-chains.md"
    match = _find(
        page, r"restarted ARPACK needs ([\d,]+) products at n = 10⁴ and\s+plain Lanczos ([\d,]+)"
    )
    arpack, plain = (_figure(x) for x in match.groups())
    assert arpack == round(run["arpack"]["products"], -3)
    assert plain == lanczos["products"]
    assert run["arpack"]["kappa"] == pytest.approx(lanczos["kappa"], rel=1e-6)


def test_long_chain_prose_is_the_committed_runs():
    from gimwatch.denoc import DenocModel
    from gimwatch.model.chains import chain_spec

    page = "docs/findings/long-chains.md"
    kappa = {(int(r["n"]), r["route"]): r for r in _csv("longchain_kappa.csv")}
    dense, free = kappa[(4000, "dense_eigvalsh")], kappa[(4000, "matrix_free_lanczos")]
    match = _find(
        page,
        r"At\s+n = 4,000 the dense route gives κ/4n⁴ = ([\d.]+) and λmin = ([\d.]+), the "
        r"matrix-free route ([\d.]+)\s+and ([\d.]+) — the value every n from 500 up converges "
        r"to — in ([\d.]+) s instead of ([\d.]+) s",
    )
    assert _numbers(match) == [
        round(float(dense["kappa_over_4n4"]), 3),
        round(float(dense["lambda_min"]), 4),
        round(float(free["kappa_over_4n4"]), 3),
        round(float(free["lambda_min"]), 4),
        float(f"{float(free['seconds']):.2g}"),
        round(float(dense["seconds"]), 1),
    ]
    products = _find(page, r"\((\d+) products of the tracker's engine, both ends certified\)")
    assert int(products.group(1)) == int(free["products"])
    converged = {
        round(float(r["lambda_min"]), 4)
        for (n, route), r in kappa.items()
        if n >= 500 and route == "matrix_free_lanczos"
    }
    assert converged == {round(float(free["lambda_min"]), 4)}
    eps = np.finfo(float).eps
    match = _find(page, r"\(κ·eps = ([\d.]+) at n ≈ ([\d,]+)\)")
    level, n = float(match.group(1)), _figure(match.group(2))
    assert n == float(f"{(level / (4 * eps)) ** 0.25:.2g}")

    ratios = [test_simulate.PUBLISHED_DEMO[n]["worst"] for n in (4, 10, 20)]
    ratios += [float(r["kappa_over_4n4"]) for r in kappa.values()]
    ratios.append(
        json.loads((BENCH / "straight_10000" / "kappa.json").read_text())["lanczos"][
            "kappa_over_4n4"
        ]
    )
    match = _find(page, r"\(κ/n⁴ ∈\s+\[([\d.]+), ([\d.]+)\]\)")
    assert _numbers(match) == [np.floor(40 * min(ratios)) / 10, np.ceil(40 * max(ratios)) / 10]

    errors = []
    for n in (100, 1_000, 10_000, 100_000):
        diagonal = DenocModel.from_chain(chain_spec(n)).state(np.zeros(n)).diagonal()
        errors.append(abs(diagonal.max() / diagonal.min() / n**3 - 1))
    match = _find(page, r"δ = n³ to ([\d.e-]+)\. Forward dynamics")
    assert float(match.group(1)) == _one_digit_up(max(errors)), errors


def test_pinocchio_data_memory_is_the_committed_measurement():
    rows = _csv("pinocchio_data/memory.csv")
    largest = max(rows, key=lambda r: int(r["n"]))
    n, peak = int(largest["n"]), int(largest["peak_bytes"])
    # n³ growth: the per-n³ bytes of the two largest sizes within 10 %
    per_cube = [int(r["peak_bytes"]) / int(r["n"]) ** 3 for r in rows[-2:]]
    assert per_cube[0] == pytest.approx(per_cube[1], rel=0.1)
    page = "docs/findings/long-chains.md"
    match = _find(
        page,
        r"building one peaks at\s+([\d.]+) GB at n = (\d+), so ≈ ([\d.]+) GB at n = 300 and "
        r"(\d+) GB at 500",
    )
    assert _numbers(match) == [
        round(peak / 1e9, 1),
        n,
        round(peak * (300 / n) ** 3 / 1e9, 1),
        round(peak * (500 / n) ** 3 / 1e9),
    ]
    hard = _find(
        "docs/findings/hard-cases.md", r"At nv = 500 Pinocchio's Data would need ~(\d+) GB"
    )
    assert int(hard.group(1)) == round(peak * (500 / n) ** 3 / 1e9)


# --- guide pages --------------------------------------------------------------------------------


def test_crosscheck_prose_is_the_committed_runs():
    runs = [
        r
        for base in ("fixed", "floating")
        for r in json.loads((BENCH / "crosscheck" / f"{base}.json").read_text())
    ]
    page = "docs/guide/crosscheck.md"
    match = _find(page, r"over every example-robot-data robot \((\d+) states each")
    assert {r["samples"] for r in runs} == {int(match.group(1))}
    icub = [r for r in runs if r["robot"] == "icub"]
    match = _find(
        page,
        r"icub's eyes and neck give κ up to ([\d.e]+) in these runs, where both implementations' "
        r"q̈\s+agree only to ([\d.e-]+) while their backward errors stay below ([\d.e-]+)\.",
    )
    kappa, forward, backward = _numbers(match)
    assert kappa == float(f"{max(r['kappa_max'] for r in icub):.0e}")
    assert forward == float(f"{max(r['qdd_rel_err'] for r in icub):.0e}")
    assert max(r["qdd_backward_err"] for r in icub) < backward
    assert max(r["qdd_backward_err"] for r in icub) > backward / 100
    rows = {(int(r["n"]), r["quantity"]): float(r["ratio"]) for r in _csv("cost/denoc.csv")}
    match = _find(
        page,
        r"forward dynamics costs (\d+)× Pinocchio's ABA at n = 10 \(call overhead\),\s+"
        r"([\d.]+)× at 100 and ([\d.]+)× at 500; the dense GIM, built by the per-depth NumPy "
        r"recursions of\s+Eqs. 11–13, costs (\d+)–(\d+)× CRBA",
    )
    gim = [rows[(n, "gim")] for n in (10, 100, 500)]
    assert _numbers(match) == [
        round(rows[(10, "forward_dynamics")]),
        round(rows[(100, "forward_dynamics")], 1),
        round(rows[(500, "forward_dynamics")], 1),
        round(min(gim)),
        float(f"{max(gim):.0e}"),
    ]


def test_simulate_prose_is_the_demo_and_bench_settings():
    from gimwatch.bench.watch_section import STEPS_PER_SAMPLE
    from gimwatch.demo import paper_chain_table

    page = "docs/guide/simulate.md"
    demo = paper_chain_table(4)
    match = _find(page, r"Measured \(`gimwatch demo`, DOP853 at ([\d.e-]+), (\d+) s\)")
    assert demo["integrator"] == {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10}
    assert _numbers(match) == [demo["integrator"]["rtol"], demo["duration"]]
    over = _find(page, r"overestimates κ by up to ~(\d+)× for the 4-link chain")
    assert int(over.group(1)) == round(1 + test_simulate.PUBLISHED_DEMO[4]["max"])
    watch = _find(page, r"RK4, a sample every\s+(\d+) steps, (\d+) links\)")
    sizes = {int(r["n"]) for r in _csv("cost/watch.csv")}
    assert _numbers(watch) == [STEPS_PER_SAMPLE, max(sizes)]


def test_rod_chain_defaults_are_the_generator_defaults():
    import inspect

    from gimwatch.model.chains import chain_spec

    defaults = inspect.signature(chain_spec).parameters
    mass, length = defaults["mass_kg"].default, defaults["length_m"].default
    for page, pattern in (
        ("docs/getting-started.md", r"chain of N slender\s+rods of ([\d.]+) kg and ([\d.]+) m\)"),
        ("docs/guide/analyze.md", r"chain of N slender rods, ([\d.]+) kg, ([\d.]+) m\)"),
        ("docs/guide/cli.md", r"chain of N slender rods, ([\d.]+) kg, ([\d.]+) m\)"),
        ("docs/findings/accuracy-costs.md", r"Paper chain \(([\d.]+) kg, ([\d.]+) m rods\)"),
    ):
        assert _numbers(_find(page, pattern)) == [mass, length], page


# --- notebooks' prose ---------------------------------------------------------------------------


def _notebook(name: str) -> tuple[str, str]:
    """(markdown, code) of ``notebooks/<name>``, each cell kind joined."""
    cells = json.loads((ROOT / "notebooks" / name).read_text())["cells"]

    def joined(kind):
        return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == kind)

    return joined("markdown"), joined("code")


def test_notebook_prose_states_what_the_code_runs():
    markdown, code = _notebook("chain_lengths.ipynb")
    lengths = tuple(int(x) for x in re.search(r"LENGTHS = \(([\d, ]+)\)", code).group(1).split(","))
    stated = re.search(r"for n = (\d+), (\d+), (\d+) and (\d+) links", markdown)
    assert tuple(int(x) for x in stated.groups()) == lengths
    readme = _find("notebooks/README.md", r"swinging chain for n = (\d+), (\d+), (\d+), (\d+):")
    assert tuple(int(x) for x in readme.groups()) == lengths
    duration = float(re.search(r"duration_s=([\d.]+)", code).group(1))
    assert float(re.search(r"runs are short \((\d+) s\)", markdown).group(1)) == duration

    markdown, code = _notebook("denoc_vs_crba.ipynb")
    samples = {int(x) for x in re.findall(r"samples=(\d+)", code)}
    assert {int(re.search(r"over (\d+) seeded random states", markdown).group(1))} == samples
    assert 'load_robot("chain:4")' in code and "paper's 4-link chain" in markdown

    markdown, code = _notebook("urdf_robots.ipynb")
    masses = re.search(r"chain_spec\((\d+), mass_kg=\[([\d., ]+)\]", code)
    assert int(re.search(r"a (\d+)-link spatial chain", markdown).group(1)) == int(masses.group(1))
    assert len(masses.group(2).split(",")) == int(masses.group(1))


# --- the bench block's tables against the committed CSV files -----------------------------------


def _block_table(heading: str) -> list[dict[str, str]]:
    """The first Markdown table under ``## heading`` in the bench block, as header → cell."""
    block = _text("docs/findings/accuracy-costs.md").split("<!-- bench:start -->")[1]
    section = block.split(f"## {heading}\n", 1)[1].split("\n## ", 1)[0]
    lines = [line for line in section.splitlines() if line.startswith("|")]
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    assert set(lines[1]) <= {"|", "-", ":"}, heading
    return [
        dict(zip(header, (c.strip() for c in line.strip("|").split("|")), strict=True))
        for line in lines[2:]
    ]


def _g3(value: str | float) -> str:
    return f"{float(value):.3g}"


def test_bench_block_tables_are_the_committed_csv_files():
    summary = json.loads((BENCH / "summary.json").read_text())["sections"]
    cost = {(r["n"], r["method"]): r for r in _csv("conditioning.csv")}
    table = _block_table("Conditioning cost vs n")
    assert [row["n"] for row in table] == sorted({n for n, _ in cost}, key=int)
    for row in table:
        for header, value in row.items():
            if header.endswith("(µs)"):
                method = header.removesuffix(" (µs)")
                assert value == _g3(1e6 * float(cost[(row["n"], method)]["median_s"])), header
        speedup = summary["conditioning"]["speedup_delta_on_vs_kappa_eig"][row["n"]]
        assert row["κ-eig / δ-O(n)"] == _g3(speedup)

    estimators = {e["estimator"]: e for e in summary["estimators"]["by_estimator"]}
    keys = ("median_rel_error", "max_rel_error", "min_ratio", "max_ratio", "cost_vs_kappa")
    for row in _block_table("Estimator quality vs cost"):
        cells = list(row.values())
        assert cells[1:] == [_g3(estimators[cells[0]][k]) for k in keys], cells[0]

    accuracy = {(r["family"], r["n"], r["method"]): r for r in _csv("accuracy.csv")}
    table = _block_table("Forward-dynamics accuracy vs κ")
    assert len(table) == len({k[:2] for k in accuracy})
    for row in table:
        key = (row["chain"], row["n"])
        first = accuracy[(*key, "aba")]
        assert [row["κ"], row["κ·eps"]] == [_g3(first["kappa"]), _g3(first["kappa_eps"])]
        for method in ("aba", "crba_pin_cholesky", "crba_cho_solve", "numpy_solve", "denoc"):
            assert row[method] == _g3(accuracy[(*key, method)]["rel_error"]), (key, method)

    dynamics = {(r["n"], r["backend"]): r for r in _csv("dynamics.csv")}
    table = _block_table("Dynamics backends per step")
    assert len(table) == len(dynamics)
    for row in table:
        source = dynamics[(row["n"], row["backend"])]
        assert [row["FD call (µs)"], row["/ aba"], row["note"]] == [
            _g3(source["call_us"]),
            _g3(source["vs_aba"]),
            source["note"],
        ]

    watch = {(r["n"], r["watch"]): r for r in _csv("cost/watch.csv")}
    columns = {
        "step (µs)": "step_us",
        "run overhead": "run_overhead",
        "one sample (µs)": "sample_us",
        "sample / bare step": "sample_vs_step",
        "amortized (1 per 10 steps)": "amortized",
        "sample / aba call": "sample_vs_aba_call",
    }
    table = _block_table("Cost of the watch per step")  # the headline: the largest n's rows
    assert table and {(row["n"], row["watch"]) for row in table} <= set(watch)
    for row in table:
        for header, key in columns.items():
            source = watch[(row["n"], row["watch"])]
            # the block rounds the run's float, the CSV keeps 6 digits: 3 digits either way
            quoted, value = float(row[header]), float(source[key])
            assert quoted == pytest.approx(value, rel=6e-3, abs=1e-12), (row["n"], header)

    denoc = {(r["n"], r["quantity"]): r for r in _csv("cost/denoc.csv")}
    table = _block_table("DeNOC vs Pinocchio cost")
    assert len(table) == len(denoc)
    for row in table:
        source = denoc[(row["n"], row["quantity"])]
        assert [row["DeNOC (µs)"], row["Pinocchio (µs)"], row["DeNOC / Pinocchio"]] == [
            _g3(source["denoc_us"]),
            _g3(source["pinocchio_us"]),
            _g3(source["ratio"]),
        ]

    analyze = _csv("longchain_analyze.csv")
    table = _block_table("Very long chains on the O(n) path")
    assert [[r["n"], r["metrics"], r["wall (s)"], r["peak RSS (MB)"]] for r in table] == [
        [r["n"], r["metrics"], _g3(r["wall_s"]), _g3(r["peak_rss_mb"])] for r in analyze
    ]


def test_bench_block_sentences_are_the_committed_summary():
    summary = json.loads((BENCH / "summary.json").read_text())["sections"]
    page = "docs/findings/accuracy-costs.md"
    accuracy = summary["accuracy"]
    _find(page, r"median and worst over all chains: `")  # methods in order of their median
    match = _find(page, r"`denoc` ([\d.e-]+) / ([\d.e-]+)[;.]")
    assert list(match.groups()) == [
        f"{accuracy['median_error_over_kappa_eps']['denoc']:.2g}",
        f"{accuracy['worst_error_over_kappa_eps']['denoc']:.2g}",
    ]
    acceptance = summary["integrators"]["acceptance"]
    match = _find(
        page,
        r"gimwatch ([\d.]+) s, MuJoCo RK4 ([\d.]+) s, ratio ([\d.]+) \(first measured run at or "
        r"below it: ([\d.]+) s vs ([\d.]+) s, ratio ([\d.]+)\)",
    )
    assert list(match.groups()) == [
        f"{acceptance[k]:.3g}"
        for k in (
            "gimwatch_dop853_interpolated_s",
            "mujoco_rk4_interpolated_s",
            "ratio_interpolated",
            "gimwatch_dop853_measured_s",
            "mujoco_rk4_measured_s",
            "ratio_measured",
        )
    ]
    watch = json.loads((BENCH / "cost" / "summary.json").read_text())["sections"]["watch"]
    match = _find(page, r"= ([\d.]+)% of a bare RK4 \+ ABA step \(([\d.]+) µs\)")
    assert float(match.group(1)) == round(100 * watch["delta_sample_vs_step"], 1)
    match = _find(page, r"watching δ costs under (\d+)% of a bare ABA step")
    assert int(match.group(1)) == round(100 * watch["delta_target"])


# --- remaining prose: settings, exit codes, what the tests run ----------------------------------


def test_exit_statuses_are_the_cli_constants():
    from gimwatch.cli import EXIT_BAD_INPUT, EXIT_CHECK_FAILED, EXIT_INTERRUPTED, EXIT_OK

    codes = [EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED]
    table = _find(
        "docs/guide/cli.md",
        r"\| (\d+) \| ok \|\n\| (\d+) \| a check failed[^\n]*\n\| (\d+) \| bad input[^\n]*\n"
        r"\| (\d+) \| interrupted",
    )
    assert [int(x) for x in table.groups()] == codes
    readme = _find(
        "README.md",
        r"Exit status: (\d+) ok, (\d+) a check failed, (\d+) bad input \([^)]*\), "
        r"(\d+) interrupted",
    )
    assert [int(x) for x in readme.groups()] == codes
    for page in ("docs/guide/simulate.md", "docs/guide/survey.md", "docs/findings/survey.md"):
        assert int(_find(page, r"(?:Ctrl-C \(exit|exits) (\d+)").group(1)) == EXIT_INTERRUPTED


def test_stress_simulation_settings_are_the_suite_code():
    import inspect

    from gimwatch.stress import suite

    source = inspect.getsource(suite.simulate_case)
    dop853 = re.search(r'"method": "DOP853", "rtol": ([\d.e-]+)', source).group(1)
    rk4 = re.search(r'"method": "RK4", "dt": ([\d.e-]+)', source).group(1)
    match = _find(
        "docs/findings/hard-cases.md",
        r"a (\d+) s\s+gravity simulation \(DOP853 at ([\d.e-]+), RK4 at (\d+) ms for floating "
        r"bases\)",
    )
    assert _numbers(match) == [suite.SIMULATION_S, float(dop853), 1e3 * float(rk4)]
    draws = inspect.getsource(suite)
    v = re.search(
        r"v, tau = rng.uniform\(([-\d.]+), ([\d.]+), nv\), rng.uniform\(([-\d.]+), ([\d.]+)", draws
    )
    match = _find(
        "docs/findings/hard-cases.md", r"v ~ U\((−?\d+), (\d+)\), τ ~ U\((−?\d+), (\d+)\)"
    )
    assert [_figure(x) for x in match.groups()] == [float(x) for x in v.groups()]


def test_figures_about_what_the_tests_run_are_the_tests():
    denoc = (ROOT / "tests" / "test_denoc.py").read_text()
    states = re.search(r"load_robot\(name, floating=floating\), samples=(\d+), seed=0", denoc)
    page = "docs/guide/crosscheck.md"
    match = _find(page, r"\(`tests/test_denoc.py`, (\d+) states per robot, both bases\)")
    assert match.group(1) == states.group(1)
    generated = re.search(r'parametrize\("n", \[([\d, ]+)\]\)\ndef test_generated_chains', denoc)
    sizes = [int(x) for x in generated.group(1).split(",")]
    match = _find(page, r"\(planar and spatial, n = (\d+)…(\d+),")
    assert _numbers(match) == [min(sizes), max(sizes)]

    longchain = (ROOT / "tests" / "test_longchain.py").read_text()
    dense = re.search(
        r'parametrize\("n", \[([\d, ]+)\]\)\ndef test_matrix_free_kappa_matches_the_dense',
        longchain,
    )
    mpmath_rel = re.search(
        r"matches_mpmath_at_50_digits\(\):.*?rel=([\d.e-]+)\)", longchain, re.DOTALL
    )
    page = "docs/findings/long-chains.md"
    match = _find(
        page,
        r"planar-chain reference at 50\s+digits \(κ to ([\d.e-]+)\), the dense eigensolver "
        r"\(n ≤ (\d+)\)",
    )
    assert _numbers(match) == [
        float(mpmath_rel.group(1)),
        max(int(x) for x in dense.group(1).split(",")),
    ]
    closed = re.findall(
        r"\((\d[\d_]*), 1e-\d+\)", longchain.split("def test_long_straight_chains")[0]
    )
    largest = re.search(r"n = (\d[\d_]*)\n\s+record = analyze_linear", longchain).group(1)
    closed = [*sorted({int(x.replace("_", "")) for x in closed}), int(largest.replace("_", ""))]
    match = _find(page, r"closed forms at n = ([\d,]+),\s+([\d,]+) and ([\d,]+)\.")
    assert [_figure(x) for x in match.groups()] == closed


def test_startup_and_chain_1000_settings_are_the_committed_runs():
    repeats = {r["case"]: int(r["repeats"]) for r in _csv("startup/startup.csv")}
    page = "docs/getting-started.md"
    match = _find(page, r"\(`gimwatch bench startup`, medians of (\d+) runs,")
    quoted = ("import gimwatch", "import pinocchio", "gimwatch analyze ur5")
    assert {repeats[case] for case in quoted} == {int(match.group(1))}
    _find(page, r"`gimwatch demo` takes [\d.]+ s \(one run\)")
    assert repeats["gimwatch demo"] == 1
    summary = json.loads((BENCH / "chain_1000" / "summary.json").read_text())
    match = _find(
        "docs/findings/long-chains.md",
        r"`gimwatch simulate chain_1000` \(DOP853, rtol = atol = ([\d.e-]+), δ watched\) simulates "
        r"(\d+) s",
    )
    integrator = summary["integrator"]
    assert integrator["method"] == "DOP853" and integrator["rtol"] == integrator["atol"]
    assert _numbers(match) == [integrator["rtol"], summary["simulated_time_s"]]
    assert summary["watched"] == ["diagonal_ratio"]


def test_claims_quote_every_demo_estimator_error():
    demo = test_simulate.PUBLISHED_DEMO
    match = _find(
        "docs/findings/claims.md",
        r"for the swinging 4-link chain, ([\d.]+) for 10 links, ([\d.]+) for 20:",
    )
    assert _numbers(match) == [demo[10]["median"], demo[20]["median"]]


def test_tracker_prose_is_the_committed_cost_run():
    rows = [r for r in _csv("cost/tracker_samples.csv") if r["method"] == "tracker"]
    ratios = {int(r["n"]): float(r["vs_dense"]) for r in rows if r["vs_dense"] != "nan"}
    page = "docs/findings/cost.md"
    _find(page, r"It is cheaper than a dense eigen-solve at every size measured")
    assert all(ratio < 1 for ratio in ratios.values())
    _find(page, r"\(n = 20 to\s+400\)")
    assert min(ratios) == 20 and max(ratios) == 400
    _find(page, r"to under a twentieth of the dense cost at 400 links")
    assert ratios[400] < 1 / 20
    match = _find(page, r"for (\d+)–(\d+) O\(n\) products and three O\(n\) factorizations")
    medians = [float(r["products_median"]) for r in rows]
    assert [int(match.group(1)), int(match.group(2))] == [min(medians), max(medians)]
    # the shift and the two certificates (λmin, λmax)
    assert all(float(r["factors_median"]) == 3 for r in rows)


def test_bench_block_work_precision_table_is_the_committed_csv():
    rows = [r for r in _csv("integrators.csv") if r["n"] == "10" and r["status"] == "completed"]
    acceptance = json.loads((BENCH / "summary.json").read_text())["sections"]["integrators"][
        "acceptance"
    ]
    table = _block_table("Work-precision of integrators (MuJoCo peer)")
    assert len(table) == len({(r["simulator"], r["method"]) for r in rows})
    for row in table:
        simulator, method = row["10-link chain"].split(" ", 1)
        runs = [r for r in rows if r["simulator"] == simulator and r["method"] == method]
        best = min(runs, key=lambda r: float(r["error_rad"]))
        assert [row["smallest error (rad)"], row["its wall (s)"], row["its energy drift"]] == [
            _g3(best["error_rad"]),
            _g3(best["wall_s"]),
            _g3(best["energy_drift"]),
        ], row
        reached = any(float(r["error_rad"]) <= 1e-10 for r in runs)
        assert (row["wall to 1e-10 rad (s)"] != "nan") == reached, row
    walls = {row["10-link chain"]: row["wall to 1e-10 rad (s)"] for row in table}
    assert walls["gimwatch DOP853"] == _g3(acceptance["gimwatch_dop853_interpolated_s"])
    assert walls["mujoco RK4"] == _g3(acceptance["mujoco_rk4_interpolated_s"])


def test_watch_page_quotes_the_committed_watch_overhead_run():
    rows = _csv("watch_overhead/watch_overhead.csv")

    def ratio(robot, loop, metric, column="watch_vs_bare"):
        (row,) = [r for r in rows if (r["robot"], r["loop"], r["metric"]) == (robot, loop, metric)]
        return f"{float(row[column]):.2f}"

    _find(
        "docs/watch.md",
        rf"a κ sample costs {ratio('xarm7', 'mujoco', 'kappa')}× `mj_fullM` \+ `eigvalsh` "
        rf"and a δ sample {ratio('xarm7', 'mujoco', 'delta')}× reading",
    )
    _find(
        "docs/watch.md",
        rf"{ratio('xarm7', 'pinocchio', 'kappa')}× `pin.crba` \+ `eigvalsh` and "
        rf"{ratio('xarm7', 'pinocchio', 'delta')}× the O\(n\) diagonal",
    )
    _find(
        "docs/watch.md",
        rf"\(nv = 35\) a κ sample costs {ratio('g1', 'mujoco', 'kappa')}× the bare `mj_fullM` "
        rf"\+ `eigvalsh`\.",
    )
    summary = json.loads((BENCH / "watch_overhead" / "summary.json").read_text())
    cpu = summary["environment"]["cpu"].split(" (")[0]
    _find(  # the ratio to the step, labelled with the machine it came from
        "docs/watch.md",
        rf"on the 2-core {cpu} of the committed run the g1 κ sample was "
        rf"{ratio('g1', 'mujoco', 'kappa', 'watch_vs_step')} `mj_step`s",
    )
    solver = {int(r["n"]): r for r in _csv("watch_overhead/watch_solver.csv")}
    from gimwatch.watch.spectrum_solver import COMPILED_MAX_NV, UNBLOCKED_MAX_NV

    first, last = COMPILED_MAX_NV + 1, UNBLOCKED_MAX_NV
    assert solver[first]["solver"] == "dsyevd, minimal workspace" == solver[last]["solver"]
    _find(
        "docs/watch.md",
        rf"solve costs {float(solver[first]['solver_vs_numpy']):.2f}× NumPy's at n = {first} and "
        rf"{float(solver[last]['solver_vs_numpy']):.2f}× at n = {last}, where",
    )
    _find("docs/watch.md", rf"the numba kernel up to n = {COMPILED_MAX_NV} and above it")
    tracker = {
        int(r["n"]): float(r["tracked_vs_dense"]) for r in _csv("watch_overhead/watch_tracker.csv")
    }
    pays = min(n for n, ratio in tracker.items() if ratio < 1.0)
    below = max(n for n in tracker if n < pays)
    _find(
        "docs/watch.md",
        rf"pays from about n = {pays}: .* costs {tracker[below]:.2f}× the dense κ sample at "
        rf"n = {below}, {tracker[pays]:.2f}× at n = {pays} and {tracker[max(tracker)]:.2f}× at "
        rf"n = {max(tracker)}",
    )


def test_explain_page_quotes_the_committed_map_timings():
    rows = _csv("explain/explain.csv")
    arm = next(r for r in rows if r["path"] == "crba" and r["workers"] == "1")
    pooled = next(r for r in rows if r["path"] == "crba" and r["workers"] == "2")
    chain = next(r for r in rows if r["path"] == "denoc")
    match = _find(
        "docs/guide/explain.md",
        r"nv = 9\) took ([\d.]+) s in one process \((\d+) µs per point\);\s+on 2 worker "
        r"processes it took ([\d.]+) s",
    )
    assert match.groups() == (
        f"{float(arm['seconds']):.2f}",
        f"{float(arm['us_per_point']):.0f}",
        f"{float(pooled['seconds']):.1f}",
    )
    match = _find("docs/guide/explain.md", r"O\(n\) path took (\d+) s on 2 workers \(([\d.]+) ms")
    assert match.groups() == (
        f"{float(chain['seconds']):.0f}",
        f"{float(chain['us_per_point']) / 1000:.1f}",
    )
    assert (arm["grid"], chain["grid"], chain["nv"]) == ("200", "100", "1000")


def test_digits_page_quotes_the_committed_study():
    """docs/findings/digits.md: both tables are what `gimwatch bench digits` makes of the
    committed CSV, and every figure its prose quotes is read off that CSV."""
    from gimwatch.bench import digits

    rows = _csv("digits/digits.csv")
    N = r"(\d(?:[\d.e+-]*\d)?)"  # a figure, without the sentence's full stop
    page = "docs/findings/digits.md"
    for line in digits.solver_table(rows).splitlines() + digits.case_table(rows).splitlines():
        assert line in _text(page), f"{page}: table line not in the page: {line}"

    def g(value: float) -> str:
        return f"{value:.3g}"

    def row(case: str, unit: str) -> list[str]:
        table = digits.case_table(rows).splitlines()
        line = next(x for x in table if x.startswith(f"| {case} | {unit} |"))
        return [c.strip() for c in line.strip("|").split("|")]

    energy = max(float(r["energy_error_over_kappa_s_eps"]) for r in rows)
    plain = max(float(r["rel_error_over_kappa_eps"]) for r in rows)
    assert _find(page, rf"exceeded\s+{N}·κ_S·eps").group(1) == g(energy)
    assert _find(page, rf"below {N}·κ·eps").group(1) == g(plain)
    heavy, chain = row("heavy_base_1e7_10", "m"), row("chain_10", "mm")
    match = _find(
        page,
        rf"has κ = {N} and a worst error\s+of {N}, no worse than the uniform "
        rf"chain_10 \({N} at κ = {N}\)",
    )
    assert list(match.groups()) == [heavy[3], heavy[7], chain[7], chain[3]]
    assert _find(page, rf"δ = {N} on the heavy base comes").group(1) == heavy[5]
    panda_m, panda_mm = row("panda", "m"), row("panda", "mm")
    match = _find(page, rf"millimetres has κ = {N} \(κ·eps ≈ [\d.e-]+\) and a worst error of {N}")
    assert list(match.groups()) == [panda_mm[3], panda_mm[7]]
    match = _find(
        page,
        rf"goes from κ = {N} to\s+κ = {N} and δ from {N} to {N}; "
        rf"κ_S stays {N}",
    )
    assert list(match.groups()) == [panda_m[3], panda_mm[3], panda_m[5], panda_mm[5], panda_m[4]]
    assert panda_m[4] == panda_mm[4]
    floating_m, floating_mm = row("ur5_floating", "m"), row("ur5_floating", "mm")
    match = _find(page, rf"κ = {N} in\s+metres, {N} in millimetres, κ_S = {N} in both")
    assert list(match.groups()) == [floating_m[3], floating_mm[3], floating_m[4]]
    assert floating_m[4] == floating_mm[4]
    worst = {
        s: max(float(r["energy_error_over_kappa_s_eps"]) for r in rows if r["solver"] == s)
        for s in ("aba", "denoc")
    }
    match = _find(page, rf"\({N} for ABA, {N} for DeNOC, both on ur5 in metres")
    assert list(match.groups()) == [g(worst["aba"]), g(worst["denoc"])]
    near = row("near_axes_1e-6_10", "m")
    assert _find(page, rf"δ = {N} on near-coincident axes").group(1) == near[5]
    eps = float(np.finfo(float).eps)
    kappa_eps = _find(page, r"κ = [\d.e+]+ \(κ·eps ≈ (\d+e-\d+)\)").group(1)
    assert float(kappa_eps) == float(f"{float(panda_mm[3]) * eps:.0e}")
    near_s = [float(row("near_axes_1e-6_10", u)[4]) for u in ("m", "mm")]
    match = _find(
        page, rf"κ_S ≈ {N}, κ_S·eps ≈ {N}, and every solver lost {N} to {N} digits at its worst"
    )
    assert float(match.group(1)) == float(f"{near_s[0]:.0e}") == float(f"{near_s[1]:.0e}")
    assert float(match.group(2)) == round(near_s[0] * eps, 1)
    lost = {}
    for r in rows:
        if r["case"] == "near_axes_1e-6_10":
            lost[r["solver"]] = max(lost.get(r["solver"], 0.0), float(r["rel_error"]))
    digits_lost = np.log10(np.array(list(lost.values())) / eps)
    assert [int(match.group(3)), int(match.group(4))] == [
        int(digits_lost.min()),
        int(digits_lost.max()),
    ]
    cholesky = max(
        float(r["energy_error_over_kappa_s_eps"])
        for r in rows
        if r["solver"] in ("crba_cho_solve", "crba_pin_ldlt")
    )
    ratios = [worst["aba"] / cholesky, worst["denoc"] / cholesky]
    assert _find(page, r"are two\s+to four times Cholesky's")
    assert 2 <= min(ratios) and max(ratios) <= 4


def test_claims_table_quotes_the_digits_study():
    """The premise table of docs/findings/claims.md: each verdict's figure from the CSV."""
    from gimwatch.bench import digits

    rows = _csv("digits/digits.csv")
    N = r"(\d(?:[\d.e+-]*\d)?)"
    claims = "docs/findings/claims.md"
    table = digits.case_table(rows).splitlines()

    def row(case: str, unit: str) -> list[str]:
        line = next(x for x in table if x.startswith(f"| {case} | {unit} |"))
        return [c.strip() for c in line.strip("|").split("|")]

    def g(value: float) -> str:
        return f"{value:.3g}"

    cases = {r["case"] for r in rows}
    assert int(_find(claims, rf"five solvers, {N} cases").group(1)) == len(cases)
    plain = max(float(r["rel_error_over_kappa_eps"]) for r in rows)
    energy = max(float(r["energy_error_over_kappa_s_eps"]) for r in rows)
    heavy, near = row("heavy_base_1e7_10", "m"), row("near_axes_1e-6_10", "m")
    match = _find(claims, rf"every error ≤ {N}·κ·eps; heavy base κ = {N}, worst error {N}")
    assert list(match.groups()) == [g(plain), heavy[3], heavy[7]]
    assert _find(claims, rf"every error ≤ {N}·κ_S·eps").group(1) == g(energy)
    assert _find(claims, rf"heavy base δ = {N} with chain_10's errors").group(1) == heavy[5]
    assert _find(claims, rf"near-coincident axes δ = {N} with").group(1) == near[5]
    match = _find(claims, rf"{N} on the heavy base \(no extra loss\), {N} on near-coincident")
    assert list(match.groups()) == [heavy[6], near[6]]
    panda_m, panda_mm = row("panda", "m"), row("panda", "mm")
    match = _find(claims, rf"κ {N} → {N}, κ_S {N} in both")
    assert list(match.groups()) == [panda_m[3], panda_mm[3], panda_m[4]]
    worst = [
        g(max(float(r["energy_error_over_kappa_s_eps"]) for r in rows if r["solver"] == s))
        for s in ("aba", "denoc")
    ]
    assert list(_find(claims, rf"worst {N} and {N}·κ_S·eps").groups()) == worst
    ur5, chain = row("ur5", "m"), row("chain_20", "m")
    assert list(_find(claims, rf"ur5 has κ = {N} and\s+κ_S = {N}").groups()) == ur5[3:5]
    match = _find(claims, rf"chain_20: κ = {N}, κ_S = {N}")
    assert list(match.groups()) == chain[3:5]


def test_readme_why_it_matters_quotes_the_digits_study():
    from gimwatch.bench import digits

    rows = _csv("digits/digits.csv")
    N = r"(\d(?:[\d.e+-]*\d)?)"
    energy = max(float(r["energy_error_over_kappa_s_eps"]) for r in rows)
    assert _find("README.md", rf"stayed within {N}·κ_S·eps").group(1) == f"{energy:.3g}"
    table = digits.case_table(rows).splitlines()
    cells = [
        [c.strip() for c in line.strip("|").split("|")]
        for line in table
        if line.startswith(("| panda | m |", "| panda | mm |"))
    ]
    match = _find("README.md", rf"panda in millimetres: κ {N} → {N}, κ_S {N} in both")
    assert list(match.groups()) == [cells[0][3], cells[1][3], cells[0][4]]
    assert cells[0][4] == cells[1][4]
