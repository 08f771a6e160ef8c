"""Shared helpers of the benchmark scripts: repeat statistics, tables, machine line, JSON.

Not a test: nothing here asserts on wall-clock time. Scripts in this folder import it as
``_bench`` (the folder of a script run as ``python benchmarks/NAME.py`` is on sys.path).
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numba
import numpy as np


@dataclass(frozen=True)
class Stats:
    """Summary of repeated measurements (any unit)."""

    samples: tuple[float, ...]

    @property
    def min(self) -> float:
        return min(self.samples)

    @property
    def median(self) -> float:
        return statistics.median(self.samples)

    @property
    def max(self) -> float:
        return max(self.samples)

    @property
    def mean(self) -> float:
        return statistics.fmean(self.samples)

    @property
    def std(self) -> float:
        return statistics.stdev(self.samples) if len(self.samples) > 1 else 0.0

    def scaled(self, factor: float) -> Stats:
        """The same samples multiplied by ``factor`` (unit change)."""
        return Stats(tuple(value * factor for value in self.samples))

    def spread(self, digits: int = 2) -> str:
        """``min / median / max`` as text."""
        return f"{self.min:.{digits}f} / {self.median:.{digits}f} / {self.max:.{digits}f}"

    def as_dict(self) -> dict[str, Any]:
        return {
            "min": self.min,
            "median": self.median,
            "max": self.max,
            "mean": self.mean,
            "std": self.std,
            "samples": list(self.samples),
        }


def stats(samples: Sequence[float]) -> Stats:
    """Stats of a non-empty sequence of numbers."""
    if len(samples) == 0:
        raise ValueError("no samples")
    return Stats(tuple(float(value) for value in samples))


def table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """Plain-text table: first column left-aligned, the others right-aligned."""
    cells = [[str(h) for h in headers]] + [[str(c) for c in row] for row in rows]
    widths = [max(len(row[i]) for row in cells) for i in range(len(headers))]

    def line(row: Sequence[str]) -> str:
        return "  ".join(
            cell.ljust(width) if i == 0 else cell.rjust(width)
            for i, (cell, width) in enumerate(zip(row, widths, strict=True))
        )

    rule = "  ".join("-" * width for width in widths)
    return "\n".join([line(cells[0]), rule, *(line(row) for row in cells[1:])])


def _cpu_model() -> str:
    try:
        for text in Path("/proc/cpuinfo").read_text().splitlines():
            if text.startswith("model name"):
                return text.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def machine() -> dict[str, Any]:
    """Where and when the figures were taken."""
    return {
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "cpu": _cpu_model(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "platform": platform.platform(),
    }


def machine_line() -> str:
    m = machine()
    return (
        f"{m['date']}  {m['cpu']} ({m['cpus']} logical CPUs)  Python {m['python']}  "
        f"numba {m['numba']}  numpy {m['numpy']}"
    )


def run_child(code: str, argument: dict[str, Any], env_updates: dict[str, str]) -> dict[str, Any]:
    """Run ``code`` in a fresh interpreter with one JSON argument; parse its last stdout line.

    The child's total wall time as seen from here is added as ``process_wall_s``.
    """
    env = dict(os.environ)
    env.update(env_updates)
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", code, json.dumps(argument)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"benchmark child failed ({done.returncode}):\n{done.stderr}")
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    result["process_wall_s"] = wall
    return result


def write_json(path: str | None, payload: dict[str, Any]) -> None:
    """Write the figures with the machine description, if a path was given."""
    if path is None:
        return
    document = {"machine": machine(), **payload}
    Path(path).write_text(json.dumps(document, indent=2, default=_jsonable) + "\n")
    print(f"\nfigures written to {path}")


def _jsonable(value: object) -> object:
    if isinstance(value, Stats):
        return value.as_dict()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
