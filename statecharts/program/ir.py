"""The program IR: one frozen, typed record of a Logix program, whatever form it was read from.

Pipeline position: program readers (:mod:`~statecharts.program.rungtext` for ASCII and
neutral rung text, :mod:`~statecharts.program.l5x` for L5X exports) -> **program IR** ->
ladder interpreter (:mod:`~statecharts.program.ladder`), called by the scan module.

Records are small frozen slotted dataclasses; collections are tuples.  Source
locations (and the file and form a program was read from) do not take part in
equality, so the same routine written as ASCII rungs, as neutral text or inside an
L5X export gives equal IR.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True, slots=True)
class SourceLocation:
    """Where an element was written: file, 1-based line and column."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


NOWHERE = SourceLocation("", 1, 1)


# -- expressions (CPT, CMP, array subscripts) ---------------------------------------


@dataclass(frozen=True, slots=True)
class Number:
    """An immediate value."""

    value: int | float
    text: str = field(default="", compare=False)


@dataclass(frozen=True, slots=True)
class Member:
    """``.name`` of a structure (``T1.DN``) or ``.3``, a bit of an integer (``Flags.3``)."""

    name: str

    @property
    def bit(self) -> int | None:
        return int(self.name) if self.name.isdigit() else None


@dataclass(frozen=True, slots=True)
class Index:
    """``[i]`` or ``[i, j]``: subscripts of an array; each an expression."""

    subscripts: tuple[Expression, ...]


@dataclass(frozen=True, slots=True)
class IndirectBit:
    """``.[i]``: the bit of an integer chosen by an expression."""

    bit: Expression


Selector = Member | Index | IndirectBit


@dataclass(frozen=True, slots=True)
class Reference:
    """A tag, optionally followed by members, subscripts and bits: ``X_STAT[0].DN``."""

    base: str
    selectors: tuple[Selector, ...] = ()

    @property
    def constant(self) -> bool:
        """True when every subscript is an immediate value (the address is known before the scan)."""
        for s in self.selectors:
            if isinstance(s, Index) and not all(isinstance(x, Number) for x in s.subscripts):
                return False
            if isinstance(s, IndirectBit):
                return False
        return True

    def __str__(self) -> str:
        out = self.base
        for s in self.selectors:
            if isinstance(s, Member):
                out += f".{s.name}"
            elif isinstance(s, Index):
                out += "[" + ",".join(expression_text(x) for x in s.subscripts) + "]"
            else:
                out += f".[{expression_text(s.bit)}]"
        return out


@dataclass(frozen=True, slots=True)
class Unary:
    op: str  # "-" | "NOT" | a function name (ABS, SQR, SIN, ...)
    operand: Expression


@dataclass(frozen=True, slots=True)
class Binary:
    op: str  # + - * / MOD ** AND OR XOR = <> < <= > >=
    left: Expression
    right: Expression


Expression = Number | Reference | Unary | Binary


def expression_text(e: Expression) -> str:
    """The expression written back in Logix syntax (fully parenthesised where nested)."""
    if isinstance(e, Number):
        return e.text or repr(e.value)
    if isinstance(e, Reference):
        return str(e)
    if isinstance(e, Unary):
        if e.op == "-":
            return f"-{_wrap(e.operand)}"
        if e.op == "NOT":
            return f"NOT {_wrap(e.operand)}"
        return f"{e.op}({expression_text(e.operand)})"
    return f"{_wrap(e.left)} {e.op} {_wrap(e.right)}"


def _wrap(e: Expression) -> str:
    return f"({expression_text(e)})" if isinstance(e, Binary) else expression_text(e)


# -- operands, instructions, rungs --------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Placeholder:
    """``?``: a value the rung shows but does not set (a timer's preset read from its tag)."""


@dataclass(frozen=True, slots=True)
class Name:
    """A bare name that is not a tag: a routine (JSR) or an enumeration value (``Volts``)."""

    text: str


Operand = Reference | Number | Placeholder | Name | Unary | Binary


@dataclass(frozen=True, slots=True)
class Instruction:
    """One instruction of a rung: its mnemonic and operands, in Logix order."""

    mnemonic: str
    operands: tuple[Operand, ...]
    location: SourceLocation = field(default=NOWHERE, compare=False)
    #: 1-based position among the instructions of its rung (errors say "instruction K")
    position: int = field(default=0, compare=False)


@dataclass(frozen=True, slots=True)
class Branch:
    """``BST … NXB … BND`` / ``[ … , … ]``: parallel legs; the rung is true after it when any leg is."""

    legs: tuple[tuple[Element, ...], ...]
    location: SourceLocation = field(default=NOWHERE, compare=False)


Element = Instruction | Branch


@dataclass(frozen=True, slots=True)
class Rung:
    number: int  # 0-based, as Logix numbers rungs
    elements: tuple[Element, ...]
    comment: str = field(default="", compare=False)
    location: SourceLocation = field(default=NOWHERE, compare=False)

    def instructions(self) -> tuple[Instruction, ...]:
        """Every instruction of the rung in scan order (branch legs top to bottom)."""
        out: list[Instruction] = []
        stack: list[Element] = list(reversed(self.elements))
        while stack:
            e = stack.pop()
            if isinstance(e, Instruction):
                out.append(e)
            else:
                for leg in reversed(e.legs):
                    stack.extend(reversed(leg))
        return tuple(out)


@dataclass(frozen=True, slots=True)
class Routine:
    name: str
    rungs: tuple[Rung, ...]
    location: SourceLocation = field(default=NOWHERE, compare=False)


# -- tags ------------------------------------------------------------------------------------

#: Logix data types the tag database holds.
ATOMIC_TYPES = ("BOOL", "SINT", "INT", "DINT", "LINT", "REAL")
STRUCTURE_TYPES = ("TIMER", "COUNTER", "MOTION_INSTRUCTION")
AXIS_TYPES = ("AXIS_CIP_DRIVE", "AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_VIRTUAL", "AXIS_GENERIC")
#: the data type of an axis tag of a rung file, whose type the scenario (or binding) gives
AXIS_UNTYPED = "AXIS"

Scalar = bool | int | float


@dataclass(frozen=True, slots=True)
class Tag:
    """A declared (or, in a rung file, inferred) tag."""

    name: str
    data_type: str  # one of ATOMIC_TYPES, STRUCTURE_TYPES, AXIS_TYPES or AXIS_UNTYPED
    dimensions: tuple[int, ...] = ()  # () for a scalar; up to three dimensions
    #: initial values other than 0 as (member path, value), e.g. ("[2]", 5) or ("PRE", 1000)
    initial: tuple[tuple[str, Scalar], ...] = ()
    scope: str = field(default="", compare=False)  # "" controller scope, else the program's name
    inferred: bool = field(default=False, compare=False)
    description: str = field(default="", compare=False)
    location: SourceLocation = field(default=NOWHERE, compare=False)

    @property
    def is_axis(self) -> bool:
        return self.data_type in AXIS_TYPES or self.data_type == AXIS_UNTYPED


@dataclass(frozen=True, slots=True)
class Program:
    """A whole program: its tags, routines and the routine a scan starts in."""

    name: str
    main: str
    routines: tuple[Routine, ...]
    tags: tuple[Tag, ...]
    form: str = field(default="", compare=False)  # "ascii" | "neutral" | "l5x"
    file: str = field(default="", compare=False)
    #: what the reader inferred or ignored, for the user to know (not errors)
    warnings: tuple[str, ...] = field(default=(), compare=False)

    def routine(self, name: str) -> Routine:
        for r in self.routines:
            if r.name == name:
                return r
        raise KeyError(name)

    def tag(self, name: str) -> Tag:
        for t in self.tags:
            if t.name == name:
                return t
        raise KeyError(name)

    def instructions(self) -> tuple[Instruction, ...]:
        return tuple(i for r in self.routines for rung in r.rungs for i in rung.instructions())

    def mnemonics(self) -> tuple[str, ...]:
        """The instructions the program uses, sorted."""
        return tuple(sorted({i.mnemonic for i in self.instructions()}))

    def axes(self) -> tuple[Tag, ...]:
        return tuple(t for t in self.tags if t.is_axis)
