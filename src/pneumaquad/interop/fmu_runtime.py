"""What the actuator FMU's Python code does for the pythonfmu binary that runs it.

pythonfmu 0.7.0's binary (the same from 0.6.4 on) has three faults in how it holds Python
objects and its own state; each crashed a host process in our tests (FMPy 0.3.32 on
Linux). This module makes up for them from the Python side; should pythonfmu fix a fault,
the measure for it keeps a few objects alive until the process ends, and does no harm:

* :func:`hold_namespace`: the namespace of the FMU's module loses a reference at each
  instantiation;
* :func:`guard_entry_points`: after a Python exception in an FMI call, the slave object,
  its class and its log queue each lose a reference;
* :func:`release_at_exit`: the binary's clean-up at process exit writes to memory its
  static destructors have freed.

The first two add the reference that the binary will release a second time, with
``Py_IncRef`` and no owner in Python: an owner (a list) would release it once more when
the interpreter shuts down.
"""

from __future__ import annotations

import ctypes
import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = [
    "FMI_ENTRY_POINTS",
    "add_reference",
    "guard_entry_points",
    "hold_namespace",
    "release_at_exit",
]

#: The FMU binaries whose interpreter state is released at exit (:func:`release_at_exit`).
_RELEASED_AT_EXIT: set[Path] = set()

#: The methods of a pythonfmu slave that its binary calls.
FMI_ENTRY_POINTS = (
    "setup_experiment", "enter_initialization_mode", "exit_initialization_mode", "do_step",
    "terminate", "get_real", "get_integer", "get_boolean", "get_string", "set_real",
    "set_integer", "set_boolean", "set_string",
)


def add_reference(target: Any) -> None:
    """One more reference to ``target`` that nothing in Python owns (``Py_IncRef``): for
    a reference the pythonfmu binary releases without holding it."""
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(target))


def hold_namespace(namespace: dict[str, Any]) -> None:
    """Add the reference to a module's namespace that pythonfmu takes away.

    The module inside an exported FMU calls this with ``globals()`` whenever its code runs.
    On every instantiation pythonfmu finds the FMU's slave class by running that code again
    in the module's namespace, then releases a reference to the namespace that it never
    took (``PyModule_GetDict`` lends it). With the module's own reference alone, the
    namespace would be freed while the module still uses it, and a later instantiation or
    the interpreter's exit would crash. Each run of the code (the import, and each
    instantiation) adds the reference that the release takes away.

    Parameters
    ----------
    namespace : dict
        The calling module's ``globals()``.
    """
    add_reference(namespace)


def _guarded(method: Callable[..., Any]) -> Callable[..., Any]:
    """``method``, adding a reference to the slave, its class and its log queue when it
    raises."""

    @functools.wraps(method)
    def call(self: Any, *args: Any, **kwargs: Any) -> Any:
        try:
            return method(self, *args, **kwargs)
        except BaseException:
            for target in (type(self), self, self.log_queue):
                add_reference(target)
            raise

    return call


def guard_entry_points(slave_class: type) -> type:
    """Make the FMI methods of a pythonfmu slave class keep their objects alive on errors.

    When one of them raises, pythonfmu reports the exception (the FMI call returns
    ``fmi2Fatal`` with the message logged) and releases its references to the slave
    object, its class and its log queue, then releases them again when the instance is
    freed. Without one more reference each, the slave (held only by its own cycles) is
    collected in between, and the second release writes to freed memory: the process
    crashed in Python's garbage collector. Each exception therefore adds one reference to
    each of the three.

    Parameters
    ----------
    slave_class : type
        A subclass of ``pythonfmu.Fmi2Slave``; the methods of :data:`FMI_ENTRY_POINTS` are
        wrapped in place.

    Returns
    -------
    type
        ``slave_class``.
    """
    for name in FMI_ENTRY_POINTS:
        setattr(slave_class, name, _guarded(getattr(slave_class, name)))
    return slave_class


def release_at_exit(resources: Path, model_identifier: str) -> None:
    """Have the FMU's binary drop its interpreter state early in the process's exit
    (Linux).

    The binary is never unloaded once used (it defines GNU unique symbols), so its own
    clean-up runs at process exit, after the static object that holds its interpreter
    state has been destroyed, and writes to freed memory: the process aborted at exit
    ("corrupted double-linked list", "free(): corrupted unsorted chunks") in about one
    FMPy run in ten, and in a C host without Python; valgrind shows the access in the
    binary's ``finalizePythonInterpreter``. That exported function, registered here as an
    exit handler (``__cxa_atexit``, which runs handlers in reverse order of registration),
    runs before that static object is destroyed: it releases the state (in a host without
    Python, pythonfmu then finishes the interpreter it started) and leaves nothing for the
    late clean-up to free. Nothing is done where the binary is not found (an FMU being
    built) or on other systems.

    Parameters
    ----------
    resources : pathlib.Path
        The FMU's extracted ``resources`` folder.
    model_identifier : str
        The FMU's model identifier (its binary's name).
    """
    binary = resources.parent / "binaries" / "linux64" / f"{model_identifier}.so"
    if not sys.platform.startswith("linux") or binary in _RELEASED_AT_EXIT \
            or not binary.is_file():
        return
    library = ctypes.CDLL(str(binary))  # loaded by the host already: the same library
    finalize = getattr(library, "finalizePythonInterpreter", None)
    if finalize is None:
        return
    register = ctypes.CDLL(None).__cxa_atexit
    register.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    register.restype = ctypes.c_int
    register(ctypes.cast(finalize, ctypes.c_void_p), None, None)
    _RELEASED_AT_EXIT.add(binary)
