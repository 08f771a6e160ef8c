"""Ctrl-C as a request to stop at the next safe point, so recordings stay whole.

A KeyboardInterrupt can land anywhere, including in the middle of writing a block of
recording rows. While a simulation runs, :func:`deferred_interrupt` turns the first
SIGINT into a flag that the loop checks between steps or chunks; a second SIGINT
interrupts at once, as usual. While a command finishes what a run left (plots, a video),
:func:`counted_interrupts` counts every SIGINT instead, and the command acts on them where
it can (:meth:`InterruptCount.check`): no KeyboardInterrupt lands in the middle of writing a
file, or in a finaliser, where Python prints it as "Exception ignored".
"""

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass


@dataclass
class StopRequest:
    """Set when the user asked the running simulation to stop."""

    requested: bool = False


@contextmanager
def deferred_interrupt() -> Iterator[StopRequest]:
    """Within the block, the first Ctrl-C sets ``requested`` instead of raising.

    Outside the main thread (where signal handlers cannot be installed) the flag is
    never set and Ctrl-C behaves as usual.
    """
    request = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield request
        return

    def handler(signum, frame):
        if request.requested:
            raise KeyboardInterrupt
        request.requested = True

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield request
    finally:
        signal.signal(signal.SIGINT, previous)


@dataclass
class InterruptCount:
    """Ctrl-Cs counted by :func:`counted_interrupts` (``presses``), and how many of them
    :meth:`check` has raised."""

    presses: int = 0
    raised: int = 0

    def check(self) -> None:
        """Raise KeyboardInterrupt for one Ctrl-C not raised yet (one per call)."""
        if self.presses > self.raised:
            self.raised += 1
            raise KeyboardInterrupt


@contextmanager
def counted_interrupts() -> Iterator[InterruptCount]:
    """Within the block, every Ctrl-C is counted instead of raised (module docstring).

    Outside the main thread (where signal handlers cannot be installed) nothing is counted
    and Ctrl-C behaves as usual.
    """
    count = InterruptCount()
    if threading.current_thread() is not threading.main_thread():
        yield count
        return

    def handler(signum: int, frame: object) -> None:
        count.presses += 1

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield count
    finally:
        signal.signal(signal.SIGINT, previous)
