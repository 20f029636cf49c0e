"""Load a program file in any of the three forms into the program IR, with every problem located.

Pipeline position: file -> **reader** (this module picks the form: ``.L5X`` is an L5X
export, any other file is rung text, ASCII or neutral, told apart by its first rung)
-> program IR.  For a rung file, which declares no tags, the tags are inferred from
their use (a contact's operand is a BOOL, a TON's a TIMER, a MOV's destination a
DINT, ...) and the inferred tags are listed in :attr:`Program.warnings`; an L5X export
declares its tags and a reference to an undeclared one is an error.

Input is third-party text: the file must be a regular file no larger than
``max_bytes`` (default :data:`MAX_PROGRAM_BYTES`), must be UTF-8, and every problem
of the file is reported in one :class:`ProgramError`, never a traceback.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from statecharts import ir as spec_ir
from statecharts.diagnostics import Diagnostic, InputError
from statecharts.program.ir import (
    AXIS_UNTYPED,
    Binary,
    Expression,
    Index,
    IndirectBit,
    Instruction,
    Member,
    Number,
    Operand,
    Program,
    Reference,
    Routine,
    Scalar,
    Tag,
    Unary,
)
from statecharts.program.rungtext import operand_slots, parse_rung_file
from statecharts.program.tags import STRUCTURES

#: largest program file read (an L5X export of a whole project can be large; raise it with max_bytes=)
MAX_PROGRAM_BYTES = 5_000_000
#: most problems listed for one file
MAX_DIAGNOSTICS = 200
RUNG_SUFFIXES = (".rll", ".txt", ".nt", ".lad")


class ProgramError(InputError):
    """A program file is wrong; ``diagnostics`` says where and why."""


def read_text(path: Path, max_bytes: int, what: str = "program") -> tuple[str | None, list[Diagnostic]]:
    """The file's text, or None and the reason (not a regular file, too large, not UTF-8)."""
    from statecharts.inputs import read_input

    errors: list[Diagnostic] = []
    raw = read_input(path, errors, what=what, limit=max_bytes)
    if raw is None:
        return None, errors
    try:
        return raw.decode("utf-8-sig"), []
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        return None, [Diagnostic(str(path), line, col, "", f"{what} is not UTF-8 text ({exc.reason} at byte {exc.start})")]


def load_program(path: Path | str, *, spec: spec_ir.Spec | None = None, routine: str | None = None,
                 program: str | None = None, max_bytes: int = MAX_PROGRAM_BYTES) -> Program:
    """Read a rung file (``.rll``/``.txt``: ASCII or neutral text) or an L5X export.

    For an L5X file, ``program`` names the Logix program (default: the only one, or the
    first) and ``routine`` the routine a scan starts in (default: the program's main
    routine).  Raises :class:`ProgramError` with every problem of the file.
    """
    path = Path(path)
    text, errors = read_text(path, max_bytes)
    if text is None:
        raise ProgramError(errors)
    if path.suffix.lower() == ".l5x":
        from statecharts.program.l5x import read_l5x
        result = read_l5x(str(path), text, spec=spec, routine=routine, program=program)
    else:
        result = parse_program_text(str(path), text, spec=spec)
        if routine is not None:
            names = [r.name for r in result.routines]
            if routine not in names:
                raise ProgramError([Diagnostic(str(path), 1, 1, "", f"no routine {routine!r}; routines: {', '.join(names)}")])
            result = Program(result.name, routine, result.routines, result.tags, result.form, result.file, result.warnings)
    return result


def parse_program_text(file: str, text: str, *, spec: spec_ir.Spec | None = None, form: str | None = None) -> Program:
    """A program from rung text (ASCII or neutral); tags inferred from use."""
    errors: list[Diagnostic] = []
    form, routines = parse_rung_file(file, text, errors, spec, form)
    if errors:
        raise ProgramError(capped(errors))
    check_routines(file, routines, errors)
    tags, warnings = infer_tags(file, routines, errors, spec)
    if errors:
        raise ProgramError(capped(errors))
    return Program(Path(file).stem, routines[0].name, routines, tags, form, file, warnings)


def capped(errors: list[Diagnostic]) -> list[Diagnostic]:
    unique = sorted(set(errors))
    if len(unique) <= MAX_DIAGNOSTICS:
        return unique
    last = unique[MAX_DIAGNOSTICS - 1]
    more = len(unique) - MAX_DIAGNOSTICS + 1
    return [*unique[:MAX_DIAGNOSTICS - 1], Diagnostic(last.file, last.line, last.column, "", f"... and {more} more problems")]


def _diag(ins: Instruction, rung: int, message: str) -> Diagnostic:
    loc = ins.location
    return Diagnostic(loc.file, loc.line, loc.column, f"rung {rung}: instruction {ins.position}", message)


def check_routines(file: str, routines: tuple[Routine, ...], errors: list[Diagnostic]) -> None:
    """Routine names unique, JSR targets exist, no routine calls itself (directly or not)."""
    names = [r.name for r in routines]
    for r in routines:
        if names.count(r.name) > 1:
            errors.append(Diagnostic(r.location.file or file, r.location.line, r.location.column, "",
                                     f"routine {r.name!r} is defined twice"))
    calls: dict[str, set[str]] = {r.name: set() for r in routines}
    for r in routines:
        for rung in r.rungs:
            for ins in rung.instructions():
                if ins.mnemonic == "JSR" and ins.operands:
                    target = getattr(ins.operands[0], "text", None)
                    if target not in calls:
                        errors.append(_diag(ins, rung.number, f"JSR to {target!r}: no such routine; routines: {', '.join(names)}"))
                    elif target is not None:
                        calls[r.name].add(target)
    # a cycle of JSRs would recurse until the controller's stack overflows
    for start in calls:
        stack, seen = [start], set()
        while stack:
            cur = stack.pop()
            for nxt in calls.get(cur, ()):
                if nxt == start:
                    r = next(x for x in routines if x.name == start)
                    errors.append(Diagnostic(r.location.file or file, r.location.line, r.location.column, "",
                                             f"routine {start!r} calls itself through JSR; recursion is not supported"))
                    stack = []
                    break
                if nxt not in seen:
                    seen.add(nxt)
                    stack.append(nxt)


@dataclass
class _Use:
    kinds: set[str] = field(default_factory=set)
    members: set[str] = field(default_factory=set)
    bits: bool = False
    subscripts: list[tuple[int, ...]] = field(default_factory=list)
    computed_subscript: bool = False
    real: bool = False
    first: tuple[Instruction, int] | None = None
    shown: list[tuple[str, Scalar]] = field(default_factory=list)


def references(op: Operand | Expression) -> Iterator[tuple[Reference, bool]]:
    """Every tag reference in an operand, with whether it is the operand itself (not inside an expression)."""
    stack: list[tuple[Operand | Expression, bool]] = [(op, True)]
    while stack:
        e, top = stack.pop()
        if isinstance(e, Reference):
            yield e, top
            for s in e.selectors:
                if isinstance(s, Index):
                    stack.extend((x, False) for x in s.subscripts)
                elif isinstance(s, IndirectBit):
                    stack.append((s.bit, False))
        elif isinstance(e, Unary):
            stack.append((e.operand, False))
        elif isinstance(e, Binary):
            stack.extend(((e.left, False), (e.right, False)))


def _has_real(op: Operand | Expression) -> bool:
    stack: list[Operand | Expression] = [op]
    while stack:
        e = stack.pop()
        if isinstance(e, Number) and isinstance(e.value, float):
            return True
        if isinstance(e, Unary):
            stack.append(e.operand)
        elif isinstance(e, Binary):
            stack.extend((e.left, e.right))
    return False


def operand_kinds(ins: Instruction, spec: spec_ir.Spec | None) -> list[str]:
    slots = operand_slots(ins.mnemonic, spec)
    if isinstance(slots, str):
        return []
    required, optional = slots
    return [s.kind for s in (*required, *optional)][:len(ins.operands)]


def infer_tags(file: str, routines: tuple[Routine, ...], errors: list[Diagnostic],
               spec: spec_ir.Spec | None) -> tuple[tuple[Tag, ...], tuple[str, ...]]:
    """The tags a rung file uses, with data types and sizes inferred from the instructions that use them."""
    uses: dict[str, _Use] = {}
    for r in routines:
        for rung in r.rungs:
            for ins in rung.instructions():
                kinds = operand_kinds(ins, spec)
                real = any(_has_real(o) for o in ins.operands)
                for _k, (op, kind) in enumerate(zip(ins.operands, kinds)):
                    for ref, top in references(op):
                        use = uses.setdefault(ref.base, _Use())
                        if use.first is None:
                            use.first = (ins, rung.number)
                        use.kinds.add(kind if top else "value")
                        if (top and kind in ("value", "dest", "expression")) or not top:
                            use.real = use.real or (real and top)
                        for s in ref.selectors:
                            if isinstance(s, Index):
                                immediate = [x.value for x in s.subscripts if isinstance(x, Number) and isinstance(x.value, int)]
                                if len(immediate) == len(s.subscripts):
                                    use.subscripts.append(tuple(int(v) for v in immediate))
                                else:
                                    use.computed_subscript = True
                            elif isinstance(s, Member):
                                if s.bit is not None:
                                    use.bits = True
                                else:
                                    use.members.add(s.name)
                            elif isinstance(s, IndirectBit):
                                use.bits = True
                        if top and kind in ("timer", "counter") and ins.mnemonic != "RES":
                            for member, shown in zip(("PRE", "ACC"), ins.operands[1:3]):
                                if isinstance(shown, Number):
                                    prefix = "".join(f"[{','.join(str(int(x.value)) for x in s.subscripts if isinstance(x, Number))}]"
                                                     for s in ref.selectors if isinstance(s, Index))
                                    use.shown.append((f"{prefix}.{member}" if prefix else member, shown.value))
    tags: list[Tag] = []
    listing: list[str] = []
    for name, use in uses.items():
        assert use.first is not None
        ins, rung_no = use.first
        use_kinds = use.kinds
        data_type: str | None = None
        structural = use_kinds & {"axis", "motion", "timer", "counter"}
        if len(structural) > 1:
            errors.append(_diag(ins, rung_no, f"tag {name!r} is used as {' and as '.join(sorted(structural))}"))
            continue
        if "axis" in use_kinds:
            data_type = AXIS_UNTYPED
        elif "motion" in use_kinds:
            data_type = "MOTION_INSTRUCTION"
        elif "timer" in use_kinds:
            data_type = "TIMER"
        elif "counter" in use_kinds:
            data_type = "COUNTER"
        elif use.members:
            candidates = [t for t, ms in STRUCTURES.items() if use.members <= {m for m, _ in ms}]
            if len(candidates) == 1:
                data_type = candidates[0]
            else:
                errors.append(_diag(ins, rung_no, (
                    f"cannot infer the data type of {name!r}: only its member(s) {', '.join(sorted(use.members))} are used; "
                    f"use it in a TON/CTU/motion instruction, or declare it in an L5X export")))
                continue
        elif "timer_or_counter" in use_kinds:
            errors.append(_diag(ins, rung_no, f"cannot tell whether {name!r} is a TIMER or a COUNTER (only RES uses it)"))
            continue
        else:
            bitwise = use_kinds & {"bit_in", "bit_out"}
            numeric = use_kinds & {"value", "dest", "expression", "array"}
            if bitwise and not use.bits and numeric:
                errors.append(_diag(ins, rung_no, (f"tag {name!r} is used both as a BOOL (by a contact or coil) and as a number; "
                                                f"use a bit of it ({name}.0) or two tags")))
                continue
            if bitwise and not use.bits:
                data_type = "BOOL"
            else:
                data_type = "REAL" if use.real and not use.bits else "DINT"
        if data_type in ("TIMER", "COUNTER", "MOTION_INSTRUCTION") and use.bits and not use.members:
            errors.append(_diag(ins, rung_no, f"{name!r} is a {data_type}; select a member before a bit"))
            continue
        dims: tuple[int, ...] = ()
        if use.subscripts or use.computed_subscript:
            if data_type == AXIS_UNTYPED:
                errors.append(_diag(ins, rung_no, f"axis {name!r} cannot be an array"))
                continue
            if not use.subscripts:
                errors.append(_diag(ins, rung_no, (f"cannot infer the size of array {name!r}: every subscript is computed; "
                                                f"use an immediate subscript somewhere or declare it in an L5X export")))
                continue
            ranks = {len(s) for s in use.subscripts}
            if len(ranks) > 1:
                errors.append(_diag(ins, rung_no, f"array {name!r} is used with {' and '.join(map(str, sorted(ranks)))} subscripts"))
                continue
            rank = ranks.pop()
            dims = tuple(max(s[d] for s in use.subscripts) + 1 for d in range(rank))
            if any(min(s[d] for s in use.subscripts) < 0 for d in range(rank)):
                errors.append(_diag(ins, rung_no, f"array {name!r} has a negative subscript"))
                continue
        tags.append(Tag(name, data_type, dims, tuple((k, v) for k, v in dict(use.shown).items() if v), inferred=True,
                        location=use.first[0].location))
        listing.append(f"{name} ({data_type}{''.join(f'[{d}]' for d in dims)})")
    warnings = (f"tags inferred from their use: {', '.join(sorted(listing, key=str.lower))}",) if listing else ()
    return tuple(sorted(tags, key=lambda t: t.name)), warnings


def check_declared(program: Program, errors: list[Diagnostic], spec: spec_ir.Spec | None) -> None:
    """Every tag a routine references must be declared (L5X: controller or program scope)."""
    declared = {t.name for t in program.tags}
    for r in program.routines:
        for rung in r.rungs:
            for ins in rung.instructions():
                for op in ins.operands:
                    for ref, _top in references(op):
                        if ref.base not in declared:
                            errors.append(_diag(ins, rung.number, (
                                f"undefined tag {ref.base!r}: it is declared neither in the controller's tags nor in "
                                f"program {program.name!r}")))


def probe_compile(program: Program, spec: spec_ir.Spec) -> None:
    """Compile the program against default axes of its declared types (ProgramError on a problem).

    A rung file declares no axis types; its axis members are checked when a scenario binds it."""
    from statecharts.engine import AxisInstance
    from statecharts.program.ladder import Ladder
    from statecharts.scan import System

    if any(t.data_type == AXIS_UNTYPED for t in program.axes()):
        ladder = Ladder(program)
        if ladder.binding_problems:
            raise ProgramError(list(ladder.binding_problems))
        return
    axes = []
    for t in program.axes():
        try:
            chart = spec.chart_for_axis_type(t.data_type)
        except KeyError:
            raise ProgramError([Diagnostic(t.location.file, t.location.line, t.location.column, "", (
                f"axis {t.name} has type {t.data_type}, which no chart of the specification models"))]) from None
        variables = {"AxisType": t.data_type} if "AxisType" in {v.name for v in chart.variables} else {}
        axes.append(AxisInstance(chart, t.name, variables=variables))
    System(spec, axes, [], ladder=Ladder(program))


def summary(program: Program) -> dict[str, object]:
    """What ``motionchart validate PROGRAM`` prints: routines, rungs, tags, instructions used."""
    from statecharts.program.table import instruction_table

    table = instruction_table()
    used = program.mnemonics()
    return {
        "program": program.name,
        "file": program.file,
        "form": program.form,
        "main_routine": program.main,
        "routines": {r.name: len(r.rungs) for r in program.routines},
        "rungs": sum(len(r.rungs) for r in program.routines),
        "tags": len(program.tags),
        "axes": {t.name: t.data_type for t in program.axes()},
        "instructions": {m: sum(1 for i in program.instructions() if i.mnemonic == m) for m in used},
        "motion_instructions": [m for m in used if m in table.motion],
        "unsupported": [m for m in used if m not in table.supported()],
        "warnings": list(program.warnings),
    }

