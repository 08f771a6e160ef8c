"""Offscreen videos of robot runs rendered with MuJoCo.

A run folder holds ``model.xml`` (the MJCF of the simulated model) and ``trajectory.npz``
(arrays ``time`` (T,) [s] and ``qpos`` (T, nq)). :func:`render_run_video` replays it at the
video rate (nearest recorded sample, so free-joint quaternions stay normalised), with a camera
tracking the ``thorax`` body, and writes ``video.mp4`` (H.264, yuv420p, frames streamed to
ffmpeg), ``video.gif`` (downscaled preview, about 10 frames/s) and ``first-frame.png``
(:mod:`pneumaquad.robot.video_output`, whose names this module re-exports).
:func:`render_states` renders joint positions as they come, for a run rendered while it goes
(:mod:`pneumaquad.robot.video_worker`).

Quality (:data:`VIDEO_QUALITIES`): ``"fast"`` renders without shadows, reflections and
multisampling and with capsules and spheres of at most 16 × 8 facets; ``"full"`` keeps the
model's own visual settings (for the robot: shadows from a 4096 px map, reflections, 4×
multisampling). On software OpenGL (llvmpipe, 2 cores) a 640 × 480 frame of the quadruped
takes about 10 ms fast and 90 ms full (13 and 155 ms of CPU; ``benchmarks/video_cost.py``,
docs/benchmarks.md).

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
import os
import subprocess
import sys
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pneumaquad.io.run_folder import MODEL_NAME, TRAJECTORY_NAME

from .video_output import (
    FIRST_FRAME_NAME,
    GIF_FPS,
    GIF_MAX_FRAMES,
    GIF_MAX_WIDTH,
    GIF_NAME,
    MP4_NAME,
    FrameProgress,
    FrameSampler,
    GifPreview,
    VideoError,
    VideoFiles,
    nearest_samples,
    video_frame_count,
    write_first_frame_png,
    write_gif_preview,
    write_video,
    write_video_files,
)

if TYPE_CHECKING:
    import mujoco

__all__ = ["DEFAULT_VIDEO_QUALITY", "FIRST_FRAME_NAME", "GIF_FPS", "GIF_MAX_FRAMES",
           "GIF_MAX_WIDTH", "GIF_NAME", "MP4_NAME", "RENDER_STYLES", "VIDEO_QUALITIES",
           "FrameProgress", "FrameSampler", "GifPreview", "MissingRunFileError",
           "RenderStyle", "RenderingUnavailableError", "VideoError", "VideoFiles",
           "create_renderer", "load_model", "nearest_samples", "render_first_frame",
           "render_frames", "render_run_video", "render_states", "render_style",
           "select_gl_backend", "video_frame_count", "write_first_frame_png",
           "write_gif_preview", "write_video", "write_video_files"]

#: Rendering qualities, cheapest first (module docstring).
VIDEO_QUALITIES = ("fast", "full")
#: The quality the commands and functions render with unless told otherwise.
DEFAULT_VIDEO_QUALITY = "fast"
_BACKENDS = ("egl", "osmesa")
_SYSTEM_PACKAGES = {"egl": "libegl1 libgl1-mesa-dri libgbm1", "osmesa": "libosmesa6"}
_PROBE_SCRIPT = """
import mujoco
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
renderer = mujoco.Renderer(model, height=8, width=8)
renderer.render()
renderer.close()
"""


class MissingRunFileError(VideoError, FileNotFoundError):
    """A file a run video needs is missing from the run folder."""


class RenderingUnavailableError(RuntimeError):
    """No working offscreen OpenGL backend is available to MuJoCo."""


@dataclass(frozen=True)
class RenderStyle:
    """What a rendering quality changes from the model's visual settings.

    Attributes
    ----------
    shadows, reflections : bool
        Scene flags ``mjRND_SHADOW`` and ``mjRND_REFLECTION``.
    multisamples : int or None
        Samples per pixel of the offscreen buffer (``visual/quality/offsamples``); ``None``
        keeps the model's.
    facets : tuple of int or None
        Most slices and stacks of capsules, spheres and cylinders (``numslices``,
        ``numstacks``); ``None`` keeps the model's.
    """

    shadows: bool
    reflections: bool
    multisamples: int | None
    facets: tuple[int, int] | None


#: The style of each of :data:`VIDEO_QUALITIES`.
RENDER_STYLES = {
    "fast": RenderStyle(shadows=False, reflections=False, multisamples=0, facets=(16, 8)),
    "full": RenderStyle(shadows=True, reflections=True, multisamples=None, facets=None),
}


def render_style(quality: str) -> RenderStyle:
    """The :class:`RenderStyle` of ``quality`` (one of :data:`VIDEO_QUALITIES`).

    Raises
    ------
    VideoError
        For an unknown quality.
    """
    if quality not in RENDER_STYLES:
        raise VideoError(f"video quality {quality!r}: expected one of {', '.join(RENDER_STYLES)}")
    return RENDER_STYLES[quality]


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


@contextlib.contextmanager
def _visual_settings(model: mujoco.MjModel, style: RenderStyle) -> Iterator[None]:
    """The style's multisampling and facets in ``model`` while a rendering context is made
    (they take effect then); the model's own values are restored afterwards."""
    quality = model.vis.quality
    saved = (quality.offsamples, quality.numslices, quality.numstacks)
    if style.multisamples is not None:
        quality.offsamples = style.multisamples
    if style.facets is not None:
        quality.numslices = min(quality.numslices, style.facets[0])
        quality.numstacks = min(quality.numstacks, style.facets[1])
    try:
        yield
    finally:
        quality.offsamples, quality.numslices, quality.numstacks = saved


def create_renderer(
    model: mujoco.MjModel, width: int, height: int, quality: str = DEFAULT_VIDEO_QUALITY
) -> mujoco.Renderer:
    """An offscreen renderer of ``width`` × ``height`` [px] drawing in ``quality``.

    The OpenGL backend is chosen first (:func:`select_gl_backend`). The model's offscreen
    buffer (``model.vis.global_.offwidth/offheight``) is enlarged if smaller than the frame;
    its other visual settings are left as they were. The scene flags of the style
    (:data:`RENDER_STYLES`) are set on ``renderer.scene``.

    Raises
    ------
    VideoError
        For an unknown quality.
    RenderingUnavailableError
        If no OpenGL context can be created.
    """
    import mujoco

    style = render_style(quality)
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    backend = select_gl_backend()
    try:
        with _context_class_bound(backend), _visual_settings(model, style):
            renderer = mujoco.Renderer(model, height=height, width=width)
    except RenderingUnavailableError:
        raise
    except Exception as error:
        message = f"cannot create a MuJoCo renderer with MUJOCO_GL={backend}: {error}"
        raise RenderingUnavailableError(message) from error
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = style.shadows
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = style.reflections
    return renderer


def _tracking_camera(
    model: mujoco.MjModel, tracking_body: str, distance: float | None, azimuth: float,
    elevation: float,
) -> mujoco.MjvCamera:
    import mujoco

    camera = mujoco.MjvCamera()
    body_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, tracking_body)
    if body_id >= 0:
        camera.type, camera.trackbodyid = mujoco.mjtCamera.mjCAMERA_TRACKING, body_id
    else:
        camera.type, camera.lookat[:] = mujoco.mjtCamera.mjCAMERA_FREE, model.stat.center
    camera.distance = 1.5 * model.stat.extent if distance is None else distance
    camera.azimuth, camera.elevation = azimuth, elevation
    return camera


def render_states(
    model: mujoco.MjModel,
    states: Iterable[np.ndarray],
    *,
    width: int = 640,
    height: int = 480,
    quality: str = DEFAULT_VIDEO_QUALITY,
    tracking_body: str = "thorax",
    distance: float | None = None,
    azimuth: float = 135.0,
    elevation: float = -20.0,
) -> Iterator[np.ndarray]:
    """Render one RGB ``uint8`` frame (height, width, 3) per joint-position vector (nq,).

    ``states`` may be a generator (frames of a run rendered as it goes). The renderer
    (:func:`create_renderer`) is made at the first frame and closed with the iterator; the
    other parameters are those of :func:`render_frames`.
    """
    import mujoco

    render_style(quality)
    camera = _tracking_camera(model, tracking_body, distance, azimuth, elevation)
    renderer = create_renderer(model, width, height, quality)
    data = mujoco.MjData(model)
    try:
        for state in states:
            data.qpos[:] = state
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=camera)
            yield renderer.render()
    finally:
        renderer.close()


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
    quality: str = DEFAULT_VIDEO_QUALITY,
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
    quality
        One of :data:`VIDEO_QUALITIES` (module docstring).

    Returns
    -------
    Iterator[numpy.ndarray]
        Lazily rendered RGB ``uint8`` frames (height, width, 3). The renderer is created at the
        first frame and closed when the iterator is exhausted or closed.

    Raises
    ------
    VideoError
        At the call, if the arrays do not match the model or the quality is unknown.
    RenderingUnavailableError
        At the first frame, if no OpenGL context can be created.
    """
    times, qpos = np.asarray(times, dtype=float), np.asarray(qpos, dtype=float)
    if times.ndim != 1 or len(times) == 0:
        raise VideoError(f"time must be a non-empty 1-D array, got shape {times.shape}")
    if qpos.shape != (len(times), model.nq):
        raise VideoError(f"qpos must have shape ({len(times)}, {model.nq}), got {qpos.shape}")
    if not np.all(np.isfinite(times)) or np.any(np.diff(times) < 0):
        raise VideoError("time must be finite and non-decreasing")
    if not fps > 0:
        raise VideoError(f"fps must be positive, got {fps}")
    render_style(quality)
    frame_count = video_frame_count(times[-1] - times[0], fps)
    samples = nearest_samples(times, times[0] + np.arange(frame_count) / fps)
    return render_states(model, qpos[samples], width=width, height=height, quality=quality,
                         tracking_body=tracking_body, distance=distance, azimuth=azimuth,
                         elevation=elevation)


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
    return load_model(model_path), times, qpos


def load_model(source: Path | str) -> mujoco.MjModel:
    """A MuJoCo model from an MJCF file (a :class:`~pathlib.Path`) or MJCF text (a ``str``),
    with the GL backend chosen before the process's first ``import mujoco`` if possible.

    Raises
    ------
    VideoError
        If MuJoCo cannot load it.
    RenderingUnavailableError
        If no backend works or ``mujoco`` cannot be imported with it.
    """
    backend = select_gl_backend()  # before the first `import mujoco` of the process, if possible
    try:
        import mujoco
    except Exception as error:  # a broken MUJOCO_GL makes the import itself fail
        message = f"importing mujoco with MUJOCO_GL={backend} failed: {error!r}"
        raise RenderingUnavailableError(message) from error
    try:
        if isinstance(source, Path):
            return mujoco.MjModel.from_xml_path(str(source))
        return mujoco.MjModel.from_xml_string(source)
    except ValueError as error:
        where = source if isinstance(source, Path) else "the model's MJCF"
        raise VideoError(f"cannot load {where}: {error}") from error


def render_first_frame(
    run_folder: Path, *, width: int = 640, height: int = 480,
    quality: str = DEFAULT_VIDEO_QUALITY,
) -> Path:
    """Write only ``first-frame.png`` of a run folder (one rendered frame); returns its path.

    Raises the same errors as :func:`render_run_video`.
    """
    render_style(quality)
    model, times, qpos = _load_run(Path(run_folder))
    frames = render_frames(model, times[:1], qpos[:1], fps=1.0, width=width, height=height,
                           quality=quality)
    frame = next(iter(frames))
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
    quality: str = DEFAULT_VIDEO_QUALITY,
    progress: FrameProgress | None = None,
    stop: Callable[[], bool] = lambda: False,
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
    quality
        One of :data:`VIDEO_QUALITIES` (module docstring).
    progress
        Called after each frame with (frames written, frames in the video).
    stop
        Asked after each frame; once true, the files are closed with the frames written so
        far (at least the first), as by :func:`write_video_files`.

    Returns
    -------
    VideoFiles
        Paths of the written files. One rendering pass feeds all three.

    Raises
    ------
    MissingRunFileError
        If ``model.xml`` or ``trajectory.npz`` is missing (a ``FileNotFoundError`` naming it).
    VideoError
        If the trajectory is malformed, the model cannot be loaded or the quality is unknown.
    RenderingUnavailableError
        If no offscreen OpenGL backend works.
    """
    render_style(quality)
    model, times, qpos = _load_run(Path(run_folder), max_seconds)
    frames = render_frames(model, times, qpos, fps=fps, width=width, height=height,
                           quality=quality)
    folder = Path(run_folder) if output is None else Path(output)
    folder.mkdir(parents=True, exist_ok=True)
    duration = float(times[-1] - times[0])
    preview = GifPreview(fps, duration) if gif else None
    total = video_frame_count(duration, fps)
    return write_video_files(frames, folder, fps, preview, progress=progress,
                             frame_total=lambda: total, stop=stop)
