"""The demo report is written by the one HTML page builder (reporting.html.HtmlPage)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from pneumaquad.demo.run import DemoReport


def test_demo_report_sections_escape_and_embed(tmp_path: Path) -> None:
    figure, axes = plt.subplots()
    axes.plot([0.0, 1.0])
    figure.savefig(tmp_path / "plot.png")
    plt.close(figure)
    report = DemoReport(tmp_path)
    report.add("Step <6 V>", "pressures & position", tmp_path / "plot.png",
               {"rise time [s]": 0.123456, "runs": 3})
    page = report.write().read_text(encoding="utf-8")
    assert "<h2>Step &lt;6 V&gt;</h2>" in page and "pressures &amp; position" in page
    assert "0.1235" in page and "data:image/png;base64," in page
    markdown = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "| rise time [s] | 0.1235 |" in markdown and "![Step <6 V>](plot.png)" in markdown
