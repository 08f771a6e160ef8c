"""A run's video rendered in a separate process, while the run goes or after it.

:class:`VideoWorker` starts ``python -m pneumaquad.robot.video_process``, which chooses its own
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

Stopping: a run cut short (Ctrl-C, an error) is finished with ``interrupted=True``, and a
Ctrl-C while waiting stops the worker the same way (:meth:`VideoWorker.stop`): it renders no
further frame, closes the files with the frames rendered so far (at least the first; a valid
MP4 and GIF) and moves them into the folder; :class:`RenderedVideo` says how many of the
frames due they hold. A second Ctrl-C while waiting cancels the worker, which then removes
what it was writing. The files are written in a folder of the worker's own and only moved
into the run folder once closed, so the run folder never holds a partial file.

The worker ignores the terminal's Ctrl-C (the command decides) and runs at a lower priority
(nice 10), so the run keeps its core.

Protocol: the parent writes messages to the worker's standard input, each a JSON line then as
many bytes as its ``"bytes"`` says: ``model`` (MJCF text, UTF-8), ``samples`` (``count`` rows
of ``width`` little-endian float64: the time [s], then qpos) and ``finish`` (``folder``,
``first_frame_only``), then possibly ``stop`` (acted on as soon as it is read, ahead of the
samples still queued). The writes never block the run: what the pipe does not take is kept
and sent later. The end of the input before ``finish`` cancels the video. The worker answers
on its standard output with JSON lines: ``{"progress": [done, total]}`` (total 0 while
unknown), then ``{"files": {...}, "frames": n, "due": m}`` or ``{"error": class name,
"message": text}``; anything else it prints goes to its standard error, which the parent
keeps in a temporary file.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .video import (
    DEFAULT_VIDEO_QUALITY,
    FrameProgress,
    MissingRunFileError,
    RenderingUnavailableError,
    VideoError,
    render_style,
    video_frame_count,
)

__all__ = ["RenderedVideo", "VideoSettings", "VideoWorker", "VideoWorkerError",
           "worker_command"]

#: The module a worker process runs (:mod:`pneumaquad.robot.video_process`).
WORKER_MODULE = "pneumaquad.robot.video_process"
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
    them), the number of video frames they hold and the number the whole run calls for
    (more when the worker was stopped)."""

    mp4: Path | None
    gif: Path | None
    first_frame: Path
    frames: int
    due: int

    @property
    def complete(self) -> bool:
        """Whether the video holds every frame of the run."""
        return self.frames >= self.due


def worker_command(settings: VideoSettings) -> list[str]:
    """The command line of a worker process rendering with ``settings``."""
    command = [sys.executable, "-m", WORKER_MODULE, "--fps", repr(float(settings.fps)),
               "--width", str(settings.width), "--height", str(settings.height),
               "--quality", settings.quality]
    return command if settings.gif else [*command, "--no-gif"]


class VideoWorker:
    """The parent's handle on a video worker process (module docstring).

    The process starts at construction. A worker left without :meth:`wait` is cancelled at
    the end of a ``with`` block. ``interrupted`` becomes true when a Ctrl-C reaches
    :meth:`wait`.

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
        self._finished = self._stopped = False
        self.interrupted = False
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

    def finish(self, run_folder: Path, *, first_frame_only: bool = False,
               interrupted: bool = False) -> None:
        """The run has ended and its folder is complete: write the files into ``run_folder``.

        Without samples the worker renders ``trajectory.npz`` and ``model.xml`` of the folder
        (``first_frame_only``: only ``first-frame.png``). ``interrupted``: the run was cut
        short, so the worker is stopped at once (:meth:`stop`).
        """
        self._send_batch()
        self._finished = True
        self._send({"kind": "finish", "folder": str(Path(run_folder).resolve()),
                    "first_frame_only": first_frame_only})
        if interrupted:
            self.stop()

    def stop(self) -> None:
        """After :meth:`finish`: render no further frame, but close the files with the frames
        rendered so far (at least the first) and move them into the run folder."""
        if not self._finished:
            raise RuntimeError("stop() before finish(): the worker has no folder to write to")
        if not self._stopped:
            self._stopped = True
            self._send({"kind": "stop"})

    def wait(self, progress: FrameProgress | None = None, poll: float = 0.1) -> RenderedVideo:
        """Wait for the worker, calling ``progress(done, total)`` every ``poll`` [s].

        The first Ctrl-C while waiting stops the worker (:meth:`stop`; ``interrupted``
        becomes true) and waits on for the files of the frames rendered so far. A Ctrl-C
        after the worker was stopped cancels it (it removes what it was writing) and is
        raised again, unless the worker had already moved its files into the folder: they
        are then returned. Any other exception cancels the worker and is raised again.

        Raises
        ------
        RenderingUnavailableError, MissingRunFileError, VideoError
            As raised in the worker.
        VideoWorkerError
            If the worker ended without an answer (its last line of standard error).
        """
        try:
            self._follow(progress, poll)
        except KeyboardInterrupt:
            self.cancel()
            if "files" not in (self._answer or {}):
                raise
            self.interrupted = True  # too late to cancel: the files are in the folder
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
                                 answer["frames"], answer["due"])
        if answer.get("error") in _ERRORS:
            raise _ERRORS[answer["error"]](answer["message"])
        if "error" in answer:
            raise VideoWorkerError(f"{answer['error']}: {answer['message']}")
        raise VideoWorkerError(f"the video worker ended with exit status "
                               f"{self._process.returncode}{error_line}")

    def _follow(self, progress: FrameProgress | None, poll: float) -> None:
        """Feed and follow the worker until it ends; the first Ctrl-C stops it (:meth:`wait`).

        What the run left unsent goes as fast as the worker reads it, so that a ``stop``
        behind it arrives at once."""
        while self._reader.is_alive():
            try:
                self._flush(poll)
                if progress is not None:
                    progress(*self._frames_done())
                self._reader.join(0.0 if self._unsent else poll)
            except KeyboardInterrupt:
                if self._stopped or not self._finished:
                    raise
                self.interrupted = True
                self.stop()
        self._process.wait()

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
        end of a streamed run, but it follows from the times of the samples sent (not once
        stopped: the video then holds fewer)."""
        done, total = self._progress
        if not total and self._finished and self.samples and not self._stopped:
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

    def _flush(self, timeout: float = 0.0) -> None:
        """Write what the pipe takes within ``timeout`` [s] (0: now, never blocking the run);
        the rest waits for the next call."""
        stdin = self._process.stdin
        deadline = time.monotonic() + timeout
        while self._unsent and not stdin.closed:
            try:
                written = os.write(stdin.fileno(), self._unsent)
            except BlockingIOError:
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                select.select([], [stdin.fileno()], [], left)  # until the worker reads
                continue
            except OSError:  # the worker has ended; wait() says why
                self._unsent.clear()
                self._close_input()
                return
            del self._unsent[:written]

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
        if self._errors.closed:
            return ""
        self._errors.seek(0)
        lines = [line.strip() for line in self._errors.read().decode(errors="replace")
                 .splitlines() if line.strip()]
        return f": {lines[-1]}" if lines else ""
