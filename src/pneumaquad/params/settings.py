"""Described settings: the help text and range of the fields of a settings dataclass.

A settings dataclass (e.g. :class:`pneumaquad.locomotion.walking.WalkSettings`) keeps the
defaults; a table of :class:`Setting` objects keyed by field name says what each field
sets and which values it takes. The library checks a settings object against the table
(:func:`check_settings`) and the command line builds its options from the dataclass and
the same table (``pneumaquad.cli.settings``): a default, a range or a help text is
written once.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from .fields import Bounds

__all__ = ["Setting", "check_settings"]


@dataclass(frozen=True)
class Setting:
    """Description of one settings field.

    Attributes
    ----------
    help : str
        What the field sets (one sentence, for ``--help`` and error messages).
    bounds : Bounds or None
        Allowed range, in the unit the value is *shown* in (see ``scale``).
    option : str or None
        Command-line name when it differs from the field's (``"margin"``).
    off_option : str or None
        For a switch, the name of its off form (``"swing-from-body"``; default
        ``"no-<option>"``).
    scale : float
        Field value = shown value × ``scale`` (``math.pi / 180`` for a field in radians
        shown in degrees).
    nested : mapping of str to Setting
        For a field holding another settings object or None: the described fields of that
        object; the field itself is then a switch (on: the object, off: None).
    """

    help: str
    bounds: Bounds | None = None
    option: str | None = None
    off_option: str | None = None
    scale: float = 1.0
    nested: Mapping[str, Setting] = field(default_factory=dict)


def check_settings(settings: Any, described: Mapping[str, Setting]) -> None:
    """Check the numeric fields of ``settings`` named in ``described`` against their ranges
    (nested settings objects too).

    Raises
    ------
    ValueError
        Naming the class, the field, the value (as shown) and the range.
    """
    for name, description in described.items():
        value = getattr(settings, name)
        if description.nested and value is not None:
            check_settings(value, description.nested)
        if (description.bounds is None or isinstance(value, bool)
                or not isinstance(value, (int, float))):
            continue
        shown = value / description.scale
        if not description.bounds.contains(shown):
            raise ValueError(f"{type(settings).__name__}.{name}: {shown:g} should be "
                             f"{description.bounds.expectation}")
