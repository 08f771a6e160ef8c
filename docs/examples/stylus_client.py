"""Example external input device for the operator console (docs/console.md, "External
devices (UDP)").

Sends a circular stylus motion for one leg (front_right by default) at 50 Hz with the
engage button pressed, and prints the force feedback the console sends back; with
``--place-every`` it also presses the place-foot button now and then (shared-control
walking: the front foot's next foothold is where the stylus points at the press).
Written from the documentation only: standard library and numpy, no pneumaquad import.

    pneumaquad console --configuration fixed --start --device-port 47100
    python docs/examples/stylus_client.py --port 47100 --duration 10
"""

from __future__ import annotations

import argparse
import socket
import struct
import time

import numpy as np

HEADER = struct.Struct("<4sHHIdHH")  # magic, version, type, sequence, time, count, reserved
MAGIC, VERSION = b"PNQD", 1
DEVICE_INPUT, DEVICE_FEEDBACK = 16, 17
INPUT_COUNT, FEEDBACK_COUNT = 5, 6
ENGAGE = 1  # button bit 0
PLACE_FOOT = 2  # button bit 1
LEGS = ("front_left", "front_right", "rear_left", "rear_right")


def device_input(sequence: int, leg: int, position: np.ndarray, buttons: int) -> bytes:
    """One DEVICE_INPUT datagram: leg index, stylus x, y, z [m], buttons bitmask."""
    header = HEADER.pack(MAGIC, VERSION, DEVICE_INPUT, sequence % 2**32, time.monotonic(),
                         INPUT_COUNT, 0)
    return header + struct.pack("<5d", leg, *position, buttons)


def feedback(datagram: bytes) -> tuple[float, np.ndarray] | None:
    """(simulation time [s], the 6 payload values) of a DEVICE_FEEDBACK, None otherwise."""
    if len(datagram) != HEADER.size + 8 * FEEDBACK_COUNT:
        return None
    magic, version, kind, _sequence, sender_time, count, _ = HEADER.unpack_from(datagram)
    if (magic, version, kind, count) != (MAGIC, VERSION, DEVICE_FEEDBACK, FEEDBACK_COUNT):
        return None
    values = np.frombuffer(datagram, dtype="<f8", count=count, offset=HEADER.size)
    if not np.all(np.isfinite(values)):
        return None
    return sender_time, values


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default="127.0.0.1", help="console host")
    parser.add_argument("--port", type=int, default=47100, help="console device port (UDP)")
    parser.add_argument("--duration", type=float, default=10.0, help="seconds to run")
    parser.add_argument("--leg", type=int, default=1, help="leg index, 1 = front_right")
    parser.add_argument("--radius", type=float, default=0.03, help="circle radius [m]")
    parser.add_argument("--period", type=float, default=2.0, help="circle period [s]")
    parser.add_argument("--rate", type=float, default=50.0, help="send rate [Hz]")
    parser.add_argument("--place-every", type=float, default=0.0,
                        help="press the place-foot button every this many seconds (0: never)")
    arguments = parser.parse_args()

    console = (arguments.host, arguments.port)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    sequence, start = 0, time.monotonic()
    next_send = start
    next_place = start + arguments.place_every
    while (now := time.monotonic()) - start < arguments.duration:
        # circle in the device's up-forward plane (thorax x up, z forward), from the origin
        phase = 2.0 * np.pi * (now - start) / arguments.period
        position = arguments.radius * np.array([np.sin(phase), 0.0, np.cos(phase) - 1.0])
        buttons = ENGAGE
        if arguments.place_every > 0.0 and now >= next_place:  # one datagram: a press
            buttons |= PLACE_FOOT
            next_place += arguments.place_every
        sock.sendto(device_input(sequence, arguments.leg, position, buttons), console)
        sequence += 1
        latest = None
        while True:  # drain; keep the newest feedback
            try:
                datagram, _ = sock.recvfrom(2048)
            except BlockingIOError:
                break
            latest = feedback(datagram) or latest
        if latest is not None:
            simulation_time, values = latest
            force = values[1:4]
            print(f"feedback t={simulation_time:.3f} s leg={LEGS[int(values[0])]} "
                  f"F=[{force[0]:+.3f} {force[1]:+.3f} {force[2]:+.3f}] N "
                  f"|F|={np.linalg.norm(force):.3f} N normal={values[4]:.1f} N "
                  f"clamped={int(values[5])}", flush=True)
        next_send += 1.0 / arguments.rate
        time.sleep(max(0.0, next_send - time.monotonic()))
    sock.sendto(device_input(sequence, arguments.leg, np.zeros(3), 0), console)  # release
    sock.close()


if __name__ == "__main__":
    main()
