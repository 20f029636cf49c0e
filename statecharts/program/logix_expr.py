"""Logix expressions and tag references: an allow-list parser, never ``eval``.

Pipeline position: used by the rung-text readers for every operand (a tag reference
such as ``X_STAT[i+1].DN``, an immediate value such as ``16#FF``) and for the
expressions of CPT and CMP.  The grammar is that of the Logix 5000 Compute/Compare
instructions (1756-RM003N, "Valid operators" and "Order of operation"): from the
tightest binding, function calls and parentheses; ``**``; negation and ``NOT``;
``*`` ``/`` ``MOD``; ``+`` ``-``; the comparisons ``=`` ``<>`` ``<`` ``<=`` ``>`` ``>=``;
``AND``; ``XOR``; ``OR``.  Anything else is a :class:`ExpressionSyntaxError` with the
offset of the offending text.
"""

from __future__ import annotations

import re

from statecharts.program.ir import Binary, Expression, Index, IndirectBit, Member, Number, Reference, Selector, Unary

#: one-argument functions of CPT/CMP expressions
FUNCTIONS = ("ABS", "ACS", "ASN", "ATN", "COS", "DEG", "LN", "LOG", "RAD", "SIN", "SQR", "SQRT", "TAN", "TRN")
KEYWORDS = ("AND", "OR", "XOR", "NOT", "MOD")
#: deepest nesting of parentheses and subscripts accepted
MAX_DEPTH = 32
MAX_LENGTH = 4000

_TOKEN = re.compile(r"""
    (?P<space>\s+)
  | (?P<radix>(?:2|8|16)\#[0-9A-Fa-f_]+)
  | (?P<number>(?:\d[\d_]*\.\d*|\.\d+|\d[\d_]*)(?:[eE][+-]?\d+)?)
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*(?::[A-Za-z0-9_]+)*)
  | (?P<op>\*\*|<=|>=|<>|[-+*/=<>()\[\],.&|])
""", re.VERBOSE)

_BINARY = {  # operator -> (left binding power, right binding power)
    "OR": (10, 11), "XOR": (12, 13), "AND": (14, 15),
    "=": (20, 21), "<>": (20, 21), "<": (20, 21), "<=": (20, 21), ">": (20, 21), ">=": (20, 21),
    "+": (30, 31), "-": (30, 31),
    "*": (40, 41), "/": (40, 41), "MOD": (40, 41),
    "**": (61, 60),  # right-associative
}
_PREFIX_POWER = 50  # - and NOT bind tighter than * but looser than **


class ExpressionSyntaxError(ValueError):
    """``offset`` is the 0-based position in the text where the problem is."""

    def __init__(self, offset: int, message: str) -> None:
        self.offset = offset
        self.message = message
        super().__init__(message)


class _Tokens:
    def __init__(self, text: str) -> None:
        if len(text) > MAX_LENGTH:
            raise ExpressionSyntaxError(0, f"expression longer than {MAX_LENGTH} characters")
        self.items: list[tuple[str, str, int]] = []
        pos = 0
        while pos < len(text):
            m = _TOKEN.match(text, pos)
            if m is None:
                raise ExpressionSyntaxError(pos, f"unexpected character {text[pos]!r}")
            kind = m.lastgroup or ""
            if kind != "space":
                value = m.group()
                if kind == "name" and value.upper() in KEYWORDS:
                    kind, value = "op", value.upper()
                elif kind == "op" and value == "&":
                    value = "AND"
                elif kind == "op" and value == "|":
                    value = "OR"
                self.items.append((kind, value, pos))
            pos = m.end()
        self.end = len(text)
        self.i = 0

    def peek(self) -> tuple[str, str, int]:
        return self.items[self.i] if self.i < len(self.items) else ("end", "", self.end)

    def take(self) -> tuple[str, str, int]:
        tok = self.peek()
        self.i += 1
        return tok

    def expect(self, value: str) -> None:
        kind, v, pos = self.take()
        if v != value:
            raise ExpressionSyntaxError(pos, f"expected {value!r}, found {_shown(kind, v)}")


def _shown(kind: str, value: str) -> str:
    return "the end of the operand" if kind == "end" else repr(value)


def number_value(text: str) -> int | float:
    """The value of a Logix numeric literal (``12``, ``-1.5e3``, ``16#FF``, ``2#1010_0001``)."""
    t = text.replace("_", "")
    if "#" in t:
        base, digits = t.split("#", 1)
        return int(digits, int(base))
    if any(c in t for c in ".eE"):
        return float(t)
    return int(t)


def parse_expression(text: str) -> Expression:
    """A whole expression; the text must hold nothing else."""
    tokens = _Tokens(text)
    expr = _expression(tokens, 0, 0)
    kind, value, pos = tokens.peek()
    if kind != "end":
        raise ExpressionSyntaxError(pos, f"unexpected {value!r} after the expression")
    return expr


def parse_reference(text: str) -> Reference:
    """A tag reference such as ``Axis_STAT[2].DN``, ``Flags.3`` or ``Word.[bit]``; nothing else."""
    tokens = _Tokens(text)
    kind, value, pos = tokens.take()
    if kind != "name":
        raise ExpressionSyntaxError(pos, f"expected a tag name, found {_shown(kind, value)}")
    ref = _selectors(tokens, value, 0)
    kind, value, pos = tokens.peek()
    if kind != "end":
        raise ExpressionSyntaxError(pos, f"unexpected {value!r} after the tag reference")
    return ref


def _expression(tokens: _Tokens, min_power: int, depth: int) -> Expression:
    if depth > MAX_DEPTH:
        raise ExpressionSyntaxError(tokens.peek()[2], f"expression nested deeper than {MAX_DEPTH} levels")
    left = _prefix(tokens, depth)
    while True:
        kind, op, _pos = tokens.peek()
        if kind != "op" or op not in _BINARY:
            return left
        lp, rp = _BINARY[op]
        if lp < min_power:
            return left
        tokens.take()
        right = _expression(tokens, rp, depth + 1)
        left = Binary(op, left, right)


def _prefix(tokens: _Tokens, depth: int) -> Expression:
    kind, value, pos = tokens.take()
    if kind == "op" and value in ("-", "NOT"):
        operand = _expression(tokens, _PREFIX_POWER, depth + 1)
        if value == "-" and isinstance(operand, Number):
            return Number(-operand.value, "-" + (operand.text or repr(operand.value)))
        return Unary(value, operand)
    if kind == "op" and value == "+":
        return _expression(tokens, _PREFIX_POWER, depth + 1)
    if kind == "op" and value == "(":
        inner = _expression(tokens, 0, depth + 1)
        tokens.expect(")")
        return inner
    if kind in ("number", "radix"):
        try:
            return Number(number_value(value), value)
        except ValueError:
            raise ExpressionSyntaxError(pos, f"{value!r} is not a number") from None
    if kind == "name":
        if tokens.peek()[1] == "(":
            fn = value.upper()
            if fn not in FUNCTIONS:
                raise ExpressionSyntaxError(pos, f"unknown function {value!r}; functions: {', '.join(FUNCTIONS)}")
            tokens.take()
            arg = _expression(tokens, 0, depth + 1)
            tokens.expect(")")
            return Unary("SQR" if fn == "SQRT" else fn, arg)
        return _selectors(tokens, value, depth)
    raise ExpressionSyntaxError(pos, f"expected a value, a tag or '(', found {_shown(kind, value)}")


def _selectors(tokens: _Tokens, base: str, depth: int) -> Reference:
    selectors: list[Selector] = []
    while True:
        kind, value, pos = tokens.peek()
        if value == "[" and kind == "op":
            tokens.take()
            subs = [_expression(tokens, 0, depth + 1)]
            while tokens.peek()[1] == ",":
                tokens.take()
                subs.append(_expression(tokens, 0, depth + 1))
            tokens.expect("]")
            if len(subs) > 3:
                raise ExpressionSyntaxError(pos, "an array has at most three dimensions")
            selectors.append(Index(tuple(subs)))
        elif value == "." and kind == "op":
            tokens.take()
            kind2, value2, pos2 = tokens.take()
            if kind2 == "name":
                selectors.append(Member(value2))
            elif kind2 == "number" and value2.isdigit():
                selectors.append(Member(str(int(value2))))
            elif kind2 == "op" and value2 == "[":
                bit = _expression(tokens, 0, depth + 1)
                tokens.expect("]")
                selectors.append(IndirectBit(bit))
            else:
                raise ExpressionSyntaxError(pos2, f"expected a member name or bit number after '.', found {_shown(kind2, value2)}")
        elif kind == "number" and value.startswith(".") and value[1:].isdigit():
            # ``Flags.3`` tokenises as the name and the number ".3"
            tokens.take()
            selectors.append(Member(str(int(value[1:]))))
        else:
            return Reference(base, tuple(selectors))
