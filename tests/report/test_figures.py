"""Every figure function draws something real from synthetic data and saves SVG + PNG."""

from __future__ import annotations

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.patches import FancyArrowPatch, Rectangle

from sosdyn.report import figures as F
from sosdyn.report.figures.poses import drift_figure

GOAL = np.zeros(2)


def assert_saved_and_not_blank(fig, tmp_path, name="fig"):
    """Save ``fig``; the PNG must have real content (pixel variance), the SVG be an SVG."""
    paths = F.save_figure(fig, tmp_path / "sub" / name)
    assert paths["svg"].read_text().lstrip().startswith("<?xml")
    assert "<svg" in paths["svg"].read_text()
    img = mpimg.imread(paths["png"])[..., :3]
    assert img.shape[0] > 200 and img.shape[1] > 200
    assert img.std() > 0.05, "PNG is (nearly) blank"
    assert (img < 0.5).mean() > 0.002, "PNG has almost no dark ink"
    return paths


def bars(ax):
    return [p for p in ax.patches if isinstance(p, Rectangle)]


def test_streamlines_samples_field_on_padded_square_grid(tmp_path, field, demos_factory):
    calls = []

    def spy(X):
        calls.append(X.copy())
        return field(X)

    demos = demos_factory(3)
    fig = F.streamlines(None, spy, demos, [d * 1.01 for d in demos], GOAL, title="spiral", grid=30,
                        density=0.7)
    (X,) = calls
    assert X.shape == (900, 2)
    ax = fig.axes[0]
    assert ax.get_aspect() == 1.0
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x1 - x0 == pytest.approx(y1 - y0)
    pts = np.vstack(demos)
    assert x0 < pts[:, 0].min() and x1 > pts[:, 0].max()
    assert y0 < pts[:, 1].min() and y1 > pts[:, 1].max()
    assert ax.get_xlabel() == "$x_1$ (mm)"
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["streamlines of the model", "demonstrations", "reproductions", "goal"]
    assert_saved_and_not_blank(fig, tmp_path)


def test_streamlines_without_field_and_with_given_bounds(tmp_path, demos_factory):
    fig = F.streamlines(None, None, demos_factory(2), [], GOAL, bounds=(-60, 60, -60, 60))
    assert fig.axes[0].get_xlim() == (-60, 60)
    assert_saved_and_not_blank(fig, tmp_path)


def test_streamline_panel_grid_hides_unused_axes(tmp_path, field, demos_factory):
    panels = [dict(predict=field, demos_pos=demos_factory(2, seed=i), reproductions=[], goal=GOAL,
                   title=f"shape {i}", grid=25, density=0.6) for i in range(5)]
    fig = F.streamline_panel(panels)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(fig.axes) == 8 and len(visible) == 5
    assert [ax.get_title() for ax in visible] == [f"shape {i}" for i in range(5)]
    assert visible[0].get_ylabel() and not visible[1].get_ylabel()
    assert len(fig.legends) == 1
    assert_saved_and_not_blank(fig, tmp_path)


def test_streamline_panel_needs_panels():
    with pytest.raises(ValueError):
        F.streamline_panel([])


def points(ax):
    """(x, median, q1, q3, hollow) of each point-with-interval of ``ax``."""
    out = []
    for c in ax.containers:
        line, _, (bars,) = c.lines
        (x,), (y,) = line.get_data()
        (lo, hi), = [seg[:, 1] for seg in bars.get_segments()]
        out.append((x, y, lo, hi, line.get_markerfacecolor() == "white"))
    return out


def test_median_iqr_of_metric_entries():
    assert F.median_iqr({"mean": 9.0, "per_demo": [1.0, 2.0, 3.0, 4.0, 100.0]}) == (3.0, 2.0, 4.0)
    assert F.median_iqr({"mean": 5.0}) == (5.0, 5.0, 5.0)
    assert F.median_iqr(7) == (7.0, 7.0, 7.0)
    assert all(np.isnan(F.median_iqr(None)))


def test_accuracy_points_one_per_shape_and_method_with_iqr(tmp_path, results):
    table = results["accuracy"]
    del table["Leaf_2"]["DMP"]                          # not run: a gap, not a crash
    fig = F.accuracy_bars(table, metrics=("sea", "dtwd_total", "vel_rmse"), log=False)
    assert len(fig.axes) == 3
    assert all(len(points(ax)) == 3 * 4 - 1 for ax in fig.axes)
    assert not any(bars(ax) for ax in fig.axes)          # no bars at all
    assert fig.axes[0].get_ylabel() == "SEA (mm²)"
    assert fig.axes[2].get_ylabel() == "velocity RMSE (mm/s)"
    _, med, lo, hi, _ = points(fig.axes[0])[0]
    per_demo = table["BendedLine"]["CDSP"]["sea"]["per_demo"]
    assert med == pytest.approx(np.median(per_demo))
    assert (lo, hi) == pytest.approx(tuple(np.percentile(per_demo, [25, 75])))
    assert_saved_and_not_blank(fig, tmp_path)


def test_accuracy_points_choose_log_scale_for_wide_ranges(results):
    table = results["accuracy"]
    table["Leaf_1"]["DMP"]["sea"]["per_demo"] = [1e7, 1e7, 1e7]
    assert F.accuracy_bars(table, metrics=("sea",)).axes[0].get_yscale() == "log"
    assert F.accuracy_bars(results["accuracy"], metrics=("dtwd_total",)).axes[0].get_yscale() == "linear"


def test_robustness_points_stay_positive_and_mark_unconverged(tmp_path, results):
    for per in results["robustness"].values():         # a spread whose mean - std < 0
        per["DMP"]["push"]["dtwd_total"] = {"mean": 1000.0, "std": 1300.0,
                                            "per_demo": [10.0, 20.0, 40.0, 3000.0]}
    fig = F.robustness_bars(results["robustness"], log=False)
    push_ax, goal_ax = fig.axes
    assert push_ax.get_title(loc="left") == "after pushes"
    assert goal_ax.get_title(loc="left") == "after goal changes"
    pts = points(push_ax)
    assert sum(p[4] for p in pts) == 3                  # GMR (converged 0.57) on 3 shapes
    assert min(p[2] for p in pts) == pytest.approx(17.5)  # first quartile, not 1000 - 1300
    assert push_ax.get_ylim()[0] == 0.0
    assert "not all runs converged" in [t.get_text() for t in fig.legends[0].get_texts()]
    fig.canvas.draw()                                    # the legend lies inside the figure
    box = fig.legends[0].get_window_extent()
    assert box.x0 >= 0 and box.x1 <= fig.bbox.width and box.y1 <= fig.bbox.height
    assert_saved_and_not_blank(fig, tmp_path)


def test_perturbation_trajectories_arrows_and_goal_markers(tmp_path, demos_factory):
    demo = demos_factory(1)[0]
    runs = {"CDSP": demo * 1.02, "DMP": demo * 0.9 + 2.0, "GMR": demo + 1.0}
    events = {m: [{"kind": "goal_change", "time": 0.8, "before": GOAL, "after": [5.0, -3.0]},
                  {"kind": "push", "time": 1.0, "before": run[60], "after": run[60] + [6.0, -4.0]}]
              for m, run in runs.items()}
    goals = np.zeros((len(demo), 2))
    goals[80:] = [5.0, -3.0]
    fig = F.perturbation_trajectories(None, demo, runs, events, goals, title="Leaf_1")
    ax = fig.axes[0]
    arrows = [p for p in ax.patches if isinstance(p, FancyArrowPatch)]
    assert len(arrows) == 3
    assert arrows[0].get_edgecolor()[:3] == pytest.approx(
        tuple(int(F.method_color("CDSP")[i:i + 2], 16) / 255 for i in (1, 3, 5)))
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["demonstration", "CDSP", "DMP", "GMR", "push", "old goal", "new goal"]
    assert ax.get_aspect() == 1.0
    assert_saved_and_not_blank(fig, tmp_path)


def test_perturbation_trajectories_constant_goal_into_given_axes(demos_factory):
    from matplotlib.figure import Figure

    demo = demos_factory(1)[0]
    ax = Figure().add_subplot()
    push = {"kind": "push", "time": 1.0, "before": demo[50], "after": demo[50] + 3.0}
    fig = F.perturbation_trajectories(ax, demo, {"CDSP": demo}, [push],
                                      goal_history=np.zeros((len(demo), 2)))
    assert fig is ax.figure and not fig.legends
    (arrow,) = [p for p in ax.patches if isinstance(p, FancyArrowPatch)]
    assert arrow.get_edgecolor()[:3] == (0.0, 0.0, 0.0)
    assert [line.get_marker() for line in ax.lines][-1] == "*"


def test_perturbation_trajectories_colour_follows_the_full_method_list(demos_factory):
    from matplotlib.figure import Figure

    demo = demos_factory(1)[0]
    ax = Figure().add_subplot()
    F.perturbation_trajectories(ax, demo, {"variant B": demo}, methods=("variant A", "variant B"))
    assert ax.lines[-1].get_color() == F.method_color("variant B", ("variant A", "variant B"))
    assert ax.lines[-1].get_color() != F.method_color("variant B", ("variant B",))


def test_scaling_plot_reports_log_log_slope(tmp_path):
    x = np.array([10.0, 20.0, 40.0, 80.0])
    fig = F.scaling_plot({"CLARABEL": {"x": x, "y": 1e-3 * x**2},
                          "SCS": {"x": x, "y": 1e-2 * x, "std": 1e-3 * x}}, xlabel="monomials")
    ax = fig.axes[0]
    assert ax.get_xscale() == ax.get_yscale() == "log"
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["CLARABEL (slope 2.00)", "SCS (slope 1.00)"]
    assert_saved_and_not_blank(fig, tmp_path)


def test_trajectories_3d(tmp_path, demos_factory):
    demos = demos_factory(3, dim=3)
    fig = F.trajectories_3d(demos, [d * 1.02 for d in demos], np.zeros(3), title="3-D")
    assert fig.axes[0].name == "3d"
    assert fig.axes[0].get_zlabel() == "$x_3$ (mm)"
    assert_saved_and_not_blank(fig, tmp_path)


def test_method_colors_are_fixed_and_distinct():
    assert F.method_color("CDSP") == F.method_color("cdsp") == F.method_color("CDSP", ["X", "Y"])
    methods = ["CDSP", "DMP", "CLF-DM", "GMR", "SEDS", "LPV-DS", "NN"]
    colors = [F.method_color(m, methods) for m in methods]
    assert len(set(colors)) == len(methods)


def test_saved_svg_is_reproducible(tmp_path, results):
    a = F.save_figure(F.accuracy_bars(results["accuracy"]), tmp_path / "a")["svg"].read_bytes()
    b = F.save_figure(F.accuracy_bars(results["accuracy"]), tmp_path / "b")["svg"].read_bytes()
    assert a == b


def test_the_drift_figure_draws_each_training_demo_over_copy_and_the_model_at_the_end():
    """Two test demos, three training demos: demo k's point is mean_t DTW(k, t) / mean copy."""
    task = {"task": "toy", "train_pos": [[4.0, 2.0, 1.0], [6.0, 4.0, 1.0]], "train_ori": [[3.0, 3.0, 3.0], [1.0, 2.0, 3.0]],
            "copy_pos": 1.0, "copy_ori": 2.0, "pos_ratio": 1.2, "ori_ratio": 0.9}
    fig = drift_figure([task], 1.5)
    pos, ori = fig.axes[:2]
    np.testing.assert_allclose(pos.lines[0].get_ydata(), [5.0, 3.0, 1.0])
    np.testing.assert_allclose(ori.lines[0].get_ydata(), [1.0, 1.25, 1.5])
    assert pos.lines[1].get_xydata().tolist() == [[3.5, 1.2]] and ori.lines[1].get_xydata().tolist() == [[3.5, 0.9]]
