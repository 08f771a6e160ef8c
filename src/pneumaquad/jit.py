"""The one numba compilation setting used by every compiled function of the package.

``error_model="numpy"`` lets float division by zero give inf/nan as in NumPy instead of
a checked Python exception, which removes a branch from every division in the hot path;
the physics functions guard their divisors explicitly where it matters. ``cache=True``
keeps the compiled code on disk between runs.
"""

from numba import njit

compiled = njit(cache=True, error_model="numpy")
