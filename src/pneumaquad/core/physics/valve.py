"""Proportional valve: command saturation, orifice area and input pressure (thesis 4.2.3).

Voltages: the valve takes 0–10 V; the *centered* voltage is measured from the valve offset
(5.25 V for the MPYE-5 of the thesis), so the centered voltage is 0 where both ports flow
equally.
"""

import math

from pneumaquad.core.jit import compiled


@compiled
def centered_voltage(
    command_voltage: float, offset_voltage: float, min_voltage: float, max_voltage: float
) -> float:
    """Saturate a valve command and measure it from the valve offset.

    Parameters
    ----------
    command_voltage : float
        Commanded valve voltage [V].
    offset_voltage : float
        Voltage of equal flow through both ports (5.25 V, thesis 4.2.3) [V].
    min_voltage, max_voltage : float
        Input range of the valve (0 and 10 V for the MPYE-5) [V].

    Returns
    -------
    float
        Centered voltage u - u_offset after saturation [V].
    """
    if command_voltage < min_voltage:
        command_voltage = min_voltage
    elif command_voltage > max_voltage:
        command_voltage = max_voltage
    return command_voltage - offset_voltage


@compiled
def simple_valve_area(
    centered: float, max_area: float, leak_area: float, full_scale_voltage: float
) -> float:
    """Geometric port area of the linear ("simple") valve model (thesis Fig. 18).

    A = A_max·|u_c|/u_fs + A_leak: linear in the centered voltage on both sides of the
    offset with a leak area at the offset. Multiply by a discharge coefficient for the
    effective area.

    Parameters
    ----------
    centered : float
        Centered voltage [V].
    max_area : float
        Area at full_scale_voltage from the offset [m^2] (0.002 m × 0.005 m, App. B.2 l.13).
    leak_area : float
        Area at the offset [m^2] (2e-7 m^2, App. B.2 l.12).
    full_scale_voltage : float
        Voltage span at which max_area is reached [V].

    Returns
    -------
    float
        Port area [m^2].
    """
    return max_area * abs(centered) / full_scale_voltage + leak_area


@compiled
def polynomial_area(
    centered: float,
    negative_coefficients,
    positive_coefficients,
) -> float:
    """Equivalent orifice area from the fitted 4th-order polynomials (thesis 4.2.3, Fig. 24).

    One polynomial per side of the offset; the result is the product cd·A and is clipped
    at zero (App. B.1.2 Port_2 lines 42–50).

    Parameters
    ----------
    centered : float
        Centered voltage [V].
    negative_coefficients, positive_coefficients : array of 5 float
        Coefficients, highest power first [m^2/V^n].

    Returns
    -------
    float
        Equivalent area [m^2], >= 0.
    """
    coefficients = positive_coefficients if centered > 0.0 else negative_coefficients
    area = 0.0
    for index in range(coefficients.shape[0]):
        area = area * centered + coefficients[index]
    return max(area, 0.0)


@compiled
def input_pressure(
    centered: float,
    supply_pressure: float,
    exhaust_pressure: float,
    high_pressure_cutoff: float,
    low_pressure_cutoff: float,
) -> float:
    """Pressure seen at a valve port in the underlapped model (eq 4.2.7–4.2.11).

    P = y_off + C_scale·tanh(K·(u_c - x_off)) with y_off = (Ps + Pe)/2,
    x_off = (C_HP + C_LP)/2, C_scale = sign(C_HP - C_LP)·(Ps - Pe)/2 and
    K = 2π/|C_LP - C_HP|. Beyond the cutoffs the port sees supply or exhaust; between them
    it sees a blend, which makes chamber pressures settle between the two (Fig. 23).

    Parameters
    ----------
    centered : float
        Centered voltage [V].
    supply_pressure, exhaust_pressure : float
        Absolute pressures [Pa].
    high_pressure_cutoff, low_pressure_cutoff : float
        Centered voltages where the curve leaves supply and exhaust pressure [V]
        (port 2: 1.25 V and -0.75 V, App. B.1.2 Port_2 lines 21–22).

    Returns
    -------
    float
        Port input pressure [Pa].
    """
    mean = 0.5 * (supply_pressure + exhaust_pressure)
    centre = 0.5 * (high_pressure_cutoff + low_pressure_cutoff)
    half_span = 0.5 * (supply_pressure - exhaust_pressure)
    scale = half_span if high_pressure_cutoff > low_pressure_cutoff else -half_span
    gain = 2.0 * math.pi / abs(low_pressure_cutoff - high_pressure_cutoff)
    return mean + scale * math.tanh(gain * (centered - centre))
