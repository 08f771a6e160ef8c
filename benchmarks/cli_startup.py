"""How long the commands that do no simulation take: help and parameter printing.

Each command runs in a fresh process of the project's venv, one after the other; figures
are the process wall times, min / median / max over ``--repeats``. The reference in the
same run is a bare ``python -c pass`` (the interpreter's own start-up). Target (a new
user's first commands): ``--help`` and ``params show`` well under a second. Nothing here is
a test.

Run: ``.venv/bin/python benchmarks/cli_startup.py [--repeats 7] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

from _bench import machine_line, stats, table, write_json

COMMAND = str(Path(sys.executable).parent / "pneumaquad")
CASES = {
    "python -c pass (the interpreter alone)": [sys.executable, "-c", "pass"],
    "pneumaquad --help": [COMMAND, "--help"],
    "pneumaquad robot walk --help": [COMMAND, "robot", "walk", "--help"],
    "pneumaquad params show crr-gamma": [COMMAND, "params", "show", "crr-gamma"],
}


def wall_time(command: list[str]) -> float:
    """Wall time [s] of one process running ``command`` (its output discarded)."""
    begun = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - begun


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--json", default=None)
    arguments = parser.parse_args()
    print(machine_line())
    samples: dict[str, list[float]] = {name: [] for name in CASES}
    for command in CASES.values():  # a first, unmeasured run of each
        wall_time(command)
    for _ in range(arguments.repeats):  # alternated, so that load hits every case alike
        for name, command in CASES.items():
            samples[name].append(wall_time(command))
    measured = {name: stats(values) for name, values in samples.items()}
    print(table(["command", "wall [s] min / median / max"],
                [[name, figures.spread(3)] for name, figures in measured.items()]))
    slowest = max(measured[name].median for name in CASES if name.startswith("pneumaquad"))
    print(f"target: well under 1 s -> slowest median {slowest:.2f} s")
    write_json(arguments.json, {name: figures.as_dict() for name, figures in measured.items()})


if __name__ == "__main__":
    main()
