"""Offscreen videos of robot runs rendered with MuJoCo.

A run folder holds ``model.xml`` (the MJCF of the simulated model) and ``trajectory.npz``
(arrays ``time`` (T,) [s] and ``qpos`` (T, nq)). :func:`render_run_video` replays it at the
video rate (nearest recorded sample, so free-joint quaternions stay normalised), with a camera
tracking the ``thorax`` body, and writes ``video.mp4`` (H.264, yuv420p, frames streamed to
ffmpeg), ``video.gif`` (downscaled preview, about 10 frames/s) and ``first-frame.png``.

OpenGL backend: MuJoCo binds its context class when ``mujoco`` is first imported, from
``MUJOCO_GL`` (unset means GLFW, which needs a display), and a failed context creation can leave
the process unusable. :func:`select_gl_backend` therefore keeps a ``MUJOCO_GL`` set by the user
and otherwise probes ``egl`` then ``osmesa`` in short-lived subprocesses, exporting the first
that renders. This module imports ``mujoco`` only inside functions, so a command that calls
:func:`select_gl_backend` before importing ``mujoco`` gets the backend natively; if ``mujoco``
was imported earlier with another context class bound, the chosen class is substituted only
while the renderer is created. :class:`RenderingUnavailableError` (no working backend) lets
callers skip the video with a warning.
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import math
import os
import subprocess
import sys
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import imageio.v2 as imageio_v2
import imageio.v3 as imageio_v3
import numpy as np
from PIL import Image

from pneumaquad.io.run_folder import MODEL_NAME, TRAJECTORY_NAME

if TYPE_CHECKING:
    import mujoco

MP4_NAME, GIF_NAME, FIRST_FRAME_NAME = "video.mp4", "video.gif", "first-frame.png"
GIF_FPS, GIF_MAX_WIDTH = 10.0, 320
GIF_MAX_FRAMES = 300  # a 320 px preview of about 10 MB at most
_BACKENDS = ("egl", "osmesa")
_SYSTEM_PACKAGES = {"egl": "libegl1 libgl1-mesa-dri libgbm1", "osmesa": "libosmesa6"}
_FFMPEG_OPTIONS = dict(codec="libx264", pixelformat="yuv420p", macro_block_size=1)
_PROBE_SCRIPT = """
import mujoco
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
renderer = mujoco.Renderer(model, height=8, width=8)
renderer.render()
renderer.close()
"""


class VideoError(ValueError):
    """Invalid input for rendering a run video."""


class MissingRunFileError(VideoError, FileNotFoundError):
    """A file a run video needs is missing from the run folder."""


class RenderingUnavailableError(RuntimeError):
    """No working offscreen OpenGL backend is available to MuJoCo."""


@dataclass(frozen=True)
class VideoFiles:
    """Files written by :func:`render_run_video` (``gif`` is ``None`` if not requested)."""

    mp4: Path
    gif: Path | None
    first_frame: Path


@functools.cache
def _probe_backend(backend: str) -> str | None:
    """Render a tiny model in a subprocess with ``MUJOCO_GL=backend``; return why it failed."""
    command = [sys.executable, "-c", _PROBE_SCRIPT]
    options = dict(env={**os.environ, "MUJOCO_GL": backend}, timeout=60, check=False)
    try:
        completed = subprocess.run(command, capture_output=True, text=True, **options)
    except subprocess.TimeoutExpired:
        return "timed out after 60 s"
    if completed.returncode == 0:
        return None
    lines = [line.strip() for line in completed.stderr.splitlines() if line.strip()]
    return lines[-1] if lines else f"exit status {completed.returncode}"


def select_gl_backend() -> str:
    """Choose the OpenGL backend MuJoCo renders with and export it as ``MUJOCO_GL``.

    Returns
    -------
    str
        ``MUJOCO_GL`` if already set, otherwise the first of ``"egl"`` and ``"osmesa"``. Each
        is checked by rendering a test image in a subprocess (cached per process).

    Raises
    ------
    RenderingUnavailableError
        If a ``MUJOCO_GL`` set by the user does not work, or neither ``egl`` nor ``osmesa``
        does; the message gives each failure and the Debian packages to install.
    """
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    if requested:
        reason = _probe_backend(requested)
        if reason is None:
            return requested
        raise RenderingUnavailableError(
            f"MUJOCO_GL={requested} (set in the environment) cannot render: {reason}. Unset it "
            f"to try {' and '.join(_BACKENDS)}, or install the packages it needs."
        )
    failures = []
    for backend in _BACKENDS:
        reason = _probe_backend(backend)
        if reason is None:
            os.environ["MUJOCO_GL"] = backend
            return backend
        failures.append(f"{backend}: {reason} (Debian packages: {_SYSTEM_PACKAGES[backend]})")
    raise RenderingUnavailableError(
        f"no offscreen OpenGL backend works for MuJoCo; tried {'; '.join(failures)}. "
        "Install the packages or set MUJOCO_GL to a working backend."
    )


@contextlib.contextmanager
def _context_class_bound(backend: str) -> Iterator[None]:
    """Make ``mujoco.Renderer`` use ``backend`` even if ``mujoco`` was imported before."""
    import mujoco

    context_module = getattr(sys.modules.get(mujoco.Renderer.__module__), "gl_context", None)
    bound = getattr(context_module, "GLContext", None)
    if backend not in _BACKENDS or bound is None or bound.__module__ == f"mujoco.{backend}":
        yield
        return
    try:
        context_module.GLContext = importlib.import_module(f"mujoco.{backend}").GLContext
    except (ImportError, AttributeError) as error:
        raise RenderingUnavailableError(f"cannot load the {backend} backend: {error}") from error
    try:
        yield
    finally:
        context_module.GLContext = bound


def _nearest_indices(times: np.ndarray, frame_times: np.ndarray) -> np.ndarray:
    """Index of the recorded sample nearest to each frame time."""
    upper = np.clip(np.searchsorted(times, frame_times), 1, max(len(times) - 1, 1))
    lower = upper - 1
    upper = np.minimum(upper, len(times) - 1)
    return np.where(frame_times - times[lower] <= times[upper] - frame_times, lower, upper)


def render_frames(
    model: mujoco.MjModel,
    times: np.ndarray,
    qpos: np.ndarray,
    *,
    fps: float = 30.0,
    width: int = 640,
    height: int = 480,
    tracking_body: str = "thorax",
    distance: float | None = None,
    azimuth: float = 135.0,
    elevation: float = -20.0,
) -> Iterator[np.ndarray]:
    """Render a recorded trajectory frame by frame at the video rate.

    Parameters
    ----------
    model
        Model the trajectory was recorded with; its offscreen buffer
        (``model.vis.global_.offwidth/offheight``) is enlarged if smaller than the frame.
    times, qpos
        Sample times (T,) [s], non-decreasing, and joint positions (T, nq).
    fps
        Video frame rate [1/s]; frame ``k`` shows the sample nearest to ``times[0] + k / fps``.
    width, height
        Frame size [px].
    tracking_body
        Body the camera tracks; without such a body a free camera looks at the model centre.
    distance, azimuth, elevation
        Camera distance [m] (``None``: 1.5 ``model.stat.extent``) and angles [deg].

    Returns
    -------
    Iterator[numpy.ndarray]
        Lazily rendered RGB ``uint8`` frames (height, width, 3). The renderer is created at the
        first frame and closed when the iterator is exhausted or closed.

    Raises
    ------
    VideoError
        At the call, if the arrays do not match the model.
    RenderingUnavailableError
        At the first frame, if no OpenGL context can be created.
    """
    import mujoco

    times, qpos = np.asarray(times, dtype=float), np.asarray(qpos, dtype=float)
    if times.ndim != 1 or len(times) == 0:
        raise VideoError(f"time must be a non-empty 1-D array, got shape {times.shape}")
    if qpos.shape != (len(times), model.nq):
        raise VideoError(f"qpos must have shape ({len(times)}, {model.nq}), got {qpos.shape}")
    if not np.all(np.isfinite(times)) or np.any(np.diff(times) < 0):
        raise VideoError("time must be finite and non-decreasing")
    if not fps > 0:
        raise VideoError(f"fps must be positive, got {fps}")
    frame_count = math.floor((times[-1] - times[0]) * fps + 1e-9) + 1
    samples = _nearest_indices(times, times[0] + np.arange(frame_count) / fps)

    camera = mujoco.MjvCamera()
    body_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, tracking_body)
    if body_id >= 0:
        camera.type, camera.trackbodyid = mujoco.mjtCamera.mjCAMERA_TRACKING, body_id
    else:
        camera.type, camera.lookat[:] = mujoco.mjtCamera.mjCAMERA_FREE, model.stat.center
    camera.distance = 1.5 * model.stat.extent if distance is None else distance
    camera.azimuth, camera.elevation = azimuth, elevation
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    return _frames(model, qpos[samples], camera, width, height)


def _frames(
    model: mujoco.MjModel, qpos: np.ndarray, camera: mujoco.MjvCamera, width: int, height: int
) -> Iterator[np.ndarray]:
    """Render one frame per row of ``qpos``; the renderer lives as long as the generator."""
    import mujoco

    backend = select_gl_backend()
    try:
        with _context_class_bound(backend):
            renderer = mujoco.Renderer(model, height=height, width=width)
    except RenderingUnavailableError:
        raise
    except Exception as error:
        message = f"cannot create a MuJoCo renderer with MUJOCO_GL={backend}: {error}"
        raise RenderingUnavailableError(message) from error
    data = mujoco.MjData(model)
    try:
        for row in qpos:
            data.qpos[:] = row
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=camera)
            yield renderer.render()
    finally:
        renderer.close()


def write_video(frames: Iterable[np.ndarray], path: Path, fps: float) -> int:
    """Stream RGB ``uint8`` frames into an H.264 MP4 (yuv420p) and return their number.

    Frames are consumed one at a time; an odd width or height is cropped by one pixel (H.264
    with yuv420p needs even sizes). The file is removed again if writing fails.
    """
    path = Path(path)
    writer = imageio_v2.get_writer(
        path, format="FFMPEG", fps=fps, ffmpeg_log_level="error", **_FFMPEG_OPTIONS
    )
    count = 0
    try:
        for frame in frames:
            even_height, even_width = frame.shape[0] // 2 * 2, frame.shape[1] // 2 * 2
            writer.append_data(np.ascontiguousarray(frame[:even_height, :even_width]))
            count += 1
    except BaseException:
        writer.close()
        path.unlink(missing_ok=True)
        raise
    writer.close()
    if count == 0:
        path.unlink(missing_ok=True)
        raise VideoError(f"no frames to write to {path}")
    return count


def _gif_step(fps: float, duration: float | None = None) -> int:
    """Frames per GIF frame: about 10 GIF frames per second of run, fewer for runs longer
    than :data:`GIF_MAX_FRAMES` / 10 s (the preview then plays as a time lapse)."""
    step = max(1, round(fps / GIF_FPS))
    if duration is not None:
        step = max(step, math.ceil(duration * fps / GIF_MAX_FRAMES))
    return step


def _downscale(frame: np.ndarray, max_width: int) -> np.ndarray:
    height, width = frame.shape[:2]
    if width <= max_width:
        return frame
    size = (max_width, max(1, round(height * max_width / width)))
    return np.asarray(Image.fromarray(frame).resize(size, Image.Resampling.BILINEAR))


def _save_gif(frames: list[np.ndarray], path: Path, frame_duration_ms: float) -> Path:
    if not frames:
        raise VideoError(f"no frames to write to {path}")
    imageio_v3.imwrite(path, np.stack(frames), extension=".gif", duration=frame_duration_ms, loop=0)
    return path


def write_gif_preview(
    frames: Iterable[np.ndarray], path: Path, fps: float, max_width: int = GIF_MAX_WIDTH
) -> Path:
    """Write a looping GIF of every ``round(fps / 10)``-th frame, at most ``max_width`` wide.

    It plays in real time at about 10 frames/s; only the kept, downscaled frames are held in
    memory. Returns ``path``.
    """
    step = _gif_step(fps)
    kept = [_downscale(frame, max_width) for index, frame in enumerate(frames) if index % step == 0]
    return _save_gif(kept, Path(path), 1000.0 * step / fps)


def write_first_frame_png(frame: np.ndarray, path: Path) -> Path:
    """Write one RGB ``uint8`` frame (height, width, 3) to ``path`` as a PNG and return it."""
    path = Path(path)
    imageio_v3.imwrite(path, frame, extension=".png")
    return path


def _load_run(run_folder: Path, max_seconds: float | None = None):
    """The run's model, times [s] and qpos, with the GL backend chosen before mujoco loads."""
    model_path, trajectory_path = run_folder / MODEL_NAME, run_folder / TRAJECTORY_NAME
    for required in (model_path, trajectory_path):
        if not required.is_file():
            raise MissingRunFileError(f"run video needs {required}, which does not exist")
    with np.load(trajectory_path, allow_pickle=False) as archive:
        missing = [key for key in ("time", "qpos") if key not in archive]
        if missing:
            raise VideoError(f"{trajectory_path} lacks the array(s) {', '.join(missing)}")
        times, qpos = np.asarray(archive["time"], float), np.asarray(archive["qpos"], float)
    if max_seconds is not None and len(times):
        keep = times <= times[0] + max_seconds
        times, qpos = times[keep], qpos[keep]
    backend = select_gl_backend()  # before the first `import mujoco` of the process, if possible
    try:
        import mujoco
    except Exception as error:  # a broken MUJOCO_GL makes the import itself fail
        message = f"importing mujoco with MUJOCO_GL={backend} failed: {error!r}"
        raise RenderingUnavailableError(message) from error

    try:
        model = mujoco.MjModel.from_xml_path(str(model_path))
    except ValueError as error:
        raise VideoError(f"cannot load {model_path}: {error}") from error
    return model, times, qpos


def render_first_frame(run_folder: Path, *, width: int = 640, height: int = 480) -> Path:
    """Write only ``first-frame.png`` of a run folder (one rendered frame); returns its path.

    Raises the same errors as :func:`render_run_video`.
    """
    model, times, qpos = _load_run(Path(run_folder))
    frame = next(iter(render_frames(model, times[:1], qpos[:1], fps=1.0, width=width,
                                    height=height)))
    return write_first_frame_png(frame, Path(run_folder) / FIRST_FRAME_NAME)


def render_run_video(
    run_folder: Path,
    *,
    output: Path | None = None,
    fps: float = 30,
    width: int = 640,
    height: int = 480,
    gif: bool = True,
    max_seconds: float | None = None,
) -> VideoFiles:
    """Render ``video.mp4``, ``video.gif`` and ``first-frame.png`` of a run folder.

    Parameters
    ----------
    run_folder
        Folder with ``model.xml`` and ``trajectory.npz``.
    output
        Folder for the files (created if missing); ``None`` means ``run_folder``.
    fps, width, height
        Video frame rate [1/s] and frame size [px].
    gif
        Also write the GIF preview (about 10 frames per second of run; runs longer than
        30 s become a time lapse of :data:`GIF_MAX_FRAMES` frames).
    max_seconds
        Render only the first ``max_seconds`` of the trajectory.

    Returns
    -------
    VideoFiles
        Paths of the written files. One rendering pass feeds all three.

    Raises
    ------
    MissingRunFileError
        If ``model.xml`` or ``trajectory.npz`` is missing (a ``FileNotFoundError`` naming it).
    VideoError
        If the trajectory is malformed or the model cannot be loaded.
    RenderingUnavailableError
        If no offscreen OpenGL backend works.
    """
    model, times, qpos = _load_run(Path(run_folder), max_seconds)
    frames = render_frames(model, times, qpos, fps=fps, width=width, height=height)

    folder = Path(run_folder) if output is None else Path(output)
    folder.mkdir(parents=True, exist_ok=True)
    gif_path = folder / GIF_NAME if gif else None
    files = VideoFiles(folder / MP4_NAME, gif_path, folder / FIRST_FRAME_NAME)
    gif_frames: list[np.ndarray] = []
    step = _gif_step(fps, float(times[-1] - times[0]) if len(times) else None)

    def tap(frames: Iterator[np.ndarray]) -> Iterator[np.ndarray]:
        for index, frame in enumerate(frames):
            if index == 0:
                write_first_frame_png(frame, files.first_frame)
            if gif and index % step == 0:
                gif_frames.append(_downscale(frame, GIF_MAX_WIDTH))
            yield frame

    write_video(tap(frames), files.mp4, fps)
    if files.gif is not None:
        _save_gif(gif_frames, files.gif, 1000.0 * step / fps)
    return files
