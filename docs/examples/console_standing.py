"""Measure the standing figures of docs/console.md (stability margin, haptic feedback).

Drives :class:`pneumaquad.console.app.ConsoleApp` headless and unpaced from its reset pose
on flat ground, 20 ms chunks as the console's thread steps them, and reads what the
console shows after each chunk from 1 s to 15 s:

* the free quadruped: the static stability margin of the loaded feet, the feedback force
  of the front feet (norm of the total at the foot and at the device, as the panel shows
  them), each standing foot's normal load, and the smallest singular value of each leg's
  foot Jacobian;
* the ``fixed`` robot (thorax held in the air, feet hanging): the total feedback force of
  each leg (the actuators holding the leg up).

    .venv/bin/python docs/examples/console_standing.py
"""

from __future__ import annotations

import numpy as np

from pneumaquad.console.app import ConsoleApp
from pneumaquad.console.devices import device_forces
from pneumaquad.robot.feedback import foot_jacobian_world, leg_dof_addresses

SETTLE, SAMPLE = 50, 700  # 20 ms chunks: 1 s to settle, then 14 s sampled


def sample(configuration: str) -> dict[str, np.ndarray]:
    app = ConsoleApp(configuration=configuration, environment="flat", port=0, real_time=False)
    try:
        simulation, robot = app.simulation, app.simulation.robot
        for _ in range(SETTLE):
            app.advance()
        rows: dict[str, list] = {"margin": [], "foot": [], "device": [], "load": [], "sigma": []}
        for _ in range(SAMPLE):
            app.advance()
            feedback = app.feedback
            rows["margin"].append(app.stability.margin)
            rows["foot"].append(feedback.total.copy())
            rows["device"].append(device_forces(simulation, feedback))
            rows["load"].append(simulation.foot_normal_forces())
            sigma = []
            for index, leg in enumerate(robot.legs):
                jacobian = foot_jacobian_world(
                    simulation.model,
                    simulation.data,
                    int(robot.foot_site_id[index]),
                    leg_dof_addresses(robot, leg),
                )
                sigma.append(np.linalg.svd(jacobian, compute_uv=False)[-1])
            rows["sigma"].append(sigma)
        result = {name: np.asarray(values) for name, values in rows.items()}
        result["legs"] = np.array(robot.legs)
        return result
    finally:
        app.close()


def main() -> None:
    free = sample("quadruped")
    legs = list(free["legs"])
    print("quadruped, reset pose, 1-15 s:")
    print(f"  loaded-feet margin: {free['margin'].min():.3f}-{free['margin'].max():.3f} m")
    print(f"  smallest singular value of J: {free['sigma'].min():.3f}-{free['sigma'].max():.3f} m")
    for leg in ("front_left", "front_right"):
        k = legs.index(leg)
        foot = np.linalg.norm(free["foot"][:, k], axis=1)
        device = np.linalg.norm(free["device"][:, k], axis=1)
        load = free["load"][:, k]
        print(
            f"  {leg}: feedback at the foot {foot.min():.1f}-{foot.max():.1f} N "
            f"(z {free['foot'][:, k, 2].mean():+.1f} N), at the device "
            f"{device.min():.2f}-{device.max():.2f} N, normal load {load.min():.1f}-"
            f"{load.max():.1f} N"
        )
        seconds = foot.reshape(-1, 50).mean(axis=1)  # mean of each second
        print(f"    feedback at the foot, mean per second from 1 s: {np.round(seconds, 1)} N")
    fixed = sample("fixed")
    print("fixed robot, legs in the air, 1-15 s: total feedback force [N]")
    for k, leg in enumerate(fixed["legs"]):
        norm = np.linalg.norm(fixed["foot"][:, k], axis=1)
        seconds = fixed["foot"][:, k, 2].reshape(-1, 50).mean(axis=1)
        print(
            f"  {leg}: norm {norm.min():.1f}-{norm.max():.1f} N; z, mean per second from 1 s: "
            f"{np.round(seconds, 1)} N"
        )


if __name__ == "__main__":
    main()
