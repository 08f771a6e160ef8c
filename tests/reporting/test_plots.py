"""The figures that compare near-equal runs, held pressures and still joints read at a
glance: differences drawn, targets drawn, no magnified noise."""

from __future__ import annotations

import matplotlib
import numpy as np

from pneumaquad.reporting.display_units import display_units
from pneumaquad.reporting.plotting import plot_difference, plot_held_pressures, plt
from pneumaquad.reporting.robot_plots import MIN_ANGLE_SPAN, _at_least_span

matplotlib.use("Agg")


def _recording(offset: float) -> dict[str, np.ndarray]:
    time = np.linspace(0.0, 1.0, 101)
    return {"time [s]": time, "position [m]": 0.02 + 0.01 * time + offset,
            "cap pressure [Pa]": 3e5 + 1e3 * time + 100 * offset / 1e-6,
            "rod pressure [Pa]": 2e5 - 1e3 * time}


def test_difference_plot_draws_the_difference(tmp_path) -> None:
    figures = []
    original = plt.close
    plt.close = lambda fig=None: figures.append(fig)  # keep the figure to look at
    try:
        path = plot_difference(_recording(2.54e-5), _recording(0.0), tmp_path / "d.png",
                               units=display_units("us"))
    finally:
        plt.close = original
    assert path.stat().st_size > 5_000
    position_difference = figures[0].axes[1].lines[0].get_ydata()
    np.testing.assert_allclose(position_difference, 1.0)  # 0.001 in
    cap_difference = figures[0].axes[2].lines[0].get_ydata()
    np.testing.assert_allclose(cap_difference, 2540.0 / 6894.757, rtol=1e-6)  # psi


def test_held_pressures_draw_their_targets(tmp_path) -> None:
    figures = []
    original = plt.close
    plt.close = lambda fig=None: figures.append(fig)
    try:
        plot_held_pressures({"5 V": _recording(0.0)}, {"5 V": (3.1e5, 1.9e5)},
                            tmp_path / "h.png", units=display_units("us"))
    finally:
        plt.close = original
    (axis,) = figures[0].axes
    levels = sorted(line.get_ydata()[0] for line in axis.lines if line.get_linestyle() == ":"
                    and len(line.get_ydata()))
    np.testing.assert_allclose(levels, np.array([1.9e5, 3.1e5]) / 6894.757, rtol=1e-6)


def test_a_still_joint_is_a_flat_line_not_magnified_noise() -> None:
    figure, axis = plt.subplots()
    axis.plot([0.0, 1.0, 2.0], [90.0, 90.0002, 89.9994])
    _at_least_span(axis, MIN_ANGLE_SPAN)
    low, high = axis.get_ylim()
    assert high - low >= MIN_ANGLE_SPAN
    figure.canvas.draw()
    assert axis.yaxis.get_offset_text().get_text() == ""
    plt.close(figure)
