"""Discrete position PID with valve-voltage output (compiled, one sample per call).

u = u_offset + Kp·e + I - Kd·d(y)/dt, with the derivative taken on the measurement (no
kick on reference steps) through a first-order filter, the integral clamped to
±integral_limit and frozen while the output saturates in the direction of the error
(conditional integration anti-windup), and u saturated to the valve's range.

Gains and controller memory are NumPy records (:data:`PID_GAINS_DTYPE`,
:data:`PID_STATE_DTYPE`): one record per controller, arrays of them for many.
"""

import numpy as np

from pneumaquad.core.jit import compiled

__all__ = [
    "PID_GAINS_DTYPE",
    "PID_STATE_DTYPE",
    "controller_gains",
    "new_pid_state",
    "pid_gains",
    "pid_update",
]

#: Gains of one controller and the valve limits it saturates to (SI).
PID_GAINS_DTYPE = np.dtype([
    ("proportional_gain", "f8"),  # Kp [V/m]
    ("integral_gain", "f8"),  # Ki [V/(m s)]
    ("derivative_gain", "f8"),  # Kd [V s/m]
    ("derivative_filter_time_constant", "f8"),  # [s]
    ("integral_limit", "f8"),  # [V]
    ("offset_voltage", "f8"),  # valve offset [V]
    ("min_voltage", "f8"),  # [V]
    ("max_voltage", "f8"),  # [V]
])

#: Memory of one controller (zeros to start).
PID_STATE_DTYPE = np.dtype([
    ("integral", "f8"),  # integral term [V]
    ("previous_measurement", "f8"),  # [m]
    ("measurement_rate", "f8"),  # filtered d(measurement)/dt [m/s]
    ("started", "i8"),  # 0 before the first sample
])


def pid_gains(
    proportional: float,
    integral: float,
    derivative: float,
    filter_time_constant: float,
    integral_limit: float,
    offset_voltage: float,
    min_voltage: float,
    max_voltage: float,
) -> np.void:
    """Gains and valve limits (SI: V/m, V/(m s), V s/m, s, V) as a :data:`PID_GAINS_DTYPE`
    record for :func:`pid_update`."""
    gains = np.zeros(1, PID_GAINS_DTYPE)[0]
    gains["proportional_gain"] = proportional
    gains["integral_gain"] = integral
    gains["derivative_gain"] = derivative
    gains["derivative_filter_time_constant"] = filter_time_constant
    gains["integral_limit"] = integral_limit
    gains["offset_voltage"] = offset_voltage
    gains["min_voltage"] = min_voltage
    gains["max_voltage"] = max_voltage
    return gains


def new_pid_state(count: int | None = None) -> np.ndarray | np.void:
    """Zeroed controller memory: one :data:`PID_STATE_DTYPE` record, or ``count`` of them."""
    if count is None:
        return np.zeros(1, PID_STATE_DTYPE)[0]
    return np.zeros(count, PID_STATE_DTYPE)


def controller_gains(controller, valve) -> np.void:
    """:func:`pid_gains` from a controller table and a valve table of a parameter set.

    ``controller`` has ``proportional_gain``, ``integral_gain``, ``derivative_gain``,
    ``derivative_filter_time_constant`` and ``integral_limit``; ``valve`` has
    ``offset_voltage``, ``min_voltage`` and ``max_voltage`` (SI).
    """
    return pid_gains(
        controller.proportional_gain,
        controller.integral_gain,
        controller.derivative_gain,
        controller.derivative_filter_time_constant,
        controller.integral_limit,
        valve.offset_voltage,
        valve.min_voltage,
        valve.max_voltage,
    )


@compiled
def scale_gains(gains, scale: float, scaled) -> None:
    """Copy the PID_GAINS_DTYPE record ``gains`` into ``scaled`` with Kp, Ki and Kd
    multiplied by ``scale`` [-] (gain scheduling); filter, limits and voltages as they are."""
    scaled.proportional_gain = gains.proportional_gain * scale
    scaled.integral_gain = gains.integral_gain * scale
    scaled.derivative_gain = gains.derivative_gain * scale
    scaled.derivative_filter_time_constant = gains.derivative_filter_time_constant
    scaled.integral_limit = gains.integral_limit
    scaled.offset_voltage = gains.offset_voltage
    scaled.min_voltage = gains.min_voltage
    scaled.max_voltage = gains.max_voltage


@compiled
def pid_update(gains, state, reference: float, measurement: float, sample_time: float) -> float:
    """One controller sample.

    Parameters
    ----------
    gains : PID_GAINS_DTYPE record
        See :func:`pid_gains`.
    state : PID_STATE_DTYPE record
        Controller memory, updated in place (zeros to start).
    reference, measurement : float
        Desired and measured piston position [m].
    sample_time : float
        Controller period [s].

    Returns
    -------
    float
        Valve command [V], within [min_voltage, max_voltage].
    """
    error = reference - measurement
    if state.started == 0:
        state.previous_measurement = measurement
        state.started = 1
    raw_rate = (measurement - state.previous_measurement) / sample_time
    state.previous_measurement = measurement
    tau = gains.derivative_filter_time_constant
    blend = sample_time / (tau + sample_time)
    state.measurement_rate += blend * (raw_rate - state.measurement_rate)
    unsaturated_without_integral = (
        gains.offset_voltage + gains.proportional_gain * error
        - gains.derivative_gain * state.measurement_rate
    )
    candidate = state.integral + gains.integral_gain * error * sample_time
    limit = gains.integral_limit
    candidate = min(max(candidate, -limit), limit)
    output = unsaturated_without_integral + candidate
    pushing_high = output > gains.max_voltage and error > 0.0
    pushing_low = output < gains.min_voltage and error < 0.0
    if not (pushing_high or pushing_low):
        state.integral = candidate
    output = unsaturated_without_integral + state.integral
    return min(max(output, gains.min_voltage), gains.max_voltage)
