"""Summary figures of a rig recording (SI units, keys name their unit)."""

import math

import numpy as np

from pneumaquad.analysis.metrics import step_metrics as analysis_step_metrics

Recording = dict[str, np.ndarray]

#: Speed below which the piston counts as at rest [m/s].
REST_SPEED = 2e-4

#: The names of :func:`general_metrics`, :func:`step_metrics` and :func:`tracking_metrics`
#: (a step that never moves gives only the first two step names).
GENERAL_METRICS = (
    "simulated time [s]", "final position [m]", "min position [m]", "max position [m]",
    "max cap pressure [Pa]", "max rod pressure [Pa]", "final cap pressure [Pa]",
    "final rod pressure [Pa]", "air consumed [kg]", "air consumed [NL]",
    "final supply pressure [Pa]", "fraction of time at rest",
)
STEP_METRICS = (
    "position at step [m]", "motion onset delay [s]", "stiction peak force [N]",
    "stiction peak time [s]", "time moving [s]", "rise time 10-90 % [s]",
    "settling time [s]",
)
TRACKING_METRICS = ("rmse [m]", "rmse [% stroke]", "max abs error [m]", "lag [s]")


def tracking_metrics(recording: Recording, stroke: float) -> dict[str, float]:
    """Closed-loop tracking error of position against the reference.

    Returns RMSE [m] and as % of stroke, the largest error [m], and the lag of the
    position behind the reference from the peak of their cross-correlation [s].
    """
    reference = recording["reference position [m]"]
    position = recording["position [m]"]
    error = position - reference
    rmse = float(np.sqrt(np.mean(error**2)))
    times = recording["time [s]"]
    dt = float(times[1] - times[0]) if times.size > 1 else math.nan
    lag = math.nan
    if times.size > 10:
        ref = reference - reference.mean()
        pos = position - position.mean()
        max_shift = min(times.size // 4, round(1.0 / dt))
        shifts = np.arange(0, max_shift)
        scores = [float(np.dot(ref[: ref.size - s], pos[s:])) for s in shifts]
        lag = float(shifts[int(np.argmax(scores))] * dt)
    return {
        "rmse [m]": rmse,
        "rmse [% stroke]": 100.0 * rmse / stroke,
        "max abs error [m]": float(np.max(np.abs(error))),
        "lag [s]": lag,
    }


def step_metrics(recording: Recording, step_time: float) -> dict[str, float]:
    """Open-loop step figures: when the piston breaks away and the stiction peak.

    Motion onset is the first sample after the step where the piston has moved more
    than 0.1 mm from its position at the step. The stiction peak is the largest
    pneumatic force between the step and the onset.
    """
    times = recording["time [s]"]
    position = recording["position [m]"]
    force = recording["pneumatic force [N]"]
    after = np.nonzero(times >= step_time)[0]
    if after.size == 0:
        return {}
    start = after[0]
    moved = np.nonzero(np.abs(position[start:] - position[start]) > 1e-4)[0]
    figures: dict[str, float] = {"position at step [m]": float(position[start])}
    if moved.size == 0:
        figures["motion onset delay [s]"] = math.nan
        return figures
    onset = start + moved[0]
    figures["motion onset delay [s]"] = float(times[onset] - times[start])
    direction = 1.0 if position[-1] >= position[start] else -1.0
    segment = direction * force[start : onset + 1]
    figures["stiction peak force [N]"] = float(direction * np.max(segment))
    figures["stiction peak time [s]"] = float(times[start + int(np.argmax(segment))])
    moving = np.abs(recording["velocity [m/s]"][onset:]) > REST_SPEED
    figures["time moving [s]"] = float(np.count_nonzero(moving) * (times[1] - times[0]))
    response = analysis_step_metrics(times[start:], position[start:], step_time=step_time,
                                     unit="m")
    figures["rise time 10-90 % [s]"] = response["rise time [s]"]
    figures["settling time [s]"] = response["settling time [s]"]
    return figures



def general_metrics(recording: Recording) -> dict[str, float]:
    """Figures every rig run has: extent of motion, pressures, air consumed, rest time."""
    times = recording["time [s]"]
    duration = float(times[-1]) if times.size else 0.0
    air = recording["air consumed [kg]"]
    velocity = recording["velocity [m/s]"]
    return {
        "simulated time [s]": duration,
        "final position [m]": float(recording["position [m]"][-1]),
        "min position [m]": float(np.min(recording["position [m]"])),
        "max position [m]": float(np.max(recording["position [m]"])),
        "max cap pressure [Pa]": float(np.max(recording["cap pressure [Pa]"])),
        "max rod pressure [Pa]": float(np.max(recording["rod pressure [Pa]"])),
        "final cap pressure [Pa]": float(recording["cap pressure [Pa]"][-1]),
        "final rod pressure [Pa]": float(recording["rod pressure [Pa]"][-1]),
        "air consumed [kg]": float(air[-1]),
        "air consumed [NL]": float(recording["air consumed [NL]"][-1]),
        "final supply pressure [Pa]": float(recording["supply pressure [Pa]"][-1]),
        "fraction of time at rest": float(np.mean(np.abs(velocity) < REST_SPEED)),
    }
