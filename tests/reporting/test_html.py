"""The HTML page builder escapes text and embeds figures as data URIs."""

from __future__ import annotations

import base64
import math
from pathlib import Path

from pneumaquad.reporting.html import HtmlPage, escape, format_value, table_html

PNG_1X1 = base64.b64decode(
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg=="
)


def test_escape_and_format() -> None:
    assert escape('<a href="x">&') == "&lt;a href=&quot;x&quot;&gt;&amp;"
    assert format_value(math.nan) == "–"
    assert format_value(None) == "–"
    assert format_value(True) == "yes"
    assert format_value(0.123456789, 4) == "0.1235"
    assert format_value(12) == "12"


def test_table_escapes_cells_and_right_aligns_numbers() -> None:
    text = table_html(["<k>", "v"], [["<script>x</script>", 1.5]])
    assert "<script>" not in text
    assert "&lt;script&gt;x&lt;/script&gt;" in text
    assert "&lt;k&gt;" in text
    assert "<td class='num'>1.5</td>" in text


def test_page_is_one_file_with_embedded_png(tmp_path: Path) -> None:
    figure = tmp_path / "f.png"
    figure.write_bytes(PNG_1X1)
    page = HtmlPage("Title <i>")
    page.heading("Section & co")
    page.paragraph("a < b")
    page.figure(figure, "caption 'quoted'")
    page.figure(PNG_1X1)
    path = page.write(tmp_path / "out" / "report.html")
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!doctype html>")
    assert "<title>Title &lt;i&gt;</title>" in text
    assert "<h2>Section &amp; co</h2>" in text
    assert "<p>a &lt; b</p>" in text
    assert text.count("src='data:image/png;base64,") == 2
    assert base64.b64encode(PNG_1X1).decode() in text
    assert "caption &#x27;quoted&#x27;" in text


def test_text_gets_code_spans_and_links_to_files_beside_the_page(tmp_path) -> None:
    from pneumaquad.reporting.html import HtmlPage

    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "video.mp4").write_bytes(b"")
    page = HtmlPage("t")
    page.paragraph("see `pneumaquad report run` & run/video.mp4, docs/robot.md <b>")
    page.table(["figure", "value"], [("report", "run/video.mp4")])
    text = page.write(tmp_path / "report.html").read_text(encoding="utf-8")
    assert "<code>pneumaquad report run</code>" in text
    assert text.count("<a href='run/video.mp4'>run/video.mp4</a>") == 2
    assert "<code>docs/robot.md</code>" in text  # not beside the page: no dead link
    assert "&lt;b&gt;" in text and "`" not in text
