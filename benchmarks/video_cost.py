"""Cost of one video frame of a robot run, per rendering quality, and of its encoding.

Setup: the run's ``model.xml`` and ``trajectory.npz`` (``--run FOLDER``, e.g. made by
``pneumaquad robot walk --distance 0.3 --no-video -o runs/walk-0.3``), or else the shipped
``crr-quadruped`` on flat ground at its initial pose, carried along x. Frames of 640 x 480
px (``--width``, ``--height``) with the tracking camera of ``pneumaquad.robot.video``, on
the OpenGL backend ``select_gl_backend`` picks (software llvmpipe on a machine without GPU;
``LP_NUM_THREADS`` sets its threads). For each of ``VIDEO_QUALITIES`` it measures, per frame:

* **render**: ``mj_forward``, ``update_scene`` and ``Renderer.render`` (read-back included)
  of ``--frames`` frames spread over the trajectory: wall ms and CPU ms (all threads of this
  process, so llvmpipe's rasteriser threads count);
* **encode**: the frames streamed to ffmpeg (H.264, x264 preset ``veryfast``) by
  ``write_video``: wall ms per frame (ffmpeg is another process, so no CPU figure);
* **GIF**: downscaling and palette reduction of a kept frame (``GifPreview.add``) and the
  GIF written at the end, per frame of the video (every third frame is kept at 30 frames/s).

Every figure is the median and the best of ``--repeats`` repeats, taken in interleaved
rounds after a warm-up. Nothing is asserted.

Run: ``.venv/bin/python benchmarks/video_cost.py [--run FOLDER] [--frames 120] [--repeats 3]
[--json out.json]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from _bench import Stats, machine_line, write_json
from pneumaquad.robot.video import (
    VIDEO_QUALITIES,
    GifPreview,
    create_renderer,
    load_model,
    write_video,
)


def _trajectory(run: Path | None, frames: int):
    """Model and ``frames`` joint-position vectors spread over the run (or a synthetic one)."""
    if run is not None:
        model = load_model(run / "model.xml")
        qpos = np.load(run / "trajectory.npz")["qpos"]
        return model, qpos[np.linspace(0, len(qpos) - 1, frames).round().astype(int)]
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import build_robot

    robot = build_robot(load_robot("crr-quadruped", []), "quadruped", "flat", 0)
    model = load_model(robot.to_xml())
    qpos = np.repeat(model.qpos0[None, :], frames, axis=0)
    qpos[:, 0] += np.linspace(0.0, 0.5, frames)  # the free joint's x: the camera follows
    return model, qpos


def _render(model, states: np.ndarray, quality: str, width: int, height: int):
    """Rendered frames and (wall, CPU) seconds per frame."""
    import mujoco

    from pneumaquad.robot.video import _tracking_camera

    renderer = create_renderer(model, width, height, quality)
    camera = _tracking_camera(model, "thorax", None, 135.0, -20.0)
    data = mujoco.MjData(model)
    frames = []
    try:
        for state in states[:3]:  # warm-up
            data.qpos[:] = state
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=camera)
            renderer.render()
        wall, cpu = time.perf_counter(), time.process_time()
        for state in states:
            data.qpos[:] = state
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=camera)
            frames.append(renderer.render())
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    finally:
        renderer.close()
    return frames, wall / len(states), cpu / len(states)


def _encode(frames: list[np.ndarray], folder: Path) -> tuple[float, float]:
    """Seconds per frame of the MP4 and of the GIF preview (30 frames/s)."""
    start = time.perf_counter()
    write_video(frames, folder / "video.mp4", 30.0)
    mp4 = (time.perf_counter() - start) / len(frames)
    start = time.perf_counter()
    preview = GifPreview(30.0, duration=len(frames) / 30.0)
    for index, frame in enumerate(frames):
        preview.add(index, frame)
    preview.save(folder / "video.gif")
    return mp4, (time.perf_counter() - start) / len(frames)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--run", type=Path, help="robot run folder (model.xml, trajectory.npz)")
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--json", type=Path)
    options = parser.parse_args()
    model, states = _trajectory(options.run, options.frames)
    figures: dict[str, dict[str, list[float]]] = {
        quality: {"render wall": [], "render cpu": [], "encode": [], "gif": []}
        for quality in VIDEO_QUALITIES}
    with tempfile.TemporaryDirectory() as scratch:
        for _ in range(options.repeats):
            for quality in VIDEO_QUALITIES:
                frames, wall, cpu = _render(model, states, quality, options.width,
                                            options.height)
                mp4, gif = _encode(frames, Path(scratch))
                for key, value in (("render wall", wall), ("render cpu", cpu),
                                   ("encode", mp4), ("gif", gif)):
                    figures[quality][key].append(value * 1000.0)
    print(machine_line())
    print(f"OpenGL: MUJOCO_GL={os.environ.get('MUJOCO_GL')}, "
          f"LP_NUM_THREADS={os.environ.get('LP_NUM_THREADS', 'unset')}")
    print(f"{options.frames} frames of {options.width} x {options.height} px, "
          f"{options.repeats} repeats; ms per frame, min / median / max")
    print(f"{'quality':8} {'render wall':>22} {'render CPU':>22} {'encode (wall)':>22} "
          f"{'GIF (wall)':>22}")
    results = {}
    for quality, measured in figures.items():
        stats = {key: Stats(tuple(values)) for key, values in measured.items()}
        print(f"{quality:8} " + " ".join(f"{stats[key].spread(1):>22}" for key in stats))
        results[quality] = {key: value.as_dict() for key, value in stats.items()}
    if options.json:
        write_json(options.json, {"video frame cost [ms]": results,
                                  "frames": options.frames, "size [px]":
                                  [options.width, options.height]})


if __name__ == "__main__":
    main()
