"""A run's video rendered in a separate process, while the run goes or after it.

:class:`VideoWorker` starts ``python -m pneumaquad.robot.video_worker``, which chooses its own
OpenGL backend (:func:`~pneumaquad.robot.video.select_gl_backend`), imports MuJoCo and waits,
all on the other core while the command builds the robot and plans. It is given the model's
MJCF (:meth:`VideoWorker.send_model`) and, while the run goes, each recorded sample
(:meth:`VideoWorker.add_sample`, the ``on_sample`` hook of a run); it renders each frame as
soon as the samples decide it (:class:`~pneumaquad.robot.video_output.FrameSampler`) into a
folder of its own. :meth:`VideoWorker.finish` names the run folder once the run has ended: the
worker renders the frames still due and moves ``video.mp4``, ``video.gif`` and
``first-frame.png`` there. Given no samples, it renders the run folder's ``trajectory.npz``
instead (:func:`~pneumaquad.robot.video.render_run_video`), or only ``first-frame.png``.
:meth:`VideoWorker.wait` follows its progress and returns the files.

The worker ignores Ctrl-C (the command decides: an interrupted run's video is finished, Ctrl-C
while waiting cancels it) and runs at a lower priority (nice 10), so the run keeps its core.

Protocol: the parent writes messages to the worker's standard input, each a JSON line then as
many bytes as its ``"bytes"`` says: ``model`` (MJCF text, UTF-8), ``samples`` (``count`` rows
of ``width`` little-endian float64: the time [s], then qpos) and ``finish`` (``folder``,
``first_frame_only``). The writes never block the run: what the pipe does not take is kept and
sent later. The end of the input before ``finish`` cancels the video. The worker answers on its
standard output with JSON lines: ``{"progress": [done, total]}`` (total 0 while unknown), then
``{"files": {...}, "frames": n}`` or ``{"error": class name, "message": text}``; anything else
it prints goes to its standard error, which the parent keeps in a temporary file.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .video import (
    DEFAULT_VIDEO_QUALITY,
    FrameProgress,
    FrameSampler,
    GifPreview,
    MissingRunFileError,
    RenderingUnavailableError,
    VideoError,
    load_model,
    render_first_frame,
    render_run_video,
    render_states,
    render_style,
    select_gl_backend,
    video_frame_count,
    write_video_files,
)

__all__ = ["RenderedVideo", "VideoSettings", "VideoWorker", "VideoWorkerError", "main",
           "worker_command"]

#: Samples sent to the worker in one message (0.1 s of a run recorded at 100 Hz).
SAMPLES_PER_MESSAGE = 10
#: Niceness the worker adds to its own, so that the simulation keeps its core.
WORKER_NICENESS = 10
_ERRORS: dict[str, type[Exception]] = {
    error.__name__: error for error in (RenderingUnavailableError, MissingRunFileError, VideoError)
}


class VideoWorkerError(RuntimeError):
    """The video worker process failed, or was cancelled."""


@dataclass(frozen=True)
class VideoSettings:
    """How the worker renders: frame rate [1/s], frame size [px], quality
    (:data:`~pneumaquad.robot.video.VIDEO_QUALITIES`), and whether to write the GIF."""

    fps: float = 30.0
    width: int = 640
    height: int = 480
    quality: str = DEFAULT_VIDEO_QUALITY
    gif: bool = True

    def check(self) -> None:
        """Raise :class:`~pneumaquad.robot.video.VideoError` for settings no video can have."""
        render_style(self.quality)
        if not (self.fps > 0 and np.isfinite(self.fps)) or min(self.width, self.height) < 1:
            raise VideoError(f"video of {self.width} x {self.height} px at {self.fps} frames/s")


@dataclass(frozen=True)
class RenderedVideo:
    """Files the worker wrote (``mp4`` and ``gif`` are ``None`` when it was not asked for
    them) and the number of video frames."""

    mp4: Path | None
    gif: Path | None
    first_frame: Path
    frames: int


def worker_command(settings: VideoSettings) -> list[str]:
    """The command line of a worker process rendering with ``settings``."""
    command = [sys.executable, "-m", __name__, "--fps", repr(float(settings.fps)),
               "--width", str(settings.width), "--height", str(settings.height),
               "--quality", settings.quality]
    return command if settings.gif else [*command, "--no-gif"]


class VideoWorker:
    """The parent's handle on a video worker process (module docstring).

    The process starts at construction. A worker left without :meth:`wait` is cancelled at
    the end of a ``with`` block.

    Raises
    ------
    VideoError
        For invalid ``settings``, before anything starts.
    """

    def __init__(self, settings: VideoSettings | None = None) -> None:
        self.settings = settings or VideoSettings()
        self.settings.check()
        self.samples = 0
        self._first_time = self._latest_time = 0.0  # of the samples [s]
        self._batch: list[np.ndarray] = []
        self._unsent = bytearray()
        self._finished = False
        self._progress = (0, 0)
        self._answer: dict[str, Any] | None = None
        self._errors = tempfile.TemporaryFile()  # noqa: SIM115 - closed by wait() or cancel()
        try:
            self._process = subprocess.Popen(
                worker_command(self.settings), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                stderr=self._errors, start_new_session=True)  # the terminal's Ctrl-C skips it
        except BaseException:
            self._errors.close()
            raise
        os.set_blocking(self._process.stdin.fileno(), False)
        self._reader = threading.Thread(target=self._read_answers, daemon=True)
        self._reader.start()

    def __enter__(self) -> VideoWorker:
        return self

    def __exit__(self, *exception: object) -> None:
        self.cancel()

    @property
    def running(self) -> bool:
        """Whether the process has not ended yet."""
        return self._process.poll() is None

    def send_model(self, mjcf: str) -> None:
        """The MJCF text of the model the run's samples belong to (before the first sample)."""
        self._send({"kind": "model"}, mjcf.encode("utf-8"))

    def add_sample(self, time: float, qpos: np.ndarray) -> None:
        """One recorded sample of the run: simulated time [s] and joint positions (nq,).

        Copies ``qpos``; never blocks and never raises for a worker that has ended (its
        failure is reported by :meth:`wait`).
        """
        self._batch.append(np.concatenate(([time], np.asarray(qpos, dtype=float).ravel())))
        if not self.samples:
            self._first_time = float(time)
        self._latest_time = float(time)
        self.samples += 1
        if len(self._batch) >= SAMPLES_PER_MESSAGE:
            self._send_batch()

    def finish(self, run_folder: Path, *, first_frame_only: bool = False) -> None:
        """The run has ended and its folder is complete: write the files into ``run_folder``.

        Without samples the worker renders ``trajectory.npz`` and ``model.xml`` of the folder
        (``first_frame_only``: only ``first-frame.png``).
        """
        self._send_batch()
        self._finished = True
        self._send({"kind": "finish", "folder": str(Path(run_folder).resolve()),
                    "first_frame_only": first_frame_only})

    def wait(self, progress: FrameProgress | None = None, poll: float = 0.1) -> RenderedVideo:
        """Wait for the worker, calling ``progress(done, total)`` every ``poll`` [s].

        Ctrl-C (or any exception) while waiting cancels the worker and is raised again.

        Raises
        ------
        RenderingUnavailableError, MissingRunFileError, VideoError
            As raised in the worker.
        VideoWorkerError
            If the worker ended without an answer (its last line of standard error).
        """
        try:
            while self._reader.is_alive():
                self._flush()
                if progress is not None:
                    progress(*self._frames_done())
                self._reader.join(poll)
            self._process.wait()
        except BaseException:
            self.cancel()
            raise
        self._close_input()
        error_line = self._last_error_line()
        self._errors.close()
        answer = self._answer or {}
        if "files" in answer:
            files = {key: Path(value) if value else None for key, value in answer["files"].items()}
            return RenderedVideo(files["mp4"], files["gif"], files["first_frame"],
                                 answer["frames"])
        if answer.get("error") in _ERRORS:
            raise _ERRORS[answer["error"]](answer["message"])
        if "error" in answer:
            raise VideoWorkerError(f"{answer['error']}: {answer['message']}")
        raise VideoWorkerError(f"the video worker ended with exit status "
                               f"{self._process.returncode}{error_line}")

    def cancel(self) -> None:
        """Stop the worker if it still runs; it removes the video it was writing."""
        if self.running:
            self._close_input()
            self._process.terminate()  # it unwinds, removing its partial files
            try:
                self._process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        self._close_input()
        self._reader.join(5)
        self._errors.close()

    def _frames_done(self) -> tuple[int, int]:
        """(frames rendered, frames of the video): the worker knows the total only at its
        end of a streamed run, but it follows from the times of the samples sent."""
        done, total = self._progress
        if not total and self._finished and self.samples:
            total = video_frame_count(self._latest_time - self._first_time, self.settings.fps)
        return done, total

    def _send_batch(self) -> None:
        if self._batch:
            rows = np.asarray(self._batch, dtype="<f8")
            self._batch.clear()
            self._send({"kind": "samples", "count": rows.shape[0], "width": rows.shape[1]},
                       rows.tobytes())

    def _send(self, header: dict[str, Any], payload: bytes = b"") -> None:
        if self._process.stdin.closed:
            return
        line = json.dumps({**header, "bytes": len(payload)}).encode("utf-8") + b"\n"
        self._unsent += line + payload
        self._flush()

    def _flush(self) -> None:
        """Write what the pipe takes now; the rest waits for the next call."""
        stdin = self._process.stdin
        while self._unsent and not stdin.closed:
            try:
                written = os.write(stdin.fileno(), self._unsent)
            except BlockingIOError:
                return
            except OSError:  # the worker has ended; wait() says why
                self._unsent.clear()
                self._close_input()
                return
            del self._unsent[:written]
        if self._finished and not self._unsent:
            self._close_input()  # all said: the worker's reader ends at the end of its input

    def _close_input(self) -> None:
        with contextlib.suppress(OSError):
            self._process.stdin.close()

    def _read_answers(self) -> None:
        for line in self._process.stdout:
            try:
                answer = json.loads(line)
            except ValueError:
                continue
            if "progress" in answer:
                self._progress = tuple(answer["progress"])
            else:
                self._answer = answer

    def _last_error_line(self) -> str:
        self._errors.seek(0)
        lines = [line.strip() for line in self._errors.read().decode(errors="replace")
                 .splitlines() if line.strip()]
        return f": {lines[-1]}" if lines else ""


# --- the worker process ------------------------------------------------------------------


class _CancelledError(Exception):
    """The parent closed the input before ``finish``."""


class _Inbox:
    """Messages from the parent, read by a thread as they come so the pipe never fills.

    The end of the input before a ``finish`` message cancels at once, whatever is queued.
    """

    def __init__(self, stream) -> None:
        self._stream = stream
        self._messages: queue.Queue[tuple[str, Any]] = queue.Queue()
        self._cancelled = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        finished = False
        try:
            while line := self._stream.readline():
                header = json.loads(line)
                payload = self._stream.read(header["bytes"]) if header["bytes"] else b""
                if len(payload) < header["bytes"]:
                    break
                finished = finished or header["kind"] == "finish"
                self._messages.put((header["kind"], self._content(header, payload)))
        except (ValueError, KeyError, OSError):
            traceback.print_exc()
        if not finished:
            self._cancelled.set()

    @staticmethod
    def _content(header: dict[str, Any], payload: bytes) -> Any:
        if header["kind"] == "samples":
            return np.frombuffer(payload, dtype="<f8").reshape(header["count"], header["width"])
        if header["kind"] == "model":
            return payload.decode("utf-8")
        return header

    def get(self) -> tuple[str, Any]:
        """The next message; raises :class:`_CancelledError` once the input ended early."""
        while not self._cancelled.is_set():
            with contextlib.suppress(queue.Empty):
                return self._messages.get(timeout=0.1)
        raise _CancelledError


def _render_stream(model, first: np.ndarray, inbox: _Inbox, settings: VideoSettings,
                   progress: FrameProgress) -> RenderedVideo:
    """Render the samples as they come into a staging folder; move the files at ``finish``."""
    sampler = FrameSampler(settings.fps)
    finish: dict[str, Any] = {}

    def states(rows: np.ndarray) -> Iterator[np.ndarray]:
        while True:
            if rows.shape[1] != model.nq + 1:
                raise VideoError(f"samples of {rows.shape[1] - 1} joint positions for a model "
                                 f"with nq = {model.nq}")
            yield from sampler.add(rows[:, 0], rows[:, 1:])
            kind, content = inbox.get()
            while kind == "model":
                kind, content = inbox.get()
            if kind == "finish":
                finish.update(content)
                yield from sampler.finish()
                return
            rows = content

    staging = Path(tempfile.mkdtemp(prefix="pneumaquad-video-"))
    try:
        frames = render_states(model, states(first), width=settings.width,
                               height=settings.height, quality=settings.quality)
        preview = GifPreview(settings.fps) if settings.gif else None
        files = write_video_files(
            frames, staging, settings.fps, preview, progress=progress,
            frame_total=lambda: sampler.frames if sampler.finished else 0,
            duration=lambda: sampler.duration)
        folder = Path(finish["folder"])
        folder.mkdir(parents=True, exist_ok=True)
        moved = {}
        for key, path in (("mp4", files.mp4), ("gif", files.gif),
                          ("first_frame", files.first_frame)):
            moved[key] = Path(shutil.move(path, folder / path.name)) if path else None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return RenderedVideo(moved["mp4"], moved["gif"], moved["first_frame"], sampler.frames)


def _render(inbox: _Inbox, settings: VideoSettings, progress: _Progress) -> RenderedVideo:
    select_gl_backend()  # in this process, before it imports mujoco
    importlib.import_module("mujoco")  # loaded while the parent is still busy
    model = None
    kind, content = inbox.get()
    while kind == "model":
        model = load_model(content)
        kind, content = inbox.get()
    if kind == "samples":
        if model is None:
            raise VideoError("samples came before the model")
        return _render_stream(model, content, inbox, settings, progress)
    folder = Path(content["folder"])
    if content["first_frame_only"]:
        path = render_first_frame(folder, width=settings.width, height=settings.height,
                                  quality=settings.quality)
        return RenderedVideo(None, None, path, 1)
    files = render_run_video(folder, fps=settings.fps, width=settings.width,
                             height=settings.height, gif=settings.gif,
                             quality=settings.quality, progress=progress)
    return RenderedVideo(files.mp4, files.gif, files.first_frame, progress.frames)


class _Progress:
    """The worker's progress answers, at most every 0.2 s (and at the last frame)."""

    def __init__(self, answer: Callable[..., None]) -> None:
        self._answer, self._sent_at, self.frames = answer, 0.0, 0

    def __call__(self, done: int, total: int) -> None:
        self.frames = done
        now = time.monotonic()
        if done == total or now - self._sent_at >= 0.2:
            self._answer(progress=[done, total])
            self._sent_at = now


def _terminated(signal_number: int, frame: object) -> None:
    raise SystemExit(128 + signal_number)  # unwinds, so partial files are removed


def main(arguments: Sequence[str] | None = None) -> int:
    """The worker process (module docstring); returns its exit status."""
    parser = argparse.ArgumentParser(prog=f"python -m {__name__}")
    parser.add_argument("--fps", type=float, default=30.0)
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--quality", default=DEFAULT_VIDEO_QUALITY)
    parser.add_argument("--no-gif", dest="gif", action="store_false")
    options = parser.parse_args(arguments)
    settings = VideoSettings(options.fps, options.width, options.height, options.quality,
                             options.gif)
    answers = os.fdopen(os.dup(sys.stdout.fileno()), "w", buffering=1, encoding="utf-8")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # stray prints go to standard error
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _terminated)
    with contextlib.suppress(OSError):
        os.nice(WORKER_NICENESS)

    def answer(**message: Any) -> None:
        answers.write(json.dumps(message) + "\n")

    progress = _Progress(answer)
    try:
        settings.check()
        video = _render(_Inbox(sys.stdin.buffer), settings, progress)
    except _CancelledError:
        return 3
    except Exception as error:  # reported to the parent, which keeps the run folder
        if not isinstance(error, RenderingUnavailableError | VideoError):
            traceback.print_exc()
        answer(error=type(error).__name__, message=str(error) or repr(error))
        return 1
    files = {"mp4": video.mp4, "gif": video.gif, "first_frame": video.first_frame}
    answer(files={key: str(path) if path else None for key, path in files.items()},
           frames=video.frames)
    return 0


if __name__ == "__main__":
    status = main()
    sys.stderr.flush()
    os._exit(status)  # without waiting for the reader thread, which may still be reading
