"""Build an ``add_on_instruction`` section of a spec file into :class:`statecharts.ir.AddOnInstruction`.

Pipeline position: called by :func:`statecharts.loader.load_spec` (same builder, same
diagnostics, same SpecError) for every spec file with an ``add_on_instruction:``
section; the schema has already accepted its shape.  Here: duplicate ids, unknown
codes, states, charts, events and variables, every call naming an instruction of the
spec with a variant for the chart of its axis, and every expression parsed against the
names it may read (the parameters, ``<REAL parameter>.finite``, the local tags, the
facts of the world's objects by alias, the rotary arithmetic and the call in process).
Every command loads the spec through :func:`statecharts.loader.load_spec`, so a spec
``motionchart validate`` rejects is rejected by every command, with the same located
diagnostics.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from statecharts import ir
from statecharts.expr import Expr, parse_expression

# ``b`` is the spec loader's builder (error, loc, prov, expr, variable, duplicates), ``f`` the
# file being built and nodes the loader's key-checked mappings: typed Any here because they
# are the loader's own classes.

#: Names of the rotary arithmetic and of the call in process (statecharts/addon.py).
DERIVED_NAMES = ("distance.magnitude", "move.type", "move.target", "call.done", "registered")
#: Facts the instance itself reads from every object of a chart kind: the positions of the
#: rotary arithmetic, the registration of the method.
REQUIRED_FACTS = {ir.ChartKind.AXIS: ("position", "unwind"), ir.ChartKind.HANDLER: ("registered",)}
#: States every recovery chart has: waiting for the rung, running the checks, finished.
RECOVERY_STATES = ("idle", "checking", "done")

_NEVER = parse_expression("False")


def build_add_on(b: Any, f: Any, node: Any, charts: dict[str, ir.Chart],
                 instructions: Sequence[ir.Instruction]) -> ir.AddOnInstruction:
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
        facts = {fa.name for fa in obj.facts} | {"name"} if obj else set()
        if obj is not None and obj.chart in charts:
            facts |= {cp.name for cp in charts[obj.chart].parameters}
        known |= {f"{par.alias}.{n}" for n in facts}

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

    axis_charts = {par.alias: next((o.chart for o in world.objects if o.kind == par.data_type), None)
                   for par in parameters if par.type == "axis" and par.alias}
    aliases = set(axis_charts)
    callable_ = {i.mnemonic for i in instructions}

    def variant_ok(parts: tuple[Any, ...], mnemonic: str, alias: str) -> None:
        """A call names an instruction with a variant for the chart of its axis."""
        chart = axis_charts.get(alias)
        if mnemonic in callable_ and chart is not None and not any(
                i.mnemonic == mnemonic and chart in i.charts for i in instructions):
            b.error(f, parts, f"{mnemonic} has no variant for chart {chart} (the chart of {alias})")

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
                b.error(f, (*p, "call", "instruction"), f"unknown instruction {c['instruction']!r}; "
                                                        f"known: {', '.join(sorted(callable_))}")
            for key in ("axis", "master"):
                if key in c and c[key] not in aliases:
                    b.error(f, (*p, "call", key), f"{c[key]!r} is not the alias of an axis parameter "
                                                  f"({', '.join(sorted(aliases))})")
            variant_ok((*p, "call", "instruction"), c["instruction"], c["axis"])
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
            b.error(f, at(key, "abort_call"), f"unknown instruction {r['abort_call']!r}")
        for st in states if "abort_call" in r else ():
            if st.call is not None:
                variant_ok(at(key, "abort_call"), r["abort_call"], st.call.axis)
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
        names = variables | {"active", "state"}

        def event_ok(parts: tuple[Any, ...], ev: str, chart: ir.Chart = chart, events: set[str] = events) -> None:
            if ev not in events:
                b.error(f, parts, f"chart {chart.id} has no event {ev!r}; events: {', '.join(sorted(events))}")

        for j, ev in enumerate(o.get("register") or ()):
            event_ok((*p, "register", j), ev)
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
        objects.append(ir.WorldObject(o["kind"], chart.id, tuple(facts), (), (), tuple(o.get("register") or ()),
                                      ir.WorldSetup((), (), ()), b.prov(f, p, o), b.loc(f, p)))
    return ir.World(tuple(objects), b.prov(f, base, node), b.loc(f, base))
