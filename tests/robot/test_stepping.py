"""How the compiled stepping loop reaches MuJoCo: its shared library and struct addresses.

The loop calls ``mj_step`` and its halves through function addresses taken from the
library the ``mujoco`` bindings load, with the raw ``mjModel*``/``mjData*`` of the
bindings' objects. These tests fail with a plain message if a MuJoCo release moves the
library or drops the address attribute."""

from __future__ import annotations

import platform
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from pneumaquad.robot.stepping import (
    MUJOCO_LIBRARY_NAMES,
    mujoco_library_path,
    mujoco_step_function,
    struct_address,
)

FALLING_BOX = """
<mujoco>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body pos="0 0 0.3"><freejoint/><geom type="box" size="0.05 0.05 0.05" mass="1"/></body>
  </worldbody>
</mujoco>
"""


def test_the_library_is_the_one_beside_the_bindings() -> None:
    path = mujoco_library_path()
    assert path.is_file()
    assert path.parent in [Path(folder) for folder in mujoco.__path__]
    system = platform.system() if platform.system() in MUJOCO_LIBRARY_NAMES else "Linux"
    assert path.name == MUJOCO_LIBRARY_NAMES[system].format(version=mujoco.__version__)


@pytest.mark.parametrize("system", sorted(MUJOCO_LIBRARY_NAMES))
def test_each_platform_name_is_versioned_or_missing_clearly(system: str) -> None:
    expected = MUJOCO_LIBRARY_NAMES[system].format(version=mujoco.__version__)
    if system == platform.system():
        assert mujoco_library_path(system).name == expected
    else:  # that platform's file is not in this wheel: a message that names it
        with pytest.raises(RuntimeError, match=expected.replace(".", r"\.")):
            mujoco_library_path(system)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/maps")
def test_only_one_mujoco_library_is_mapped() -> None:
    # the ctypes handle is the library the bindings use, not a second copy
    maps = Path("/proc/self/maps").read_text().splitlines()
    mapped = {line.split()[-1] for line in maps if "libmujoco" in line}
    assert mapped == {str(mujoco_library_path().resolve())}


def test_mujoco_still_exposes_struct_addresses() -> None:
    model = mujoco.MjModel.from_xml_string(FALLING_BOX)
    data = mujoco.MjData(model)
    assert hasattr(model, "_address") and hasattr(data, "_address"), (
        f"mujoco {mujoco.__version__} dropped MjModel/MjData._address: "
        "pneumaquad.robot.stepping.struct_address needs another way to the raw pointers")
    assert struct_address(model) != 0 and struct_address(data) != 0
    assert struct_address(model) != struct_address(data)


def test_struct_address_names_what_is_missing() -> None:
    class NotAStruct:
        pass

    with pytest.raises(RuntimeError, match="_address"):
        struct_address(NotAStruct())  # type: ignore[arg-type]


def test_a_step_through_the_library_equals_the_bindings_step() -> None:
    model = mujoco.MjModel.from_xml_string(FALLING_BOX)
    through_library, through_bindings = mujoco.MjData(model), mujoco.MjData(model)
    for _ in range(200):  # 0.4 s: the box falls, lands and settles on the plane
        mujoco_step_function(struct_address(model), struct_address(through_library))
        mujoco.mj_step(model, through_bindings)
    assert through_library.time == pytest.approx(200 * model.opt.timestep)
    np.testing.assert_array_equal(through_library.qpos, through_bindings.qpos)
    assert through_library.qpos[2] < 0.3 - 0.1  # it fell
