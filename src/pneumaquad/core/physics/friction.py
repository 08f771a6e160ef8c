"""Seal friction models of the cylinder (thesis 4.2.2) and a sticking LuGre model.

All forces oppose motion: a positive friction force acts against a positive velocity.
The thesis's models (Coulomb, Coulomb-viscous, viscous, Stribeck-tanh) are force laws of
velocity; Stribeck-tanh is zero at zero velocity, so a slowly moving piston creeps instead
of sticking (thesis 4.4.2). LuGre (Canudas de Wit et al., 1995) adds a bristle deflection
state z that holds the piston still below breakaway.
"""

import math

from pneumaquad.core.jit import compiled

FRICTION_VISCOUS = 0
FRICTION_COULOMB = 1
FRICTION_COULOMB_VISCOUS = 2
FRICTION_STRIBECK_TANH = 3
FRICTION_LUGRE = 4

#: exp(-x) is exactly 0.0 in double precision beyond this [-] (the smallest subnormal is
#: exp(-745.13)).
EXP_UNDERFLOW = 746.0

#: tanh(x) is exactly ±1.0 in double precision beyond this [-] (from x = 19.06 on; the
#: C library returns ±1 outright above 22).
TANH_SATURATION = 22.0


@compiled
def saturating_tanh(x: float) -> float:
    """tanh(x) [-], returning ±1.0 without the call where it is exactly that
    (|x| > :data:`TANH_SATURATION`): the same value, bit for bit, cheaper for a piston
    that moves."""
    if x > TANH_SATURATION:
        return 1.0
    if x < -TANH_SATURATION:
        return -1.0
    return math.tanh(x)


def stribeck_flat_velocity(stribeck_velocity: float, stribeck_exponent: float) -> float:
    """Speed [m/s] below which the Stribeck curve is exactly Fs (eq 4.2.6).

    Below vS·2^(-56/i), (|v|/vS)^i is under 2^-55 (with the rounding of the division
    and the power), and exp(-x) of any x under 2^-54 rounds to exactly 1.0, so g(v) is
    Fc + (Fs - Fc) bit for bit: a caller that compares |v| with this once-computed speed
    skips the power and the exponential for a piston at rest (most of a held position).
    """
    return stribeck_velocity * 2.0 ** (-56.0 / stribeck_exponent)


@compiled
def stribeck_tanh_force_and_slope_of_curve(
    curve: float, velocity: float, viscous_coefficient: float, tanh_coefficient: float
) -> tuple[float, float]:
    """:func:`stribeck_tanh_force_and_slope` from the Stribeck curve's value g(v) [N]."""
    t = saturating_tanh(tanh_coefficient * velocity)
    force = curve * t + viscous_coefficient * velocity
    slope = curve * tanh_coefficient * (1.0 - t) * (1.0 + t) + viscous_coefficient
    return force, max(slope, 0.0)


@compiled
def stribeck_curve(
    velocity: float,
    static_force: float,
    coulomb_force: float,
    stribeck_velocity: float,
    stribeck_exponent: float,
) -> float:
    """Magnitude of dry friction g(v) = Fc + (Fs - Fc)·exp(-(|v|/vS)^i) (eq 4.2.6).

    Parameters
    ----------
    velocity : float
        Piston velocity [m/s].
    static_force, coulomb_force : float
        Fs and Fc [N].
    stribeck_velocity : float
        vS [m/s].
    stribeck_exponent : float
        i [-].

    Returns
    -------
    float
        g(v) [N], between Fc and Fs.
    """
    exponent = (abs(velocity) / stribeck_velocity) ** stribeck_exponent
    if exponent > EXP_UNDERFLOW:  # exp(-exponent) is exactly 0.0: skip it
        return coulomb_force
    return coulomb_force + (static_force - coulomb_force) * math.exp(-exponent)


@compiled
def stribeck_tanh_force(
    velocity: float,
    static_force: float,
    coulomb_force: float,
    viscous_coefficient: float,
    stribeck_velocity: float,
    stribeck_exponent: float,
    tanh_coefficient: float,
) -> float:
    """Stribeck-tanh friction of eq 4.2.6: g(v)·tanh(k_tanh·v) + Cv·v.

    Parameters
    ----------
    velocity : float
        v [m/s].
    static_force, coulomb_force : float
        Fs, Fc [N] (4.5 lbf and 3 lbf in the thesis, App. B.1.1 l.61–63).
    viscous_coefficient : float
        Cv [N s/m].
    stribeck_velocity : float
        vS [m/s].
    stribeck_exponent : float
        i [-].
    tanh_coefficient : float
        k_tanh [s/m].

    Returns
    -------
    float
        Friction force [N] (:func:`stribeck_tanh_force_and_slope`'s).
    """
    return stribeck_tanh_force_and_slope(velocity, static_force, coulomb_force,
                                         viscous_coefficient, stribeck_velocity,
                                         stribeck_exponent, tanh_coefficient)[0]


@compiled
def stribeck_tanh_force_and_slope(
    velocity: float,
    static_force: float,
    coulomb_force: float,
    viscous_coefficient: float,
    stribeck_velocity: float,
    stribeck_exponent: float,
    tanh_coefficient: float,
) -> tuple[float, float]:
    """Stribeck-tanh friction of eq 4.2.6 and its dissipative slope, sharing one Stribeck
    curve and one tanh: the one form of the law (:func:`stribeck_tanh_force` and
    :func:`friction_damping` take their part of it).

    The force is g(v)·tanh(k_tanh·v) + Cv·v; the slope is
    g(v)·k_tanh·(1 - tanh²(k_tanh·v)) + Cv clipped at zero, with 1 - tanh² written as
    (1 - t)(1 + t), which is exact to rounding where t is close to ±1 (the falling branch
    of the Stribeck curve left explicit). One exponential, one power and one tanh for
    both, and for a moving piston neither the exponential nor the tanh where their values
    are exactly 0 and ±1 (:func:`stribeck_curve`, :func:`saturating_tanh`).

    Parameters
    ----------
    velocity : float
        v [m/s].
    static_force, coulomb_force : float
        Fs, Fc [N].
    viscous_coefficient : float
        Cv [N s/m].
    stribeck_velocity : float
        vS [m/s].
    stribeck_exponent : float
        i [-].
    tanh_coefficient : float
        k_tanh [s/m].

    Returns
    -------
    tuple of float
        Friction force [N] and dF/dv clipped at zero [N s/m].
    """
    g = stribeck_curve(velocity, static_force, coulomb_force, stribeck_velocity, stribeck_exponent)
    return stribeck_tanh_force_and_slope_of_curve(g, velocity, viscous_coefficient,
                                                  tanh_coefficient)


@compiled
def lugre_bristle_rate(
    velocity: float, deflection: float, bristle_stiffness: float, stribeck_force: float
) -> float:
    """LuGre bristle dynamics dz/dt = v - sigma0·|v|·z / g(v).

    Parameters
    ----------
    velocity : float
        v [m/s].
    deflection : float
        Bristle deflection z [m].
    bristle_stiffness : float
        sigma0 [N/m].
    stribeck_force : float
        g(v) of :func:`stribeck_curve` [N].

    Returns
    -------
    float
        dz/dt [m/s].
    """
    return velocity - bristle_stiffness * abs(velocity) * deflection / stribeck_force


@compiled
def lugre_bristle_update(
    deflection: float,
    velocity: float,
    time_step: float,
    bristle_stiffness: float,
    stribeck_force: float,
) -> float:
    """Advance the bristle deflection over a step with the velocity held constant.

    With v fixed, dz/dt = v - sigma0·|v|·z/g is linear in z, so the update is exact:
    z(h) = z_ss + (z0 - z_ss)·exp(-sigma0·|v|·h/g), z_ss = g·sign(v)/sigma0. It is
    stable for any step, unlike an explicit step of this stiff equation.

    Parameters
    ----------
    deflection : float
        z at the start of the step [m].
    velocity : float
        v over the step [m/s].
    time_step : float
        h [s].
    bristle_stiffness : float
        sigma0 [N/m].
    stribeck_force : float
        g(v) [N].

    Returns
    -------
    float
        z at the end of the step [m].
    """
    if velocity == 0.0:
        return deflection
    steady = stribeck_force / bristle_stiffness
    if velocity < 0.0:
        steady = -steady
    decay = math.exp(-bristle_stiffness * abs(velocity) * time_step / stribeck_force)
    return steady + (deflection - steady) * decay


@compiled
def friction_force(
    model: int,
    velocity: float,
    deflection: float,
    static_force: float,
    coulomb_force: float,
    viscous_coefficient: float,
    stribeck_velocity: float,
    stribeck_exponent: float,
    tanh_coefficient: float,
    damping_coefficient: float,
    bristle_stiffness: float,
    bristle_damping: float,
) -> float:
    """Friction force of the selected model at a velocity (and bristle state).

    Models: FRICTION_VISCOUS: b·v (eq 4.2.5); FRICTION_COULOMB: Fc·sign(v) (eq 4.2.1,
    sliding branch); FRICTION_COULOMB_VISCOUS: Fc·sign(v) + Cv·v (eq 4.2.4, sliding
    branch; the thesis prints -Cv·v, a sign slip: viscous friction opposes motion);
    FRICTION_STRIBECK_TANH: eq 4.2.6; FRICTION_LUGRE: sigma0·z + sigma1·dz/dt + Cv·v.

    Parameters
    ----------
    model : int
        One of the FRICTION_* codes.
    velocity : float
        v [m/s].
    deflection : float
        LuGre bristle deflection z [m] (ignored by the other models).
    static_force, coulomb_force : float
        Fs, Fc [N].
    viscous_coefficient : float
        Cv [N s/m].
    stribeck_velocity, stribeck_exponent, tanh_coefficient : float
        vS [m/s], i [-], k_tanh [s/m].
    damping_coefficient : float
        b of the viscous model [N s/m] (70 N s/m, App. B.1.1 l.57).
    bristle_stiffness, bristle_damping : float
        LuGre sigma0 [N/m] and sigma1 [N s/m].

    Returns
    -------
    float
        Friction force [N], opposing positive velocity when positive.
    """
    if model == FRICTION_VISCOUS:
        return damping_coefficient * velocity
    if model == FRICTION_STRIBECK_TANH:
        return stribeck_tanh_force(
            velocity,
            static_force,
            coulomb_force,
            viscous_coefficient,
            stribeck_velocity,
            stribeck_exponent,
            tanh_coefficient,
        )
    if model == FRICTION_LUGRE:
        g = stribeck_curve(
            velocity, static_force, coulomb_force, stribeck_velocity, stribeck_exponent
        )
        rate = lugre_bristle_rate(velocity, deflection, bristle_stiffness, g)
        return (
            bristle_stiffness * deflection
            + bristle_damping * rate
            + (viscous_coefficient * velocity)
        )
    sign = 0.0
    if velocity > 0.0:
        sign = 1.0
    elif velocity < 0.0:
        sign = -1.0
    if model == FRICTION_COULOMB:
        return coulomb_force * sign
    return coulomb_force * sign + viscous_coefficient * velocity


@compiled
def friction_damping(
    model: int,
    velocity: float,
    static_force: float,
    coulomb_force: float,
    viscous_coefficient: float,
    stribeck_velocity: float,
    stribeck_exponent: float,
    tanh_coefficient: float,
    damping_coefficient: float,
    bristle_stiffness: float,
    bristle_damping: float,
    deflection: float,
) -> float:
    """Non-negative slope dF/dv of the friction law, for a linearly implicit velocity step.

    Only the dissipative (positive) part is returned; the falling branch of the Stribeck
    curve is left explicit. For the set-valued Coulomb models this is the viscous part.

    Returns
    -------
    float
        dF/dv clipped at zero [N s/m].
    """
    if model == FRICTION_VISCOUS:
        return damping_coefficient
    if model == FRICTION_STRIBECK_TANH:
        return stribeck_tanh_force_and_slope(velocity, static_force, coulomb_force,
                                             viscous_coefficient, stribeck_velocity,
                                             stribeck_exponent, tanh_coefficient)[1]
    if model == FRICTION_LUGRE:
        g = stribeck_curve(
            velocity, static_force, coulomb_force, stribeck_velocity, stribeck_exponent
        )
        along = deflection if velocity >= 0.0 else -deflection
        return max(bristle_damping * (1.0 - bristle_stiffness * along / g), 0.0) + (
            viscous_coefficient
        )
    return viscous_coefficient if model == FRICTION_COULOMB_VISCOUS else 0.0
