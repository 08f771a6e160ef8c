"""End-to-end speed of the runs a user starts, against the physics they contain.

Each figure is measured in this run, next to its reference:

(a) Rig, ``pneumaquad rig track sine`` (10 s closed-loop sine on the thesis rig):
    the bare compiled kernel (``simulate_rig`` without a recorder), the run as the command
    does it in a warm process (simulation with its recording written: CSV blocks and the
    Parquet file), and the command itself in fresh processes (``--profile``: start-up,
    run, metrics, plot). Target: the run ≥ 300× real time, within 2× of the kernel.
(b) Walk, ``pneumaquad robot walk --distance 1 --no-video --profile`` in fresh processes:
    the run (from the first phase to the recording written) against its own physics
    stage (the compiled steps: MuJoCo, 12 actuators, joint controllers). Targets: the run
    ≥ 30× real time and within 1.5× of its physics.
(c) A short walk process (``--distance 0.3 --no-video``), whole process wall time, against
    bare ``mj_step`` on the same standing model in this process. Target: at least half
    of bare MuJoCo's real-time factor.
(d) With ``--video``: the short walk with and without its video. Target: ≤ 1.3×.

Processes are run one after the other (never in parallel) and alternated between the
variants compared; figures are medians with min/max. Nothing here is a test.

Run: ``.venv/bin/python benchmarks/end_to_end.py [--video] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pyarrow as pa
import pyarrow.csv as pa_csv

from _bench import Stats, machine_line, stats, table, write_json
from pneumaquad.io.run_folder import RunFolderWriter
from pneumaquad.io.tables import float64_array
from pneumaquad.params import load_rig, load_robot
from pneumaquad.rig.signals import sine
from pneumaquad.rig.simulate import RIG_COLUMNS, simulate_rig
from pneumaquad.robot.builder import build_robot

INCH = 0.0254
#: the installed command of the interpreter running this script (the project venv)
COMMAND = [str(Path(sys.executable).parent / "pneumaquad")]


def rig_reference(duration: float) -> tuple[Any, np.ndarray]:
    """The thesis rig and ``rig track sine``'s default reference (0.875 in ± 0.4 in, 0.5 Hz)."""
    setup = load_rig("thesis-rig", [])
    return setup, sine(0.875 * INCH, 0.4 * INCH, 0.5, duration, setup.simulation.control_step)


def background_recorder(writer: RunFolderWriter) -> Any:
    """The rig command's recorder (CSV written by a writer thread), or the plain one of a
    version of the code without that mode."""
    try:
        return writer.recorder(RIG_COLUMNS, background=True)
    except TypeError:
        return writer.recorder(RIG_COLUMNS)


def csv_formatting_seconds(rows: np.ndarray, repeats: int) -> Stats:
    """Seconds Arrow's CSV writer takes to format ``rows`` (one table, into memory): the
    part of writing a recording that no overlap with the simulation can remove."""
    table = pa.Table.from_arrays([float64_array(column) for column in rows.T.copy()],
                                 names=list(RIG_COLUMNS))
    seconds = []
    for _ in range(repeats):
        begun = time.perf_counter()
        sink = pa.BufferOutputStream()
        with pa_csv.CSVWriter(sink, table.schema) as writer:
            writer.write_table(table)
        seconds.append(time.perf_counter() - begun)
    return stats(seconds)


def time_rig_in_process(repeats: int, duration: float) -> tuple[Stats, Stats, Stats, Stats]:
    """Warm-process seconds of the bare kernel, of the run with its recording written, of
    writing that recording alone (CSV blocks of 500 rows and the Parquet file, in this
    thread), interleaved, and of formatting its CSV alone."""
    setup, reference = rig_reference(duration)
    result = simulate_rig(setup, reference, True)  # load the compiled code
    rows = np.column_stack([result.recording[name] for name in RIG_COLUMNS])
    kernel, run, writing = [], [], []
    with tempfile.TemporaryDirectory(prefix="e2e-rig-") as folder:
        for repeat in range(repeats):
            begun = time.perf_counter()
            simulate_rig(setup, reference, True)
            kernel.append(time.perf_counter() - begun)
            writer = RunFolderWriter(Path(folder) / f"run-{repeat}")
            writer.write_parameters(setup)
            begun = time.perf_counter()
            with background_recorder(writer) as recorder:
                simulate_rig(setup, reference, True, recorder=recorder)
            run.append(time.perf_counter() - begun)
            writer = RunFolderWriter(Path(folder) / f"write-{repeat}")
            begun = time.perf_counter()
            with writer.recorder(RIG_COLUMNS) as recorder:
                for start in range(0, rows.shape[0], 500):
                    recorder.append(rows[start:start + 500])
            writing.append(time.perf_counter() - begun)
    return stats(kernel), stats(run), stats(writing), csv_formatting_seconds(rows, repeats)


#: "--profile", or nothing to time a version of the code that does not have the option
PROFILE: list[str] = ["--profile"]


def run_command(arguments: list[str], folder: Path) -> dict[str, Any]:
    """Run a pneumaquad command in a fresh process; its wall time and run folder files."""
    begun = time.perf_counter()
    done = subprocess.run([*COMMAND, *arguments, *PROFILE, "--output", str(folder)],
                          capture_output=True, text=True, check=False)
    wall = time.perf_counter() - begun
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(arguments)} failed:\n{done.stdout}\n{done.stderr}")
    result: dict[str, Any] = {"process [s]": wall}
    summary = json.loads((folder / "summary.json").read_text())
    result["simulated [s]"] = summary.get("simulated time [s]")
    result["run [s]"] = summary.get("wall time [s]")
    profile_file = folder / "profile.json"
    if profile_file.exists():
        result["profile"] = json.loads(profile_file.read_text())
    return result


def stage(result: dict[str, Any], name: str) -> float:
    """Seconds of one profiled stage (0 when absent)."""
    entry = result.get("profile", {}).get("stages", {}).get(name)
    return float(entry["seconds"]) if entry else 0.0


def bare_mujoco_factor(steps: int = 5000) -> float:
    """Real-time factor of bare ``mj_step`` on the standing quadruped (flat ground)."""
    robot = build_robot(load_robot("crr-quadruped", []), "quadruped", "flat", 0)
    model, data = robot.model, mujoco.MjData(robot.model)
    mujoco.mj_forward(model, data)
    for _ in range(500):
        mujoco.mj_step(model, data)
    begun = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    return steps * model.opt.timestep / (time.perf_counter() - begun)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="processes per variant")
    parser.add_argument("--walk-distance", type=float, default=1.0, help="(b) [m]")
    parser.add_argument("--short-distance", type=float, default=0.3, help="(c), (d) [m]")
    parser.add_argument("--video", action="store_true", help="also measure (d)")
    parser.add_argument("--skip-walk", action="store_true", help="only (a)")
    parser.add_argument("--no-profile", action="store_true",
                        help="run the commands without --profile (code before the option)")
    parser.add_argument("--json", default=None, help="write the figures to this file")
    args = parser.parse_args()
    if args.no_profile:
        PROFILE.clear()
    print(f"end-to-end speed  ({machine_line()})\n")
    figures: dict[str, Any] = {}

    kernel, run, writing, formatting = time_rig_in_process(max(args.repeats, 5), 10.0)
    with tempfile.TemporaryDirectory(prefix="e2e-cmd-") as folder:
        commands = [run_command(["rig", "track", "sine"], Path(folder) / f"{i}")
                    for i in range(args.repeats)]
    fresh_run = stats([c["run [s]"] for c in commands])
    process = stats([c["process [s]"] for c in commands])
    start_up = stats([stage(c, "start-up") for c in commands])
    plot = stats([stage(c, "plot") for c in commands])
    print("(a) rig track sine, 10 s simulated")
    print(table(["part", "wall [s] min / median / max", "real-time factor", "vs kernel"], [
        ["bare kernel (warm process)", kernel.spread(4), f"{10 / kernel.median:.0f}", "1"],
        ["run: simulation + recording written (warm)", run.spread(4),
         f"{10 / run.median:.0f}", f"{run.median / kernel.median:.2f}"],
        ["  writing the recording alone (CSV, Parquet)", writing.spread(4),
         f"{10 / writing.median:.0f}", f"{writing.median / kernel.median:.2f}"],
        ["    of which formatting the CSV (Arrow)", formatting.spread(4),
         f"{10 / formatting.median:.0f}", f"{formatting.median / kernel.median:.2f}"],
        ["run in a fresh command process", fresh_run.spread(4),
         f"{10 / fresh_run.median:.0f}", f"{fresh_run.median / kernel.median:.1f}"],
        ["  command start-up (imports)", start_up.spread(3), "", ""],
        ["  command plot (rig.png)", plot.spread(3), "", ""],
        ["whole command process", process.spread(3), f"{10 / process.median:.1f}", ""],
    ]))
    print(f"target: run >= 300x and within 2x of the kernel -> {10 / run.median:.0f}x, "
          f"{run.median / kernel.median:.2f}x the kernel (warm); the command's own run, as "
          f"it prints it: {10 / fresh_run.median:.0f}x, "
          f"{fresh_run.median / kernel.median:.1f}x\n")
    figures["rig"] = {"kernel_s": kernel, "run_s": run, "writing_s": writing,
                      "csv_formatting_s": formatting,
                      "fresh_run_s": fresh_run,
                      "process_s": process, "start_up_s": start_up, "plot_s": plot}
    if args.skip_walk:
        write_json(args.json, {"figures": figures})
        return

    with tempfile.TemporaryDirectory(prefix="e2e-walk-") as folder:
        walks = [run_command(["robot", "walk", "--distance", f"{args.walk_distance:g}",
                              "--no-video"], Path(folder) / f"{i}")
                 for i in range(args.repeats)]
    simulated = walks[0]["simulated [s]"]
    walk_run = stats([w["run [s]"] for w in walks])
    physics = stats([stage(w, "simulation") for w in walks])
    versus_physics = walk_run.median / physics.median if physics.median > 0 else math.nan
    rows = [["run: first phase to recording written", walk_run.spread(3),
             f"{simulated / walk_run.median:.1f}", f"{versus_physics:.2f}"]]
    for name in ("simulation", "walking feedback", "recording", "walk plan", "plots",
                 "start-up", "model (parameters, MuJoCo model, actuator bank)"):
        seconds = stats([stage(w, name) for w in walks])
        if seconds.median > 0:
            rows.append([f"  {name}", seconds.spread(3),
                         f"{simulated / seconds.median:.0f}", ""])
    walk_process = stats([w["process [s]"] for w in walks])
    rows.append(["whole command process", walk_process.spread(3),
                 f"{simulated / walk_process.median:.1f}", ""])
    print(f"(b) robot walk --distance {args.walk_distance:g} --no-video, "
          f"{simulated:g} s simulated")
    print(table(["part", "wall [s] min / median / max", "real-time factor", "vs physics"],
                rows))
    print(f"targets: run >= 30x and within 1.5x of its physics -> "
          f"{simulated / walk_run.median:.1f}x, {versus_physics:.2f}x\n")
    figures["walk"] = {"simulated_s": simulated, "run_s": walk_run, "physics_s": physics,
                       "process_s": walk_process, "profiles": [w.get("profile") for w in walks]}

    bare = bare_mujoco_factor()
    variants = [("no video", ["--no-video"])] + ([("video", ["--video"])] if args.video else [])
    short: dict[str, list[dict[str, Any]]] = {name: [] for name, _ in variants}
    with tempfile.TemporaryDirectory(prefix="e2e-short-") as folder:
        for repeat in range(args.repeats):
            for name, flags in variants:
                short[name].append(run_command(
                    ["robot", "walk", "--distance", f"{args.short_distance:g}", *flags],
                    Path(folder) / f"{name}-{repeat}"))
    short_simulated = short["no video"][0]["simulated [s]"]
    plain = stats([w["process [s]"] for w in short["no video"]])
    factor = short_simulated / plain.median
    print(f"(c) robot walk --distance {args.short_distance:g} --no-video process, "
          f"{short_simulated:g} s simulated")
    print(table(["part", "wall [s] min / median / max", "real-time factor", "vs bare"], [
        ["whole process", plain.spread(3), f"{factor:.1f}", f"{factor / bare:.2f}"],
        ["bare mj_step, standing model", "", f"{bare:.1f}", "1"],
    ]))
    print(f"target: >= half of bare mj_step's factor -> {factor / bare:.2f}\n")
    figures["short_walk"] = {"simulated_s": short_simulated, "process_s": plain,
                             "bare_mujoco_factor": bare}
    if args.video:
        with_video = stats([w["process [s]"] for w in short["video"]])
        print(f"(d) the same walk with --video: {with_video.spread(2)} s, "
              f"{with_video.median / plain.median:.2f}x the walk without (target <= 1.3x)")
        figures["short_walk"]["video_process_s"] = with_video
    write_json(args.json, {"figures": figures})


if __name__ == "__main__":
    main()
