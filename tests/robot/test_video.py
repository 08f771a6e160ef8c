"""Offscreen run videos: files, frame counts and contents, error messages."""

from __future__ import annotations

from itertools import pairwise
from pathlib import Path

import imageio.v3 as iio
import mujoco
import numpy as np
import pytest

from pneumaquad.robot import video
from pneumaquad.robot.video import (
    MissingRunFileError,
    RenderingUnavailableError,
    VideoError,
    VideoFiles,
    render_frames,
    render_run_video,
    select_gl_backend,
)

FPS = 30
WIDTH, HEIGHT = 160, 120
DURATION = 1.0
SAMPLE_RATE = 100.0

# A free-floating capsule "thorax" with a hinged leg, dropped onto a checkered floor.
MJCF = """
<mujoco model="falling-thorax">
  <option timestep="0.002"/>
  <asset>
    <texture name="grid" type="2d" builtin="checker" width="64" height="64"
             rgb1="0.2 0.3 0.4" rgb2="0.8 0.8 0.8"/>
    <material name="grid" texture="grid" texrepeat="8 8"/>
  </asset>
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="3 3 0.1" material="grid"/>
    <body name="thorax" pos="0 0 0.6">
      <freejoint/>
      <geom type="capsule" fromto="-0.15 0 0 0.15 0 0" size="0.05" rgba="0.8 0.3 0.2 1"/>
      <body name="leg" pos="0.15 0 0">
        <joint name="knee" type="hinge" axis="0 1 0" damping="0.01"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" rgba="0.2 0.7 0.3 1"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def make_run_folder(folder: Path) -> Path:
    """Simulate the model for DURATION and store ``model.xml`` and ``trajectory.npz``."""
    model = mujoco.MjModel.from_xml_string(MJCF)
    data = mujoco.MjData(model)
    data.qvel[3:6] = [0.0, 2.0, 4.0]  # spin the thorax
    data.qvel[6] = 6.0  # swing the leg
    steps_per_sample = round(1.0 / (SAMPLE_RATE * model.opt.timestep))
    times, qpos = [], []
    for sample in range(round(DURATION * SAMPLE_RATE) + 1):
        if sample:
            mujoco.mj_step(model, data, nstep=steps_per_sample)
        times.append(data.time)
        qpos.append(data.qpos.copy())
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "model.xml").write_text(MJCF)
    np.savez(folder / "trajectory.npz", time=np.array(times), qpos=np.array(qpos))
    return folder


@pytest.fixture(scope="module")
def rendered(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, VideoFiles]:
    folder = make_run_folder(tmp_path_factory.mktemp("run"))
    try:
        files = render_run_video(folder, fps=FPS, width=WIDTH, height=HEIGHT)
    except RenderingUnavailableError as error:
        pytest.skip(f"offscreen rendering unavailable: {error}")
    return folder, files


def test_files_are_written_into_the_run_folder(rendered: tuple[Path, VideoFiles]) -> None:
    folder, files = rendered
    assert files == VideoFiles(
        folder / "video.mp4", folder / "video.gif", folder / "first-frame.png"
    )
    for path in (files.mp4, files.gif, files.first_frame):
        assert path.is_file() and path.stat().st_size > 0


def test_mp4_has_one_frame_per_video_period(rendered: tuple[Path, VideoFiles]) -> None:
    frames = iio.imread(rendered[1].mp4)
    assert abs(len(frames) - FPS * DURATION) <= 1
    assert frames.shape[1:] == (HEIGHT, WIDTH, 3)


def test_first_frame_png_matches_first_video_frame(rendered: tuple[Path, VideoFiles]) -> None:
    png = iio.imread(rendered[1].first_frame)
    first = iio.imread(rendered[1].mp4, index=0)
    assert png.shape == (HEIGHT, WIDTH, 3)
    assert np.mean(np.abs(png.astype(float) - first.astype(float))) < 4.0


def test_frames_show_a_moving_scene(rendered: tuple[Path, VideoFiles]) -> None:
    frames = iio.imread(rendered[1].mp4).astype(float)
    assert all(frame.std() > 10.0 for frame in frames)
    # The thorax spins and the leg swings throughout the first half second.
    changes = [np.mean(np.abs(after - before)) for before, after in pairwise(frames[:15])]
    assert min(changes) > 0.5


def test_gif_preview_is_small_and_about_ten_frames_per_second(
    rendered: tuple[Path, VideoFiles],
) -> None:
    frames = iio.imread(rendered[1].gif)
    assert abs(len(frames) - 10 * DURATION) <= 1
    assert frames.shape[2] <= 320


def test_render_frames_resamples_to_the_video_rate(tmp_path: Path) -> None:
    folder = make_run_folder(tmp_path)
    model = mujoco.MjModel.from_xml_path(str(folder / "model.xml"))
    trajectory = np.load(folder / "trajectory.npz")
    try:
        frames = list(
            render_frames(
                model,
                trajectory["time"][:51],
                trajectory["qpos"][:51],
                fps=10,
                width=64,
                height=48,
                tracking_body="no-such-body",
            )
        )
    except RenderingUnavailableError as error:
        pytest.skip(f"offscreen rendering unavailable: {error}")
    assert len(frames) == 6  # 0.0, 0.1, ..., 0.5 s
    assert frames[0].shape == (48, 64, 3) and frames[0].dtype == np.uint8


def test_missing_trajectory_is_named(tmp_path: Path) -> None:
    folder = make_run_folder(tmp_path)
    (folder / "trajectory.npz").unlink()
    with pytest.raises(FileNotFoundError, match=r"trajectory\.npz") as caught:
        render_run_video(folder)
    assert isinstance(caught.value, MissingRunFileError | VideoError)


def test_missing_model_is_named(tmp_path: Path) -> None:
    folder = make_run_folder(tmp_path)
    (folder / "model.xml").unlink()
    with pytest.raises(MissingRunFileError, match=r"model\.xml"):
        render_run_video(folder)


def test_trajectory_not_matching_the_model_is_rejected() -> None:
    model = mujoco.MjModel.from_xml_string(MJCF)
    with pytest.raises(VideoError, match="qpos must have shape"):
        render_frames(model, np.linspace(0.0, 1.0, 5), np.zeros((5, model.nq + 1)))


def test_existing_mujoco_gl_is_respected(monkeypatch: pytest.MonkeyPatch) -> None:
    probed = []
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    monkeypatch.setattr(video, "_probe_backend", lambda backend: probed.append(backend))
    assert select_gl_backend() == "osmesa"
    assert probed == ["osmesa"]


def test_broken_mujoco_gl_from_the_user_is_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    monkeypatch.setattr(video, "_probe_backend", lambda backend: "no libOSMesa")
    with pytest.raises(RenderingUnavailableError, match=r"MUJOCO_GL=osmesa .*no libOSMesa"):
        select_gl_backend()


def test_no_working_backend_raises_with_package_hints(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setattr(video, "_probe_backend", lambda backend: f"{backend} is broken")
    with pytest.raises(RenderingUnavailableError) as caught:
        select_gl_backend()
    message = str(caught.value)
    assert "egl is broken" in message and "osmesa is broken" in message
    assert "libegl1" in message and "libosmesa6" in message
