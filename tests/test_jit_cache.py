"""The package's numba cache: its own folder keyed by the source, numba's settings untouched.

Each check runs in a fresh Python process with an empty cache base, so it sees what an
import does to numba's process-wide configuration and where the cache files land."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from pneumaquad.core import jit
from pneumaquad.core.jit import cache_folder, compiled

#: run in a child process: import the package, call one compiled function, report
_CHILD = """
import json, numba
before = numba.config.CACHE_DIR
import pneumaquad, pneumaquad.core.kernel, pneumaquad.robot.stepping
from pneumaquad.core.jit import cache_folder
from pneumaquad.core.physics.orifice import area_to_sonic_conductance
value = area_to_sonic_conductance(1e-6, 0.04)
print(json.dumps({
    "before": before, "after": numba.config.CACHE_DIR, "folder": str(cache_folder()),
    "hits": sum(area_to_sonic_conductance.stats.cache_hits.values()),
    "misses": sum(area_to_sonic_conductance.stats.cache_misses.values()),
}))
"""


def _run_child(environment: dict[str, str]) -> dict[str, object]:
    env = {key: value for key, value in os.environ.items()
           if key not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env.update(environment)
    result = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True,
                            text=True, check=True, timeout=300)
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_importing_the_package_leaves_numba_cache_dir_alone(tmp_path: Path) -> None:
    report = _run_child({"XDG_CACHE_HOME": str(tmp_path)})
    assert report["before"] == report["after"] == ""  # numba's default: not set
    folder = Path(str(report["folder"]))
    assert folder.parent == tmp_path / "pneumaquad"
    assert folder.name.startswith("numba-") and len(folder.name) == len("numba-") + 16


def test_cache_lands_in_the_hashed_folder_and_a_second_process_reuses_it(
    tmp_path: Path,
) -> None:
    environment = {"NUMBA_CACHE_DIR": str(tmp_path)}
    first = _run_child(environment)
    assert first["before"] == first["after"] == str(tmp_path)  # respected, not rewritten
    folder = Path(str(first["folder"]))
    assert folder.parent == tmp_path
    index_files = sorted(folder.rglob("orifice.area_to_sonic_conductance-*.nbi"))
    assert index_files, f"no index file under {folder}"
    assert all(path.is_relative_to(folder) for path in tmp_path.rglob("*.nbi"))
    assert (first["hits"], first["misses"]) == (0, 1)
    second = _run_child(environment)
    assert second["folder"] == first["folder"]
    assert (second["hits"], second["misses"]) == (1, 0)


def test_the_folder_name_follows_every_source_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # numba does not notice an edit of an inlined callee in another file; the folder does
    assert cache_folder().name == f"numba-{jit._source_hash()}"
    (tmp_path / "physics").mkdir()
    (tmp_path / "kernel.py").write_text("x = 1\n")
    (tmp_path / "physics" / "valve.py").write_text("y = 1\n")
    monkeypatch.setattr(jit, "PACKAGE_FOLDER", tmp_path)
    original = jit._source_hash()
    (tmp_path / "physics" / "valve.py").write_text("y = 2\n")
    assert jit._source_hash() != original


def test_compiled_functions_carry_the_package_cache() -> None:
    @compiled
    def _double(value: float) -> float:
        return 2.0 * value

    assert isinstance(_double, numba.core.dispatcher.Dispatcher)
    assert Path(_double._cache.cache_path).is_relative_to(cache_folder())


def test_old_cache_folders_are_pruned_to_the_most_recently_used(tmp_path):
    import os

    from pneumaquad.core.jit import prune_cache_folders

    folders = []
    for age in range(12):  # numba-0 newest ... numba-11 oldest
        folder = tmp_path / f"numba-{age}"
        (folder / "sub").mkdir(parents=True)
        (folder / "sub" / "f.nbi").write_bytes(b"x")
        os.utime(folder, (1e9 - age * 100, 1e9 - age * 100))
        folders.append(folder)
    (tmp_path / "other").mkdir()  # not a cache folder: left alone
    keep = tmp_path / "numba-11"  # the present version: kept whatever its age
    removed = prune_cache_folders(tmp_path, keep, versions=3)
    left = {path.name for path in tmp_path.iterdir()}
    assert left == {"numba-0", "numba-1", "numba-11", "other"}
    assert {path.name for path in removed} == {f"numba-{k}" for k in range(2, 11)}


def test_load_compiled_loads_what_a_call_with_those_types_uses() -> None:
    from pneumaquad.core.jit import load_compiled

    @compiled
    def weighted_sum(values, weight):
        return weight * values.sum()

    load_compiled(weighted_sum, np.zeros(3), 0.0)
    assert len(weighted_sum.signatures) == 1
    assert weighted_sum(np.arange(4.0), 0.5) == 3.0
    assert len(weighted_sum.signatures) == 1  # the call ran the loaded code
    weighted_sum(np.arange(4), 0.5)  # integers: a second specialisation
    assert len(weighted_sum.signatures) == 2
