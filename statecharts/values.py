"""Typed readings of run-time values.

Chart variables, tag members and operands are held as ``object`` (a spec decides their
types); where code needs a number it reads one through these, which say what they got
when the value is not a number.
"""

from __future__ import annotations


def as_int(value: object) -> int:
    """``value`` as an ``int`` (from an int, a bool, a float or numeric text)."""
    if isinstance(value, int | float | str):
        return int(value)
    raise TypeError(f"expected an integer, got {value!r}")


def as_float(value: object) -> float:
    """``value`` as a ``float`` (from an int, a bool, a float or numeric text)."""
    if isinstance(value, int | float | str):
        return float(value)
    raise TypeError(f"expected a number, got {value!r}")
