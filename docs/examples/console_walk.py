"""Measure the console's automatic walking (docs/console.md, "Walking").

Drives :class:`pneumaquad.console.app.ConsoleApp` headless and unpaced (no browser): the
free quadruped on flat ground from the console's reset pose, 0.5 s to settle, then the
automatic walking mode (straight ahead unless ``--heading``): the command line's walk
(:class:`pneumaquad.locomotion.live_walk.LiveWalk`), which first moves the robot into
the walk's first pose (a shift of the body, or the feet re-placed for a sideways
posture), then walks; ``--duration`` seconds of walking are measured from the walk's
start, one 20 ms chunk at a time as the console's thread steps it. After every chunk it
reads what the console shows: the loaded-feet static stability margin (feet with a
normal force above 1 N) and the thorax pose.

    .venv/bin/python docs/examples/console_walk.py --speed 15 --speed 30
    .venv/bin/python docs/examples/console_walk.py --speed 15 --stance position
    .venv/bin/python docs/examples/console_walk.py --speed 15 --heading 90
    .venv/bin/python docs/examples/console_walk.py --speed 0 --yaw-rate 2

Prints per run: the time from the command to the walk's start, the body's travel along
the heading and its forward (x) and sideways (y) travel (the thorax, the walk's planned
sway taken out: meaningful for walks that do not turn), the largest |yaw|, the final yaw
and the yaw turned while walking, how far the centre of the four feet moved (a turn in
place's drift), steps taken, the mean and lowest
thorax height, the fraction of chunks whose loaded-feet margin is negative (and those
with no loaded foot), whether the thorax fell below 0.25 m, and the wall time spent in
the console's chunks while walking (stepping and refreshing the scene and panels, as the
unpaced console's thread does).

The margin is the one the console shows (``app.stability``, from ``foot_normal_forces()``
between chunks: a chunk ends with MuJoCo's force stages, so these are the contact forces of
the present contacts, the same as ``mujoco.mj_forward`` gives; tests/robot/test_coupling_exact.py).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from pneumaquad.console.app import ConsoleApp
from pneumaquad.console.walking import ConsoleWalking
from pneumaquad.robot.recording import thorax_attitude

SETTLE_CHUNKS = 25  # 0.5 s of 20 ms chunks before walking starts
FALLEN_HEIGHT = 0.25  # thorax height [m] below which the robot counts as fallen


def walk(speed: float, duration: float, stance: str, heading: float = 0.0,
         yaw_rate: float = 0.0) -> dict[str, float]:
    """One automatic walk at ``speed`` [m/s], ``heading`` [rad] and ``yaw_rate``
    [rad/s]; the measured figures."""
    app = ConsoleApp(configuration="quadruped", environment="flat", port=0, real_time=False)
    try:
        if stance == "position":
            app.walking = ConsoleWalking(app.simulation, stance=None)
        simulation = app.simulation
        thorax = simulation.robot.thorax_id
        for _ in range(SETTLE_CHUNKS):
            app.advance()
        commanded = simulation.time
        app.set_walking("automatic", speed=speed, heading=heading, yaw_rate=yaw_rate)
        live = app.walking.live
        while not live.walking and not app.message and simulation.time < commanded + 60.0:
            app.advance()
        walking = live.current_walk
        if walking is None:
            return {"message": app.message or live.message or "the walk did not begin"}
        began = simulation.time

        def body() -> np.ndarray:
            return simulation.data.xpos[thorax][:2] - walking.sway(simulation.time)

        start = body()
        feet_start = simulation.foot_positions()[:, :2].mean(axis=0)
        chunks = round(duration / (app.chunk_steps * simulation.control_step))
        margins, yaws, heights = [], [], []
        wall = 0.0
        for _ in range(chunks):
            clock = time.perf_counter()
            app.advance()
            wall += time.perf_counter() - clock
            if app.message:  # a diverging step pauses the console
                break
            margins.append(app.stability.margin)
            yaws.append(thorax_attitude(simulation)[2])
            heights.append(simulation.data.xpos[thorax][2])
        moved = body() - start
        margins = np.asarray(margins)
        yaws = np.degrees(np.unwrap(yaws))
        return {
            "command to the walk's start [s]": began - commanded,
            "walked [s]": len(margins) * app.chunk_steps * simulation.control_step,
            "along the heading [m]": float(moved @ [math.cos(heading), math.sin(heading)]),
            "forward x [m]": moved[0],
            "sideways y [m]": moved[1],
            "max |yaw| [deg]": float(np.max(np.abs(yaws))),
            "final yaw [deg]": float(yaws[-1]),
            "turned [deg]": float(yaws[-1] - yaws[0]),
            "centre of the feet moved [m]": float(np.hypot(
                *(simulation.foot_positions()[:, :2].mean(axis=0) - feet_start))),
            "steps": app.walking.steps_taken,
            "mean thorax height [m]": float(np.mean(heights)),
            "min thorax height [m]": float(np.min(heights)),
            "loaded-feet margin < 0 [%]": 100.0 * float(np.mean(margins < 0.0)),
            "no loaded foot [%]": 100.0 * float(np.mean(np.isnan(margins))),
            "fell": float(np.min(heights) < FALLEN_HEIGHT),
            "wall time of the console's chunks [s]": wall,
            "message": app.message or live.message,
        }
    finally:
        app.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--speed",
        type=float,
        action="append",
        help="commanded body speed [mm/s], repeatable (default 15 and 30)",
    )
    parser.add_argument("--duration", type=float, default=30.0, help="walking time measured [s]")
    parser.add_argument("--heading", type=float, default=0.0,
                        help="walking direction [deg], counter-clockwise from forward")
    parser.add_argument("--yaw-rate", type=float, default=0.0,
                        help="body yaw rate [deg/s], counter-clockwise (0: straight)")
    parser.add_argument(
        "--stance",
        choices=("force", "position"),
        default="force",
        help="force-controlled stance (the console's) or plain position control",
    )
    args = parser.parse_args()
    for speed in args.speed or [15.0, 30.0]:
        figures = walk(speed / 1000.0, args.duration, args.stance, math.radians(args.heading),
                       math.radians(args.yaw_rate))
        print(f"{speed:g} mm/s, heading {args.heading:g}°, yaw rate {args.yaw_rate:g}°/s, "
              f"{args.stance} stance:")
        for name, value in figures.items():
            if isinstance(value, float) and not math.isnan(value):
                print(f"  {name}: {value:.3f}")
            else:
                print(f"  {name}: {value}")


if __name__ == "__main__":
    main()
