"""Shared fixtures and helpers of the physics, kernel and rig tests.

Loading a parameter set validates it with pydantic (milliseconds), so setups are cached by
their override tuple; tests must not mutate the returned objects.
"""

from __future__ import annotations

import functools
import math
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.core import layout
from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.params import load_actuator, load_rig
from pneumaquad.params.schema import ActuatorParameters, RigSetup
from pneumaquad.rig.simulate import RigResult, simulate_rig

IN = 0.0254  # thesis in2m, App. B.1.1 l.30
PSI = 6894.76  # thesis psi2Pa, App. B.1.1 l.31
LBF = 4.4482216152605  # N per lbf
G = 9.81  # App. B.1.1 l.15

# Thesis air constants (eq 4.1.8-4.1.10, App. B.1.1 l.11-21).
K_AIR = 1.4
R_AIR = 287.0
CP_AIR = 1012.0
TS = 298.0


@functools.cache
def _rig(overrides: tuple[str, ...]) -> RigSetup:
    return load_rig("thesis-rig", list(overrides))


@functools.cache
def _actuator(name: str, overrides: tuple[str, ...]) -> ActuatorParameters:
    return load_actuator(name, list(overrides))


def rig_setup(*overrides: str) -> RigSetup:
    """The thesis rig with TOML overrides (cached; do not mutate)."""
    return _rig(tuple(overrides))


def actuator_setup(name: str = "crr-gamma", *overrides: str) -> ActuatorParameters:
    """A shipped actuator with TOML overrides (cached; do not mutate)."""
    return _actuator(name, tuple(overrides))


def run_rig(setup: RigSetup, signal: np.ndarray, closed_loop: bool) -> dict[str, np.ndarray]:
    """Simulate and return the recording, asserting the run completed."""
    result: RigResult = simulate_rig(setup, np.asarray(signal, dtype=float), closed_loop)
    assert not result.interrupted
    assert result.recording["time [s]"].shape[0] == len(signal)
    return result.recording


def gravity_along_rod(setup: RigSetup) -> float:
    """Weight of the moving mass along +x (extension) [N], computed independently."""
    mass = setup.rig.load_mass + setup.actuator.cylinder.piston_mass
    return mass * setup.rig.gravity * math.sin(setup.rig.orientation_angle)


def cap_volume(setup_or_actuator, position) -> np.ndarray:
    """Cap chamber volume A_cap·(x + dead) [m^3] (x_abs·A of eq 4.1.7)."""
    cyl = _cylinder(setup_or_actuator)
    return cyl.cap_area * (np.asarray(position) + cyl.cap_dead_length)


def rod_volume(setup_or_actuator, position) -> np.ndarray:
    """Rod chamber volume A_rod·(stroke - x + dead) [m^3]."""
    cyl = _cylinder(setup_or_actuator)
    return cyl.rod_area * (cyl.stroke - np.asarray(position) + cyl.rod_dead_length)


def _cylinder(obj):
    return obj.actuator.cylinder if isinstance(obj, RigSetup) else obj.cylinder


class Actuators:
    """N externally driven actuators for :func:`pneumaquad.core.kernel.step_actuators`."""

    def __init__(self, actuators, positions, cap_pressures, rod_pressures):
        self.params = pack_parameter_array(actuators)
        self.state = np.zeros(len(actuators), layout.ACTUATOR_STATE_DTYPE)
        starts = zip(positions, cap_pressures, rod_pressures, strict=True)
        for i, (x, pc, pr) in enumerate(starts):
            initial_state(self.params[i], x, pc, pr, out=self.state[i])
        self.supply = supply_state(actuators[0])
        self.outputs = new_outputs(len(actuators))


@pytest.fixture(scope="session")
def thesis() -> RigSetup:
    """The shipped thesis rig (App. B.1.1), unmodified."""
    return rig_setup()


@pytest.fixture(scope="session")
def gamma() -> ActuatorParameters:
    """The shipped crr-gamma actuator (App. C.1.1)."""
    return actuator_setup("crr-gamma")


#: The command line, started the way the console script does.
CLI = [sys.executable, "-c", "from pneumaquad.cli.main import main; main()"]


def interrupt_when_recording(
    arguments: list[str],
    csv: Path,
    min_bytes: int,
    wait: float,
    cwd: Path | None = None,
    between_polls: Callable[[], None] | None = None,
    poll_interval: float = 0.1,
) -> tuple[int, str]:
    """Run ``pneumaquad <arguments>``, send a real SIGINT once ``csv`` holds ``min_bytes``
    (or after ``wait`` [s]), and return (exit status, stderr). ``between_polls`` runs
    before each check (e.g. to feed a server with commands)."""
    process = subprocess.Popen(
        [*CLI, *arguments], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            if between_polls is not None:
                between_polls()
            if csv.is_file() and csv.stat().st_size > min_bytes:
                break
            time.sleep(poll_interval)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    return process.returncode, stderr


@pytest.fixture
def client_socket() -> Iterator[socket.socket]:
    """A UDP socket on 127.0.0.1 (any free port) with a 2 s receive timeout."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(2.0)
    yield sock
    sock.close()
