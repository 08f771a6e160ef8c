"""The single-DoF rig against physics stated independently of the implementation.

Mass bookkeeping (eq 4.1.7), fixed-piston steady pressures (eq 4.2.7), the open-loop
stiction peak (4.2.3, 4.3), sticking at closed-loop reversals (4.4.2), the fixed-step
integrator against the adaptive reference, and the PID controller.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import (
    IN,
    LBF,
    R_AIR,
    TS,
    cap_volume,
    gravity_along_rod,
    rig_setup,
    rod_volume,
    run_rig,
)
from pneumaquad.core.control.pid import (
    new_pid_state,
    pid_gains,
    pid_update,
)
from pneumaquad.core.physics.valve import input_pressure
from pneumaquad.params import ParameterError
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig


def thesis_step(setup, step_voltage: float, step_time: float = 5.0, duration: float = 10.0):
    valve = setup.actuator.valve
    return signals.thesis_step_command(
        step_voltage,
        valve.offset_voltage,
        valve.min_voltage,
        valve.max_voltage,
        setup.simulation.control_step,
        step_time=step_time,
        duration=duration,
    )


def varied_commands(setup, seconds: float, seed: int, hold: float = 0.1) -> np.ndarray:
    dt = setup.simulation.control_step
    rng = np.random.default_rng(seed)
    per = round(hold / dt)
    levels = rng.uniform(0.0, 10.0, size=round(seconds / hold))
    levels[::3] = rng.uniform(4.5, 6.0, size=levels[::3].shape)  # near the offset too
    return np.repeat(levels, per)


def longest_run(mask: np.ndarray) -> int:
    best = current = 0
    for value in mask:
        current = current + 1 if value else 0
        best = max(best, current)
    return best


# --- mass bookkeeping ------------------------------------------------------------------


@pytest.mark.parametrize("valve", ["underlapped", "simple"])
def test_recorded_flows_integrate_to_chamber_masses(valve: str) -> None:
    setup = rig_setup(f'valve.model="{valve}"')
    dt = setup.simulation.control_step
    rec = run_rig(setup, varied_commands(setup, 3.0, seed=11), closed_loop=False)
    rig = setup.rig
    x0 = rig.initial_position
    initial = {
        "cap": rig.initial_cap_pressure * cap_volume(setup, x0) / (R_AIR * TS),
        "rod": rig.initial_rod_pressure * rod_volume(setup, x0) / (R_AIR * TS),
    }
    x = rec["position [m]"]
    volumes = {"cap": cap_volume(setup, x), "rod": rod_volume(setup, x)}
    assert np.ptp(x) > 0.02  # the piston really travelled
    for side in ("cap", "rod"):
        mass = rec[f"{side} mass [kg]"]
        integrated = initial[side] + np.cumsum(rec[f"{side} mass flow [kg/s]"] * dt)
        np.testing.assert_allclose(mass, integrated, rtol=1e-9)
        assert np.ptp(mass) > 0.5 * mass.max()  # filled and emptied substantially
        # eq 4.1.7: m = P·V/(R·T) from the recorded pressure and temperature
        ideal_gas = (
            rec[f"{side} pressure [Pa]"] * volumes[side] / (R_AIR * rec[f"{side} temperature [K]"])
        )
        np.testing.assert_allclose(mass, ideal_gas, rtol=1e-9)
    consumed = np.cumsum(rec["supply mass flow [kg/s]"] * dt)
    np.testing.assert_allclose(rec["air consumed [kg]"], consumed, rtol=1e-9)
    assert np.all(np.diff(rec["air consumed [kg]"]) >= 0.0)


def test_tank_pressure_drop_matches_air_consumed() -> None:
    setup = rig_setup(
        'supply.model="tank"', 'supply.tank_volume="0.05 L"',
        'supply.tank_initial_pressure="5 bara"',
    )
    supply = setup.actuator.supply
    rec = run_rig(setup, varied_commands(setup, 3.0, seed=5), closed_loop=False)
    consumed = rec["air consumed [kg]"]
    tank = supply.tank_initial_pressure - (
        R_AIR * supply.tank_temperature * consumed / supply.tank_volume
    )
    np.testing.assert_allclose(rec["tank pressure [Pa]"], tank, rtol=1e-12)
    # the regulator passes the set point, or the tank pressure once that is lower
    regulated = np.minimum(supply.supply_pressure, tank)
    np.testing.assert_allclose(rec["supply pressure [Pa]"], regulated, rtol=1e-12)
    assert tank[-1] < supply.supply_pressure  # the run drained the tank below the set point
    assert rec["cap pressure [Pa]"].max() <= supply.supply_pressure * (1 + 1e-9)


# --- fixed piston: steady pressures on the input-pressure curve ------------------------


@pytest.mark.parametrize("centered", [0.3, -0.4])
def test_spacer_pressures_settle_on_input_pressure_curve(centered: float) -> None:
    setup = rig_setup("rig.spacer=true")
    act = setup.actuator
    valve = act.valve
    assert valve.cap_port == 2
    cap_port, rod_port = valve.port2, valve.port1
    ps, pe = act.supply.supply_pressure, act.supply.exhaust_pressure
    seconds = 6.0
    command = np.full(
        round(seconds / setup.simulation.control_step), valve.offset_voltage + centered
    )
    rec = run_rig(setup, command, closed_loop=False)
    np.testing.assert_array_equal(rec["position [m]"], act.cylinder.stroke)
    expected_cap = input_pressure(
        centered, ps, pe, cap_port.high_pressure_cutoff, cap_port.low_pressure_cutoff
    )
    expected_rod = input_pressure(
        centered, ps, pe, rod_port.high_pressure_cutoff, rod_port.low_pressure_cutoff
    )
    # strictly between exhaust and supply: the underlap blends both (Fig. 23)
    for p in (expected_cap, expected_rod):
        assert pe + 0.01 * (ps - pe) < p < ps - 0.01 * (ps - pe)
    assert rec["cap pressure [Pa]"][-1] == pytest.approx(expected_cap, rel=5e-3)
    assert rec["rod pressure [Pa]"][-1] == pytest.approx(expected_rod, rel=5e-3)
    # settled: no drift over the last second
    last = slice(-1000, None)
    assert np.ptp(rec["cap pressure [Pa]"][last]) < 1e-3 * ps
    assert np.ptp(rec["rod pressure [Pa]"][last]) < 1e-3 * ps


# --- open-loop step: the stiction peak --------------------------------------------------


def stiction_peak(setup, step_voltage: float = 6.0):
    """Run the thesis step protocol and locate breakaway after the step at 5 s."""
    rec = run_rig(setup, thesis_step(setup, step_voltage), closed_loop=False)
    t, x, v = rec["time [s]"], rec["position [m]"], rec["velocity [m/s]"]
    net = rec["pneumatic force [N]"] + gravity_along_rod(setup)
    after = t > 5.0
    start = np.argmax(after)
    moving = np.argmax(after & (v > 0.01))  # first sample above 10 mm/s
    assert moving > start
    return rec, t, x, v, net, start, moving


@pytest.mark.parametrize(
    ("friction", "orientation"),
    [
        ("stribeck_tanh", "vertical_down"),
        ("stribeck_tanh", "vertical_up"),
        ("lugre", "vertical_down"),
        ("lugre", "horizontal"),
    ],
)
def test_open_loop_step_shows_stiction_peak(friction: str, orientation: str) -> None:
    """Thesis 4.2.3: pressures "ascend ... to reach the stiction peak, then drop" while the
    piston moves. Breakaway needs |F_pneumatic + m·g| >= Fs = 4.5 lbf."""
    setup = rig_setup(f'friction.model="{friction}"', f'rig.orientation="{orientation}"')
    static = setup.actuator.friction.static_force
    assert static == pytest.approx(4.5 * LBF)  # App. B.1.1 l.61
    rec, t, x, v, net, start, moving = stiction_peak(setup)
    stroke = setup.actuator.cylinder.stroke
    # retracted by the opposite saturation before the step (thesis protocol)
    assert abs(x[start]) < 1e-4
    # held until the net force reaches breakaway: no travel, at most a slow creep
    assert np.all(np.abs(x[start:moving] - x[start]) < 5e-5)
    assert np.all(np.abs(v[start : moving - 1]) < 2e-3)
    peak = moving - 5 + np.argmax(net[moving - 5 : moving + 20])
    assert net[peak] >= static
    assert net[peak] < static + 3.0
    # the net force crosses 95 % of breakaway only shortly before motion begins
    assert t[moving] - t[start + np.argmax(net[start:] > 0.95 * static)] < 0.01
    # then the pressures drop while the piston travels: a local maximum before the stop
    arrival = start + np.argmax(x[start:] > stroke - 1e-3)
    travel = slice(peak + 20, arrival)
    assert arrival - peak > 100
    assert net[travel].max() < net[peak] - 1.0
    cap = rec["cap pressure [Pa]"]
    cap_peak = np.argmax(cap[start:arrival]) + start
    assert abs(cap_peak - peak) <= 10
    assert cap[travel].min() < cap[cap_peak] - 0.02 * setup.actuator.supply.supply_pressure
    # the end stop is reached and the pressures then rise to their steady state
    assert x[-1] == pytest.approx(stroke, abs=1e-4)
    assert cap[-1] > cap[cap_peak]


def test_coulomb_viscous_breakaway_from_end_stop_needs_static_friction() -> None:
    setup = rig_setup('friction.model="coulomb_viscous"')
    static = setup.actuator.friction.static_force
    _, _, x, _, net, start, _ = stiction_peak(setup)
    leaves = start + np.argmax(x[start:] > 0.0)
    # eq 4.2.4: at rest the piston holds while |F_cyl| < Fs
    assert net[leaves] >= static - 0.5


@pytest.mark.parametrize("step_voltage", [5.7, 6.0])
def test_piston_resting_on_end_stop_is_at_rest(step_voltage: float) -> None:
    setup = rig_setup()  # thesis defaults: Stribeck-tanh friction, 5 substeps
    stroke = setup.actuator.cylinder.stroke
    rec = run_rig(setup, thesis_step(setup, step_voltage), closed_loop=False)
    settled = rec["time [s]"] > 8.0  # on the extended stop, pressures steady
    x = rec["position [m]"][settled]
    assert x.min() > stroke and np.ptp(x) < 1e-6
    assert np.abs(rec["velocity [m/s]"][settled]).max() < 1e-4
    # the stop carries the load; friction at rest is (near) zero for this law
    assert np.abs(rec["friction force [N]"][settled]).max() < 1.0


def test_zero_moving_mass_is_rejected_or_finite() -> None:
    try:
        setup = rig_setup('rig.load_mass="0 kg"', 'friction.model="coulomb"')
    except ParameterError:
        return
    rec = run_rig(setup, np.full(200, 8.0), closed_loop=False)
    assert np.all(np.isfinite(rec["position [m]"]))


# --- closed-loop reversals: sticking (4.4.2) ----------------------------------------------

SINE_FREQUENCY = 0.2  # Hz
SINE_SECONDS = 10.0
DWELL_SPEED = 5e-5  # m/s


def reversal_dwells(friction: str) -> tuple[list[int], dict[str, np.ndarray], object]:
    """Longest run (samples = ms) with |v| < DWELL_SPEED around each reversal."""
    setup = rig_setup(f'friction.model="{friction}"')
    dt = setup.simulation.control_step
    reference = signals.sine(
        setup.actuator.cylinder.stroke / 2, 0.3 * IN, SINE_FREQUENCY, SINE_SECONDS, dt
    )
    rec = run_rig(setup, reference, closed_loop=True)
    t, v = rec["time [s]"], rec["velocity [m/s]"]
    period = 1.0 / SINE_FREQUENCY
    dwells = []
    for k in range(4):  # reversals of the reference at 1.25, 3.75, 6.25, 8.75 s
        reversal = period / 4 + k * period / 2
        window = (t > reversal - 0.15 * period) & (t < reversal + 0.2 * period)
        dwells.append(longest_run(np.abs(v[window]) < DWELL_SPEED))
    return dwells, rec, setup


def test_lugre_dwells_at_reversals_and_stribeck_tanh_creeps() -> None:
    """0.2 Hz, 0.3 in sine about mid-stroke, 10 s, shipped PID and friction parameters.

    Measured longest |v| < 0.05 mm/s at the four reversals: LuGre 362/754/328/791 ms,
    Stribeck-tanh 33/56/26/27 ms (Coulomb-viscous 364/762/374/802 ms, v == 0 exactly).
    At |v| < 0.2 mm/s: LuGre 389-816 ms, Stribeck-tanh 100-276 ms."""
    lugre, rec, _ = reversal_dwells("lugre")
    stribeck, stribeck_rec, _ = reversal_dwells("stribeck_tanh")
    assert min(lugre) >= 200, lugre
    assert max(stribeck) < 100, stribeck
    # both track the sine comparably well, so the difference is the sticking itself
    for r in (rec, stribeck_rec):
        late = r["time [s]"] > 1.0
        error = r["position [m]"][late] - r["reference position [m]"][late]
        assert np.sqrt(np.mean(error**2)) < 1e-3


def test_coulomb_viscous_sticks_exactly_below_breakaway() -> None:
    dwells, rec, setup = reversal_dwells("coulomb_viscous")
    static = setup.actuator.friction.static_force
    v = rec["velocity [m/s]"]
    net = rec["pneumatic force [N]"] + gravity_along_rod(setup)
    friction = rec["friction force [N]"]
    assert min(dwells) >= 200, dwells
    stuck = v == 0.0
    assert stuck.mean() > 0.3
    held = stuck[1:] & stuck[:-1]
    # at rest the friction balances the net force exactly and stays within Fs (eq 4.2.4)
    np.testing.assert_allclose(friction[1:][held], net[1:][held], atol=1e-6)
    assert np.all(np.abs(net[1:][held]) <= static + 1e-9)
    # a stuck piston stays stuck while the net force is below breakaway (0.5 N margin for
    # the force change within one 1 ms step) ...
    below = stuck[:-1] & (np.abs(net[:-1]) < static - 0.5)
    assert below.sum() > 1000
    assert np.all(stuck[1:][below])
    # ... and breaks away only once it exceeds Fs
    breakaway = stuck[:-1] & ~stuck[1:]
    assert breakaway.sum() >= 8
    assert np.all(np.abs(net[1:][breakaway]) >= static - 0.05)


# --- fixed step vs adaptive reference -----------------------------------------------------

# Measured RMSEs are 4-20x below these (see the docstrings); the brief allowed 2 % / 3 %.
POSITION_TOLERANCE = 0.003  # fraction of stroke
PRESSURE_TOLERANCE = 0.01  # fraction of supply pressure


def compare_integrators(overrides, signal_for, closed_loop):
    runs = {}
    for integrator in ("fixed", "radau"):
        setup = rig_setup(*overrides, f'simulation.integrator="{integrator}"')
        runs[integrator] = run_rig(setup, signal_for(setup), closed_loop)
    fixed, radau = runs["fixed"], runs["radau"]
    stroke = setup.actuator.cylinder.stroke
    supply = setup.actuator.supply.supply_pressure

    def rmse(column):
        return float(np.sqrt(np.mean((fixed[column] - radau[column]) ** 2)))

    position = rmse("position [m]") / stroke
    pressure = max(rmse("cap pressure [Pa]"), rmse("rod pressure [Pa]")) / supply
    return position, pressure, runs


def test_fixed_step_matches_radau_open_loop_step() -> None:
    """Thesis step protocol shortened to 1 s + 1.5 s at 6 V, Stribeck-tanh friction.

    Measured (5 substeps of 0.2 ms vs Radau rtol 1e-6): position RMSE 0.016 mm = 0.036 %
    of stroke (max 0.20 mm, during the initial slam); pressure RMSE cap 0.15 kPa,
    rod 0.43 kPa = 0.096 % of supply."""
    position, pressure, runs = compare_integrators(
        (), lambda s: thesis_step(s, 6.0, step_time=1.0, duration=2.5), closed_loop=False
    )
    assert position < POSITION_TOLERANCE
    assert pressure < PRESSURE_TOLERANCE
    assert np.ptp(runs["radau"]["position [m]"]) > 0.04  # a full stroke each way


def test_fixed_step_matches_radau_closed_loop_sine() -> None:
    """1 Hz, 0.3 in sine about mid-stroke for 2.5 s, LuGre friction, PID in the loop.

    Measured: position RMSE 0.016 mm = 0.035 % of stroke (max 0.25 mm); pressure RMSE
    cap 0.15 kPa, rod 0.52 kPa = 0.12 % of supply. (Stribeck-tanh: 0.013 mm = 0.029 %,
    0.47 kPa = 0.10 %.)"""
    position, pressure, _ = compare_integrators(
        ('friction.model="lugre"',),
        lambda s: signals.sine(
            s.actuator.cylinder.stroke / 2, 0.3 * IN, 1.0, 2.5, s.simulation.control_step
        ),
        closed_loop=True,
    )
    assert position < POSITION_TOLERANCE
    assert pressure < PRESSURE_TOLERANCE


@pytest.mark.slow
def test_fixed_step_matches_radau_full_thesis_step_lugre() -> None:
    """Full 5 s + 5 s protocol at 6 V. Measured: position RMSE 0.0097 mm = 0.022 % of
    stroke; pressure RMSE cap 0.079 kPa, rod 0.24 kPa = 0.054 % of supply."""
    position, pressure, _ = compare_integrators(
        ('friction.model="lugre"',), lambda s: thesis_step(s, 6.0), closed_loop=False
    )
    assert position < POSITION_TOLERANCE
    assert pressure < PRESSURE_TOLERANCE


@pytest.mark.slow
def test_radau_reference_finishes_full_thesis_step_stribeck() -> None:
    """The whole 10 s protocol, including the piston resting on the end stop, where Radau
    used to crawl (~19,000 RHS calls per 1 ms) with absolute tolerances of 1e-8 of each
    state's scale; and it agrees with the fixed step once settled."""
    setup = rig_setup('simulation.integrator="radau"')
    result = simulate_rig(setup, thesis_step(setup, 6.0), False)
    reference = result.recording
    assert reference["time [s]"].size == 10000
    fixed = run_rig(rig_setup(), thesis_step(setup, 6.0), closed_loop=False)
    settled = reference["time [s]"] > 8.0
    for column in ("position [m]", "cap pressure [Pa]", "rod pressure [Pa]"):
        scale = (
            setup.actuator.cylinder.stroke
            if "position" in column
            else (setup.actuator.supply.supply_pressure)
        )
        difference = np.abs(reference[column][settled] - fixed[column][settled])
        assert difference.max() < 1e-3 * scale, column


# --- PID -------------------------------------------------------------------------------

DT = 1e-3


def gains(kp=0.0, ki=0.0, kd=0.0, tau=0.0, limit=2.0, umin=0.0, umax=10.0):
    return pid_gains(kp, ki, kd, tau, limit, 5.25, umin, umax)


def test_pid_integral_clamped_to_limit() -> None:
    g = gains(ki=100.0, limit=2.0)
    state = new_pid_state()
    outputs = [pid_update(g, state, 0.01, 0.0, DT) for _ in range(3000)]
    assert outputs[0] == pytest.approx(5.25 + 100.0 * 0.01 * DT)
    assert state["integral"] == 2.0
    assert outputs[-1] == 7.25
    state = new_pid_state()
    outputs = [pid_update(g, state, -0.01, 0.0, DT) for _ in range(3000)]
    assert state["integral"] == -2.0 and outputs[-1] == 3.25


def test_pid_output_saturated() -> None:
    g = gains(kp=1e4)
    assert pid_update(g, new_pid_state(), 0.01, 0.0, DT) == 10.0
    assert pid_update(g, new_pid_state(), -0.01, 0.0, DT) == 0.0


def test_pid_no_integral_windup_while_saturated() -> None:
    g = gains(kp=1000.0, ki=50.0, limit=4.0)
    state = new_pid_state()
    for _ in range(2000):  # 2 s pushing into the upper limit
        assert pid_update(g, state, 0.01, 0.0, DT) == 10.0
    assert state["integral"] == 0.0
    # the output leaves saturation as soon as the error allows: no wound-up integral
    u = pid_update(g, state, 0.001, 0.0, DT)
    assert u == pytest.approx(5.25 + 1.0 + 50.0 * 0.001 * DT)
    # saturated high but with the error reversed, the integral may unwind
    g = gains(ki=100.0, limit=2.0, umax=7.0)
    state = new_pid_state()
    state["integral"] = 2.0
    assert pid_update(g, state, -0.01, 0.0, DT) == 7.0
    assert state["integral"] == pytest.approx(2.0 - 100.0 * 0.01 * DT)


def test_pid_derivative_on_measurement() -> None:
    kp, kd, tau = 300.0, 3.0, 5e-3
    with_d, without_d = gains(kp=kp, kd=kd, tau=tau), gains(kp=kp, tau=tau)
    a, b = new_pid_state(), new_pid_state()
    for reference in (0.02, 0.02, 0.03, 0.01, 0.01):  # reference steps, measurement fixed
        u = pid_update(with_d, a, reference, 0.02, DT)
        assert u == pid_update(without_d, b, reference, 0.02, DT)  # no derivative kick
        assert u == pytest.approx(5.25 + kp * (reference - 0.02))
    assert a["measurement_rate"] == 0.0
    # a measurement step enters through the filtered rate: -Kd·(dt/(tau+dt))·dy/dt
    step = 1e-3
    u = pid_update(with_d, a, 0.01, 0.02 + step, DT)
    rate = DT / (tau + DT) * step / DT
    assert u == pytest.approx(5.25 + kp * (0.01 - 0.02 - step) - kd * rate)
