"""A small self-contained HTML page builder: headings, text, tables and embedded PNGs.

Every piece of text goes through :func:`html.escape`, so parameter-set names, file paths
and descriptions can hold ``<``, ``&`` or quotes safely. Figures are embedded as
``data:image/png;base64`` URIs, so the written page is a single file that can be mailed
or archived on its own.
"""

from __future__ import annotations

import base64
import html
import math
import re
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

__all__ = ["HtmlPage", "escape", "format_value", "inline_html", "png_data_uri", "table_html",
           "table_markdown"]

_STYLE = (
    "body{font-family:system-ui,sans-serif;max-width:1050px;margin:auto;padding:0 1em;"
    "color:#222}h1{border-bottom:2px solid #446}h2{margin-top:1.8em;border-bottom:1px solid"
    " #bbb}table{border-collapse:collapse;margin:0.6em 0;font-size:0.92em}"
    "td,th{border:1px solid #bbb;padding:2px 8px;text-align:left;vertical-align:top}"
    "th{background:#eef}td.num{text-align:right;font-variant-numeric:tabular-nums}"
    "figure{margin:1em 0}figcaption{font-size:0.9em;color:#444}img{max-width:100%}"
    "p.note{color:#555;font-size:0.92em}pre{background:#f6f6f6;padding:0.5em}"
)


def escape(text: Any) -> str:
    """HTML-escape the string form of ``text`` (quotes included)."""
    return html.escape(str(text), quote=True)


#: Inline code as the Markdown of our texts writes it.
_CODE = re.compile(r"`([^`]+)`")
#: A relative path into a folder beside the report (a run's files, a sub-report, a
#: video): at least one folder, so that a bare file name in a label stays text.
_FILE = re.compile(r"(?<![\w/.:-])((?:[\w.-]+/)+[\w-][\w.-]*\."
                   r"(?:html|md|png|gif|mp4|csv|parquet|json|toml|npz|xml))(?![\w/])")


#: A link :func:`inline_html` made.
_LINK = re.compile(r"<a href='([^']+)'>\1</a>")


def inline_html(text: Any) -> str:
    """Escaped text with its Markdown code spans as ``<code>`` and relative file paths
    (``step-train/report/report.html``, ``robot-walk/video.mp4``) as links."""
    escaped = escape(text)
    escaped = _FILE.sub(r"<a href='\1'>\1</a>", escaped)
    return _CODE.sub(r"<code>\1</code>", escaped)


def format_value(value: Any, digits: int = 5) -> str:
    """Format a table cell: floats to ``digits`` significant digits, NaN/None as "–".

    Parameters
    ----------
    value : Any
        A number, bool, string, None or anything with a ``str``.
    digits : int
        Significant digits of floats.

    Returns
    -------
    str
        Plain text (not yet escaped).
    """
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return "–" if not math.isfinite(value) else f"{value:.{digits}g}"
    return str(value)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def table_html(headers: Sequence[str], rows: Iterable[Sequence[Any]], digits: int = 5) -> str:
    """An HTML table; numbers are right-aligned, every cell is escaped (text cells through
    :func:`inline_html`).

    Parameters
    ----------
    headers : sequence of str
        Column titles.
    rows : iterable of sequences
        Cell values, formatted with :func:`format_value`.
    digits : int
        Significant digits of floats.

    Returns
    -------
    str
        ``<table>...</table>``.
    """
    head = "".join(f"<th>{escape(h)}</th>" for h in headers)
    body = []
    for row in rows:
        cells = "".join(
            f"<td class='num'>{escape(format_value(c, digits))}</td>"
            if _is_number(c)
            else f"<td>{inline_html(format_value(c, digits))}</td>"
            for c in row
        )
        body.append(f"<tr>{cells}</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def table_markdown(headers: Sequence[str], rows: Iterable[Sequence[Any]],
                   digits: int = 5) -> str:
    """A Markdown table of the same cells as :func:`table_html` (formatted with
    :func:`format_value`; a ``|`` in a cell is escaped), ending with a newline."""

    def cell(value: Any) -> str:
        return format_value(value, digits).replace("|", "\\|")

    lines = ["| " + " | ".join(cell(h) for h in headers) + " |",
             "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def png_data_uri(png: bytes) -> str:
    """``data:image/png;base64,...`` URI of PNG bytes."""
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


class HtmlPage:
    """Collects blocks of a report page and renders one self-contained HTML file.

    Parameters
    ----------
    title : str
        Page title and first heading.
    """

    def __init__(self, title: str) -> None:
        self.title = title
        self.blocks: list[str] = []

    def heading(self, text: str, level: int = 2) -> None:
        """Add a heading ``<h2>`` (or another level 1–6)."""
        level = min(max(level, 1), 6)
        self.blocks.append(f"<h{level}>{escape(text)}</h{level}>")

    def paragraph(self, text: str, note: bool = False) -> None:
        """Add a paragraph (:func:`inline_html`: code spans and file links); ``note``
    renders it smaller and grey."""
        css = " class='note'" if note else ""
        self.blocks.append(f"<p{css}>{inline_html(text)}</p>")

    def preformatted(self, text: str) -> None:
        """Add preformatted text (e.g. an error message)."""
        self.blocks.append(f"<pre>{escape(text)}</pre>")

    def table(self, headers: Sequence[str], rows: Iterable[Sequence[Any]], digits: int = 5) -> None:
        """Add a table (see :func:`table_html`)."""
        self.blocks.append(table_html(headers, rows, digits))

    def figure(self, png: Path | bytes, caption: str = "") -> None:
        """Embed a PNG or GIF (file path or bytes) as a base64 data URI, with a caption."""
        data = Path(png).read_bytes() if isinstance(png, Path) else png
        alt = escape(caption or "figure")
        caption_html = f"<figcaption>{escape(caption)}</figcaption>" if caption else ""
        uri = (png_data_uri(data) if not data.startswith(b"GIF8")
               else "data:image/gif;base64," + base64.b64encode(data).decode("ascii"))
        self.blocks.append(f"<figure><img alt='{alt}' src='{uri}'>{caption_html}</figure>")

    def render(self) -> str:
        """The whole page as HTML text."""
        title = escape(self.title)
        return "\n".join(
            [
                "<!doctype html>",
                "<html lang='en'><head><meta charset='utf-8'>",
                f"<title>{title}</title><style>{_STYLE}</style></head><body>",
                f"<h1>{title}</h1>",
                *self.blocks,
                "</body></html>",
                "",
            ]
        )

    def write(self, path: Path) -> Path:
        """Write the page (UTF-8) and return its path; parent folders are created. A file
        link whose file is not beside the page (a path of the repository, a file not
        written) is shown as code instead."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)

        def checked(match: re.Match[str]) -> str:
            target = html.unescape(match.group(1))
            if (path.parent / target).exists():
                return match.group(0)
            return f"<code>{match.group(1)}</code>"

        path.write_text(_LINK.sub(checked, self.render()), encoding="utf-8")
        return path
