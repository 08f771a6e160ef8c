"""The single exception raised for every invalid parameter input."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

__all__ = ["MISSING", "ParameterError", "Problem"]


class _Missing:
    """Sentinel for a key that is absent from the input."""

    def __repr__(self) -> str:
        return "<missing>"


MISSING: Any = _Missing()


@dataclass(frozen=True)
class Problem:
    """One problem found in a parameter input.

    Parameters
    ----------
    key : str
        Dotted key path, e.g. ``"cylinder.bore"``; ``"<file>"`` or ``"<override>"`` for
        problems that are not about one key.
    value : Any
        The offending input value as written, or `MISSING` when the key is absent.
    expected : str
        What is wrong / what was expected, phrased to follow the value, e.g.
        ``"should be greater than 0"``.
    """

    key: str
    value: Any
    expected: str

    def __str__(self) -> str:
        if self.value is MISSING:
            return f"{self.key}: missing; {self.expected}"
        return f"{self.key}: {self.value!r} {self.expected}"


class ParameterError(ValueError):
    """Invalid parameters: carries every problem found, not just the first.

    Parameters
    ----------
    problems : iterable of Problem
        The problems found (at least one).
    source : str, optional
        Where the parameters came from (file path or set name), used in the message.

    Attributes
    ----------
    problems : list of Problem
    source : str or None
    """

    def __init__(self, problems: Iterable[Problem], source: str | None = None) -> None:
        self.problems: list[Problem] = list(problems)
        self.source = source
        super().__init__(str(self))

    @classmethod
    def single(cls, key: str, value: Any, expected: str) -> ParameterError:
        """One problem: ``key`` had ``value`` where ``expected`` was wanted."""
        return cls([Problem(key, value, f"is invalid; expected {expected}")])

    def __str__(self) -> str:
        n = len(self.problems)
        where = f" in {self.source}" if self.source else ""
        head = f"{n} problem{'s' if n != 1 else ''} with parameters{where}:"
        return "\n".join([head, *(f"  {p}" for p in self.problems)])

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.problems, self.source))
