"""The ladder interpreter: a program IR bound to a tag database and to the axes of a scan.

Pipeline position: program IR + tag database -> **ladder interpreter** -> called by
:class:`statecharts.scan.System` in step 1 of every scan.  Each rung starts with its
rung-condition-in true; every instruction, left to right, receives the rung condition
and hands on its rung-condition-out; a branch gives each leg the condition entering it
and is true after it when any leg is.  Every instruction of a rung is scanned, also
when the rung is false (an OTE then clears its bit).  Motion instructions run their
execution-table row (``rung_true`` / ``rung_false``; ``prescan``) inline, through the
scan module, on their MOTION_INSTRUCTION tag, so a later rung reads the real DN.
The rules, each with its source, are in ``docs/semantics.md`` (section "Ladder
programs"); the interpreter is deterministic and changes nothing but its tag database
and, through the scan module, the motion instructions and axes.

Everything is compiled once, when the program is attached to a system, into closures
over the database's value list; a scan runs no parser and looks nothing up by name
unless an array subscript or bit number is computed from a tag.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from statecharts.diagnostics import Diagnostic
from statecharts.program.ir import (
    Binary,
    Branch,
    Element,
    Expression,
    Index,
    IndirectBit,
    Instruction,
    Member,
    Name,
    Number,
    Operand,
    Program,
    Reference,
    Routine,
    Scalar,
    Unary,
)
from statecharts.program.rungtext import operand_slots
from statecharts.program.tags import INTEGER_BITS, STRUCTURES, TagDatabase, convert, wrap

if TYPE_CHECKING:
    from statecharts.scan import System

DINT_MAX = 2**31 - 1
DINT_MIN = -(2**31)

Run = Callable[[bool], bool]
Action = Callable[[], None]


class ProgramFault(RuntimeError):
    """A major fault of the controller while scanning (Logix halts the program)."""

    def __init__(self, instruction: Instruction, rung: int, fault_type: int, code: int, message: str) -> None:
        self.instruction = instruction
        self.rung = rung
        self.fault_type = fault_type
        self.code = code
        where = f"{instruction.location}: rung {rung}: instruction {instruction.position} ({instruction.mnemonic})"
        super().__init__(f"{where}: major fault (type {fault_type}, code {code}): {message}")


@dataclass(frozen=True, slots=True)
class MinorFault:
    """A minor fault recorded while scanning (division by zero and other arithmetic errors)."""

    scan: int
    rung: int
    instruction: int
    mnemonic: str
    fault_type: int
    code: int
    message: str


@dataclass(frozen=True, slots=True)
class MotionBinding:
    """A motion instruction of the program and the MOTION_INSTRUCTION tag element it runs on."""

    tag: str  # canonical element path, e.g. "X_STAT[0]"
    mnemonic: str
    axis: str
    instruction: Instruction
    routine: str
    rung: int


class _ArithmeticError(Exception):
    pass


def canonical(ref: Reference) -> str:
    """The element path of a reference with immediate subscripts: ``X_STAT[0]``, ``T1.DN``."""
    out = ref.base
    for s in ref.selectors:
        if isinstance(s, Index):
            out += "[" + ",".join(str(int(x.value)) for x in s.subscripts if isinstance(x, Number)) + "]"
        elif isinstance(s, Member):
            out += f".{s.name}"
    return out


def motion_bindings(program: Program, diagnostics: list[Diagnostic]) -> list[MotionBinding]:
    """Every motion instruction with its tag and axis, in program order; a tag used twice is an error."""
    from statecharts.program.table import instruction_table

    motion = instruction_table().motion
    out: list[MotionBinding] = []
    seen: dict[str, MotionBinding] = {}
    for routine in program.routines:
        for rung in routine.rungs:
            for ins in rung.instructions():
                if ins.mnemonic not in motion or len(ins.operands) < 2:
                    continue
                axis, tag = ins.operands[0], ins.operands[1]
                if not isinstance(axis, Reference) or not isinstance(tag, Reference):
                    continue
                where = f"rung {rung.number}: instruction {ins.position}"
                if not tag.constant:
                    diagnostics.append(Diagnostic(ins.location.file, ins.location.line, ins.location.column, where, (
                        f"the MOTION_INSTRUCTION tag of {ins.mnemonic} must have immediate subscripts, not {tag}")))
                    continue
                name = canonical(tag)
                if name in seen:
                    first = seen[name]
                    diagnostics.append(Diagnostic(ins.location.file, ins.location.line, ins.location.column, where, (
                        f"{ins.mnemonic} uses MOTION_INSTRUCTION tag {name}, already used by {first.mnemonic} in rung "
                        f"{first.rung} ({first.instruction.location}); each motion instruction needs its own tag")))
                    continue
                b = MotionBinding(name, ins.mnemonic, axis.base, ins, routine.name, rung.number)
                seen[name] = b
                out.append(b)
    return out


class Ladder:
    """A program ready to scan: its tag database and, once attached, its compiled routines."""

    def __init__(self, program: Program, *, scan_ms: int = 10) -> None:
        self.program = program
        self.db = TagDatabase(program.tags)
        self.scan_ms = scan_ms
        problems: list[Diagnostic] = []
        self.bindings = motion_bindings(program, problems)
        self.binding_problems = tuple(problems)
        self.system: System | None = None
        self.minor_faults: list[MinorFault] = []
        self._routines: dict[str, list[tuple[list[tuple[Run, Instruction]], bool]]] = {}
        self._prescans: dict[str, list[Action]] = {}
        self._postscans: dict[str, list[Action]] = {}
        self._returning = False
        self._prescanned: set[str] = set()
        self._write_slots: dict[str, tuple[int, str, int | None]] = {}
        self._set_initial_values()

    # -- set-up ------------------------------------------------------------------------

    def _set_initial_values(self) -> None:
        for tag in self.program.tags:
            layout = self.db.layouts.get(tag.name)
            if layout is None:
                continue
            leaves = {suffix: (slot, t) for suffix, slot, t in self.db.leaves(tag.name)}
            for path, value in tag.initial:
                key = path.lstrip(".") if not path.startswith("[") else path
                if key in leaves:
                    slot, t = leaves[key]
                    self.db.values[slot] = convert(t, value)
        self.db.initial = tuple(self.db.values)

    def attach(self, system: System) -> None:
        """Compile the routines against ``system``'s axes and motion tags; raises ProgramBindError."""
        from statecharts.program.reader import ProgramError

        self.system = system
        problems: list[Diagnostic] = list(self.binding_problems)
        compiler = _Compiler(self, system, problems)
        for routine in self.program.routines:
            self._routines[routine.name] = compiler.routine(routine)
            self._prescans[routine.name] = compiler.prescans.pop(routine.name, [])
            self._postscans[routine.name] = compiler.postscans.pop(routine.name, [])
        if problems:
            raise ProgramError(problems)

    # -- scanning ----------------------------------------------------------------------

    def scan(self) -> None:
        """One scan of the main routine (and the routines it calls)."""
        self.run_routine(self.program.main)

    def run_routine(self, name: str) -> None:
        self._returning = False
        for steps, has_ret in self._routines[name]:
            rung = True
            if has_ret:
                for run, _ins in steps:
                    rung = run(rung)
                    if self._returning:
                        break
                if self._returning:
                    break
            else:
                for run, _ins in steps:
                    rung = run(rung)
        self._returning = False

    def prescan(self) -> None:
        """The prescan of Logix on entering Run mode: every routine reached from the main one, once."""
        self._prescanned = set()
        self.prescan_routine(self.program.main)

    def prescan_routine(self, name: str) -> None:
        if name in self._prescanned:
            return
        self._prescanned.add(name)
        for action in self._prescans[name]:
            action()

    def postscan(self) -> None:
        """The postscan of every routine (what Logix does to a routine it stops scanning, e.g. an SFC action)."""
        for name in self._postscans:
            for action in self._postscans[name]:
                action()

    # -- tags ------------------------------------------------------------------------------

    def observe(self) -> dict[str, dict[str, Scalar]]:
        """Every BOOL, integer, REAL, TIMER and COUNTER value: {tag: {path suffix: value}}."""
        out: dict[str, dict[str, Scalar]] = {}
        values = self.db.values
        for name, layout in self.db.layouts.items():
            if layout.data_type == "MOTION_INSTRUCTION":
                continue
            out[name] = {suffix: values[slot] for suffix, slot, _t in self.db.leaves(name)}
        return out

    def paths(self) -> dict[str, tuple[str, str]]:
        """Observable label -> (observation object, field), e.g. ``T1.DN`` -> (``T1``, ``DN``)."""
        out: dict[str, tuple[str, str]] = {}
        for name, layout in self.db.layouts.items():
            if layout.data_type == "MOTION_INSTRUCTION":
                continue
            for suffix, _slot, _t in self.db.leaves(name):
                out[label(name, suffix)] = (name, suffix)
        return out

    def slot(self, path: str) -> tuple[int, str, int | None]:
        """(slot, type, bit) of a writable path such as ``START_PB``, ``Arr[3]``, ``T1.PRE``, ``Flags.2``."""
        from statecharts.program.logix_expr import ExpressionSyntaxError, parse_reference

        try:
            ref = parse_reference(path)
        except ExpressionSyntaxError as exc:
            raise KeyError(f"{path!r} is not a tag path: {exc.message}") from None
        if not ref.constant:
            raise KeyError(f"{path!r}: write a tag path with immediate subscripts")
        resolved = _resolve_static(self.db, ref)
        if isinstance(resolved, str):
            raise KeyError(resolved)
        slot, t, bit = resolved
        if t in STRUCTURES:
            raise KeyError(f"{path!r} is a whole {t}; write one of its members: "
                           f"{', '.join(m for m, _ in STRUCTURES[t])}")
        if self.db.layouts[ref.base].data_type == "MOTION_INSTRUCTION":
            raise KeyError(f"{path!r}: members of a MOTION_INSTRUCTION tag are set by its instruction, not written")
        return slot, t, bit

    def read(self, path: str) -> Scalar:
        """The value of a program tag path, a motion tag member or an axis member."""
        system = self.system
        if system is not None:
            head, _, member = path.rpartition(".")
            if head in system.tags:
                inst = system.tags[head]
                return inst.flags if member == "FLAGS" else inst.values[member]  # type: ignore[return-value]  # motion tag members are BOOL or integers
            if head in system.axes:
                return system.axes[head].observe()[member]  # type: ignore[return-value]  # program-readable axis values are scalars
        slot, _t, bit = self.slot(path)
        v = self.db.values[slot]
        if bit is not None:
            return bool((int(v) >> bit) & 1)
        return v

    def write(self, path: str, value: Scalar) -> None:
        """Write a program tag path (``START_PB``, ``Arr[3]``, ``T1.PRE``, ``Flags.2``); KeyError names a bad one."""
        where = self._write_slots.get(path)
        if where is None:
            where = self._write_slots[path] = self.slot(path)
        slot, t, bit = where
        if bit is not None:
            word = int(self.db.values[slot])
            word = word | (1 << bit) if value else word & ~(1 << bit)
            self.db.values[slot] = wrap(word, INTEGER_BITS[t])
        else:
            self.db.values[slot] = convert(t, value)


def label(obj: str, suffix: str) -> str:
    """How a value is named in tables and expectations: ``STATE``, ``Arr[2]``, ``T1.DN``."""
    if not suffix:
        return obj
    return obj + suffix if suffix.startswith("[") else f"{obj}.{suffix}"


def _resolve_static(db: TagDatabase, ref: Reference) -> tuple[int, str, int | None] | str:
    """(slot, type, bit) of a reference with immediate subscripts, or why it does not name a value."""
    layout = db.layouts.get(ref.base)
    if layout is None:
        return f"no tag {ref.base!r}"
    sels = list(ref.selectors)
    element = 0
    if layout.dimensions:
        if not sels or not isinstance(sels[0], Index):
            return f"{ref} is a whole array {ref.base}{list(layout.dimensions)}; give a subscript"
        index = sels.pop(0)
        assert isinstance(index, Index)
        subs = [int(x.value) for x in index.subscripts if isinstance(x, Number)]
        if len(subs) != len(layout.dimensions):
            return f"{ref}: {ref.base} has {len(layout.dimensions)} dimension(s)"
        e = layout.element_index(subs)
        if e is None:
            return f"{ref}: subscript out of range for {ref.base}{list(layout.dimensions)}"
        element = e
    slot = layout.offset + element * layout.size
    t = layout.data_type
    head = sels[0] if sels else None
    if isinstance(head, Member) and t in STRUCTURES:
        sels.pop(0)
        m = layout.member(head.name)
        if m is None:
            return f"{ref}: a {t} has no member {ref.selectors[-1]}; members: {', '.join(n for n, _ in STRUCTURES[t])}"
        slot += m[0]
        t = m[1]
    bit: int | None = None
    first = sels[0] if sels else None
    if isinstance(first, Member) and first.bit is not None and t in INTEGER_BITS:
        sels.pop(0)
        bit = first.bit
        if bit is not None and bit >= INTEGER_BITS[t]:
            return f"{ref}: bit {bit} is beyond the {INTEGER_BITS[t]} bits of a {t}"
    if sels:
        return f"{ref}: cannot select {sels[0]} of a {t}"
    return slot, t, bit


class _Compiler:
    """Turns routines into closures over one ladder's tag database and one system."""

    def __init__(self, ladder: Ladder, system: System, problems: list[Diagnostic]) -> None:
        self.ladder = ladder
        self.system = system
        self.db = ladder.db
        self.values = ladder.db.values
        self.problems = problems
        self.prescans: dict[str, list[Action]] = {}
        self.postscans: dict[str, list[Action]] = {}
        self.rung = 0
        self.routine_name = ""

    def problem(self, ins: Instruction, message: str) -> None:
        loc = ins.location
        self.problems.append(Diagnostic(loc.file, loc.line, loc.column, f"rung {self.rung}: instruction {ins.position}",
                                        message))

    def routine(self, routine: Routine) -> list[tuple[list[tuple[Run, Instruction]], bool]]:
        self.routine_name = routine.name
        pre: list[Action] = []
        post: list[Action] = []
        out: list[tuple[list[tuple[Run, Instruction]], bool]] = []
        for rung in routine.rungs:
            self.rung = rung.number
            steps = [(self.element(e, pre, post), _first(e)) for e in rung.elements]
            out.append((steps, any(i.mnemonic == "RET" for i in rung.instructions())))
        self.prescans[routine.name] = pre
        self.postscans[routine.name] = post
        return out

    def element(self, e: Element, pre: list[Action], post: list[Action]) -> Run:
        if isinstance(e, Branch):
            legs = [[self.element(x, pre, post) for x in leg] for leg in e.legs]

            def branch(rci: bool) -> bool:
                out = False
                for leg in legs:
                    r = rci
                    for run in leg:
                        r = run(r)
                    out = out or r
                return out
            return branch
        return self.instruction(e, pre, post)

    # -- operands ----------------------------------------------------------------------------

    def reader(self, ins: Instruction, op: Operand) -> Callable[[], Scalar] | None:
        """A function giving the operand's current value (immediate, tag, motion or axis member)."""
        if isinstance(op, Number):
            value = op.value
            return lambda: value
        if isinstance(op, Reference):
            return self.ref_reader(ins, op)
        if isinstance(op, (Unary, Binary)):
            return self.expression(ins, op)
        self.problem(ins, f"{op} is not a value")
        return None

    def ref_reader(self, ins: Instruction, ref: Reference) -> Callable[[], Scalar] | None:
        system = self.system
        if ref.base in system.axes:
            return self.axis_reader(ins, ref)
        layout = self.db.layouts.get(ref.base)
        if layout is None:
            self.problem(ins, f"undefined tag {ref.base!r}")
            return None
        if layout.data_type == "MOTION_INSTRUCTION":
            return self.motion_reader(ins, ref)
        addr = self.address(ins, ref)
        if addr is None:
            return None
        locate, _t, bit = addr
        values = self.values
        if isinstance(locate, int):
            slot = locate
            if bit is None:
                return lambda: values[slot]
            if isinstance(bit, int):
                b = bit
                return lambda: bool((int(values[slot]) >> b) & 1)
            bitf = bit
            return lambda: bool((int(values[slot]) >> bitf()) & 1)
        slotf = locate
        if bit is None:
            return lambda: values[slotf()]
        if isinstance(bit, int):
            b2 = bit
            return lambda: bool((int(values[slotf()]) >> b2) & 1)
        bitf2 = bit
        return lambda: bool((int(values[slotf()]) >> bitf2()) & 1)

    def writer(self, ins: Instruction, op: Operand) -> tuple[Callable[[Scalar], None], str] | None:
        """A function storing a value into the operand (with the conversion of its type), and the type."""
        if not isinstance(op, Reference):
            self.problem(ins, f"{op} cannot be written")
            return None
        if op.base in self.system.axes:
            self.problem(ins, f"{op}: axis members are read-only in the model")
            return None
        layout = self.db.layouts.get(op.base)
        if layout is None:
            self.problem(ins, f"undefined tag {op.base!r}")
            return None
        if layout.data_type == "MOTION_INSTRUCTION":
            self.problem(ins, f"{op}: members of a MOTION_INSTRUCTION tag are set by its instruction, not by the program")
            return None
        addr = self.address(ins, op)
        if addr is None:
            return None
        locate, t, bit = addr
        values = self.values
        if t in STRUCTURES:
            self.problem(ins, f"{op} is a whole {t}, not a value")
            return None
        if bit is not None:
            width = INTEGER_BITS[t]

            def set_bit(v: Scalar) -> None:
                s = locate if isinstance(locate, int) else locate()
                b = bit if isinstance(bit, int) else bit()
                word = int(values[s])
                values[s] = wrap(word | (1 << b) if v else word & ~(1 << b), width)
            return set_bit, "BOOL"
        if isinstance(locate, int):
            slot = locate
            if t == "BOOL":
                def set_bool(v: Scalar) -> None:
                    values[slot] = bool(v)
                return set_bool, t

            def set_value(v: Scalar) -> None:
                values[slot] = convert(t, v)
            return set_value, t
        slotf = locate

        def set_dynamic(v: Scalar) -> None:
            values[slotf()] = convert(t, v)
        return set_dynamic, t

    def address(self, ins: Instruction, ref: Reference) -> tuple[int | Callable[[], int], str, int | Callable[[], int] | None] | None:
        """(slot or slot function, type, bit or bit function) of a reference into the database."""
        layout = self.db.layouts[ref.base]
        sels = list(ref.selectors)
        t = layout.data_type
        base = layout.offset
        offset: int | Callable[[], int] = base
        if layout.dimensions:
            if not sels or not isinstance(sels[0], Index):
                self.problem(ins, f"{ref}: {ref.base} is an array {list(layout.dimensions)}; give a subscript")
                return None
            index = sels.pop(0)
            assert isinstance(index, Index)
            if len(index.subscripts) != len(layout.dimensions):
                self.problem(ins, f"{ref}: {ref.base} has {len(layout.dimensions)} dimension(s), "
                                  f"not {len(index.subscripts)}")
                return None
            immediate = [int(s.value) for s in index.subscripts if isinstance(s, Number)]
            if len(immediate) == len(index.subscripts):
                e = layout.element_index(immediate)
                if e is None:
                    self.problem(ins, f"{ref}: subscript out of range for {ref.base}{list(layout.dimensions)}")
                    return None
                offset = base + e * layout.size
            else:
                subs = [self.expression(ins, s) for s in index.subscripts]
                if any(s is None for s in subs):
                    return None
                dims, size, name = layout.dimensions, layout.size, ref.base
                subfs = [s for s in subs if s is not None]
                instr = ins
                rung = self.rung

                def element() -> int:
                    idx = [int(f()) for f in subfs]
                    e2 = layout.element_index(idx)
                    if e2 is None:
                        raise ProgramFault(instr, rung, 4, 20, (
                            f"array subscript {idx} out of range for {name}{list(dims)}"))
                    return base + e2 * size
                offset = element
        member_slot = 0
        if sels and isinstance(sels[0], Member) and t in STRUCTURES:
            m = layout.member(sels[0].name)
            if m is None:
                self.problem(ins, f"{ref}: a {t} has no member {sels[0].name!r}; members: "
                                  f"{', '.join(n for n, _ in STRUCTURES[t])}")
                return None
            sels.pop(0)
            member_slot, t = m
        bit: int | Callable[[], int] | None = None
        if sels:
            s = sels.pop(0)
            if t not in INTEGER_BITS:
                self.problem(ins, f"{ref}: a {t} has no bits or members to select")
                return None
            width = INTEGER_BITS[t]
            if isinstance(s, Member) and s.bit is not None:
                if s.bit >= width:
                    self.problem(ins, f"{ref}: bit {s.bit} is beyond the {width} bits of a {t}")
                    return None
                bit = s.bit
            elif isinstance(s, IndirectBit):
                bf = self.expression(ins, s.bit)
                if bf is None:
                    return None
                instr2, rung2 = ins, self.rung

                def bit_number() -> int:
                    b = int(bf())
                    if not 0 <= b < width:
                        raise ProgramFault(instr2, rung2, 4, 20, f"bit number {b} out of range for a {t}")
                    return b
                bit = bit_number
            else:
                self.problem(ins, f"{ref}: a {t} has no member {s}")
                return None
            if bit is not None:
                word_type = t
                t = word_type
        if sels:
            self.problem(ins, f"{ref}: nothing can be selected after {ref.selectors[-len(sels) - 1]}")
            return None
        if isinstance(offset, int):
            return offset + member_slot, t, bit
        off_f = offset
        if member_slot:
            ms = member_slot
            return (lambda: off_f() + ms), t, bit
        return off_f, t, bit

    def structure(self, ins: Instruction, op: Operand, kinds: tuple[str, ...]) -> tuple[Callable[[], int] | int, str] | None:
        """The first slot of a TIMER or COUNTER element (an int, or a function for computed subscripts)."""
        if not isinstance(op, Reference) or op.base not in self.db.layouts:
            self.problem(ins, f"{op}: expected a {' or '.join(kinds)} tag")
            return None
        layout = self.db.layouts[op.base]
        if layout.data_type not in kinds:
            self.problem(ins, f"{op} is a {layout.data_type}; {ins.mnemonic} needs a {' or '.join(kinds)}")
            return None
        addr = self.address(ins, op)
        if addr is None:
            return None
        locate, t, bit = addr
        if t != layout.data_type or bit is not None:
            self.problem(ins, f"{op}: {ins.mnemonic} needs the whole {layout.data_type}, not a member")
            return None
        return locate, t

    def motion_reader(self, ins: Instruction, ref: Reference) -> Callable[[], Scalar] | None:
        sels = list(ref.selectors)
        if not sels or not isinstance(sels[-1], Member):
            self.problem(ins, f"{ref}: read a member of the MOTION_INSTRUCTION tag ("
                              f"{', '.join(m for m, _ in STRUCTURES['MOTION_INSTRUCTION'])})")
            return None
        member = sels[-1].name
        members = [m for m, _ in STRUCTURES["MOTION_INSTRUCTION"]]
        if member not in members:
            self.problem(ins, f"{ref}: a MOTION_INSTRUCTION has no member {member!r}; members: {', '.join(members)}")
            return None
        element = Reference(ref.base, tuple(sels[:-1]))
        tags = self.system.tags
        if element.constant:
            name = canonical(element)
            inst = tags.get(name)
            if inst is None:
                # a MOTION_INSTRUCTION no instruction uses: its members keep their values
                addr = self.address(ins, ref)
                if addr is None:
                    return None
                slot = addr[0]
                values = self.values
                if isinstance(slot, int):
                    s = slot
                    return lambda: values[s]
                sf = slot
                return lambda: values[sf()]
            if member == "FLAGS":
                return lambda: inst.flags
            vals = inst.values
            return lambda: vals[member]  # type: ignore[return-value]  # motion tag members are BOOL or integers
        addr = self.address(ins, Reference(ref.base, tuple(sels[:-1])))
        if addr is None:
            return None
        layout = self.db.layouts[ref.base]
        slot_f = addr[0]
        values = self.values
        dims = layout.dimensions
        base, size = layout.offset, layout.size
        member_slot = layout.member(member)
        assert member_slot is not None

        def read_dynamic() -> Scalar:
            s = slot_f if isinstance(slot_f, int) else slot_f()
            e = (s - base) // size
            subs = []
            for d in reversed(dims):
                subs.append(e % d)
                e //= d
            name2 = ref.base + "[" + ",".join(str(x) for x in reversed(subs)) + "]"
            inst2 = tags.get(name2)
            if inst2 is None:
                return values[s + member_slot[0]]
            return inst2.flags if member == "FLAGS" else inst2.values[member]  # type: ignore[return-value]  # motion tag members are BOOL or integers
        return read_dynamic

    def axis_reader(self, ins: Instruction, ref: Reference) -> Callable[[], Scalar] | None:
        axis = self.system.axes[ref.base]
        chart = axis.chart
        readable = [chart.state_attribute] + [v.name for v in chart.variables if v.type in ("bool", "int", "real")]
        if len(ref.selectors) != 1 or not isinstance(ref.selectors[0], Member) or ref.selectors[0].bit is not None:
            self.problem(ins, f"{ref}: read one member of axis {ref.base}: {', '.join(readable)}")
            return None
        member = ref.selectors[0].name
        if member == chart.state_attribute:
            return lambda: axis.value or 0
        if member not in readable:
            enum = [v.name for v in chart.variables if v.type == "enum"]
            extra = f" ({member} is an enumeration in the model)" if member in enum else ""
            self.problem(ins, f"{ref}: axis {ref.base} ({chart.id}) has no readable member {member!r}{extra}; "
                              f"readable members: {', '.join(readable)}")
            return None
        env = axis.env
        return lambda: env[member]  # type: ignore[return-value]  # only bool, int and real variables are readable (checked above)

    def expression(self, ins: Instruction, e: Expression) -> Callable[[], Scalar] | None:
        if isinstance(e, Number):
            v = e.value
            return lambda: v
        if isinstance(e, Reference):
            return self.ref_reader(ins, e)
        if isinstance(e, Unary):
            f = self.expression(ins, e.operand)
            if f is None:
                return None
            fn = _UNARY[e.op]
            return lambda: fn(f())
        lf, rf = self.expression(ins, e.left), self.expression(ins, e.right)
        if lf is None or rf is None:
            return None
        op = _BINARY[e.op]
        return lambda: op(lf(), rf())

    # -- instructions ---------------------------------------------------------------------

    def instruction(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run:
        m = ins.mnemonic
        build = getattr(self, f"_{m}", None)
        if build is None:
            slots = operand_slots(m, self.system.spec)
            if isinstance(slots, tuple) and m in _motion():
                return self._motion(ins, pre)
            self.problem(ins, slots if isinstance(slots, str) else f"{m} is not executable")
            return _passthrough
        run: Run | None = build(ins, pre, post)
        return run if run is not None else _passthrough

    def _XIC(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        get = self.bit_reader(ins, ins.operands[0])
        if get is None:
            return None
        return lambda rci: rci and bool(get())

    def _XIO(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        get = self.bit_reader(ins, ins.operands[0])
        if get is None:
            return None
        return lambda rci: rci and not get()

    def bit_reader(self, ins: Instruction, op: Operand) -> Callable[[], Scalar] | None:
        get = self.reader(ins, op)
        if get is None:
            return None
        if isinstance(op, Reference) and op.base in self.db.layouts:
            addr_type = self._type_of(op)
            if addr_type is not None and addr_type != "BOOL":
                self.problem(ins, f"{op} is a {addr_type}; {ins.mnemonic} examines a BOOL (a bit: {op}.0)")
                return None
        return get

    def _type_of(self, ref: Reference) -> str | None:
        layout = self.db.layouts[ref.base]
        t = layout.data_type
        sels = list(ref.selectors)
        if layout.dimensions and sels and isinstance(sels[0], Index):
            sels.pop(0)
        first = sels[0] if sels else None
        if isinstance(first, Member) and t in STRUCTURES:
            sels.pop(0)
            m = layout.member(first.name)
            if m is None:
                return None
            t = m[1]
        if sels:
            return "BOOL"
        return t

    def bit_writer(self, ins: Instruction, op: Operand) -> Callable[[Scalar], None] | None:
        w = self.writer(ins, op)
        if w is None:
            return None
        setter, t = w
        if t != "BOOL":
            self.problem(ins, f"{op} is a {t}; {ins.mnemonic} writes a BOOL (a bit: {op}.0)")
            return None
        return setter

    def _OTE(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        put = self.bit_writer(ins, ins.operands[0])
        if put is None:
            return None
        pre.append(lambda: put(False))  # RM003N p96: prescan clears the bit
        post.append(lambda: put(False))

        def ote(rci: bool) -> bool:
            put(rci)
            return rci
        return ote

    def _OTL(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        put = self.bit_writer(ins, ins.operands[0])
        if put is None:
            return None

        def otl(rci: bool) -> bool:
            if rci:
                put(True)
            return rci
        return otl

    def _OTU(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        put = self.bit_writer(ins, ins.operands[0])
        if put is None:
            return None

        def otu(rci: bool) -> bool:
            if rci:
                put(False)
            return rci
        return otu

    def _ONS(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        get = self.bit_reader(ins, ins.operands[0])
        put = self.bit_writer(ins, ins.operands[0])
        if get is None or put is None:
            return None
        pre.append(lambda: put(True))  # RM003N p103: set, so the first scan cannot trigger
        post.append(lambda: put(False))

        def ons(rci: bool) -> bool:
            if not rci:
                put(False)
                return False
            if get():
                return False
            put(True)
            return True
        return ons

    def _OSR(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        get = self.bit_reader(ins, ins.operands[0])
        put = self.bit_writer(ins, ins.operands[0])
        out = self.bit_writer(ins, ins.operands[1])
        if get is None or put is None or out is None:
            return None

        def osr_pre() -> None:
            put(True)
            out(False)
        pre.append(osr_pre)

        def osr(rci: bool) -> bool:
            if rci:
                if get():
                    out(False)
                else:
                    put(True)
                    out(True)
            else:
                put(False)
                out(False)
            return rci
        return osr

    def _OSF(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        get = self.bit_reader(ins, ins.operands[0])
        put = self.bit_writer(ins, ins.operands[0])
        out = self.bit_writer(ins, ins.operands[1])
        if get is None or put is None or out is None:
            return None

        def osf_pre() -> None:
            put(False)
            out(False)
        pre.append(osf_pre)

        def osf(rci: bool) -> bool:
            if rci:
                put(True)
                out(False)
            elif get():
                put(False)
                out(True)
            else:
                out(False)
            return rci
        return osf

    def _timer(self, ins: Instruction, kind: str, pre: list[Action]) -> Run | None:
        located = self.structure(ins, ins.operands[0], ("TIMER",))
        if located is None:
            return None
        locate, _t = located
        values = self.values
        dt = self.ladder.scan_ms
        rung = self.rung
        base_f: Callable[[], int] = (lambda: locate) if isinstance(locate, int) else locate

        def check(b: int) -> None:
            if values[b] < 0 or values[b + 1] < 0:
                raise ProgramFault(ins, rung, 4, 34, f"negative timer preset or accumulator "
                                                     f"(PRE {values[b]}, ACC {values[b + 1]})")

        def timing(b: int) -> None:
            # RM003N p118 (TON) / p127 (RTO), rung-condition-in true
            if values[b + 4]:
                return
            if not values[b + 2]:
                values[b + 2] = True
                values[b + 3] = True
                return
            acc = int(values[b + 1]) + dt
            values[b + 1] = DINT_MAX if acc > DINT_MAX else acc
            if values[b + 1] >= values[b]:
                values[b + 4] = True
                values[b + 3] = False
            else:
                values[b + 3] = True

        if kind == "TON":
            def ton_off(b: int) -> None:
                values[b + 2] = values[b + 3] = values[b + 4] = False
                values[b + 1] = 0
            pre.append(lambda: ton_off(base_f()))

            def ton(rci: bool) -> bool:
                b = base_f()
                if rci:
                    check(b)
                    timing(b)
                else:
                    ton_off(b)
                return rci
            return ton
        if kind == "RTO":
            def rto_pre() -> None:
                b = base_f()
                values[b + 2] = values[b + 3] = values[b + 4] = False
            pre.append(rto_pre)

            def rto(rci: bool) -> bool:
                b = base_f()
                if rci:
                    check(b)
                    timing(b)
                else:
                    values[b + 2] = values[b + 3] = False
                return rci
            return rto

        def tof_pre() -> None:
            b = base_f()
            values[b + 2] = values[b + 3] = values[b + 4] = False
            values[b + 1] = values[b]
        pre.append(tof_pre)

        def tof(rci: bool) -> bool:
            # RM003N p122
            b = base_f()
            if rci:
                values[b + 2] = True
                values[b + 3] = False
                values[b + 4] = True
                values[b + 1] = 0
                return rci
            check(b)
            if not values[b + 4]:
                values[b + 2] = False
                return rci
            if values[b + 2]:
                values[b + 2] = False
                values[b + 3] = True
                return rci
            acc = int(values[b + 1]) + dt
            values[b + 1] = DINT_MAX if acc > DINT_MAX else acc
            if values[b + 1] >= values[b]:
                values[b + 4] = False
                values[b + 3] = False
            else:
                values[b + 3] = True
            return rci
        return tof

    def _TON(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._timer(ins, "TON", pre)

    def _TOF(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._timer(ins, "TOF", pre)

    def _RTO(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._timer(ins, "RTO", pre)

    def _counter(self, ins: Instruction, up: bool, pre: list[Action]) -> Run | None:
        located = self.structure(ins, ins.operands[0], ("COUNTER",))
        if located is None:
            return None
        locate, _t = located
        values = self.values
        base_f: Callable[[], int] = (lambda: locate) if isinstance(locate, int) else locate
        edge = 2 if up else 3  # CU / CD

        def counter_pre() -> None:
            values[base_f() + edge] = True  # RM003N p143/p146: no count on the first scan
        pre.append(counter_pre)

        def count(rci: bool) -> bool:
            b = base_f()
            if not rci:
                values[b + edge] = False
                return rci
            if not values[b + edge]:
                values[b + edge] = True
                acc = int(values[b + 1]) + (1 if up else -1)
                if acc > DINT_MAX or acc < DINT_MIN:
                    acc = wrap(acc, 32)
                    same, other = (5, 6) if up else (6, 5)  # OV / UN
                    if values[b + other]:
                        values[b + other] = False
                    else:
                        values[b + same] = True
                values[b + 1] = acc
            if values[b + 5] or values[b + 6]:
                values[b + 4] = False
            else:
                values[b + 4] = values[b + 1] >= values[b]
            return rci
        return count

    def _CTU(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._counter(ins, True, pre)

    def _CTD(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._counter(ins, False, pre)

    def _RES(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        located = self.structure(ins, ins.operands[0], ("TIMER", "COUNTER"))
        if located is None:
            return None
        locate, t = located
        values = self.values
        base_f: Callable[[], int] = (lambda: locate) if isinstance(locate, int) else locate
        bits = (2, 3, 4) if t == "TIMER" else (2, 3, 4, 5, 6)

        def res(rci: bool) -> bool:
            if rci:
                b = base_f()
                values[b + 1] = 0
                for k in bits:
                    values[b + k] = False
            return rci
        return res

    def value_and_dest(self, ins: Instruction, src: Operand, dst: Operand) -> tuple[Callable[[], Scalar], Callable[[Scalar], None]] | None:
        get = self.reader(ins, src)
        w = self.writer(ins, dst)
        if get is None or w is None:
            return None
        return get, w[0]

    def _MOV(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        pair = self.value_and_dest(ins, ins.operands[0], ins.operands[1])
        if pair is None:
            return None
        get, put = pair

        def mov(rci: bool) -> bool:
            if rci:
                put(get())
            return rci
        return mov

    def _CLR(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        w = self.writer(ins, ins.operands[0])
        if w is None:
            return None
        put = w[0]

        def clr(rci: bool) -> bool:
            if rci:
                put(0)
            return rci
        return clr

    def _COP(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        src, dst, length = ins.operands
        if not isinstance(src, Reference) or not isinstance(dst, Reference) or \
                src.base not in self.db.layouts or dst.base not in self.db.layouts:
            self.problem(ins, "COP copies from a tag to a tag of the program")
            return None
        sl, dl = self.db.layouts[src.base], self.db.layouts[dst.base]
        if sl.data_type != dl.data_type:
            self.problem(ins, f"COP between {sl.data_type} and {dl.data_type}: only copies between tags of the same "
                              f"data type are modelled")
            return None
        if dl.data_type == "MOTION_INSTRUCTION":
            self.problem(ins, "COP into a MOTION_INSTRUCTION tag: its members are set by its instruction")
            return None
        sa = self.address(ins, Reference(src.base, tuple(s for s in src.selectors if isinstance(s, Index))))
        da = self.address(ins, Reference(dst.base, tuple(s for s in dst.selectors if isinstance(s, Index))))
        n = self.reader(ins, length)
        if sa is None or da is None or n is None:
            return None
        values = self.values
        s_end, d_end = sl.offset + sl.count * sl.size, dl.offset + dl.count * dl.size
        size = dl.size
        sloc, dloc = sa[0], da[0]
        t = dl.data_type
        member_types = [mt for _, mt in STRUCTURES.get(t, ())] or [t]

        def cop(rci: bool) -> bool:
            if rci:
                s0 = sloc if isinstance(sloc, int) else sloc()
                d0 = dloc if isinstance(dloc, int) else dloc()
                count = max(0, int(n()))
                # the copy stops at the end of either array (INT-P09)
                count = min(count * size, s_end - s0, d_end - d0)
                chunk = values[s0:s0 + count]
                for k, v in enumerate(chunk):
                    values[d0 + k] = convert(member_types[(d0 + k - dl.offset) % size], v)
            return rci
        return cop

    def _compare(self, ins: Instruction, test: Callable[[Scalar, Scalar], bool]) -> Run | None:
        a, b = self.reader(ins, ins.operands[0]), self.reader(ins, ins.operands[1])
        if a is None or b is None:
            return None
        return lambda rci: rci and test(a(), b())

    def _EQU(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._compare(ins, lambda x, y: x == y)

    def _NEQ(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._compare(ins, lambda x, y: x != y)

    def _LES(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._compare(ins, lambda x, y: x < y)

    def _LEQ(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._compare(ins, lambda x, y: x <= y)

    def _GRT(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._compare(ins, lambda x, y: x > y)

    def _GEQ(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._compare(ins, lambda x, y: x >= y)

    def _LIM(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        lo, test, hi = (self.reader(ins, o) for o in ins.operands)
        if lo is None or test is None or hi is None:
            return None

        def lim(rci: bool) -> bool:
            if not rci:
                return False
            low, t, high = lo(), test(), hi()
            if low <= high:
                return bool(low <= t <= high)
            return bool(t >= low or t <= high)
        return lim

    def _CMP(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        f = self.reader(ins, ins.operands[0])
        if f is None:
            return None
        fault = self.minor

        def cmp(rci: bool) -> bool:
            if not rci:
                return False
            try:
                return bool(f())
            except _ArithmeticError as exc:
                fault(ins, str(exc))
                return False
        return cmp

    def minor(self, ins: Instruction, message: str) -> None:
        ladder = self.ladder
        rung = self.rung
        system = self.system
        ladder.minor_faults.append(MinorFault(system.index, rung, ins.position, ins.mnemonic, 4, 4, message))

    def _math(self, ins: Instruction, dest: Operand, compute: Callable[[], Scalar]) -> Run | None:
        w = self.writer(ins, dest)
        if w is None:
            return None
        put = w[0]
        ladder, rung, system = self.ladder, self.rung, self.system

        def math_ins(rci: bool) -> bool:
            if rci:
                try:
                    put(compute())
                except _ArithmeticError as exc:
                    # the destination keeps its value (INT-P08)
                    ladder.minor_faults.append(MinorFault(system.index, rung, ins.position, ins.mnemonic, 4, 4, str(exc)))
            return rci
        return math_ins

    def _binary_math(self, ins: Instruction, op: str) -> Run | None:
        a, b = self.reader(ins, ins.operands[0]), self.reader(ins, ins.operands[1])
        if a is None or b is None:
            return None
        f = _BINARY[op]
        return self._math(ins, ins.operands[2], lambda: f(a(), b()))

    def _ADD(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._binary_math(ins, "+")

    def _SUB(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._binary_math(ins, "-")

    def _MUL(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._binary_math(ins, "*")

    def _DIV(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._binary_math(ins, "/")

    def _MOD(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return self._binary_math(ins, "MOD")

    def _NEG(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        a = self.reader(ins, ins.operands[0])
        if a is None:
            return None
        return self._math(ins, ins.operands[1], lambda: -a())

    def _CPT(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        f = self.reader(ins, ins.operands[1])
        if f is None:
            return None
        return self._math(ins, ins.operands[0], f)

    def _BTD(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        src, sbit, dst, dbit, length = ins.operands
        fs, fsb, fdb, fl = (self.reader(ins, o) for o in (src, sbit, dbit, length))
        fd = self.reader(ins, dst)
        w = self.writer(ins, dst)
        if None in (fs, fsb, fdb, fl, fd) or w is None:
            return None
        assert fs and fsb and fdb and fl and fd
        put = w[0]

        def btd(rci: bool) -> bool:
            if rci:
                n = int(fl())
                field_bits = (int(fs()) >> int(fsb())) & ((1 << n) - 1)
                shift = int(fdb())
                mask = ((1 << n) - 1) << shift
                put((int(fd()) & ~mask) | (field_bits << shift))
            return rci
        return btd

    def _AFI(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return lambda rci: False

    def _NOP(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        return _passthrough

    def _JSR(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        target = ins.operands[0]
        if not isinstance(target, Name):
            self.problem(ins, "JSR names a routine")
            return None
        name = target.text
        if name not in {r.name for r in self.ladder.program.routines}:
            self.problem(ins, f"JSR to {name!r}: the program has no such routine; routines: "
                              f"{', '.join(r.name for r in self.ladder.program.routines)}")
            return None
        if len(ins.operands) > 1 and not (isinstance(ins.operands[1], Number) and ins.operands[1].value == 0):
            self.problem(ins, "JSR with parameters is not modelled; call the routine without parameters (JSR(name) or JSR(name,0))")
            return None
        ladder = self.ladder
        pre.append(lambda: ladder.prescan_routine(name))

        def jsr(rci: bool) -> bool:
            if rci:
                ladder.run_routine(name)
            return rci
        return jsr

    def _RET(self, ins: Instruction, pre: list[Action], post: list[Action]) -> Run | None:
        ladder = self.ladder

        def ret(rci: bool) -> bool:
            if rci:
                ladder._returning = True
            return rci
        return ret

    def _motion(self, ins: Instruction, pre: list[Action]) -> Run:
        system = self.system
        axis, tagref = ins.operands[0], ins.operands[1]
        if not isinstance(axis, Reference) or axis.base not in system.axes or axis.selectors:
            self.problem(ins, f"{ins.mnemonic}: the first operand must be an axis of the set-up; axes: "
                              f"{', '.join(system.axes) or '(none)'}")
            return _passthrough
        if not isinstance(tagref, Reference):
            self.problem(ins, f"{ins.mnemonic}: the second operand must be a MOTION_INSTRUCTION tag")
            return _passthrough
        layout = self.db.layouts.get(tagref.base)
        if layout is None or layout.data_type != "MOTION_INSTRUCTION":
            what = "undefined" if layout is None else f"a {layout.data_type}"
            self.problem(ins, f"{ins.mnemonic}: {tagref} is {what}; the second operand must be a MOTION_INSTRUCTION tag")
            return _passthrough
        name = canonical(tagref)
        tag = system.tags.get(name)
        if tag is None:
            return _passthrough  # already reported by motion_bindings
        spec_operands = [o for o in tag.instruction.operands if o.type not in ("axis", "tag")]
        setters: list[tuple[str, Callable[[], Scalar]]] = []
        for spec_op, op in zip(spec_operands, ins.operands[2:]):
            if isinstance(op, Name):
                values = dict(spec_op.text_values)
                v = values.get(op.text)
                if v is None:
                    self.problem(ins, f"{op.text!r} is not a value of {spec_op.name}; values: {', '.join(values)}")
                    continue
                const: Scalar = v
                setters.append((spec_op.name, functools.partial(_constant, const)))
                continue
            get = self.reader(ins, op)
            if get is not None:
                setters.append((spec_op.name, get))
        row = system.motion_row
        operands = tag.operands
        pre.append(lambda: row(tag, "prescan"))
        if not setters:
            def motion(rci: bool) -> bool:
                row(tag, "rung_true" if rci else "rung_false")
                return rci
            return motion

        def motion_with_operands(rci: bool) -> bool:
            for k, get in setters:
                operands[k] = get()
            row(tag, "rung_true" if rci else "rung_false")
            return rci
        return motion_with_operands


def _first(e: Element) -> Instruction:
    if isinstance(e, Instruction):
        return e
    for leg in e.legs:
        for x in leg:
            return _first(x)
    return Instruction("NOP", ())


def _passthrough(rci: bool) -> bool:
    return rci


def _motion() -> tuple[str, ...]:
    from statecharts.program.table import instruction_table
    return instruction_table().motion


# -- arithmetic (1756-RM003N Compute/Math chapter; INT-P06 .. INT-P08) ----------------------


def _num(v: Scalar) -> int | float:
    return int(v) if isinstance(v, bool) else v


def _div(a: Scalar, b: Scalar) -> Scalar:
    x, y = _num(a), _num(b)
    if isinstance(x, float) or isinstance(y, float):
        if y == 0:
            raise _ArithmeticError("division by zero")
        return x / y
    if y == 0:
        raise _ArithmeticError("division by zero")
    q = abs(x) // abs(y)
    return q if (x >= 0) == (y >= 0) else -q  # integer division truncates toward zero


def _mod(a: Scalar, b: Scalar) -> Scalar:
    x, y = _num(a), _num(b)
    if y == 0:
        raise _ArithmeticError("division by zero (MOD)")
    if isinstance(x, float) or isinstance(y, float):
        return math.fmod(x, y)
    return x - _div(x, y) * y


def _constant(value: Scalar) -> Scalar:
    return value


def _pow(a: Scalar, b: Scalar) -> Scalar:
    x, y = _num(a), _num(b)
    try:
        r: object = float(x) ** float(y)
    except (OverflowError, ZeroDivisionError):
        raise _ArithmeticError("overflow in **") from None
    if not isinstance(r, float):  # a complex number
        raise _ArithmeticError("** of a negative number with a fractional exponent")
    return r


def _logical(op: Callable[[int, int], int], bools: Callable[[bool, bool], bool]) -> Callable[[Scalar, Scalar], Scalar]:
    def f(a: Scalar, b: Scalar) -> Scalar:
        if isinstance(a, bool) and isinstance(b, bool):
            return bools(a, b)
        if isinstance(a, float) or isinstance(b, float):
            raise _ArithmeticError("AND, OR and XOR take integers")
        return op(int(a), int(b))
    return f


def _math_fn(fn: Callable[[float], float], name: str) -> Callable[[Scalar], Scalar]:
    def f(a: Scalar) -> Scalar:
        try:
            return fn(float(_num(a)))
        except (ValueError, OverflowError):
            raise _ArithmeticError(f"{name} of {a} is undefined") from None
    return f


def _not(a: Scalar) -> Scalar:
    if isinstance(a, bool):
        return not a
    if isinstance(a, float):
        raise _ArithmeticError("NOT takes an integer")
    return ~a


_BINARY: dict[str, Callable[[Scalar, Scalar], Any]] = {
    "+": lambda a, b: _num(a) + _num(b),
    "-": lambda a, b: _num(a) - _num(b),
    "*": lambda a, b: _num(a) * _num(b),
    "/": _div,
    "MOD": _mod,
    "**": _pow,
    "=": lambda a, b: _num(a) == _num(b),
    "<>": lambda a, b: _num(a) != _num(b),
    "<": lambda a, b: _num(a) < _num(b),
    "<=": lambda a, b: _num(a) <= _num(b),
    ">": lambda a, b: _num(a) > _num(b),
    ">=": lambda a, b: _num(a) >= _num(b),
    "AND": _logical(lambda a, b: a & b, lambda a, b: a and b),
    "OR": _logical(lambda a, b: a | b, lambda a, b: a or b),
    "XOR": _logical(lambda a, b: a ^ b, lambda a, b: a != b),
}

_UNARY: dict[str, Callable[[Scalar], Any]] = {
    "-": lambda a: -_num(a),
    "NOT": _not,
    "ABS": lambda a: abs(_num(a)),
    "SQR": _math_fn(lambda x: math.sqrt(abs(x)), "SQR"),
    "SIN": _math_fn(math.sin, "SIN"),
    "COS": _math_fn(math.cos, "COS"),
    "TAN": _math_fn(math.tan, "TAN"),
    "ASN": _math_fn(math.asin, "ASN"),
    "ACS": _math_fn(math.acos, "ACS"),
    "ATN": _math_fn(math.atan, "ATN"),
    "LN": _math_fn(math.log, "LN"),
    "LOG": _math_fn(math.log10, "LOG"),
    "DEG": _math_fn(math.degrees, "DEG"),
    "RAD": _math_fn(math.radians, "RAD"),
    "TRN": lambda a: math.trunc(_num(a)) if isinstance(a, float) else _num(a),
}

