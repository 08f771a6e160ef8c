"""Exact conversion factors of the US customary units the thesis uses, for display and
for the places that convert outside the unit-aware parameter loader.

Definitions: 1 in = 0.0254 m and 1 lbf = 4.4482216152605 N (exact, international yard and
pound, 1959); 1 psi = 1 lbf/in² follows from them. Parameters with units go through
:mod:`pneumaquad.params.units` (pint), which uses the same definitions.
"""

from __future__ import annotations

__all__ = ["METRE_PER_INCH", "NEWTON_PER_LBF", "PASCAL_PER_PSI"]

METRE_PER_INCH = 0.0254
NEWTON_PER_LBF = 4.4482216152605
PASCAL_PER_PSI = NEWTON_PER_LBF / METRE_PER_INCH**2  # 6894.757293168361
