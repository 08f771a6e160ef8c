"""Writing a measured :class:`~pneumaquad.reporting.cost_table.CostTable`: HTML page with
a bar chart, Markdown table and JSON figures."""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path

from pneumaquad.reporting.plotting import DPI, plt

from .cost_table import CostTable
from .html import HtmlPage, format_value

__all__ = ["cost_table_markdown", "cost_table_rows", "plot_cost_table", "write_cost_table_report"]

HEADERS = (
    "case",
    "mean [µs/step]",
    "std [µs]",
    "min [µs]",
    "change [µs]",
    "change [%]",
    "thesis TET [µs]",
    "thesis reduction [%]",
    "RMS tracking error [mm]",
)


def cost_table_rows(table: CostTable) -> list[list[object]]:
    """Table rows in :data:`HEADERS` order (the complete model's changes as None)."""
    rows: list[list[object]] = []
    for index, row in enumerate(table.rows):
        first = index == 0
        rows.append(
            [
                row.case,
                row.mean_us,
                row.std_us,
                row.min_us,
                None if first else row.change_us,
                None if first else row.change_percent,
                row.thesis_us,
                row.thesis_reduction_percent,
                row.rms_error * 1e3,
            ]
        )
    return rows


def cost_table_markdown(table: CostTable) -> str:
    """The table as Markdown (numbers to 4 significant digits)."""
    lines = ["| " + " | ".join(HEADERS) + " |", "|" + "---|" * len(HEADERS)]
    for row in cost_table_rows(table):
        lines.append("| " + " | ".join(format_value(cell, 4) for cell in row) + " |")
    return "\n".join(lines) + "\n"


def plot_cost_table(table: CostTable, path: Path) -> Path:
    """Horizontal bars: mean µs per step ± std per case, the thesis's TETs beside them."""
    names = [row.case for row in table.rows][::-1]
    means = [row.mean_us for row in table.rows][::-1]
    stds = [row.std_us for row in table.rows][::-1]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True, layout="constrained")
    axes[0].barh(names, means, xerr=stds, color="C0", capsize=3)
    axes[0].set_xlabel("µs per 1 ms control step (this machine)")
    axes[1].barh(names, [row.thesis_us for row in table.rows][::-1], color="0.6")
    axes[1].set_xlabel("thesis TET, µs (xPC target, 2011)")
    for ax in axes:
        ax.grid(True, axis="x", alpha=0.35)
    fig.suptitle("Component cost (thesis Table 3 analogue)")
    path = Path(path)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def _clean(value: object) -> object:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    return value


def write_cost_table_report(table: CostTable, folder: Path) -> Path:
    """Write ``report.html``, ``cost-table.png``, ``cost-table.md`` and ``cost-table.json``.

    Returns
    -------
    Path
        The written ``report.html``.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    page = HtmlPage("pneumaquad component cost table (thesis Table 3 analogue)")
    page.paragraph(
        f"Parameter set {table.parameter_set}: closed-loop sine about half stroke, "
        f"{table.steps} control steps of {table.control_step * 1e3:g} ms with "
        f"{table.substeps} substeps; the compiled loop (PID + rig kernel + recording row) "
        f"timed {table.repeats} times per case, interleaved. Machine: {table.machine}."
    )
    page.table(HEADERS, cost_table_rows(table), digits=4)
    page.paragraph(
        "change [%] = 100·(mean − complete)/complete; negative is faster. The thesis printed "
        "the reduction (minus this). Its 'no controller' row is against its open-loop "
        "complete model (37.260 µs); ours against the closed-loop one.",
        note=True,
    )
    page.table(("case", "how it was made"), [(row.case, row.how) for row in table.rows])
    page.paragraph(
        "The 'area part only' and 'pressure part only' cases are parameter overrides: the "
        "underlapped kernel still evaluates both the polynomial and the tanh, so they show "
        "the effect of the simpler curves on the flow regimes, not the saving of removing "
        "the arithmetic. A valve option selecting each part separately is needed for that.",
        note=True,
    )
    page.figure(
        plot_cost_table(table, folder / "cost-table.png"),
        "Mean µs per control step (error bar: standard deviation) and the thesis's average TETs.",
    )
    (folder / "cost-table.md").write_text(cost_table_markdown(table), encoding="utf-8")
    document = _clean({**asdict(table), "reference": "Daepp 2011, Table 3 (5.5.3)"})
    (folder / "cost-table.json").write_text(
        json.dumps(document, indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    return page.write(folder / "report.html")
