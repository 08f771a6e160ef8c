"""Imports point down the layers of the design brief (DESIGN.md §6): planning geometry
(gait) knows no robot, the robot simulation knows no walking driver, console or network."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "pneumaquad"

#: package -> packages it must not import
FORBIDDEN = {
    "gait": ("robot", "locomotion", "console", "network", "reporting"),
    "robot": ("locomotion", "console", "network", "reporting"),
    "locomotion": ("console", "network"),
    "physics": ("robot", "rig", "locomotion", "gait", "console", "network"),
}


def _imported_packages(path: Path) -> set[str]:
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


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_imports_point_down_the_layers(package: str) -> None:
    offenders = []
    for path in sorted((PACKAGE / package).glob("*.py")):
        wrong = _imported_packages(path) & set(FORBIDDEN[package])
        offenders += [f"{path.name} imports pneumaquad.{name}" for name in sorted(wrong)]
    assert offenders == []
