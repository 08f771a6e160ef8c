"""Ctrl-C as a request to stop at the next safe point, so recordings stay whole.

A KeyboardInterrupt can land anywhere, including in the middle of writing a block of
recording rows. While a simulation runs, :func:`deferred_interrupt` turns the first
SIGINT into a flag that the loop checks between steps or chunks; a second SIGINT
interrupts at once, as usual.
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
