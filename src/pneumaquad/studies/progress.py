"""The progress line of a running study: cases done, failures, cases/s and time left."""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["StudyProgress", "progress_text"]


def _duration(seconds: float) -> str:
    """``"1 h 02 min"``, ``"3 min 05 s"``, ``"12 s"``."""
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return f"{hours} h {minutes:02d} min"
    return f"{minutes} min {secs:02d} s" if minutes else f"{secs} s"


def progress_text(name: str, done: int, total: int, failed: int, rate: float) -> str:
    """One progress line: ``"study X: 120/256 cases (47 %), 3 failed, 12.3 cases/s,
    11 s left"`` (``rate`` in cases/s over this run's cases; no time left while it is 0)."""
    share = 100.0 * done / total if total else 100.0
    left = f", {_duration((total - done) / rate)} left" if rate > 0 and done < total else ""
    return (f"study {name}: {done}/{total} cases ({share:.0f} %), {failed} failed, "
            f"{rate:.3g} cases/s{left}")


class StudyProgress:
    """Writes :func:`progress_text` to ``stream`` (stderr) as cases finish: over one line
    on a terminal, else a line at most every ``interval`` seconds (and the last one).

    Parameters
    ----------
    name : str
    total : int
        Cases of the study.
    already_done, already_failed : int
        Cases recorded before this run (a resumed study): counted as done, not in the rate.
    stream : text stream, optional
    interval : float
        Seconds between lines on a stream that is not a terminal.
    """

    def __init__(self, name: str, total: int, already_done: int = 0, already_failed: int = 0,
                 stream: TextIO | None = None, interval: float = 5.0) -> None:
        self.name, self.total = name, total
        self.done, self.failed = already_done, already_failed
        self.stream = stream if stream is not None else sys.stderr
        self.terminal = bool(getattr(self.stream, "isatty", lambda: False)())
        self.interval = interval
        self.started = time.perf_counter()
        self.run_cases = 0
        self.last_line = -float("inf")

    @property
    def rate(self) -> float:
        """Cases/s of this run so far."""
        elapsed = time.perf_counter() - self.started
        return self.run_cases / elapsed if elapsed > 0 else 0.0

    def update(self, finished: int, failed: int) -> None:
        """Count ``finished`` more cases, ``failed`` of them failed, and show the line."""
        self.done += finished
        self.failed += failed
        self.run_cases += finished
        now = time.perf_counter()
        last = self.done >= self.total
        if not self.terminal and not last and now - self.last_line < self.interval:
            return
        self.last_line = now
        text = progress_text(self.name, self.done, self.total, self.failed, self.rate)
        self.stream.write(f"\r{text}\033[K" if self.terminal else f"{text}\n")
        self.stream.flush()

    def close(self) -> None:
        """End the line on a terminal."""
        if self.terminal:
            self.stream.write("\n")
            self.stream.flush()
