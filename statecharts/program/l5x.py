"""Reader for L5X exports (a whole project, or one program or routine exported from Logix Designer).

Pipeline position: ``.L5X`` file -> **L5X reader** -> program IR.  The XML is parsed
with :mod:`defusedxml` (a DTD is refused, so no entity can expand and no external
resource is fetched) and the element positions are recorded while parsing, so every
problem points at its line.  What is read:

* controller-scope and program-scope tags: name, data type, dimensions, and the
  initial values of the ``Decorated`` data format (program tags hide controller tags
  of the same name);
* the program (``program=``, else the only one, else the first) and its routines; a
  ladder (RLL) routine's rungs are read as neutral text by
  :mod:`statecharts.program.rungtext`; a Structured Text, Function Block or SFC
  routine is an error naming it;
* axis tags (AXIS_CIP_DRIVE, AXIS_SERVO, AXIS_SERVO_DRIVE, AXIS_VIRTUAL), which a
  scenario binds to axes of the specification's axis charts.
"""

from __future__ import annotations

import dataclasses
import functools
import xml.etree.ElementTree as ET
from typing import Any

from defusedxml import DefusedXmlException
from defusedxml.ElementTree import DefusedXMLParser

from statecharts import ir as spec_ir
from statecharts.diagnostics import Diagnostic
from statecharts.program.ir import (
    ATOMIC_TYPES,
    AXIS_TYPES,
    STRUCTURE_TYPES,
    Binary,
    Branch,
    Element,
    Index,
    IndirectBit,
    Instruction,
    Operand,
    Program,
    Reference,
    Routine,
    Rung,
    Scalar,
    SourceLocation,
    Tag,
    Unary,
)
from statecharts.program.logix_expr import ExpressionSyntaxError, number_value, parse_reference
from statecharts.program.reader import ProgramError, capped, check_declared, check_routines
from statecharts.program.rungtext import RungParser, parse_neutral_rung, shifted_locator

ROUTINE_KINDS = {"ST": "Structured Text (ST)", "FBD": "Function Block Diagram (FBD)",
                 "SFC": "Sequential Function Chart (SFC)"}


class _Builder(ET.TreeBuilder):
    """A tree builder that remembers where each element starts."""

    def __init__(self) -> None:
        super().__init__()
        self.parser: Any = None
        self.positions: dict[int, tuple[int, int]] = {}
        self.keep: list[ET.Element] = []

    def start(self, tag: str, attrs: dict[str, str]) -> ET.Element:
        element = super().start(tag, attrs)
        expat = self.parser.parser
        self.positions[id(element)] = (expat.CurrentLineNumber, expat.CurrentColumnNumber + 1)
        self.keep.append(element)
        return element


def parse_xml(file: str, text: str) -> tuple[ET.Element, dict[int, tuple[int, int]]]:
    """The element tree and element positions; a DTD, an entity or bad XML is a ProgramError."""
    builder = _Builder()
    parser = DefusedXMLParser(target=builder, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    builder.parser = parser
    try:
        parser.feed(text)
        root = parser.close()
    except DefusedXmlException as exc:
        at = text.find("<!DOCTYPE")
        at = at if at >= 0 else text.find("<!ENTITY")
        line = text.count("\n", 0, at) + 1 if at >= 0 else 1
        col = at - (text.rfind("\n", 0, at) + 1) + 1 if at >= 0 else 1
        raise ProgramError([Diagnostic(file, line, col, "", (
            f"the L5X file declares a DTD or entities ({type(exc).__name__}); they are refused: an L5X export "
            f"has none, and entity expansion is how XML bombs work"))]) from None
    except ET.ParseError as exc:
        line, col = exc.position
        raise ProgramError([Diagnostic(file, line, col + 1, "", f"not well-formed XML: {str(exc).split(':')[0]}")]) from None
    return root, builder.positions


def read_l5x(file: str, text: str, *, spec: spec_ir.Spec | None = None, routine: str | None = None,
             program: str | None = None) -> Program:
    root, positions = parse_xml(file, text)
    errors: list[Diagnostic] = []

    def where(el: ET.Element) -> tuple[int, int]:
        return positions.get(id(el), (1, 1))

    def err(el: ET.Element, message: str, path: str = "") -> None:
        line, col = where(el)
        errors.append(Diagnostic(file, line, col, path, message))

    if root.tag != "RSLogix5000Content":
        err(root, f"not an L5X export: the root element is <{root.tag}>, expected <RSLogix5000Content>")
        raise ProgramError(errors)
    controller = root.find("Controller")
    if controller is None:
        err(root, "the L5X export has no <Controller> element")
        raise ProgramError(errors)
    programs = controller.findall("Programs/Program")
    if not programs:
        err(controller, "the L5X export holds no program (<Programs>/<Program>)")
        raise ProgramError(errors)
    chosen = None
    if program is not None:
        chosen = next((p for p in programs if p.get("Name") == program), None)
        if chosen is None:
            err(controller, f"no program {program!r}; programs: {', '.join(p.get('Name', '?') for p in programs)}")
            raise ProgramError(errors)
    else:
        chosen = next((p for p in programs if p.get("Use") == "Target"), programs[0])
    pname = chosen.get("Name", "Program")

    tags: dict[str, Tag] = {}
    unmodelled: dict[str, str] = {}
    aliases: dict[str, tuple[Reference, SourceLocation]] = {}
    for scope, holder in (("", controller), (pname, chosen)):
        for el in holder.findall("Tags/Tag"):
            tag = _tag(el, scope, file, where, err, unmodelled, aliases)
            if tag is not None:
                tags[tag.name] = tag  # a program tag hides a controller tag of that name

    routines: list[Routine] = []
    parser = RungParser(file, errors, spec)
    line_offsets = [0]
    for ln in text.split("\n"):
        line_offsets.append(line_offsets[-1] + len(ln) + 1)

    def locate_absolute(offset: int) -> tuple[int, int]:
        lo, hi = 0, len(line_offsets) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if line_offsets[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1, offset - line_offsets[lo] + 1

    for rel in chosen.findall("Routines/Routine"):
        name = rel.get("Name", "")
        kind = rel.get("Type", "RLL")
        line, col = where(rel)
        if kind != "RLL":
            described = ROUTINE_KINDS.get(kind, kind)
            err(rel, (f"routine {name!r} is a {described} routine; only ladder (RLL) routines can be run: "
                      f"rewrite it in ladder or leave it out of the export"))
            continue
        rungs: list[Rung] = []
        for rung_el in rel.findall("RLLContent/Rung"):
            number = int(rung_el.get("Number", len(rungs))) if rung_el.get("Number", "").isdigit() else len(rungs)
            text_el = rung_el.find("Text")
            comment_el = rung_el.find("Comment")
            comment = " ".join((comment_el.text or "").split()) if comment_el is not None else ""
            if text_el is None or not (text_el.text or "").strip():
                rungs.append(Rung(number, (), comment, SourceLocation(file, *where(rung_el))))
                continue
            t_line, t_col = where(text_el)
            start = line_offsets[t_line - 1] + t_col - 1
            close = text.find("</Text>", start)
            cdata = text.find("<![CDATA[", start, close if close >= 0 else len(text))
            raw = text_el.text or ""
            if cdata >= 0:
                # the element's text is the white space before the CDATA section, then its content
                content = cdata + len("<![CDATA[") - (len(raw) - len(raw.lstrip()))
            else:
                content = text.find(">", start) + 1
            rung = parse_neutral_rung(parser, raw, functools.partial(shifted_locator, locate_absolute, content), number, comment)
            rungs.append(rung if rung is not None else Rung(number, (), comment, SourceLocation(file, t_line, t_col)))
        routines.append(Routine(name, tuple(rungs), SourceLocation(file, line, col)))
    if not routines and not errors:
        err(chosen, f"program {pname!r} has no ladder routine")
    if errors:
        raise ProgramError(capped(errors))
    if aliases:
        routines = [_without_aliases(r, aliases, errors) for r in routines]
        if errors:
            raise ProgramError(capped(errors))
    names = [r.name for r in routines]
    main = routine or chosen.get("MainRoutineName") or names[0]
    if main not in names:
        err(chosen, f"no routine {main!r} in program {pname!r}; routines: {', '.join(names)}")
        raise ProgramError(errors)
    check_routines(file, tuple(routines), errors)
    result = Program(pname, main, tuple(routines), tuple(sorted(tags.values(), key=lambda t: t.name)), "l5x", file,
                     tuple(f"tag {n}, {t}, is not modelled and was left out" for n, t in sorted(unmodelled.items())))
    check_declared(result, errors, spec)
    if unmodelled:
        errors[:] = [_unmodelled_message(d, unmodelled) for d in errors]
    if errors:
        raise ProgramError(capped(errors))
    return result


def _unmodelled_message(d: Diagnostic, unmodelled: dict[str, str]) -> Diagnostic:
    for name, t in unmodelled.items():
        if d.message.startswith(f"undefined tag {name!r}"):
            return Diagnostic(d.file, d.line, d.column, d.path, (
                f"tag {name!r} is {t}; the modelled data types are {', '.join(ATOMIC_TYPES + STRUCTURE_TYPES + AXIS_TYPES)}"))
    return d


def _tag(el: ET.Element, scope: str, file: str, where: Any, err: Any, unmodelled: dict[str, str],
         aliases: dict[str, tuple[Reference, SourceLocation]]) -> Tag | None:
    name = el.get("Name")
    if not name:
        err(el, "a <Tag> without a Name")
        return None
    data_type = el.get("DataType", "")
    if el.get("TagType") == "Alias":
        target = el.get("AliasFor", "")
        if ":" in target.split(".")[0] or not target:
            unmodelled[name] = f"an alias for {target or '?'} (module I/O data is not modelled)"
        else:
            try:
                aliases[name] = (parse_reference(target), SourceLocation(file, *where(el)))
            except ExpressionSyntaxError as exc:
                err(el, f"alias tag {name!r}: AliasFor {target!r} is not a tag reference: {exc.message}")
        return None
    if data_type not in ATOMIC_TYPES + STRUCTURE_TYPES + AXIS_TYPES:
        unmodelled[name] = f"a {data_type}" if data_type else "a tag without a DataType"
        return None
    dims_text = el.get("Dimensions", "").replace(",", " ").split()
    try:
        dims = tuple(int(d) for d in dims_text)
    except ValueError:
        err(el, f"tag {name!r}: Dimensions {el.get('Dimensions')!r} are not whole numbers")
        return None
    if len(dims) > 3 or any(d <= 0 for d in dims):
        err(el, f"tag {name!r}: Dimensions {el.get('Dimensions')!r}: one to three positive sizes expected")
        return None
    if dims and data_type in AXIS_TYPES:
        err(el, f"axis tag {name!r} cannot be an array")
        return None
    initial: list[tuple[str, Scalar]] = []
    data = next((d for d in el.findall("Data") if d.get("Format") == "Decorated"), None)
    if data is not None:
        for child in data:
            _values(child, "", initial, lambda e, m: err(e, f"tag {name!r}: {m}"))
    desc_el = el.find("Description")
    description = " ".join((desc_el.text or "").split()) if desc_el is not None else ""
    return Tag(name, data_type, dims, tuple((k, v) for k, v in initial if v), scope, description=description,
               location=SourceLocation(file, *where(el)))


def _values(el: ET.Element, prefix: str, out: list[tuple[str, Scalar]], err: Any) -> None:
    """Initial values of a Decorated <Data> subtree as (member path, value)."""
    stack = [(el, prefix)]
    while stack:
        node, path = stack.pop()
        if node.tag in ("DataValue", "DataValueMember"):
            member = node.get("Name")
            p = f"{path}.{member}" if member and path else (member or path)
            value = node.get("Value")
            if value is not None:
                v = _scalar(value, node.get("DataType", ""))
                if v is None:
                    err(node, f"value {value!r} is not a number")
                else:
                    out.append((p, v))
        elif node.tag == "Element":
            index = node.get("Index", "")
            p = path + index
            value = node.get("Value")
            if value is not None:
                v = _scalar(value, "")
                if v is None:
                    err(node, f"value {value!r} is not a number")
                else:
                    out.append((p, v))
            stack.extend((c, p) for c in node)
        elif node.tag in ("Array", "Structure", "ArrayMember", "StructureMember"):
            member = node.get("Name")
            p = f"{path}.{member}" if member and path else (member or path)
            stack.extend((c, p) for c in node)


def _scalar(text: str, data_type: str) -> Scalar | None:
    t = text.strip()
    try:
        v = number_value(t.lstrip("+")) if not t.startswith("-") else -number_value(t[1:])
    except ValueError:
        return None
    if data_type == "BOOL":
        return bool(v)
    return v


#: longest chain of alias tags followed (an alias of an alias ...)
MAX_ALIAS_CHAIN = 8


def _without_aliases(routine: Routine, aliases: dict[str, tuple[Reference, SourceLocation]],
                     errors: list[Diagnostic]) -> Routine:
    """The routine with every reference to an alias tag replaced by the tag it stands for."""

    def ref(r: Reference, ins: Instruction, rung: int) -> Reference:
        selectors = tuple(_selector(s, ins, rung) for s in r.selectors)
        out = Reference(r.base, selectors)
        for _ in range(MAX_ALIAS_CHAIN):
            if out.base not in aliases:
                return out
            target = aliases[out.base][0]
            out = Reference(target.base, target.selectors + out.selectors)
        loc = ins.location
        errors.append(Diagnostic(loc.file, loc.line, loc.column, f"rung {rung}: instruction {ins.position}",
                                 f"alias tag {r.base!r} resolves through more than {MAX_ALIAS_CHAIN} aliases"))
        return out

    def _selector(s: Any, ins: Instruction, rung: int) -> Any:
        if isinstance(s, Index):
            return Index(tuple(operand(x, ins, rung) for x in s.subscripts))
        if isinstance(s, IndirectBit):
            return IndirectBit(operand(s.bit, ins, rung))
        return s

    def operand(op: Any, ins: Instruction, rung: int) -> Any:
        if isinstance(op, Reference):
            return ref(op, ins, rung)
        if isinstance(op, Unary):
            return Unary(op.op, operand(op.operand, ins, rung))
        if isinstance(op, Binary):
            return Binary(op.op, operand(op.left, ins, rung), operand(op.right, ins, rung))
        return op

    def element(e: Element, rung: int) -> Element:
        if isinstance(e, Branch):
            return Branch(tuple(tuple(element(x, rung) for x in leg) for leg in e.legs), e.location)
        ops: tuple[Operand, ...] = tuple(operand(o, e, rung) for o in e.operands)
        return dataclasses.replace(e, operands=ops)

    rungs = tuple(dataclasses.replace(r, elements=tuple(element(e, r.number) for e in r.elements))
                  for r in routine.rungs)
    return dataclasses.replace(routine, rungs=rungs)
