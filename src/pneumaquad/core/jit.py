"""The one numba compilation setting used by every compiled function of the package.

``error_model="numpy"`` lets float division by zero give inf/nan as in NumPy instead of
a checked Python exception, which removes a branch from every division in the hot path;
the physics functions guard their divisors explicitly where it matters. ``cache=True``
keeps the compiled code on disk between runs.

numba invalidates a cached function when its own source file changes, but not when a
function it calls (and inlines) in another file changes. The cache therefore lives in a
folder named by a hash of the whole package's source, so any edit or upgrade starts from
a clean cache. It is under ``$NUMBA_CACHE_DIR`` if set, else ``~/.cache/pneumaquad``.
"""

import hashlib
import os
from pathlib import Path

import numba
from numba import njit


def _source_hash() -> str:
    """Short hash of every Python file of the package (names and contents)."""
    digest = hashlib.sha256()
    package = Path(__file__).resolve().parents[1]  # the whole pneumaquad package
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _cache_folder() -> Path:
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "pneumaquad"
    )
    return Path(base) / f"numba-{_source_hash()}"


numba.config.CACHE_DIR = str(_cache_folder())

compiled = njit(cache=True, error_model="numpy")
