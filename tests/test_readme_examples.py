"""The README's Python examples run as printed, and the package's public names resolve."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pneumaquad

README = Path(__file__).resolve().parents[1] / "README.md"


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)


def test_the_readme_has_python_examples() -> None:
    assert len(_python_blocks()) >= 2


@pytest.mark.parametrize("index", range(len(_python_blocks())))
def test_readme_python_example_runs(index: int, capsys: pytest.CaptureFixture[str]) -> None:
    exec(compile(_python_blocks()[index], f"README.md python block {index}", "exec"), {})
    printed = capsys.readouterr().out
    assert printed.strip(), "each example prints what it computed"
    assert "nan" not in printed.lower()


def test_every_public_name_resolves() -> None:
    for name in pneumaquad.__all__:
        assert getattr(pneumaquad, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'simulate_everything'"):
        pneumaquad.simulate_everything  # noqa: B018


def test_public_names_are_the_library_objects() -> None:
    from pneumaquad.rig.simulate import simulate_rig
    from pneumaquad.robot.simulation import RobotSimulation

    assert pneumaquad.simulate_rig is simulate_rig
    assert pneumaquad.RobotSimulation is RobotSimulation


def test_importing_the_package_loads_neither_mujoco_nor_the_kernel() -> None:
    code = ("import sys, pneumaquad; "
            "print(sorted(m for m in ('mujoco', 'numba', 'pneumaquad.core.kernel') "
            "if m in sys.modules))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True).stdout.strip()
    assert loaded == "[]"


def test_the_rig_example_tracks_its_sine() -> None:
    """The first example's physics: the closed loop follows the 0.5 Hz sine about 22 mm."""
    setup = pneumaquad.load_rig("thesis-rig")
    reference = pneumaquad.signals.sine(0.022, 0.01, 0.5, 4.0, setup.simulation.control_step)
    result = pneumaquad.simulate_rig(setup, reference, closed_loop=True)
    position = result.recording["position [m]"]
    late = position[position.size // 2:]
    assert 0.022 - 0.012 < late.min() < 0.022 - 0.008
    assert 0.022 + 0.008 < late.max() < 0.022 + 0.012
    assert np.isfinite(result.recording["cap pressure [Pa]"]).all()
