"""The one numba compilation setting used by every compiled function of the package.

``error_model="numpy"`` lets float division by zero give inf/nan as in NumPy instead of
a checked Python exception, which removes a branch from every division in the hot path;
the physics functions guard their divisors explicitly where it matters.

The compiled code is kept on disk between runs. numba invalidates a cached function when
its own source file changes, but not when a function it calls (and inlines) in another
file changes. The package's functions are therefore cached in a folder named by a hash of
the whole package's source, so any edit or upgrade starts from a clean cache:
``<base>/numba-<hash>/``, where ``<base>`` is numba's own ``NUMBA_CACHE_DIR`` setting if
one is given, else ``$XDG_CACHE_HOME/pneumaquad`` (``~/.cache/pneumaquad``). The folders
of older versions are pruned to the :data:`KEPT_VERSIONS` most recently used
(:func:`prune_cache_folders`).

Only the functions decorated with :data:`compiled` use that folder: each gets its own
numba cache object whose locator names it. numba's process-wide configuration
(``numba.config.CACHE_DIR``, its list of cache locators) is left as it is, so other
libraries' cached functions go where numba would put them without pneumaquad.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numba
from numba import njit
from numba.core.caching import (
    CompileResultCacheImpl,
    FunctionCache,
    _CacheLocator,
    _SourceFileBackedLocatorMixin,
)
from numba.core.dispatcher import Dispatcher

#: the package folder (src/pneumaquad) whose source the cache folder is keyed by
PACKAGE_FOLDER = Path(__file__).resolve().parents[1]


def _source_hash() -> str:
    """Short hash of every Python file of the package (names and contents)."""
    digest = hashlib.sha256()
    for path in sorted(PACKAGE_FOLDER.rglob("*.py")):
        digest.update(path.relative_to(PACKAGE_FOLDER).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


@functools.cache
def cache_folder() -> Path:
    """Folder that holds the on-disk cache of the package's compiled functions.

    ``<base>/numba-<source hash>``; ``<base>`` is numba's ``CACHE_DIR`` setting (from
    ``$NUMBA_CACHE_DIR``) if set, else ``$XDG_CACHE_HOME/pneumaquad`` or
    ``~/.cache/pneumaquad``. Computed once per process; only read, never written to
    numba's configuration.
    """
    base = numba.config.CACHE_DIR or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "pneumaquad"
    )
    folder = Path(base) / f"numba-{_source_hash()}"
    prune_cache_folders(Path(base), keep=folder)
    return folder


#: How many source versions' cache folders :func:`prune_cache_folders` keeps.
KEPT_VERSIONS = 8


def prune_cache_folders(base: Path, keep: Path, versions: int = KEPT_VERSIONS) -> list[Path]:
    """Remove the cache folders of old source versions: of the ``numba-*`` folders in
    ``base``, all but the ``versions`` most recently used (modification time) and ``keep``
    (the present version's, marked used now). Each edit or upgrade of the package starts a
    new folder (tens of MB); without pruning they pile up. Folders that cannot be removed
    (another process, permissions) are left. Returns the folders removed."""
    try:
        keep.mkdir(parents=True, exist_ok=True)
        os.utime(keep)
        folders = sorted((path for path in base.glob("numba-*") if path.is_dir()),
                         key=lambda path: path.stat().st_mtime, reverse=True)
    except OSError:  # a read-only or vanished cache: nothing to prune
        return []
    removed = []
    for folder in [path for path in folders if path != keep][max(versions - 1, 0):]:
        shutil.rmtree(folder, ignore_errors=True)
        if not folder.exists():
            removed.append(folder)
    return removed


class PackageCacheLocator(_SourceFileBackedLocatorMixin, _CacheLocator):
    """numba cache locator that puts a function's cache files in :func:`cache_folder`.

    Like numba's own locators it keeps one sub-folder per source folder and stamps each
    entry with its source file's hash; the enclosing folder adds the whole package's hash.
    """

    def __init__(self, py_func: Callable[..., Any], py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = str(cache_folder() / self.get_suitable_cache_subpath(py_file))

    def get_cache_path(self) -> str:
        """Folder of this function's index and data files."""
        return self._cache_path


class _PackageCacheImpl(CompileResultCacheImpl):
    # only the package's locator: numba's in-tree or user-wide folders would not notice an
    # edit of an inlined callee in another file
    _locator_classes: ClassVar[list[type[_CacheLocator]]] = [PackageCacheLocator]


class PackageFunctionCache(FunctionCache):
    """numba's function cache with :class:`PackageCacheLocator` as its locator."""

    _impl_class = _PackageCacheImpl


def compiled(
    function: Callable[..., Any] | None = None, *, inline: bool = False, nogil: bool = False
) -> Callable[..., Any]:
    """Compile ``function`` with ``njit(error_model="numpy")``, cached in :func:`cache_folder`.

    The decorator of every compiled function of the package. Where the cache folder cannot
    be created or written, the function is compiled afresh in each process instead.

    ``@compiled(inline=True)`` also inlines the function's body into its compiled callers
    (numba's ``inline="always"``, at numba's IR level); called from Python it compiles
    and caches like any other. For the functions of the robot's control step, which pass
    bundles of arrays down a chain of calls: each compiled call boundary takes a reference
    to every array it receives and releases it on return (atomic reference counting,
    tens of arrays per control step), which inlining removes.

    ``@compiled(nogil=True)`` releases the GIL while the function runs: for the loops
    that run a chunk of control steps, so that the thread writing the recording (and any
    other Python thread) runs beside them instead of waiting for the chunk to end.
    """
    if function is None:
        return functools.partial(compiled, inline=inline, nogil=nogil)
    options: dict[str, Any] = {"error_model": "numpy"}
    if inline:
        options["inline"] = "always"
    if nogil:
        options["nogil"] = True
    dispatcher = njit(**options)(function)
    if isinstance(dispatcher, Dispatcher):  # a plain function under NUMBA_DISABLE_JIT
        try:
            cache = PackageFunctionCache(function)
        except RuntimeError:  # "no locator available": the folder is not writable
            return dispatcher
        # what Dispatcher.enable_caching() does, with the package's cache class
        dispatcher._cache = cache
    return dispatcher


def load_compiled(function: Callable[..., Any], *arguments: Any) -> None:
    """Load ``function``'s machine code for the types of ``arguments`` (from the cache
    folder, or compile it) without running it.

    A compiled function's first call in a process loads its code: 2-15 ms each. An object
    that calls one in every chunk of a run loads it where it is built instead, so that the
    run's stages time the run. ``arguments`` must have the types of the calls (the same
    objects, or arrays of the same dtype, dimensions and layout); with others this loads
    an extra specialisation, and the first call still loads its own. Does nothing under
    ``NUMBA_DISABLE_JIT``.
    """
    if isinstance(function, Dispatcher):
        function.compile(tuple(numba.typeof(argument) for argument in arguments))
