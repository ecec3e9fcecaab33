"""The survey's human-readable pages: report.md and the table the docs quote (table.md)."""

from __future__ import annotations

import datetime
import math

import numpy as np

from gimwatch.output.environment import cpu_model, versions
from gimwatch.survey.run import RobotSurvey, SurveyResult
from gimwatch.survey.trajectory import TrajectoryStatistics

__all__ = ["markdown_report", "readme_table"]

SCATTER_PNG = "kappa_vs_delta.png"
GRID_PNG = "kappa_vs_delta_per_robot.png"
_EXTREME_COLUMNS = ("max_diagonal_dof", "min_diagonal_dof", "lambda_max_dof", "lambda_min_dof")


def _g(value: float, digits: int = 3) -> str:
    return "—" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def _f(value: float) -> str:
    return "—" if not math.isfinite(value) else f"{value:.2f}"


def _base(robot: RobotSurvey) -> str:
    return ("floating" if robot.floating else "fixed") + ("*" if robot.note else "")


def readme_table(result: SurveyResult) -> str:
    """Markdown table "Does the diagonal ratio track κ on real robots?", one row per robot."""
    along = result.trajectory_settings is not None
    lines = [
        "| robot | nv | base | κ median | κ max | δ median | Pearson log δ~log κ | Spearman δ~κ "
        "| αδ rel. err. median | αδ rel. err. max | λmin eigenvector on |"
        + (" along runs: Pearson (median) | along runs: αδ rel. err. median |" if along else ""),
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---|" + ("---:|---:|" if along else ""),
    ]
    for r in result.robots:
        q_kappa, q_delta = r.quantiles["kappa"], r.quantiles["diagonal_ratio"]
        dof, frequency = r.extreme_dofs["lambda_min_dof"]
        line = (
            f"| {r.name} | {r.nv} | {_base(r)} | {_g(q_kappa['median'])} | {_g(q_kappa['max'])} "
            f"| {_g(q_delta['median'])} | {_f(r.pearson_log)} | {_f(r.spearman)} "
            f"| {_g(r.alpha_delta_rel_error_median, 2)} | {_g(r.alpha_delta_rel_error_max, 2)} "
            f"| {dof} ({frequency:.0%}) |"
        )
        if along:
            stats = r.trajectories or TrajectoryStatistics()
            line += (
                f" {_f(stats.pearson_log_median)}{'†' if stats.skipped else ''} "
                f"| {_g(stats.alpha_delta_rel_error_median, 2)} |"
            )
        lines.append(line)
    return "\n".join(lines) + "\n"


def _summary(result: SurveyResult) -> str:
    pearson = np.array([r.pearson_log for r in result.robots])
    pearson = pearson[np.isfinite(pearson)]
    error = np.array([r.alpha_delta_rel_error_median for r in result.robots])
    error = error[np.isfinite(error)]
    if pearson.size == 0:
        return "No robot has enough varying samples for a correlation.\n"
    return (
        f"{len(result.robots)} robots surveyed, {len(result.failures)} failed. "
        f"Pearson correlation of log δ with log κ: median {np.median(pearson):.2f} over "
        f"{pearson.size} robots with a varying κ; r > 0.9 for {np.sum(pearson > 0.9)}, "
        f"r < 0.5 for {np.sum(pearson < 0.5)}. Median relative error of αδ (α at the neutral "
        f"configuration): median {np.median(error):.2g} over robots, worst "
        f"{np.max(error):.2g}.{_coupling_summary(result)}\n" + _trajectory_summary(result)
    )


def _coupling_summary(result: SurveyResult) -> str:
    """Whether δ tracks κ_S: by construction it need not (κ ≤ δ·κ_S splits κ in two)."""
    pearson = np.array([r.pearson_log_delta_kappa_equilibrated for r in result.robots])
    pearson = pearson[np.isfinite(pearson)]
    if pearson.size == 0:
        return ""
    return (
        f" δ against κ_S (κ of D^-1/2 M D^-1/2, the coupling part of κ ≤ δ·κ_S): Pearson "
        f"r(log δ, log κ_S) median {np.median(pearson):.2f} over {pearson.size} robots, "
        f"r > 0.9 for {np.sum(pearson > 0.9)}. δ is the diagonal's spread, which a Cholesky "
        "solve does not pay for; where r is low, δ does not follow the part of κ that costs "
        "digits, and a high r(log δ, log κ) says that κ is mostly spread."
    )


def _trajectory_summary(result: SurveyResult) -> str:
    stats = [r.trajectories for r in result.robots if r.trajectories is not None]
    runs = [run for s in stats for run in s.runs]
    if not stats:
        return ""
    pearson = np.array([s.pearson_log_median for s in stats])
    pearson = pearson[np.isfinite(pearson)]
    error = np.array([s.alpha_delta_rel_error_median for s in stats])
    error = error[np.isfinite(error)]
    simulated = sum(1 for s in stats if not s.skipped)
    text = (
        f"\nAlong simulated trajectories: {simulated} robots simulated, "
        f"{sum(run.status == 'completed' for run in runs)} of {len(runs)} runs completed"
    )
    if pearson.size:
        text += (
            f"; Pearson r(log δ, log κ) along a run, median over robots {np.median(pearson):.2f}"
            f" (r > 0.9 for {np.sum(pearson > 0.9)} of {pearson.size})"
        )
    if error.size:
        text += f"; αδ relative error (α at t0 of each run), median {np.median(error):.2g}"
    return text + ".\n"


def _trajectory_section(result: SurveyResult) -> list[str]:
    settings = result.trajectory_settings
    if settings is None:
        return []
    lines = [
        "",
        "## Along simulated trajectories",
        "",
        f"Per robot, up to {settings.count} runs of {settings.duration_s:g} s from random samples "
        f"1..{settings.count}, at rest, falling under gravity (z down; y down for generated "
        f"chains) with light joint damping c_i = {settings.damping_per_s:g}/s · M_ii(q0); "
        f"joint limits are not enforced. DOP853 (rtol {settings.rtol:g}, atol "
        f"{settings.atol:g}), or RK4 (dt {settings.dt_s:g} s) for robots with continuous "
        f"joints; runs stop after {settings.max_steps} steps. The watch samples κ and δ "
        f"every {settings.sample_s:g} s; α = κ/δ is calibrated at t0 of each run (the "
        "paper's setting) and αδ errors are over the later samples of the completed runs. "
        "Correlations: median (and minimum) over completed runs; κ spread = max κ / min κ "
        "along a run (median over runs).",
        "",
        "| robot | runs completed | integrator | κ spread | Pearson log δ~log κ median (min) "
        "| Spearman δ~κ median | αδ rel. err. median | αδ rel. err. max | notes |",
        "|---|---:|---|---:|---:|---:|---:|---:|---|",
    ]
    for r in result.robots:
        t = r.trajectories
        if t is None:
            continue
        if t.skipped:
            lines.append(f"| {r.name} | 0/0 | — | — | — | — | — | — | not simulated: {t.skipped} |")
            continue
        notes = [f"from sample {s}: {reason}" for s, reason in t.errors]
        notes += [
            f"from sample {run.start_sample}: {run.status}, {run.message}"
            for run in t.runs
            if run.status != "completed"
        ]
        method = "/".join(sorted({run.method for run in t.runs})) or "—"
        lines.append(
            f"| {r.name} | {len(t.completed)}/{len(t.runs) + len(t.errors)} | {method} "
            f"| {_g(t.kappa_spread_median)} | {_f(t.pearson_log_median)} ({_f(t.pearson_log_min)}) "
            f"| {_f(t.spearman_median)} | {_g(t.alpha_delta_rel_error_median, 2)} "
            f"| {_g(t.alpha_delta_rel_error_max, 2)} | {'; '.join(notes)} |"
        )
    return lines


def markdown_report(result: SurveyResult, wall_time_s: float | None) -> str:
    """The survey's report.md: settings, per-robot tables, worst samples, runs, failures."""
    lines = _header(result, wall_time_s)
    lines += [_summary(result), "## κ, δ and αδ", "", readme_table(result)]
    lines += _pivot_section(result)
    lines += _extremes_section(result)
    lines += _worst_section(result)
    lines += _placeholder_section(result)
    lines += _trajectory_section(result)
    if result.failures:
        lines += ["", "## Robots not surveyed", "", "| robot | stage | reason |", "|---|---|---|"]
        lines += [f"| {f.spec} | {f.stage} | {f.reason} |" for f in result.failures]
    lines += [
        "",
        "## Plots",
        "",
        f"![κ vs δ, all robots]({SCATTER_PNG})",
        "",
        f"![κ vs δ per robot]({GRID_PNG})",
        "",
    ]
    return "\n".join(lines)


def _header(result: SurveyResult, wall_time_s: float | None) -> list[str]:
    """Title, date, libraries, CPU and settings; the robots not reached if interrupted."""
    libraries = ", ".join(f"{k} {v}" for k, v in versions().items())
    wall = "" if wall_time_s is None else f", wall time {wall_time_s:.1f} s"
    lines = [
        "# Survey: does the diagonal ratio track κ on real robots?",
        "",
        f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}; {libraries}; "
        f"CPU {cpu_model()}.",
        f"{result.samples} random configurations per robot + the neutral one (sample 0), "
        f"seed {result.seed}{wall}. α = κ/δ is calibrated at the neutral configuration; "
        "αδ errors are over the random samples.",
        "",
    ]
    if result.interrupted:
        reached = ", ".join(result.not_reached) or "none"
        lines += [f"**Interrupted**: partial results; robots not reached: {reached}.", ""]
    return lines


def _pivot_section(result: SurveyResult) -> list[str]:
    """The legend of the κ table, then the pivot ratios per robot."""
    lines = [
        "`*`: no joint with a fixed base, surveyed with a free-flyer base. With a floating "
        "base the GIM mixes kg (translations) and kg·m² (rotations): κ and δ depend on units. "
        "`—`: undefined, κ or δ is the same at every sample."
        + (
            " Along runs: see the section on simulated trajectories; `†`: not simulated."
            if result.trajectory_settings is not None
            else ""
        ),
        "",
        "## Pivot ratios (median / max)",
        "",
        "| robot | κ p05 | κ p95 | δ p05 | δ p95 | forward pivot ratio | backward pivot ratio |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in result.robots:
        k, d = r.quantiles["kappa"], r.quantiles["diagonal_ratio"]
        f, b = r.quantiles["pivot_ratio_forward"], r.quantiles["pivot_ratio_backward"]
        lines.append(
            f"| {r.name} | {_g(k['p05'])} | {_g(k['p95'])} | {_g(d['p05'])} | {_g(d['p95'])} "
            f"| {_g(f['median'])} / {_g(f['max'])} | {_g(b['median'])} / {_g(b['max'])} |"
        )
    return lines


def _extremes_section(result: SurveyResult) -> list[str]:
    """The coordinates that most often hold the extremes of the diagonal and the spectrum."""
    lines = [
        "",
        "## What makes each robot ill-conditioned",
        "",
        "Most frequent coordinate (share of samples) holding the largest and smallest diagonal "
        "entry, and dominating the eigenvectors of λmax and λmin; the last column is the share "
        "of samples where λmin's eigenvector lives on the coordinate with the smallest diagonal "
        "entry (a light distal body or a short lever arm sets κ).",
        "",
        "| robot | largest M_ii | smallest M_ii | λmax eigenvector | λmin eigenvector "
        "| λmin on smallest M_ii |",
        "|---|---|---|---|---|---:|",
    ]
    for r in result.robots:
        cells = [f"{d} ({f:.0%})" for d, f in (r.extreme_dofs[k] for k in _EXTREME_COLUMNS)]
        lines.append(f"| {r.name} | {' | '.join(cells)} | {r.lambda_min_on_min_diagonal:.0%} |")
    return lines


def _worst_section(result: SurveyResult) -> list[str]:
    """The samples with the largest κ, per robot."""
    lines = [
        "",
        "## Worst configurations",
        "",
        "The samples with the largest κ (their q is in `survey.json`).",
        "",
        "| robot | sample | κ | δ |",
        "|---|---:|---:|---:|",
    ]
    for r in result.robots:
        for w in r.worst:
            kappa, delta = _g(w.kappa, 4), _g(w.diagonal_ratio, 4)
            lines.append(f"| {r.name} | {w.sample} | {kappa} | {delta} |")
    return lines


def _placeholder_section(result: SurveyResult) -> list[str]:
    """The joints whose placeholder limits were sampled in ±π rad / ±1 m, if any."""
    placeholders = [r for r in result.robots if r.placeholder_limits]
    if not placeholders:
        return []
    lines = [
        "",
        "## Placeholder joint limits",
        "",
        'Limits of |limit| >= 1e3 (or none) stand for "unlimited"; the random samples draw '
        "those coordinates in ±π rad (angles) or ±1 m (translations) instead.",
        "",
    ]
    return lines + [f"- {r.name}: {', '.join(r.placeholder_limits)}" for r in placeholders]
