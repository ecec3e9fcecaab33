"""Every figure-producing function labels both axes with a unit, returns what it drew on,
and draws a capped number of lines for long chains.

A unit is written in brackets, ``[s]``, ``[kg·m²]``, or ``[-]`` for a dimensionless ratio.
The bench figures are drawn from the committed tables in ``benchmarks/`` (measure, then plot).
"""

from __future__ import annotations

import inspect
import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.figure import Figure

from gimwatch.bench import plots as bench_plots
from gimwatch.output import figures
from gimwatch.survey import plots as survey_plots

ROOT = Path(__file__).resolve().parents[1]
UNIT = re.compile(r"\[[^\]]+\]")


def _axes():
    return Figure(figsize=(6, 4)).add_subplot()


def _assert_units(ax, where: str) -> None:
    for axis, label in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())):
        assert UNIT.search(label), f"{where}: {axis} label {label!r} has no unit in [...]"


T = np.linspace(0.0, 1.0, 21)
RNG = np.random.default_rng(0)
POSITIVE = np.exp(RNG.normal(size=(21, 4)))

FIGURE_CALLS = {
    "plot_eigenvalues": lambda ax: figures.plot_eigenvalues(T, np.sort(POSITIVE, axis=1), ax=ax),
    "plot_diagonal": lambda ax: figures.plot_diagonal(T, POSITIVE, ax=ax),
    "plot_kappa_and_delta": lambda ax: figures.plot_kappa_and_delta(
        T, 50 * POSITIVE[:, 0], POSITIVE[:, 1], ax=ax
    ),
    "plot_delta": lambda ax: figures.plot_delta(T, POSITIVE[:, 0], threshold=2.0, ax=ax),
    "plot_pivot_ratios": lambda ax: figures.plot_pivot_ratios(
        T, POSITIVE[:, 0], POSITIVE[:, 1], POSITIVE[:, 2], ax=ax
    ),
    "plot_kappa_and_scaled": lambda ax: figures.plot_kappa_and_scaled(
        T, POSITIVE[:, 0], POSITIVE[:, 1], ax=ax
    ),
    "plot_energy": lambda ax: figures.plot_energy(T, POSITIVE[:, 0], ax=ax),
    "plot_joint_angles": lambda ax: figures.plot_joint_angles(
        T, POSITIVE, names=["a", "b", "c", "d"], units=["rad", "rad", "m", "-"], ax=ax
    ),
    "plot_watch": lambda ax: figures.plot_watch(
        T, {"kappa": POSITIVE[:, 0]}, alarm_metric="kappa", threshold=2.0, ax=ax
    ),
}


def test_every_plot_function_of_figures_is_checked():
    public = {n for n in figures.__all__ if n.startswith("plot_")}
    assert public == set(FIGURE_CALLS)


@pytest.mark.parametrize("name", sorted(FIGURE_CALLS))
def test_run_figures_label_units_and_return_the_axes(name):
    ax = _axes()
    assert FIGURE_CALLS[name](ax) is ax
    _assert_units(ax, name)


def test_animation_axes_have_units():
    xy = np.zeros((3, 3, 2))
    xy[:, 1, 0], xy[:, 2, 0] = 1.0, 2.0
    animation = figures.animate_chain(T[:3], xy, np.array([1.0, 2.0, 3.0]))
    ax = animation._fig.axes[0]  # matplotlib's animation keeps its figure there
    _assert_units(ax, "animate_chain")


def test_joint_plot_names_joints_and_separates_units():
    ax = figures.plot_joint_angles(
        T, POSITIVE[:, :2], names=["shoulder", "slider"], units=["rad", "m"], ax=_axes()
    )
    labels = [line.get_label() for line in ax.get_lines()]
    assert labels == ["shoulder", "slider"]
    assert "[rad]" in ax.get_ylabel() and "[m]" in ax.get_ylabel()
    assert [line.get_linestyle() for line in ax.get_lines()] == ["-", "--"]


def test_a_thousand_joints_draw_an_envelope_not_a_thousand_lines():
    q = RNG.normal(size=(21, 1000))
    ax = figures.plot_joint_angles(T, q, ax=_axes())
    assert len(ax.get_lines()) <= figures.MAX_LINES
    ax = figures.plot_eigenvalues(T, np.sort(np.exp(q), axis=1), ax=_axes())
    assert len(ax.get_lines()) <= figures.MAX_LINES


def test_kappa_and_delta_start_together_so_trends_compare():
    ax = figures.plot_kappa_and_delta(T, 80 * POSITIVE[:, 0], POSITIVE[:, 1], ax=_axes())
    kappa, delta = (line.get_ydata() for line in ax.get_lines())
    np.testing.assert_allclose([kappa[0], delta[0]], [1.0, 1.0], rtol=1e-12)


def test_joint_coordinate_units_from_a_model():
    import pinocchio as pin

    model = pin.Model()
    parent = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "hinge")
    model.addJoint(parent, pin.JointModelPX(), pin.SE3.Identity(), "slider")
    names, units = figures.joint_coordinate_units(model)
    assert (names, units) == (["hinge", "slider"], ["rad", "m"])


#: Tables of the sections measured in benchmarks/cost/ (each figure has one home).
COST_TABLES = ("watch.json", "denoc.json")


def _rows(folder: str, table: str) -> list[dict]:
    rows = json.loads((ROOT / folder / table).read_text(encoding="utf-8"))["rows"]
    return [{k: float("nan") if v is None else v for k, v in row.items()} for row in rows]


@pytest.mark.parametrize("png", sorted(bench_plots.FIGURES))
def test_bench_figures_label_units(png, tmp_path):
    table, _, keep = bench_plots.FIGURES[png]
    folder = "benchmarks/cost" if table in COST_TABLES else "benchmarks"
    rows = [r for r in _rows(folder, table) if keep(r)]
    name = {
        "conditioning_cost.png": "draw_cost_vs_n",
        "estimators_pareto.png": "draw_pareto",
        "accuracy_vs_kappa.png": "draw_accuracy_vs_kappa",
        "dynamics_cost.png": "draw_dynamics_cost",
        "work_precision.png": "draw_work_precision",
        "watch_cost.png": "draw_watch_cost",
        "denoc_cost.png": "draw_denoc_cost",
    }[png]
    draw = getattr(bench_plots, name)
    args = (rows, rows[0]["n"]) if "n" in inspect.signature(draw).parameters else (rows,)
    ax = _axes()
    assert draw(*args, ax=ax) is ax
    _assert_units(ax, name)


def test_every_bench_draw_function_is_in_the_figure_table():
    drawn = {n for n in bench_plots.__all__ if n.startswith("draw_")}
    assert len(drawn) == len(bench_plots.FIGURES)


def test_watch_cost_bars_are_on_a_linear_axis():
    ax = bench_plots.draw_watch_cost(_rows("benchmarks/cost", "watch.json"), ax=_axes())
    assert ax.get_yscale() == "linear"


def test_replot_redraws_from_the_tables_alone(tmp_path):
    for table in ("watch.json", "denoc.json"):
        (tmp_path / table).write_text((ROOT / "benchmarks" / "cost" / table).read_text())
    written = bench_plots.replot(tmp_path)
    assert sorted(p.name for p in written) == ["denoc_cost.png", "watch_cost.png"]
    assert all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in written)


def _survey(count: int, seed: int = 0):
    """A made-up survey; its own seeded generator, so a test sees the same data in any order."""
    rng = np.random.default_rng(seed)
    robots = []
    for k in range(count):
        delta = np.exp(rng.normal(size=30)) * (k + 1)
        robots.append(
            SimpleNamespace(
                name=f"robot_{k}",
                metrics={"diagonal_ratio": delta, "kappa": 2.0 * delta},
                quantiles={
                    "diagonal_ratio": {"min": delta.min()},
                    "kappa": {"max": 2 * delta.max()},
                },
                pearson_log=1.0 - k / 100,
                alpha=2.0,
            )
        )
    return SimpleNamespace(robots=robots)


def test_survey_scatter_uses_categorical_highlights_and_units():
    ax = survey_plots.plot_kappa_vs_delta(_survey(20), ax=_axes())
    _assert_units(ax, "plot_kappa_vs_delta")
    coloured = [c for c in ax.collections if c.get_label().startswith("robot_")]
    assert len(coloured) == survey_plots.HIGHLIGHTED
    assert {c.get_label().split(" ")[0] for c in coloured} == {
        f"robot_{k}" for k in range(20 - survey_plots.HIGHLIGHTED, 20)
    }


def test_survey_grid_has_units_and_few_ticks():
    fig = survey_plots.plot_kappa_vs_delta_grid(_survey(7), fig=Figure(figsize=(12, 6)))
    assert UNIT.search(fig.get_supxlabel()) and UNIT.search(fig.get_supylabel())
    fig.canvas.draw()
    for ax in fig.axes:
        if ax.axison:
            low, high = sorted(ax.get_xlim())
            shown = [
                t
                for t in ax.get_xticklabels()
                if t.get_text() and low <= t.get_position()[0] <= high
            ]
            assert len(shown) <= 4, [t.get_text() for t in shown]


def _visible_labels(ax, axis: str) -> list[str]:
    low, high = sorted(getattr(ax, f"get_{axis}lim")())
    ticks = getattr(ax, f"get_{axis}ticklabels")(minor=False) + getattr(
        ax, f"get_{axis}ticklabels"
    )(minor=True)
    index = 0 if axis == "x" else 1
    return [t.get_text() for t in ticks if t.get_text() and low <= t.get_position()[index] <= high]


def _drawn(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    return fig.canvas.get_renderer()


def _inside(fig, artist) -> bool:
    renderer = fig.canvas.get_renderer()
    box, page = artist.get_window_extent(renderer), fig.bbox
    return page.x0 - 1 <= box.x0 and box.x1 <= page.x1 + 1 and page.y0 - 1 <= box.y0
    # (the top is checked by callers that need it)


def test_one_outlier_does_not_stretch_the_survey_scatter():
    survey = _survey(20)
    survey.robots[3].metrics["kappa"][0] = 1e17  # one bad configuration of one robot
    ax = survey_plots.plot_kappa_vs_delta(survey, ax=_axes())
    assert ax.get_ylim()[1] < 1e4  # the 600 others span ~1e-1 .. 1e3
    notes = [t.get_text() for t in ax.texts]
    assert notes == ["1 point(s) beyond the axes; largest κ = 1e+17 (robot_3)"]
    plain = survey_plots.plot_kappa_vs_delta(_survey(20), ax=_axes())
    assert not plain.texts  # nothing left out when nothing is far out


def test_a_small_survey_has_no_empty_legend_entry():
    survey = _survey(3)
    survey.robots[0].pearson_log = 0.5  # all three coloured
    ax = survey_plots.plot_kappa_vs_delta(survey, ax=_axes())
    labels = [c.get_label() for c in ax.collections]
    assert not [x for x in labels if "other" in x]
    many = survey_plots.plot_kappa_vs_delta(_survey(12), ax=_axes())
    assert "the other 4 robots" in [c.get_label() for c in many.collections]


def test_every_grid_panel_has_tick_labels_and_no_label_is_clipped():
    survey = _survey(3)
    narrow = np.linspace(95.0, 110.0, 30)  # far less than a decade on both axes
    survey.robots[1].metrics = {"diagonal_ratio": narrow, "kappa": 2.5 * narrow}
    fig = Figure(figsize=survey_plots.grid_figsize(3))
    survey_plots.plot_kappa_vs_delta_grid(survey, fig=fig)
    _drawn(fig)
    renderer = fig.canvas.get_renderer()
    for ax in [a for a in fig.axes if a.axison]:
        assert _visible_labels(ax, "x") and _visible_labels(ax, "y"), ax.get_title()
        for labels in (ax.get_xticklabels(which="both"), ax.get_yticklabels(which="both")):
            boxes = [x.get_window_extent(renderer) for x in labels if x.get_text()]
            boxes = [b for b in boxes if b.width > 0]
            overlapping = [(a, b) for k, a in enumerate(boxes) for b in boxes[k + 1 :]]
            assert not [pair for pair in overlapping if pair[0].overlaps(pair[1])], ax.get_title()
    for label in (fig._supxlabel, fig._supylabel, fig._suptitle):
        assert _inside(fig, label), label.get_text()
        assert label.get_window_extent().y1 <= fig.bbox.y1 + 1, label.get_text()


def test_diagonal_legend_names_joints_and_sits_beside_the_data():
    t = np.linspace(0.0, 1.0, 20)
    fig = Figure(figsize=(6.4, 4.0), layout="constrained")
    ax = figures.plot_diagonal(
        t,
        np.ones((20, 3)) * [1.0, 2.0, 3.0],
        names=("shoulder", "elbow", "wrist"),
        ax=fig.subplots(),
    )
    legend = ax.get_legend()
    assert [x.get_text() for x in legend.get_texts()] == [
        "M_ii of shoulder",
        "M_ii of elbow",
        "M_ii of wrist",
    ]
    renderer = _drawn(fig)
    assert legend.get_window_extent(renderer).x0 >= ax.get_window_extent(renderer).x1
    with pytest.raises(ValueError, match="2 names for 3"):
        figures.plot_diagonal(t, np.ones((20, 3)), names=("a", "b"), ax=_axes())


def test_the_animation_text_does_not_overlap_its_title():
    t = np.linspace(0.0, 1.0, 3)
    xy = np.zeros((3, 3, 2))
    xy[:, 1, 0], xy[:, 2, 0] = 1.0, 2.0
    fig = Figure(figsize=(5, 5), layout="constrained")
    animation = figures.animate_chain(
        t, xy, np.array([10.0, 100.0, 1000.0]), title="a title", fig=fig
    )
    renderer = _drawn(fig)
    animation._func(2)  # the last frame's text
    renderer = _drawn(fig)
    (ax,) = [a for a in fig.axes if a.get_xlabel() == "x [m]"]
    (text,) = [x for x in ax.texts if x.get_text().startswith("t = ")]
    title, words = fig._suptitle.get_window_extent(renderer), text.get_window_extent(renderer)
    assert not title.overlaps(words)
    assert words.y0 >= ax.get_window_extent(renderer).y1  # above the drawing, not on it


def test_watch_plot_draws_the_watched_metrics_and_the_threshold():
    import gimwatch as gw

    robot = gw.load_robot("chain:4")
    watch = gw.Watch(
        robot,
        ("diagonal_ratio", "kappa", "eigenvalues"),
        alarm_metric="kappa",
        alarm_threshold=50.0,
        warn=False,
    )
    for k, q in enumerate(gw.random_configurations(robot, 5, seed=0)):
        watch.sample(0.1 * k, q)
    ax = watch.plot(ax=_axes())
    lines = {line.get_label(): line for line in ax.get_lines()}
    assert set(lines) == {"diagonal_ratio", "kappa", "alarm: kappa > 50"}
    np.testing.assert_array_equal(lines["kappa"].get_ydata(), watch.array("kappa"))
    _assert_units(ax, "plot_watch")
    with pytest.raises(gw.InputError):
        watch.plot(("eigenvalues",), ax=_axes())


def test_a_robot_whose_r_prints_as_one_is_never_coloured_as_tracking_worst():
    survey = _survey(3)  # r = 1.00, 0.99, 0.98
    survey.robots[1].pearson_log = 0.996  # prints as 1.00 too
    ax = survey_plots.plot_kappa_vs_delta(survey, ax=_axes())
    coloured = [c.get_label() for c in ax.collections if c.get_label().startswith("robot_")]
    assert coloured == ["robot_2 (r = 0.98)"]
    assert "the 1 where log δ tracks log κ worst" in ax.get_title()
    for robot in survey.robots:
        robot.pearson_log = 1.0
    ax = survey_plots.plot_kappa_vs_delta(survey, ax=_axes())
    assert "worst" not in ax.get_title()
    assert not [c for c in ax.collections if c.get_label().startswith("robot_")]
