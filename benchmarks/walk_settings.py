"""What each part of the walking controller is worth: short flat walks with one setting changed.

Every setting walks 0.5 m on flat ground at 15, 20 and 25 mm/s (single walks differ by a
few points, so each setting is walked at three speeds), with the defaults of
``pneumaquad robot walk`` otherwise. Each walk is judged by
:func:`pneumaquad.locomotion.walking.walking_outcome`; the script prints one line per walk and,
per setting, the means over the speeds and the number of successes. The planned travel is
whole gait cycles (8 s cycles: 0.6, 0.64 and 0.6 m at the three speeds), so "travelled /
0.5 m" of a walk that follows its plan is about 1.2-1.3.

Settings (``--settings``, default: all, in this order):

``position``       position-controlled stance (the thesis's PID on every leg), other defaults
``force-bare``     force-controlled stance with the stiffness factor 1, no transfer gap and no
                   start-up cycle
``force-gap``      ... with the 4 % transfer gap
``force-startup``  ... and the start-up cycle
``defaults``       ... and the stiffness factor 2: the shipped defaults (k_F 0.015 V/N)
``stiffness-3``    defaults with the stiffness factor 3
``gain-0.005``, ``gain-0.01``, ``gain-0.02``  defaults with another force gain k_F [V/N]
``impratio-1``     defaults with MuJoCo's default friction impedance (impratio 1)
``impratio-1-noslip-2``, ``impratio-1-noslip-5``  ... and 2 or 5 no-slip iterations
``lift-0``         defaults with lift fraction 0 (the foot moves along while it rises)
``margin-0.04``    defaults with a 40 mm planned static margin

The stiffness factor and the start-up cycle are not CLI options: ``pneumaquad robot walk``
always plans the start-up cycle and uses the stiffness factor 2. This script sets the
stiffness through :class:`pneumaquad.locomotion.stance_control.StanceControlSettings` and, for
the rows without the start-up cycle, plans the gait with ``start_up=False`` (it wraps the
gait constructor :func:`pneumaquad.locomotion.walking.walking_phases` calls); everything else is
the code path of the CLI.

Run: ``.venv/bin/python benchmarks/walk_settings.py [--settings defaults position ...]
[--speeds 0.015 0.02 0.025] [--output runs/walk-settings]``; ``--summary`` reprints the
table from the JSON files of an earlier run. About 3-20 s of wall time per walk on the shared
2-core machine (42 walks: 5-10 min).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

import pneumaquad.locomotion.walking as walking_module
from pneumaquad.locomotion.stance_control import StanceControlSettings
from pneumaquad.locomotion.walk import robot_gait
from pneumaquad.locomotion.walking import WalkSettings, tip_over_series, walking_outcome
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import run_phases
from pneumaquad.robot.simulation import RobotSimulation

DISTANCE = 0.5
SPEEDS = (0.015, 0.02, 0.025)


def _setting(stance: StanceControlSettings | None = None, start_up: bool = True,
             overrides: tuple[str, ...] = (), **walk: Any) -> dict[str, Any]:
    return {"stance": stance, "start_up": start_up, "overrides": list(overrides), "walk": walk}


SETTINGS: dict[str, dict[str, Any]] = {
    "position": _setting(stance=None),
    "force-bare": _setting(StanceControlSettings(stiffness=1.0), start_up=False,
                           transfer_gap=0.0),
    "force-gap": _setting(StanceControlSettings(stiffness=1.0), start_up=False),
    "force-startup": _setting(StanceControlSettings(stiffness=1.0)),
    "defaults": _setting(StanceControlSettings()),
    "stiffness-3": _setting(StanceControlSettings(stiffness=3.0)),
    "gain-0.005": _setting(StanceControlSettings(force_gain=0.005)),
    "gain-0.01": _setting(StanceControlSettings(force_gain=0.01)),
    "gain-0.02": _setting(StanceControlSettings(force_gain=0.02)),
    "impratio-1": _setting(StanceControlSettings(),
                           overrides=("contact.friction_impedance_ratio=1.0",)),
    "impratio-1-noslip-2": _setting(StanceControlSettings(), overrides=(
        "contact.friction_impedance_ratio=1.0", "simulation.noslip_iterations=2")),
    "impratio-1-noslip-5": _setting(StanceControlSettings(), overrides=(
        "contact.friction_impedance_ratio=1.0", "simulation.noslip_iterations=5")),
    "lift-0": _setting(StanceControlSettings(), lift_fraction=0.0),
    "margin-0.04": _setting(StanceControlSettings(), minimum_margin=0.04),
}


def _gait_constructor(start_up: bool):
    """:func:`robot_gait` with the start-up cycle on or off."""

    def build(*args: Any, **kwargs: Any):
        kwargs["start_up"] = start_up
        return robot_gait(*args, **kwargs)

    return build


def tripod_loads(recording: dict[str, np.ndarray], summary: dict[str, Any],
                 legs: tuple[str, ...], plan) -> np.ndarray:
    """Smallest normal force [N] among the three feet the gait holds down, at every walk
    sample with exactly one leg in planned swing."""
    times = recording["time [s]"]
    walk = summary["phases"]["walk"]
    inside = (times >= walk["start [s]"]) & (times <= walk["start [s]"] + walk["duration [s]"])
    step = float(plan.times[1] - plan.times[0])
    index = np.clip(np.round((times[inside] - walk["start [s]"]) / step).astype(int), 0,
                    len(plan.stance) - 1)
    stance = plan.stance[index]
    forces = np.column_stack([recording[f"{leg} foot normal force [N]"][inside]
                              for leg in legs])
    tripod = stance.sum(axis=1) == 3
    return np.where(stance[tripod], forces[tripod], np.inf).min(axis=1)


def walk_once(name: str, speed: float, output: Path) -> dict[str, Any]:
    """One 0.5 m flat walk of setting ``name`` at ``speed`` [m/s]; its figures."""
    setting = SETTINGS[name]
    # Walk whole cycles covering at least DISTANCE (the table's walks: 1.2-1.28 x 0.5 m;
    # WalkSettings.duration() would take the nearest whole number of cycles instead).
    cycle = speed * setting["walk"].get("period", WalkSettings().period)
    planned_distance = math.ceil(DISTANCE / cycle - 1e-9) * cycle
    settings = WalkSettings(speed=speed, distance=planned_distance,
                            stance_control=setting["stance"],
                            **setting["walk"])
    robot = build_robot(load_robot("crr-quadruped", setting["overrides"]), "quadruped",
                        environment="flat")
    simulation = RobotSimulation(robot)
    original = walking_module.robot_gait
    walking_module.robot_gait = _gait_constructor(setting["start_up"])
    try:
        phases, plan = walking_module.walking_phases(simulation, settings)
    finally:
        walking_module.robot_gait = original
    folder = output / f"{name}-{round(speed * 1000)}mm"
    started = time.perf_counter()
    run = run_phases(simulation, phases, folder, f"walk {name} {speed:g} m/s")
    wall = time.perf_counter() - started
    if "walk" not in run.summary["phases"]:  # the stance before it was not verified
        stopped = run.summary.get("stopped before") or {"reason": "interrupted"}
        figures = dict.fromkeys(FIGURE_KEYS, math.nan) | {
            "setting": name, "speed [m/s]": speed, "success": False,
            "reasons": [f"not begun: {stopped['reason']}"],
            "simulated [s]": float(run.summary["simulated time [s]"]), "wall [s]": wall}
        (folder / "figures.json").write_text(json.dumps(figures, indent=2), encoding="utf-8")
        return figures
    tip_over = tip_over_series(run.recording, run.summary, robot, plan)
    outcome = walking_outcome(run.recording, run.summary, settings, robot, tip_over)
    times = run.recording["time [s]"]
    walk = run.summary["phases"]["walk"]
    inside = (times >= walk["start [s]"]) & (times <= walk["start [s]"] + walk["duration [s]"])
    yaw = np.degrees(run.recording["thorax yaw [rad]"][inside])
    tripod = tripod_loads(run.recording, run.summary, tuple(robot.legs), plan)
    planned = settings.duration() * speed
    figures = {
        "setting": name,
        "speed [m/s]": speed,
        "planned travel [m]": planned,
        "success": bool(outcome["success"]),
        "reasons": outcome["reasons"],
        "loaded-feet margin < 0 [%]": outcome["time with negative static margin [%]"],
        "tip-over margin < 0 [%]": outcome["time with negative tip-over margin [%]"],
        "largest slide [m]": outcome["largest stance-foot slide [m]"],
        "travelled [m]": outcome["distance travelled [m]"],
        "travelled / 0.5 m": outcome["distance travelled [m]"] / DISTANCE,
        "travelled / planned": outcome["distance travelled [m]"] / planned,
        "drift [m]": outcome["sideways drift [m]"],
        "yaw min [deg]": float(yaw.min()),
        "yaw max [deg]": float(yaw.max()),
        "air [NL/m]": outcome["air per metre [NL/m]"],
        "tripod smallest load, median [N]": float(np.median(tripod)),
        "tripod smallest load, 5th percentile [N]": float(np.percentile(tripod, 5)),
        "simulated [s]": float(run.summary["simulated time [s]"]),
        "wall [s]": wall,
    }
    (folder / "figures.json").write_text(json.dumps(figures, indent=2), encoding="utf-8")
    return figures


#: The figures of a walk (NaN for a walk that did not begin).
FIGURE_KEYS = ("planned travel [m]", "loaded-feet margin < 0 [%]", "tip-over margin < 0 [%]",
               "largest slide [m]", "travelled [m]", "travelled / 0.5 m",
               "travelled / planned", "drift [m]", "yaw min [deg]", "yaw max [deg]",
               "air [NL/m]", "tripod smallest load, median [N]",
               "tripod smallest load, 5th percentile [N]")


def _line(f: dict[str, Any]) -> str:
    return (f"{f['setting']:<20} {f['speed [m/s]'] * 1000:4.0f} mm/s  "
            f"{'success' if f['success'] else ','.join(f['reasons']):<22} "
            f"margin<0 {f['loaded-feet margin < 0 [%]']:4.1f} %  "
            f"tip<0 {f['tip-over margin < 0 [%]']:3.1f} %  "
            f"slide {f['largest slide [m]'] * 100:4.1f} cm  "
            f"travel {f['travelled / 0.5 m']:.2f} (plan {f['travelled / planned']:.2f})  "
            f"drift {f['drift [m]'] * 100:4.1f} cm  "
            f"yaw {f['yaw min [deg]']:+.1f}..{f['yaw max [deg]']:+.1f}°  "
            f"air {f['air [NL/m]']:.1f} NL/m  "
            f"tripod min load {f['tripod smallest load, median [N]']:.1f} N "
            f"(5 % {f['tripod smallest load, 5th percentile [N]']:.1f} N)  "
            f"{f['simulated [s]'] / f['wall [s]']:.1f}x real time")


def summarise(results: list[dict[str, Any]]) -> None:
    print()
    print("setting              margin<0  slide    travelled/0.5 m  /planned  drift    "
          "yaw range       air      success  x real time")
    for name in dict.fromkeys(r["setting"] for r in results):
        rows = [r for r in results if r["setting"] == name]

        def mean(key: str, rows=rows) -> float:
            return float(np.nanmean([r[key] for r in rows]))

        successes = sum(r["success"] for r in rows)
        low = float(np.nanmin([r["yaw min [deg]"] for r in rows]))
        high = float(np.nanmax([r["yaw max [deg]"] for r in rows]))
        speed = sum(r["simulated [s]"] for r in rows) / sum(r["wall [s]"] for r in rows)
        print(f"{name:<20} {mean('loaded-feet margin < 0 [%]'):5.1f} %  "
              f"{mean('largest slide [m]') * 100:4.1f} cm  {mean('travelled / 0.5 m'):5.2f}"
              f"            {mean('travelled / planned'):5.2f}    "
              f"{mean('drift [m]') * 100:4.1f} cm  "
              f"{low:+5.1f}..{high:+5.1f}°"
              f"  {mean('air [NL/m]'):4.1f} NL/m  {successes}/{len(rows)}      {speed:.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--settings", nargs="+", choices=list(SETTINGS), default=list(SETTINGS))
    parser.add_argument("--speeds", nargs="+", type=float, default=list(SPEEDS))
    parser.add_argument("--output", type=Path, default=Path("runs/walk-settings"))
    parser.add_argument("--summary", action="store_true",
                        help="only reprint the table from the figures.json files in --output")
    arguments = parser.parse_args()
    results = []
    for name in arguments.settings:
        for speed in arguments.speeds:
            path = arguments.output / f"{name}-{round(speed * 1000)}mm" / "figures.json"
            if arguments.summary:
                if not path.is_file():
                    continue
                figures = json.loads(path.read_text(encoding="utf-8"))
            else:
                figures = walk_once(name, speed, arguments.output)
            results.append(figures)
            print(_line(figures), flush=True)
    if results:
        summarise(results)
    elif arguments.summary:
        print(f"no figures.json under {arguments.output}")
    if any(not math.isfinite(r["air [NL/m]"]) for r in results):
        print("(air per metre undefined for a walk that did not move forward)")


if __name__ == "__main__":
    main()
