"""Build hooks of the documentation site (``hooks:`` in mkdocs.yml).

The parameter reference of parameters.md is generated from the parameter schema while the
site is built, so it cannot fall behind the models.
"""

from __future__ import annotations

from typing import Any

from pneumaquad.params.reference import insert_reference


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """Put the generated parameter tables into parameters.md; other pages pass through."""
    if page.file.src_uri == "parameters.md":
        return insert_reference(markdown)
    return markdown
