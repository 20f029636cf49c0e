"""Load a motionchart specification: YAML -> JSON Schema -> semantic checks -> frozen IR.

Pipeline position: first stage.  :func:`load_spec` reads every ``*.yaml`` file of the
spec (the bundled one by default), validates each against the shipped JSON Schema,
resolves references across files, parses every guard, check and action with the
expression language, runs the semantic checks (unknown targets and variables,
duplicate ids, unreachable states, overlapping guards without a priority, unknown
interpretations and error codes), and returns a :class:`~statecharts.ir.Spec`.

All problems of all files are collected and raised together as one
:class:`~statecharts.diagnostics.SpecError`; nothing downstream ever sees YAML.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
from ruamel.yaml import YAML
from ruamel.yaml.error import MarkedYAMLError, YAMLError

from statecharts import ir
from statecharts.diagnostics import Diagnostic, SpecError, locate, node_path
from statecharts.expr import Assignment, Expr, ExprError, check_names, parse_assignment, parse_expression

SPEC_FORMAT = "motionchart-spec/1"
MAX_FILE_BYTES = 2_000_000

#: Names every axis-chart expression may read besides the chart's own variables.
SYSTEM_PARAMETERS: dict[str, tuple[int, ...]] = {"coarse_update_ms": (10,), "scan_ms": (10,)}
#: Axis attributes that instructions may read but never assign.
AXIS_READ_ONLY = ("active", "state", "chart")
#: Largest number of variable assignments enumerated to show two guards disjoint.
OVERLAP_ENUMERATION_LIMIT = 20_000


def bundled_spec_dir() -> Path:
    """The spec shipped with the package (``spec/`` in a checkout, package data in a wheel)."""
    return Path(str(resources.files("motionchart_spec")))


def spec_schema() -> dict[str, Any]:
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


def _plain(node: Any) -> Any:
    """ruamel round-trip tree -> plain dicts/lists (for the JSON Schema validator)."""
    if isinstance(node, dict):
        return {str(k): _plain(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_plain(v) for v in node]
    if isinstance(node, str):
        return str(node)
    if isinstance(node, bool):
        return bool(node)
    if isinstance(node, int):
        return int(node)
    if isinstance(node, float):
        return float(node)
    return node


def read_yaml(path: Path, errors: list[Diagnostic], *, what: str = "file") -> Any | None:
    """Parse one YAML file; a syntax error becomes a located diagnostic, never a traceback."""
    name = str(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        errors.append(Diagnostic(name, 1, 1, "", f"cannot read {what}: {exc.strerror or exc}"))
        return None
    if len(raw) > MAX_FILE_BYTES:
        errors.append(Diagnostic(name, 1, 1, "", f"{what} is larger than {MAX_FILE_BYTES} bytes"))
        return None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        errors.append(Diagnostic(name, 1, 1, "", f"{what} is not UTF-8 text ({exc.reason} at byte {exc.start})"))
        return None
    yaml = YAML(typ="rt")
    try:
        return yaml.load(text)
    except MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
        problem = exc.problem or exc.context or "invalid YAML"
        errors.append(Diagnostic(name, line, col, "", f"YAML syntax error: {problem}"))
    except (YAMLError, ValueError, TypeError, RecursionError) as exc:
        errors.append(Diagnostic(name, 1, 1, "", f"YAML error: {exc}"))
    return None


def schema_diagnostics(
    name: str, tree: Any, schema: dict[str, Any], what: str
) -> list[Diagnostic]:
    """Validate ``tree`` against ``schema``; each violation located at its node."""
    validator = jsonschema.Draft202012Validator(schema)
    out = []
    for err in validator.iter_errors(_plain(tree)):
        parts = tuple(err.absolute_path)
        line, col = locate(tree, parts)
        message = err.message
        if err.validator == "additionalProperties":
            allowed = sorted(err.schema.get("properties", {}))
            message = f"{err.message}; expected one of: {', '.join(allowed)}"
        elif err.validator == "required":
            message = f"{err.message} in {what}"
        out.append(Diagnostic(name, line, col, node_path(parts) or "(document)", message))
    return out


# --------------------------------------------------------------------------- building


@dataclass
class _File:
    name: str
    tree: Any


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

    def prov(self, f: _File, parts: tuple[Any, ...], node: dict[str, Any]) -> ir.Provenance:
        interp = node.get("interpretation")
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
            hint = _closest(name, known_set)
            extra = f"; did you mean {hint!r}?" if hint else ""
            self.error(f, parts, f"unknown variable {name!r} in {e.text!r}{extra}")

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

    def duplicates(self, f: _File, parts: tuple[Any, ...], items: Sequence[dict[str, Any]], key: str, what: str) -> None:
        seen: dict[Any, int] = {}
        for i, item in enumerate(items):
            k = item.get(key)
            if k in seen:
                self.error(f, (*parts, i, key), f"duplicate {what} {k!r} (first defined at item {seen[k]})")
            else:
                seen[k] = i

    # -- variables -----------------------------------------------------------

    def variable(self, f: _File, parts: tuple[Any, ...], v: dict[str, Any]) -> ir.Variable:
        vtype = v["type"]
        domain = v.get("domain")
        initial = v["initial"]
        if vtype == "bool":
            domain = [False, True]
            if not isinstance(initial, bool):
                self.error(f, (*parts, "initial"), f"initial value {initial!r} is not a bool")
        elif vtype == "enum":
            if not domain:
                self.error(f, parts, "an enum variable needs a domain")
                domain = [initial]
        elif vtype == "int":
            if domain is None and "range" in v:
                lo, hi = int(v["range"][0]), int(v["range"][1])
                if hi < lo:
                    self.error(f, (*parts, "range"), f"empty range [{lo}, {hi}]")
                domain = list(range(lo, hi + 1)) if hi - lo <= 4096 else None
        if domain is not None and initial not in domain:
            self.error(f, (*parts, "initial"), f"initial value {initial!r} is not in the domain {list(domain)!r}")
        return ir.Variable(
            name=v["name"], type=vtype, initial=initial,
            domain=tuple(domain) if domain is not None else None,
            description=str(v.get("description", "")), provenance=self.prov(f, parts, v),
            location=self.loc(f, parts),
        )

    # -- charts --------------------------------------------------------------

    def chart(self, f: _File, c: dict[str, Any]) -> ir.Chart | None:
        base: tuple[Any, ...] = ("chart",)
        var_nodes = list(c.get("variables", []))
        self.duplicates(f, (*base, "variables"), var_nodes, "name", "variable")
        variables = tuple(self.variable(f, (*base, "variables", i), v) for i, v in enumerate(var_nodes))
        var_names = [v.name for v in variables]
        known = var_names + list(SYSTEM_PARAMETERS)

        event_nodes = list(c.get("events", []))
        self.duplicates(f, (*base, "events"), event_nodes, "name", "event")
        events = []
        for i, e in enumerate(event_nodes):
            p = (*base, "events", i)
            events.append(ir.Event(
                name=e["name"], kind=e["kind"], description=str(e.get("description", "")),
                parameters=tuple(e.get("parameters", [])),
                actions=self.actions(f, (*p, "actions"), e.get("actions"), known, var_names),
                provenance=self.prov(f, p, e),
            ))
        event_names = {e.name for e in events}

        states: list[ir.State] = []
        state_nodes: dict[str, tuple[Any, ...]] = {}

        def walk(nodes: Sequence[dict[str, Any]], parts: tuple[Any, ...], parent: str | None) -> list[str]:
            ids = []
            for i, s in enumerate(nodes):
                p = (*parts, i)
                sid = s["id"]
                if sid in state_nodes:
                    self.error(f, (*p, "id"), f"duplicate state id {sid!r}")
                    continue
                state_nodes[sid] = p
                children_nodes = list(s.get("states", []))
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
                        self.error(f, p, "a compound state must name its initial child (`initial:`)")
                    elif initial not in children:
                        self.error(f, (*p, "initial"), f"initial {initial!r} is not a child of {sid!r}; children: {', '.join(children)}")
                elif initial is not None:
                    self.error(f, (*p, "initial"), f"only a compound state has an initial child ({sid!r} is {kind_name})")
                if kind is ir.StateKind.HISTORY and "history" not in s:
                    self.error(f, p, "a history state must say `history: shallow` or `history: deep`")
                states.append(ir.State(
                    id=sid, name=str(s.get("name", sid)), kind=kind, value=s.get("value"),
                    parent=parent, children=tuple(children),
                    initial=initial if kind is ir.StateKind.COMPOUND else None,
                    history_type=s.get("history"),
                    entry=self.actions(f, (*p, "entry"), s.get("entry"), known, var_names),
                    exit=self.actions(f, (*p, "exit"), s.get("exit"), known, var_names),
                    description=str(s.get("description", "")),
                    provenance=self.prov(f, p, s), location=self.loc(f, p),
                ))
                ids.append(sid)
            return ids

        top = walk(list(c["states"]), (*base, "states"), None)
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
            self.error(f, (*base, "initial"), f"initial {root_initial!r} is not a top-level state")

        trans_nodes = list(c.get("transitions", []))
        self.duplicates(f, (*base, "transitions"), trans_nodes, "id", "transition")
        transitions = []
        for i, t in enumerate(trans_nodes):
            p = (*base, "transitions", i)
            src, dst, ev = t["from"], t.get("to"), t.get("event")
            if src not in by_id:
                self.error(f, (*p, "from"), f"unknown source state {src!r}; states: {', '.join(sorted(by_id))}")
            if dst is not None and dst not in by_id:
                self.error(f, (*p, "to"), f"unknown target state {dst!r}; states: {', '.join(sorted(by_id))}")
            if ev is not None and ev not in event_names:
                self.error(f, (*p, "event"), f"unknown event {ev!r}; declare it under chart.events (events: {', '.join(sorted(event_names))})")
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

        chart = ir.Chart(
            id=c["id"], name=c["name"], kind=ir.ChartKind(c["kind"]), state_attribute=c["state_attribute"],
            axis_types=tuple(c["axis_types"]), variables=variables, events=tuple(events),
            states=tuple(states), transitions=tuple(transitions), root_initial=root_initial,
            description=str(c.get("description", "")), provenance=self.prov(f, base, c), location=self.loc(f, base),
        )
        if any(d.file == f.name for d in self.errors):
            return chart
        self._reachability(f, chart, state_nodes)
        self._overlaps(f, chart)
        return chart

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
        self, f: _File, node: dict[str, Any], charts: dict[str, ir.Chart], tables: dict[str, ir.ExecutionTable],
        tag_type: ir.TagType | None,
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

        op_nodes = list(node["operands"])
        self.duplicates(f, (*base, "operands"), op_nodes, "name", "operand")
        operands = []
        for i, o in enumerate(op_nodes):
            p = (*base, "operands", i)
            operands.append(ir.Operand(
                name=o["name"], type=o["type"], domain=tuple(o["domain"]) if "domain" in o else None,
                range=(float(o["range"][0]), float(o["range"][1])) if "range" in o else None,
                text_values=tuple(sorted(dict(o.get("text_values", {})).items())), default=o.get("default"),
                description=str(o.get("description", "")), provenance=self.prov(f, p, o),
            ))
        known_ops = [f"op.{o.name}" for o in operands if o.type not in ("axis", "tag")]
        known = known_axis + known_ops

        check_nodes = list(node["checks"])
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
        for i, ab in enumerate(node.get("aborts", [])):
            p = (*base, "aborts", i)
            e = self.expr(f, (*p, "when"), ab["when"], known)
            aborts.append(ir.Check(
                id=ab["id"], fails_when=e if e is not None else _NEVER, err=int(ab["err"]),
                exerr=int(ab.get("exerr", 0)), stage=ir.Stage.MESSAGE,
                description=str(ab.get("description", "")), provenance=self.prov(f, p, ab), location=self.loc(f, p),
            ))

        request = None
        if "request" in node:
            r = node["request"]
            for c in chart_list:
                if r["event"] not in {e.name for e in c.events if e.kind == "request"}:
                    self.error(f, (*base, "request", "event"), f"chart {c.id!r} declares no request event {r['event']!r}")
            request = ir.Request(
                event=r["event"],
                actions=self.actions(f, (*base, "request", "actions"), r.get("actions"), known, writable_axis),
            )
        done = node["done"]
        done_when = self.expr(f, (*base, "done", "when"), done["when"], known) if "when" in done else None
        self.prov(f, (*base, "done"), done)

        table_id = node["execution_table"]
        table = tables.get(table_id)
        if table is None:
            self.error(f, (*base, "execution_table"), f"unknown execution table {table_id!r}; tables: {', '.join(sorted(tables))}")
            table = _EMPTY_TABLE
        all_vars = set(axis_vars)
        for i, (bit, _value) in enumerate(dict(node.get("status_bits", {})).items()):
            if bit not in all_vars:
                self.error(f, (*base, "status_bits"), f"unknown status bit {bit!r}")
        return ir.Instruction(
            id=node["id"], name=node["name"], charts=tuple(c.id for c in chart_list),
            axis_types=tuple(node["axis_types"]), operands=tuple(operands), execution=node["execution"],
            table=table, checks=tuple(checks), aborts=tuple(aborts), request=request, done_when=done_when,
            status_bits=tuple(sorted(dict(node.get("status_bits", {})).items())),
            description=str(node.get("description", "")), provenance=self.prov(f, base, node),
            done_provenance=ir.Provenance(str(done["source"]), done.get("interpretation")),
            location=self.loc(f, base),
        )

    def tag_type(self, f: _File, node: dict[str, Any]) -> ir.TagType:
        base: tuple[Any, ...] = ("tag_type",)
        self.duplicates(f, (*base, "members"), list(node["members"]), "name", "member")
        members = tuple(
            ir.TagMember(
                name=m["name"], type=m["type"], bit=m.get("bit"), description=str(m.get("description", "")),
                provenance=self.prov(f, (*base, "members", i), m),
            )
            for i, m in enumerate(node["members"])
        )
        internal = tuple(self.variable(f, (*base, "internal", i), v) for i, v in enumerate(node.get("internal", [])))
        return ir.TagType(name=node["name"], members=members, internal=internal, provenance=self.prov(f, base, node))

    def table(self, f: _File, parts: tuple[Any, ...], node: dict[str, Any], tag_type: ir.TagType) -> ir.ExecutionTable:
        names = [m.name for m in tag_type.members] + [v.name for v in tag_type.internal]
        rows = []
        self.duplicates(f, (*parts, "rows"), list(node["rows"]), "condition", "row for condition")
        for i, r in enumerate(node["rows"]):
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
            self.prov(f, (*parts, key), node[key])
            return self.actions(f, (*parts, key, "actions"), node[key]["actions"], names, names)

        return ir.ExecutionTable(
            id=node["id"], rows=tuple(rows), on_execute=block("on_execute"), on_error=block("on_error"),
            on_accept=block("on_accept"), on_done=block("on_done"), provenance=self.prov(f, parts, node),
        )


_NEVER = parse_expression("False")
_EMPTY_TABLE = ir.ExecutionTable("", (), (), (), (), (), ir.Provenance(""))


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
        except Exception:  # noqa: BLE001 - a guard failing on some value cannot prove disjointness
            return None, False
    return None, True


def _closest(name: str, known: set[str]) -> str | None:
    import difflib

    match = difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.75)
    return match[0] if match else None


# --------------------------------------------------------------------------- entry point


def load_spec(paths: Sequence[Path | str] | None = None) -> ir.Spec:
    """Load, validate and build the specification; raise SpecError with every problem found."""
    schema = spec_schema()
    b = _Builder()
    files: list[_File] = []
    for path in spec_files(paths):
        if path.suffix == ".json" or path.parent.name == "schema":
            continue
        tree = read_yaml(path, b.errors)
        if tree is None:
            if not any(d.file == str(path) for d in b.errors):
                b.errors.append(Diagnostic(str(path), 1, 1, "", "empty file; expected a mapping with `format: motionchart-spec/1`"))
            continue
        problems = schema_diagnostics(str(path), tree, schema, "a spec file")
        b.errors.extend(problems)
        if not problems:
            files.append(_File(str(path), tree))
    if not files and not b.errors:
        b.errors.append(Diagnostic(str(paths[0]) if paths else "spec", 1, 1, "", "no spec files (*.yaml) found"))

    interpretations: list[ir.Interpretation] = []
    interp_where: dict[str, tuple[_File, tuple[Any, ...]]] = {}
    errors: list[ir.ErrorCode] = []
    extended: list[ir.ExtendedError] = []
    tag_type: ir.TagType | None = None
    for f in files:
        t = f.tree
        for i, n in enumerate(t.get("interpretations", [])):
            if n["id"] in interp_where:
                b.error(f, ("interpretations", i, "id"), f"duplicate interpretation {n['id']!r}")
                continue
            interp_where[n["id"]] = (f, ("interpretations", i))
            interpretations.append(ir.Interpretation(
                id=n["id"], title=n["title"], text=" ".join(str(n["text"]).split()),
                confidence=ir.Confidence(n["confidence"]), evidence=tuple(n["evidence"]),
            ))
        codes_seen: set[int] = set()
        for i, n in enumerate(t.get("errors", [])):
            if n["code"] in codes_seen:
                b.error(f, ("errors", i, "code"), f"duplicate error code {n['code']}")
            codes_seen.add(n["code"])
            errors.append(ir.ErrorCode(n["code"], n["name"], n["meaning"], ir.Confidence(n["confidence"]), b.prov(f, ("errors", i), n)))
        for i, n in enumerate(t.get("extended_errors", [])):
            extended.append(ir.ExtendedError(
                n["instruction"], n["err"], n["exerr"], n["name"], n["meaning"], ir.Confidence(n["confidence"]),
                b.prov(f, ("extended_errors", i), n),
            ))
        if "tag_type" in t:
            if tag_type is not None:
                b.error(f, ("tag_type",), "the MOTION_INSTRUCTION tag type is defined twice")
            tag_type = b.tag_type(f, t["tag_type"])

    tables: dict[str, ir.ExecutionTable] = {}
    if tag_type is None and files:
        b.errors.append(Diagnostic(files[0].name, 1, 1, "", "no file defines `tag_type` (the MOTION_INSTRUCTION data type)"))
    for f in files:
        for i, n in enumerate(f.tree.get("execution_tables", [])):
            if n["id"] in tables:
                b.error(f, ("execution_tables", i, "id"), f"duplicate execution table {n['id']!r}")
            elif tag_type is not None:
                tables[n["id"]] = b.table(f, ("execution_tables", i), n, tag_type)

    charts: dict[str, ir.Chart] = {}
    for f in files:
        if "chart" in f.tree:
            cid = f.tree["chart"]["id"]
            if cid in charts:
                b.error(f, ("chart", "id"), f"duplicate chart id {cid!r}")
                continue
            chart = b.chart(f, f.tree["chart"])
            if chart is not None:
                charts[cid] = chart

    instructions: dict[str, ir.Instruction] = {}
    for f in files:
        if "instruction" in f.tree:
            iid = f.tree["instruction"]["id"]
            if iid in instructions:
                b.error(f, ("instruction", "id"), f"duplicate instruction {iid!r}")
                continue
            instructions[iid] = b.instruction(f, f.tree["instruction"], charts, tables, tag_type)

    # cross-file references: error codes and interpretations
    codes = {e.code for e in errors}
    ext_pairs = {(x.instruction, x.err, x.exerr) for x in extended}
    for f in files:
        if "instruction" not in f.tree:
            continue
        ins = instructions.get(f.tree["instruction"]["id"])
        if ins is None:
            continue
        for kind, items in (("checks", ins.checks), ("aborts", ins.aborts)):
            for i, ch in enumerate(items):
                p = ("instruction", kind, i)
                if codes and ch.err not in codes:
                    b.error(f, (*p, "err"), f"error code {ch.err} is not in the error catalog (errors.yaml)")
                if ch.exerr and (ins.id, ch.err, ch.exerr) not in ext_pairs:
                    b.error(f, (*p, "exerr"), f"extended error {ch.err}/{ch.exerr} of {ins.id} is not in extended_errors")
    for f in files:
        for i, n in enumerate(f.tree.get("extended_errors", [])):
            if n["instruction"] not in instructions and instructions:
                b.error(f, ("extended_errors", i, "instruction"), f"unknown instruction {n['instruction']!r}")
    for interp_id, f, parts in b.interp_refs:
        b.used_interpretations.add(interp_id)
        if interp_id not in interp_where:
            b.error(f, parts, f"unknown interpretation {interp_id!r}; add it to interpretations.yaml")
    for interp_id, (f, parts) in interp_where.items():
        if interp_id not in b.used_interpretations:
            b.error(f, parts, f"interpretation {interp_id} is not used by any spec element")

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
    )
