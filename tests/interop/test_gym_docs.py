"""The Python examples of docs/gymnasium.md run as printed."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[2] / "docs" / "gymnasium.md"


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)


def test_the_page_has_python_examples() -> None:
    assert len(_python_blocks()) >= 2


@pytest.mark.parametrize("index", range(len(_python_blocks())))
def test_gymnasium_page_example_runs(index: int) -> None:
    exec(compile(_python_blocks()[index], f"docs/gymnasium.md python block {index}", "exec"), {})
