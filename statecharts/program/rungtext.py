"""Readers for rung text: ASCII rungs (as the ladder editor copies them) and neutral text.

Pipeline position: rung file or L5X ``<Text>`` -> **rung-text reader** -> program IR
(:mod:`statecharts.program.ir`).

* **ASCII rungs**, one rung per line: a mnemonic followed by its operands separated by
  spaces, branches ``BST … NXB … BND``, e.g.
  ``XIC STATE9_IND BST MSF X_axis X_STAT[0] NXB MSF Y_axis Y_STAT[0] BND``.  The
  number of operands of each mnemonic comes from the instruction table
  (``instructions.yaml``) or, for motion instructions, from the specification.  An
  operand that holds spaces (a CPT expression) is written in double quotes.  A leading
  ``SOR`` and a trailing ``EOR`` are accepted.
* **Neutral text**, as inside L5X and L5K files: ``XIC(A)[XIO(B),XIC(C)]OTE(D);``.

A rung file holds one form.  Lines starting with ``#`` or ``//`` are comments (the
comment right before a rung becomes its rung comment); a line ``ROUTINE name`` starts
another routine (the first one, ``MainRoutine`` unless named, is where a scan starts).
Every problem is a :class:`~statecharts.diagnostics.Diagnostic` located at
``file:line:col`` with the path ``rung N: instruction K``; all problems of a file are
reported in one pass.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable
from dataclasses import dataclass

from statecharts import ir as spec_ir
from statecharts.diagnostics import Diagnostic
from statecharts.program.ir import Branch, Element, Instruction, Name, Number, Operand, Placeholder, Routine, Rung, SourceLocation
from statecharts.program.logix_expr import ExpressionSyntaxError, parse_expression, parse_reference
from statecharts.program.table import instruction_table

#: deepest nesting of branches accepted in a rung
MAX_BRANCH_DEPTH = 32
#: most instructions accepted in one rung
MAX_RUNG_INSTRUCTIONS = 2000

_MNEMONIC = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_ROUTINE_LINE = re.compile(r"\s*ROUTINE\s+([A-Za-z_][A-Za-z0-9_]*)\s*\Z")


@functools.lru_cache(maxsize=1)
def _bundled_spec() -> spec_ir.Spec:
    from statecharts.loader import load_spec
    return load_spec()


@dataclass(frozen=True, slots=True)
class OperandSlot:
    """What one operand position of an instruction accepts."""

    kind: str  # an operand kind of instructions.yaml
    text_values: tuple[str, ...] = ()  # enumeration names a motion operand accepts as text


def operand_slots(mnemonic: str, spec: spec_ir.Spec | None) -> tuple[tuple[OperandSlot, ...], tuple[OperandSlot, ...]] | str:
    """(required, optional) operand slots of ``mnemonic``, or the message for one the interpreter cannot run."""
    table = instruction_table()
    entry = table.get(mnemonic)
    if entry is not None:
        return (tuple(OperandSlot(k) for k in entry.operands), tuple(OperandSlot(k) for k in entry.optional))
    if mnemonic in table.motion:
        variants = (spec or _bundled_spec()).variants(mnemonic)
        if not variants:
            return f"motion instruction {mnemonic} is not in the specification"
        slots = []
        for o in variants[0].operands:
            kind = {"axis": "axis", "tag": "motion"}.get(o.type, "value")
            slots.append(OperandSlot(kind, tuple(k for k, _ in o.text_values)))
        return tuple(slots), ()
    return table.why_not(mnemonic)


class RungParser:
    """Shared state of one file: where errors go and how positions map to lines."""

    def __init__(self, file: str, errors: list[Diagnostic], spec: spec_ir.Spec | None) -> None:
        self.file = file
        self.errors = errors
        self.spec = spec

    def error(self, loc: SourceLocation, rung: int, position: int | None, message: str) -> None:
        path = f"rung {rung}" + (f": instruction {position}" if position else "")
        self.errors.append(Diagnostic(self.file, loc.line, loc.column, path, message))

    def operand(self, slot: OperandSlot, text: str, loc: SourceLocation, rung: int, position: int,
                mnemonic: str, number: int) -> Operand | None:
        """Parse one operand's text for its slot; None (and an error) when it is not valid there."""
        text = text.strip()
        if len(text) >= 2 and text[0] == text[-1] == '"':
            text = text[1:-1].strip()
        where = f"operand {number} of {mnemonic}"
        if not text:
            self.error(loc, rung, position, f"{where} is empty")
            return None
        if text == "?":
            if slot.kind == "shown":
                return Placeholder()
            self.error(loc, rung, position, f"{where}: '?' stands only for a shown timer or counter value")
            return None
        try:
            if slot.kind == "expression":
                return parse_expression(text)
            if slot.kind == "routine":
                if not _MNEMONIC.match(text):
                    self.error(loc, rung, position, f"{where}: expected a routine name, got {text!r}")
                    return None
                return Name(text)
            if slot.text_values and text.lower() in {t.lower() for t in slot.text_values}:
                return Name(next(t for t in slot.text_values if t.lower() == text.lower()))
            if text[0].isdigit() or text[0] in "+-.":
                value = parse_expression(text)
                if not isinstance(value, Number):
                    self.error(loc, rung, position, f"{where}: expected a tag or an immediate value, got {text!r}")
                    return None
                if slot.kind not in ("value", "shown"):
                    self.error(loc, rung, position, f"{where} must be a tag, not the value {text}")
                    return None
                return value
            return parse_reference(text)
        except ExpressionSyntaxError as exc:
            self.error(loc, rung, position, f"{where} {text!r}: {exc.message} (at character {exc.offset + 1})")
            return None


class _Frame:
    """A branch being read: its finished legs and the leg being filled."""

    def __init__(self, loc: SourceLocation) -> None:
        self.loc = loc
        self.legs: list[tuple[Element, ...]] = []
        self.current: list[Element] = []


def _assemble(parser: RungParser, rung: int) -> tuple[Callable[[str, SourceLocation], bool], Callable[[Element], None],
                                                       Callable[[SourceLocation], bool], Callable[[SourceLocation], bool],
                                                       Callable[[SourceLocation], tuple[Element, ...] | None]]:
    """Branch bookkeeping shared by both forms: open, add, next leg, close, finish."""
    top: list[Element] = []
    stack: list[_Frame] = []

    def open_(what: str, loc: SourceLocation) -> bool:
        if len(stack) >= MAX_BRANCH_DEPTH:
            parser.error(loc, rung, None, f"branches nested deeper than {MAX_BRANCH_DEPTH} levels")
            return False
        stack.append(_Frame(loc))
        return True

    def add(e: Element) -> None:
        (stack[-1].current if stack else top).append(e)

    def next_leg(loc: SourceLocation) -> bool:
        if not stack:
            parser.error(loc, rung, None, "a branch leg starts (NXB or ',') outside any branch")
            return False
        stack[-1].legs.append(tuple(stack[-1].current))
        stack[-1].current = []
        return True

    def close(loc: SourceLocation) -> bool:
        if not stack:
            parser.error(loc, rung, None, "a branch ends (BND or ']') that was never started")
            return False
        frame = stack.pop()
        frame.legs.append(tuple(frame.current))
        add(Branch(tuple(frame.legs), frame.loc))
        return True

    def finish(loc: SourceLocation) -> tuple[Element, ...] | None:
        if stack:
            parser.error(stack[-1].loc, rung, None, f"unbalanced branch: {len(stack)} branch(es) started here are never ended (BND or ']')")
            return None
        return tuple(top)

    return open_, add, next_leg, close, finish


def _ascii_tokens(text: str) -> list[tuple[str, int]]:
    """Words of an ASCII rung with their offsets; quotes and brackets keep spaces inside one word."""
    out: list[tuple[str, int]] = []
    i, n = 0, len(text)
    while i < n:
        if text[i].isspace():
            i += 1
            continue
        start, depth, quoted = i, 0, False
        while i < n and (quoted or depth > 0 or not text[i].isspace()):
            c = text[i]
            if c == '"':
                quoted = not quoted
            elif not quoted and c in "[(":
                depth += 1
            elif not quoted and c in "])":
                depth = max(0, depth - 1)
            i += 1
        out.append((text[start:i], start))
    return out


def parse_ascii_rung(parser: RungParser, text: str, line: int, column: int, rung: int, comment: str = "") -> Rung | None:
    """One ASCII rung (the text of one line, starting at ``line:column``)."""
    words = _ascii_tokens(text)
    if words and words[0][0].upper() == "SOR":
        words = words[1:]
    if words and words[-1][0].upper() == "EOR":
        words = words[:-1]
    open_, add, next_leg, close, finish = _assemble(parser, rung)
    ok = True
    position = 0
    i = 0
    rung_loc = SourceLocation(parser.file, line, column + (words[0][1] if words else 0))
    while i < len(words):
        word, off = words[i]
        loc = SourceLocation(parser.file, line, column + off)
        upper = word.upper()
        i += 1
        if upper == "BST":
            ok = open_("BST", loc) and ok
            if not ok and len(words) > 0:
                return None
            continue
        if upper == "NXB":
            ok = next_leg(loc) and ok
            continue
        if upper == "BND":
            ok = close(loc) and ok
            continue
        position += 1
        if position > MAX_RUNG_INSTRUCTIONS:
            parser.error(loc, rung, position, f"more than {MAX_RUNG_INSTRUCTIONS} instructions in one rung")
            return None
        if not _MNEMONIC.match(word):
            parser.error(loc, rung, position, f"expected an instruction mnemonic, found {word!r}")
            return None
        slots = operand_slots(upper, parser.spec)
        if isinstance(slots, str):
            # without its operand count the rest of the rung cannot be read
            parser.error(loc, rung, position, slots)
            return None
        required, optional = slots
        operands: list[Operand] = []
        for n, slot in enumerate(required, start=1):
            if i >= len(words) or words[i][0].upper() in ("BST", "NXB", "BND"):
                parser.error(loc, rung, position, (f"{upper} takes {len(required)} operand(s), found {n - 1}"
                                                   + (": the rung ends" if i >= len(words) else f" before {words[i][0]}")))
                return None
            text_i, off_i = words[i]
            i += 1
            op = parser.operand(slot, text_i, SourceLocation(parser.file, line, column + off_i), rung, position, upper, n)
            if op is None:
                ok = False
            else:
                operands.append(op)
        for n, slot in enumerate(optional, start=len(required) + 1):
            # an optional operand is an immediate value (JSR's input count); a word that
            # could be a mnemonic starts the next instruction
            if i < len(words) and words[i][0][:1].isdigit():
                op = parser.operand(slot, words[i][0], SourceLocation(parser.file, line, column + words[i][1]),
                                    rung, position, upper, n)
                i += 1
                if op is None:
                    ok = False
                else:
                    operands.append(op)
        add(Instruction(upper, tuple(operands), loc, position))
    elements = finish(rung_loc)
    if elements is None or not ok:
        return None
    return Rung(rung, elements, comment, rung_loc)


def _split_operands(text: str, start: int) -> tuple[list[tuple[str, int]], int] | None:
    """Operands of ``MNEMONIC(`` … ``)`` starting after the '(' at ``start``: (texts with offsets, index after ')')."""
    depth = 0
    out: list[tuple[str, int]] = []
    begin = start
    i = start
    quoted = False
    while i < len(text):
        c = text[i]
        if c == '"':
            quoted = not quoted
        elif quoted:
            pass
        elif c in "([":
            depth += 1
        elif c in ")]":
            if depth == 0:
                if c == "]":
                    return None
                out.append((text[begin:i], begin))
                return out, i + 1
            depth -= 1
        elif c == "," and depth == 0:
            out.append((text[begin:i], begin))
            begin = i + 1
        i += 1
    return None


def shifted_locator(locate: Callable[[int], tuple[int, int]], start: int, offset: int) -> tuple[int, int]:
    """``locate`` for an offset counted from ``start``."""
    return locate(start + offset)


def parse_neutral_rung(parser: RungParser, text: str, locate: Callable[[int], tuple[int, int]], rung: int,
                       comment: str = "") -> Rung | None:
    """One neutral-text rung (``;`` optional); ``locate(offset)`` gives the (line, column) of an offset."""
    def at(offset: int) -> SourceLocation:
        line, col = locate(offset)
        return SourceLocation(parser.file, line, col)

    open_, add, next_leg, close, finish = _assemble(parser, rung)
    ok = True
    position = 0
    i, n = 0, len(text)
    while i < n and text[i].isspace():
        i += 1
    m = re.match(r"N\s*:", text[i:])
    if m:
        i += m.end()
    rung_loc = at(i)
    ended = False
    while i < n:
        c = text[i]
        if c.isspace():
            i += 1
            continue
        loc = at(i)
        if ended:
            parser.error(loc, rung, None, f"text after the rung's ';': {text[i:i + 20]!r}")
            return None
        if c == ";":
            ended = True
            i += 1
            continue
        if c == "[":
            if not open_("[", loc):
                return None
            i += 1
            continue
        if c == ",":
            ok = next_leg(loc) and ok
            i += 1
            continue
        if c == "]":
            ok = close(loc) and ok
            i += 1
            continue
        m = re.compile(r"[A-Za-z_][A-Za-z0-9_]*").match(text, i)
        if m is None:
            parser.error(loc, rung, position + 1 if position else None, f"expected an instruction, '[', ',' or ']', found {c!r}")
            return None
        position += 1
        if position > MAX_RUNG_INSTRUCTIONS:
            parser.error(loc, rung, position, f"more than {MAX_RUNG_INSTRUCTIONS} instructions in one rung")
            return None
        mnemonic = m.group().upper()
        j = m.end()
        while j < n and text[j].isspace():
            j += 1
        if j >= n or text[j] != "(":
            parser.error(loc, rung, position, f"expected '(' after {m.group()}: neutral text writes every instruction as MNEMONIC(operands)")
            return None
        split = _split_operands(text, j + 1)
        if split is None:
            parser.error(at(j), rung, position, f"the operand list of {mnemonic} is never closed with ')'")
            return None
        texts, i = split
        if len(texts) == 1 and not texts[0][0].strip():
            texts = []
        slots = operand_slots(mnemonic, parser.spec)
        if isinstance(slots, str):
            parser.error(loc, rung, position, slots)
            ok = False
            continue
        required, optional = slots
        if not (len(required) <= len(texts) <= len(required) + len(optional)):
            want = str(len(required)) if not optional else f"{len(required)} to {len(required) + len(optional)}"
            parser.error(loc, rung, position, f"{mnemonic} takes {want} operand(s), found {len(texts)}")
            ok = False
            continue
        operands: list[Operand] = []
        for k, ((otext, off), slot) in enumerate(zip(texts, (*required, *optional)), start=1):
            op = parser.operand(slot, otext, at(off), rung, position, mnemonic, k)
            if op is None:
                ok = False
            else:
                operands.append(op)
        add(Instruction(mnemonic, tuple(operands), loc, position))
    elements = finish(rung_loc)
    if elements is None or not ok:
        return None
    return Rung(rung, elements, comment, rung_loc)


def sniff_form(text: str) -> str:
    """"neutral" when the first rung writes an instruction as ``MNEMONIC(``, else "ascii"."""
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith(("#", "//")) or _ROUTINE_LINE.match(line):
            continue
        m = re.match(r"(?:N\s*:\s*)?\[*\s*[A-Za-z_][A-Za-z0-9_]*\s*(.)", line + " ")
        return "neutral" if m and m.group(1) == "(" else "ascii"
    return "ascii"


def parse_rung_file(file: str, text: str, errors: list[Diagnostic], spec: spec_ir.Spec | None,
                    form: str | None = None) -> tuple[str, tuple[Routine, ...]]:
    """(form, routines) of a rung file; problems go to ``errors``."""
    form = form or sniff_form(text)
    parser = RungParser(file, errors, spec)
    routines: list[tuple[str, SourceLocation, list[Rung]]] = []
    current: list[Rung] = []
    name, name_loc = "MainRoutine", SourceLocation(file, 1, 1)
    comment: list[str] = []
    lines = text.split("\n")
    started = False

    def new_routine(new: str, loc: SourceLocation) -> None:
        nonlocal current, name, name_loc, started
        if started or current:
            routines.append((name, name_loc, current))
        current, name, name_loc, started = [], new, loc, True

    if form == "ascii":
        for lineno, raw in enumerate(lines, start=1):
            line = raw.rstrip("\r")
            stripped = line.strip()
            if not stripped:
                continue
            if stripped.startswith(("#", "//")):
                comment.append(stripped.lstrip("#/").strip())
                continue
            m = _ROUTINE_LINE.match(line)
            if m:
                new_routine(m.group(1), SourceLocation(file, lineno, 1))
                comment = []
                continue
            rung = parse_ascii_rung(parser, line, lineno, 1, len(current), " ".join(comment))
            comment = []
            # a rung that failed still takes its number, so later rungs keep theirs
            current.append(rung if rung is not None else Rung(len(current), (), "", SourceLocation(file, lineno, 1)))
    else:
        # rungs end with ';' and may span lines; comments and ROUTINE lines sit between rungs
        offsets = [0]
        for ln in lines:
            offsets.append(offsets[-1] + len(ln) + 1)

        def locate(offset: int) -> tuple[int, int]:
            lo, hi = 0, len(offsets) - 1
            while lo < hi:
                mid = (lo + hi + 1) // 2
                if offsets[mid] <= offset:
                    lo = mid
                else:
                    hi = mid - 1
            return lo + 1, offset - offsets[lo] + 1

        p, n = 0, len(text)
        while p < n:
            if text[p].isspace():
                p += 1
                continue
            line0, col0 = locate(p)
            line_text = lines[line0 - 1]
            if col0 == len(line_text) - len(line_text.lstrip()) + 1:
                stripped = line_text.strip()
                if stripped.startswith(("#", "//")):
                    comment.append(stripped.lstrip("#/").strip())
                    p = offsets[line0]
                    continue
                m = _ROUTINE_LINE.match(line_text.rstrip("\r"))
                if m:
                    new_routine(m.group(1), SourceLocation(file, line0, 1))
                    comment = []
                    p = offsets[line0]
                    continue
            end = _rung_end(text, p)
            rung = parse_neutral_rung(parser, text[p:end], functools.partial(shifted_locator, locate, p), len(current), " ".join(comment))
            current.append(rung if rung is not None else Rung(len(current), (), "", SourceLocation(file, line0, col0)))
            comment = []
            p = end
    routines.append((name, name_loc, current))
    return form, tuple(Routine(n, tuple(rs), loc) for n, loc, rs in routines)


def _rung_end(text: str, start: int) -> int:
    """Offset just after the ';' that ends the rung begun at ``start`` (or the text's end)."""
    quoted = False
    for i in range(start, len(text)):
        c = text[i]
        if c == '"':
            quoted = not quoted
        elif c == ";" and not quoted:
            return i + 1
    return len(text)
