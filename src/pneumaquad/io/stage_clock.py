"""Where a run's wall time went: named stages timed as the run goes.

A :class:`StageClock` accumulates wall-clock seconds per stage (``"simulation"``,
``"recording"``, ``"plots"`` …). Timing a stage costs two ``time.perf_counter`` calls
(well under a microsecond), so the clock can stay on in every run; the ``--profile``
option of the run commands writes what it holds to ``profile.json`` in the run folder
and prints it. Stages may nest only by name prefix convention (``"simulation"`` and
``"simulation: MuJoCo (estimated)"``); the clock itself never subtracts one from another.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["StageClock"]


class StageClock:
    """Wall-clock seconds per named stage, from the clock's creation on.

    Parameters
    ----------
    started : float, optional
        ``time.perf_counter()`` reading that counts as the start of the run (default:
        now). A command passes the moment it started, so start-up counts too.
    """

    def __init__(self, started: float | None = None) -> None:
        self.started = time.perf_counter() if started is None else started
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}

    def add(self, stage: str, seconds: float, calls: int = 1) -> None:
        """Count ``seconds`` [s] of wall time (over ``calls`` calls) to ``stage``."""
        self.seconds[stage] = self.seconds.get(stage, 0.0) + seconds
        self.calls[stage] = self.calls.get(stage, 0) + calls

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        """Time the ``with`` block as (part of) stage ``name``, also when it raises."""
        begun = time.perf_counter()
        try:
            yield
        finally:
            self.add(name, time.perf_counter() - begun)

    def elapsed(self) -> float:
        """Wall time [s] since the clock's start."""
        return time.perf_counter() - self.started

    def report(self, simulated_time: float | None = None) -> dict[str, object]:
        """The stages in the order first timed, the total and what no stage covered.

        Parameters
        ----------
        simulated_time : float, optional
            Simulated time of the run [s]; adds each stage's share of it as a real-time
            factor would read (``simulated / stage seconds``).

        Returns
        -------
        dict
            ``{"total [s]": …, "stages": {name: {"seconds": …, "share": …, "calls": …}},
            "untimed [s]": …}`` (JSON-ready).
        """
        total = self.elapsed()
        stages: dict[str, dict[str, float | int]] = {}
        for name, seconds in self.seconds.items():
            entry: dict[str, float | int] = {
                "seconds": seconds,
                "share": seconds / total if total > 0 else 0.0,
                "calls": self.calls[name],
            }
            if simulated_time is not None and seconds > 0:
                entry["real-time factor"] = simulated_time / seconds
            stages[name] = entry
        top_level = sum(s for name, s in self.seconds.items() if ":" not in name)
        report: dict[str, object] = {"total [s]": total, "stages": stages,
                                     "untimed [s]": max(total - top_level, 0.0)}
        if simulated_time is not None:
            report["simulated time [s]"] = simulated_time
            report["real-time factor"] = simulated_time / total if total > 0 else 0.0
        return report
