"""Errors of robot runs, importable without loading MuJoCo."""

__all__ = ["SimulationDivergedError"]


class SimulationDivergedError(RuntimeError):
    """MuJoCo met a non-finite or huge acceleration (it would silently reset the state)."""
