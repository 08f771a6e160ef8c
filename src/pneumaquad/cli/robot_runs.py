"""The steps every robot command shares after its simulation is built: the run with its
progress bar and video hook, the report (plots, key figures, stance verdicts, the
command's real-time factor and profile) and the video worker's start and end.

The video is rendered by a separate process (:mod:`pneumaquad.robot.video_worker`)
started with the command and fed the recorded samples while the run goes; the report
waits for it last. Ctrl-C while reporting is counted, not raised, and acted on while
waiting for the worker (the module docstring of :mod:`pneumaquad.cli.robot`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import typer

from pneumaquad.cli.common import (
    console,
    exit_if_interrupted,
    progress_bar,
    report_command_time,
    stderr_console,
)
from pneumaquad.io.interruption import InterruptCount, counted_interrupts
from pneumaquad.io.stage_clock import StageClock
from pneumaquad.robot.errors import SimulationDivergedError
from pneumaquad.robot.video import RenderingUnavailableError, VideoError
from pneumaquad.robot.video_worker import (
    RenderedVideo,
    VideoSettings,
    VideoWorker,
    VideoWorkerError,
)

__all__ = ["print_checks", "print_video", "progress_in_milliseconds", "report_figures",
           "report_run", "run_and_report", "sample_hook", "start_video_worker",
           "video_of_a_diverged_run", "wait_for_video"]


def progress_in_milliseconds(
    update: Callable[[int, int], None],
) -> Callable[[float, float], None]:
    """A run's progress in simulated seconds for the progress bar (in milliseconds)."""
    return lambda done, total: update(int(done * 1000), int(total * 1000))


def start_video_worker(video: bool, fps: float, quality: str) -> VideoWorker | None:
    """The command's video worker, started first so that it is ready (OpenGL chosen, MuJoCo
    loaded) when the run begins; without ``video`` it renders only first-frame.png. None,
    with a yellow warning, if it cannot start."""
    try:
        return VideoWorker(VideoSettings(fps=fps, quality=quality, gif=video))
    except OSError as error:
        what = "video" if video else "first-frame.png"
        stderr_console.print(f"[yellow]no {what}: cannot start the video worker: {error}[/yellow]")
        return None


def sample_hook(worker: VideoWorker | None, video: bool, simulation) -> dict[str, Any]:
    """``on_sample=worker.add_sample`` for a video, after sending the model: the worker
    renders while the run goes. Without a video nothing: the worker renders only
    first-frame.png once the run has ended."""
    if not video or worker is None:
        return {}
    worker.send_model(simulation.robot.to_xml())
    return {"on_sample": worker.add_sample}


def run_and_report(simulation, phases, folder_option: Path | None, kind: str,
                   description: str, worker: VideoWorker | None, video: bool,
                   clock: StageClock, profile: bool, joints: list[str] | None = None) -> Path:
    """Play ``phases`` on ``simulation`` into a new run folder (``folder_option`` or
    runs/<kind>-<time>) with a progress bar, feeding the video worker, then
    :func:`report_run`; returns the folder."""
    from pneumaquad.io.run_folder import create_run_folder
    from pneumaquad.robot.experiment import run_phases

    folder = create_run_folder(folder_option, kind)
    with video_of_a_diverged_run(worker, video), progress_bar(kind) as update:
        run = run_phases(simulation, phases, folder, description,
                         progress_in_milliseconds(update), clock=clock,
                         **sample_hook(worker, video, simulation))
    report_run(simulation, run, description, worker, video, clock, profile, joints)
    return folder


def report_run(simulation, run, description: str, worker: VideoWorker | None, video: bool,
               clock: StageClock, profile: bool, joints: list[str] | None = None) -> None:
    """Plots, video and key figures of a finished robot run; exit 130 if interrupted.

    ``worker`` (:func:`start_video_worker`) renders the video, or only first-frame.png
    without ``video``. It is told that the run has ended first (and stopped if the run was
    interrupted), works while the plots are drawn, and is waited for at the end
    (:func:`wait_for_video`). Ctrl-C until then is counted, not raised
    (:func:`~pneumaquad.io.interruption.counted_interrupts`), and acted on while waiting:
    the plots and key figures are written whole, and the command exits with 130. The
    command's real-time factor follows, and with ``profile`` where its wall time went
    (``profile.json``).
    """
    folder = run.folder
    with counted_interrupts() as ctrl_c:
        if worker is not None:
            worker.finish(folder, first_frame_only=not video, interrupted=run.interrupted)
        with clock.stage("plots"):
            report_figures(simulation, run, description, joints)
        with clock.stage("video (waiting for the worker)" if video else
                         "first frame (waiting)"):
            waited = wait_for_video(worker, folder, first_frame_only=not video,
                                    ctrl_c=ctrl_c)
    if profile:
        from pneumaquad.robot.profiling import split_simulation_time

        steps = round(run.summary["simulated time [s]"] / simulation.control_step)
        with clock.stage("profile (timing the parts of the simulation)"):
            split_simulation_time(simulation, clock, steps)
    report_command_time(folder, run.summary, clock, profile)
    exit_if_interrupted(run.summary)  # the figures above are printed once
    if not waited or ctrl_c.presses:
        raise typer.Exit(130)


def report_figures(simulation, run, description: str, joints: list[str] | None) -> None:
    """Plots and key figures of a finished robot run."""
    from pneumaquad.reporting.robot_plots import plot_body, plot_joints

    folder = run.folder
    robot = simulation.robot
    leg_joints = joints or [n for n in robot.joint_names if n.startswith("front_right")]
    if run.recording["time [s]"].size > 1:
        plot_joints(run.recording, leg_joints, folder / "joints.png", description)
        if robot.free:
            plot_body(run.recording, robot.legs, folder / "body.png", description)
    summary = dict(run.summary)
    console.print(f"run folder: [bold]{folder}[/bold]")
    for key in ("simulated time [s]", "wall time [s]", "real-time factor", "air consumed [NL]",
                "mean air flow [NL/min]", "tank endurance at this mean flow [s]"):
        console.print(f"  {key}: {summary[key]:.6g}", markup=False, highlight=False)
    for name, phase in summary["phases"].items():
        console.print(
            f"  phase {name}: {phase['duration [s]']:.3g} s, air "
            f"{phase['mean air flow [NL/min]']:.3g} NL/min, tank lasts "
            f"{phase['tank endurance at this flow [s]'] / 60.0:.4g} min",
            markup=False, highlight=False,
        )
    for joint, error in summary["angle rmse [deg]"].items():
        if joint in leg_joints:
            console.print(f"  {joint} angle rmse [deg]: {error:.3g}", markup=False,
                          highlight=False)
    print_checks(summary)


def print_checks(summary: dict[str, Any]) -> None:
    """The verdicts of the run's stance checks (:class:`pneumaquad.robot.stance_check.
    StanceCheck`) and where the run stopped because of one."""
    for phase, verdict in summary.get("checks", {}).items():
        if "verified" not in verdict:
            continue
        word = "verified" if verdict["verified"] else "[bold red]not verified[/bold red]"
        console.print(
            f"stance {'after the hold' if phase == 'stance check' else 'before ' + phase}: "
            f"{word}: thorax {verdict['thorax height [m]']:.3f} m "
            f"(target {verdict['target thorax height [m]']:.3f} m), largest joint error "
            f"{verdict['largest joint error [deg]']:.1f}° "
            f"({verdict['joint with the largest error']}), roll "
            f"{verdict['thorax roll [deg]']:+.1f}°, pitch {verdict['thorax pitch [deg]']:+.1f}°",
            highlight=False)
    stopped = summary.get("stopped before")
    if stopped is not None:
        stderr_console.print(f"[yellow]stopped before {stopped['phase']}: {stopped['reason']}"
                             "[/yellow]", highlight=False)


def wait_for_video(worker: VideoWorker | None, folder: Path, first_frame_only: bool = False,
                   ctrl_c: InterruptCount | None = None) -> bool:
    """Wait for the worker with a progress bar and print its video; False after Ctrl-C.

    A Ctrl-C while waiting (with ``ctrl_c``: each one counted since, raised here) stops the
    worker, which keeps the frames rendered so far (:meth:`VideoWorker.wait`); one after the
    worker was stopped (also by an interrupted run) discards the video. A worker that fails
    leaves a yellow warning (the run folder is complete without it).
    """
    what = "first-frame.png" if first_frame_only else "video"
    if worker is None:
        return True

    def checked(update: Callable[[int, int], None] | None) -> Callable[[int, int], None]:
        def progress(done: int, total: int) -> None:
            if ctrl_c is not None:
                ctrl_c.check()
            if update is not None:
                update(done, total)
        return progress

    try:
        if first_frame_only:
            worker.wait(checked(None))
            return not worker.interrupted
        with progress_bar("video frames") as update:
            rendered = worker.wait(checked(update))
    except KeyboardInterrupt:
        hint = "" if first_frame_only else f"; `pneumaquad video {folder}` renders it"
        stderr_console.print(f"[yellow]no {what}: interrupted again{hint}[/yellow]")
        return False
    except (RenderingUnavailableError, VideoError, VideoWorkerError) as error:
        stderr_console.print(f"[yellow]no {what}: {error}[/yellow]")
        return not worker.interrupted
    print_video(rendered, worker.settings, folder)
    return not worker.interrupted


def print_video(rendered: RenderedVideo, settings: VideoSettings, folder: Path) -> None:
    """The line of a rendered video: its file and frames, and for a video stopped early
    (Ctrl-C, an interrupted or diverged run) how many of the frames due it holds."""
    if rendered.complete:
        console.print(f"video: {rendered.mp4} ({rendered.frames} frames at {settings.fps:g} "
                      f"frames/s, {settings.quality} quality)")
        return
    stderr_console.print(
        f"[yellow]video: {rendered.mp4} holds {rendered.frames} of {rendered.due} frames "
        f"(stopped early, at {settings.fps:g} frames/s); `pneumaquad video {folder}` renders "
        "them all[/yellow]")


@contextlib.contextmanager
def video_of_a_diverged_run(worker: VideoWorker | None, video: bool) -> Iterator[None]:
    """Around a run: if it diverges (its run folder written), the worker stops and its
    frames so far become the run's video before the error goes on."""
    try:
        yield
    except SimulationDivergedError as error:
        if video and worker is not None and error.folder is not None:
            worker.finish(error.folder, interrupted=True)
            wait_for_video(worker, error.folder)
        raise
