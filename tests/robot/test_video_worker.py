"""The video worker process: streamed and finished runs, frame counts, quality, failures."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path
from time import monotonic, sleep

import imageio.v3 as iio
import mujoco
import numpy as np
import pytest
from test_video import DURATION, MJCF, make_run_folder
from typer.testing import CliRunner

from conftest import CLI, interrupt_when_recording
from pneumaquad.cli.main import app
from pneumaquad.io.interruption import counted_interrupts
from pneumaquad.robot import video_worker
from pneumaquad.robot.errors import SimulationDivergedError
from pneumaquad.robot.video import (
    RenderingUnavailableError,
    create_renderer,
    nearest_samples,
)
from pneumaquad.robot.video_output import GIF_MAX_FRAMES, FrameSampler, GifPreview
from pneumaquad.robot.video_worker import VideoSettings, VideoWorker, VideoWorkerError

runner = CliRunner()
SMALL = dict(width=64, height=48)


def expected_frames(duration: float, fps: float) -> int:
    """Frames at 0, 1/fps, ... up to ``duration`` [s], a recorded duration (a sum of
    control steps, e.g. 3.4999999999997 s for 3.5 s) taken to the nearest microsecond."""
    return math.floor(duration * fps + 1e-6) + 1


def finished_video(worker: VideoWorker) -> video_worker.RenderedVideo:
    try:
        return worker.wait()
    except RenderingUnavailableError as error:
        pytest.skip(f"offscreen rendering unavailable: {error}")


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_run_folder(tmp_path_factory.mktemp("run"))


@pytest.mark.parametrize(("fps", "seconds"), [(12.0, DURATION), (20.0, 0.55)])
def test_streamed_samples_give_one_frame_per_video_period(
    run_folder: Path, tmp_path: Path, fps: float, seconds: float
) -> None:
    trajectory = np.load(run_folder / "trajectory.npz")
    kept = trajectory["time"] <= trajectory["time"][0] + seconds + 1e-9
    with VideoWorker(VideoSettings(fps=fps, **SMALL)) as worker:
        worker.send_model(MJCF)
        for time, qpos in zip(trajectory["time"][kept], trajectory["qpos"][kept], strict=True):
            worker.add_sample(time, qpos)
        worker.finish(tmp_path)
        video = finished_video(worker)
    frames = iio.imread(video.mp4)
    assert len(frames) == video.frames == expected_frames(seconds, fps)
    assert frames.shape[1:] == (48, 64, 3)
    assert video.first_frame == tmp_path / "first-frame.png" and video.first_frame.is_file()
    assert video.gif is not None and len(iio.imread(video.gif)) > 1


def test_worker_renders_a_finished_run_folder_like_a_streamed_run(
    run_folder: Path, tmp_path: Path
) -> None:
    settings = VideoSettings(fps=15.0, **SMALL)
    with VideoWorker(settings) as worker:
        worker.finish(run_folder)  # no samples: trajectory.npz
        from_file = finished_video(worker)
    trajectory = np.load(run_folder / "trajectory.npz")
    with VideoWorker(settings) as worker:
        worker.send_model(MJCF)
        for time, qpos in zip(trajectory["time"], trajectory["qpos"], strict=True):
            worker.add_sample(time, qpos)
        worker.finish(tmp_path)
        streamed = finished_video(worker)
    assert from_file.mp4 == run_folder / "video.mp4"
    assert from_file.frames == streamed.frames == expected_frames(DURATION, 15.0)
    assert np.array_equal(iio.imread(from_file.mp4), iio.imread(streamed.mp4))


def test_frame_sampler_chooses_as_on_the_whole_trajectory() -> None:
    random = np.random.default_rng(3)
    times = np.cumsum(random.choice([0.0, 0.004, 0.01, 0.013], size=400))  # with repeats
    qpos = np.arange(len(times), dtype=float)[:, None]
    for fps in (7.0, 30.0, 100.0, 333.0):
        sampler, chosen, start = FrameSampler(fps), [], 0
        while start < len(times):
            stop = start + int(random.integers(1, 25))
            chosen += sampler.add(times[start:stop], qpos[start:stop])
            start = stop
        chosen += sampler.finish()
        count = expected_frames(times[-1] - times[0], fps)
        reference = nearest_samples(times, times[0] + np.arange(count) / fps)
        assert [int(row[0]) for row in chosen] == reference.tolist()


@pytest.mark.parametrize(("quality", "shadows", "multisamples"),
                         [("fast", False, 0), ("full", True, 4)])
def test_quality_sets_the_scene_flags(quality: str, shadows: bool, multisamples: int) -> None:
    model = mujoco.MjModel.from_xml_string(MJCF)
    model.vis.quality.offsamples = 4
    try:
        renderer = create_renderer(model, 32, 24, quality)
    except RenderingUnavailableError as error:
        pytest.skip(f"offscreen rendering unavailable: {error}")
    try:
        flags = renderer.scene.flags
        assert flags[mujoco.mjtRndFlag.mjRND_SHADOW] == shadows
        assert flags[mujoco.mjtRndFlag.mjRND_REFLECTION] == shadows
        assert renderer._mjr_context.offSamples == multisamples  # the buffer it was made with
        assert model.vis.quality.offsamples == 4  # the model itself is left as it was
    finally:
        renderer.close()


@pytest.mark.parametrize("command", [
    ["robot", "walk"], ["robot", "stand"], ["leg", "validate"], ["leg", "foot-cycle"],
    ["video", "no-such-run"],
])
@pytest.mark.parametrize("fps", ["0", "241", "nan"])
def test_invalid_video_fps_is_refused_naming_the_option(command: list[str], fps: str) -> None:
    result = runner.invoke(app, [*command, "--video-fps", fps])
    assert result.exit_code == 2
    assert "--video-fps" in result.output and "240 frames/s" in result.output
    assert "Traceback" not in result.output


def test_unknown_video_quality_is_refused_naming_the_option() -> None:
    result = runner.invoke(app, ["robot", "walk", "--video-quality", "best"])
    assert result.exit_code == 2
    assert "--video-quality" in result.output and "fast or full" in result.output


def test_video_command_renders_a_run_folder(tmp_path: Path) -> None:
    folder = make_run_folder(tmp_path / "run")
    result = runner.invoke(app, ["video", str(folder), "--video-fps", "10", "--width", "64",
                                 "--height", "48", "--video-quality", "full"])
    if "no video" in result.output:
        pytest.skip(result.output)
    assert result.exit_code == 0, result.output
    assert len(iio.imread(folder / "video.mp4")) == expected_frames(DURATION, 10.0)
    result = runner.invoke(app, ["video", str(tmp_path / "nothing-here")])
    assert result.exit_code != 0 and "model.xml" in str(result.exception or result.output)


def test_a_failed_worker_is_reported_and_leaves_no_video(tmp_path: Path) -> None:
    with VideoWorker(VideoSettings(**SMALL)) as worker:
        worker.send_model(MJCF)
        worker._process.kill()  # a crash
        worker._process.wait()
        for step in range(50):  # the run goes on without noticing
            worker.add_sample(step * 0.01, np.zeros(8))
        worker.finish(tmp_path)
        with pytest.raises(VideoWorkerError, match="exit status"):
            worker.wait()
    assert list(tmp_path.iterdir()) == []


def test_cancelled_worker_removes_what_it_was_writing(run_folder: Path, tmp_path: Path) -> None:
    trajectory = np.load(run_folder / "trajectory.npz")
    worker = VideoWorker(VideoSettings(**SMALL))
    worker.send_model(MJCF)
    for time, qpos in zip(trajectory["time"], trajectory["qpos"], strict=True):
        worker.add_sample(time, qpos)
    worker.cancel()  # before finish: as after Ctrl-C or an error in the run
    assert not worker.running
    assert list(tmp_path.iterdir()) == []


def test_run_folder_is_complete_when_the_worker_fails(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    failing = [sys.executable, "-c", "import sys; sys.stderr.write('renderer crashed\\n'); "
               "sys.exit(7)"]
    monkeypatch.setattr(video_worker, "worker_command", lambda settings: failing)
    out = tmp_path / "run"
    result = runner.invoke(app, ["leg", "foot-cycle", "--rate", "fast", "--cycles", "1",
                                 "--video", "--video-fps", "5", "-o", str(out)])
    assert result.exit_code == 0, result.output
    shown = " ".join(result.output.split())
    assert "no video: the video worker ended with exit status 7: renderer crashed" in shown
    for name in ("parameters.toml", "model.xml", "recording.parquet", "trajectory.npz",
                 "summary.json", "joints.png"):
        assert (out / name).stat().st_size > 0, name
    assert not (out / "video.mp4").exists()


@pytest.mark.parametrize("frame_count", [100, 1000, 5000])
def test_gif_preview_of_a_run_of_unknown_length_stays_short(tmp_path: Path,
                                                           frame_count: int) -> None:
    preview = GifPreview(30.0)  # the run's duration is known only at its end
    random = np.random.default_rng(0)
    for index in range(frame_count):
        preview.add(index, random.integers(0, 255, (8, 8, 3), dtype=np.uint8))
    duration = (frame_count - 1) / 30.0
    frames = iio.imread(preview.save(tmp_path / "preview.gif", duration))
    wanted = math.ceil(frame_count / max(3, math.ceil(duration * 30.0 / GIF_MAX_FRAMES)))
    assert abs(len(frames) - wanted) <= 1 and len(frames) <= GIF_MAX_FRAMES + 1


def long_samples(run_folder: Path, repeats: int) -> tuple[np.ndarray, np.ndarray]:
    """The run folder's trajectory played ``repeats`` times in a row: times [s], qpos."""
    trajectory = np.load(run_folder / "trajectory.npz")
    times, qpos = trajectory["time"], trajectory["qpos"]
    span = times[-1] - times[0] + 0.01
    return np.concatenate([times + k * span for k in range(repeats)]), np.tile(qpos, (repeats, 1))


def assert_readable_part(video: video_worker.RenderedVideo, folder: Path, due: int) -> None:
    """``video`` is in ``folder``, holds 1 to ``due - 1`` of the ``due`` frames, and its MP4
    and GIF read back whole; no partial file is left beside them."""
    assert video.due == due and 1 <= video.frames < due and not video.complete
    assert video.mp4 == folder / "video.mp4" and len(iio.imread(video.mp4)) == video.frames
    assert video.gif is not None and len(iio.imread(video.gif)) >= 1
    assert video.first_frame.is_file()
    assert not list(folder.glob(".*.part"))


def test_an_interrupted_run_keeps_the_frames_rendered_so_far(
    run_folder: Path, tmp_path: Path
) -> None:
    """Finished with ``interrupted=True`` while far behind the run (240 frames/s of a 30 s
    run, all sent at once), the worker renders no further frame: the files hold the frames
    it had, and say how many the run called for."""
    times, qpos = long_samples(run_folder, 30)
    with VideoWorker(VideoSettings(fps=240.0, **SMALL)) as worker:
        worker.send_model(MJCF)
        for at, row in zip(times, qpos, strict=True):
            worker.add_sample(at, row)
        worker.finish(tmp_path, interrupted=True)
        video = finished_video(worker)
    assert_readable_part(video, tmp_path, expected_frames(times[-1] - times[0], 240.0))
    assert not worker.interrupted  # no Ctrl-C reached wait()


def test_ctrl_c_while_waiting_stops_the_worker_with_the_frames_so_far(
    run_folder: Path, tmp_path: Path
) -> None:
    """``pneumaquad video`` of a long run folder: the first Ctrl-C while waiting stops the
    worker, which moves the frames rendered so far into the folder."""
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "model.xml").write_text(MJCF)
    times, qpos = long_samples(run_folder, 30)
    np.savez(folder / "trajectory.npz", time=times, qpos=qpos)
    presses = []

    def ctrl_c_once(done: int, total: int) -> None:
        if not presses:
            presses.append(done)
            raise KeyboardInterrupt

    with VideoWorker(VideoSettings(fps=240.0, **SMALL)) as worker:
        worker.finish(folder)
        try:
            video = worker.wait(ctrl_c_once)
        except RenderingUnavailableError as error:
            pytest.skip(f"offscreen rendering unavailable: {error}")
    assert worker.interrupted and presses == [0]
    assert_readable_part(video, folder, expected_frames(times[-1] - times[0], 240.0))


def test_a_second_ctrl_c_while_waiting_leaves_no_partial_file(
    run_folder: Path, tmp_path: Path
) -> None:
    """Ctrl-C at every progress call: the first stops the worker, the second cancels it.
    Either it was cancelled (KeyboardInterrupt, nothing written) or it had already moved
    its files (returned, whole); never a part of a file."""
    times, qpos = long_samples(run_folder, 30)

    def ctrl_c(done: int, total: int) -> None:
        raise KeyboardInterrupt

    with VideoWorker(VideoSettings(fps=240.0, **SMALL)) as worker:
        worker.send_model(MJCF)
        for at, row in zip(times, qpos, strict=True):
            worker.add_sample(at, row)
        worker.finish(tmp_path)
        try:
            video = worker.wait(ctrl_c)
        except KeyboardInterrupt:
            assert list(tmp_path.iterdir()) == []
        else:
            assert_readable_part(video, tmp_path, expected_frames(times[-1] - times[0], 240.0))
    assert not worker.running


def test_stop_needs_the_folder_from_finish() -> None:
    with VideoWorker(VideoSettings(**SMALL)) as worker, pytest.raises(RuntimeError,
                                                                      match="finish"):
        worker.stop()


def test_ctrl_c_after_a_run_is_counted_and_raised_where_checked() -> None:
    before = signal.getsignal(signal.SIGINT)  # SIG_IGN where started in the background
    with counted_interrupts() as ctrl_c:
        os.kill(os.getpid(), signal.SIGINT)
        os.kill(os.getpid(), signal.SIGINT)
        assert ctrl_c.presses == 2  # nothing raised where the signals landed
        for _ in range(2):
            with pytest.raises(KeyboardInterrupt):
                ctrl_c.check()
        ctrl_c.check()  # each press raised once
    assert signal.getsignal(signal.SIGINT) is before  # the handler put back


def test_a_diverged_run_keeps_the_video_of_the_part_that_ran(tmp_path: Path) -> None:
    """30 ms Euler steps with massless pistons diverge
    (``test_a_diverging_run_stops_with_a_clear_error_and_keeps_its_recording``): the run
    ends with its error, and the video holds the frames rendered up to then."""
    out = tmp_path / "diverged"
    diverging = ['simulation.control_step="30 ms"', 'simulation.integrator="euler"',
                 *(f'linkages.{joint}.moving_mass="0 kg"' for joint in ("alpha", "beta",
                                                                          "gamma"))]
    result = runner.invoke(app, ["leg", "validate", "--signal", "fast-sine", "--settle", "0.5",
                                 "--video", "--video-fps", "240", "-o", str(out),
                                 *(part for item in diverging for part in ("--set", item))])
    assert isinstance(result.exception, SimulationDivergedError), result.output
    if "no video" in result.output:
        pytest.skip(result.output)
    times = np.load(out / "trajectory.npz")["time"]
    due = expected_frames(times[-1] - times[0], 240.0)
    frames = len(iio.imread(out / "video.mp4"))
    assert 1 <= frames <= due and (out / "video.gif").is_file()
    shown = " ".join(result.output.split())
    assert (f"({frames} frames at 240" in shown if frames == due
            else f"holds {frames} of {due} frames" in shown)


def sigint_twice(arguments: list[str], out: Path, min_bytes: int) -> tuple[int, str]:
    """Run ``pneumaquad <arguments>`` writing into ``out``; SIGINT once ``recording.csv``
    holds ``min_bytes``, again as soon as ``summary.json`` exists (the run has stopped and
    the command is finishing); return (exit status, stderr)."""
    process = subprocess.Popen([*CLI, *arguments], cwd=out.parent, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        for wanted, size in ((out / "recording.csv", min_bytes), (out / "summary.json", 0)):
            deadline = monotonic() + 120.0  # a hang guard, no measure of speed
            while process.poll() is None and monotonic() < deadline:
                if wanted.is_file() and wanted.stat().st_size >= size:
                    break
                sleep(0.01)
            process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    return process.returncode, stderr


def test_ctrl_c_in_the_run_stops_the_video_with_the_frames_rendered_so_far(
    tmp_path: Path,
) -> None:
    """Issue 18: a 600 s hold with a 240 frames/s video, Ctrl-C once the run has recorded a
    few seconds. The worker is far behind the run (each simulated second is 240 frames);
    the command used to render every frame due before exiting. Now it exits with 130, the
    summary says interrupted, and the video holds fewer frames than the run called for:
    the command did not wait for the rest."""
    out = tmp_path / "long"
    returncode, stderr = interrupt_when_recording(
        ["robot", "stand", "--hold", "600", "--video", "--video-fps", "240", "-o", str(out)],
        out / "recording.csv", 1_000_000, 120.0, cwd=tmp_path,
    )
    assert returncode == 130, stderr
    assert json.loads((out / "summary.json").read_text())["interrupted"] is True
    if "no video" in stderr:
        pytest.skip(stderr)
    times = np.load(out / "trajectory.npz")["time"]
    due = expected_frames(times[-1] - times[0], 240.0)
    frames = len(iio.imread(out / "video.mp4"))
    assert 1 <= frames < due
    assert f"holds {frames} of {due} frames" in " ".join(stderr.split())
    assert len(iio.imread(out / "video.gif")) >= 1 and (out / "first-frame.png").is_file()
    assert "Traceback" not in stderr


def test_a_second_ctrl_c_while_the_command_finishes_breaks_nothing(tmp_path: Path) -> None:
    """Ctrl-C, then Ctrl-C again while the command writes the plots and closes the video:
    exit 130 (or SIGINT itself, if it landed as the interpreter exited), no traceback, the
    summary written, and a video that is whole or absent."""
    out = tmp_path / "twice"
    returncode, stderr = sigint_twice(["robot", "stand", "--hold", "600", "--video", "-o",
                                       str(out)], out, 300_000)
    assert returncode in (130, -signal.SIGINT), stderr
    assert "Traceback" not in stderr and "Exception ignored" not in stderr
    assert json.loads((out / "summary.json").read_text())["interrupted"] is True
    assert not list(out.glob(".*.part"))
    if (out / "video.mp4").exists():
        assert len(iio.imread(out / "video.mp4")) >= 1
