"""Equivalent-area and input-pressure fitting for the proportional valve.

Reimplements the procedure of Daepp (2011), section 4.2.3 and Appendix B.2
("Equivalent Area Curve Fitting Tools", thesis text line ~1746): hand-tuned
discharge coefficients at 19 centred valve voltages are multiplied by a linear
geometric orifice-area model, and each side of the valve offset is fitted with
a fourth-order polynomial. The input-pressure curve is the offset, scaled tanh
of eqs. (4.2.7)-(4.2.11).

All voltages here are *centred* (adjusted) voltages, i.e. the command minus
the 5.25 V valve offset, in [V]. Script line numbers ``l.N`` refer to the
numbered MATLAB listing in App. B.2.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from pneumaquad.core.physics.valve import input_pressure as port_input_pressure

#: Valve offset voltage the centred voltages are measured from [V].
VALVE_OFFSET_VOLTAGE = 5.25

_STEPS = np.array([0.15, 0.35, 0.55, 0.75, 1.25, 1.75, 2.75, 3.75, 4.75])

#: Centred valve voltages of the tuning steps [V] (App. B.2 l.5-7): nine negative,
#: zero, nine positive; index 9 is the valve offset.
THESIS_VOLTAGES: np.ndarray = np.concatenate([-_STEPS[::-1], [0.0], _STEPS])

#: Hand-tuned discharge coefficients of port 1 [-] (App. B.2 l.11, 50 psig supply).
PORT1_DISCHARGE_COEFFICIENTS: np.ndarray = np.array(
    [0.08, 0.10, 0.13, 0.15, 0.15, 0.15, 0.15, 0.12, 0.13, 0.11,
     0.07, 0.06, 0.10, 0.12, 0.165, 0.175, 0.16, 0.14, 0.11]
)  # fmt: skip

#: Hand-tuned discharge coefficients of port 2 [-] (App. B.2 l.10, 50 psig supply).
PORT2_DISCHARGE_COEFFICIENTS: np.ndarray = np.array(
    [0.115, 0.14, 0.18, 0.20, 0.20, 0.19, 0.18, 0.17, 0.19, 0.09,
     0.06, 0.05, 0.06, 0.09, 0.125, 0.135, 0.12, 0.09, 0.075]
)  # fmt: skip

#: Full-open orifice area of the geometric model, 2 mm x 5 mm [m^2] (App. B.2 l.13).
MAX_ORIFICE_AREA = 0.002 * 0.005
#: Centred voltage at which the geometric model reaches ``MAX_ORIFICE_AREA`` [V] (l.13).
FULL_SCALE_VOLTAGE = 5.0
#: Leak area added at the valve offset, x = 0 [m^2] (App. B.2 l.12).
LEAK_AREA = 2e-7

#: Polynomial order of each side of the equivalent-area curve (App. B.2 l.26-30).
POLYNOMIAL_ORDER = 4

#: Port 2 tanh cutoffs used in the Simulink model [V] (App. B.1.2 Port_2 l.21-22).
PORT2_HIGH_CUTOFF = 1.25
PORT2_LOW_CUTOFF = -0.75


def geometric_area(
    voltages: ArrayLike,
    max_area: float = MAX_ORIFICE_AREA,
    full_scale_voltage: float = FULL_SCALE_VOLTAGE,
) -> np.ndarray:
    """Linear geometric orifice area ``|max_area / full_scale_voltage * x|`` (App. B.2 l.13).

    Parameters
    ----------
    voltages
        Centred valve voltages x [V].
    max_area
        Orifice area at ``|x| = full_scale_voltage`` [m^2].
    full_scale_voltage
        Centred voltage of the fully open valve [V].

    Returns
    -------
    np.ndarray
        Geometric orifice area [m^2].
    """
    x = np.asarray(voltages, dtype=float)
    return np.abs(max_area / full_scale_voltage * x)


def equivalent_areas(
    discharge_coefficients: ArrayLike,
    voltages: ArrayLike,
    max_area: float = MAX_ORIFICE_AREA,
    full_scale_voltage: float = FULL_SCALE_VOLTAGE,
    leak_area: float = LEAK_AREA,
) -> np.ndarray:
    """Equivalent orifice areas ``Aeq = cd * (A_geom + A_leak)`` (App. B.2 l.12-16).

    The leak area is added only at the valve offset (``x == 0``), as in the
    thesis script, where ``AL`` is zero except at index 10 (x = 0).

    Parameters
    ----------
    discharge_coefficients
        Discharge coefficient cd at each voltage [-].
    voltages
        Centred valve voltages x [V], same shape as ``discharge_coefficients``.
    max_area
        Full-open geometric orifice area [m^2].
    full_scale_voltage
        Centred voltage of the fully open valve [V].
    leak_area
        Leak area at ``x == 0`` [m^2].

    Returns
    -------
    np.ndarray
        Equivalent orifice areas [m^2].
    """
    cd = np.asarray(discharge_coefficients, dtype=float)
    x = np.asarray(voltages, dtype=float)
    if cd.shape != x.shape:
        raise ValueError(f"shape mismatch: cd {cd.shape} vs voltages {x.shape}")
    leak = np.where(x == 0.0, leak_area, 0.0)
    return cd * (geometric_area(x, max_area, full_scale_voltage) + leak)


def fit_equivalent_area_polynomials(
    voltages: ArrayLike, areas: ArrayLike, order: int = POLYNOMIAL_ORDER
) -> tuple[np.ndarray, np.ndarray]:
    """Fit one polynomial per side of the valve offset (App. B.2 l.18-30).

    Each side is an ordinary least-squares fit (``np.polyfit``) of the points
    with ``x <= 0`` (negative side) or ``x >= 0`` (positive side); the point at
    ``x == 0`` belongs to both, so the two curves meet near the leak area.

    Parameters
    ----------
    voltages
        Centred valve voltages x [V].
    areas
        Equivalent orifice areas at those voltages [m^2].
    order
        Polynomial order of each side.

    Returns
    -------
    tuple[np.ndarray, np.ndarray]
        ``(negative, positive)`` coefficients [m^2 / V^k], highest power first
        (``np.polyval`` order).
    """
    x = np.asarray(voltages, dtype=float)
    a = np.asarray(areas, dtype=float)
    if x.shape != a.shape or x.ndim != 1:
        raise ValueError("voltages and areas must be 1-D arrays of equal length")
    negative = x <= 0.0
    positive = x >= 0.0
    for side, mask in (("negative", negative), ("positive", positive)):
        if np.count_nonzero(mask) <= order:
            raise ValueError(f"need more than {order} points on the {side} side")
    return np.polyfit(x[negative], a[negative], order), np.polyfit(x[positive], a[positive], order)


def thesis_port_polynomials(port: int) -> tuple[np.ndarray, np.ndarray]:
    """Run the App. B.2 procedure on the printed data of one valve port.

    Parameters
    ----------
    port
        Valve port, 1 or 2.

    Returns
    -------
    tuple[np.ndarray, np.ndarray]
        ``(negative, positive)`` coefficients [m^2 / V^k], highest power first.
        For port 2 these round to the coefficients printed in App. B.1.2
        (Port_2 l.44 and l.48).
    """
    coefficients = {1: PORT1_DISCHARGE_COEFFICIENTS, 2: PORT2_DISCHARGE_COEFFICIENTS}
    if port not in coefficients:
        raise ValueError(f"port must be 1 or 2, got {port!r}")
    areas = equivalent_areas(coefficients[port], THESIS_VOLTAGES)
    return fit_equivalent_area_polynomials(THESIS_VOLTAGES, areas)


def evaluate_equivalent_area(
    negative: ArrayLike, positive: ArrayLike, centered_voltage: ArrayLike
) -> np.ndarray:
    """Evaluate the two-sided equivalent-area curve, clipped at zero.

    Follows App. B.1.2 Port_2 l.42-50: the positive polynomial for ``x > 0``
    and the negative one otherwise.

    Parameters
    ----------
    negative, positive
        Polynomial coefficients, highest power first [m^2 / V^k].
    centered_voltage
        Centred valve voltage x [V]; scalar or array.

    Returns
    -------
    np.ndarray
        Equivalent orifice area [m^2], ``>= 0``, same shape as the input.
    """
    x = np.asarray(centered_voltage, dtype=float)
    area = np.where(x > 0.0, np.polyval(positive, x), np.polyval(negative, x))
    return np.maximum(area, 0.0)


def input_pressure(
    centered_voltage: ArrayLike,
    supply_pressure: float,
    exhaust_pressure: float,
    high_cutoff: float,
    low_cutoff: float,
) -> np.ndarray:
    """Effective valve input pressure, eqs. (4.2.7)-(4.2.11), for arrays of voltages.

    The array form of :func:`pneumaquad.core.physics.valve.input_pressure` (the one
    implementation, compiled, that the kernel uses), evaluated element by element:
    ``P = y_off + C_scale * tanh(K * (u - x_off))`` with ``y_off = (Ps + Pe)/2``,
    ``x_off = (Chp + Clp)/2``, ``C_scale = sign(Chp - Clp) (Ps - Pe)/2`` and
    ``K = 2 pi / |Clp - Chp|`` (also App. B.1.2 Port_2 l.30-35). The fit of the cutoffs
    to measured pressures is :func:`pneumaquad.identification.fit_input_pressure_curve`.

    Parameters
    ----------
    centered_voltage
        Centred valve voltage u [V]; scalar or array.
    supply_pressure, exhaust_pressure
        Supply and exhaust pressures Ps, Pe [Pa].
    high_cutoff, low_cutoff
        Voltages Chp, Clp at which the curve leaves the supply and the exhaust
        pressure plateaus [V]; must differ.

    Returns
    -------
    np.ndarray
        Input pressure [Pa], same shape as ``centered_voltage``.
    """
    if high_cutoff == low_cutoff:
        raise ValueError("high and low cutoffs must differ")
    return _input_pressure_array(np.asarray(centered_voltage, dtype=float),
                                 float(supply_pressure), float(exhaust_pressure),
                                 float(high_cutoff), float(low_cutoff))


_input_pressure_array = np.vectorize(port_input_pressure, otypes=[float])
