"""MuJoCo options on the quadruped: what each costs per step and what it does to a walk.

Each variant changes one MuJoCo option (or one modelling choice that MuJoCo's cost
depends on) from the baseline, the options of ``crr-quadruped`` before this study
(:data:`BASELINE_OVERRIDES` over the shipped file), through ``--set`` overrides of the
robot file or, for options the robot file does not expose, by changing the compiled
``MjModel`` before the simulation is made. For every variant the script measures:

* **cost**, on the standing quadruped of ``robot_speed.py`` (flat ground, every leg at
  alpha 0°, beta -20°, gamma 50°, closed-loop and settled for 1 s):
  the **bare** MuJoCo step (``mujoco.mj_step`` with ``data.ctrl`` held at the standing
  cylinder forces, in blocks of 250 steps, each block started again from the settled
  state so that the pose and the contacts stay those of standing) and the **coupled**
  step (``RobotSimulation.step(N)``: MuJoCo, 12 pneumatic actuators and the joint
  controllers in one compiled loop), µs per 1 ms control step; all variants are timed
  in interleaved rounds (baseline, variant 1, variant 2, ..., baseline, ...) after one
  warm-up each, and the ratio to the baseline is taken per round. Beside them, untimed:
  the constraint rows, contacts and mean solver iterations per step of the bare step;
* **physics**, over flat walks (``pneumaquad.locomotion.walk_run.run_walk``, the code path
  of ``pneumaquad robot walk --no-video``) of ``--distance`` at each of ``--speeds``:
  the distance made good, whether the walk succeeded (the walk's own judgement), foot
  slip per metre (the largest stance-foot slide of the judgement / distance made good,
  in %), stance-force tracking error (RMS of pneumatic force - force set-point over every
  joint and recorded sample under force-controlled stance during the walk phase, N), the
  joint-angle RMSE (the summary's, mean over the 12 joints, whole run, degrees), the
  solver iterations per step (sampled every 0.2 s of the walk) and the whole run's wall
  time per control step. Walks are interleaved the same way (all variants at one speed,
  then the next speed);
* **determinism**: the walk at the first speed is run a second time from a fresh build;
  the variant is deterministic when every column of the two recordings is bit-identical;
  "= baseline" when its first walk's recording is bit-identical to the baseline's.

Variants (``--variants``, default all, in this order): see :data:`VARIANTS`. Nothing is
asserted; the table and ``--json`` hold the figures. ``--quick``: 1000 steps x 3
repeats, one 0.3 m walk at 20 mm/s.

Run: ``.venv/bin/python benchmarks/mujoco_options.py [--variants baseline euler ...]
[--quick] [--steps 3000] [--repeats 7] [--distance 0.5] [--speeds 0.015 0.02 0.025]
[--no-walk] [--json out.json] [--output runs/mujoco-options]``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from _bench import Stats, machine_line, stats, table, write_json
from pneumaquad.locomotion.walk_run import run_walk
from pneumaquad.locomotion.walking import WalkSettings
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import RobotModel, build_robot
from pneumaquad.robot.errors import SimulationDivergedError
from pneumaquad.robot.simulation import RobotSimulation

#: Standing posture of every leg, alpha, beta, gamma [deg] (as robot_speed.py).
POSTURE_DEG = (0.0, -20.0, 50.0)
#: Bare MuJoCo steps per block started again from the settled standing state.
BARE_BLOCK = 250
#: Walk speeds [m/s] and distance [m] of the full run (as walk_settings.py).
SPEEDS = (0.015, 0.02, 0.025)
DISTANCE = 0.5

ModelChange = Callable[[mujoco.MjModel], None]


@dataclass(frozen=True)
class Variant:
    """One option set: parameter overrides and an optional change of the compiled model.

    Attributes
    ----------
    name : str
        Command-line name.
    description : str
        Table text.
    overrides : tuple of str
        ``section.key=value`` overrides of ``crr-quadruped``.
    change : callable, optional
        Applied to the compiled ``MjModel`` before the simulation is made.
    """

    name: str
    description: str
    overrides: tuple[str, ...] = ()
    change: ModelChange | None = None


def _disable(flag: mujoco.mjtDisableBit) -> ModelChange:
    def change(model: mujoco.MjModel) -> None:
        model.opt.disableflags |= int(flag)

    return change


def _sparse_jacobian(model: mujoco.MjModel) -> None:
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_SPARSE


def _colliding_bodies(keep: tuple[str, ...]) -> ModelChange:
    """Robot geoms collide only on bodies whose name ends with one of ``keep``."""

    def change(model: mujoco.MjModel) -> None:
        for geom in range(model.ngeom):
            body = model.geom_bodyid[geom]
            if body != 0 and not model.body(body).name.endswith(keep):
                model.geom_contype[geom] = 0
                model.geom_conaffinity[geom] = 0

    return change


#: The options before this study (MuJoCo's island discovery on), over the shipped file:
#: the baseline, and the base of every other variant.
BASELINE_OVERRIDES = ("simulation.constraint_islands=true",)

#: The variants, in table order; the first is the baseline. Every other variant is the
#: baseline with one change (or two, named with a +).
VARIANTS: dict[str, Variant] = {v.name: v for v in (
    Variant("baseline", "the options before this study: Newton, 50 iterations, tolerance "
            "1e-8, elliptic cone, impratio 10, implicitfast, seal friction in the solver, "
            "island discovery on, piston mass as tendon armature"),
    Variant("pyramidal", "pyramidal friction cone", ("contact.friction_cone=pyramidal",)),
    Variant("impratio-1", "impratio 1", ("contact.friction_impedance_ratio=1.0",)),
    Variant("cg", "solver CG", ("simulation.solver=cg",)),
    Variant("pgs", "solver PGS", ("simulation.solver=pgs",)),
    Variant("iterations-10", "Newton, at most 10 iterations",
            ("simulation.solver_iterations=10",)),
    Variant("iterations-3", "Newton, at most 3 iterations",
            ("simulation.solver_iterations=3",)),
    Variant("tolerance-1e-6", "Newton, tolerance 1e-6", ("simulation.solver_tolerance=1e-6",)),
    Variant("tolerance-1e-4", "Newton, tolerance 1e-4", ("simulation.solver_tolerance=1e-4",)),
    Variant("no-warmstart", "warm start off (disableflags warmstart)",
            change=_disable(mujoco.mjtDisableBit.mjDSBL_WARMSTART)),
    Variant("sparse", "sparse Jacobian (auto picks dense for 18 dofs)",
            change=_sparse_jacobian),
    Variant("seal-actuator", "seal friction outside the solver (force law on the motor)",
            ("simulation.seal_friction=actuator",)),
    Variant("feet-thorax", "only the feet and the thorax collide",
            change=_colliding_bodies(("_tibia", "thorax"))),
    Variant("feet-only", "only the feet collide", change=_colliding_bodies(("_tibia",))),
    Variant("euler", "integrator Euler", ("simulation.integrator=euler",)),
    Variant("seal-actuator+euler", "seal friction outside the solver, and Euler",
            ("simulation.seal_friction=actuator", "simulation.integrator=euler")),
    Variant("implicit", "integrator implicit", ("simulation.integrator=implicit",)),
    Variant("no-islands", "island discovery off (disableflags island): the shipped options",
            ("simulation.constraint_islands=false",)),
    Variant("piston-joint", "piston mass as joint armature m<r^2>, not tendon armature",
            ("simulation.piston_inertia=joint",)),
)}


def build_variant(variant: Variant) -> RobotModel:
    """The quadruped on flat ground: the shipped file with :data:`BASELINE_OVERRIDES` and
    the variant's overrides, then the variant's model change."""
    overrides = [*BASELINE_OVERRIDES, *variant.overrides]
    robot = build_robot(load_robot("crr-quadruped", overrides), "quadruped", "flat")
    if variant.change is not None:
        variant.change(robot.model)
    return robot


def standing_simulation(variant: Variant) -> RobotSimulation:
    """The variant's quadruped standing on flat ground, closed-loop, settled for 1 s."""
    simulation = RobotSimulation(build_variant(variant))
    pose = np.tile(np.radians(POSTURE_DEG), len(simulation.robot.legs))
    simulation.set_pose(pose)
    thorax = simulation.data.qpos[0:3].copy()
    thorax[2] -= simulation.foot_positions()[:, 2].min()  # lowest foot on the ground
    simulation.set_pose(pose, thorax_position=thorax,
                        thorax_quaternion=simulation.data.qpos[3:7].copy())
    simulation.command_angles(pose)
    simulation.step(round(1.0 / simulation.control_step))
    return simulation


def time_coupled(simulation: RobotSimulation, steps: int) -> float:
    """Seconds per control step of ``simulation.step(steps)`` (one compiled call)."""
    start = time.perf_counter()
    simulation.step(steps)
    return (time.perf_counter() - start) / steps


def time_bare(model: mujoco.MjModel, snapshot: mujoco.MjData, steps: int) -> float:
    """Seconds per ``mj_step``, in blocks of :data:`BARE_BLOCK` from ``snapshot``."""
    data = mujoco.MjData(model)
    blocks = max(1, steps // BARE_BLOCK)
    elapsed = 0.0
    for _ in range(blocks):
        mujoco.mj_copyData(data, model, snapshot)
        start = time.perf_counter()
        mujoco.mj_step(model, data, nstep=BARE_BLOCK)
        elapsed += time.perf_counter() - start
    return elapsed / (blocks * BARE_BLOCK)


def solver_figures(model: mujoco.MjModel, snapshot: mujoco.MjData) -> dict[str, Any]:
    """Constraint rows, contacts and mean solver iterations per bare step over one block,
    and whether the bare step diverged (it stops at the first non-finite acceleration)."""
    data = mujoco.MjData(model)
    mujoco.mj_copyData(data, model, snapshot)
    iterations = []
    diverged = False
    for _ in range(BARE_BLOCK):
        mujoco.mj_step(model, data)
        if not np.isfinite(data.qacc).all():
            diverged = True
            break
        iterations.append(int(data.solver_niter[: max(1, data.nisland)].max()))
    return {"constraint rows": int(data.nefc), "contacts": int(data.ncon),
            "solver iterations per step": float(np.mean(iterations)) if iterations else math.nan,
            "thorax height [m]": float(data.qpos[2]), "bare step diverged": diverged}


def measure_cost(names: list[str], steps: int, repeats: int) -> dict[str, dict[str, Any]]:
    """Bare and coupled µs per step of every variant, interleaved (module docstring).

    A variant whose bare step diverges from the standing state (constant motor forces,
    no controller) is timed coupled only."""
    simulations, snapshots, results = {}, {}, {}
    for name in names:
        simulation = standing_simulation(VARIANTS[name])
        snapshot = mujoco.MjData(simulation.model)
        mujoco.mj_copyData(snapshot, simulation.model, simulation.data)
        simulations[name], snapshots[name] = simulation, snapshot
        results[name] = {"standing": solver_figures(simulation.model, snapshot)}
    calls: dict[tuple[str, str], Callable[[], float]] = {}
    for name in names:
        simulation, snapshot = simulations[name], snapshots[name]
        calls[name, "coupled"] = lambda s=simulation: time_coupled(s, steps)
        if not results[name]["standing"]["bare step diverged"]:
            calls[name, "bare"] = lambda s=simulation, d=snapshot: time_bare(s.model, d, steps)
    for call in calls.values():
        call()
    samples: dict[tuple[str, str], list[float]] = {key: [] for key in calls}
    for _ in range(repeats):
        for key, call in calls.items():
            samples[key].append(call() * 1e6)
    base = names[0]
    for name in names:
        for kind in ("coupled", "bare"):
            if (name, kind) not in samples or (base, kind) not in samples:
                continue
            own, reference = samples[name, kind], samples[base, kind]
            results[name][f"{kind} [us/step]"] = stats(own)
            results[name][f"{kind} ratio to {base}"] = stats(
                [a / b for a, b in zip(own, reference, strict=True)])
    return results


def force_tracking_error(recording: dict[str, np.ndarray], summary: dict[str, Any],
                         joints: tuple[str, ...]) -> float:
    """RMS of pneumatic force - force set-point [N] over every joint and sample under
    force-controlled stance during the walk phase (NaN when there is none)."""
    times = recording["time [s]"]
    walk = summary["phases"]["walk"]
    inside = (times >= walk["start [s]"]) & (times <= walk["start [s]"] + walk["duration [s]"])
    errors = []
    for joint in joints:
        set_point = recording[f"{joint} force set-point [N]"][inside]
        force = recording[f"{joint} force [N]"][inside]
        tracked = np.isfinite(set_point)
        errors.append(force[tracked] - set_point[tracked])
    pooled = np.concatenate(errors)
    return float(np.sqrt(np.mean(pooled**2))) if pooled.size else math.nan


def walk_once(variant: Variant, speed: float, distance: float, folder: Path
              ) -> tuple[dict[str, Any], dict[str, np.ndarray] | None]:
    """One flat walk of ``variant``: its figures and recording (None when it diverged)."""
    simulation = RobotSimulation(build_variant(variant))
    iterations: list[int] = []

    def progress(_now: float, _total: float) -> None:
        data = simulation.data
        iterations.append(int(data.solver_niter[: max(1, data.nisland)].max()))

    settings = WalkSettings(speed=speed, distance=distance)
    start = time.perf_counter()
    try:
        judged = run_walk(simulation, settings, folder, progress=progress)
    except SimulationDivergedError as error:
        return {"success": False, "reasons": [f"diverged: {error}"]}, None
    wall = time.perf_counter() - start
    run, outcome = judged.run, judged.outcome
    steps = run.summary["simulated time [s]"] / simulation.control_step
    figures: dict[str, Any] = {"walk wall time per step [us]": wall / steps * 1e6,
                               "solver iterations per step (sampled)": float(
                                   np.mean(iterations)) if iterations else math.nan,
                               "solver iterations, largest sample": max(iterations, default=0)}
    if outcome is None:
        figures.update(success=False, reasons=["not judged"])
        return figures, run.recording
    travelled = outcome["distance travelled [m]"]
    rmse = run.summary["angle rmse [deg]"]
    figures.update({
        "success": bool(outcome["success"]),
        "reasons": outcome["reasons"],
        "distance travelled [m]": travelled,
        "largest stance-foot slide [m]": outcome["largest stance-foot slide [m]"],
        "slip per metre [%]": 100.0 * outcome["largest stance-foot slide [m]"]
        / max(travelled, 1e-9),
        "force tracking RMS [N]": force_tracking_error(run.recording, run.summary,
                                                       simulation.robot.joint_names),
        "joint angle RMSE [deg]": float(np.mean(list(rmse.values()))),
        "time with negative static margin [%]":
            outcome["time with negative static margin [%]"],
    })
    return figures, run.recording


def identical(first: dict[str, np.ndarray] | None,
              second: dict[str, np.ndarray] | None) -> bool:
    """Whether two recordings have the same columns with bit-identical values."""
    if first is None or second is None or first.keys() != second.keys():
        return False
    return all(np.asarray(first[key]).tobytes() == np.asarray(second[key]).tobytes()
               for key in first)


def measure_walks(names: list[str], speeds: list[float], distance: float,
                  output: Path) -> dict[str, dict[str, Any]]:
    """Walk figures of every variant at every speed, then the repeat for determinism."""
    walks: dict[str, list[dict[str, Any]]] = {name: [] for name in names}
    first: dict[str, dict[str, np.ndarray] | None] = {}
    walk_once(VARIANTS[names[0]], speeds[0], 0.1, output / "warm-up")  # compiles, loads
    for speed in speeds:
        for name in names:
            folder = output / f"{name}-{round(speed * 1000)}mm"
            figures, recording = walk_once(VARIANTS[name], speed, distance, folder)
            figures["speed [m/s]"] = speed
            walks[name].append(figures)
            if speed == speeds[0]:
                first[name] = recording
            print(f"  walk {name:<26} {speed * 1000:4.0f} mm/s  "
                  f"{'success' if figures['success'] else ','.join(figures['reasons'])}",
                  flush=True)
    results = {}
    for name in names:
        _, again = walk_once(VARIANTS[name], speeds[0], distance, output / f"{name}-repeat")
        results[name] = {"walks": walks[name],
                         "deterministic": identical(first[name], again),
                         "identical to the baseline": identical(first[name], first[names[0]])}
    return results


def _mean(walks: list[dict[str, Any]], key: str) -> float:
    values = [w[key] for w in walks if key in w and math.isfinite(w[key])]
    return statistics.fmean(values) if values else math.nan


def _ratio_text(value: Stats) -> str:
    return f"{value.median:.2f}"


def summary_rows(names: list[str], cost: dict[str, dict[str, Any]],
                 walks: dict[str, dict[str, Any]]) -> list[list[str]]:
    """One table row per variant (module docstring)."""
    base = names[0]
    rows = []
    for name in names:
        row = [name]
        if name in cost:
            figures = cost[name]
            for kind in ("bare", "coupled"):
                value = figures.get(f"{kind} [us/step]")
                row.append("diverged" if value is None else
                           f"{value.median:.2f} ({value.min:.2f}-{value.max:.2f})")
            for kind in ("bare", "coupled"):
                ratio = figures.get(f"{kind} ratio to {base}")
                row.append("-" if ratio is None else _ratio_text(ratio))
            row.append(f"{figures['standing']['solver iterations per step']:.1f}")
        else:
            row += ["-"] * 5
        if name in walks:
            runs = walks[name]["walks"]
            successes = sum(bool(w["success"]) for w in runs)
            row += [f"{_mean(runs, 'distance travelled [m]'):.3f}",
                    f"{_mean(runs, 'slip per metre [%]'):.2f}",
                    f"{_mean(runs, 'force tracking RMS [N]'):.2f}",
                    f"{_mean(runs, 'joint angle RMSE [deg]'):.2f}",
                    f"{_mean(runs, 'solver iterations per step (sampled)'):.1f}",
                    f"{successes}/{len(runs)}",
                    "yes" if walks[name]["deterministic"] else "NO",
                    "yes" if walks[name]["identical to the baseline"] else "no"]
        else:
            row += ["-"] * 8
        rows.append(row)
    return rows


HEADERS = ["variant", "bare µs/step (min-max)", "coupled µs/step (min-max)", "bare ratio",
           "coupled ratio", "iter. standing", "travel m", "slip %/m", "force RMS N",
           "joint RMSE °", "iter. walking", "walks ok", "deterministic",
           "= baseline"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=None,
                        help="variants to measure (the baseline is always measured first)")
    parser.add_argument("--quick", action="store_true",
                        help="1000 steps x 3 repeats, one 0.3 m walk at 20 mm/s")
    parser.add_argument("--steps", type=int, default=3000, help="control steps per repeat")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--distance", type=float, default=DISTANCE, help="walk distance [m]")
    parser.add_argument("--speeds", nargs="+", type=float, default=list(SPEEDS),
                        help="walk speeds [m/s]")
    parser.add_argument("--no-walk", action="store_true", help="cost only")
    parser.add_argument("--no-cost", action="store_true", help="walks only")
    parser.add_argument("--output", type=Path, default=None,
                        help="keep the walks' run folders here (default: a temporary folder)")
    parser.add_argument("--json", default=None, help="write the figures to this file")
    args = parser.parse_args()
    if args.quick:
        args.steps, args.repeats, args.distance, args.speeds = 1000, 3, 0.3, [0.02]
    names = list(VARIANTS) if args.variants is None else list(
        dict.fromkeys(["baseline", *args.variants]))

    print(f"MuJoCo options on the quadruped  ({machine_line()}; MuJoCo {mujoco.__version__})")
    started = time.perf_counter()
    cost: dict[str, dict[str, Any]] = {}
    if not args.no_cost:
        print(f"cost: standing quadruped, {args.steps} steps x {args.repeats} interleaved "
              f"repeats per variant (bare: blocks of {BARE_BLOCK} from the settled state)",
              flush=True)
        cost = measure_cost(names, args.steps, args.repeats)
    walks: dict[str, dict[str, Any]] = {}
    if not args.no_walk:
        print(f"walks: {args.distance:g} m on flat ground at "
              f"{', '.join(f'{s * 1000:g}' for s in args.speeds)} mm/s, and the first again "
              "for determinism", flush=True)
        with tempfile.TemporaryDirectory() as temporary:
            output = args.output or Path(temporary)
            walks = measure_walks(names, args.speeds, args.distance, output)
    print(f"\n{time.perf_counter() - started:.0f} s\n")
    print(table(HEADERS, summary_rows(names, cost, walks)))
    print("\nbare / coupled: median (min-max) µs per 1 ms step; ratios: median of per-round "
          "ratios to the baseline; iter.: mean solver iterations per step; walk figures: "
          "means over the speeds")
    for name in names:
        if name in cost:
            standing = cost[name]["standing"]
            after = ("bare step diverged" if standing["bare step diverged"] else
                     f"thorax {standing['thorax height [m]']:.3f} m after {BARE_BLOCK} bare steps")
            print(f"  {name:<22} standing: {standing['contacts']} contacts, "
                  f"{standing['constraint rows']} constraint rows, {after};  "
                  f"{VARIANTS[name].description}")
    write_json(args.json, {
        "mujoco": mujoco.__version__,
        "steps": args.steps,
        "repeats": args.repeats,
        "distance [m]": args.distance,
        "speeds [m/s]": args.speeds,
        "variants": {name: {"description": VARIANTS[name].description,
                            "overrides": list(VARIANTS[name].overrides),
                            "model change": VARIANTS[name].change is not None,
                            **cost.get(name, {}), **walks.get(name, {})}
                     for name in names},
    })


if __name__ == "__main__":
    main()
