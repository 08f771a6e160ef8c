"""What a run video is made of, without OpenGL: the sample each frame shows, and the files.

:func:`nearest_samples` and :class:`FrameSampler` choose the recorded sample each video frame
shows (frame ``k`` at ``t0 + k / fps`` shows the nearest sample, the earlier one on a tie), on
a whole trajectory or while the samples of a run arrive. :func:`write_video_files` writes
``video.mp4`` (H.264, yuv420p, x264 preset ``veryfast``, frames streamed to ffmpeg),
``first-frame.png`` and, through :class:`GifPreview`, ``video.gif`` (at most
:data:`GIF_MAX_WIDTH` px wide, about 10 frames per second of run, a time lapse of at most about
:data:`GIF_MAX_FRAMES` frames for runs longer than 30 s) from one pass over the frames.
:mod:`pneumaquad.robot.video` renders the frames.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import imageio.v2 as imageio_v2
import imageio.v3 as imageio_v3
import numpy as np
from PIL import Image

__all__ = ["FIRST_FRAME_NAME", "GIF_FPS", "GIF_MAX_FRAMES", "GIF_MAX_WIDTH", "GIF_NAME",
           "MP4_NAME", "FrameProgress", "FrameSampler", "GifPreview", "VideoError",
           "VideoFiles", "nearest_samples", "video_frame_count", "write_first_frame_png",
           "write_gif_preview", "write_video", "write_video_files"]

MP4_NAME, GIF_NAME, FIRST_FRAME_NAME = "video.mp4", "video.gif", "first-frame.png"
GIF_FPS, GIF_MAX_WIDTH = 10.0, 320
GIF_MAX_FRAMES = 300  # a 320 px preview of about 10 MB at most
# x264's "veryfast" preset encodes a 640 x 480 frame in about 2 ms instead of 5 ms ("medium").
_FFMPEG_OPTIONS = dict(codec="libx264", pixelformat="yuv420p", macro_block_size=1,
                       output_params=["-preset", "veryfast"])

#: Called with (frames written, frames in the video; 0 while not yet known).
FrameProgress = Callable[[int, int], None]


class VideoError(ValueError):
    """Invalid input for rendering a run video."""


@dataclass(frozen=True)
class VideoFiles:
    """Files written by :func:`render_run_video` (``gif`` is ``None`` if not requested)."""

    mp4: Path
    gif: Path | None
    first_frame: Path


def nearest_samples(times: np.ndarray, frame_times: np.ndarray) -> np.ndarray:
    """Index of the recorded sample (times (T,) [s], non-decreasing) nearest to each frame
    time [s]; the earlier one on a tie."""
    upper = np.clip(np.searchsorted(times, frame_times), 1, max(len(times) - 1, 1))
    lower = upper - 1
    upper = np.minimum(upper, len(times) - 1)
    return np.where(frame_times - times[lower] <= times[upper] - frame_times, lower, upper)


def video_frame_count(duration: float, fps: float) -> int:
    """Frames of a video of a run lasting ``duration`` [s]: one at 0, 1/fps, ... ≤ duration."""
    return math.floor(duration * fps + 1e-9) + 1


class FrameSampler:
    """The recorded sample each video frame shows, chosen while the samples arrive.

    Frame ``k`` shows the sample nearest to ``t0 + k / fps`` (the earlier one on a tie), as
    :func:`~pneumaquad.robot.video.render_frames` chooses on a whole trajectory; a frame is
    decided as soon as a sample at or after its time has arrived, and only the latest sample
    is kept.

    Parameters
    ----------
    fps
        Video frame rate [1/s].
    """

    def __init__(self, fps: float) -> None:
        if not fps > 0:
            raise VideoError(f"fps must be positive, got {fps}")
        self.fps = fps
        self.frames = 0  # frames decided so far
        self._start: float | None = None
        self._last: tuple[float, np.ndarray] | None = None
        self.finished = False

    @property
    def duration(self) -> float:
        """Time from the first to the latest sample [s] (0 before any)."""
        return 0.0 if self._last is None else self._last[0] - self._start

    def add(self, times: np.ndarray, qpos: np.ndarray) -> list[np.ndarray]:
        """Take samples (times (n,) [s], non-decreasing, and qpos (n, nq)); return the qpos of
        each frame now decided, in order.

        Raises
        ------
        VideoError
            For times that are not finite or go back, or mismatched shapes.
        """
        times, qpos = np.asarray(times, dtype=float), np.asarray(qpos, dtype=float)
        if times.ndim != 1 or qpos.ndim != 2 or len(qpos) != len(times):
            raise VideoError(f"samples: {times.shape} times for qpos of shape {qpos.shape}")
        previous = -np.inf if self._last is None else self._last[0]
        if not np.all(np.isfinite(times)) or np.any(np.diff(times, prepend=previous) < 0):
            raise VideoError("time must be finite and non-decreasing")
        rows = []
        for time, row in zip(times.tolist(), qpos, strict=True):
            if self._start is None:
                self._start = time
            while (frame_time := self._start + self.frames / self.fps) <= time:
                earlier = self._last
                if earlier is not None and frame_time - earlier[0] <= time - frame_time:
                    rows.append(earlier[1])
                else:
                    rows.append(row)
                self.frames += 1
            self._last = (time, row.copy())
        return rows

    def finish(self) -> list[np.ndarray]:
        """End of the samples: the qpos of the frames still due (the latest sample's)."""
        self.finished = True
        if self._last is None:
            return []
        due = video_frame_count(self.duration, self.fps) - self.frames
        self.frames += max(due, 0)
        return [self._last[1]] * max(due, 0)


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
    """At most ``max_width`` wide: a box average by a whole factor, then bilinear if need be."""
    height, width = frame.shape[:2]
    if width <= max_width:
        return frame
    image = Image.fromarray(frame)
    if width // max_width >= 2:
        image = image.reduce(width // max_width)
    if image.width > max_width:
        size = (max_width, max(1, round(height * max_width / width)))
        image = image.resize(size, Image.Resampling.BILINEAR)
    return np.asarray(image)


class GifPreview:
    """The frames of the GIF preview, kept while the video is written.

    Every ``step``-th frame (:func:`_gif_step`) is downscaled to ``max_width`` and reduced to
    a palette of its own colours. Given the run's ``duration`` [s], the step is final from the
    start; without it (a run rendered as it goes) the step doubles whenever more than twice
    :data:`GIF_MAX_FRAMES` frames are kept, and :meth:`save` thins them to the step of the
    duration it is then given.
    """

    def __init__(self, fps: float, duration: float | None = None,
                 max_width: int = GIF_MAX_WIDTH) -> None:
        self.fps, self.max_width, self.duration = fps, max_width, duration
        self.step = _gif_step(fps, duration)
        self._kept: list[Image.Image] = []

    def add(self, index: int, frame: np.ndarray) -> None:
        """Offer frame number ``index`` (0, 1, 2, ... in order) of the video."""
        if index % self.step:
            return
        image = Image.fromarray(np.ascontiguousarray(_downscale(frame, self.max_width)))
        self._kept.append(image.quantize(colors=256, method=Image.Quantize.FASTOCTREE))
        if self.duration is None and len(self._kept) > 2 * GIF_MAX_FRAMES:
            self.step, self._kept = 2 * self.step, self._kept[::2]

    def save(self, path: Path, duration: float | None = None) -> Path:
        """Write the looping GIF (real time, or a time lapse for long runs); returns ``path``.

        ``duration`` [s] is the run's, when not given at construction.
        """
        wanted = _gif_step(self.fps, self.duration if duration is None else duration)
        kept, step = self._kept, max(wanted, self.step)
        if step % self.step == 0:
            kept = kept[:: step // self.step]
        elif kept:
            count = math.ceil(len(kept) * self.step / step)
            kept = [kept[min(round(j * step / self.step), len(kept) - 1)] for j in range(count)]
        return _save_gif(kept, Path(path), 1000.0 * step / self.fps)


def _save_gif(images: list[Image.Image], path: Path, frame_duration_ms: float) -> Path:
    if not images:
        raise VideoError(f"no frames to write to {path}")
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:],
                   duration=frame_duration_ms, loop=0)
    return path


def write_gif_preview(
    frames: Iterable[np.ndarray], path: Path, fps: float, max_width: int = GIF_MAX_WIDTH
) -> Path:
    """Write a looping GIF of every ``round(fps / 10)``-th frame, at most ``max_width`` wide.

    It plays in real time at about 10 frames/s; only the kept, downscaled frames are held in
    memory. Returns ``path``.
    """
    preview = GifPreview(fps, duration=0.0, max_width=max_width)  # real time at any length
    for index, frame in enumerate(frames):
        preview.add(index, frame)
    return preview.save(Path(path))


def write_first_frame_png(frame: np.ndarray, path: Path) -> Path:
    """Write one RGB ``uint8`` frame (height, width, 3) to ``path`` as a PNG and return it."""
    path = Path(path)
    imageio_v3.imwrite(path, frame, extension=".png")
    return path


def write_video_files(
    frames: Iterable[np.ndarray],
    folder: Path,
    fps: float,
    preview: GifPreview | None,
    *,
    progress: FrameProgress | None = None,
    frame_total: Callable[[], int] = lambda: 0,
    duration: Callable[[], float | None] = lambda: None,
    stop: Callable[[], bool] = lambda: False,
) -> VideoFiles:
    """Write ``video.mp4``, ``first-frame.png`` and (with a ``preview``) ``video.gif`` into
    ``folder`` from one pass over ``frames``.

    ``progress`` is called after each frame with the frames written and ``frame_total()``
    (0 while unknown); ``duration()`` [s] is read once the frames are exhausted, for a preview
    made without it. ``stop()`` is asked after each frame: once it is true no further frame
    is taken (``frames`` is closed) and the files hold the frames written so far, at least
    the first (the preview then lasts as long as they do).
    """
    folder = Path(folder)
    gif_path = folder / GIF_NAME if preview is not None else None
    files = VideoFiles(folder / MP4_NAME, gif_path, folder / FIRST_FRAME_NAME)
    written, cut = 0, False

    def tap(frames: Iterable[np.ndarray]) -> Iterator[np.ndarray]:
        nonlocal written, cut
        for index, frame in enumerate(frames):
            if index == 0:
                write_first_frame_png(frame, files.first_frame)
            if preview is not None:
                preview.add(index, frame)
            yield frame
            written = index + 1
            if progress is not None:
                progress(written, frame_total())
            if stop():
                cut = True
                return

    frames = iter(frames)
    try:
        write_video(tap(frames), files.mp4, fps)
    finally:
        close = getattr(frames, "close", None)
        if close is not None:
            close()  # a generator stopped early releases its renderer now
    if preview is not None and files.gif is not None:
        preview.save(files.gif, (written - 1) / fps if cut else duration())
    return files
