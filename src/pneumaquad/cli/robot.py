"""Command-line interface of the robot: ``pneumaquad leg ...``, ``robot ...``, ``video``.

Every experiment writes a run folder (see :mod:`pneumaquad.robot.experiment`), prints
its key figures, and optionally renders a video offscreen. The video is rendered by a
separate process (:mod:`pneumaquad.robot.video_worker`) started with the command and fed
the recorded samples while the run goes (the runs' ``on_sample`` hook); it works on beside
the plots and the command waits for it at the end. Without a video the worker writes only
``first-frame.png``, from ``trajectory.npz`` once the run has ended.

Ctrl-C: the first stops the run (at the next chunk) and the worker alike; the command writes
the summary (``interrupted: true``), the plots and a video of the frames rendered so far (a
line says how many of how many), then exits with 130. A Ctrl-C while waiting for the video
of a finished run stops the worker the same way. Further Ctrl-Cs while the plots are drawn
and the video closed are counted rather than raised; one that comes while a stopped worker
is still closing its files discards the video. A run that diverges keeps the video of the
frames rendered up to then too.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from pneumaquad.cli.common import (
    MAX_SIMULATED_TIME,
    OutputOption,
    ProfileOption,
    SetOption,
    command_clock,
    command_group,
    console,
    number_in,
    option_range,
    progress_bar,
    refuse_occupied_output,
    stderr_console,
)
from pneumaquad.cli.robot_runs import (
    progress_in_milliseconds,
    report_run,
    run_and_report,
    sample_hook,
    start_video_worker,
    video_of_a_diverged_run,
)
from pneumaquad.cli.settings import option_names, settings_options
from pneumaquad.cli.walk_outcome import print_walk_outcome
from pneumaquad.io.stage_clock import StageClock
from pneumaquad.locomotion.walk_settings import WALK_SETTINGS, WalkSettings
from pneumaquad.params import JOINT_NAMES, load_robot
from pneumaquad.params.fields import Bounds
from pneumaquad.robot.video import (
    DEFAULT_VIDEO_QUALITY,
    VIDEO_QUALITIES,
    RenderingUnavailableError,
)
from pneumaquad.robot.video_worker import (
    VideoSettings,
    VideoWorker,
    VideoWorkerError,
)

leg_app = command_group(
    help="The front-right leg on a fixed thorax (thesis 5.5.2 validation set-up).",
    no_args_is_help=True,
)
robot_app = command_group(help="The whole quadruped on its 12 pneumatic joints.",
                          no_args_is_help=True)

RobotParamsOption = Annotated[
    str, typer.Option("--params", "-p", help="Robot parameter set name or TOML path.")
]
EnvironmentOption = Annotated[str, typer.Option(help="flat, block, ramp, rough or hill.")]
SeedOption = Annotated[int, typer.Option(help="Seed of the rough terrain.")]
#: A phase of simulated time [s] in [0, 3600 s].
PHASE_TIME = Bounds(0.0, MAX_SIMULATED_TIME, "s", lower_inclusive=True)


def _within(lower: float, upper: float,
            unit: str = "") -> Callable[[float | int | None], float | int | None]:
    """Typer callback: a finite number within [lower, upper] (see :class:`Bounds`)."""
    return option_range(Bounds(lower, upper, unit, lower_inclusive=True))


def _check_video_quality(quality: str) -> str:
    """Typer callback: one of :data:`~pneumaquad.robot.video.VIDEO_QUALITIES`."""
    if quality not in VIDEO_QUALITIES:
        raise typer.BadParameter(f"{quality!r}: expected {' or '.join(VIDEO_QUALITIES)}")
    return quality


#: Default video frame rate [frames/s].
VIDEO_FPS = 30.0
VideoOption = Annotated[
    bool, typer.Option("--video/--no-video", help="Render video.mp4 and a GIF (in a separate "
                       "process, beside the run and the plots; a walk takes about 2.5x as "
                       "long with it). first-frame.png is drawn either way.")
]
VideoFpsOption = Annotated[
    float, typer.Option("--video-fps", help="Video frame rate, 1 to 240 frames/s.",
                        callback=_within(1.0, 240.0, "frames/s"))
]
VideoQualityOption = Annotated[
    str, typer.Option("--video-quality", help="fast: no shadows, reflections or "
                      "multisampling (about a tenth of the cost of a frame on software "
                      "OpenGL); full: the model's own look.", callback=_check_video_quality)
]


def _simulation(clock: StageClock, params: str, overrides: list[str] | None,
                configuration: str, environment: str = "flat", seed: int = 0,
                supply: str | None = None):
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.simulation import RobotSimulation

    with clock.stage("model (parameters, MuJoCo model, actuator bank)"):
        robot = build_robot(load_robot(params, overrides or []), configuration, environment,
                            seed)
        return RobotSimulation(robot, supply=supply)


#: Where a supply too low to stand or walk can be changed.
SUPPLY_HINT = "--set actuators.supply_pressure / thorax.mass"


def _refuse_short_supply(check, simulation, standing_angles, walking: bool) -> None:
    """``check`` (:func:`pneumaquad.locomotion.capacity.check_supply`) as a usage error."""
    from pneumaquad.locomotion.capacity import InsufficientSupplyError

    try:
        check(simulation, standing_angles, walking=walking)
    except InsufficientSupplyError as error:
        raise typer.BadParameter(str(error), param_hint=SUPPLY_HINT) from None


def _check_environment(environment: str) -> None:
    from pneumaquad.robot.environment import ENVIRONMENTS

    if environment not in ENVIRONMENTS:
        raise typer.BadParameter(f"{environment!r}: expected one of {', '.join(ENVIRONMENTS)}",
                                 param_hint="--environment")


@leg_app.command("validate")
@refuse_occupied_output
def leg_validate(
    joint: Annotated[
        str, typer.Option(help="Tested joint: alpha, beta, gamma, or all.")
    ] = "gamma",
    signal: Annotated[
        str, typer.Option(help="steps, trapezoid, slow-sine, fast-sine, or all.")
    ] = "steps",
    settle: Annotated[float, typer.Option(
        help="Open-loop extension phase [s], 0 to 3600.", callback=option_range(PHASE_TIME),
        parser=number_in("s"), metavar="QUANTITY")
    ] = 2.0,
    params: RobotParamsOption = "crr-quadruped",
    overrides: SetOption = None,
    output: OutputOption = None,
    video: VideoOption = False,
    video_fps: VideoFpsOption = VIDEO_FPS,
    video_quality: VideoQualityOption = DEFAULT_VIDEO_QUALITY,
    profile: ProfileOption = False,
) -> None:
    """Thesis 5.5.2: one joint of the front-right leg follows a test signal.

    With ``all`` for the joint and/or the signal, every combination runs, each in its own
    sub-folder of the output folder (``<joint>-<signal>``).
    """
    from pneumaquad.io.run_folder import create_run_folder
    from pneumaquad.robot.scenarios import LEG_SIGNALS, leg_validation_phases

    clock = command_clock()

    if joint not in (*JOINT_NAMES, "all"):
        raise typer.BadParameter(f"{joint!r}: expected one of {', '.join(JOINT_NAMES)} or all",
                                 param_hint="--joint")
    if signal not in (*LEG_SIGNALS, "all"):
        raise typer.BadParameter(f"{signal!r}: expected one of {', '.join(LEG_SIGNALS)} or all",
                                 param_hint="--signal")
    joints = JOINT_NAMES if joint == "all" else (joint,)
    signals = LEG_SIGNALS if signal == "all" else (signal,)
    several = len(joints) * len(signals) > 1
    base = create_run_folder(output, f"leg-{joint}-{signal}") if several else output
    folders = []
    for tested in joints:
        for kind in signals:
            worker = start_video_worker(video, video_fps, video_quality)
            with worker or contextlib.nullcontext():
                simulation = _simulation(clock, params, overrides, "fixed")
                phases = leg_validation_phases(simulation, tested, kind, settle)
                folder = base / f"{tested}-{kind}" if several else output
                folders.append((tested, kind, run_and_report(
                    simulation, phases, folder, f"leg-{tested}-{kind}",
                    f"front-right {tested}: {kind}", worker, video, clock, profile)))
                clock = StageClock()  # the next run's stages (start-up counted once)
    if several:
        _print_leg_matrix(folders, base)


def _print_leg_matrix(folders: list[tuple[str, str, Path]], base: Path) -> None:
    """One table of a leg matrix: per run, the tested joint's angle RMSE and its folder
    (in ``base``)."""
    from rich.markup import escape
    from rich.table import Table

    from pneumaquad.io.run_folder import read_summary

    table = Table(title=escape(f"leg validation: every run, in {base}"))
    for header in ("joint", "signal", "angle RMSE [deg]", "run folder"):
        table.add_column(escape(header), justify="right" if "RMSE" in header else "left")
    for tested, kind, folder in folders:
        rmse = read_summary(folder).get("angle rmse [deg]", {}).get(f"front_right_{tested}")
        table.add_row(tested, kind, "–" if rmse is None else f"{rmse:.2f}", escape(folder.name))
    console.print(table)


@leg_app.command("foot-cycle")
@refuse_occupied_output
def leg_foot_cycle(
    rate: Annotated[str, typer.Option(help="slow, medium, fast or all.")] = "all",
    cycles: Annotated[int, typer.Option(help="Cycles per rate, 1 to 1000.",
                                        callback=_within(1, 1000))] = 3,
    alpha_gain_scale: Annotated[
        float, typer.Option(help="Alpha PID gain scale (thesis: 0.75), 0 to 100.",
                            callback=_within(0.0, 100.0))
    ] = 1.0,
    params: RobotParamsOption = "crr-quadruped",
    overrides: SetOption = None,
    output: OutputOption = None,
    video: VideoOption = False,
    video_fps: VideoFpsOption = VIDEO_FPS,
    video_quality: VideoQualityOption = DEFAULT_VIDEO_QUALITY,
    profile: ProfileOption = False,
) -> None:
    """Thesis 5.5.2.4: the walking-like foot cycle of the front-right leg through IK."""
    from pneumaquad.robot.scenarios import FOOT_CYCLE_PERIODS, foot_cycle_phases

    clock = command_clock()

    rates = tuple(FOOT_CYCLE_PERIODS) if rate == "all" else (rate,)
    if any(r not in FOOT_CYCLE_PERIODS for r in rates):
        raise typer.BadParameter(f"{rate!r}: expected slow, medium, fast or all",
                                 param_hint="--rate")
    settings = [*(overrides or []), f"controller.alpha.gain_scale={alpha_gain_scale!r}"]
    with start_video_worker(video, video_fps, video_quality) or contextlib.nullcontext() as worker:
        simulation = _simulation(clock, params, settings, "fixed")
        phases = foot_cycle_phases(simulation, rates, cycles)
        run_and_report(simulation, phases, output, f"foot-cycle-{rate}",
                       f"foot cycle ({rate}), alpha gain x{alpha_gain_scale:g}", worker, video,
                       clock, profile)


@robot_app.command("stand")
@refuse_occupied_output
def robot_stand(
    hold: Annotated[float, typer.Option(help="Holding time after rising [s], 0 to 3600.",
                                        callback=option_range(PHASE_TIME),
                                        parser=number_in("s"), metavar="QUANTITY")] = 3.0,
    posture: Annotated[
        bool, typer.Option("--posture/--no-posture", help="Body height/roll/pitch commands.")
    ] = True,
    environment: EnvironmentOption = "flat",
    configuration: Annotated[
        str, typer.Option(help="quadruped, or testbed (front legs, rear on wheels).")
    ] = "quadruped",
    supply: Annotated[str | None, typer.Option(help="Override supply: ideal or tank.")] = None,
    rise: Annotated[str, typer.Option(
        help="Stand up with all legs together, a pair at a time (pairs), or auto: pairs "
             "where the supply is short of what rising together needs.")] = "auto",
    seed: SeedOption = 0,
    params: RobotParamsOption = "crr-quadruped",
    overrides: SetOption = None,
    output: OutputOption = None,
    video: VideoOption = False,
    video_fps: VideoFpsOption = VIDEO_FPS,
    video_quality: VideoQualityOption = DEFAULT_VIDEO_QUALITY,
    profile: ProfileOption = False,
) -> None:
    """The quadruped stands up from lying on the ground, holds, follows body commands; the
    stance after the hold is checked (height, joint errors, attitude) and reported."""
    from pneumaquad.locomotion.capacity import check_supply, rise_in_pairs
    from pneumaquad.robot.scenarios import STANDING_ANGLES, stand_up_phases

    clock = command_clock()

    if rise not in ("auto", "together", "pairs"):
        raise typer.BadParameter(f"{rise!r}: expected auto, together or pairs",
                                 param_hint="--rise")

    if supply not in (None, "ideal", "tank"):
        raise typer.BadParameter(f"{supply!r}: expected ideal or tank", param_hint="--supply")
    if configuration not in ("quadruped", "testbed"):
        raise typer.BadParameter(f"{configuration!r}: expected quadruped or testbed",
                                 param_hint="--configuration")
    _check_environment(environment)
    with start_video_worker(video, video_fps, video_quality) or contextlib.nullcontext() as worker:
        simulation = _simulation(clock, params, overrides, configuration, environment, seed,
                                 supply)
        if configuration == "quadruped":
            _refuse_short_supply(check_supply, simulation, STANDING_ANGLES, walking=False)
        staged = rise == "pairs" or (rise == "auto" and configuration == "quadruped"
                                     and rise_in_pairs(simulation, STANDING_ANGLES))
        phases = stand_up_phases(simulation, hold=hold, posture=posture, staged=staged)
        run_and_report(simulation, phases, output, f"{configuration}-stand",
                       f"{configuration}: stand up and hold", worker, video, clock, profile)


@robot_app.command("walk")
@settings_options(WalkSettings, WALK_SETTINGS)
@refuse_occupied_output
def robot_walk(
    settings: WalkSettings,
    environment: EnvironmentOption = "flat",
    seed: SeedOption = 0,
    params: RobotParamsOption = "crr-quadruped",
    overrides: SetOption = None,
    output: OutputOption = None,
    video: VideoOption = False,
    video_fps: VideoFpsOption = VIDEO_FPS,
    video_quality: VideoQualityOption = DEFAULT_VIDEO_QUALITY,
    profile: ProfileOption = False,
    waypoints: Annotated[str | None, typer.Option(
        metavar="X,Y;X,Y", help="Walk through these points in turn instead of --distance "
        "and --heading: metres from the start, x forward, y to the left; the robot keeps "
        "its yaw and re-places its feet at each (locomotion.waypoints).")] = None,
) -> None:
    """The quadruped stands up and walks a statically stable crawl (lateral-sequence wave
    gait, duty factor >= 0.75); reports success or failure with the reason."""
    from pneumaquad.locomotion.capacity import InsufficientSupplyError
    from pneumaquad.locomotion.walk_run import WalkSettingsError, run_walk, run_waypoints
    from pneumaquad.locomotion.waypoints import parse_waypoints

    clock = command_clock()

    _check_environment(environment)
    points = None
    if waypoints is not None:
        try:
            points = parse_waypoints(waypoints)
        except ValueError as error:
            raise typer.BadParameter(str(error), param_hint="--waypoints") from None
        settings = dataclasses.replace(settings, distance=float(np.sum(np.hypot(
            *np.diff(np.vstack([[0.0, 0.0], points]), axis=0).T))))
    distance, speed = settings.distance, settings.speed
    if distance / speed > MAX_SIMULATED_TIME:
        raise typer.BadParameter(
            f"walking {distance:g} m at {speed:g} m/s takes {distance / speed:.4g} s; expected "
            f"at most {MAX_SIMULATED_TIME:g} s of walking", param_hint="--distance / --speed")
    with start_video_worker(video, video_fps, video_quality) or contextlib.nullcontext() as worker:
        simulation = _simulation(clock, params, overrides, "quadruped", environment,
                                 seed)
        kind = f"walk-{environment}"
        try:
            with video_of_a_diverged_run(worker, video), progress_bar(kind) as update:
                hooks = sample_hook(worker, video, simulation)
                progress = progress_in_milliseconds(update)
                walk = (run_walk(simulation, settings, output, progress=progress, clock=clock,
                                 **hooks) if points is None else
                        run_waypoints(simulation, settings, points, output, progress=progress,
                                      clock=clock, **hooks))
        except WalkSettingsError as error:  # out of range, or a gait that cannot be planned
            hints = ["--waypoints"] if "waypoints" in error.fields else []
            fields = tuple(field for field in error.fields if field != "waypoints")
            if fields:
                hints.append(option_names(WALK_SETTINGS, fields))
            raise typer.BadParameter(str(error), param_hint=", ".join(hints)) from None
        except InsufficientSupplyError as error:
            raise typer.BadParameter(str(error), param_hint=SUPPLY_HINT) from None
        report_run(simulation, walk.run, walk.run.summary["description"], worker, video, clock,
                   profile)
    print_walk_outcome(walk.outcome, settings, waypoints=points is not None)


@robot_app.command("export")
def robot_export(
    path: Annotated[Path | None, typer.Argument(
        help="MJCF file to write (default: model.xml in a new runs/robot-export-<time> "
             "folder).")] = None,
    configuration: Annotated[str, typer.Option(help="quadruped, fixed or testbed.")] = (
        "quadruped"
    ),
    environment: EnvironmentOption = "flat",
    seed: SeedOption = 0,
    params: RobotParamsOption = "crr-quadruped",
    overrides: SetOption = None,
    overwrite: Annotated[bool, typer.Option(
        "--overwrite", help="Replace PATH if it exists.")] = False,
) -> None:
    """Write the MuJoCo model as MJCF (open it with `python -m mujoco.viewer --mjcf FILE`);
    without PATH under runs/, like every run."""
    from pneumaquad.robot.builder import CONFIGURATIONS, build_robot

    _check_environment(environment)
    if configuration not in CONFIGURATIONS:
        raise typer.BadParameter(
            f"{configuration!r}: expected one of {', '.join(CONFIGURATIONS)}",
            param_hint="--configuration",
        )
    if path is not None and path.exists() and not overwrite:
        raise typer.BadParameter(f"{path} exists; pass --overwrite to replace it, or choose "
                                 "another file (or none: runs/robot-export-<time>/model.xml)",
                                 param_hint="PATH")
    robot = build_robot(load_robot(params, overrides or []), configuration, environment, seed)
    if path is None:
        from pneumaquad.io.run_folder import MODEL_NAME, create_run_folder

        path = create_run_folder(None, "robot-export") / MODEL_NAME
    path.write_text(robot.to_xml(), encoding="utf-8")
    console.print(f"wrote {path}", soft_wrap=True, highlight=False)


@robot_app.command("geometry")
def robot_geometry(
    params: RobotParamsOption = "crr-quadruped", overrides: SetOption = None
) -> None:
    """Print the cylinder linkages (l1, l2, l3, γ0), the DH table of a leg and the least
    supply pressure at which the robot can stand up, stand and walk (statics)."""
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.kinematics import format_dh_table
    from pneumaquad.robot.legs import leg_dh_table
    from pneumaquad.robot.linkage import moment_arm

    robot = build_robot(load_robot(params, overrides or []), "fixed")
    for name in JOINT_NAMES:
        link = robot.linkages[name]
        joint = getattr(robot.parameters.leg, name)
        arms = np.abs(moment_arm(link, np.linspace(joint.lower_limit, joint.upper_limit, 50)))
        console.print(
            f"{name}: l3 (barrel) {link.parent_pivot_radius * 1e3:.1f} mm, l1 (rod pin) "
            f"{link.child_pivot_radius * 1e3:.1f} mm, l2 (retracted) "
            f"{link.retracted_length * 1e3:.1f} mm, "
            f"γ0 {math.degrees(link.included_angle_at_zero):.1f}°, "
            f"moment arm {arms.min() * 1e3:.1f}-{arms.max() * 1e3:.1f} mm",
            highlight=False,
        )
    console.print(format_dh_table(leg_dh_table(robot, "front_right")), highlight=False)
    _print_supply_requirements(params, overrides)


def _print_supply_requirements(params: str, overrides: list[str] | None) -> None:
    """The least supply pressure to stand up, stand and walk, from statics."""
    from pneumaquad.locomotion.capacity import (
        FOUR_LEGGED_RISE_MARGIN,
        four_legged_rise_path,
        gauge_text,
        stall_forces,
        supply_requirements,
    )
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.scenarios import STANDING_ANGLES
    from pneumaquad.robot.simulation import RobotSimulation

    robot = build_robot(load_robot(params, overrides or []), "quadruped")
    simulation = RobotSimulation(robot)
    atmosphere = simulation.atmospheric_pressure()
    console.print(f"least supply pressure from statics, {robot.model.body_mass.sum():.2f} kg "
                  f"robot (supply {gauge_text(simulation.supply_pressure(), atmosphere)}):",
                  highlight=False)
    for name in JOINT_NAMES:
        extending, retracting = stall_forces(robot.actuators[name])
        console.print(f"  {name} cylinder at this supply: {extending:.0f} N extending, "
                      f"{retracting:.0f} N retracting (Coulomb friction deducted)",
                      highlight=False)
    path = four_legged_rise_path(STANDING_ANGLES)
    for requirement in supply_requirements(simulation, STANDING_ANGLES, path):
        where = ", ".join(f"{math.degrees(a):.0f}°" for a in requirement.angles)
        console.print(
            f"  {requirement.situation}: {gauge_text(requirement.pressure, atmosphere)} "
            f"({requirement.joint} {requirement.force:+.0f} N at alpha, beta, gamma = "
            f"{where})", highlight=False)
    console.print(f"  (standing up: all four legs together; below "
                  f"{FOUR_LEGGED_RISE_MARGIN:g}x that absolute pressure the robot rises a "
                  "pair of legs at a time, which needs less)", highlight=False)


def video_command(
    run: Annotated[Path, typer.Argument(help="Run folder with model.xml and trajectory.npz.")],
    video_fps: Annotated[float, typer.Option(
        "--video-fps", "--fps", help="Video frame rate, 1 to 240 frames/s.",
        callback=_within(1.0, 240.0, "frames/s"))] = VIDEO_FPS,
    width: Annotated[int, typer.Option(help="Pixels, 16 to 7680.",
                                       callback=_within(16, 7680))] = 640,
    height: Annotated[int, typer.Option(help="Pixels, 16 to 4320.",
                                        callback=_within(16, 4320))] = 480,
    video_quality: VideoQualityOption = DEFAULT_VIDEO_QUALITY,
    profile: ProfileOption = False,
) -> None:
    """Render a robot run offscreen to MP4, a GIF preview and first-frame.png (in a separate
    process; a missing model.xml or trajectory.npz is an error, a missing OpenGL a warning)."""
    settings = VideoSettings(fps=video_fps, width=width, height=height, quality=video_quality)
    with VideoWorker(settings) as worker:
        worker.finish(run)
        try:
            with progress_bar("video frames") as update:
                rendered = worker.wait(update)  # Ctrl-C: the frames so far (VideoWorker.wait)
        except KeyboardInterrupt:  # a second Ctrl-C: the worker removes what it was writing
            stderr_console.print("[yellow]no video: interrupted again (Ctrl-C); the run "
                                 "folder is unchanged[/yellow]", highlight=False)
            raise typer.Exit(130) from None
        except RenderingUnavailableError as error:
            stderr_console.print(f"[yellow]no video: {error}[/yellow]")
            return
        except VideoWorkerError as error:
            stderr_console.print(f"[red]no video: {error}[/red]")
            raise typer.Exit(1) from None
    if rendered.complete:
        console.print(f"video: {rendered.mp4} ({rendered.frames} frames)")
    else:
        stderr_console.print(f"[yellow]video: {rendered.mp4} holds {rendered.frames} of "
                             f"{rendered.due} frames (interrupted)[/yellow]", highlight=False)
    if worker.interrupted:
        raise typer.Exit(130)
