"""The tag database: Logix data types over one flat list of values.

Pipeline position: program IR tags -> **tag database** -> ladder interpreter.  Every
BOOL, integer, REAL and every member of a TIMER, COUNTER or MOTION_INSTRUCTION
element has one slot in :attr:`TagDatabase.values`, so the whole program state is one
tuple (:meth:`TagDatabase.snapshot`) and can be restored exactly.  Values are stored
the way the controller stores them: integers wrap around to their width (SINT 8, INT
16, DINT 32, LINT 64 bits, two's complement), a REAL is rounded to single precision,
a REAL stored into an integer is rounded to the nearest integer, halves to even
(1756-RM003N, "Data conversions"; INT-P07 in docs/semantics.md).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from statecharts.program.ir import AXIS_TYPES, AXIS_UNTYPED, Scalar, Tag

INTEGER_BITS = {"SINT": 8, "INT": 16, "DINT": 32, "LINT": 64}
NUMERIC_TYPES = ("SINT", "INT", "DINT", "LINT", "REAL")

#: members of the predefined structures, in storage order (1756-RM003N, TIMER and COUNTER structures)
STRUCTURES: dict[str, tuple[tuple[str, str], ...]] = {
    "TIMER": (("PRE", "DINT"), ("ACC", "DINT"), ("EN", "BOOL"), ("TT", "BOOL"), ("DN", "BOOL")),
    "COUNTER": (("PRE", "DINT"), ("ACC", "DINT"), ("CU", "BOOL"), ("CD", "BOOL"), ("DN", "BOOL"),
                ("OV", "BOOL"), ("UN", "BOOL")),
    # the members the specification gives the MOTION_INSTRUCTION data type, plus FLAGS
    "MOTION_INSTRUCTION": (("EN", "BOOL"), ("DN", "BOOL"), ("ER", "BOOL"), ("PC", "BOOL"), ("IP", "BOOL"),
                           ("ERR", "INT"), ("EXERR", "SINT"), ("FLAGS", "DINT")),
}


def wrap(value: int, bits: int) -> int:
    """Two's-complement wrap-around of an integer to ``bits`` bits."""
    mask = (1 << bits) - 1
    value &= mask
    return value - (1 << bits) if value >> (bits - 1) else value


def to_real(value: float) -> float:
    """``value`` rounded to IEEE single precision (a REAL); beyond its range it is infinite."""
    try:
        return float(struct.unpack("<f", struct.pack("<f", value))[0])
    except OverflowError:
        return math.copysign(math.inf, value)


def convert(data_type: str, value: Scalar) -> Scalar:
    """``value`` as a tag of ``data_type`` stores it."""
    if data_type == "BOOL":
        return bool(value)
    if data_type == "REAL":
        return to_real(float(value))
    bits = INTEGER_BITS[data_type]
    if isinstance(value, float):
        if math.isnan(value) or math.isinf(value):
            return 0
        value = round(value)  # halves to even, as the controller rounds
    return wrap(int(value), bits)


def zero(data_type: str) -> Scalar:
    return False if data_type == "BOOL" else (0.0 if data_type == "REAL" else 0)


@dataclass(frozen=True, slots=True)
class TagLayout:
    """Where one tag's values live: ``size`` slots per element, elements in row-major order."""

    tag: Tag
    offset: int
    size: int
    count: int

    @property
    def data_type(self) -> str:
        return self.tag.data_type

    @property
    def dimensions(self) -> tuple[int, ...]:
        return self.tag.dimensions

    def member(self, name: str) -> tuple[int, str] | None:
        """(slot within an element, type) of a structure member."""
        for k, (m, t) in enumerate(STRUCTURES.get(self.data_type, ())):
            if m == name:
                return k, t
        return None

    def element_index(self, subscripts: Sequence[int]) -> int | None:
        """Row-major element number of ``subscripts``, or None when one is out of range."""
        index = 0
        for s, d in zip(subscripts, self.dimensions):
            if not 0 <= s < d:
                return None
            index = index * d + s
        return index


class TagDatabase:
    """Every non-axis tag of a program, as one list of values."""

    def __init__(self, tags: Sequence[Tag]) -> None:
        self.layouts: dict[str, TagLayout] = {}
        self.values: list[Scalar] = []
        for tag in tags:
            if tag.data_type in AXIS_TYPES or tag.data_type == AXIS_UNTYPED:
                continue
            members = STRUCTURES.get(tag.data_type)
            size = len(members) if members else 1
            count = math.prod(tag.dimensions) if tag.dimensions else 1
            layout = TagLayout(tag, len(self.values), size, count)
            self.layouts[tag.name] = layout
            types = [t for _, t in members] if members else [tag.data_type]
            for _ in range(count):
                self.values.extend(zero(t) for t in types)
        self.initial = tuple(self.values)

    def snapshot(self) -> tuple[Scalar, ...]:
        return tuple(self.values)

    def restore(self, snap: Sequence[Scalar]) -> None:
        self.values[:] = snap

    def leaves(self, name: str) -> Iterator[tuple[str, int, str]]:
        """(path suffix, slot, type) of every value of tag ``name``: ``""``, ``[2]``, ``[0].DN``, ``ACC``."""
        layout = self.layouts[name]
        members = STRUCTURES.get(layout.data_type)
        dims = layout.dimensions
        for e in range(layout.count):
            if dims:
                subs = []
                rest = e
                for d in reversed(dims):
                    subs.append(rest % d)
                    rest //= d
                prefix = "[" + ",".join(str(s) for s in reversed(subs)) + "]"
            else:
                prefix = ""
            base = layout.offset + e * layout.size
            if members:
                for k, (m, t) in enumerate(members):
                    yield (f"{prefix}.{m}" if prefix else m), base + k, t
            else:
                yield prefix, base, layout.data_type
