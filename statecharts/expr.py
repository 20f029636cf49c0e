"""The small expression language of statechart specs: spec text -> checked AST -> closures; no eval.

Guards, checks and actions in a (third-party, YAML) statechart specification are
written in a tiny subset of Python expression syntax.  Each text is parsed ONCE,
at load time, with :func:`ast.parse`; the resulting tree is checked against an
allow-list of node types and compiled bottom-up into plain Python closures that
take a flat environment mapping (``Env``) and return a value.  Spec text is never
handed to ``eval``/``exec``/the built-in byte-code compiler, and nothing is ever
looked up with ``getattr``: a dotted name such as ``axis.state`` is a single key
``"axis.state"`` of the environment.

Allowed:

* constants: ``True``/``False``, ints, floats, strings, ``None``;
* names (not starting with ``_``) and dotted names on a name chain (``a.b.c``);
* ``and`` / ``or`` (short-circuit, result is a ``bool``), ``not``, unary ``-``/``+``;
* ``+ - * / // %`` (``%`` is arithmetic only: string formatting is refused at run time);
* comparisons ``== != < <= > >= in not in``, chained as in Python;
* tuple / list / set displays (constant ones used with ``in`` become a frozenset);
* ``a if c else b``;
* calls of ``abs``, ``min`` and ``max`` with positional arguments only.

Everything else is an :class:`ExprError` naming the construct and its 0-based
character offset in the text.
"""

from __future__ import annotations

import ast
import functools
import re
import warnings
from collections.abc import Callable, Collection, Mapping, MutableMapping
from dataclasses import dataclass, field
from typing import Any, Final, Literal, TypeAlias, cast

__all__ = [
    "Assignment",
    "Env",
    "EvalError",
    "Expr",
    "ExprError",
    "check_names",
    "parse_assignment",
    "parse_expression",
]

Env: TypeAlias = Mapping[str, object]
Fn: TypeAlias = Callable[[Env], object]

#: The operator closures below compute on values whose types the language checks when
#: the operator runs (a spec decides them), so they are typed as dynamic.
_Dyn: TypeAlias = Any
_DynFn: TypeAlias = Callable[[Mapping[str, Any]], Any]

#: Longest accepted expression text, in characters.
MAX_LENGTH: Final = 2000
#: Deepest accepted AST nesting (counting every AST node on the path from the root).
MAX_DEPTH: Final = 50
#: Longest string, tuple or list an expression may build (by ``*`` repetition or ``+``).
MAX_SIZE: Final = 10_000
#: Longest sequence that ``*`` may build by repetition (``'ab' * n``); kept as an alias.
MAX_REPEAT: Final = MAX_SIZE
#: Largest magnitude of an integer product (Logix LINT is 64 bits).
MAX_INT: Final = 2**63 - 1

_ALLOWED: Final = (
    "allowed: constants, names, dotted names, and/or/not, + - * / // %, "
    "== != < <= > >= in / not in, tuple/list/set literals, "
    "'a if c else b', abs()/min()/max()"
)

_FUNCTIONS: Final[dict[str, Callable[..., object]]] = {"abs": abs, "min": min, "max": max}


# --------------------------------------------------------------------------- errors


class ExprError(ValueError):
    """A spec expression that cannot be parsed or is not allowed."""

    def __init__(self, message: str, text: str, offset: int) -> None:
        super().__init__(message)
        self.message = message
        self.text = text
        self.offset = offset

    def __str__(self) -> str:
        return self.message


class EvalError(RuntimeError):
    """An expression failed at run time (unknown name in env, division by zero, type error)."""

    def __init__(self, message: str, text: str) -> None:
        super().__init__(message)
        self.message = message
        self.text = text

    def __str__(self) -> str:
        return self.message


# --------------------------------------------------------------------------- public types


def _eval_error(text: str, exc: Exception) -> EvalError:
    if isinstance(exc, KeyError):
        key = exc.args[0] if exc.args else "?"
        return EvalError(f"unknown variable {key!r} in expression {text!r}", text)
    if isinstance(exc, ZeroDivisionError):
        return EvalError(f"division by zero in expression {text!r}", text)
    if isinstance(exc, LimitError):
        return EvalError(f"{exc} in expression {text!r}", text)
    return EvalError(f"{type(exc).__name__} in expression {text!r}: {exc}", text)


@dataclass(frozen=True, slots=True)
class Expr:
    """A checked, compiled spec expression.

    ``names`` holds every variable the expression reads (dotted paths as single
    keys).  ``fn`` is the raw compiled closure: it raises plain ``KeyError`` /
    ``ZeroDivisionError`` / ``TypeError``; calling the ``Expr`` itself wraps those
    in :class:`EvalError`.
    """

    text: str
    names: frozenset[str]
    fn: Fn = field(compare=False, repr=False)

    def __call__(self, env: Env) -> object:
        try:
            return self.fn(env)
        except (KeyError, ArithmeticError, TypeError, ValueError) as exc:
            raise _eval_error(self.text, exc) from exc


@dataclass(frozen=True, slots=True)
class Assignment:
    """A checked ``target = expr`` (or ``target += expr`` / ``target -= expr``) action."""

    text: str
    target: str
    value: Expr

    def apply(self, env: MutableMapping[str, object]) -> None:
        env[self.target] = self.value(env)


# --------------------------------------------------------------------------- source positions

_NEWLINE = r"\r\n|\r|\n"  # the newlines Python's tokenizer recognises in a str source
# Whitespace the tokenizer itself skips; anything else (e.g. U+00A0) is its business.
_LEADING_WS = " \t\f\r\n"


class _Source:
    """Maps parser positions of a (stripped) text back to offsets into the original."""

    __slots__ = ("base", "body", "lines", "original", "starts")

    def __init__(self, original: str, body: str, base: int) -> None:
        self.original = original
        self.body = body
        self.base = base
        starts = [0]
        lines: list[str] = []
        pos = 0
        for m in re.finditer(_NEWLINE, body):
            lines.append(body[pos : m.start()])
            pos = m.end()
            starts.append(pos)
        lines.append(body[pos:])
        self.starts = starts
        self.lines = lines

    def _clamp(self, off: int) -> int:
        return max(0, min(off, len(self.original)))

    def at_char(self, lineno: int | None, col: int | None) -> int:
        """Offset of (1-based line, 0-based character column)."""
        if not lineno:
            return self._clamp(self.base)
        i = min(max(lineno - 1, 0), len(self.lines) - 1)
        return self._clamp(self.base + self.starts[i] + max(col or 0, 0))

    def line_end(self, lineno: int | None) -> int:
        """Offset just past the last character of a line (the end of the text if unknown)."""
        if not lineno:
            return self._clamp(self.base + len(self.body.rstrip()))
        i = min(max(lineno - 1, 0), len(self.lines) - 1)
        return self.at_char(i + 1, len(self.lines[i].rstrip()))

    def at_byte(self, lineno: int | None, col: int | None) -> int:
        """Offset of (1-based line, 0-based UTF-8 byte column), as in AST nodes."""
        if not lineno:
            return self._clamp(self.base)
        i = min(max(lineno - 1, 0), len(self.lines) - 1)
        raw = self.lines[i].encode("utf-8", "surrogatepass")[: max(col or 0, 0)]
        return self.at_char(lineno, len(raw.decode("utf-8", "ignore")))

    def node(self, node: ast.AST) -> int:
        return self.at_byte(getattr(node, "lineno", None), getattr(node, "col_offset", None))

    def node_end(self, node: ast.AST) -> int:
        return self.at_byte(getattr(node, "end_lineno", None), getattr(node, "end_col_offset", None))


def _parse(text: str, mode: Literal["eval", "exec"], what: str) -> tuple[ast.AST, _Source]:
    """Parse text with the stdlib parser, turning every failure into ExprError."""
    if not isinstance(text, str):
        raise ExprError(f"{what} must be a string, not {type(text).__name__}", str(text), 0)
    if len(text) > MAX_LENGTH:
        raise ExprError(
            f"{what} is too long ({len(text)} characters; at most {MAX_LENGTH} are allowed)",
            text,
            MAX_LENGTH,
        )
    body = text.lstrip(_LEADING_WS)
    if not body.strip():
        raise ExprError(f"empty {what}", text, 0)
    src = _Source(text, body, len(text) - len(body))
    if "\0" in body:
        raise ExprError(f"{what} contains a null character", text, text.index("\0"))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tree = ast.parse(body, mode=mode)
    except SyntaxError as exc:  # includes IndentationError / TabError
        msg = exc.msg or "invalid syntax"
        if exc.offset and exc.offset > 0:
            off = src.at_char(exc.lineno, exc.offset - 1)
        else:  # the parser reports "unexpected end of input" without a column
            off = src.line_end(exc.lineno)
        raise ExprError(f"syntax error in {what}: {msg}", text, off) from None
    except (RecursionError, MemoryError):
        raise ExprError(f"{what} is too complex to parse", text, 0) from None
    except ValueError as exc:  # e.g. lone surrogates, null bytes on other versions
        raise ExprError(f"{what} cannot be parsed: {exc}", text, 0) from None
    _check_depth(tree, src)
    if not body.isascii():
        _check_identifiers(text, body, src)
    return tree, src


def _check_identifiers(text: str, body: str, src: _Source) -> None:
    """Refuse identifiers that Python would silently NFKC-normalise to other letters
    (full-width or mathematical-bold letters reading as an ASCII variable name)."""
    import io
    import tokenize
    import unicodedata

    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(body).readline))
    except (tokenize.TokenError, SyntaxError, ValueError):
        return  # the parser accepted it; positions are only a refinement
    for tok in tokens:
        if tok.type == tokenize.NAME and not tok.string.isascii():
            normal = unicodedata.normalize("NFKC", tok.string)
            if normal != tok.string:
                raise ExprError(
                    f"identifier {tok.string!r} uses look-alike Unicode letters (it would read as {normal!r}); "
                    "write names in ASCII", text, src.at_char(tok.start[0], tok.start[1]))


def _check_depth(tree: ast.AST, src: _Source) -> None:
    """Iteratively refuse trees nested deeper than MAX_DEPTH (before any recursion)."""
    stack: list[tuple[ast.AST, int]] = [(tree, 0)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise ExprError(
                f"expression is nested too deeply (more than {MAX_DEPTH} levels)",
                src.original,
                src.node(node),
            )
        stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))


# --------------------------------------------------------------------------- run-time helpers

_NUMBER_TYPES: Final = (int, float, bool)
_SEQUENCE_TYPES: Final = (str, bytes, tuple, list)


class LimitError(ValueError):
    """An expression would build a value larger than the language allows."""


def _mul(a: _Dyn, b: _Dyn) -> object:
    ta = type(a)
    tb = type(b)
    if ta is int and tb is int:
        r = a * b
        if -MAX_INT <= r <= MAX_INT:
            return r
        raise LimitError(f"integer product beyond 64 bits (at most {MAX_INT} in magnitude)")
    if (ta is int or ta is float or ta is bool) and (tb is int or tb is float or tb is bool):
        return a * b
    if isinstance(a, _SEQUENCE_TYPES) and isinstance(b, int):
        if len(a) * b > MAX_SIZE:
            raise LimitError(f"sequence repetition longer than {MAX_SIZE}")
    elif isinstance(b, _SEQUENCE_TYPES) and isinstance(a, int) and len(b) * a > MAX_SIZE:
        raise LimitError(f"sequence repetition longer than {MAX_SIZE}")
    return a * b


def _add(a: _Dyn, b: _Dyn) -> object:
    r = a + b
    if type(r) in _SEQUENCE_TYPES and len(r) > MAX_SIZE:
        raise LimitError(f"concatenation longer than {MAX_SIZE}")
    return r


def _mod(a: _Dyn, b: _Dyn) -> object:
    if isinstance(a, (str, bytes)):
        raise TypeError("string formatting with '%' is not allowed in a spec expression")
    return a % b


def _is_immutable(value: object, depth: int = 0) -> bool:
    if value is None or type(value) in (bool, int, float, str):
        return True
    if depth < MAX_DEPTH and type(value) in (tuple, frozenset):
        return all(_is_immutable(v, depth + 1) for v in cast("tuple[object, ...]", value))
    return False


# --------------------------------------------------------------------------- closure factories
#
# Each binary operator has three factories: both sides computed (ff), constant
# right (fc) and constant left (cf), so that constants are not re-fetched
# through a closure call in the inner loop.

_BinFactories: TypeAlias = tuple[
    Callable[[_DynFn, _DynFn], Fn], Callable[[_DynFn, _Dyn], Fn], Callable[[_Dyn, _DynFn], Fn]
]

_BINOPS: Final[dict[type[ast.operator], tuple[str, Callable[[_Dyn, _Dyn], object], _BinFactories]]] = {
    ast.Add: (
        "+",
        _add,
        (
            lambda l, r: lambda env: _add(l(env), r(env)),
            lambda l, c: (lambda env: l(env) + c) if type(c) in _NUMBER_TYPES else (lambda env: _add(l(env), c)),
            lambda c, r: (lambda env: c + r(env)) if type(c) in _NUMBER_TYPES else (lambda env: _add(c, r(env))),
        ),
    ),
    ast.Sub: (
        "-",
        lambda a, b: a - b,
        (
            lambda l, r: lambda env: l(env) - r(env),
            lambda l, c: lambda env: l(env) - c,
            lambda c, r: lambda env: c - r(env),
        ),
    ),
    ast.Mult: (
        "*",
        _mul,
        (
            lambda l, r: lambda env: _mul(l(env), r(env)),
            lambda l, c: lambda env: _mul(l(env), c),
            lambda c, r: lambda env: _mul(c, r(env)),
        ),
    ),
    ast.Div: (
        "/",
        lambda a, b: a / b,
        (
            lambda l, r: lambda env: l(env) / r(env),
            lambda l, c: lambda env: l(env) / c,
            lambda c, r: lambda env: c / r(env),
        ),
    ),
    ast.FloorDiv: (
        "//",
        lambda a, b: a // b,
        (
            lambda l, r: lambda env: l(env) // r(env),
            lambda l, c: lambda env: l(env) // c,
            lambda c, r: lambda env: c // r(env),
        ),
    ),
    ast.Mod: (
        "%",
        _mod,
        (
            lambda l, r: lambda env: _mod(l(env), r(env)),
            lambda l, c: lambda env: _mod(l(env), c),
            lambda c, r: lambda env: _mod(c, r(env)),
        ),
    ),
}

_REFUSED_BINOPS: Final[dict[type[ast.operator], str]] = {
    ast.Pow: "**",
    ast.MatMult: "@",
    ast.LShift: "<<",
    ast.RShift: ">>",
    ast.BitOr: "|",
    ast.BitXor: "^",
    ast.BitAnd: "&",
}


def _contains(a: _Dyn, b: _Dyn) -> bool:
    return a in b


def _not_contains(a: _Dyn, b: _Dyn) -> bool:
    return a not in b


_CMPOPS: Final[dict[type[ast.cmpop], tuple[Callable[[_Dyn, _Dyn], object], _BinFactories]]] = {
    ast.Eq: (
        lambda a, b: a == b,
        (
            lambda l, r: lambda env: l(env) == r(env),
            lambda l, c: lambda env: l(env) == c,
            lambda c, r: lambda env: c == r(env),
        ),
    ),
    ast.NotEq: (
        lambda a, b: a != b,
        (
            lambda l, r: lambda env: l(env) != r(env),
            lambda l, c: lambda env: l(env) != c,
            lambda c, r: lambda env: c != r(env),
        ),
    ),
    ast.Lt: (
        lambda a, b: a < b,
        (
            lambda l, r: lambda env: l(env) < r(env),
            lambda l, c: lambda env: l(env) < c,
            lambda c, r: lambda env: c < r(env),
        ),
    ),
    ast.LtE: (
        lambda a, b: a <= b,
        (
            lambda l, r: lambda env: l(env) <= r(env),
            lambda l, c: lambda env: l(env) <= c,
            lambda c, r: lambda env: c <= r(env),
        ),
    ),
    ast.Gt: (
        lambda a, b: a > b,
        (
            lambda l, r: lambda env: l(env) > r(env),
            lambda l, c: lambda env: l(env) > c,
            lambda c, r: lambda env: c > r(env),
        ),
    ),
    ast.GtE: (
        lambda a, b: a >= b,
        (
            lambda l, r: lambda env: l(env) >= r(env),
            lambda l, c: lambda env: l(env) >= c,
            lambda c, r: lambda env: c >= r(env),
        ),
    ),
    ast.In: (
        _contains,
        (
            lambda l, r: lambda env: l(env) in r(env),
            lambda l, c: lambda env: l(env) in c,
            lambda c, r: lambda env: c in r(env),
        ),
    ),
    ast.NotIn: (
        _not_contains,
        (
            lambda l, r: lambda env: l(env) not in r(env),
            lambda l, c: lambda env: l(env) not in c,
            lambda c, r: lambda env: c not in r(env),
        ),
    ),
}

_REFUSED_CMPOPS: Final[dict[type[ast.cmpop], str]] = {ast.Is: "is", ast.IsNot: "is not"}

_CMP_NAME_CONST: Final[dict[type[ast.cmpop], Callable[[str, _Dyn], _DynFn]]] = {
    ast.Eq: lambda k, c: lambda env: env[k] == c,
    ast.NotEq: lambda k, c: lambda env: env[k] != c,
    ast.Lt: lambda k, c: lambda env: env[k] < c,
    ast.LtE: lambda k, c: lambda env: env[k] <= c,
    ast.Gt: lambda k, c: lambda env: env[k] > c,
    ast.GtE: lambda k, c: lambda env: env[k] >= c,
    ast.In: lambda k, c: lambda env: env[k] in c,
    ast.NotIn: lambda k, c: lambda env: env[k] not in c,
}


def _member_fn(lf: Fn, fs: frozenset[object], tup: tuple[object, ...], negate: bool) -> Fn:
    """``x in <constant display>`` as a frozenset probe (tuple scan for unhashable x)."""
    if negate:

        def not_in_fn(env: Env) -> object:
            v = lf(env)
            try:
                return v not in fs
            except TypeError:
                return v not in tup

        return not_in_fn

    def in_fn(env: Env) -> object:
        v = lf(env)
        try:
            return v in fs
        except TypeError:
            return v in tup

    return in_fn


_CONSTRUCT_NAMES: Final[dict[type[ast.AST], str]] = {
    ast.Lambda: "lambda",
    ast.ListComp: "list comprehension",
    ast.SetComp: "set comprehension",
    ast.DictComp: "dict comprehension",
    ast.GeneratorExp: "generator expression",
    ast.Dict: "dict display",
    ast.Subscript: "subscript",
    ast.Slice: "slice",
    ast.NamedExpr: "walrus operator ':='",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield from",
    ast.JoinedStr: "f-string",
    ast.FormattedValue: "f-string",
    ast.Starred: "starred expression",
}


# --------------------------------------------------------------------------- compiler


class _Node:
    """A compiled sub-expression: its closure, its value when it is a constant, and
    (for a tuple/list/set display of constants) the constant members."""

    __slots__ = ("const", "fn", "key", "members", "value")

    def __init__(self, fn: Fn, const: bool = False, value: object = None) -> None:
        self.fn = fn
        self.const = const
        self.value = value
        self.members: tuple[object, ...] | None = None
        self.key: str | None = None  # set for a plain variable read (lets parents fuse the lookup)


def _constant(value: object) -> _Node:
    return _Node(lambda env: value, True, value)


def _folded(fn: Fn) -> _Node:
    """Evaluate a closure built only from constants once; keep it lazy if that fails."""
    try:
        value = fn({})
    except LimitError:
        raise  # reported at load time: the value would be too large whenever it is computed
    except (ArithmeticError, TypeError, ValueError):
        return _Node(fn)  # the error belongs to run time, where it is reported with context
    if _is_immutable(value):
        return _constant(value)
    return _Node(fn)


def _dotted(node: ast.expr) -> str | None:
    """'a.b.c' for a Name/Attribute chain, else None."""
    parts: list[str] = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    parts.append(node.id)
    return ".".join(reversed(parts))


class _Compiler:
    def __init__(self, src: _Source) -> None:
        self.src = src
        self.names: dict[str, int] = {}  # name -> offset of its first occurrence

    # -- errors

    def refuse(self, what: str, node: ast.AST, offset: int | None = None) -> ExprError:
        off = self.src.node(node) if offset is None else offset
        return ExprError(f"{what} is not allowed in a spec expression ({_ALLOWED})", self.src.original, off)

    # -- names

    def path(self, node: ast.expr) -> tuple[str, int]:
        """Check a Name/dotted-Attribute chain; return its dotted key and offset."""
        if isinstance(node, ast.Name):
            if node.id.startswith("_"):
                raise self.refuse(f"name {node.id!r} (names must not start with '_')", node)
            return node.id, self.src.node(node)
        assert isinstance(node, ast.Attribute)
        attr_off = max(self.src.node(node), self.src.node_end(node) - len(node.attr))
        if node.attr.startswith("_"):
            raise self.refuse(f"attribute {node.attr!r}", node, attr_off)
        if not isinstance(node.value, (ast.Name, ast.Attribute)):
            raise self.refuse(
                f"attribute {node.attr!r} of something that is not a (dotted) name", node, attr_off
            )
        base, off = self.path(node.value)
        return f"{base}.{node.attr}", off

    def read(self, node: ast.expr) -> _Node:
        key, off = self.path(node)
        self.names.setdefault(key, off)
        leaf = _Node(lambda env: env[key])
        leaf.key = key
        return leaf

    # -- dispatch

    def expr(self, node: ast.AST) -> _Node:
        if isinstance(node, ast.Constant):
            return self.constant(node)
        if isinstance(node, (ast.Name, ast.Attribute)):
            return self.read(node)
        if isinstance(node, ast.BoolOp):
            return self.boolop(node)
        if isinstance(node, ast.UnaryOp):
            return self.unaryop(node)
        if isinstance(node, ast.BinOp):
            return self.binop(node)
        if isinstance(node, ast.Compare):
            return self.compare(node)
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return self.display(node)
        if isinstance(node, ast.IfExp):
            return self.ifexp(node)
        if isinstance(node, ast.Call):
            return self.call(node)
        what = _CONSTRUCT_NAMES.get(type(node))
        if what is None:
            what = f"construct {type(node).__name__}"
        raise self.refuse(what, node)

    def constant(self, node: ast.Constant) -> _Node:
        v = node.value
        if v is None or type(v) in (bool, int, float, str):
            return _constant(v)
        if isinstance(v, bytes):
            what = "bytes literal"
        elif isinstance(v, complex):
            what = "complex literal"
        elif v is Ellipsis:
            what = "ellipsis '...'"
        else:
            what = f"constant of type {type(v).__name__}"
        raise self.refuse(what, node)

    def boolop(self, node: ast.BoolOp) -> _Node:
        is_and = isinstance(node.op, ast.And)
        parts = [self.expr(v) for v in node.values]
        # Trivial folding: constants that cannot decide the result are dropped; a
        # deciding constant ends the chain (the operands before it still run, so
        # a missing variable there is still reported).
        fns: list[Fn] = []
        final = is_and  # result when every kept operand "passes"
        for p in parts:
            if p.const:
                if bool(p.value) != is_and:  # False in `and`, True in `or`: decides
                    final = not is_and
                    break
                continue
            fns.append(p.fn)
        if not fns:
            return _constant(final)
        if is_and:
            if final:
                if len(fns) == 1:
                    (a,) = fns
                    return _Node(lambda env: True if a(env) else False)
                if len(fns) == 2:
                    a, b = fns
                    return _Node(lambda env: True if (a(env) and b(env)) else False)
                if len(fns) == 3:
                    a, b, c = fns
                    return _Node(lambda env: True if (a(env) and b(env) and c(env)) else False)
            fs = tuple(fns)

            def and_fn(env: Env) -> object:
                for f in fs:
                    if not f(env):
                        return False
                return final

            return _Node(and_fn)
        if not final:
            if len(fns) == 1:
                (a,) = fns
                return _Node(lambda env: True if a(env) else False)
            if len(fns) == 2:
                a, b = fns
                return _Node(lambda env: True if (a(env) or b(env)) else False)
            if len(fns) == 3:
                a, b, c = fns
                return _Node(lambda env: True if (a(env) or b(env) or c(env)) else False)
        fs = tuple(fns)

        def or_fn(env: Env) -> object:
            for f in fs:
                if f(env):
                    return True
            return final

        return _Node(or_fn)

    def unaryop(self, node: ast.UnaryOp) -> _Node:
        if isinstance(node.op, ast.Invert):
            raise self.refuse("operator '~'", node)
        operand = self.expr(node.operand)
        f = operand.fn
        fn: Fn
        k = operand.key
        if isinstance(node.op, ast.Not):
            if k is not None:
                fn = lambda env: not env[k]
            else:
                fn = lambda env: not f(env)
        elif isinstance(node.op, ast.USub):
            dyn: _DynFn = f
            fn = lambda env: -dyn(env)
        else:
            pos: _DynFn = f
            fn = lambda env: +pos(env)
        return _folded(fn) if operand.const else _Node(fn)

    def binop(self, node: ast.BinOp) -> _Node:
        op = type(node.op)
        if op in _REFUSED_BINOPS:
            raise self.refuse(f"operator {_REFUSED_BINOPS[op]!r}", node)
        if op not in _BINOPS:  # pragma: no cover - future operators
            raise self.refuse(f"operator {op.__name__}", node)
        left = self.expr(node.left)
        if op is ast.Mod and left.const and isinstance(left.value, str):
            raise self.refuse("string formatting with '%'", node)
        right = self.expr(node.right)
        _, _, (ff, fc, cf) = _BINOPS[op]
        if left.const and right.const:
            return _folded(ff(left.fn, right.fn))
        if right.const:
            return _Node(fc(left.fn, right.value))
        if left.const:
            return _Node(cf(left.value, right.fn))
        return _Node(ff(left.fn, right.fn))

    def compare(self, node: ast.Compare) -> _Node:
        for op, comp in zip(node.ops, node.comparators):
            if type(op) in _REFUSED_CMPOPS:
                raise self.refuse(f"comparison {_REFUSED_CMPOPS[type(op)]!r}", comp)
        left = self.expr(node.left)
        if len(node.ops) == 1:
            op_t = type(node.ops[0])
            comp_node = node.comparators[0]
            right = self.expr(comp_node)
            if op_t in (ast.In, ast.NotIn) and right.members is not None and not left.const:
                tup = right.members
                try:
                    fs = frozenset(tup)
                except TypeError:  # an unhashable constant member: plain tuple scan
                    fs = None
                if fs is not None:
                    return _Node(_member_fn(left.fn, fs, tup, op_t is ast.NotIn))
            _, (ff, fc, cf) = _CMPOPS[op_t]
            if left.const and right.const:
                return _folded(ff(left.fn, right.fn))
            if right.const:
                if left.key is not None:
                    return _Node(_CMP_NAME_CONST[op_t](left.key, right.value))
                return _Node(fc(left.fn, right.value))
            if left.const:
                return _Node(cf(left.value, right.fn))
            return _Node(ff(left.fn, right.fn))
        steps = tuple((_CMPOPS[type(op)][0], self.expr(c).fn) for op, c in zip(node.ops, node.comparators))
        first = left.fn

        def chain_fn(env: Env) -> object:
            a = first(env)
            for test, g in steps:
                b = g(env)
                if not test(a, b):
                    return False
                a = b
            return True

        return _Node(chain_fn)

    def display(self, node: ast.Tuple | ast.List | ast.Set) -> _Node:
        elts = [self.expr(e) for e in node.elts]
        members = tuple(e.value for e in elts) if all(e.const for e in elts) else None
        fs = tuple(e.fn for e in elts)
        result: _Node
        if isinstance(node, ast.List):
            # Lists are mutable: build a fresh one on every evaluation.
            result = _Node(lambda env: [f(env) for f in fs])
        elif members is not None:
            values = members
            if isinstance(node, ast.Tuple):
                result = _constant(values)
            else:
                result = _folded(lambda env: frozenset(values))
        elif isinstance(node, ast.Tuple):
            result = _Node(lambda env: tuple([f(env) for f in fs]))
        else:
            result = _Node(lambda env: frozenset([f(env) for f in fs]))
        result.members = members
        return result

    def ifexp(self, node: ast.IfExp) -> _Node:
        test = self.expr(node.test)
        body = self.expr(node.body)
        orelse = self.expr(node.orelse)
        if test.const:
            return body if test.value else orelse
        t, b, o = test.fn, body.fn, orelse.fn
        return _Node(lambda env: b(env) if t(env) else o(env))

    def call(self, node: ast.Call) -> _Node:
        func = node.func
        fname = _dotted(func)
        if fname is None:
            shown = ast.unparse(func)
            if len(shown) > 40:
                shown = shown[:37] + "..."
            raise self.refuse(f"function call {shown!r}", node)
        if fname not in _FUNCTIONS:
            raise self.refuse(f"function call {fname!r}", node)
        for kw in node.keywords:
            if kw.arg is None:
                raise self.refuse(f"keyword argument unpacking '**' in a call of {fname}", kw)
            raise self.refuse(f"keyword argument {kw.arg!r} to {fname}", kw)
        for a in node.args:
            if isinstance(a, ast.Starred):
                raise self.refuse("starred expression", a)
        n = len(node.args)
        if fname == "abs" and n != 1:
            raise ExprError(f"abs() takes exactly one argument ({n} given)", self.src.original, self.src.node(node))
        if n == 0:
            raise ExprError(f"{fname}() needs at least one argument", self.src.original, self.src.node(node))
        args = [self.expr(a) for a in node.args]
        f = _FUNCTIONS[fname]
        fn: Fn
        if n == 1:
            a0 = args[0].fn
            fn = lambda env: f(a0(env))
        elif n == 2:
            a0, a1 = args[0].fn, args[1].fn
            fn = lambda env: f(a0(env), a1(env))
        else:
            fs = tuple(a.fn for a in args)
            fn = lambda env: f(*[g(env) for g in fs])
        if all(a.const for a in args):
            return _folded(fn)
        return _Node(fn)


# --------------------------------------------------------------------------- entry points

_AUG_OPS: Final[dict[type[ast.operator], str]] = {ast.Add: "+", ast.Sub: "-"}


def _build_expression(text: str) -> tuple[Expr, dict[str, int]]:
    tree, src = _parse(text, "eval", "expression")
    assert isinstance(tree, ast.Expression)
    comp = _Compiler(src)
    try:
        node = comp.expr(tree.body)
    except LimitError as exc:
        raise ExprError(f"{exc} in expression {text!r}", text, 0) from None
    return Expr(text, frozenset(comp.names), node.fn), comp.names


def _build_assignment(text: str) -> tuple[Assignment, dict[str, int], int]:
    tree, src = _parse(text, "exec", "assignment")
    assert isinstance(tree, ast.Module)
    if len(tree.body) != 1:
        second = tree.body[1] if len(tree.body) > 1 else tree
        raise ExprError(
            "an action must be exactly one assignment 'target = expr'", text, src.node(second)
        )
    stmt = tree.body[0]
    comp = _Compiler(src)

    def check_target(t: ast.expr) -> tuple[str, int]:
        if not isinstance(t, (ast.Name, ast.Attribute)):
            raise ExprError(
                f"assignment target must be a name or dotted name, not {ast.unparse(t)[:40]!r}",
                text,
                src.node(t),
            )
        return comp.path(t)

    if isinstance(stmt, ast.Assign):
        if len(stmt.targets) != 1:
            raise ExprError("chained assignment 'a = b = ...' is not allowed", text, src.node(stmt.targets[1]))
        target, target_off = check_target(stmt.targets[0])
        value_node: ast.expr = stmt.value
        value_text = ast.get_source_segment(src.body, stmt.value) or ast.unparse(stmt.value)
    elif isinstance(stmt, ast.AugAssign):
        op = type(stmt.op)
        if op not in _AUG_OPS:
            sym = _BINOPS[op][0] if op in _BINOPS else _REFUSED_BINOPS.get(op, op.__name__)
            raise comp.refuse(f"augmented assignment '{sym}=' (only '+=' and '-=')", stmt)
        target, target_off = check_target(stmt.target)
        rhs = ast.get_source_segment(src.body, stmt.value) or ast.unparse(stmt.value)
        value_text = f"{target} {_AUG_OPS[op]} ({rhs})"
        load_target = _load_copy(stmt.target)
        value_node = ast.BinOp(left=load_target, op=stmt.op, right=stmt.value)
        ast.copy_location(value_node, stmt)
    elif isinstance(stmt, ast.AnnAssign):
        raise comp.refuse("annotated assignment", stmt)
    elif isinstance(stmt, ast.Expr):
        raise ExprError(
            "an action must be an assignment 'target = expr', not a bare expression", text, src.node(stmt)
        )
    else:
        kind = type(stmt).__name__.lower()
        raise comp.refuse(f"{kind} statement", stmt)
    try:
        node = comp.expr(value_node)
    except LimitError as exc:
        raise ExprError(f"{exc} in action {text!r}", text, 0) from None
    value = Expr(value_text, frozenset(comp.names), node.fn)
    return Assignment(text, target, value), comp.names, target_off


def _load_copy(t: ast.expr) -> ast.expr:
    """A Load-context copy of a Name/Attribute chain (positions preserved)."""
    if isinstance(t, ast.Name):
        new: ast.expr = ast.Name(id=t.id, ctx=ast.Load())
    else:
        assert isinstance(t, ast.Attribute)
        new = ast.Attribute(value=_load_copy(t.value), attr=t.attr, ctx=ast.Load())
    return ast.copy_location(new, t)


def parse_expression(text: str) -> Expr:
    """Parse and check a guard/check expression; raise ExprError if not allowed."""
    if not isinstance(text, str):
        return _build_expression(text)[0]
    return _parse_expression_cached(text)


def parse_assignment(text: str) -> Assignment:
    """Parse ``target = expr`` (or ``+=`` / ``-=``); raise ExprError if not allowed."""
    if not isinstance(text, str):
        return _build_assignment(text)[0]
    return _parse_assignment_cached(text)


# Expressions are immutable and their closures hold no state, so one parse per text serves
# every load (an error is not cached: it is raised again from a fresh parse).
@functools.lru_cache(maxsize=8192)
def _parse_expression_cached(text: str) -> Expr:
    return _build_expression(text)[0]


@functools.lru_cache(maxsize=8192)
def _parse_assignment_cached(text: str) -> Assignment:
    return _build_assignment(text)[0]


@functools.lru_cache(maxsize=4096)
def _name_offsets(text: str, kind: str) -> tuple[tuple[str, int], ...]:
    if kind == "expr":
        _, names = _build_expression(text)
        return tuple(names.items())
    assignment, names, target_off = _build_assignment(text)
    out = dict(names)
    if assignment.target not in out or out[assignment.target] > target_off:
        out[assignment.target] = target_off
    return tuple(out.items())


def check_names(expr: Expr | Assignment, known: Collection[str]) -> list[tuple[str, int]]:
    """Names read (and, for an Assignment, written) that are not in ``known``.

    Each unknown name is listed once, with the 0-based character offset of its
    first occurrence in ``expr.text``; the list is ordered by offset.  (Offsets
    come from re-parsing ``expr.text``, which is cached; an ``Expr`` built by hand
    from text that does not parse reports its ``names`` at offset 0.)
    """
    kind = "assign" if isinstance(expr, Assignment) else "expr"
    try:
        pairs = _name_offsets(expr.text, kind)
    except ExprError:  # built by hand from text that does not parse: no positions known
        if isinstance(expr, Assignment):
            pairs = ((expr.target, 0), *((n, 0) for n in sorted(expr.value.names)))
        else:
            pairs = tuple((n, 0) for n in sorted(expr.names))
    return sorted(((n, off) for n, off in pairs if n not in known), key=lambda p: (p[1], p[0]))


# --------------------------------------------------------------------------- result kinds

#: The kinds :func:`result_kinds` speaks of.
KINDS: Final = frozenset({"bool", "int", "real", "str", "none"})


def result_kinds(expr: Expr, kinds: Mapping[str, frozenset[str]]) -> tuple[frozenset[str], tuple[object, ...]]:
    """What ``expr`` can evaluate to, without running it: (kinds, constants).

    ``kinds`` maps each variable to the kinds it may hold (absent: any kind).  The
    result is a subset of :data:`KINDS`, or all of them when it cannot be told; the
    constants are the literal values among the possible results (the branches of
    ``a if c else b`` that are literals), for domain checks.
    """
    try:
        tree = ast.parse(expr.text.lstrip(_LEADING_WS), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return KINDS, ()
    consts: list[object] = []
    found = _kinds(tree.body, kinds, consts, 0)
    return found, tuple(consts)


def _kinds(node: ast.AST, kinds: Mapping[str, frozenset[str]], consts: list[object], depth: int) -> frozenset[str]:
    if depth > MAX_DEPTH:
        return KINDS
    if isinstance(node, ast.Constant):
        v = node.value
        consts.append(v)
        if isinstance(v, bool):
            return frozenset({"bool"})
        if isinstance(v, int):
            return frozenset({"int"})
        if isinstance(v, float):
            return frozenset({"real"})
        if isinstance(v, str):
            return frozenset({"str"})
        if v is None:
            return frozenset({"none"})
        return KINDS
    if isinstance(node, (ast.Compare, ast.BoolOp)) or (isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not)):
        return frozenset({"bool"})
    if isinstance(node, (ast.Name, ast.Attribute)):
        name = _dotted(node)
        return kinds.get(name, KINDS) if name is not None else KINDS
    if isinstance(node, ast.IfExp):
        return _kinds(node.body, kinds, consts, depth + 1) | _kinds(node.orelse, kinds, consts, depth + 1)
    ignored: list[object] = []
    if isinstance(node, ast.UnaryOp):
        inner = _kinds(node.operand, kinds, ignored, depth + 1)
        return _numeric(inner)
    if isinstance(node, ast.BinOp):
        left = _kinds(node.left, kinds, ignored, depth + 1)
        right = _kinds(node.right, kinds, ignored, depth + 1)
        if isinstance(node.op, ast.Div):
            return frozenset({"real"})
        if isinstance(node.op, (ast.Add, ast.Mult)) and ("str" in left or "str" in right):
            return KINDS
        return _numeric(left | right)
    if isinstance(node, ast.Call) and _dotted(node.func) in _FUNCTIONS:
        out: frozenset[str] = frozenset()
        for a in node.args:
            out |= _kinds(a, kinds, ignored, depth + 1)
        return out or KINDS
    return KINDS


def _numeric(kinds: frozenset[str]) -> frozenset[str]:
    """Arithmetic on these kinds gives a number: real if a real may be involved."""
    if not kinds <= {"bool", "int", "real"}:
        return KINDS
    return frozenset({"real"}) if "real" in kinds else frozenset({"int", "real"} & ({"int"} | kinds))
