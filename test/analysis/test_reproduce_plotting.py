"""The shared reproduction drawing: a headless PNG, log floors, one line per joint, event lines."""

from __future__ import annotations

import numpy as np

from rns_ros.analysis.reproduce import plotting as plot


def test_save_figure_writes_a_titled_png_headless(tmp_path):
    drawn = []

    def draw(figure):
        ax = figure.add_subplot()
        ax.plot([0.0, 1.0], [0.0, 1.0])
        drawn.append(figure)

    path = tmp_path / "line.png"
    plot.save_figure(path, (4.0, 3.0), "Fig. 0.1: a line", draw)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    figure = drawn[0]
    assert figure.get_suptitle() == "Fig. 0.1: a line"
    assert tuple(figure.get_size_inches()) == (4.0, 3.0)


def test_floored_keeps_positive_values_and_lifts_zeros():
    values = np.array([0.0, 1e-15, 2e-3, 5.0])
    np.testing.assert_array_equal(plot.floored(values), [plot.FLOOR, plot.FLOOR, 2e-3, 5.0])
    assert plot.floored(np.array([0.0]), 1e-16)[0] == 1e-16


def _axes():
    from matplotlib.figure import Figure

    return Figure().add_subplot()


def test_joint_lines_draw_one_labelled_line_per_column():
    ax = _axes()
    t = np.linspace(0.0, 1.0, 5)
    rates = np.outer(t, [1.0, -2.0, 3.0])
    plot.joint_lines(ax, t, rates, plot.THETA_DOT_LABEL, lw=0.9)
    lines = ax.get_lines()
    assert [line.get_label() for line in lines] == [rf"$\dot\theta_{i}$" for i in (1, 2, 3)]
    for column, line in enumerate(lines):
        np.testing.assert_array_equal(line.get_ydata(), rates[:, column])
        assert line.get_linewidth() == 0.9


def test_event_lines_and_time_axes():
    ax = _axes()
    plot.event_lines(ax, [1.0, 2.5], alpha=0.6)
    plot.time_axes(ax, "deviation [deg]", "base attitude")
    assert [line.get_xdata()[0] for line in ax.get_lines()] == [1.0, 2.5]
    assert all(line.get_alpha() == 0.6 for line in ax.get_lines())
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) == (
        "t [s]",
        "deviation [deg]",
        "base attitude",
    )
    plot.label_axes(ax, None, "other [-]")
    assert ax.get_xlabel() == "t [s]"  # None keeps a shared x axis unlabelled
