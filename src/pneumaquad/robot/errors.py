"""Errors of robot runs, importable without loading MuJoCo."""

from __future__ import annotations

from pathlib import Path

__all__ = ["SimulationDivergedError"]


class SimulationDivergedError(RuntimeError):
    """The coupled state went non-finite or huge (MuJoCo's unstable-state warnings, or a
    cylinder's piston or chambers); the run stops at ``time`` [s] instead of resetting.
    ``folder`` is the run folder written before it was raised, if any."""

    def __init__(self, message: str, time: float = float("nan")) -> None:
        super().__init__(message)
        self.time = time
        self.folder: Path | None = None
