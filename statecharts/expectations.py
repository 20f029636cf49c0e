"""Expected values of a scenario step beyond plain equality.

A scenario's ``expect`` field may hold, besides a plain value:

* ``{approx: X, within: T}``: a number within ``T`` of ``X`` (``T`` a non-negative
  number or a named tolerance from :data:`NAMED_TOLERANCES`);
* ``{not: V}``: anything but ``V``;
* for an axis, ``passes_through: [S1, S2, ...]``: during the step the axis is in each
  of these states, in this order (a state it is in when the step starts counts, and so
  does a state entered and left within one coarse update).

Plain values are compared as before: booleans exactly, numbers to a relative 1e-9.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

#: Tolerances a scenario may name instead of giving a number.
NAMED_TOLERANCES: Mapping[str, float] = {
    # one step of the 16-bit DAC of a servo module over its 20 V span (002: about 305 uV)
    "dac_step": 20.0 / 65536,
}
#: The keys of an expectation written as a mapping.
APPROX_KEYS = frozenset({"approx", "within"})
NOT_KEYS = frozenset({"not"})
#: The axis pseudo-field whose value is a list of states.
PASSES_THROUGH = "passes_through"


@dataclass(frozen=True, slots=True)
class Approx:
    value: float
    within: float
    tolerance_name: str | None = None

    def __str__(self) -> str:
        tol = self.tolerance_name or repr(self.within)
        return f"{self.value!r} within {tol}"


@dataclass(frozen=True, slots=True)
class Not:
    value: object

    def __str__(self) -> str:
        return f"not {yaml_value(self.value)}"


@dataclass(frozen=True, slots=True)
class PassesThrough:
    states: tuple[str, ...]

    def __str__(self) -> str:
        return "passes through " + ", ".join(self.states)


def yaml_value(value: object) -> str:
    """Spell a value as it is written in a scenario (true/false, not True/False)."""
    if isinstance(value, (Approx, Not, PassesThrough)):
        return str(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def same(expected: object, actual: object) -> bool:
    """Plain comparison: booleans exactly, numbers to a relative 1e-9, else equality."""
    if isinstance(expected, bool) or isinstance(actual, bool):
        return isinstance(expected, bool) and isinstance(actual, bool) and expected == actual
    if isinstance(expected, int) and isinstance(actual, int):
        return expected == actual  # exactly: an integer beyond any float is no error
    if isinstance(expected, (int, float)) and isinstance(actual, (int, float)):
        if abs(expected) > 1e300 or abs(actual) > 1e300:  # beyond any REAL: no float() of a huge int
            return expected == actual
        return abs(float(expected) - float(actual)) <= 1e-9 * max(1.0, abs(float(expected)))
    return expected == actual


def holds(expected: object, actual: object) -> bool:
    """Whether an observed value satisfies an expectation (not ``passes_through``)."""
    if isinstance(expected, Approx):
        return (isinstance(actual, (int, float)) and not isinstance(actual, bool)
                and abs(float(actual) - expected.value) <= expected.within)
    if isinstance(expected, Not):
        return not same(expected.value, actual)
    return same(expected, actual)


def passes_through(wanted: Sequence[str], visited: Sequence[str]) -> bool:
    """``wanted`` is a subsequence of ``visited``."""
    it = iter(visited)
    return all(any(state == v for v in it) for state in wanted)


def parse(value: object, *, numeric: bool) -> tuple[object, str | None]:
    """(the expectation, or None with the reason it is malformed) for one field value.

    ``numeric`` says whether the observable is a number (``approx`` needs one)."""
    if not isinstance(value, Mapping):
        return value, None
    keys = set(value)
    if keys == NOT_KEYS:
        inner = value["not"]
        if isinstance(inner, (Mapping, list)):
            return None, "`not:` takes a plain value"
        return Not(inner), None
    if keys == APPROX_KEYS:
        if not numeric:
            return None, "`approx:` applies to numbers only"
        target, tol = value["approx"], value["within"]
        if isinstance(target, bool) or not isinstance(target, (int, float)):
            return None, f"`approx:` needs a number, got {target!r}"
        if isinstance(tol, str):
            if tol not in NAMED_TOLERANCES:
                return None, f"unknown tolerance {tol!r}; named tolerances: {', '.join(NAMED_TOLERANCES)}"
            return Approx(float(target), NAMED_TOLERANCES[tol], tol), None
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol >= 0:
            return None, f"`within:` needs a number at least 0 or a named tolerance, got {tol!r}"
        return Approx(float(target), float(tol)), None
    return None, ("an expected value is a plain value, {approx: X, within: T} or {not: V}; "
                  f"got keys {', '.join(sorted(map(str, keys)))}")
