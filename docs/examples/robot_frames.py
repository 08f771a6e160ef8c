"""Still frames of a robot run folder, side by side, each labelled with its time.

Renders ``model.xml`` + ``trajectory.npz`` of a ``pneumaquad robot stand|walk`` run offscreen
(EGL or OSMesa, chosen as ``pneumaquad video`` does) with the video's camera following the
thorax, at the given simulated times (nearest recorded sample), and writes one PNG.

Run (the images of docs/robot.md and the README)::

    .venv/bin/python docs/examples/robot_frames.py runs/walk-ramp 40 62 86 --distance 1.8 \\
        --output docs/images/walk-ramp-frames.png
    .venv/bin/python docs/examples/robot_frames.py runs/stand 6 --width 800 --height 500 \\
        --distance 1.6 --no-label --output docs/images/robot-stand.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from pneumaquad.robot.video import render_frames, select_gl_backend


def render(run: Path, times: list[float], width: int, height: int, distance: float | None,
           label: bool) -> Image.Image:
    select_gl_backend()  # before mujoco is imported
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(run / "model.xml"))
    with np.load(run / "trajectory.npz") as archive:
        recorded, qpos = archive["time"], archive["qpos"]
    strip = Image.new("RGB", (width * len(times), height))
    for k, moment in enumerate(times):
        index = int(np.argmin(np.abs(recorded - moment)))
        frame = next(iter(render_frames(model, recorded[index:index + 1], qpos[index:index + 1],
                                        fps=1.0, width=width, height=height,
                                        distance=distance)))
        image = Image.fromarray(frame)
        if label:
            draw = ImageDraw.Draw(image)  # dark text on a light box: readable on the sky
            text = f"{recorded[index]:.0f} s"
            box = draw.textbbox((8, 6), text)
            draw.rectangle((box[0] - 4, box[1] - 3, box[2] + 4, box[3] + 3),
                           fill=(255, 255, 255))
            draw.text((8, 6), text, fill=(20, 20, 20))
        strip.paste(image, (k * width, 0))
    return strip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="run folder (model.xml, trajectory.npz)")
    parser.add_argument("times", nargs="+", type=float, help="simulated times [s]")
    parser.add_argument("--output", type=Path, required=True, help="PNG to write")
    parser.add_argument("--width", type=int, default=500, help="pixels per frame")
    parser.add_argument("--height", type=int, default=375)
    parser.add_argument("--distance", type=float, default=None,
                        help="camera distance [m] (default: the video's, 1.5 model extents)")
    parser.add_argument("--no-label", dest="label", action="store_false",
                        help="leave out the time labels")
    arguments = parser.parse_args()
    image = render(arguments.run, arguments.times, arguments.width, arguments.height,
                   arguments.distance, arguments.label)
    arguments.output.parent.mkdir(parents=True, exist_ok=True)
    image.save(arguments.output)
    print(f"wrote {arguments.output} ({image.width} x {image.height})")


if __name__ == "__main__":
    main()
