"""Property-based tests: random valve commands, loads and model choices stay physical."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import (
    R_AIR,
    TS,
    Actuators,
    actuator_setup,
    cap_volume,
    rig_setup,
    rod_volume,
    run_rig,
)
from pneumaquad.core.kernel import step_actuators
from pneumaquad.core.layout import float_view

FRICTION = ["stribeck_tanh", "viscous", "coulomb", "coulomb_viscous", "lugre"]
ORIENTATION = ["vertical_down", "vertical_up", "horizontal"]

segments = st.lists(
    st.tuples(st.floats(0.0, 10.0), st.integers(10, 300)),  # (volts, milliseconds)
    min_size=1,
    max_size=8,
)

rig_models = st.fixed_dictionaries(
    {
        "rig.load_mass": st.floats(0.01, 5.0).map(lambda m: f'"{m} kg"'),
        "rig.orientation": st.one_of(
            st.sampled_from(ORIENTATION), st.floats(-90.0, 90.0).map(lambda a: f"{a} deg")
        ).map(lambda o: f'"{o}"'),
        "valve.model": st.sampled_from(['"underlapped"', '"simple"']),
        "valve.flow_form": st.sampled_from(['"orifice"', '"iso6358"']),
        "friction.model": st.sampled_from([f'"{f}"' for f in FRICTION]),
        "thermodynamics.model": st.sampled_from(['"adiabatic"', '"polytropic"', '"heat_transfer"']),
        "rig.spacer": st.sampled_from(["false", "false", "false", "true"]),
    }
)


def piecewise(segs, dt: float = 1e-3) -> np.ndarray:
    return np.concatenate([np.full(max(1, round(ms * 1e-3 / dt)), volts) for volts, ms in segs])


@settings(max_examples=40, deadline=None)
@given(models=rig_models, segs=segments)
def test_rig_never_leaves_physical_bounds(models, segs) -> None:
    setup = rig_setup(*(f"{key}={value}" for key, value in sorted(models.items())))
    supply = setup.actuator.supply
    ps, pe = supply.supply_pressure, supply.exhaust_pressure
    stroke = setup.actuator.cylinder.stroke
    command = piecewise(segs)
    rec = run_rig(setup, command, closed_loop=False)
    for name, column in rec.items():
        if name not in ("reference position [m]", "tank pressure [Pa]"):
            assert np.all(np.isfinite(column)), name
    for side in ("cap", "rod"):
        pressure = rec[f"{side} pressure [Pa]"]
        assert np.all(rec[f"{side} mass [kg]"] > 0.0)
        assert np.all(rec[f"{side} temperature [K]"] > 0.0)
        assert pressure.min() >= 0.5 * pe, (side, pressure.min())
        assert pressure.max() <= 1.5 * ps, (side, pressure.max())
    x = rec["position [m]"]
    assert x.min() > -1e-3 and x.max() < stroke + 1e-3  # end stops hold
    assert np.all(np.diff(rec["air consumed [kg]"]) >= 0.0)
    # mass bookkeeping holds for any run
    dt = setup.simulation.control_step
    m0 = (
        setup.rig.initial_cap_pressure
        * cap_volume(setup, stroke if setup.rig.spacer else setup.rig.initial_position)
        / (R_AIR * TS)
    )
    integrated = m0 + np.cumsum(rec["cap mass flow [kg/s]"] * dt)
    np.testing.assert_allclose(rec["cap mass [kg]"], integrated, rtol=1e-8)


@settings(max_examples=30, deadline=None)
@given(
    name=st.sampled_from(["crr-alpha", "crr-beta", "crr-gamma"]),
    valve=st.sampled_from(['"underlapped"', '"simple"']),
    flow=st.sampled_from(['"orifice"', '"iso6358"']),
    segs=segments,
    amplitude=st.floats(0.0, 0.45),
    frequency=st.floats(0.1, 5.0),
)
def test_driven_actuator_stays_in_compression_envelope(
    name, valve, flow, segs, amplitude, frequency
) -> None:
    """Prescribed piston motion (the robot case) with any valve command.

    Prescribed motion can compress a chamber beyond supply, so the bound is the adiabatic
    envelope of eq 4.1.10: while P > Ps the valve only lets air out, so P·V^n cannot
    grow, and while P < Pe only in, so it cannot fall. Hence
    min(P0, Pe)·(Vmin/Vmax)^n <= P <= max(P0, Ps)·(Vmax/Vmin)^n, n = 1 + k·R/cp.
    """
    actuator = actuator_setup(name, f"valve.model={valve}", f"valve.flow_form={flow}")
    ps, pe = actuator.supply.supply_pressure, actuator.supply.exhaust_pressure
    gas = actuator.gas
    n = 1 + gas.heat_capacity_ratio * gas.gas_constant / gas.specific_heat_cp
    stroke = actuator.cylinder.stroke
    command = piecewise(segs)
    dt = 1e-3
    t = np.arange(command.size) * dt
    w = 2 * np.pi * frequency
    positions = stroke * (0.5 + amplitude * np.sin(w * t))
    velocities = stroke * amplitude * w * np.cos(w * t)
    p0 = {"cap": pe, "rod": ps}
    acts = Actuators([actuator], [positions[0]], [p0["cap"]], [p0["rod"]])
    pressures = np.zeros((command.size, 2))
    for k in range(command.size):
        step_actuators(
            acts.params,
            acts.state,
            command[k : k + 1],
            positions[k : k + 1],
            velocities[k : k + 1],
            dt,
            5,
            acts.supply,
            acts.outputs,
        )
        s = acts.state[0]
        assert np.all(np.isfinite(float_view(acts.state)))
        assert np.all(np.isfinite(float_view(acts.outputs)))
        assert s["cap_mass"] > 0.0 and s["rod_mass"] > 0.0
        pressures[k] = s["cap_pressure"], s["rod_pressure"]
    x = np.concatenate([positions, [positions[-1] + velocities[-1] * dt]])
    volumes = {"cap": cap_volume(actuator, x), "rod": rod_volume(actuator, x)}
    for column, side in enumerate(("cap", "rod")):
        ratio = (volumes[side].max() / volumes[side].min()) ** n
        assert pressures[:, column].max() <= max(p0[side], ps) * ratio * 1.01
        assert pressures[:, column].min() >= min(p0[side], pe) / ratio / 1.01
