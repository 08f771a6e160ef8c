"""Latency and pacing of the networked co-simulation on the loopback (figures, no asserts).

Setup: ``crr-quadruped`` as shipped, ``fixed`` configuration (12 joints), dynamics server
in its own process (force commands, no recording), client in this process.

* **lockstep**: the actuator side (controllers + pneumatic kernel) computes forces, sends
  a ``FORCE_COMMAND`` and waits for the answering ``STATE``; commands are paced at 1 kHz.
  Round trip = receive time of the answering ``STATE`` - send time of the command (this
  process's monotonic clock): one MuJoCo step, two encodes/decodes and two loopback hops.
  Target: p99 <= 0.5 ms.
* **realtime**: the server paces itself at 1 kHz for ``--duration`` s (default 60) while
  the client sends a command every ~1 ms; figures from the server's wake-up times
  (:func:`pneumaquad.network.timing.jitter_statistics`): achieved rate, p99 jitter
  (``|interval - 1 ms|``) and overruns (intervals > 1.5 ms).

Usage: ``.venv/bin/python benchmarks/network_latency.py [--commands 5000] [--duration 60]``.
"""

from __future__ import annotations

import argparse
import multiprocessing
import time

import numpy as np

from pneumaquad.network.endpoint import UdpEndpoint
from pneumaquad.network.protocol import MessageType, encode_bye, encode_command
from pneumaquad.network.timing import round_trip_times, rtt_statistics

POSTURE = np.tile(np.radians((0.0, -30.0, 60.0)), 4)


def _build():
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import build_robot

    return build_robot(load_robot("crr-quadruped"), "fixed")


def _serve(mode: str, duration: float, queue: multiprocessing.Queue, busy_wait: float) -> None:
    from pneumaquad.network.dynamics_side import DynamicsSide
    from pneumaquad.network.server import DynamicsServer

    side = DynamicsSide(_build(), "force")
    side.set_pose(POSTURE)
    server = DynamicsServer(side, mode=mode, timeout=1.0, duration=duration,
                            busy_wait=busy_wait)
    queue.put(server.address)
    queue.put(server.run())


def _start(mode: str, duration: float, busy_wait: float = 0.0):
    context = multiprocessing.get_context("spawn")
    queue = context.Queue()
    process = context.Process(target=_serve, args=(mode, duration, queue, busy_wait),
                              daemon=True)
    process.start()
    return process, queue, queue.get(timeout=120)


def lockstep(commands: int, busy_wait: float = 0.0) -> dict[str, float]:
    """Round-trip statistics [s] of ``commands`` paced lockstep exchanges; ``busy_wait``
    [s] is both endpoints' polling window before they block (0: block at once)."""
    from pneumaquad.network.actuator_side import ActuatorSide
    from pneumaquad.network.client import ActuatorClient

    process, queue, address = _start("lockstep", 3600.0, busy_wait)
    client = ActuatorClient(ActuatorSide(_build()), address, reply_timeout=0.1,
                            busy_wait=busy_wait)
    state = client.connect()
    client.side.command_angles(state.joint_angles)
    period, next_send = 1e-3, time.perf_counter()
    for _ in range(commands):
        while time.perf_counter() < next_send:
            pass
        next_send += period
        state = client.exchange_forces(client.side.forces(state), state.simulation_time)
    client.bye()
    statistics = rtt_statistics(round_trip_times(client.endpoint.log, "command"))
    statistics["resends [count]"] = client.resends
    client.close()
    queue.get(timeout=30)
    process.join(10)
    return statistics


def realtime(duration: float) -> dict[str, float]:
    """Server pacing figures of a ``duration`` s real-time run with 1 kHz commands."""
    process, queue, address = _start("realtime", duration + 5.0)
    endpoint = UdpEndpoint(peer=address, joint_count=12)
    forces = np.zeros(12)
    end = time.perf_counter() + duration
    next_send = time.perf_counter()
    while time.perf_counter() < end:
        endpoint.receive(max(next_send - time.perf_counter(), 0.0))
        if time.perf_counter() >= next_send:
            endpoint.send(encode_command(MessageType.FORCE_COMMAND, endpoint.take_sequence(),
                                         0.0, forces), address)
            next_send += 1e-3
    for _ in range(3):
        endpoint.send(encode_bye(endpoint.take_sequence(), time.monotonic()), address)
    summary = queue.get(timeout=60)
    process.join(10)
    endpoint.close()
    return summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commands", type=int, default=5000, help="lockstep exchanges")
    parser.add_argument("--duration", type=float, default=60.0, help="realtime run [s]")
    parser.add_argument("--busy-wait", type=float, default=0.002,
                        help="polling window [s] of the low-latency lockstep run")
    arguments = parser.parse_args()
    for label, busy_wait in (("blocking", 0.0), ("busy-wait", arguments.busy_wait)):
        figures = lockstep(arguments.commands, busy_wait)
        print(f"lockstep ({label} {busy_wait * 1e3:g} ms), {figures['round trips [count]']} "
              f"commands at 1 kHz: round trip median "
              f"{figures['round-trip time median [s]'] * 1e3:.3f} ms, p90 "
              f"{figures['round-trip time p90 [s]'] * 1e3:.3f} ms, p99 "
              f"{figures['round-trip time p99 [s]'] * 1e3:.3f} ms, max "
              f"{figures['round-trip time max [s]'] * 1e3:.3f} ms (target p99 <= 0.5 ms); "
              f"resends {figures['resends [count]']}")
    summary = realtime(arguments.duration)
    print(f"realtime, {arguments.duration:g} s at 1 kHz: achieved rate "
          f"{summary['achieved rate [Hz]']:.2f} Hz, jitter p50 "
          f"{summary['jitter p50 [s]'] * 1e6:.1f} us, p99 {summary['jitter p99 [s]'] * 1e6:.1f} us,"
          f" max {summary['jitter max [s]'] * 1e6:.1f} us, overruns {summary['overruns [count]']}"
          f", max lateness {summary['max lateness [s]'] * 1e3:.3f} ms, timeouts "
          f"{summary['timeouts [count]']}")


if __name__ == "__main__":
    main()
