"""Figure for the slow-sine stiction comparison: position and |velocity| on a log scale."""

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from pneumaquad.params.conversions import METRE_PER_INCH


def plot_stiction_comparison(
    recordings: Mapping[str, Mapping[str, np.ndarray]], path: Path
) -> Path:
    """Position against reference, and piston speed on a log axis, for several friction models.

    A piston that truly sticks shows speed falling by orders of magnitude at the
    reversals; one that creeps keeps a floor of slow motion.
    """
    figure, (ax_position, ax_speed) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for index, (label, recording) in enumerate(recordings.items()):
        time = recording["time [s]"]
        ax_position.plot(time, recording["position [m]"] / METRE_PER_INCH, color=f"C{index}",
                         label=label)
        speed = np.maximum(np.abs(recording["velocity [m/s]"]), 1e-9)
        ax_speed.semilogy(time, speed * 1000.0, color=f"C{index}", lw=0.8, label=label)
    first = next(iter(recordings.values()))
    ax_position.plot(
        first["time [s]"],
        first["reference position [m]"] / METRE_PER_INCH,
        "k--",
        lw=1.0,
        label="reference",
    )
    ax_position.set_ylabel("Position (in)")
    ax_speed.set_ylabel("|velocity| (mm/s)")
    ax_speed.set_xlabel("Time (s)")
    ax_speed.set_ylim(1e-6, 1e3)
    for axis in (ax_position, ax_speed):
        axis.grid(True, alpha=0.4)
        axis.legend(loc="upper right")
    figure.suptitle("Slow closed-loop sine: creep (Stribeck-tanh) vs stick (LuGre)")
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=150)
    plt.close(figure)
    return path
