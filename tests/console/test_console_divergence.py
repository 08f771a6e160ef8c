"""A diverging console simulation pauses at its last good state and says so (no reset)."""

from __future__ import annotations

import numpy as np

from pneumaquad.console.app import ConsoleApp

# 30 ms steps, explicit Euler and massless pistons: the fixed-thorax legs blow up
UNSTABLE = ('simulation.control_step="30 ms"', 'simulation.integrator="euler"',
            *(f'linkages.{joint}.moving_mass="0 kg"' for joint in ("alpha", "beta", "gamma")))


def test_a_diverging_console_pauses_at_the_last_good_state() -> None:
    app = ConsoleApp(configuration="fixed", port=0, real_time=False, overrides=UNSTABLE)
    try:
        simulation = app.simulation
        rng = np.random.default_rng(0)
        app.running = True
        times = []
        for _ in range(100):
            simulation.command_voltages(rng.choice([0.0, 10.0], size=12))  # bang-bang
            app.advance(1)
            if not app.running:
                break
            times.append(simulation.time)
        assert not app.running, "the run did not diverge"
        assert "diverged" in app.message and "last good state" in app.message
        assert simulation.divergences == 1
        assert simulation.time == times[-1] > 0.0  # paused where it was, not reset to 0
        assert np.all(np.isfinite(simulation.data.qpos))
        assert np.all(np.isfinite(simulation.chamber_pressures()))
    finally:
        app.close()
