"""Friction identification: recovery of known simulator parameters from noisy steps.

Measured on the data of conftest (seeded): F_S from the median of the clear stiction
peaks -5.1 % (the Stribeck-tanh law's own maximum lies ~4 % below F_S, and the filters
round the peak), F_C +0.01 %, C_V -0.10 %. Tolerances: the brief's 10 % / 10 % / 25 %.
"""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.identification import (
    FrictionPoints,
    IdentificationError,
    fit_coulomb_viscous,
    fit_stribeck_tanh,
    kinetic_friction_points,
    stiction_from_step,
    stribeck_tanh_curve,
    summarize_stiction,
)

from .conftest import (
    FAST_STEPS,
    SLOW_STEPS,
    TRUE_COULOMB,
    TRUE_STATIC,
    TRUE_VISCOUS,
    step_recording,
)


def relative_error(estimate: float, truth: float) -> float:
    return (estimate - truth) / truth


def test_fit_coulomb_viscous_on_noisy_points() -> None:
    rng = np.random.default_rng(7)
    velocity = np.concatenate([rng.uniform(-0.4, -0.02, 300), rng.uniform(0.02, 0.4, 300)])
    friction = 12.0 * np.sign(velocity) + 80.0 * velocity + rng.normal(0.0, 0.5, velocity.size)
    fit = fit_coulomb_viscous(velocity, friction)
    assert fit.value("coulomb_force") == pytest.approx(12.0, abs=4 * 0.05)
    assert fit.value("viscous_coefficient") == pytest.approx(80.0, abs=1.0)
    # the standard errors are consistent with the scatter (truth within 4 sigma)
    for key, truth in (("coulomb_force [N]", 12.0), ("viscous_coefficient [N*s/m]", 80.0)):
        assert abs(fit.parameters[key] - truth) < 4 * fit.standard_errors[key]
    assert fit.n_points == 600 and fit.r_squared > 0.99
    assert fit.residual_rms == pytest.approx(0.5, rel=0.15)


def test_fit_coulomb_viscous_needs_two_velocity_levels() -> None:
    with pytest.raises(IdentificationError, match="separate"):
        fit_coulomb_viscous([0.1, 0.1, 0.1], [5.0, 5.1, 4.9])


def test_fit_stribeck_tanh_recovers_the_law() -> None:
    truth = {
        "static_force": 20.0,
        "coulomb_force": 13.3,
        "viscous_coefficient": 88.0,
        "stribeck_velocity": 0.0025,
        "stribeck_exponent": 5.0,
        "tanh_coefficient": 1575.0,
    }
    rng = np.random.default_rng(3)
    speeds = np.concatenate([np.geomspace(2e-4, 0.3, 400)])
    velocity = np.concatenate([speeds, -speeds])
    friction = stribeck_tanh_curve(velocity, truth) + rng.normal(0.0, 0.2, velocity.size)
    initial = {
        **truth,
        "static_force": 16.0,
        "coulomb_force": 10.0,
        "viscous_coefficient": 60.0,
        "stribeck_velocity": 0.005,
    }
    fit = fit_stribeck_tanh(velocity, friction, initial, fixed=("stribeck_exponent",))
    for name in ("static_force", "coulomb_force", "viscous_coefficient"):
        assert fit.value(name) == pytest.approx(truth[name], rel=0.03), name
    assert fit.value("stribeck_velocity") == pytest.approx(truth["stribeck_velocity"], rel=0.1)
    assert fit.value("tanh_coefficient") == pytest.approx(truth["tanh_coefficient"], rel=0.2)
    assert fit.standard_errors["stribeck_exponent [-]"] == 0.0
    assert fit.r_squared > 0.99


def test_fit_stribeck_tanh_checks_its_inputs() -> None:
    velocity = np.linspace(-0.2, 0.2, 20)
    with pytest.raises(IdentificationError, match="missing"):
        fit_stribeck_tanh(velocity, velocity, {"static_force": 1.0})


def test_stiction_from_one_slow_step(friction_rig) -> None:
    recording = step_recording(friction_rig, 5.6, seed=11)
    estimate = stiction_from_step(recording, friction_rig)
    assert estimate.direction == 1 and estimate.clear_peak
    assert estimate.step_voltage == pytest.approx(5.6)
    assert abs(relative_error(estimate.static_force, TRUE_STATIC)) < 0.10
    assert 0.5 < estimate.onset_time < 0.5 + 1.0


def test_no_motion_is_reported(friction_rig) -> None:
    recording = step_recording(friction_rig, 5.25, seed=12, duration=1.0)
    with pytest.raises(IdentificationError, match="does not move"):
        stiction_from_step(recording, friction_rig)
    del recording["command [V]"]
    with pytest.raises(IdentificationError, match="command"):
        stiction_from_step(recording, friction_rig)


def test_friction_recovery_from_simulated_steps(friction_rig, friction_steps) -> None:
    estimates = [stiction_from_step(friction_steps[u], friction_rig) for u in SLOW_STEPS]
    assert all(estimate.clear_peak for estimate in estimates)
    stiction = summarize_stiction(estimates)
    points = FrictionPoints.concatenate(
        kinetic_friction_points(recording, friction_rig) for recording in friction_steps.values()
    )
    sliding = fit_coulomb_viscous(points.velocity, points.friction)
    rows = [
        ("static_force [N]", stiction.value("static_force"), TRUE_STATIC, 0.10),
        ("coulomb_force [N]", sliding.value("coulomb_force"), TRUE_COULOMB, 0.10),
        ("viscous_coefficient [N*s/m]", sliding.value("viscous_coefficient"), TRUE_VISCOUS, 0.25),
    ]
    print("\nfriction: parameter, recovered, true, error")
    for key, estimate, truth, tolerance in rows:
        error = relative_error(estimate, truth)
        print(f"  {key:30s} {estimate:10.4f} {truth:10.4f} {100 * error:+7.2f} %")
        assert abs(error) < tolerance, key
    for estimate in estimates:
        print(f"  stiction at {estimate.step_voltage} V: {estimate.static_force:.3f} N")
    # the sliding samples cover both directions and a wide velocity range
    assert points.velocity.min() < -0.2 and points.velocity.max() > 0.2
    # fast steps do not resolve the breakaway: flagged, not used
    fast = [stiction_from_step(friction_steps[u], friction_rig) for u in (3.0, 8.0)]
    assert not any(estimate.clear_peak for estimate in fast)


def test_end_stop_samples_are_excluded(friction_rig, friction_steps) -> None:
    """With the end-stop margin the fit is unbiased; without it the stop reaction leaks in.

    A looser acceleration limit (5 m/s^2) lets samples of the end-stop impacts through;
    the 2 mm margin removes them.
    """
    fits = {}
    for margin in (0.0, 0.002):
        points = FrictionPoints.concatenate(
            kinetic_friction_points(
                friction_steps[u], friction_rig, max_acceleration=5.0, end_margin=margin
            )
            for u in FAST_STEPS
        )
        if margin > 0:
            stroke = friction_rig.actuator.cylinder.stroke
            assert np.all((points.position >= margin) & (points.position <= stroke - margin))
        fits[margin] = fit_coulomb_viscous(points.velocity, points.friction)
    biased, clean = fits[0.0], fits[0.002]
    print("\nend stops: margin, F_C [N], C_V [N*s/m], R^2")
    for margin, fit in fits.items():
        print(
            f"  {margin * 1000:.0f} mm {fit.value('coulomb_force'):8.3f} "
            f"{fit.value('viscous_coefficient'):8.3f} {fit.r_squared:.4f}"
        )
    assert abs(relative_error(clean.value("coulomb_force"), TRUE_COULOMB)) < 0.01
    assert abs(relative_error(clean.value("viscous_coefficient"), TRUE_VISCOUS)) < 0.02
    assert abs(relative_error(biased.value("coulomb_force"), TRUE_COULOMB)) > 0.03
    assert biased.r_squared < clean.r_squared - 0.1
