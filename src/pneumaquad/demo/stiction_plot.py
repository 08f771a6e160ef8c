"""Figure for the slow-sine stiction comparison: position and |velocity| on a log scale."""

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from pneumaquad.reporting.display_units import SI, DisplayUnits

#: Range of the speed axis [m/s]: from 1 nm/s (still) to 1 m/s.
SPEED_RANGE = (1e-9, 1.0)


def plot_stiction_comparison(
    recordings: Mapping[str, Mapping[str, np.ndarray]], path: Path, units: DisplayUnits = SI
) -> Path:
    """Position against reference, and piston speed on a log axis, for several friction models.

    A piston that truly sticks shows speed falling by orders of magnitude at the
    reversals; one that creeps keeps a floor of slow motion. Drawn in ``units``.
    """
    figure, (ax_position, ax_speed) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for index, (label, recording) in enumerate(recordings.items()):
        time = recording["time [s]"]
        ax_position.plot(time, units.value(recording["position [m]"], "small length"),
                         color=f"C{index}", label=label)
        speed = np.maximum(np.abs(recording["velocity [m/s]"]), SPEED_RANGE[0])
        ax_speed.semilogy(time, units.value(speed, "small velocity"), color=f"C{index}",
                          lw=0.8, label=label)
    first = next(iter(recordings.values()))
    ax_position.plot(
        first["time [s]"],
        units.value(first["reference position [m]"], "small length"),
        "k--",
        lw=1.0,
        label="reference",
    )
    ax_position.set_ylabel(units.axis("Position", "small length"))
    ax_speed.set_ylabel(units.axis("|velocity|", "small velocity"))
    ax_speed.set_xlabel("Time (s)")
    ax_speed.set_ylim(*units.value(np.array(SPEED_RANGE), "small velocity"))
    for axis in (ax_position, ax_speed):
        axis.grid(True, alpha=0.4)
        axis.legend(loc="upper right")
    figure.suptitle("Slow closed-loop sine: creep (Stribeck-tanh) vs stick (LuGre)")
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=150)
    plt.close(figure)
    return path
