"""The version is stated once (pyproject.toml) and the changelog's latest entry agrees."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pneumaquad

ROOT = Path(__file__).resolve().parents[1]


def test_package_pyproject_and_changelog_versions_agree() -> None:
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    latest = re.search(r"^## (\S+)", (ROOT / "CHANGELOG.md").read_text(), re.MULTILINE)
    assert latest is not None
    assert pneumaquad.__version__ == declared == latest.group(1)
