"""Write a survey result (`SurveyResult`): report, JSON, CSV, plots.

The folder is written beside its place and swapped in whole (`gimwatch.output.folders`),
so an interrupted or failed write leaves the previous survey as it was, never a mix of two;
an interrupted survey is written too, and says so.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from gimwatch.output.atomic import write_bytes_atomic, write_json_atomic, write_text_atomic
from gimwatch.output.environment import versions
from gimwatch.output.folders import ResultsFolder
from gimwatch.survey.plots import grid_figsize, plot_kappa_vs_delta, plot_kappa_vs_delta_grid
from gimwatch.survey.report_markdown import GRID_PNG, SCATTER_PNG, markdown_report, readme_table
from gimwatch.survey.run import DOF_METRICS, METRICS, SurveyResult
from gimwatch.survey.trajectory import TrajectoryStatistics

__all__ = [
    "plot_kappa_vs_delta",
    "plot_kappa_vs_delta_grid",
    "readme_table",
    "survey_record",
    "write_survey",
]

#: ``trajectory`` and ``t_s`` are empty on the random samples; on the rows of a simulated run
#: ``sample`` is the sample it started from and only κ, δ and αδ are filled (the watched ones).
CSV_COLUMNS = (
    "robot",
    "sample",
    "trajectory",
    "t_s",
    *METRICS,
    "scaled_diagonal_ratio",
    *DOF_METRICS,
)


def _trajectory_record(stats: TrajectoryStatistics | None) -> dict | None:
    if stats is None:
        return None
    return {
        "skipped": stats.skipped,
        "runs": len(stats.runs),
        "completed": len(stats.completed),
        "pearson_log_delta_log_kappa_median": stats.pearson_log_median,
        "pearson_log_delta_log_kappa_min": stats.pearson_log_min,
        "spearman_delta_kappa_median": stats.spearman_median,
        "alpha_delta_rel_error_median": stats.alpha_delta_rel_error_median,
        "alpha_delta_rel_error_max": stats.alpha_delta_rel_error_max,
        "kappa_spread_median": stats.kappa_spread_median,
        "errors": [{"start_sample": s, "reason": r} for s, r in stats.errors],
        "per_run": [
            {
                "start_sample": run.start_sample,
                "status": run.status,
                "message": run.message,
                "method": run.method,
                "steps": run.steps,
                "samples": int(run.t.size),
                "alpha": run.alpha,
                "kappa_spread": run.kappa_spread,
                "pearson_log_delta_log_kappa": run.pearson_log,
                "spearman_delta_kappa": run.spearman,
                "alpha_delta_rel_error_median": run.alpha_delta_rel_error_median,
                "alpha_delta_rel_error_max": run.alpha_delta_rel_error_max,
            }
            for run in stats.runs
        ],
    }


def survey_record(result: SurveyResult, *, wall_time_s: float | None = None) -> dict:
    """The JSON-ready summary: settings, versions, per-robot statistics, failures."""
    robots = []
    for r in result.robots:
        robots.append(
            {
                "robot": r.name,
                "spec": r.spec,
                "nv": r.nv,
                "floating": r.floating,
                "note": r.note,
                "placeholder_limits": list(r.placeholder_limits),
                "samples": r.samples,
                "alpha": r.alpha,
                "quantiles": r.quantiles,
                "pearson_log_delta_log_kappa": r.pearson_log,
                "spearman_delta_kappa": r.spearman,
                "pearson_log_delta_log_kappa_equilibrated": r.pearson_log_delta_kappa_equilibrated,
                "alpha_delta_rel_error_median": r.alpha_delta_rel_error_median,
                "alpha_delta_rel_error_max": r.alpha_delta_rel_error_max,
                "extreme_dofs": {
                    k: {"dof": d, "frequency": f} for k, (d, f) in r.extreme_dofs.items()
                },
                "lambda_min_on_min_diagonal": r.lambda_min_on_min_diagonal,
                "worst": [
                    {
                        "sample": w.sample,
                        "kappa": w.kappa,
                        "diagonal_ratio": w.diagonal_ratio,
                        "q": list(w.q),
                    }
                    for w in r.worst
                ],
                "trajectories": _trajectory_record(r.trajectories),
            }
        )
    return {
        "samples_per_robot": result.samples,
        "seed": result.seed,
        "calibration": "alpha = kappa/delta at sample 0, the neutral configuration",
        "trajectory_settings": (
            None if result.trajectory_settings is None else result.trajectory_settings.record()
        ),
        "interrupted": result.interrupted,
        "not_reached": list(result.not_reached),
        "wall_time_s": wall_time_s,
        "versions": versions(),
        "robots": robots,
        "failures": [vars(f) for f in result.failures],
    }


def _csv_text(result: SurveyResult) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for r in result.robots:
        alpha_delta = r.scaled_diagonal_ratio()
        for row, sample in enumerate(r.sample_index):
            floats = [repr(float(r.metrics[key][row])) for key in METRICS]
            dofs = [r.dof_names[r.metrics[key][row]] for key in DOF_METRICS]
            writer.writerow(
                [r.name, int(sample), "", "", *floats, repr(float(alpha_delta[row])), *dofs]
            )
        for k, run in enumerate(() if r.trajectories is None else r.trajectories.runs):
            for row, t in enumerate(run.t):
                floats = [""] * len(METRICS)
                floats[METRICS.index("kappa")] = repr(float(run.kappa[row]))
                floats[METRICS.index("diagonal_ratio")] = repr(float(run.diagonal_ratio[row]))
                cells = [r.name, run.start_sample, k, repr(float(t)), *floats]
                writer.writerow([*cells, repr(float(run.scaled_diagonal_ratio[row])), *[""] * 4])
    return buffer.getvalue()


def _png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    return buffer.getvalue()


def write_survey(
    result: SurveyResult, output: str | Path, *, wall_time_s: float | None = None
) -> Path:
    """Write report.md, survey.json, survey.csv, table.md and two PNGs into ``output``.

    Returns:
        The path of report.md.
    """
    from matplotlib.figure import Figure  # no pyplot: leaves the user's backend alone

    with ResultsFolder(output, writer="survey") as folder:
        staging = folder.staging
        assert staging is not None  # made on entering the block
        fig = Figure(figsize=(8, 6), layout="constrained")
        plot_kappa_vs_delta(result, ax=fig.subplots())
        write_bytes_atomic(staging / SCATTER_PNG, _png(fig))
        grid = Figure(figsize=grid_figsize(len(result.robots)))
        write_bytes_atomic(staging / GRID_PNG, _png(plot_kappa_vs_delta_grid(result, fig=grid)))
        record = survey_record(result, wall_time_s=wall_time_s)
        write_json_atomic(staging / "survey.json", record)
        write_text_atomic(staging / "survey.csv", _csv_text(result))
        write_text_atomic(staging / "table.md", readme_table(result))
        write_text_atomic(staging / "report.md", markdown_report(result, wall_time_s))
        folder.commit()
    return Path(output) / "report.md"
