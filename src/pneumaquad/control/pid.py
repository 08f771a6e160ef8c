"""Discrete position PID with valve-voltage output (compiled, one sample per call).

u = u_offset + Kp·e + I - Kd·d(y)/dt, with the derivative taken on the measurement (no
kick on reference steps) through a first-order filter, the integral clamped to
±integral_limit and frozen while the output saturates in the direction of the error
(conditional integration anti-windup), and u saturated to the valve's range.
"""

import numpy as np

from pneumaquad.jit import compiled

G_KP = 0  # proportional gain [V/m]
G_KI = 1  # integral gain [V/(m s)]
G_KD = 2  # derivative gain [V s/m]
G_FILTER = 3  # derivative filter time constant [s]
G_INTEGRAL_LIMIT = 4  # [V]
G_OFFSET = 5  # valve offset voltage [V]
G_UMIN = 6  # [V]
G_UMAX = 7  # [V]
N_GAINS = 8

C_INTEGRAL = 0  # integral term [V]
C_PREVIOUS = 1  # previous measurement [m]
C_DERIVATIVE = 2  # filtered measurement rate [m/s]
C_STARTED = 3  # 0 before the first sample
N_CONTROLLER_STATES = 4


def pid_gains(
    proportional: float,
    integral: float,
    derivative: float,
    filter_time_constant: float,
    integral_limit: float,
    offset_voltage: float,
    min_voltage: float,
    max_voltage: float,
) -> np.ndarray:
    """Pack PID gains and valve limits (SI: V/m, V/(m s), V s/m, s, V) for :func:`pid_update`."""
    gains = np.zeros(N_GAINS)
    gains[G_KP] = proportional
    gains[G_KI] = integral
    gains[G_KD] = derivative
    gains[G_FILTER] = filter_time_constant
    gains[G_INTEGRAL_LIMIT] = integral_limit
    gains[G_OFFSET] = offset_voltage
    gains[G_UMIN] = min_voltage
    gains[G_UMAX] = max_voltage
    return gains


def controller_gains(controller, valve) -> np.ndarray:
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
def pid_update(gains, state, reference: float, measurement: float, sample_time: float) -> float:
    """One controller sample.

    Parameters
    ----------
    gains : ndarray (N_GAINS,)
        See :func:`pid_gains`.
    state : ndarray (N_CONTROLLER_STATES,)
        Controller memory, updated in place (zeros to start).
    reference, measurement : float
        Desired and measured piston position [m].
    sample_time : float
        Controller period [s].

    Returns
    -------
    float
        Valve command [V], within [umin, umax].
    """
    error = reference - measurement
    if state[C_STARTED] == 0.0:
        state[C_PREVIOUS] = measurement
        state[C_STARTED] = 1.0
    raw_rate = (measurement - state[C_PREVIOUS]) / sample_time
    state[C_PREVIOUS] = measurement
    tau = gains[G_FILTER]
    blend = sample_time / (tau + sample_time)
    state[C_DERIVATIVE] += blend * (raw_rate - state[C_DERIVATIVE])
    unsaturated_without_integral = (
        gains[G_OFFSET] + gains[G_KP] * error - gains[G_KD] * state[C_DERIVATIVE]
    )
    candidate = state[C_INTEGRAL] + gains[G_KI] * error * sample_time
    limit = gains[G_INTEGRAL_LIMIT]
    candidate = min(max(candidate, -limit), limit)
    output = unsaturated_without_integral + candidate
    pushing_high = output > gains[G_UMAX] and error > 0.0
    pushing_low = output < gains[G_UMIN] and error < 0.0
    if not (pushing_high or pushing_low):
        state[C_INTEGRAL] = candidate
    output = unsaturated_without_integral + state[C_INTEGRAL]
    return min(max(output, gains[G_UMIN]), gains[G_UMAX])
