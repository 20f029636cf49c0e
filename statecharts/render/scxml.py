"""IR chart -> W3C SCXML 1.0 document that python-statemachine's own reader runs alike.

Pipeline position: IR -> **scxml** -> ``generated/scxml/<chart>.scxml``.

The document has a ``<datamodel>`` with every chart variable (and the system
parameters ``coarse_update_ms`` / ``scan_ms`` that expressions may read), and the
chart's states as ``<state>`` / ``<parallel>`` / ``<history>`` / ``<final>`` with
``<onentry>`` / ``<onexit>`` actions; transitions are ``<transition event= cond=
target=>`` with ``<assign>`` actions, in the priority order the engine uses
(:func:`statecharts.engine.machine_class`), which SCXML's document order then
preserves.  Targetless transitions have no ``target``; eventless ones no ``event``.
A history pseudo-state's default transition goes to its parent's initial child.
State names and values, which SCXML has no place for, ride along as attributes in the
``urn:motionchart`` namespace (``mc:name``, ``mc:value``).

Expressions are Python-like (``datamodel="python"``).  python-statemachine evaluates
them with its restricted (safe) evaluator, which lacks a few constructs of the
motionchart expression language, so the exporter rewrites them into equivalents it
has -- the meaning is unchanged, and ``tests/test_scxml.py`` checks it by running
both machines on random event sequences:

* ``x in (a, b)`` -> ``(x == a or x == b)``; ``x not in (a, b)`` -> ``(x != a and x != b)``
  (the reader has no ``in`` operator);
* ``abs``, ``min``, ``max`` and ``a if c else b`` -> conditional forms: in an action
  an ``<if cond=...>`` / ``<else/>`` tree of plain ``<assign>`` elements, in a guard
  ``(c and E[a]) or (not c and E[b])``;
* ``a and b`` / ``a or b`` used as a value -> ``not not (a and b)``, because the
  motionchart language yields a bool where Python yields an operand.

What cannot be rewritten raises :class:`ScxmlUnsupported` with the chart, element and
construct: membership in something other than a literal tuple/list/set, dotted names,
a string constant containing ``true`` / ``false`` / ``null`` in a guard (the reader
rewrites those words, as for ECMAScript), and variable names the reader reserves.

Environment events whose ``actions`` change drive-model variables are listed in a
comment: the environment applies those assignments to the datamodel before it sends
the event, exactly as :mod:`statecharts.scan` does for the engine.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Mapping
from typing import cast
from xml.sax.saxutils import escape, quoteattr

from statecharts import ir
from statecharts.engine import DEFAULT_PARAMETERS, ordered_transitions
from statecharts.expr import Assignment, Expr
from statecharts.render.labels import children

SCXML_NS = "http://www.w3.org/2005/07/scxml"
MC_NS = "urn:motionchart"
INDENT = "  "

#: Names python-statemachine keeps for itself on the model or in callback arguments.
RESERVED_NAMES = frozenset({
    "state", "machine", "model", "event", "event_data", "source", "target", "transition",
    "state_id", "In", "True", "False", "None",
})
_COND_WORDS = re.compile(r"\b(?:true|false|null)\b|===|!==|&&|\|\|")


class ScxmlUnsupported(ValueError):
    """A construct of the chart that the SCXML export cannot express faithfully."""

    def __init__(self, chart: str, where: str, message: str) -> None:
        self.chart = chart
        self.where = where
        super().__init__(f"chart {chart}: {where}: {message}")


# --------------------------------------------------------------------------- expressions


class _Rewriter:
    """Rewrites one expression AST into the subset python-statemachine evaluates."""

    def __init__(self, fail: _Fail) -> None:
        self.fail = fail

    def value(self, node: ast.expr, boolean: bool = False) -> ast.expr:
        """Rewrite ``node``; ``boolean`` says only its truth value is used."""
        if isinstance(node, ast.Constant):
            return node
        if isinstance(node, ast.Name):
            if node.id.startswith("_") or node.id in RESERVED_NAMES:
                raise self.fail(f"variable name {node.id!r} is reserved by python-statemachine")
            return node
        if isinstance(node, ast.Attribute):
            raise self.fail(f"dotted name {ast.unparse(node)!r} has no SCXML datamodel location")
        if isinstance(node, ast.BoolOp):
            new: ast.expr = ast.BoolOp(op=node.op, values=[self.value(v, True) for v in node.values])
            if not boolean:  # the motionchart language yields a bool, Python an operand
                new = ast.UnaryOp(op=ast.Not(), operand=ast.UnaryOp(op=ast.Not(), operand=new))
            return new
        if isinstance(node, ast.UnaryOp):
            return ast.UnaryOp(op=node.op, operand=self.value(node.operand, isinstance(node.op, ast.Not)))
        if isinstance(node, ast.BinOp):
            return ast.BinOp(left=self.value(node.left), op=node.op, right=self.value(node.right))
        if isinstance(node, ast.Compare):
            return self.compare(node)
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return type(node)(elts=[self.value(e) for e in node.elts], ctx=ast.Load()) if not isinstance(
                node, ast.Set) else ast.Set(elts=[self.value(e) for e in node.elts])
        if isinstance(node, ast.IfExp):
            return ast.IfExp(test=self.value(node.test, True), body=self.value(node.body, boolean),
                             orelse=self.value(node.orelse, boolean))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            return self.call(node.func.id, [self.value(a) for a in node.args])
        raise self.fail(f"construct {ast.unparse(node)!r}")

    def call(self, name: str, args: list[ast.expr]) -> ast.expr:
        if name == "abs" and len(args) == 1:
            (x,) = args
            return ast.IfExp(test=_cmp(x, ast.Lt(), ast.Constant(0)), body=ast.UnaryOp(op=ast.USub(), operand=x),
                             orelse=x)
        if name in ("min", "max") and len(args) >= 2:
            result = args[0]
            for nxt in args[1:]:
                # Python returns the first of equal values: replace only on a strict win
                op: ast.cmpop = ast.Lt() if name == "min" else ast.Gt()
                result = ast.IfExp(test=_cmp(nxt, op, result), body=nxt, orelse=result)
            return result
        raise self.fail(f"call of {name}() with {len(args)} argument(s)")

    def compare(self, node: ast.Compare) -> ast.expr:
        left = self.value(node.left)
        parts: list[ast.expr] = []
        for op, comp in zip(node.ops, node.comparators):
            right = comp
            if isinstance(op, (ast.In, ast.NotIn)):
                if not isinstance(right, (ast.Tuple, ast.List, ast.Set)):
                    raise self.fail(
                        f"membership test {ast.unparse(node)!r}: the reader has no 'in' and only a literal "
                        "tuple, list or set can be rewritten")
                members = [self.value(e) for e in right.elts]
                if isinstance(op, ast.In):
                    tests: list[ast.expr] = [_cmp(left, ast.Eq(), m) for m in members]
                    parts.append(ast.BoolOp(op=ast.Or(), values=tests) if len(tests) > 1 else
                                 tests[0] if tests else ast.Constant(False))
                else:
                    tests = [_cmp(left, ast.NotEq(), m) for m in members]
                    parts.append(ast.BoolOp(op=ast.And(), values=tests) if len(tests) > 1 else
                                 tests[0] if tests else ast.Constant(True))
                left = ast.Tuple(elts=members, ctx=ast.Load())
            else:
                new_right = self.value(right)
                parts.append(_cmp(left, op, new_right))
                left = new_right
        if len(parts) == 1:
            return parts[0]
        return ast.BoolOp(op=ast.And(), values=parts)


def _cmp(a: ast.expr, op: ast.cmpop, b: ast.expr) -> ast.Compare:
    return ast.Compare(left=a, ops=[op], comparators=[b])


class _Fail:
    def __init__(self, chart: str, where: str) -> None:
        self.chart = chart
        self.where = where

    def __call__(self, message: str) -> ScxmlUnsupported:
        return ScxmlUnsupported(self.chart, self.where, message)


def _first_ifexp(node: ast.AST) -> ast.IfExp | None:
    """An IfExp whose test holds no other IfExp (so its test can be written as is)."""
    for sub in ast.walk(node):
        if isinstance(sub, ast.IfExp) and not any(isinstance(x, ast.IfExp) for x in ast.walk(sub.test)):
            return sub
    return None


def _replace(node: ast.AST, old: ast.AST, new: ast.expr) -> ast.expr:
    """A copy of ``node`` with every occurrence of ``old`` (by identity) replaced; no mutation."""
    if node is old:
        return new
    fields: dict[str, object] = {}
    for name, value in ast.iter_fields(node):
        if isinstance(value, list):
            fields[name] = [_replace(v, old, new) if isinstance(v, ast.AST) else v for v in value]
        elif isinstance(value, ast.AST):
            fields[name] = _replace(value, old, new)
        else:
            fields[name] = value
    return cast(ast.expr, type(node)(**fields))  # node is an expression, so is its copy


def _unparse(node: ast.expr) -> str:
    return ast.unparse(ast.fix_missing_locations(node))


def _guard_text(node: ast.expr) -> str:
    """A guard without IfExp: ``E[c ? a : b]`` -> ``(c and E[a]) or (not c and E[b])``."""
    ife = _first_ifexp(node)
    if ife is None:
        return _unparse(node)
    test = _unparse(ife.test)
    yes = _guard_text(_replace(node, ife, ife.body))
    no = _guard_text(_replace(node, ife, ife.orelse))
    return f"(({test}) and ({yes})) or (not ({test}) and ({no}))"


def translate_guard(expr: Expr, chart: str = "?", where: str = "guard") -> str:
    """The SCXML ``cond`` text of a guard (see the module docstring for the rewrites)."""
    fail = _Fail(chart, where)
    tree = ast.parse(expr.text.strip(), mode="eval")
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and _COND_WORDS.search(node.value):
            raise fail(f"string {node.value!r}: the reader rewrites true/false/null inside conditions")
    return _guard_text(_Rewriter(fail).value(tree.body, True))


def _assign_xml(target: str, node: ast.expr, depth: int) -> list[str]:
    pad = INDENT * depth
    ife = _first_ifexp(node)
    if ife is None:
        return [f"{pad}<assign location={quoteattr(target)} expr={quoteattr(_unparse(node))}/>"]
    out = [f"{pad}<if cond={quoteattr(_unparse(ife.test))}>"]
    out.extend(_assign_xml(target, _replace(node, ife, ife.body), depth + 1))
    out.append(f"{pad}{INDENT}<else/>")
    out.extend(_assign_xml(target, _replace(node, ife, ife.orelse), depth + 1))
    out.append(f"{pad}</if>")
    return out


def translate_assignment(a: Assignment, depth: int = 0, chart: str = "?", where: str = "action") -> list[str]:
    """``<assign>`` (or an ``<if>`` tree of them) lines for one action."""
    fail = _Fail(chart, where)
    if "." in a.target or a.target.startswith("_") or a.target in RESERVED_NAMES:
        raise fail(f"assignment target {a.target!r} has no SCXML datamodel location")
    tree = ast.parse(a.value.text.strip(), mode="eval")
    return _assign_xml(a.target, _Rewriter(fail).value(tree.body), depth)


# --------------------------------------------------------------------------- document


def _literal(value: object) -> str:
    if isinstance(value, float) and (value != value or value in (float("inf"), float("-inf"))):
        raise ValueError(f"{value!r} has no literal")
    return repr(value)


class _Writer:
    def __init__(self, chart: ir.Chart) -> None:
        self.chart = chart
        self.lines: list[str] = []

    def actions(self, tag: str, actions: tuple[Assignment, ...], depth: int, where: str) -> None:
        if not actions:
            return
        pad = INDENT * depth
        self.lines.append(f"{pad}<{tag}>")
        for i, a in enumerate(actions):
            self.lines.extend(translate_assignment(a, depth + 1, self.chart.id, f"{where}[{i}] {a.text!r}"))
        self.lines.append(f"{pad}</{tag}>")

    def transition(self, t: ir.Transition, depth: int) -> None:
        pad = INDENT * depth
        attrs = []
        if t.event is not None:
            attrs.append(f"event={quoteattr(t.event)}")
        if t.guard is not None:
            cond = translate_guard(t.guard, self.chart.id, f"transition {t.id} guard {t.guard.text!r}")
            attrs.append(f"cond={quoteattr(cond)}")
        if t.target is not None:
            attrs.append(f"target={quoteattr(t.target)}")
        attrs.append(f"mc:id={quoteattr(t.id)}")
        head = f"{pad}<transition {' '.join(attrs)}"
        if not t.actions:
            self.lines.append(head + "/>")
            return
        self.lines.append(head + ">")
        for i, a in enumerate(t.actions):
            self.lines.extend(translate_assignment(a, depth + 1, self.chart.id, f"transition {t.id} action[{i}]"))
        self.lines.append(f"{pad}</transition>")

    def state(self, s: ir.State, depth: int) -> None:
        pad = INDENT * depth
        chart = self.chart
        if s.kind is ir.StateKind.HISTORY:
            parent = chart.state(s.parent) if s.parent else None
            default = parent.initial if parent is not None else None
            kind = s.history_type or "shallow"
            self.lines.append(f"{pad}<history id={quoteattr(s.id)} type={quoteattr(kind)} mc:name={quoteattr(s.name)}>")
            if default:
                self.lines.append(f"{pad}{INDENT}<transition target={quoteattr(default)}/>")
            self.lines.append(f"{pad}</history>")
            return
        tag = {ir.StateKind.PARALLEL: "parallel", ir.StateKind.FINAL: "final"}.get(s.kind, "state")
        attrs = [f"id={quoteattr(s.id)}"]
        if s.kind is ir.StateKind.COMPOUND and s.initial:
            attrs.append(f"initial={quoteattr(s.initial)}")
        attrs.append(f"mc:name={quoteattr(s.name)}")
        if s.value is not None:
            attrs.append(f"mc:value={quoteattr(str(s.value))}")
        self.lines.append(f"{pad}<{tag} {' '.join(attrs)}>")
        self.actions("onentry", s.entry, depth + 1, f"state {s.id} entry")
        self.actions("onexit", s.exit, depth + 1, f"state {s.id} exit")
        for t in ordered_transitions(x for x in chart.transitions if x.source == s.id):
            self.transition(t, depth + 1)
        for c in children(chart, s.id):
            self.state(c, depth + 1)
        self.lines.append(f"{pad}</{tag}>")


def chart_scxml(
    chart: ir.Chart,
    *,
    initial: Mapping[str, object] | None = None,
    parameters: Mapping[str, int] | None = None,
    source: str | None = None,
) -> str:
    """The SCXML text of ``chart``; ``initial`` overrides initial variable values.

    Raises :class:`ScxmlUnsupported` for a construct that cannot be exported faithfully.
    """
    w = _Writer(chart)
    values: dict[str, object] = {v.name: v.initial for v in chart.variables}
    unknown = sorted(set(initial or {}) - set(values))
    if unknown:
        raise ScxmlUnsupported(chart.id, "initial values", f"unknown variable(s): {', '.join(unknown)}")
    values.update(initial or {})
    params = dict(DEFAULT_PARAMETERS)
    params.update(parameters or {})
    lines = w.lines
    lines.append('<?xml version="1.0" encoding="UTF-8"?>')
    lines.append(f"<!-- {escape(chart.name)} ({chart.id}), exported by motionchart"
                 + (f" from {escape(source)}" if source else "") + ". Do not edit: regenerate. -->")
    env_events = [e for e in chart.events if e.actions]
    if env_events:
        lines.append("<!-- Events whose assignments the environment applies to the datamodel before sending them:")
        for e in env_events:
            lines.append(f"     {e.name}: " + "; ".join(escape(a.text) for a in e.actions).replace("--", "- -"))
        lines.append("-->")
    lines.append(
        f"<scxml xmlns={quoteattr(SCXML_NS)} xmlns:mc={quoteattr(MC_NS)} version=\"1.0\" datamodel=\"python\" "
        f"name={quoteattr(chart.id)} initial={quoteattr(chart.root_initial)}>")
    lines.append(f"{INDENT}<datamodel>")
    for v in chart.variables:
        if v.name.startswith("_") or v.name in RESERVED_NAMES:
            raise ScxmlUnsupported(chart.id, f"variable {v.name}", "name reserved by python-statemachine")
        lines.append(f"{INDENT * 2}<data id={quoteattr(v.name)} expr={quoteattr(_literal(values[v.name]))}/>")
    for name in sorted(params):
        if name not in values:
            lines.append(f"{INDENT * 2}<data id={quoteattr(name)} expr={quoteattr(_literal(params[name]))}/>")
    lines.append(f"{INDENT}</datamodel>")
    for s in children(chart, None):
        w.state(s, 1)
    lines.append("</scxml>")
    return "\n".join(lines) + "\n"
