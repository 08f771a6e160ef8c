"""Keyboard control of walking from the terminal that runs the console.

The browser page (viser) does not pass key presses to Python, so the keys are read from
the console's own terminal (when it is one): single key presses, no Enter needed.

=======  ==========================================
key      effect
=======  ==========================================
w / s    body speed +5 / −5 mm/s (±50 mm/s at most)
a / d    heading +15° / −15° (counter-clockwise +)
q / e    yaw rate +1 / −1 °/s (automatic; ±5 °/s at most)
space    stop (speed and yaw rate 0)
m        next walking mode: off → automatic → shared
=======  ==========================================
"""

from __future__ import annotations

import math
import sys
import threading
from collections.abc import Callable

from .walking import MAX_SPEED, MAX_YAW_RATE, WALKING_MODES

__all__ = ["HELP", "KeyboardControl", "key_command"]

SPEED_STEP = 0.005  # [m/s]
HEADING_STEP = math.radians(15.0)
YAW_RATE_STEP = math.radians(1.0)  # [rad/s]
HELP = ("keys: w/s speed ±5 mm/s, a/d heading ±15°, q/e yaw rate ±1°/s (automatic), "
        "space stop, m walking mode")


def key_command(key: str, mode: str, speed: float, heading: float, yaw_rate: float = 0.0
                ) -> tuple[str, float, float, float]:
    """The walking command (mode, speed [m/s], heading [rad], yaw rate [rad/s]) after
    pressing ``key``."""
    key = key.lower()
    if key == "w":
        speed = min(speed + SPEED_STEP, MAX_SPEED)
    elif key == "s":
        speed = max(speed - SPEED_STEP, -MAX_SPEED)
    elif key == "a":
        heading += HEADING_STEP
    elif key == "d":
        heading -= HEADING_STEP
    elif key == "q":
        yaw_rate = min(yaw_rate + YAW_RATE_STEP, MAX_YAW_RATE)
    elif key == "e":
        yaw_rate = max(yaw_rate - YAW_RATE_STEP, -MAX_YAW_RATE)
    elif key == " ":
        speed = yaw_rate = 0.0
    elif key == "m":
        mode = WALKING_MODES[(WALKING_MODES.index(mode) + 1) % len(WALKING_MODES)]
    heading = math.remainder(heading, 2.0 * math.pi)
    return mode, round(speed, 6), heading, round(yaw_rate, 9)


class KeyboardControl:
    """Read keys from the terminal in a daemon thread and apply them through ``apply``.

    Parameters
    ----------
    state : callable
        Returns the present (mode, speed, heading, yaw rate).
    apply : callable
        Takes the new (mode, speed, heading, yaw rate).
    stream
        A terminal (``sys.stdin`` by default); nothing is read when it is not a TTY.
    """

    def __init__(self, state: Callable[[], tuple[str, float, float, float]],
                 apply: Callable[[str, float, float, float], None], stream=None) -> None:
        self.state, self.apply = state, apply
        self.stream = sys.stdin if stream is None else stream
        self.active = bool(getattr(self.stream, "isatty", lambda: False)())
        self._saved = None
        if self.active:
            import termios
            import tty

            descriptor = self.stream.fileno()
            self._saved = termios.tcgetattr(descriptor)
            tty.setcbreak(descriptor)  # keys one by one, Ctrl-C still interrupts
            threading.Thread(target=self._read, name="console-keys", daemon=True).start()

    def _read(self) -> None:
        while True:
            key = self.stream.read(1)
            if not key:
                return
            self.apply(*key_command(key, *self.state()))

    def close(self) -> None:
        """Give the terminal its settings back."""
        if self._saved is not None:
            import termios

            termios.tcsetattr(self.stream.fileno(), termios.TCSADRAIN, self._saved)
            self._saved = None
