"""The video worker process: streamed and finished runs, frame counts, quality, failures."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import imageio.v3 as iio
import mujoco
import numpy as np
import pytest
from test_video import DURATION, MJCF, make_run_folder
from typer.testing import CliRunner

from conftest import interrupt_when_recording
from pneumaquad.cli.main import app
from pneumaquad.robot import video_worker
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


def test_ctrl_c_in_the_run_keeps_the_folder_and_renders_the_part_that_ran(
    tmp_path: Path,
) -> None:
    out = tmp_path / "long"
    returncode, stderr = interrupt_when_recording(
        ["robot", "stand", "--hold", "3000", "--video", "--video-fps", "2", "-o", str(out)],
        out / "recording.csv", 200_000, 120.0, cwd=tmp_path,
    )
    assert returncode == 130, stderr
    assert json.loads((out / "summary.json").read_text())["interrupted"] is True
    if "no video" in stderr:
        pytest.skip(stderr)
    times = np.load(out / "trajectory.npz")["time"]
    frames = iio.imread(out / "video.mp4")
    assert len(frames) == expected_frames(times[-1] - times[0], 2.0) > 1
    assert (out / "first-frame.png").is_file() and (out / "video.gif").is_file()
