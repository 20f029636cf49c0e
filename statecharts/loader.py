"""Load a motionchart specification: YAML -> JSON Schema -> semantic checks -> frozen IR.

Pipeline position: first stage.  :func:`load_spec` reads every ``*.yaml`` file of the
spec (the bundled one by default; files of another motionchart format, such as the
model checker's ``motionchart-properties/1``, are left to their own loaders), checks the shape of each YAML tree (no mapping keys
other than strings, no runaway nesting or alias expansion), validates it against the
shipped JSON Schema, resolves references across files, parses every guard, check and
action with the expression language, runs the semantic checks (unknown targets and
variables, duplicate ids, unreachable states, overlapping guards without a priority,
unknown interpretations and error codes), and returns a :class:`~statecharts.ir.Spec`.

Each node kind of the spec language has its accepted keys in one module constant
(``CHART_KEYS``, ``STATE_KEYS``... collected in :data:`NODE_KEYS`).  The builder reads
YAML mappings only through :class:`Node`, which refuses a key its kind does not
declare, and ``tests/test_schema_agreement.py`` asserts that each constant equals the
properties of the same node in ``spec/schema/spec.schema.json`` -- so the schema and
the loader cannot drift apart.

All problems of all files are collected and raised together as one
:class:`~statecharts.diagnostics.SpecError`; nothing downstream ever sees YAML.  A file
that fails to parse or to match the schema is left out of the semantic checks, and so
are the cross-file checks that would only repeat its failure (unused interpretations,
unknown charts...).
"""

from __future__ import annotations

import copy
import functools
import itertools
import json
import math
import os
import re
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
from ruamel.yaml import YAML
from ruamel.yaml.anchor import Anchor
from ruamel.yaml.comments import CommentedMap, CommentedSeq, Format, LineCol
from ruamel.yaml.error import MarkedYAMLError
from ruamel.yaml.events import CollectionEndEvent, CollectionStartEvent
from ruamel.yaml.tag import Tag

from statecharts import addon_loader, drive, ir, sources
from statecharts.cycles import eventless_cycles
from statecharts.diagnostics import Diagnostic, SpecError, locate, node_path
from statecharts.expr import (
    KINDS,
    Assignment,
    Expr,
    ExprError,
    check_names,
    parse_assignment,
    parse_expression,
    result_kinds,
)
from statecharts.inputs import MAX_INPUT_BYTES, read_input, shown_name

SPEC_FORMAT = "motionchart-spec/1"
MAX_FILE_BYTES = MAX_INPUT_BYTES
#: Deepest nesting of YAML mappings and sequences accepted (the spec needs about 12).
MAX_YAML_DEPTH = 64
#: Most YAML nodes a file may expand to, counting each use of an alias (``*name``).
MAX_YAML_NODES = 200_000

#: Names every axis-chart expression may read besides the chart's own variables.
SYSTEM_PARAMETERS: dict[str, tuple[int, ...]] = {"coarse_update_ms": (10,), "scan_ms": (10,)}
#: Axis attributes that instructions may read but never assign.
AXIS_READ_ONLY = ("active", "state", "chart")
#: Largest number of variable assignments enumerated to show two guards disjoint.
OVERLAP_ENUMERATION_LIMIT = 20_000

# --------------------------------------------------------------------------- the keys of each node kind
# One constant per node kind of the spec language: the keys the loader accepts and
# reads.  tests/test_schema_agreement.py compares each with the JSON Schema.

_PROVENANCE = frozenset({"source", "interpretation"})
FILE_KEYS = frozenset(
    {"format", "chart", "instruction", "add_on_instruction", "tag_type", "execution_tables", "interpretations", "errors",
     "extended_errors"}
)
CHART_KEYS = frozenset(
    {"id", "name", "kind", "state_attribute", "axis_types", "description", "variables", "events", "states",
     "initial", "transitions", "drive_model", "parameters"}
) | _PROVENANCE
CHART_PARAMETER_KEYS = frozenset({"name", "type", "default", "description"}) | _PROVENANCE
STATE_KEYS = frozenset(
    {"id", "name", "kind", "value", "initial", "history", "description", "entry", "exit", "states", "implies"}
) | _PROVENANCE
TRANSITION_KEYS = frozenset({"id", "from", "to", "event", "guard", "actions", "priority"}) | _PROVENANCE
VARIABLE_KEYS = frozenset({"name", "type", "domain", "range", "initial", "description", "writable", "values"}) | _PROVENANCE
VALUE_KEYS = frozenset({"value", "meaning", "confidence"}) | _PROVENANCE
EVENT_KEYS = frozenset({"name", "kind", "description", "actions", "parameters"}) | _PROVENANCE
INSTRUCTION_KEYS = frozenset(
    {"id", "mnemonic", "name", "charts", "axis_types", "description", "operands", "execution", "execution_table", "checks",
     "aborts", "request", "done", "status_bits", "process"}
) | _PROVENANCE
OPERAND_KEYS = frozenset(
    {"name", "type", "domain", "range", "text_values", "default", "description", "role"}
) | _PROVENANCE
CHECK_KEYS = frozenset({"id", "fails_when", "err", "exerr", "stage", "description"}) | _PROVENANCE
ABORT_KEYS = frozenset({"id", "when", "err", "exerr", "description"}) | _PROVENANCE
REQUEST_KEYS = frozenset({"event", "actions"})
DONE_KEYS = frozenset({"when"}) | _PROVENANCE
PROCESS_KEYS = frozenset({"kind", "complete_when", "ends_when"}) | _PROVENANCE
EXECUTION_TABLE_KEYS = frozenset(
    {"id", "rows", "on_execute", "on_error", "on_accept", "on_done", "on_complete", "on_end"}
) | _PROVENANCE
TABLE_ROW_KEYS = frozenset({"condition", "guard", "actions", "execute", "description"}) | _PROVENANCE
TABLE_BLOCK_KEYS = frozenset({"actions"}) | _PROVENANCE
TAG_TYPE_KEYS = frozenset({"name", "members", "internal", "wrong_axis_family", "source"})
WRONG_AXIS_FAMILY_KEYS = frozenset({"err", "exerr", "description"}) | _PROVENANCE
TAG_MEMBER_KEYS = frozenset({"name", "type", "bit", "description", "source"})
INTERPRETATION_KEYS = frozenset({"id", "title", "confidence", "text", "evidence"})
ERROR_KEYS = frozenset({"code", "name", "meaning", "confidence"}) | _PROVENANCE
EXTENDED_ERROR_KEYS = frozenset(
    {"instruction", "err", "exerr", "name", "meaning", "confidence"}
) | _PROVENANCE
# the add-on instruction (statecharts/addon_loader.py builds it)
ADD_ON_INSTRUCTION_KEYS = frozenset(
    {"id", "name", "description", "execution", "parameters", "status", "local_tags", "errors", "checks", "recovery",
     "on_done", "rung_false", "prescan", "world"}
) | _PROVENANCE
EXECUTION_KEYS = frozenset({"mode"}) | _PROVENANCE
ADDON_PARAMETER_KEYS = frozenset({"name", "usage", "type", "data_type", "alias", "default", "description", "values"}) | _PROVENANCE
STATUS_MEMBER_KEYS = frozenset({"name", "type", "description"}) | _PROVENANCE
ADDON_ERROR_KEYS = frozenset({"code", "name", "description"}) | _PROVENANCE
RECOVERY_KEYS = frozenset({"initial", "states", "transitions", "description"}) | _PROVENANCE
RECOVERY_STATE_KEYS = frozenset({"id", "description", "call", "error"}) | _PROVENANCE
RECOVERY_CALL_KEYS = frozenset({"instruction", "axis", "master", "operands"})
RECOVERY_TRANSITION_KEYS = frozenset({"from", "to", "when"}) | _PROVENANCE
ON_DONE_KEYS = frozenset({"when", "set"}) | _PROVENANCE
SCAN_RULE_KEYS = frozenset({"clear", "abort_call", "forget"}) | _PROVENANCE
WORLD_KEYS = frozenset({"objects"}) | _PROVENANCE
WORLD_OBJECT_KEYS = frozenset({"kind", "chart", "register", "facts"}) | _PROVENANCE
FACT_KEYS = frozenset({"name", "when", "variable", "set"}) | _PROVENANCE
FACT_SET_KEYS = frozenset({"value", "fire"})

#: Every node kind and its keys (``tag_type.internal`` items are variables).
NODE_KEYS: dict[str, frozenset[str]] = {
    "file": FILE_KEYS,
    "chart": CHART_KEYS,
    "state": STATE_KEYS,
    "transition": TRANSITION_KEYS,
    "variable": VARIABLE_KEYS,
    "value": VALUE_KEYS,
    "event": EVENT_KEYS,
    "instruction": INSTRUCTION_KEYS,
    "operand": OPERAND_KEYS,
    "check": CHECK_KEYS,
    "abort": ABORT_KEYS,
    "request": REQUEST_KEYS,
    "done": DONE_KEYS,
    "process": PROCESS_KEYS,
    "execution_table": EXECUTION_TABLE_KEYS,
    "table_row": TABLE_ROW_KEYS,
    "table_block": TABLE_BLOCK_KEYS,
    "tag_type": TAG_TYPE_KEYS,
    "wrong_axis_family": WRONG_AXIS_FAMILY_KEYS,
    "tag_member": TAG_MEMBER_KEYS,
    "interpretation": INTERPRETATION_KEYS,
    "error": ERROR_KEYS,
    "extended_error": EXTENDED_ERROR_KEYS,
    "chart_parameter": CHART_PARAMETER_KEYS,
    "add_on_instruction": ADD_ON_INSTRUCTION_KEYS,
    "execution": EXECUTION_KEYS,
    "addon_parameter": ADDON_PARAMETER_KEYS,
    "status_member": STATUS_MEMBER_KEYS,
    "addon_error": ADDON_ERROR_KEYS,
    "recovery": RECOVERY_KEYS,
    "recovery_state": RECOVERY_STATE_KEYS,
    "recovery_call": RECOVERY_CALL_KEYS,
    "recovery_transition": RECOVERY_TRANSITION_KEYS,
    "on_done": ON_DONE_KEYS,
    "scan_rule": SCAN_RULE_KEYS,
    "world": WORLD_KEYS,
    "world_object": WORLD_OBJECT_KEYS,
    "fact": FACT_KEYS,
    "fact_set": FACT_SET_KEYS,
}


class Node:
    """Read access to one schema-checked YAML mapping, limited to the keys of its kind.

    Reading a key that the kind's constant does not declare is a bug in the loader
    (the schema would have let such a key through unchecked), so it fails loudly.
    """

    __slots__ = ("keys", "kind", "raw")

    def __init__(self, raw: Any, kind: str) -> None:
        self.kind = kind
        self.keys = NODE_KEYS[kind]
        self.raw = raw

    def _declared(self, key: str) -> None:
        if key not in self.keys:
            raise AssertionError(f"the loader reads {key!r} of a {self.kind}, which NODE_KEYS[{self.kind!r}] does not declare")

    def declares(self, key: str) -> bool:
        return key in self.keys

    def __getitem__(self, key: str) -> Any:
        self._declared(key)
        return self.raw[key]

    def get(self, key: str, default: Any = None) -> Any:
        self._declared(key)
        return self.raw.get(key, default)

    def __contains__(self, key: str) -> bool:
        self._declared(key)
        return key in self.raw

    def items(self, key: str, kind: str) -> list[Node]:
        """The mappings of the list under ``key``, each read as a ``kind`` node."""
        return [Node(x, kind) for x in self.get(key) or ()]

    def child(self, key: str, kind: str) -> Node:
        return Node(self[key], kind)


def bundled_spec_dir() -> Path:
    """The spec shipped with the package (``spec/`` in a checkout, package data in a wheel)."""
    return Path(str(resources.files("motionchart_spec")))


@functools.lru_cache(maxsize=1)
def spec_schema() -> dict[str, Any]:
    """The spec's JSON Schema (read once; treat it as read-only)."""
    text = (bundled_spec_dir() / "schema" / "spec.schema.json").read_text(encoding="utf-8")
    schema: dict[str, Any] = json.loads(text)
    return schema


def spec_files(paths: Sequence[Path | str] | None = None) -> list[Path]:
    """Expand files and directories into the sorted list of spec YAML files."""
    roots = [Path(p) for p in paths] if paths else [bundled_spec_dir()]
    files: list[Path] = []
    for root in roots:
        if root.is_dir():
            files.extend(sorted(p for p in root.rglob("*.yaml") if p.is_file()))
            files.extend(sorted(p for p in root.rglob("*.yml") if p.is_file()))
        else:
            files.append(root)
    return files


# --------------------------------------------------------------------------- YAML


def plain_data(node: Any) -> Any:
    """ruamel round-trip tree -> plain dicts/lists (for the JSON Schema validator).

    Only called on trees that passed :func:`tree_diagnostics` (bounded depth and size).
    """
    if isinstance(node, dict):
        return {str(k): plain_data(v) for k, v in node.items()}
    if isinstance(node, list):
        return [plain_data(v) for v in node]
    if isinstance(node, str):
        return str(node)
    if isinstance(node, bool):
        return bool(node)
    if isinstance(node, int):
        return int(node)
    if isinstance(node, float):
        return float(node)
    return node


def _key_text(key: Any) -> str:
    text = repr(key)
    return text if len(text) <= 40 else text[:37] + "..."


def tree_diagnostics(name: str, tree: Any, *, what: str = "file") -> tuple[list[Diagnostic], bool]:
    """Shape problems of a parsed YAML tree: (diagnostics, fatal?).

    Mapping keys must be strings (``1:``, ``true:``, ``null:`` or ``? [a, b]`` keys would
    silently turn into text for the schema and into surprises after it).  Nesting deeper
    than :data:`MAX_YAML_DEPTH` and trees that expand to more than :data:`MAX_YAML_NODES`
    nodes through aliases (the "billion laughs") are fatal: nothing else is checked.
    The walk is iterative, so no input can exhaust the recursion limit here.
    """
    out: list[Diagnostic] = []
    count = 0
    stack: list[tuple[Any, tuple[Any, ...]]] = [(tree, ())]
    while stack:
        node, parts = stack.pop()
        count += 1
        if count > MAX_YAML_NODES:
            return [Diagnostic(name, 1, 1, "", (
                f"{what} expands to more than {MAX_YAML_NODES} YAML nodes (aliases `*name` used too often?)"))], True
        if len(parts) > MAX_YAML_DEPTH:
            line, col = locate(tree, parts)
            return [Diagnostic(name, line, col, node_path(parts[:MAX_YAML_DEPTH]), (
                f"nesting deeper than {MAX_YAML_DEPTH} levels"))], True
        if isinstance(node, dict):
            for k, v in node.items():
                if not isinstance(k, str):
                    lc = getattr(node, "lc", None)
                    line, col = locate(tree, parts)
                    try:
                        if lc is not None:
                            kline, kcol = lc.key(k)
                            line, col = kline + 1, kcol + 1
                    except (KeyError, TypeError, AttributeError):
                        pass
                    out.append(Diagnostic(name, line, col, node_path(parts) or "(document)", (
                        f"mapping key {_key_text(k)} is not a string; write the key in quotes")))
                    continue
                stack.append((v, (*parts, k)))
        elif isinstance(node, list):
            stack.extend((v, (*parts, i)) for i, v in enumerate(node))
    return out, False


def read_yaml(path: Path, errors: list[Diagnostic], *, what: str = "file") -> Any | None:
    """Parse one YAML file; every problem becomes a located diagnostic, never a traceback.

    Returns the ruamel round-trip tree, or ``None`` when there is nothing to check
    further (unreadable, not UTF-8, not YAML, empty, or a fatal shape problem).  A
    tree can be returned together with new diagnostics (e.g. a non-string key): the
    caller must not build from a file that added diagnostics.
    """
    name = shown_name(path)
    raw = read_input(path, errors, what=what, limit=MAX_FILE_BYTES)
    if raw is None:
        return None
    # the project's own files' trees are kept; any file with the same bytes (a copy of
    # one) is read from that entry
    remembered = _remembered_tree(name, raw)
    if remembered is not None:  # read in this process already: neither parsed nor stored again
        return remembered
    cacheable = _project_file(path)
    from statecharts import tree_cache

    cached = tree_cache.load(raw)
    if cached is not None:
        _remember_tree(name, raw, cached)
        return cached
    before = len(errors)
    tree = parse_yaml_bytes(name, raw, errors, what=what)
    if cacheable and tree is not None and len(errors) == before:
        tree_cache.store(raw, tree)
    return tree


@functools.lru_cache(maxsize=1)
def _project_dirs() -> tuple[Path, ...]:
    """The folders of the project's own YAML files: the bundled spec, the bundled
    conformance systems and, in a checkout, the scenarios."""
    spec = bundled_spec_dir().resolve()
    out = [spec, (Path(__file__).resolve().parent.parent / "conformance" / "systems")]
    scenarios = spec.parent / "scenarios"
    if scenarios.is_dir():
        out.append(scenarios)
    return tuple(out)


def _project_file(path: Path) -> bool:
    """Whether ``path`` is one of the project's own files (whose parsed trees are cached on disk)."""
    try:
        parents = Path(path).resolve().parents
        return any(d in parents for d in _project_dirs())
    except (OSError, ModuleNotFoundError):  # pragma: no cover - package data missing
        return False


def parse_yaml_bytes(name: str, raw: bytes, errors: list[Diagnostic], *, what: str = "file") -> Any | None:
    """:func:`read_yaml` on bytes already read (``name`` is the file shown in diagnostics)."""
    seen = _remembered_tree(name, raw)
    if seen is not None:
        return seen
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        errors.append(Diagnostic(name, line, col, "", (
            f"{what} is not UTF-8 text ({exc.reason} at byte {exc.start}); save it as UTF-8")))
        return None
    deep = _flow_nesting(text)
    if deep is not None:
        errors.append(Diagnostic(name, deep[0], deep[1], "", f"nesting deeper than {MAX_YAML_DEPTH} levels"))
        return None
    yaml = YAML(typ="rt")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # e.g. ReusedAnchorWarning: not ours to print
            tree = yaml.load(text)
    except MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
        problem = exc.problem or exc.context or "invalid YAML"
        errors.append(Diagnostic(name, line, col, "", f"YAML syntax error: {problem}"))
        return None
    except RecursionError:
        line, col = _deep_event(text)
        errors.append(Diagnostic(name, line, col, "", f"nesting deeper than {MAX_YAML_DEPTH} levels"))
        return None
    except Exception as exc:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        line, col = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
        errors.append(Diagnostic(name, line, col, "", f"YAML error: {exc}".splitlines()[0]))
        return None
    problems, fatal = tree_diagnostics(name, tree, what=what)
    errors.extend(problems)
    if not problems:
        _remember_tree(name, raw, tree)
    return None if fatal else tree


#: Trees of files read cleanly, by file name and content: the spec, the scenarios and the
#: checker's files are read again and again in one process (tests, generation), and
#: parsing with positions is the slow part of loading.  Callers get their own copy.
_TREES: dict[tuple[str, bytes], Any] = {}
_TREES_MAX_BYTES = 16_000_000
_trees_bytes = 0


def forget_trees() -> None:
    """Empty the in-process memos of parsed trees, of documents found valid and of built
    specs (the next load parses, checks and builds, or reads the disk cache)."""
    global _trees_bytes
    _TREES.clear()
    _VALID_DOCUMENTS.clear()
    _SPECS.clear()
    _trees_bytes = 0


def _remember_tree(name: str, raw: bytes, tree: Any) -> None:
    global _trees_bytes
    if _trees_bytes + len(raw) > _TREES_MAX_BYTES:
        _TREES.clear()
        _trees_bytes = 0
    _TREES[(name, raw)] = _copy_tree(tree)
    _trees_bytes += len(raw)


def _remembered_tree(name: str, raw: bytes) -> Any | None:
    tree = _TREES.get((name, raw))
    return None if tree is None else _copy_tree(tree)


def _copy_tree(node: Any) -> Any:
    """A copy of a round-trip tree: new mappings and sequences with the same positions
    (``lc``), tags and anchors; scalars are shared (immutable), comments are left out."""
    if isinstance(node, CommentedMap):
        m = CommentedMap()
        for k, v in node.items():
            m[k] = _copy_tree(v)
        _share_attributes(node, m)
        return m
    if isinstance(node, CommentedSeq):
        s = CommentedSeq(_copy_tree(v) for v in node)
        _share_attributes(node, s)
        return s
    if isinstance(node, dict | list):
        return copy.deepcopy(node)
    return node


def _share_attributes(old: Any, new: Any) -> None:
    for attrib in (LineCol.attrib, Format.attrib, Anchor.attrib, Tag.attrib):
        if hasattr(old, attrib):
            setattr(new, attrib, getattr(old, attrib))


def read_document(path: Path, errors: list[Diagnostic], *, what: str = "file") -> Any | None:
    """Read one input document: JSON when the name ends in ``.json``, else YAML.

    The one reader of user files: :func:`~statecharts.inputs.read_input` (regular files
    only, bounded size), then the parser, then :func:`tree_diagnostics`.  A JSON
    document is parsed with the json module (exact error positions) and, when it is
    also valid YAML with the same content, returned as the YAML tree so that later
    diagnostics carry line numbers.  Returns ``None`` when nothing can be checked further.
    """
    if Path(path).suffix != ".json":
        return read_yaml(Path(path), errors, what=what)
    name = shown_name(path)
    raw = read_input(path, errors, what=what, limit=MAX_FILE_BYTES)
    if raw is None:
        return None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        errors.append(Diagnostic(name, 1, 1, "", f"{what} is not UTF-8 text ({exc.reason} at byte {exc.start})"))
        return None
    try:
        tree = json.loads(text, parse_constant=_json_constant)
    except json.JSONDecodeError as exc:
        errors.append(Diagnostic(name, exc.lineno, exc.colno, "", f"JSON syntax error: {exc.msg}"))
        return None
    except ValueError as exc:  # NaN / Infinity, or an integer too long to convert
        errors.append(Diagnostic(name, 1, 1, "", f"JSON error: {exc}"))
        return None
    except RecursionError:
        errors.append(Diagnostic(name, 1, 1, "", "JSON nesting too deep to parse"))
        return None
    problems, fatal = tree_diagnostics(name, tree, what=what)
    if problems:
        errors.extend(problems)
        return None if fatal else tree
    positioned = parse_yaml_bytes(name, raw, [], what=what)
    try:
        same = positioned is not None and plain_data(positioned) == tree
    except RecursionError:
        same = False
    return positioned if same else tree


def _json_constant(text: str) -> Any:
    raise ValueError(f"{text} is not a number a motionchart file may hold")


_FLOW_TOKENS = re.compile(r"[\[\]{}#'\"\n]")


def _quoted_end(text: str, start: int, quote: str) -> int:
    """Index of the quote that closes the string opened at ``start`` (or the text's end)."""
    i = start + 1
    while True:
        j = text.find(quote, i)
        if j < 0:
            return len(text)
        if quote == "'":
            if text.startswith("''", j):  # '' is a quote inside a single-quoted string
                i = j + 2
                continue
            return j
        backslashes = 0
        k = j - 1
        while k > start and text[k] == "\\":
            backslashes += 1
            k -= 1
        if backslashes % 2:
            i = j + 1
            continue
        return j


def _flow_nesting(text: str) -> tuple[int, int] | None:
    """(line, column) where ``[ ]``/``{ }`` nest deeper than MAX_YAML_DEPTH, or None.

    ruamel's scanner takes time quadratic in the depth of flow collections (seconds
    for a few thousand ``[``) and its composer recurses, so such text is refused
    before parsing.  The count is a cheap approximation (quoted strings and comments
    are skipped; a ``[`` inside a plain or block scalar counts), so only text with
    dozens of unclosed brackets in a scalar could be refused wrongly.
    """
    if text.count("[") + text.count("{") <= MAX_YAML_DEPTH:
        return None
    depth, line, line_start, i = 0, 1, 0, 0
    while (m := _FLOW_TOKENS.search(text, i)) is not None:
        ch, at = m.group(), m.start()
        i = at + 1
        if ch == "\n":
            line, line_start = line + 1, i
            continue
        before = text[at - 1] if at else "\n"
        if ch == "#":
            if before in " \t\n":
                nl = text.find("\n", at)
                if nl < 0:
                    break
                i = nl  # the comment's newline is the next token
        elif ch in "'\"":
            if before in " \t\n[{,:":
                end = _quoted_end(text, at, ch)
                newlines = text.count("\n", at, end)
                if newlines:
                    line, line_start = line + newlines, text.rfind("\n", at, end) + 1
                i = end + 1
        elif ch in "[{":
            depth += 1
            if depth > MAX_YAML_DEPTH:
                return line, at - line_start + 1
        else:
            depth = max(0, depth - 1)
    return None


def _deep_event(text: str) -> tuple[int, int]:
    """(line, column) where block nesting passes MAX_YAML_DEPTH, found with the
    (iterative) event parser after the (recursive) composer gave up."""
    depth = 0
    try:
        for event in YAML(typ="rt").parse(text):
            if isinstance(event, CollectionStartEvent):
                depth += 1
                if depth > MAX_YAML_DEPTH and event.start_mark is not None:
                    return event.start_mark.line + 1, event.start_mark.column + 1
            elif isinstance(event, CollectionEndEvent):
                depth -= 1
    except Exception:
        pass
    return 1, 1


_TYPE_NAMES = {
    "object": "a mapping", "array": "a list", "string": "a string", "integer": "an integer",
    "number": "a number", "boolean": "true or false", "null": "nothing",
}


def _instance_text(value: Any) -> str:
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _expected(err: jsonschema.ValidationError) -> str:
    """What the schema wanted, in words (``err.message`` can quote a whole subtree)."""
    # the schema keyword's argument: its type depends on the keyword checked below
    v = err.validator
    inst: Any = err.instance
    spec: Any = err.validator_value
    schema: Any = err.schema
    if v == "type":
        kinds = [spec] if isinstance(spec, str) else list(spec)
        return f"expected {' or '.join(_TYPE_NAMES.get(k, k) for k in kinds)}, got {_instance_text(inst)}"
    if v == "enum":
        return f"expected one of: {', '.join(map(str, spec))}; got {_instance_text(inst)}"
    if v == "const":
        return f"expected {spec!r}, got {_instance_text(inst)}"
    if v == "pattern":
        if spec.startswith("^INT-"):
            return f"expected an interpretation id like INT-007, got {_instance_text(inst)}"
        if spec == "^[A-Za-z_][A-Za-z0-9_]*$":
            return f"expected a name (letters, digits and _, not starting with a digit), got {_instance_text(inst)}"
        return f"expected text matching {spec}, got {_instance_text(inst)}"
    if v == "minItems":
        return f"expected at least {spec} item(s), got {len(inst)}"
    if v == "maxItems":
        return f"expected at most {spec} item(s), got {len(inst)}"
    if v == "minLength":
        return "expected non-empty text"
    if v == "minProperties":
        names = sorted(schema.get("properties", {}))
        if names:
            return f"expected at least {spec} key(s) out of: {', '.join(names)}"
        return f"expected at least {spec} key(s)"
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        word = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}[v]
        return f"expected a number {word} {spec}, got {_instance_text(inst)}"
    message = err.message
    return message if len(message) <= 200 else message[:197] + "..."


def _node_at(tree: Any, parts: tuple[Any, ...]) -> Any:
    node = tree
    for p in parts:
        try:
            node = node[p]
        except (KeyError, IndexError, TypeError):
            return None
    return node


_VALIDATORS: dict[int, tuple[dict[str, Any], Any]] = {}
#: (schema, document text) pairs already found valid: a valid document is valid again.
_VALID_DOCUMENTS: set[tuple[int, str]] = set()


def _validator(schema: dict[str, Any]) -> Any:
    """A compiled validator per schema object (building one costs more than a small file)."""
    hit = _VALIDATORS.get(id(schema))
    if hit is not None and hit[0] is schema:
        return hit[1]
    if len(_VALIDATORS) > 16:
        _VALIDATORS.clear()
    validator = jsonschema.Draft202012Validator(schema)
    _VALIDATORS[id(schema)] = (schema, validator)
    return validator


def schema_diagnostics(
    name: str, tree: Any, schema: dict[str, Any], what: str
) -> list[Diagnostic]:
    """Validate ``tree`` against ``schema``; each violation located at its node.

    An unknown key is reported at the key itself, with the keys that are allowed there.
    """
    validator = _validator(schema)
    plain = plain_data(tree)
    try:
        key: tuple[int, str] | None = (id(schema), json.dumps(plain, sort_keys=True, default=repr))
    except (TypeError, ValueError, RecursionError):
        key = None
    if key is not None and key in _VALID_DOCUMENTS:
        return []
    from statecharts import tree_cache

    schema_text = _schema_text(schema)
    if key is not None and tree_cache.known_valid(schema_text, key[1]):
        _VALID_DOCUMENTS.add(key)
        return []
    out = []
    for err in validator.iter_errors(plain):
        parts = tuple(err.absolute_path)
        if err.validator == "additionalProperties" and isinstance(err.instance, dict):
            allowed = sorted(err.schema.get("properties", {}))
            parent = _node_at(tree, parts)
            for key in sorted(set(err.instance) - set(allowed)):
                if not (isinstance(parent, dict) and key in parent):
                    continue  # a non-string key: tree_diagnostics reported it already
                line, col = locate(tree, (*parts, key), key=True)
                hint = f"expected one of: {', '.join(allowed)}" if allowed else "no keys are allowed here"
                out.append(Diagnostic(name, line, col, node_path((*parts, key)), f"unknown key {key!r}; {hint}"))
            if allowed:
                continue
        line, col = locate(tree, parts)
        where = node_path(parts) or "(document)"
        if err.validator == "required":
            missing = [k for k in err.validator_value if isinstance(err.instance, dict) and k not in err.instance]
            message = f"missing required key {', '.join(map(repr, missing)) or err.message}"
            if not parts:
                message += f" in {what}"
        else:
            message = _expected(err)
        out.append(Diagnostic(name, line, col, where, message))
    if not out and key is not None:
        if len(_VALID_DOCUMENTS) > 512:
            _VALID_DOCUMENTS.clear()
        _VALID_DOCUMENTS.add(key)
        tree_cache.remember_valid(schema_text, key[1])
    return out


_SCHEMA_TEXTS: dict[int, tuple[dict[str, Any], str]] = {}


def _schema_text(schema: dict[str, Any]) -> str:
    """A schema as canonical JSON (kept per schema object)."""
    hit = _SCHEMA_TEXTS.get(id(schema))
    if hit is not None and hit[0] is schema:
        return hit[1]
    text = json.dumps(schema, sort_keys=True, default=repr)
    if len(_SCHEMA_TEXTS) > 16:
        _SCHEMA_TEXTS.clear()
    _SCHEMA_TEXTS[id(schema)] = (schema, text)
    return text


#: The Logix DINT range: ERR, EXERR, state values and integer tag values are DINTs.
DINT_MIN, DINT_MAX = -(2**31), 2**31 - 1


def number_diagnostics(name: str, tree: Any, *, what: str = "spec file") -> list[Diagnostic]:
    """Numbers a spec file may not hold: integers outside the DINT range (ERR and EXERR,
    state values, integer variables and operands are all DINTs in Logix), NaN and
    infinities (a spec value is a finite number).  Iterative, over the whole tree."""
    out: list[Diagnostic] = []
    stack: list[tuple[Any, tuple[Any, ...]]] = [(tree, ())]
    while stack:
        node, parts = stack.pop()
        if isinstance(node, dict):
            stack.extend((v, (*parts, k)) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, (*parts, i)) for i, v in enumerate(node))
        elif isinstance(node, bool):
            continue
        elif isinstance(node, int) and not DINT_MIN <= node <= DINT_MAX:
            line, col = locate(tree, parts)
            shown = str(node) if node.bit_length() <= 128 else f"an integer of {node.bit_length()} bits"
            out.append(Diagnostic(name, line, col, node_path(parts), (
                f"{shown} is outside the DINT range [{DINT_MIN}, {DINT_MAX}] of Logix integers")))
        elif isinstance(node, float) and not math.isfinite(node):
            line, col = locate(tree, parts)
            out.append(Diagnostic(name, line, col, node_path(parts), f"{node} is not a finite number; a {what} holds finite values"))
    return out


def variable_kinds(v: ir.Variable) -> frozenset[str]:
    """The kinds of value (:data:`statecharts.expr.KINDS`) a variable may hold."""
    if v.type == "bool":
        return frozenset({"bool"})
    if v.type == "int":
        return frozenset({"int"})
    if v.type == "real":
        return frozenset({"int", "real"})
    found: set[str] = set()
    for value in v.domain or ():
        found |= result_kinds(parse_expression(repr(value)), {})[0] if isinstance(value, (int, float, str)) else set()
    return frozenset(found) or KINDS


def assignment_problem(a: Assignment, var: ir.Variable, kinds: dict[str, frozenset[str]]) -> str | None:
    """Why action ``a`` could give ``var`` a value of the wrong type or outside its domain, or None."""
    got, constants = result_kinds(a.value, kinds)
    wanted = variable_kinds(var)
    if not got & wanted:
        article = "an" if var.type[0] in "aeiou" else "a"
        return (f"{a.text!r} assigns {' or '.join(sorted(_KIND_WORDS[k] for k in got))} to {var.name}, "
                f"{article} {var.type} variable")
    if var.domain is not None:
        for c in constants:
            if any(c == d and type(c) is type(d) for d in var.domain) or (
                    var.type == "real" and isinstance(c, (int, float)) and not isinstance(c, bool) and c in var.domain):
                continue
            if var.type in ("int", "real") and var.domain and not isinstance(c, bool) and isinstance(c, (int, float)) and c in var.domain:
                continue
            return f"{a.text!r} can assign {c!r} to {var.name}, outside its domain {domain_text(var.domain)}"
    return None


def _parameter_result_problem(
    a: Assignment, var: ir.Variable, domains: dict[str, tuple[Any, ...] | None], written: set[str]
) -> str | None:
    """An action that reads a parameter (a variable no action writes) and not its own
    target, over finite domains only, is evaluated on every combination: each result
    must be in the target's domain (a 10**9 ms enable delay must not make a 10**8-step
    timer)."""
    if var.domain is None or a.target in a.value.names or not a.value.names - written:
        return None
    names = sorted(a.value.names)
    size = 1
    for n in names:
        d = domains.get(n)
        if d is None:
            return None
        size *= len(d)
        if size > 4096:
            return None
    for values in itertools.product(*(domains[n] or () for n in names)):
        env = dict(zip(names, values))
        try:
            result = a.value(env)
        except Exception as exc:
            shown = ", ".join(f"{k}={v!r}" for k, v in env.items())
            return f"{a.text!r} cannot be evaluated with {shown}: {exc}"
        if result not in var.domain or isinstance(result, bool) != isinstance(var.initial, bool):
            shown = ", ".join(f"{k}={v!r}" for k, v in env.items())
            return (f"{a.text!r} gives {var.name} the value {result!r} with {shown}, "
                    f"outside its domain {domain_text(var.domain)}")
    return None


def domain_text(domain: Sequence[object]) -> str:
    """A domain as a reader wants it: ``[0, 2000]`` for a long run of integers, else the list."""
    values = list(domain)
    ints = [v for v in values if type(v) is int]
    if len(values) > 8 and len(ints) == len(values) and ints == list(range(ints[0], ints[-1] + 1)):
        return f"(the range {values[0]} to {values[-1]})"
    return repr(values)


_KIND_WORDS = {"bool": "a bool", "int": "an integer", "real": "a real", "str": "a string", "none": "None"}


# --------------------------------------------------------------------------- building


@dataclass
class _File:
    name: str
    tree: Any

    @property
    def top(self) -> Node:
        return Node(self.tree, "file")


@dataclass
class _Builder:
    errors: list[Diagnostic] = field(default_factory=list)
    used_interpretations: set[str] = field(default_factory=set)
    interp_refs: list[tuple[str, _File, tuple[Any, ...]]] = field(default_factory=list)

    # -- helpers ---------------------------------------------------------------

    def error(self, f: _File, parts: tuple[Any, ...], message: str) -> None:
        line, col = locate(f.tree, parts)
        self.errors.append(Diagnostic(f.name, line, col, node_path(parts), message))

    def loc(self, f: _File, parts: tuple[Any, ...]) -> ir.Location:
        line, col = locate(f.tree, parts)
        return ir.Location(f.name, line, col, node_path(parts))

    def prov(self, f: _File, parts: tuple[Any, ...], node: Node) -> ir.Provenance:
        interp = node.get("interpretation") if node.declares("interpretation") else None
        if interp is not None:
            self.interp_refs.append((str(interp), f, (*parts, "interpretation")))
        return ir.Provenance(str(node.get("source", "")), str(interp) if interp else None)

    def expr(self, f: _File, parts: tuple[Any, ...], text: str, known: Iterable[str]) -> Expr | None:
        try:
            e = parse_expression(str(text))
        except ExprError as exc:
            self.error(f, parts, f"{exc.message} (at character {exc.offset + 1} of {text!r})")
            return None
        self._unknown(f, parts, e, known)
        return e

    def assign(
        self, f: _File, parts: tuple[Any, ...], text: str, known: Iterable[str], writable: Iterable[str]
    ) -> Assignment | None:
        try:
            a = parse_assignment(str(text))
        except ExprError as exc:
            self.error(f, parts, f"{exc.message} (at character {exc.offset + 1} of {text!r})")
            return None
        self._unknown(f, parts, a.value, known)
        if a.target not in set(writable):
            self.error(f, parts, f"cannot assign to {a.target!r}: not a writable variable here")
        return a

    def _unknown(self, f: _File, parts: tuple[Any, ...], e: Expr, known: Iterable[str]) -> None:
        known_set = set(known)
        for name, _offset in check_names(e, known_set):
            self.error(f, parts, f"unknown variable {name!r}{_hint(name, known_set)} in {e.text!r}")

    def actions(
        self, f: _File, parts: tuple[Any, ...], texts: Sequence[str] | None, known: Iterable[str],
        writable: Iterable[str],
    ) -> tuple[Assignment, ...]:
        known_l, writable_l = list(known), list(writable)
        out = []
        for i, t in enumerate(texts or ()):
            a = self.assign(f, (*parts, i), t, known_l, writable_l)
            if a is not None:
                out.append(a)
        return tuple(out)

    def duplicates(self, f: _File, parts: tuple[Any, ...], items: Sequence[Node], key: str, what: str) -> None:
        seen: dict[Any, int] = {}
        for i, item in enumerate(items):
            k = item.get(key)
            if k in seen:
                self.error(f, (*parts, i, key), f"duplicate {what} {k!r} (first defined at item {seen[k]})")
            else:
                seen[k] = i

    # -- variables -----------------------------------------------------------

    def variable(self, f: _File, parts: tuple[Any, ...], v: Node) -> ir.Variable:
        vtype = v["type"]
        domain = v.get("domain")
        initial = v["initial"]
        if vtype == "bool":
            domain = [False, True]
            if not isinstance(initial, bool):
                self.error(f, (*parts, "initial"), f"initial value {initial!r} is not a bool (true or false)")
        elif vtype == "enum":
            if not domain:
                self.error(f, parts, "an enum variable needs a domain")
                domain = [initial]
        elif vtype in ("int", "real"):
            wanted = "an integer" if vtype == "int" else "a number"
            for j, value in enumerate(domain or ()):
                if not _is_number(value, integral=vtype == "int"):
                    self.error(f, (*parts, "domain", j), f"domain value {value!r} of an {vtype} variable is not {wanted}")
            if not _is_number(initial, integral=vtype == "int"):
                self.error(f, (*parts, "initial"), f"initial value {initial!r} of an {vtype} variable is not {wanted}")
            if vtype == "int" and domain is None and "range" in v:
                lo_f, hi_f = float(v["range"][0]), float(v["range"][1])
                if not (math.isfinite(lo_f) and math.isfinite(hi_f)):
                    self.error(f, (*parts, "range"), f"range bounds must be finite numbers, got [{lo_f}, {hi_f}]")
                else:
                    lo, hi = math.ceil(lo_f), math.floor(hi_f)
                    if hi < lo:
                        self.error(f, (*parts, "range"), f"empty range [{lo}, {hi}]")
                    domain = list(range(lo, hi + 1)) if hi - lo <= 4096 else None
        if domain is not None and initial not in domain:
            self.error(f, (*parts, "initial"), f"initial value {initial!r} is not in the domain {list(domain)!r}")
        values: list[ir.DocumentedValue] = []
        for j, n in enumerate(v.items("values", "value") if "values" in v else ()):
            vp = (*parts, "values", j)
            if domain is not None and n["value"] not in domain:
                self.error(f, (*vp, "value"), f"documented value {n['value']!r} is not in the domain {list(domain)!r}")
            if any(x.value == n["value"] for x in values):
                self.error(f, (*vp, "value"), f"value {n['value']!r} is documented twice")
            values.append(ir.DocumentedValue(n["value"], str(n["meaning"]), ir.Confidence(n.get("confidence", "C")),
                                             self.prov(f, vp, n)))
        return ir.Variable(
            name=v["name"], type=vtype, initial=initial,
            domain=tuple(domain) if domain is not None else None,
            description=str(v.get("description", "")), provenance=self.prov(f, parts, v),
            location=self.loc(f, parts), writable=bool(v.get("writable", False)), values=tuple(values),
        )

    def implies(self, f: _File, parts: tuple[Any, ...], given: Any, variables: Sequence[ir.Variable]) -> tuple[tuple[str, object], ...]:
        """A state's ``implies:``: chart variables and the values a set-up in that state needs."""
        if not given:
            return ()
        by_name = {v.name: v for v in variables}
        out: list[tuple[str, object]] = []
        for name, value in given.items():
            var = by_name.get(name)
            if var is None:
                self.error(f, (*parts, name), f"unknown variable {name!r}{_hint(name, by_name)}; variables: {', '.join(by_name)}")
                continue
            if var.type == "bool" and not isinstance(value, bool):
                self.error(f, (*parts, name), f"{name} is a bool: expected true or false, got {value!r}")
                continue
            if var.type in ("int", "real") and (isinstance(value, bool) or not isinstance(value, (int, float))):
                self.error(f, (*parts, name), f"{name} is a number: got {value!r}")
                continue
            if var.domain is not None and value not in var.domain:
                self.error(f, (*parts, name), f"{value!r} is not in the domain of {name}: {list(var.domain)!r}")
                continue
            out.append((name, value))
        return tuple(out)

    # -- charts --------------------------------------------------------------

    def chart(self, f: _File, c: Node) -> ir.Chart:
        base: tuple[Any, ...] = ("chart",)
        var_nodes = c.items("variables", "variable")
        self.duplicates(f, (*base, "variables"), var_nodes, "name", "variable")
        variables = tuple(self.variable(f, (*base, "variables", i), v) for i, v in enumerate(var_nodes))
        var_names = [v.name for v in variables]
        known = var_names + list(SYSTEM_PARAMETERS)

        event_nodes = c.items("events", "event")
        self.duplicates(f, (*base, "events"), event_nodes, "name", "event")
        events = []
        for i, e in enumerate(event_nodes):
            p = (*base, "events", i)
            events.append(ir.Event(
                name=e["name"], kind=e["kind"], description=str(e.get("description", "")),
                parameters=tuple(e.get("parameters") or ()),
                actions=self.actions(f, (*p, "actions"), e.get("actions"), known, var_names),
                provenance=self.prov(f, p, e),
            ))
        event_names = {e.name for e in events}

        states: list[ir.State] = []
        state_nodes: dict[str, tuple[Any, ...]] = {}

        def walk(nodes: Sequence[Node], parts: tuple[Any, ...], parent: str | None) -> list[str]:
            # recursion depth is bounded by MAX_YAML_DEPTH, checked before the schema
            ids = []
            for i, s in enumerate(nodes):
                p = (*parts, i)
                sid = s["id"]
                if sid in state_nodes:
                    self.error(f, (*p, "id"), f"duplicate state id {sid!r}")
                    continue
                state_nodes[sid] = p
                children_nodes = s.items("states", "state")
                kind_name = s.get("kind") or ("compound" if children_nodes else "atomic")
                kind = ir.StateKind(kind_name)
                if kind in (ir.StateKind.COMPOUND, ir.StateKind.PARALLEL) and not children_nodes:
                    self.error(f, p, f"a {kind_name} state needs child states")
                if kind not in (ir.StateKind.COMPOUND, ir.StateKind.PARALLEL) and children_nodes:
                    self.error(f, (*p, "states"), f"a {kind_name} state cannot have child states")
                children = walk(children_nodes, (*p, "states"), sid)
                initial = s.get("initial")
                if kind is ir.StateKind.COMPOUND:
                    if initial is None:
                        self.error(f, p, (
                            f"compound state {sid!r} must name its initial child (`initial:`); "
                            f"children: {', '.join(children)}"))
                    elif initial not in children:
                        self.error(f, (*p, "initial"), f"initial {initial!r} is not a child of {sid!r}; children: {', '.join(children)}")
                elif initial is not None:
                    self.error(f, (*p, "initial"), f"only a compound state has an initial child ({sid!r} is {kind_name})")
                history = s.get("history")
                if kind is ir.StateKind.HISTORY and history is None:
                    self.error(f, p, "a history state must say `history: shallow` or `history: deep`")
                value = s.get("value")
                states.append(ir.State(
                    id=sid, name=str(s.get("name", sid)), kind=kind, value=int(value) if value is not None else None,
                    parent=parent, children=tuple(children),
                    initial=initial if kind is ir.StateKind.COMPOUND else None,
                    history_type=history,
                    entry=self.actions(f, (*p, "entry"), s.get("entry"), known, var_names),
                    exit=self.actions(f, (*p, "exit"), s.get("exit"), known, var_names),
                    description=str(s.get("description", "")),
                    provenance=self.prov(f, p, s), location=self.loc(f, p),
                    implies=self.implies(f, (*p, "implies"), s.get("implies"), variables),
                ))
                ids.append(sid)
            return ids

        top = walk(c.items("states", "state"), (*base, "states"), None)
        by_id = {s.id: s for s in states}
        for s in states:
            if s.kind is ir.StateKind.PARALLEL:
                for ch in s.children:
                    if by_id[ch].kind is not ir.StateKind.COMPOUND:
                        self.error(f, state_nodes[ch], f"each region of parallel state {s.id!r} must be a compound state")
        seen_values: dict[int, str] = {}
        for s in states:
            if s.value is not None:
                if s.value in seen_values:
                    self.error(f, (*state_nodes[s.id], "value"), f"state value {s.value} is already used by {seen_values[s.value]!r}")
                seen_values[s.value] = s.id

        root_initial = c.get("initial", top[0] if len(top) == 1 else None)
        if root_initial is None:
            root_initial = top[0] if top else ""
            if len(top) > 1:
                self.error(f, base, "a chart with several top-level states must name its initial state (`initial:`)")
        elif root_initial not in top:
            self.error(f, (*base, "initial"), f"initial {root_initial!r} is not a top-level state; top-level states: {', '.join(top)}")

        trans_nodes = c.items("transitions", "transition")
        self.duplicates(f, (*base, "transitions"), trans_nodes, "id", "transition")
        transitions = []
        for i, t in enumerate(trans_nodes):
            p = (*base, "transitions", i)
            src, dst, ev = t["from"], t.get("to"), t.get("event")
            if src not in by_id:
                self.error(f, (*p, "from"), f"unknown source state {src!r}{_hint(src, by_id)}; states: {', '.join(sorted(by_id))}")
            if dst is not None and dst not in by_id:
                self.error(f, (*p, "to"), f"unknown target state {dst!r}{_hint(dst, by_id)}; states: {', '.join(sorted(by_id))}")
            if ev is not None and ev not in event_names:
                self.error(f, (*p, "event"), (
                    f"unknown event {ev!r}{_hint(ev, event_names)}; declare it under chart.events "
                    f"(events: {', '.join(sorted(event_names))})"))
            if ev is None and "guard" not in t:
                self.error(f, p, "an eventless transition needs a guard (it would fire forever)")
            if dst is None and not t.get("actions"):
                self.error(f, p, "a transition with no target must have actions")
            guard = self.expr(f, (*p, "guard"), t["guard"], known) if "guard" in t else None
            transitions.append(ir.Transition(
                id=t["id"], source=src, target=dst, event=ev, guard=guard,
                actions=self.actions(f, (*p, "actions"), t.get("actions"), known, var_names),
                priority=int(t.get("priority", 0)), provenance=self.prov(f, p, t), location=self.loc(f, p),
            ))

        drive_model = c.get("drive_model")
        if drive_model is not None:
            self._drive_model(f, base, variables, events)
        chart = ir.Chart(
            id=c["id"], name=c["name"], kind=ir.ChartKind(c["kind"]), state_attribute=c["state_attribute"],
            axis_types=tuple(c["axis_types"]), variables=variables, events=tuple(events),
            states=tuple(states), transitions=tuple(transitions), root_initial=root_initial,
            description=str(c.get("description", "")), provenance=self.prov(f, base, c), location=self.loc(f, base),
            drive_model=drive_model,
            parameters=self.chart_parameters(f, c),
        )
        if any(d.file == f.name for d in self.errors):
            return chart
        self._reachability(f, chart, state_nodes)
        self._overlaps(f, chart)
        self._eventless_cycles(f, chart)
        self._assignment_kinds(f, chart, state_nodes, [(i, e.actions) for i, e in enumerate(events)])
        return chart

    def _drive_model(
        self, f: _File, base: tuple[Any, ...], variables: Sequence[ir.Variable], events: Sequence[ir.Event],
    ) -> None:
        """A chart with ``drive_model: motion`` declares the drive model's variables and events."""
        declared = {v.name: v.type for v in variables}
        for name, typ in drive.VARIABLES.items():
            if name not in declared:
                self.error(f, (*base, "drive_model"), (
                    f"a chart with the motion drive model declares the variable {name!r} ({typ}); "
                    f"the drive model needs: {', '.join(drive.VARIABLES)}"))
            elif declared[name] != typ:
                self.error(f, (*base, "drive_model"), f"the drive-model variable {name!r} must be of type {typ}, not {declared[name]}")
        kinds = {e.name: e.kind for e in events}
        for name in drive.EVENTS:
            if kinds.get(name) != "drive":
                self.error(f, (*base, "drive_model"), (
                    f"a chart with the motion drive model declares the event {name!r} with kind drive"))

    def chart_parameters(self, f: _File, c: Node) -> tuple[ir.ChartParameter, ...]:
        nodes = c.items("parameters", "chart_parameter")
        self.duplicates(f, ("chart", "parameters"), nodes, "name", "parameter")
        variables = {str(v["name"]) for v in c.items("variables", "variable")}
        out = []
        for i, n in enumerate(nodes):
            p = ("chart", "parameters", i)
            if n["name"] in variables:
                self.error(f, (*p, "name"), f"parameter {n['name']!r} is also a variable of the chart")
            out.append(ir.ChartParameter(n["name"], n["type"], n.get("default"), str(n.get("description", "")),
                                         self.prov(f, p, n)))
        return tuple(out)

    def _assignment_kinds(
        self, f: _File, chart: ir.Chart, state_nodes: dict[str, tuple[Any, ...]],
        events: list[tuple[int, tuple[Assignment, ...]]],
    ) -> None:
        """Each action must be able to give its variable a value of its type and domain."""
        variables = {v.name: v for v in chart.variables}
        kinds = {n: variable_kinds(v) for n, v in variables.items()}
        kinds.update({k: frozenset({"int"}) for k in SYSTEM_PARAMETERS})
        sites: list[tuple[tuple[Any, ...], Assignment]] = []
        for i, acts in events:
            sites.extend(((("chart", "events", i, "actions", j), a) for j, a in enumerate(acts)))
        for s in chart.states:
            for key, acts in (("entry", s.entry), ("exit", s.exit)):
                sites.extend((((*state_nodes[s.id], key, j), a) for j, a in enumerate(acts)))
        for i, t in enumerate(chart.transitions):
            sites.extend(((("chart", "transitions", i, "actions", j), a) for j, a in enumerate(t.actions)))
        written = {a.target for _, a in sites}
        domains: dict[str, tuple[Any, ...] | None] = {v.name: v.domain for v in chart.variables}
        domains.update(SYSTEM_PARAMETERS)
        for parts, a in sites:
            var = variables.get(a.target)
            if var is None:
                continue
            problem = assignment_problem(a, var, kinds) or _parameter_result_problem(a, var, domains, written)
            if problem:
                self.error(f, parts, problem)

    def _eventless_cycles(self, f: _File, chart: ir.Chart) -> None:
        for cycle in eventless_cycles(chart, SYSTEM_PARAMETERS):
            self.error(f, _loc_parts(cycle.transitions[0].location), cycle.describe())

    def _reachability(self, f: _File, chart: ir.Chart, state_nodes: dict[str, tuple[Any, ...]]) -> None:
        reached: set[str] = set()
        by_id = {s.id: s for s in chart.states}

        def enter(sid: str, todo: list[str]) -> None:
            for a in chart.ancestors(sid):
                if a not in reached:
                    reached.add(a)
                    todo.append(a)

        todo: list[str] = []
        enter(chart.root_initial, todo)
        while todo:
            sid = todo.pop()
            s = by_id[sid]
            if s.kind is ir.StateKind.COMPOUND and s.initial:
                enter(s.initial, todo)
            if s.kind is ir.StateKind.PARALLEL:
                for ch in s.children:
                    enter(ch, todo)
            if s.kind is ir.StateKind.HISTORY and s.parent:
                for ch in by_id[s.parent].children:
                    enter(ch, todo)
            # a transition leaving an ancestor applies to every descendant; entering a
            # leaf enters its ancestors, so testing the source alone covers that case
            for t in chart.transitions:
                if t.target and t.source == sid:
                    enter(t.target, todo)
        for s in chart.states:
            if s.id not in reached:
                self.error(f, state_nodes[s.id], f"state {s.id!r} is unreachable from the initial state {chart.root_initial!r}")

    def _overlaps(self, f: _File, chart: ir.Chart) -> None:
        domains: dict[str, tuple[Any, ...] | None] = {v.name: v.domain for v in chart.variables}
        domains.update(SYSTEM_PARAMETERS)
        groups: dict[tuple[str, str | None], list[ir.Transition]] = {}
        for t in chart.transitions:
            groups.setdefault((t.source, t.event), []).append(t)
        for (src, ev), ts in groups.items():
            for a, b in itertools.combinations(ts, 2):
                if a.priority != b.priority:
                    continue
                witness, decided = _joint_witness(a.guard, b.guard, domains)
                label = f"event {ev!r}" if ev else "no event (eventless)"
                parts = _loc_parts(b.location)
                if not decided:
                    self.error(f, parts, (
                        f"transitions {a.id!r} and {b.id!r} leave {src!r} on {label} with equal priority and guards "
                        "over unbounded variables; give them different `priority:` values"))
                elif witness is not None:
                    shown = ", ".join(f"{k}={v!r}" for k, v in sorted(witness.items())) or "always"
                    self.error(f, parts, (
                        f"transitions {a.id!r} and {b.id!r} leave {src!r} on {label} and can both be enabled "
                        f"({shown}); make the guards disjoint or give them different `priority:` values"))

    # -- instructions ----------------------------------------------------------

    def instruction(
        self, f: _File, node: Node, charts: dict[str, ir.Chart], tables: dict[str, ir.ExecutionTable],
    ) -> ir.Instruction:
        base: tuple[Any, ...] = ("instruction",)
        chart_list = []
        for i, cid in enumerate(node["charts"]):
            if cid not in charts:
                self.error(f, (*base, "charts", i), f"unknown chart {cid!r}; charts: {', '.join(sorted(charts))}")
            else:
                chart_list.append(charts[cid])
        common_vars: set[str] | None = None
        for c in chart_list:
            names = {v.name for v in c.variables} | {c.state_attribute}
            common_vars = names if common_vars is None else common_vars & names
        axis_vars = sorted(common_vars or ())
        known_axis = [f"axis.{v}" for v in (*axis_vars, *AXIS_READ_ONLY)]
        writable_axis = [f"axis.{v}" for v in axis_vars if v not in {c.state_attribute for c in chart_list}]

        op_nodes = node.items("operands", "operand")
        self.duplicates(f, (*base, "operands"), op_nodes, "name", "operand")
        operands = []
        for i, o in enumerate(op_nodes):
            p = (*base, "operands", i)
            rng = o.get("range")
            operands.append(ir.Operand(
                name=o["name"], type=o["type"], domain=tuple(o["domain"]) if "domain" in o else None,
                range=(float(rng[0]), float(rng[1])) if rng is not None else None,
                text_values=tuple(sorted((str(k), int(v)) for k, v in dict(o.get("text_values") or {}).items())),
                default=o.get("default"),
                description=str(o.get("description", "")), provenance=self.prov(f, p, o),
            ))
        known_ops = [f"op.{o.name}" for o in operands if o.type not in ("axis", "tag")]
        known = known_axis + known_ops
        master_operand = None
        for i, o in enumerate(op_nodes):
            if o.get("role") == "master":
                if o["type"] != "axis" or master_operand is not None:
                    self.error(f, (*base, "operands", i, "role"), "only one operand, of type axis, may be the master axis")
                    continue
                master_operand = str(o["name"])
        if master_operand is not None:
            # the master is any chart with the drive model: its motion variables and states
            known = known + [f"master.{v}" for v in (*drive.VARIABLES, *AXIS_READ_ONLY)]

        check_nodes = node.items("checks", "check")
        self.duplicates(f, (*base, "checks"), check_nodes, "id", "check")
        checks = []
        for i, ch in enumerate(check_nodes):
            p = (*base, "checks", i)
            e = self.expr(f, (*p, "fails_when"), ch["fails_when"], known)
            checks.append(ir.Check(
                id=ch["id"], fails_when=e if e is not None else _NEVER, err=int(ch["err"]),
                exerr=int(ch.get("exerr", 0)), stage=ir.Stage(ch.get("stage", "execute")),
                description=str(ch.get("description", "")), provenance=self.prov(f, p, ch), location=self.loc(f, p),
            ))
        aborts = []
        for i, ab in enumerate(node.items("aborts", "abort")):
            p = (*base, "aborts", i)
            e = self.expr(f, (*p, "when"), ab["when"], known)
            aborts.append(ir.Check(
                id=ab["id"], fails_when=e if e is not None else _NEVER, err=int(ab["err"]),
                exerr=int(ab.get("exerr", 0)), stage=ir.Stage.MESSAGE,
                description=str(ab.get("description", "")), provenance=self.prov(f, p, ab), location=self.loc(f, p),
            ))

        request = None
        if "request" in node:
            r = node.child("request", "request")
            for c in chart_list:
                requests = sorted(e.name for e in c.events if e.kind == "request")
                if r["event"] not in requests:
                    self.error(f, (*base, "request", "event"), (
                        f"chart {c.id!r} declares no request event {r['event']!r}; request events: {', '.join(requests)}"))
            request = ir.Request(
                event=r["event"],
                actions=self.actions(f, (*base, "request", "actions"), r.get("actions"), known, writable_axis),
            )
        done = node.child("done", "done")
        done_when = self.expr(f, (*base, "done", "when"), done["when"], known) if "when" in done else None
        done_prov = self.prov(f, (*base, "done"), done)

        process = None
        if "process" in node:
            pn = node.child("process", "process")
            pp = (*base, "process")
            process = ir.Process(
                kind=str(pn["kind"]),
                complete_when=self.expr(f, (*pp, "complete_when"), pn["complete_when"], known) if "complete_when" in pn else None,
                ends_when=self.expr(f, (*pp, "ends_when"), pn["ends_when"], known) if "ends_when" in pn else None,
                provenance=self.prov(f, pp, pn),
            )
        table_id = node["execution_table"]
        table = tables.get(table_id)
        if table is None:
            self.error(f, (*base, "execution_table"), f"unknown execution table {table_id!r}; tables: {', '.join(sorted(tables))}")
            table = _EMPTY_TABLE
        status_bits = dict(node.get("status_bits") or {})
        for bit in status_bits:
            if bit not in axis_vars:
                self.error(f, (*base, "status_bits", bit), f"unknown status bit {bit!r}{_hint(str(bit), set(axis_vars))}")
        return ir.Instruction(
            id=node["id"], mnemonic=str(node.get("mnemonic", node["id"])), name=node["name"], charts=tuple(c.id for c in chart_list),
            axis_types=tuple(node["axis_types"]), operands=tuple(operands), execution=node["execution"],
            table=table, checks=tuple(checks), aborts=tuple(aborts), request=request, done_when=done_when,
            status_bits=tuple(sorted((str(k), bool(v)) for k, v in status_bits.items())),
            description=str(node.get("description", "")), provenance=self.prov(f, base, node),
            done_provenance=done_prov,
            location=self.loc(f, base), process=process, master_operand=master_operand,
        )

    def tag_type(self, f: _File, node: Node) -> ir.TagType:
        base: tuple[Any, ...] = ("tag_type",)
        member_nodes = node.items("members", "tag_member")
        self.duplicates(f, (*base, "members"), member_nodes, "name", "member")
        members = []
        bits: dict[int, str] = {}
        for i, m in enumerate(member_nodes):
            bit = m.get("bit")
            if bit is not None:
                if not 0 <= int(bit) <= 31:
                    self.error(f, (*base, "members", i, "bit"), f"bit {bit} of {m['name']} is outside a DINT (0 to 31)")
                elif int(bit) in bits:
                    self.error(f, (*base, "members", i, "bit"), f"bit {bit} of {m['name']} is already {bits[int(bit)]}")
                else:
                    bits[int(bit)] = str(m["name"])
            members.append(ir.TagMember(
                name=m["name"], type=m["type"], bit=int(bit) if bit is not None else None,
                description=str(m.get("description", "")), provenance=self.prov(f, (*base, "members", i), m),
            ))
        internal = tuple(
            self.variable(f, (*base, "internal", i), v) for i, v in enumerate(node.items("internal", "variable"))
        )
        wrong = None
        if "wrong_axis_family" in node:
            w = node.child("wrong_axis_family", "wrong_axis_family")
            p = (*base, "wrong_axis_family")
            wrong = ir.Check(
                id="wrong_axis_family", fails_when=parse_expression("True"), err=int(w["err"]),
                exerr=int(w.get("exerr", 0)), stage=ir.Stage.EXECUTE, description=str(w.get("description", "")),
                provenance=self.prov(f, p, w), location=self.loc(f, p),
            )
        return ir.TagType(name=node["name"], members=tuple(members), internal=internal,
                          provenance=self.prov(f, base, node), wrong_axis_family=wrong)

    def table(self, f: _File, parts: tuple[Any, ...], node: Node, tag_type: ir.TagType) -> ir.ExecutionTable:
        names = [m.name for m in tag_type.members] + [v.name for v in tag_type.internal]
        rows = []
        row_nodes = node.items("rows", "table_row")
        self.duplicates(f, (*parts, "rows"), row_nodes, "condition", "row for condition")
        for i, r in enumerate(row_nodes):
            p = (*parts, "rows", i)
            rows.append(ir.TableRow(
                condition=r["condition"],
                guard=self.expr(f, (*p, "guard"), r["guard"], names) if "guard" in r else None,
                actions=self.actions(f, (*p, "actions"), r.get("actions"), names, names),
                execute=bool(r.get("execute", False)), description=str(r.get("description", "")),
                provenance=self.prov(f, p, r),
            ))
        present = {r.condition for r in rows}
        for cond in ("prescan", "rung_false", "rung_true", "postscan"):
            if cond not in present:
                self.error(f, (*parts, "rows"), f"execution table has no row for {cond!r}")

        def block(key: str) -> tuple[Assignment, ...]:
            b = node.child(key, "table_block")
            self.prov(f, (*parts, key), b)
            return self.actions(f, (*parts, key, "actions"), b["actions"], names, names)

        return ir.ExecutionTable(
            id=node["id"], rows=tuple(rows), on_execute=block("on_execute"), on_error=block("on_error"),
            on_accept=block("on_accept"), on_done=block("on_done"), provenance=self.prov(f, parts, node),
            on_complete=block("on_complete") if "on_complete" in node else (),
            on_end=block("on_end") if "on_end" in node else (),
        )


_NEVER = parse_expression("False")
_EMPTY_TABLE = ir.ExecutionTable("", (), (), (), (), (), ir.Provenance(""))


def _other_format(tree: Any) -> bool:
    """A file of another motionchart format (``motionchart-properties/1``...), not a spec file."""
    fmt = Node(tree, "file").get("format") if isinstance(tree, dict) else None
    return isinstance(fmt, str) and fmt.startswith("motionchart-") and not fmt.startswith("motionchart-spec/")


def _cited_interpretations(tree: Any) -> set[str]:
    out: set[str] = set()
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, dict):
            value = node.get("interpretation")
            if isinstance(value, str):
                out.add(value)
            stack.extend(node.values())
        elif isinstance(node, list):
            stack.extend(node)
    return out


def _is_number(value: Any, *, integral: bool) -> bool:
    if isinstance(value, bool):
        return False
    return isinstance(value, int) if integral else isinstance(value, (int, float))


def _loc_parts(location: ir.Location) -> tuple[Any, ...]:
    parts: list[Any] = []
    for token in location.path.replace("[", ".[").split("."):
        if token.startswith("["):
            parts.append(int(token[1:-1]))
        elif token:
            parts.append(token)
    return tuple(parts)


def _joint_witness(
    a: Expr | None, b: Expr | None, domains: dict[str, tuple[Any, ...] | None]
) -> tuple[dict[str, Any] | None, bool]:
    """An assignment under which both guards hold: (witness or None, decided?)."""
    names = sorted((a.names if a else frozenset()) | (b.names if b else frozenset()))
    if any(domains.get(n) is None for n in names):
        return None, False
    sizes = 1
    for n in names:
        sizes *= len(domains[n] or ())
    if sizes > OVERLAP_ENUMERATION_LIMIT:
        return None, False
    for values in itertools.product(*(domains[n] or () for n in names)):
        env = dict(zip(names, values))
        try:
            if (a is None or a(env)) and (b is None or b(env)):
                return env, True
        except Exception:
            return None, False
    return None, True


def _closest(name: str, known: set[str]) -> str | None:
    import difflib

    match = difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.75)
    return match[0] if match else None


def _hint(name: str, known: Iterable[str]) -> str:
    match = _closest(str(name), set(known))
    return f" (did you mean {match!r}?)" if match else ""


# --------------------------------------------------------------------------- entry point


#: specs built in this process, by what they were built from (_spec_key); the IR is
#: frozen, so one Spec object serves every load of the same files
_SPECS: dict[tuple[object, ...], ir.Spec] = {}


def _spec_key(paths: Sequence[Path | str] | None, files: Sequence[Path]) -> tuple[object, ...] | None:
    """What a load of ``files`` depends on: the paths as given, each file's bytes (as a
    digest) and the working directory; None (no memo) unless every file is a regular file
    within the size limit (anything else is the load's to report: a FIFO or a device is
    never read here)."""
    import hashlib

    digests = []
    for f in files:
        raw = read_input(f, [], limit=MAX_FILE_BYTES)  # the loader's own guarded read
        if raw is None:
            return None
        digests.append(hashlib.sha256(raw).digest())
    given = None if paths is None else tuple(str(p) for p in paths)
    return (given, tuple(str(f) for f in files), tuple(digests), os.getcwd())


def load_spec(paths: Sequence[Path | str] | None = None) -> ir.Spec:
    """Load, validate and build the specification; raise SpecError with every problem found.

    A spec built from the same files (same bytes) earlier in this process is returned
    again (:func:`forget_trees` forgets them)."""
    all_paths = spec_files(paths)
    key = _spec_key(paths, all_paths)
    if key is not None:
        hit = _SPECS.get(key)
        if hit is not None:
            return hit
    spec = _load_spec(paths, all_paths)
    if key is not None and _spec_key(paths, all_paths) == key:  # no file changed meanwhile
        if len(_SPECS) > 8:
            _SPECS.clear()
        _SPECS[key] = spec
    return spec


def _load_spec(paths: Sequence[Path | str] | None, all_paths: list[Path]) -> ir.Spec:
    errors: list[Diagnostic] = []
    documents: list[tuple[str, Any]] = []
    registry, registry_errors = sources.registry_for(all_paths)
    side: list[tuple[str, Any]] = []
    for path in all_paths:
        # schema/ holds JSON Schemas; systems/ and properties/ are the model checker's files,
        # read here only for their citations (their own loaders report everything else)
        if path.suffix == ".json":
            continue
        if path.parent.name in ("schema", "systems", "properties") or path.parent.parent.name == "systems":
            if path.parent.name != "schema":
                tree = read_yaml(path, [])
                if tree is not None:
                    side.append((str(path), tree))
            continue
        before = len(errors)
        tree = read_yaml(path, errors)
        if tree is None and len(errors) == before:
            errors.append(Diagnostic(str(path), 1, 1, "", f"empty file; expected a mapping with `format: {SPEC_FORMAT}`"))
        documents.append((str(path), tree if len(errors) == before else _FAILED))
    return _build_spec(documents, errors, str(paths[0]) if paths else "spec",
                       registry=registry, registry_errors=registry_errors, side=side)


def load_spec_documents(documents: Mapping[str, Any]) -> ir.Spec:
    """Build the specification from parsed documents (file name -> YAML tree or plain
    data), exactly as :func:`load_spec` builds it from files: the same shape, schema and
    semantic checks, the same SpecError.  For tools that produce or transform spec data
    in memory (and for the fuzzing tests, which mutate parsed trees)."""
    errors: list[Diagnostic] = []
    docs: list[tuple[str, Any]] = []
    for name, tree in documents.items():
        if tree is None:
            errors.append(Diagnostic(name, 1, 1, "", f"empty file; expected a mapping with `format: {SPEC_FORMAT}`"))
            docs.append((name, _FAILED))
            continue
        problems, fatal = tree_diagnostics(name, tree)
        errors.extend(problems)
        docs.append((name, _FAILED if problems or fatal else tree))
    registry, registry_errors = sources.registry_for([])
    return _build_spec(docs, errors, next(iter(documents), "spec"), registry=registry, registry_errors=registry_errors)


_FAILED = object()  # a document that could not be read: its diagnostics are in the list already


def _build_spec(
    documents: Sequence[tuple[str, Any]], read_errors: list[Diagnostic], label: str, *,
    registry: sources.Registry | None = None, registry_errors: Sequence[Diagnostic] = (),
    side: Sequence[tuple[str, Any]] = (),
) -> ir.Spec:
    """Build from parsed documents.  ``registry`` resolves every ``source:`` (of the
    documents and of the ``side`` files, the model checker's, checked only for their
    citations); its own problems are ``registry_errors``."""
    schema = spec_schema()
    b = _Builder()
    b.errors.extend(read_errors)
    files: list[_File] = []
    failed_files = 0
    source_errors: list[Diagnostic] = list(registry_errors)
    cited_trees: list[tuple[str, Any]] = []
    if registry is not None:
        for name, tree in side:
            source_errors.extend(sources.tree_source_diagnostics(name, tree, registry))
            cited_trees.append((name, tree))
    for name, tree in documents:
        before = len(b.errors)
        if tree is _FAILED or tree is None:
            failed_files += 1
            continue
        if registry is not None and isinstance(tree, (dict, list)):
            source_errors.extend(sources.tree_source_diagnostics(name, tree, registry))
            cited_trees.append((name, tree))
        if _other_format(tree):
            # properties, systems... live beside the spec and have their own loaders; an
            # interpretation they cite still counts as used.
            b.used_interpretations.update(_cited_interpretations(tree))
            continue
        b.errors.extend(schema_diagnostics(name, tree, schema, "a spec file"))
        if len(b.errors) == before:
            b.errors.extend(number_diagnostics(name, tree))
        if len(b.errors) == before:
            files.append(_File(name, tree))
        else:
            failed_files += 1
    if not files and not b.errors:
        b.errors.append(Diagnostic(label, 1, 1, "", "no spec files (*.yaml) found"))
    # When a file could not be read, what it defines is unknown: checks across files
    # would only repeat its failure (every use of its charts, codes, interpretations).
    complete = failed_files == 0

    interpretations: list[ir.Interpretation] = []
    interp_where: dict[str, tuple[_File, tuple[Any, ...]]] = {}
    errors: list[ir.ErrorCode] = []
    extended: list[ir.ExtendedError] = []
    tag_type: ir.TagType | None = None
    codes_seen: dict[int, str] = {}
    extended_seen: dict[tuple[str, int, int], str] = {}
    for f in files:
        t = f.top
        for i, n in enumerate(t.items("interpretations", "interpretation")):
            if n["id"] in interp_where:
                b.error(f, ("interpretations", i, "id"), f"duplicate interpretation {n['id']!r}")
                continue
            interp_where[n["id"]] = (f, ("interpretations", i))
            interpretations.append(ir.Interpretation(
                id=n["id"], title=n["title"], text=" ".join(str(n["text"]).split()),
                confidence=ir.Confidence(n["confidence"]), evidence=tuple(n["evidence"]),
            ))
        for i, n in enumerate(t.items("errors", "error")):
            code = int(n["code"])
            if code in codes_seen:
                b.error(f, ("errors", i, "code"), f"duplicate error code {code} (first defined at {codes_seen[code]})")
                continue
            codes_seen[code] = str(b.loc(f, ("errors", i, "code"))).rsplit(":", 1)[0]
            errors.append(ir.ErrorCode(code, n["name"], n["meaning"], ir.Confidence(n["confidence"]), b.prov(f, ("errors", i), n)))
        for i, n in enumerate(t.items("extended_errors", "extended_error")):
            triple = (str(n["instruction"]), int(n["err"]), int(n["exerr"]))
            if triple in extended_seen:
                b.error(f, ("extended_errors", i), (
                    f"duplicate extended error {triple[1]}/{triple[2]} of {triple[0]} "
                    f"(first defined at {extended_seen[triple]})"))
                continue
            extended_seen[triple] = str(b.loc(f, ("extended_errors", i))).rsplit(":", 1)[0]
            extended.append(ir.ExtendedError(
                n["instruction"], int(n["err"]), int(n["exerr"]), n["name"], n["meaning"], ir.Confidence(n["confidence"]),
                b.prov(f, ("extended_errors", i), n),
            ))
        if "tag_type" in t:
            if tag_type is not None:
                b.error(f, ("tag_type",), "the MOTION_INSTRUCTION tag type is defined twice")
            tag_type = b.tag_type(f, t.child("tag_type", "tag_type"))

    tables: dict[str, ir.ExecutionTable] = {}
    if tag_type is None and files and complete:
        b.errors.append(Diagnostic(files[0].name, 1, 1, "", "no file defines `tag_type` (the MOTION_INSTRUCTION data type)"))
    for f in files:
        for i, n in enumerate(f.top.items("execution_tables", "execution_table")):
            if n["id"] in tables:
                b.error(f, ("execution_tables", i, "id"), f"duplicate execution table {n['id']!r}")
            elif tag_type is not None:
                tables[n["id"]] = b.table(f, ("execution_tables", i), n, tag_type)

    charts: dict[str, ir.Chart] = {}
    for f in files:
        if "chart" in f.top:
            c = f.top.child("chart", "chart")
            if c["id"] in charts:
                b.error(f, ("chart", "id"), f"duplicate chart id {c['id']!r}")
                continue
            charts[c["id"]] = b.chart(f, c)

    instructions: dict[str, ir.Instruction] = {}
    instruction_files: list[tuple[_File, str]] = []
    for f in files:
        if "instruction" in f.top:
            node = f.top.child("instruction", "instruction")
            iid = node["id"]
            if iid in instructions:
                b.error(f, ("instruction", "id"), f"duplicate instruction {iid!r}")
                continue
            if not complete and (
                any(cid not in charts for cid in node["charts"]) or node["execution_table"] not in tables
            ):
                continue  # what it refers to may be in the file that failed
            instructions[iid] = b.instruction(f, node, charts, tables)
            instruction_files.append((f, iid))
            new = instructions[iid]
            for other in instructions.values():
                shared = set(other.charts) & set(new.charts)
                if other is not new and other.mnemonic == new.mnemonic and shared:
                    b.error(f, ("instruction", "charts"), (
                        f"{new.mnemonic} already has variant {other.id!r} for chart(s) {', '.join(sorted(shared))}; "
                        "each chart needs exactly one variant of an instruction"))

    add_ons: dict[str, ir.AddOnInstruction] = {}
    for f in files:
        if "add_on_instruction" in f.top:
            node = f.top.child("add_on_instruction", "add_on_instruction")
            if node["id"] in add_ons or node["id"] in {i.mnemonic for i in instructions.values()}:
                b.error(f, ("add_on_instruction", "id"), f"duplicate instruction {node['id']!r}")
                continue
            if complete:
                add_ons[node["id"]] = addon_loader.build_add_on(b, f, node, charts, tuple(instructions.values()))

    # cross-file references: error codes and interpretations
    codes = {e.code for e in errors}
    ext_pairs = {(x.instruction, x.err, x.exerr) for x in extended}
    for f, iid in instruction_files:
        ins = instructions[iid]
        for kind, items in (("checks", ins.checks), ("aborts", ins.aborts)):
            for i, ch in enumerate(items):
                p = ("instruction", kind, i)
                if complete and codes and ch.err not in codes:
                    b.error(f, (*p, "err"), f"error code {ch.err} is not in the error catalog (errors.yaml)")
                if complete and ch.exerr and (ins.mnemonic, ch.err, ch.exerr) not in ext_pairs:
                    b.error(f, (*p, "exerr"), f"extended error {ch.err}/{ch.exerr} of {ins.mnemonic} is not in extended_errors")
    if complete:
        for f in files:
            for i, n in enumerate(f.top.items("extended_errors", "extended_error")):
                mnemonics = {x.mnemonic for x in instructions.values()}
                if n["instruction"] not in mnemonics and instructions:
                    b.error(f, ("extended_errors", i, "instruction"), (
                        f"unknown instruction {n['instruction']!r}; instructions: {', '.join(sorted(mnemonics))}"))
    for interp_id, f, parts in b.interp_refs:
        b.used_interpretations.add(interp_id)
        if interp_id not in interp_where and complete:
            b.error(f, parts, f"unknown interpretation {interp_id!r}; add it to interpretations.yaml")
    for name, tree in cited_trees:
        for parts, interp_id in sources.interpretation_citations(tree):
            b.used_interpretations.add(interp_id)
            if interp_id not in interp_where and complete:
                line, col = locate(tree, parts)
                b.errors.append(Diagnostic(name, line, col, node_path(parts), (
                    f"the source cites unknown interpretation {interp_id!r}; add it to interpretations.yaml")))
    b.errors.extend(source_errors)
    if complete:
        for interp_id, (f, parts) in interp_where.items():
            if interp_id not in b.used_interpretations:
                b.error(f, (*parts, "id"), f"interpretation {interp_id} is not used by any spec element")

    if b.errors:
        raise SpecError(b.errors)
    assert tag_type is not None
    return ir.Spec(
        charts=tuple(charts[k] for k in sorted(charts)),
        instructions=tuple(instructions[k] for k in sorted(instructions)),
        tag_type=tag_type, tables=tuple(tables[k] for k in sorted(tables)),
        errors=tuple(sorted(errors, key=lambda e: e.code)),
        extended_errors=tuple(sorted(extended, key=lambda x: (x.instruction, x.err, x.exerr))),
        interpretations=tuple(sorted(interpretations, key=lambda i: i.id)),
        files=tuple(f.name for f in files),
        add_ons=tuple(add_ons[k] for k in sorted(add_ons)),
    )
