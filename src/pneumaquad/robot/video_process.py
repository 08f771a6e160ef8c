"""The video worker process: what ``python -m pneumaquad.robot.video_process`` runs.

Its parent's side, the protocol and the stopping rules are in
:mod:`pneumaquad.robot.video_worker`. A reader thread takes the parent's messages as they
come (:class:`_Inbox`); the main thread renders each frame as soon as the samples decide it
into a folder of its own, closes the files (also when stopped early) and moves them into
the run folder once they are whole; progress and the result go back as JSON lines.
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
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .video import (
    DEFAULT_VIDEO_QUALITY,
    FrameSampler,
    GifPreview,
    RenderingUnavailableError,
    VideoError,
    VideoFiles,
    load_model,
    render_first_frame,
    render_run_video,
    render_states,
    select_gl_backend,
    video_frame_count,
    write_video_files,
)
from .video_worker import WORKER_NICENESS, RenderedVideo, VideoSettings


class _CancelledError(Exception):
    """The parent closed the input before ``finish``."""


class _Inbox:
    """Messages from the parent, read by a thread as they come so the pipe never fills.

    The end of the input before a ``finish`` message cancels at once, whatever is queued; a
    ``stop`` message sets :attr:`stopped` at once instead of being queued.
    """

    def __init__(self, stream) -> None:
        self._stream = stream
        self._messages: queue.Queue[tuple[str, Any]] = queue.Queue()
        self._cancelled = threading.Event()
        self.stopped = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        finished = False
        try:
            while line := self._stream.readline():
                header = json.loads(line)
                payload = self._stream.read(header["bytes"]) if header["bytes"] else b""
                if len(payload) < header["bytes"]:
                    break
                if header["kind"] == "stop":
                    self.stopped.set()
                    continue
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


class _Progress:
    """The worker's progress answers, at most every 0.2 s (and at the last frame); keeps the
    frames written and the latest total (0 while unknown)."""

    def __init__(self, answer: Callable[..., None]) -> None:
        self._answer, self._sent_at = answer, 0.0
        self.frames = self.total = 0

    def __call__(self, done: int, total: int) -> None:
        self.frames, self.total = done, total
        now = time.monotonic()
        if done == total or now - self._sent_at >= 0.2:
            self._answer(progress=[done, total])
            self._sent_at = now


def _move_files(files: VideoFiles, folder: Path) -> dict[str, Path | None]:
    """Move the closed files into ``folder``, each under a hidden name first and then renamed,
    so that ``folder`` never holds part of a file. SIGTERM (:meth:`VideoWorker.cancel`) is
    blocked from here on: files moved are files the parent is told of."""
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
    folder.mkdir(parents=True, exist_ok=True)
    moved: dict[str, Path | None] = {}
    for key, path in (("mp4", files.mp4), ("gif", files.gif),
                      ("first_frame", files.first_frame)):
        if path is None:
            moved[key] = None
            continue
        part, target = folder / f".{path.name}.part", folder / path.name
        try:
            shutil.move(path, part)
            os.replace(part, target)
        finally:
            part.unlink(missing_ok=True)
        moved[key] = target
    return moved


def _render_stream(model, first: np.ndarray, inbox: _Inbox, settings: VideoSettings,
                   progress: _Progress) -> RenderedVideo:
    """Render the samples as they come into a staging folder; move the files at ``finish``.

    Once stopped, the samples still queued are only read (for the number of frames due) up
    to ``finish``.
    """
    sampler = FrameSampler(settings.fps)
    finish: dict[str, Any] = {}
    latest = float(first[-1, 0])  # time of the latest sample received [s]

    def states(rows: np.ndarray) -> Iterator[np.ndarray]:
        nonlocal latest
        while True:
            if rows.shape[1] != model.nq + 1:
                raise VideoError(f"samples of {rows.shape[1] - 1} joint positions for a model "
                                 f"with nq = {model.nq}")
            latest = float(rows[-1, 0])
            yield from sampler.add(rows[:, 0], rows[:, 1:])
            rows = _next_samples(inbox, finish)
            if rows is None:
                yield from sampler.finish()
                return

    staging = Path(tempfile.mkdtemp(prefix="pneumaquad-video-"))
    try:
        frames = render_states(model, states(first), width=settings.width,
                               height=settings.height, quality=settings.quality)
        preview = GifPreview(settings.fps) if settings.gif else None
        files = write_video_files(
            frames, staging, settings.fps, preview, progress=progress,
            frame_total=lambda: sampler.frames if sampler.finished else 0,
            duration=lambda: sampler.duration, stop=inbox.stopped.is_set)
        while not finish:  # stopped: the rest of the run is not rendered
            rows = _next_samples(inbox, finish)
            latest = latest if rows is None else float(rows[-1, 0])
        moved = _move_files(files, Path(finish["folder"]))
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    due = (sampler.frames if sampler.finished
           else video_frame_count(latest - float(first[0, 0]), settings.fps))
    return RenderedVideo(moved["mp4"], moved["gif"], moved["first_frame"], progress.frames,
                         due)


def _next_samples(inbox: _Inbox, finish: dict[str, Any]) -> np.ndarray | None:
    """The next samples from ``inbox``; None at ``finish``, whose content goes to ``finish``."""
    kind, content = inbox.get()
    while kind == "model":
        kind, content = inbox.get()
    if kind == "finish":
        finish.update(content)
        return None
    return content


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
        return RenderedVideo(None, None, path, 1, 1)
    staging = Path(tempfile.mkdtemp(prefix="pneumaquad-video-"))
    try:
        files = render_run_video(folder, output=staging, fps=settings.fps,
                                 width=settings.width, height=settings.height,
                                 gif=settings.gif, quality=settings.quality,
                                 progress=progress, stop=inbox.stopped.is_set)
        moved = _move_files(files, folder)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return RenderedVideo(moved["mp4"], moved["gif"], moved["first_frame"], progress.frames,
                         progress.total)


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
           frames=video.frames, due=video.due)
    return 0


if __name__ == "__main__":
    status = main()
    sys.stderr.flush()
    os._exit(status)  # without waiting for the reader thread, which may still be reading
