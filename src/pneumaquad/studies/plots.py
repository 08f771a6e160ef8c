"""Figures of a study's table, as PNG bytes: a metric's distribution (histogram and box
plot, the box plot read like the thesis's Figs. 13-14: median line, quartile box,
whiskers to the furthest cases within 1.5 box heights, the others marked), a metric
against each varied parameter, and the cases as parallel coordinates."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = ["distribution_png", "parallel_png", "scatter_png"]


def _png(figure: Figure) -> bytes:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=100)
    plt.close(figure)
    return buffer.getvalue()


def distribution_png(metric: str, values: np.ndarray) -> bytes:
    """Histogram and box plot of one metric's finite values."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    figure, (histogram, box) = plt.subplots(1, 2, figsize=(9, 3.2),
                                            gridspec_kw={"width_ratios": [3, 1]})
    histogram.hist(values, bins=min(40, max(5, values.size // 8)), color="#4a6fa5")
    histogram.set_xlabel(metric)
    histogram.set_ylabel("cases")
    box.boxplot(values, whis=1.5, widths=0.5,
                medianprops={"color": "red"}, flierprops={"marker": "+", "markeredgecolor": "red"})
    box.set_xticks([])
    box.set_ylabel(metric)
    figure.tight_layout()
    return _png(figure)


def scatter_png(metric: str, values: np.ndarray, parameters: dict[str, np.ndarray],
                failed: np.ndarray) -> bytes:
    """The metric against each numeric varied parameter; failed cases as red marks on the
    parameter axis."""
    names = list(parameters)
    figure, axes = plt.subplots(1, len(names), figsize=(3.6 * len(names), 3.0), squeeze=False)
    values = np.asarray(values, dtype=float)
    for axis, name in zip(axes[0], names, strict=True):
        column = np.asarray(parameters[name], dtype=float)
        axis.scatter(column, values, s=8, alpha=0.6, color="#4a6fa5")
        if failed.any():
            low = np.nanmin(values) if np.isfinite(values).any() else 0.0
            axis.scatter(column[failed], np.full(failed.sum(), low), marker="x", color="red",
                         s=16, label="failed")
            axis.legend(fontsize=7)
        axis.set_xlabel(name)
    axes[0][0].set_ylabel(metric)
    figure.tight_layout()
    return _png(figure)


def parallel_png(columns: dict[str, np.ndarray], colour_by: str) -> bytes:
    """Every case as a line across its parameters and metrics, each axis scaled to its
    own range, coloured by ``colour_by``."""
    names = list(columns)
    data = np.column_stack([np.asarray(columns[name], dtype=float) for name in names])
    finite = np.all(np.isfinite(data), axis=1)
    data = data[finite]
    low, high = data.min(axis=0), data.max(axis=0)
    scaled = (data - low) / np.where(high > low, high - low, 1.0)
    colour = scaled[:, names.index(colour_by)]
    figure, axis = plt.subplots(figsize=(max(6.0, 1.8 * len(names)), 3.6))
    colours = plt.get_cmap("viridis")(colour)
    for row, line_colour in zip(scaled, colours, strict=True):
        axis.plot(range(len(names)), row, color=line_colour, alpha=0.35, linewidth=0.8)
    axis.set_xticks(range(len(names)), names, rotation=15, ha="right", fontsize=8)
    axis.set_yticks([0, 1], ["min", "max"])
    axis.set_title(f"cases, coloured by {colour_by}", fontsize=9)
    figure.tight_layout()
    return _png(figure)
