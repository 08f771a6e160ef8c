"""Imports point down the layers of the design brief (DESIGN.md §6, README "Layout").

Each package has a rank; a module may import its own package and packages of lower rank
only. Packages of one rank (e.g. ``gait`` and ``analysis``) do not import each other."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "pneumaquad"

#: package -> rank, top (front-ends) to bottom (parameters); imports go to lower ranks
RANK = {
    "cli": 10,
    "console": 9,
    "demo": 9,
    "network": 8,
    "interop": 8,
    "validation": 8,
    "studies": 8,
    "locomotion": 7,
    "robot": 6,
    "reporting": 5,
    "identification": 5,
    "rig": 4,
    "gait": 4,
    "core": 3,
    "analysis": 2,
    "io": 1,
    "params": 0,
}


def _imported_packages(path: Path) -> set[str]:
    """Top-level pneumaquad packages that ``path`` imports (absolute or relative)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: set[str] = set()
    package = path.parent.relative_to(PACKAGE.parent).parts  # e.g. ('pneumaquad', 'robot')
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against the module's package
                base = package[: len(package) - node.level + 1]
                names.add(".".join((*base, node.module or "")).rstrip("."))
            elif node.module:
                names.add(node.module)
    return {name.split(".")[1] for name in names
            if name.startswith("pneumaquad.") and name.count(".") >= 1}


def test_every_package_has_a_rank() -> None:
    packages = {path.name for path in PACKAGE.iterdir()
                if path.is_dir() and (path / "__init__.py").exists()}
    assert packages == set(RANK)


def test_the_package_root_holds_no_modules_but_the_entry() -> None:
    assert sorted(path.name for path in PACKAGE.glob("*.py")) == ["__init__.py"]


@pytest.mark.parametrize("package", sorted(RANK))
def test_imports_point_down_the_layers(package: str) -> None:
    offenders = []
    for path in sorted((PACKAGE / package).rglob("*.py")):
        for name in sorted(_imported_packages(path)):
            if name != package and name in RANK and RANK[name] >= RANK[package]:
                where = path.relative_to(PACKAGE)
                offenders.append(f"{where} imports pneumaquad.{name}")
    assert offenders == []
