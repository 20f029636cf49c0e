"""Build an ``add_on_instruction`` section of a spec file into :class:`statecharts.ir.AddOnInstruction`,
and the motion instructions its recovery calls (``format: motionchart-subinstruction/1``).

Pipeline position: called by :func:`statecharts.loader.load_spec` (same builder, same
diagnostics, same SpecError) for every spec file with an ``add_on_instruction:``
section; the schema has already accepted its shape.  Here: duplicate ids, unknown
codes, states, charts, events and variables, and every expression parsed against the
names it may read (the parameters, ``<REAL parameter>.finite``, the local tags, the
facts of the world's objects by alias, the motion numbers and the rotary arithmetic).

The sub-instruction files (``spec/instructions/motion/``) are checked here too, by the
same load: their schema, their check expressions, one file per mnemonic, and every call
of an add-on instruction naming one of them.  Every command loads the spec through
:func:`statecharts.loader.load_spec`, so a spec ``motionchart validate`` rejects is
rejected by every command, with the same located diagnostics.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, cast

from statecharts import ir
from statecharts.diagnostics import Diagnostic, locate, node_path
from statecharts.expr import Expr, ExprError, check_names, parse_expression

# ``b`` is the spec loader's builder (error, loc, prov, expr, variable, duplicates), ``f`` the
# file being built and nodes the loader's key-checked mappings: typed Any here because they
# are the loader's own classes.

#: What an axis parameter offers besides its chart facts: the motion numbers and configuration.
AXIS_NAMES = ("type", "position", "velocity", "unwind", "homed", "energized", "faulted", "shutdown", "control_mode",
              "direct_control", "home_config_ok", "home_position", "homing", "rotary", "geared", "name")
#: What the handle parameter offers besides its chart facts (its instance parameters are added).
HANDLER_NAMES = ("eState", "mode", "OnPath")
#: Names of the rotary arithmetic and of the call in process.
DERIVED_NAMES = ("distance.magnitude", "move.type", "move.target", "call.done", "registered")
#: The motions the drive model carries out for a recovery call.
MOTION_CALLS = ("MAH", "MAM", "MAG", "MRP", "MAS")
#: Facts the world reads from every object of a chart kind.
REQUIRED_FACTS = {ir.ChartKind.AXIS: ("faulted", "shutdown", "energized", "tracking", "starting"),
                  ir.ChartKind.HANDLER: ("eState", "mode", "OnPath", "registered", "capacity")}
#: States every recovery chart has: waiting for the rung, running the checks, finished.
RECOVERY_STATES = ("idle", "checking", "done")

_NEVER = parse_expression("False")


def build_add_on(b: Any, f: Any, node: Any, charts: dict[str, ir.Chart]) -> ir.AddOnInstruction:
    base: tuple[Any, ...] = ("add_on_instruction",)

    def at(*parts: Any) -> tuple[Any, ...]:
        return (*base, *parts)

    params = node.items("parameters", "addon_parameter")
    b.duplicates(f, at("parameters"), params, "name", "parameter")
    parameters = tuple(ir.AddOnParameter(
        p["name"], p["usage"], p["type"], p.get("data_type"), p.get("alias"), p.get("default"),
        str(p.get("description", "")), b.prov(f, at("parameters", i), p), b.loc(f, at("parameters", i)),
        tuple(p["values"]) if "values" in p else None)
        for i, p in enumerate(params))
    status_nodes = node.items("status", "status_member")
    b.duplicates(f, at("status"), status_nodes, "name", "status member")
    status = tuple(ir.StatusMember(m["name"], m["type"], str(m.get("description", "")),
                                   b.prov(f, at("status", i), m), b.loc(f, at("status", i)))
                   for i, m in enumerate(status_nodes))
    local_nodes = node.items("local_tags", "variable")
    b.duplicates(f, at("local_tags"), local_nodes, "name", "local tag")
    local_tags = tuple(b.variable(f, at("local_tags", i), v) for i, v in enumerate(local_nodes))
    error_nodes = node.items("errors", "addon_error")
    b.duplicates(f, at("errors"), error_nodes, "code", "error code")
    errors = tuple(ir.AddOnError(int(e["code"]), e["name"], str(e.get("description", "")),
                                 b.prov(f, at("errors", i), e), b.loc(f, at("errors", i)))
                   for i, e in enumerate(error_nodes))
    codes = {e.code for e in errors}

    world = _world(b, f, node.child("world", "world"), charts, at("world"))
    known = set(DERIVED_NAMES) | {t.name for t in local_tags}
    for par in parameters:
        known.add(par.name)
        if par.type == "REAL":
            known.add(f"{par.name}.finite")
        if par.alias is None:
            continue
        obj = next((o for o in world.objects if o.kind == (par.data_type if par.type == "axis" else "handler")), None)
        facts = {fa.name for fa in obj.facts} if obj else set()
        extra: set[str] = set(AXIS_NAMES) if par.type == "axis" else set(HANDLER_NAMES)
        if obj is not None and obj.chart in charts:
            extra |= {cp.name for cp in charts[obj.chart].parameters}
        known |= {f"{par.alias}.{n}" for n in facts | extra}

    check_nodes = node.items("checks", "check")
    b.duplicates(f, at("checks"), check_nodes, "id", "check")
    checks = []
    for i, ch in enumerate(check_nodes):
        p = at("checks", i)
        if int(ch["err"]) not in codes:
            b.error(f, (*p, "err"), f"code {ch['err']} is not in add_on_instruction.errors")
        e = b.expr(f, (*p, "fails_when"), ch["fails_when"], known)
        checks.append(ir.Check(ch["id"], e or _NEVER, int(ch["err"]), int(ch.get("exerr", 0)),
                               ir.Stage(ch.get("stage", "execute")), str(ch.get("description", "")),
                               b.prov(f, p, ch), b.loc(f, p)))

    aliases = {par.alias for par in parameters if par.type == "axis" and par.alias}
    callable_ = set(MOTION_CALLS)
    rec = node.child("recovery", "recovery")
    state_nodes = rec.items("states", "recovery_state")
    b.duplicates(f, at("recovery", "states"), state_nodes, "id", "recovery state")
    states = []
    for i, s in enumerate(state_nodes):
        p = at("recovery", "states", i)
        call = None
        if "call" in s:
            c = s.child("call", "recovery_call")
            if c["instruction"] not in callable_:
                b.error(f, (*p, "call", "instruction"), f"unknown sub-instruction {c['instruction']!r}; "
                                                        f"known: {', '.join(sorted(callable_))}")
            for key in ("axis", "master"):
                if key in c and c[key] not in aliases:
                    b.error(f, (*p, "call", key), f"{c[key]!r} is not the alias of an axis parameter "
                                                  f"({', '.join(sorted(aliases))})")
            ops: list[tuple[str, Expr]] = []
            for k, v in (c.get("operands") or {}).items():
                e = b.expr(f, (*p, "call", "operands", k), str(v), known)
                if e is not None:
                    ops.append((str(k), e))
            call = ir.RecoveryCall(c["instruction"], c["axis"], c.get("master"), tuple(ops))
            if "error" not in s:
                b.error(f, p, "a state with a call needs `error` (the code reported when the call errs)")
            elif int(s["error"]) not in codes:
                b.error(f, (*p, "error"), f"code {s['error']} is not in add_on_instruction.errors")
        states.append(ir.RecoveryState(s["id"], call, s.get("error"), str(s.get("description", "")),
                                       b.prov(f, p, s), b.loc(f, p)))
    ids = {s.id for s in states}
    for need in (*RECOVERY_STATES, rec["initial"]):
        if need not in ids:
            b.error(f, at("recovery", "states"), f"the recovery chart needs a state {need!r}")
    transitions = []
    for i, t in enumerate(rec.items("transitions", "recovery_transition")):
        p = at("recovery", "transitions", i)
        for key in ("from", "to"):
            if t[key] not in ids:
                b.error(f, (*p, key), f"unknown state {t[key]!r}")
        e = b.expr(f, (*p, "when"), t["when"], known)
        transitions.append(ir.RecoveryTransition(t["from"], t["to"], e or _NEVER, b.prov(f, p, t), b.loc(f, p)))
    recovery = ir.Recovery(rec["initial"], tuple(states), tuple(transitions), str(rec.get("description", "")),
                           b.prov(f, at("recovery"), rec), b.loc(f, at("recovery")))

    on_done = []
    for i, o in enumerate(node.items("on_done", "on_done")):
        e = b.expr(f, at("on_done", i, "when"), o["when"], known)
        on_done.append(ir.OnDone(e or _NEVER, o["set"], b.prov(f, at("on_done", i), o), b.loc(f, at("on_done", i))))
    member_names = {m.name for m in status}
    rules = []
    for key in ("rung_false", "prescan"):
        r = node.child(key, "scan_rule")
        for j, m in enumerate(r["clear"]):
            if m not in member_names:
                b.error(f, at(key, "clear", j), f"{m!r} is not a status member")
        for j, m in enumerate(r.get("forget") or ()):
            if m not in {t.name for t in local_tags}:
                b.error(f, at(key, "forget", j), f"{m!r} is not a local tag")
        if "abort_call" in r and r["abort_call"] not in callable_:
            b.error(f, at(key, "abort_call"), f"unknown sub-instruction {r['abort_call']!r}")
        rules.append(ir.ScanRule(tuple(r["clear"]), r.get("abort_call"), tuple(r.get("forget") or ()), "",
                                 b.prov(f, at(key), r), b.loc(f, at(key))))
    ex = node.child("execution", "execution")
    return ir.AddOnInstruction(
        id=node["id"], name=node["name"], execution=ir.Execution(ex["mode"], b.prov(f, at("execution"), ex), b.loc(f, at("execution"))),
        parameters=parameters, status=status, local_tags=local_tags, errors=errors, checks=tuple(checks),
        recovery=recovery, on_done=tuple(on_done), rung_false=rules[0], prescan=rules[1], world=world,
        description=str(node.get("description", "")), provenance=b.prov(f, base, node), location=b.loc(f, base),
    )


def _world(b: Any, f: Any, node: Any, charts: dict[str, ir.Chart], base: tuple[Any, ...]) -> ir.World:
    """The world: every chart, variable, event, state and fact name checked against the charts."""
    objects: list[ir.WorldObject] = []
    kinds: set[str] = set()
    for i, o in enumerate(node.items("objects", "world_object")):
        p = (*base, "objects", i)
        if o["kind"] in kinds:
            b.error(f, (*p, "kind"), f"a second binding for {o['kind']}")
        kinds.add(o["kind"])
        chart = charts.get(o["chart"])
        if chart is None:
            b.error(f, (*p, "chart"), f"unknown chart {o['chart']!r}; charts: {', '.join(sorted(charts))}")
            continue
        if any(st.kind is ir.StateKind.HISTORY for st in chart.states):
            b.error(f, (*p, "chart"), f"chart {chart.id} has history states; the world restores charts from "
                                      "snapshots, which do not hold history")
        variables = {v.name for v in chart.variables}
        events = {e.name for e in chart.events}
        states = {st.id for st in chart.states}
        names = variables | {"active", "state"}

        def event_ok(parts: tuple[Any, ...], ev: str, chart: ir.Chart = chart, events: set[str] = events) -> None:
            if ev not in events:
                b.error(f, parts, f"chart {chart.id} has no event {ev!r}; events: {', '.join(sorted(events))}")

        for key in ("on_scan", "stop", "register"):
            for j, ev in enumerate(o.get(key) or ()):
                event_ok((*p, key, j), ev)
        facts: list[ir.Fact] = []
        for j, fa in enumerate(o.items("facts", "fact")):
            q = (*p, "facts", j)
            if ("when" in fa) == ("variable" in fa):
                b.error(f, q, "a fact needs exactly one of `when` (an expression) and `variable` (a chart variable)")
                continue
            when = b.expr(f, (*q, "when"), fa["when"], names) if "when" in fa else None
            if "variable" in fa and fa["variable"] not in variables:
                b.error(f, (*q, "variable"), f"chart {chart.id} has no variable {fa['variable']!r}")
            sets = []
            for k, sv in enumerate(fa.items("set", "fact_set")):
                for m, ev in enumerate(sv["fire"]):
                    event_ok((*q, "set", k, "fire", m), ev)
                sets.append(ir.FactSet(sv["value"], tuple(sv["fire"])))
            facts.append(ir.Fact(fa["name"], when, fa.get("variable"), tuple(sets), b.prov(f, q, fa), b.loc(f, q)))
        fact_names = {fa.name for fa in facts}
        missing = [n for n in REQUIRED_FACTS[chart.kind] if n not in fact_names]
        if missing:
            b.error(f, (*p, "facts"), f"{o['kind']} needs the fact(s) {', '.join(missing)}")
        flags = set(HANDLER_NAMES) | {"registered", "capacity"} if chart.kind is ir.ChartKind.HANDLER else set(AXIS_NAMES)
        flags |= fact_names | {cp.name for cp in chart.parameters}

        def assignments(given: Any, parts: tuple[Any, ...], variables: set[str] = variables, chart: ir.Chart = chart,
                        flags: set[str] = flags) -> tuple[tuple[str, Expr], ...]:
            got = []
            for name, text in (given or {}).items():
                if name not in variables:
                    b.error(f, (*parts, name), f"chart {chart.id} has no variable {name!r}")
                    continue
                e = b.expr(f, (*parts, name), text, flags)
                if e is not None:
                    got.append((str(name), e))
            return tuple(got)

        setup = ir.WorldSetup((), (), ())
        if "setup" in o:
            su = o.child("setup", "world_setup")
            rules = []
            for j, r in enumerate(su.items("rules", "setup_rule")):
                q = (*p, "setup", "rules", j)
                if "state" in r and r["state"] not in states:
                    b.error(f, (*q, "state"), f"chart {chart.id} has no state {r['state']!r}")
                e = b.expr(f, (*q, "when"), r["when"], flags)
                rules.append(ir.SetupRule(e or _NEVER, r.get("state"), assignments(r.get("variables"), (*q, "variables"))))
            for j, name in enumerate(su.get("then_set") or ()):
                if name not in fact_names:
                    b.error(f, (*p, "setup", "then_set", j), f"{name!r} is not a fact of {o['kind']}")
            setup = ir.WorldSetup(assignments(su.get("variables"), (*p, "setup", "variables")), tuple(rules),
                                  tuple(su.get("then_set") or ()))
        objects.append(ir.WorldObject(o["kind"], chart.id, tuple(facts), tuple(o.get("on_scan") or ()),
                                      tuple(o.get("stop") or ()), tuple(o.get("register") or ()), setup,
                                      b.prov(f, p, o), b.loc(f, p)))
    return ir.World(tuple(objects), b.prov(f, base, node), b.loc(f, base))


# --------------------------------------------------------------------------- sub-instructions

SUB_FORMAT = "motionchart-subinstruction/1"
#: Names a sub-instruction's checks may read: the facts of its axis and master, its operands.
SUB_NAMES = frozenset({f"{a}.{k}" for a in ("axis", "master") for k in AXIS_NAMES}
                      | {"MoveType", "Speed", "Position", "Position.finite", "Speed.finite"})


@dataclass(frozen=True, slots=True)
class SubCheck:
    fails: Expr
    err: int
    provenance: ir.Provenance
    location: ir.Location


@dataclass(frozen=True, slots=True)
class SubInstruction:
    mnemonic: str
    name: str
    axis_types: tuple[str, ...]
    checks: tuple[SubCheck, ...]
    kind: str
    scans: int
    provenance: ir.Provenance
    location: ir.Location
    completes: ir.Provenance
    completes_location: ir.Location


def is_sub_instruction(tree: Any) -> bool:
    """Whether a parsed file is a sub-instruction file (by its ``format:``)."""
    return isinstance(tree, dict) and tree.get("format") == SUB_FORMAT


@functools.cache
def sub_instruction_schema() -> dict[str, Any]:
    from statecharts.loader import bundled_spec_dir
    text = (bundled_spec_dir() / "schema" / "subinstruction.schema.json").read_text(encoding="utf-8")
    return cast("dict[str, Any]", json.loads(text))


def _sub_expr(f: str, tree: Any, parts: tuple[Any, ...], text: str, errors: list[Diagnostic]) -> Expr | None:
    line, col = locate(tree, parts)
    try:
        e = parse_expression(text)
    except ExprError as exc:
        errors.append(Diagnostic(f, line, col, node_path(parts), f"bad expression: {exc}"))
        return None
    unknown = check_names(e, SUB_NAMES)
    if unknown:
        names = ", ".join(n for n, _ in unknown)
        errors.append(Diagnostic(f, line, col, node_path(parts), f"unknown name(s) {names} in {text!r}"))
        return None
    return e


def build_sub_instructions(documents: Sequence[tuple[str, Any]], errors: list[Diagnostic]) -> tuple[SubInstruction, ...]:
    """The sub-instructions of parsed sub-instruction files (name, YAML tree); every
    problem is appended to ``errors`` (a file with a problem gives no sub-instruction)."""
    from statecharts.loader import plain_data, schema_diagnostics

    subs: list[SubInstruction] = []
    for f, tree in documents:
        before = len(errors)
        errors.extend(schema_diagnostics(f, tree, sub_instruction_schema(), "a sub-instruction file"))
        if len(errors) > before:
            continue
        d = plain_data(tree)["instruction"]

        def where(*parts: Any, f: str = f, tree: Any = tree) -> ir.Location:
            return ir.Location(f, *locate(tree, parts), node_path(parts))

        def prov(n: Any) -> ir.Provenance:
            return ir.Provenance(str(n["source"]), n.get("interpretation"))

        checks = []
        for i, c in enumerate(d["checks"]):
            e = _sub_expr(f, tree, ("instruction", "checks", i, "fails"), c["fails"], errors)
            if e is not None:
                checks.append(SubCheck(e, int(c["err"]), prov(c), where("instruction", "checks", i)))
        if d["mnemonic"] in {x.mnemonic for x in subs}:
            errors.append(Diagnostic(f, *locate(tree, ("instruction", "mnemonic")), "instruction.mnemonic",
                                     f"sub-instruction {d['mnemonic']!r} is defined twice"))
        if len(errors) > before:
            continue
        subs.append(SubInstruction(d["mnemonic"], d["name"], tuple(d["axis_types"]), tuple(checks),
                                   d["completes"]["kind"], int(d["completes"].get("scans", 1)), prov(d),
                                   where("instruction"), prov(d["completes"]), where("instruction", "completes")))
    return tuple(subs)


def calls_of(add_on: ir.AddOnInstruction) -> list[tuple[str, ir.Location]]:
    """The sub-instructions an add-on instruction calls, each with the place of the call."""
    out = [(s.call.instruction, s.location) for s in add_on.recovery.states if s.call is not None]
    for rule in (add_on.rung_false, add_on.prescan):
        if rule.abort_call:
            out.append((rule.abort_call, rule.location))
    return out


def undefined_calls(add_ons: Sequence[ir.AddOnInstruction], subs: Sequence[SubInstruction]) -> list[Diagnostic]:
    """A call of an add-on instruction naming no sub-instruction of ``subs`` (a call of
    none of :data:`MOTION_CALLS` is reported by :func:`build_add_on` already)."""
    known = {s.mnemonic for s in subs}
    out = []
    for a in add_ons:
        for mnemonic, loc in calls_of(a):
            if mnemonic not in known and mnemonic in MOTION_CALLS:
                out.append(Diagnostic(loc.file, loc.line, loc.column, loc.path,
                                      f"unknown sub-instruction {mnemonic!r}; known: {', '.join(sorted(known))}"))
    return out
