"""The documentation site's sources (mkdocs.yml, docs/): the checks that need no build.
`make docs` builds the site with every warning an error (CI runs it after the tests)."""

from __future__ import annotations

from pathlib import Path

import pneumaquad

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_every_top_level_name_links_to_its_definition() -> None:
    page = (DOCS / "api" / "index.md").read_text(encoding="utf-8")
    assert "`pneumaquad.__version__`" in page
    for name, module in pneumaquad._PUBLIC.items():
        target = module if module.rsplit(".", 1)[1] == name else f"{module}.{name}"
        assert f"[`{name}`][{target}]" in page, name

