"""Properties as data: invariants, reachability goals, deadlock freedom, bounded response, coverage.

Pipeline position: ``spec/properties/*.yaml`` -> **checker.properties** -> :mod:`checker.model`
(evaluation during the search) and :mod:`checker.report` (verdicts).

A properties file (``format: motionchart-properties/1``, schema
``spec/schema/properties.schema.json``) lists properties of five kinds:

``invariant``
    ``holds`` is true in every reachable state, for every axis (``scope: axis``) or
    every instruction tag (``scope: tag``) matching the optional ``chart`` /
    ``instruction`` / ``where`` filters.
``reachable``
    some reachable state has an axis or tag for which ``goal`` is true.
``deadlock_free``
    every reachable state has a successor other than itself.
``response``
    bounded response in scans, per tag: once ``trigger`` holds, ``response`` holds within
    ``within`` scans (counting the scan in which the trigger was first seen) unless
    ``unless`` holds first; the obligation lapses when the trigger stops holding and is
    discharged until then once the response or the exception was seen.
``cover``
    every chart state / transition / documented error code / instruction x axis-state
    cell / value of a ``variable`` is reached, except the items listed under
    ``unreachable``, each with the reason it cannot occur.

Expressions use the spec expression language (:mod:`statecharts.expr`; never ``eval``).
Names in ``scope: axis``: the chart's variables, its state attribute, ``state`` (the
leaf state id), ``active`` (the set of active state ids), ``axis`` (the axis name).
Names in ``scope: tag``: the MOTION_INSTRUCTION members and internal variables,
``rung``, ``queued``, ``instruction`` (the mnemonic), ``tag`` (its name) and the
``axis.X`` names that instruction checks use.  Every problem is reported with its
file, line and node path.
"""

from __future__ import annotations

import ast
import difflib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from statecharts import ir
from statecharts.diagnostics import Diagnostic, InputError, locate, node_path
from statecharts.expr import Expr, ExprError, check_names, parse_expression
from statecharts.loader import AXIS_READ_ONLY, bundled_spec_dir, plain_data, read_yaml, schema_diagnostics

PROPERTIES_FORMAT = "motionchart-properties/1"
KINDS = ("invariant", "reachable", "deadlock_free", "response", "cover")
COVER_TARGETS = ("states", "transitions", "error_codes", "cells", "values")


class PropertyError(InputError):
    """A properties file is malformed."""


@dataclass(frozen=True, slots=True)
class Unreachable:
    """A coverage item that cannot occur, with the reason (recorded as data)."""

    item: str
    reason: str
    source: str


@dataclass(frozen=True, slots=True)
class Property:
    name: str
    kind: str
    description: str
    source: str
    file: str
    line: int
    scope: str | None = None  # "axis" | "tag"
    chart: str | None = None
    instruction: str | None = None
    where: Expr | None = None
    holds: Expr | None = None  # invariant
    goal: Expr | None = None  # reachable
    trigger: Expr | None = None  # response
    response: Expr | None = None
    unless: Expr | None = None
    within: int = 1
    cover: str | None = None
    variable: str | None = None
    unreachable: tuple[Unreachable, ...] = ()
    #: the systems the property is checked on (empty: every system with its chart)
    systems: tuple[str, ...] = ()

    def names(self) -> frozenset[str]:
        """Every name the property's expressions read."""
        out: set[str] = set()
        for e in (self.where, self.holds, self.goal, self.trigger, self.response, self.unless):
            if e is not None:
                out |= e.names
        if self.variable:
            out.add(self.variable)
        return frozenset(out)

    def applies_to_axis(self, chart: ir.Chart) -> bool:
        return self.chart is None or self.chart == chart.id

    def applies_to_tag(self, instruction: ir.Instruction, chart: ir.Chart) -> bool:
        return (self.instruction is None or self.instruction == instruction.id) and (
            self.chart is None or self.chart == chart.id
        )


def properties_dir() -> Path:
    return bundled_spec_dir() / "properties"


def properties_schema() -> dict[str, Any]:
    import json

    schema: dict[str, Any] = json.loads((bundled_spec_dir() / "schema" / "properties.schema.json").read_text("utf-8"))
    return schema


def axis_names(chart: ir.Chart) -> set[str]:
    return {v.name for v in chart.variables} | {chart.state_attribute, "state", "active", "axis"}


def tag_names(spec: ir.Spec, charts: Sequence[ir.Chart]) -> set[str]:
    names = {m.name for m in spec.tag_type.members} | {v.name for v in spec.tag_type.internal}
    names |= {"rung", "queued", "instruction", "tag"}
    for c in charts:
        names |= {f"axis.{v.name}" for v in c.variables}
        names |= {f"axis.{c.state_attribute}"} | {f"axis.{x}" for x in AXIS_READ_ONLY}
    return names


def add_on_names(spec: ir.Spec, add_ons: Sequence[ir.AddOnInstruction]) -> set[str]:
    """Names in ``scope: add_on``: an instance's parameters, status members, local tags,
    recovery ``state``, ``rung``, ``tag``, what its checks read (``registered``,
    ``distance.magnitude``, ``move.type``, ``move.target``, ``call.done``, ``<REAL>.finite``)
    and the ``world:`` facts and chart variables of the objects its InOut parameters name
    (``phy.faulted``, ``phy.GearingStatus``, ``handler.mode``)."""
    names = {"state", "rung", "tag", "registered", "distance.magnitude", "move.type", "move.target", "call.done"}
    for ao in add_ons:
        names |= {p.name for p in ao.parameters} | {m.name for m in ao.status} | {v.name for v in ao.local_tags}
        names |= {f"{p.name}.finite" for p in ao.parameters if p.type == "REAL"}
        facts = {f.name for o in ao.world.objects for f in o.facts} | {"name"}
        charts = {c.id: c for c in spec.charts}
        for o in ao.world.objects:
            if o.chart in charts:
                facts |= {cp.name for cp in charts[o.chart].parameters} | {v.name for v in charts[o.chart].variables}
        names |= {f"{p.alias}.{f}" for p in ao.parameters if p.alias for f in facts}
    return names


def property_files(paths: Sequence[Path | str] | None = None) -> list[Path]:
    roots = [Path(p) for p in paths] if paths else [properties_dir()]
    out: list[Path] = []
    for r in roots:
        if r.is_dir():
            out.extend(sorted(p for p in r.iterdir() if p.suffix in (".yaml", ".yml") and p.is_file()))
        else:
            out.append(r)
    return out


def load_properties(spec: ir.Spec, paths: Sequence[Path | str] | None = None) -> tuple[Property, ...]:
    """Read and check property files (default: the bundled ones); raise PropertyError with every problem."""
    errors: list[Diagnostic] = []
    out: list[Property] = []
    seen: dict[str, str] = {}
    for path in property_files(paths):
        name = str(path)
        tree = read_yaml(path, errors, what="properties file")
        if tree is None:
            if not any(d.file == name for d in errors):
                errors.append(Diagnostic(name, 1, 1, "", f"empty file; expected `format: {PROPERTIES_FORMAT}`"))
            continue
        problems = schema_diagnostics(name, tree, properties_schema(), "a properties file")
        if problems:
            errors.extend(problems)
            continue
        doc = plain_data(tree)
        for i, node in enumerate(doc["properties"]):
            parts: tuple[Any, ...] = ("properties", i)
            prop = _build(spec, name, tree, parts, node, errors)
            if prop is None:
                continue
            if prop.name in seen:
                line, col = locate(tree, (*parts, "name"))
                errors.append(Diagnostic(name, line, col, node_path((*parts, "name")),
                                         f"duplicate property name {prop.name!r} (first in {seen[prop.name]})"))
                continue
            seen[prop.name] = name
            out.append(prop)
    if errors:
        raise PropertyError(errors)
    return tuple(out)


_NEEDS: dict[str, tuple[str, ...]] = {
    "invariant": ("scope", "holds"),
    "reachable": ("scope", "goal"),
    "deadlock_free": (),
    "response": ("trigger", "response", "within"),
    "cover": ("cover",),
}


def _build(
    spec: ir.Spec, file: str, tree: Any, parts: tuple[Any, ...], node: dict[str, Any], errors: list[Diagnostic]
) -> Property | None:
    def err(sub: tuple[Any, ...], message: str) -> None:
        line, col = locate(tree, (*parts, *sub))
        errors.append(Diagnostic(file, line, col, node_path((*parts, *sub)), message))

    before = len(errors)
    kind = node["kind"]
    for key in _NEEDS[kind]:
        if key not in node:
            err((), f"a {kind} property needs `{key}`")
    scope = node.get("scope")
    if kind == "response":
        if scope not in (None, "tag"):
            err(("scope",), "a response property is about instruction tags: `scope: tag`")
        scope = "tag"
    charts = list(spec.charts)
    if "chart" in node:
        try:
            charts = [spec.chart(node["chart"])]
        except KeyError:
            err(("chart",), f"unknown chart {node['chart']!r}; charts: {', '.join(c.id for c in spec.charts)}")
    add_ons = list(spec.add_ons)
    if "instruction" in node and scope == "add_on":
        add_ons = [a for a in spec.add_ons if a.id == node["instruction"]]
        if not add_ons:
            err(("instruction",), f"unknown add-on instruction {node['instruction']!r}; the spec defines: "
                                  f"{', '.join(a.id for a in spec.add_ons) or '(none)'}")
    elif "instruction" in node:
        try:
            ins = spec.instruction(node["instruction"])
            charts = [c for c in charts if c.id in ins.charts]
        except KeyError:
            err(("instruction",), f"unknown instruction {node['instruction']!r}")
        if scope == "axis":
            err(("instruction",), "`instruction` filters tags; use it with `scope: tag`")
    known: set[str]
    if scope == "add_on":
        known = add_on_names(spec, add_ons)
        if "chart" in node:
            err(("chart",), "`chart` filters axes and tags; an add-on instruction property names its objects "
                            "through its parameters (phy., pth., handler.)")
    elif scope == "axis":
        known = set()
        for c in charts:
            known |= axis_names(c)
    else:
        known = tag_names(spec, charts)

    def expr(key: str) -> Expr | None:
        if key not in node:
            return None
        text = str(node[key])
        try:
            e = parse_expression(text)
        except ExprError as exc:
            err((key,), f"{exc.message} (at character {exc.offset + 1} of {text!r})")
            return None
        unknown = check_names(e, known)
        for n, _off in unknown:
            err((key,), f"unknown name {n!r} in {text!r} for scope {scope}; known: {', '.join(sorted(known))}")
        states = sorted({st.id for c in charts for st in c.leaf_states()})
        if scope == "add_on":
            states = sorted({st.id for a in add_ons for st in a.recovery.states} | {"error"})
        bad = [lit for lit in state_literals(text) if lit not in states]
        for lit in bad:
            hint = difflib.get_close_matches(lit, states, n=1, cutoff=0.6)
            did = f" (did you mean {hint[0]!r}?)" if hint else ""
            err((key,), f"{text!r} compares the state with {lit!r}, which is no leaf state{did}; states: {', '.join(states)}")
        return e if not unknown and not bad else None

    cover = node.get("cover")
    variable = node.get("variable")
    if cover == "values":
        if not variable:
            err((), "`cover: values` needs `variable:` (a chart variable with a finite domain)")
        else:
            found = [c.variable(variable) for c in charts if variable in {v.name for v in c.variables}]
            if not found:
                err(("variable",), f"no chart has a variable {variable!r}")
            elif found[0].domain is None:
                err(("variable",), f"{variable} has no finite domain to cover")
    unreachable = tuple(
        Unreachable(str(u["item"]), " ".join(str(u["reason"]).split()), str(u.get("source", "")))
        for u in node.get("unreachable", [])
    )
    if unreachable and kind != "cover":
        err(("unreachable",), "`unreachable` explains coverage items; use it with `kind: cover`")
    prop = Property(
        name=node["name"], kind=kind, description=" ".join(str(node.get("description", "")).split()),
        source=str(node["source"]), file=file, line=locate(tree, parts)[0], scope=scope,
        chart=node.get("chart"), instruction=node.get("instruction"), where=expr("where"), holds=expr("holds"),
        goal=expr("goal"), trigger=expr("trigger"), response=expr("response"), unless=expr("unless"),
        within=int(node.get("within", 1)), cover=cover, variable=variable, unreachable=unreachable,
        systems=tuple(str(x) for x in node.get("systems", ())),
    )
    return prop if len(errors) == before else None


def state_literals(text: str) -> list[str]:
    """The strings an expression compares ``state`` (or ``axis.state``) with."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return []
    out: list[str] = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Compare):
            continue
        operands = [node.left, *node.comparators]
        if not any(ast.unparse(o) in ("state", "axis.state") for o in operands):
            continue
        for o in operands:
            if isinstance(o, ast.Constant) and isinstance(o.value, str):
                out.append(o.value)
            elif isinstance(o, (ast.Tuple, ast.List, ast.Set)):
                out.extend(x.value for x in o.elts if isinstance(x, ast.Constant) and isinstance(x.value, str))
    return out

