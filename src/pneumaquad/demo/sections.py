"""Robot sections of ``pneumaquad demo``: the quadruped standing up, a leg validation step
train, the foot cycle with the thesis's reduced alpha gain, and a short crawl."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pneumaquad.params import load_robot
from pneumaquad.reporting.display_units import DisplayUnits
from pneumaquad.reporting.robot_plots import plot_body, plot_joints
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import run_phases
from pneumaquad.robot.scenarios import foot_cycle_phases, leg_validation_phases, stand_up_phases
from pneumaquad.robot.simulation import RobotSimulation

__all__ = ["ROBOT_SECTIONS"]


class Report(Protocol):
    units: DisplayUnits

    def add(self, title: str, text: str, figure: Path, figures: dict[str, Any]) -> None: ...


def _simulation(configuration: str, overrides: list[str] | None = None) -> RobotSimulation:
    return RobotSimulation(build_robot(load_robot("crr-quadruped", overrides or []),
                                       configuration))


def _stand(folder: Path, report: Report) -> None:
    simulation = _simulation("quadruped")
    run = run_phases(simulation, stand_up_phases(simulation), folder / "robot-stand",
                     "quadruped: stand up, hold, body commands")
    recording = run.recording
    plot_body(recording, simulation.robot.legs, folder / "robot-stand" / "body.png",
              "Quadruped standing up on 12 pneumatic joints", report.units)
    figure = folder / "robot-stand" / "body.png"
    try:
        from pneumaquad.robot.video import RenderingUnavailableError, render_run_video

        files = render_run_video(folder / "robot-stand", fps=20, width=480, height=360,
                                 max_seconds=None)
        figure = files.first_frame
        video_note = f" Video: robot-stand/{files.mp4.name}."
    except RenderingUnavailableError as error:
        video_note = f" (No video: {error})"
    phases = run.summary["phases"]
    stance = run.summary["checks"]["stance check"]
    if not stance["verified"]:
        raise RuntimeError(f"the demo robot did not stand up ({folder / 'robot-stand'}): "
                           + "; ".join(stance["reasons"]))
    t = recording["time [s]"]
    holding = (t >= phases["hold"]["start [s]"] + 1.0) & (t < phases["height up"]["start [s]"])
    report.add(
        "Quadruped: standing up and holding posture",
        "The robot lies on the ground, tucks its feet in, pushes up on all 12 cylinders, "
        "holds, then follows body height (±3 cm), roll (5°) and pitch (5°) commands with "
        "its feet in place (IK per leg). After the hold its stance is checked against "
        "stated limits (thorax height ±3 cm of the commanded pose's, every joint within "
        "5°, roll and pitch within 5°): verified. Figure: first video frame; body.png has "
        "the thorax height, attitude, foot forces and air." + video_note,
        figure,
        {
            "largest joint error after the hold [deg]": stance["largest joint error [deg]"],
            "standing thorax height [m]": float(np.mean(recording["thorax z [m]"][holding])),
            "largest roll while holding [deg]": float(
                np.degrees(np.max(np.abs(recording["thorax roll [rad]"][holding])))),
            "air consumed [NL]": run.summary["air consumed [NL]"],
            "mean air flow [NL/min]": run.summary["mean air flow [NL/min]"],
            "air flow while holding [NL/min]": phases["hold"]["mean air flow [NL/min]"],
            "2 L / 200 bar tank lasts, holding [h]":
                phases["hold"]["tank endurance at this flow [s]"] / 3600.0,
            "2 L / 200 bar tank lasts, whole run's mean flow [min]":
                run.summary["tank endurance at this mean flow [s]"] / 60.0,
            "real-time factor": run.summary["real-time factor"],
        },
    )


def _leg_steps(folder: Path, report: Report) -> None:
    simulation = _simulation("fixed")
    name = "leg-gamma-steps"
    run = run_phases(simulation, leg_validation_phases(simulation, "gamma", "steps"),
                     folder / name, "front-right gamma: step train")
    joints = [n for n in simulation.robot.joint_names if n.startswith("front_right")]
    plot_joints(run.recording, joints, folder / name / "joints.png", "Gamma step train",
                report.units)
    report.add(
        "Leg validation: gamma step train (thesis 5.5.2.1, Fig. 38)",
        "Fixed thorax; alpha and beta driven to full extension open loop, then gamma "
        "follows a step train across its 17-95° range.",
        folder / name / "joints.png",
        {"gamma angle rmse [deg]": run.summary["angle rmse [deg]"]["front_right_gamma"],
         "real-time factor": run.summary["real-time factor"]},
    )


def _foot_cycle(folder: Path, report: Report) -> None:
    figures: dict[str, Any] = {}
    for scale in (1.0, 0.75):
        simulation = _simulation("fixed", [f"controller.alpha.gain_scale={scale}"])
        name = f"foot-cycle-alpha-{scale:g}"
        run = run_phases(simulation, foot_cycle_phases(simulation), folder / name,
                         f"foot cycle, alpha gain x{scale:g}")
        joints = [n for n in simulation.robot.joint_names if n.startswith("front_right")]
        plot_joints(run.recording, joints, folder / name / "joints.png",
                    f"Foot cycle, slow/medium/fast, alpha gain x{scale:g}", report.units)
        for joint in joints:
            key = f"{joint.split('_')[-1]} rmse [deg], alpha gain x{scale:g}"
            figures[key] = run.summary["angle rmse [deg]"][joint]
        if scale == 1.0:
            for rate in ("slow", "medium", "fast"):
                phase = run.summary["phases"][rate]
                figures[f"{rate} cycle: air [NL/min]"] = phase["mean air flow [NL/min]"]
                figures[f"{rate} cycle: 2 L / 200 bar tank lasts [h]"] = (
                    phase["tank endurance at this flow [s]"] / 3600.0
                )
    report.add(
        "Leg commands: the walking-like foot cycle (thesis 5.5.2.4, Fig. 44-45)",
        "The front-right foot goes rear-bottom → arc up → front-bottom → drag back at "
        "slow (4 s), medium (2 s) and fast (1 s) periods, through inverse kinematics; "
        "run with the original alpha gain and with it reduced by 25 %. Figure: reduced gain.",
        folder / "foot-cycle-alpha-0.75" / "joints.png",
        figures,
    )


def _walk(folder: Path, report: Report) -> None:
    from pneumaquad.locomotion.walk_run import run_walk
    from pneumaquad.locomotion.walking import WalkSettings

    settings = WalkSettings(distance=0.32)  # two 8 s cycles at 20 mm/s
    walk = run_walk(_simulation("quadruped"), settings, folder / "robot-walk",
                    "quadruped: crawl 0.32 m",
                    figure_title="Crawl gait on flat ground (two cycles)")
    outcome, figure = walk.outcome, walk.figure
    if outcome is None or figure is None:
        raise RuntimeError(f"the demo walk in {walk.folder} was not judged (interrupted?)")
    verdict = "success" if outcome["success"] else "failure"
    report.add(
        "Quadruped: crawl gait (lateral-sequence wave gait, duty factor 0.9)",
        "Two 8 s cycles at 20 mm/s on flat ground (the first a start-up from the symmetric "
        "stance), with the force-controlled stance: each stance leg's cylinders carry the "
        "share of the weight statics gives it. Judged by the criteria of docs/robot.md: "
        f"{verdict} ({', '.join(outcome['reasons'])}). The tip-over margin uses the feet "
        "the gait holds down, the recorded margin the feet carrying load; the difference is "
        "the robot rocking onto diagonal pairs of feet. `pneumaquad robot walk` walks 1 m, "
        "onto the ramp or over the rough field with a video.",
        figure,
        {key: value for key, value in outcome.items()
         if isinstance(value, (int, float)) and not isinstance(value, bool)},
    )


ROBOT_SECTIONS = (_stand, _leg_steps, _foot_cycle, _walk)
