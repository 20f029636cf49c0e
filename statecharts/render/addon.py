"""What the common renderers need that is particular to an add-on instruction.

Pipeline position: IR (``spec.add_ons``) -> **addon** -> the flowchart model of
:mod:`~statecharts.render.flowchart`, an :class:`~statecharts.ir.Chart` of the recovery for
:mod:`~statecharts.render.dot` / :mod:`~statecharts.render.mermaid`, and a page made of the
tables of :mod:`~statecharts.render.reference`.  Particular here: the status tag
(``Sts_ERR``), the instruction's own codes, and the recovery drawn as ``idle`` beside an
``executing`` composite that a false rung leaves, with an ``errored`` state for a failing
check or call; a call names the variant of the motion instruction for the axis it is given.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

from statecharts import ir
from statecharts.expr import Assignment, Expr, parse_expression
from statecharts.render import reference as R
from statecharts.render.flowchart import Flowchart, FlowEdge, FlowNode, check_chain
from statecharts.render.labels import paragraph, where
from statecharts.render.mermaid import chart_mermaid
from statecharts.render.traceability import Traceability

RECOVERY_SUFFIX = "_recovery"  # diagrams/<ID>_recovery.*, ``motionchart diagram <ID>_recovery``
IDLE = "idle"  # the recovery state outside an execution (the loader requires it)
_TRUE = parse_expression("True")


def _text(text: str) -> Expr:  # a condition shown, never evaluated
    return dataclasses.replace(_TRUE, text=text)


def _acts(*texts: str) -> tuple[Assignment, ...]:
    return tuple(Assignment(t, "", _TRUE) for t in texts)


def call_text(spec: ir.Spec, a: ir.AddOnInstruction, call: ir.RecoveryCall) -> tuple[str, ir.Instruction | None]:
    """``MAG_CIP(Ref_AxisPhy, master Ref_AxisPth, Ratio: 1.0)`` and the variant called (None: none fits)."""
    par = a.parameter(call.axis)
    chart = next((o.chart for o in a.world.objects if o.kind == par.data_type), None)  # the chart running the axis
    try:
        ins: ir.Instruction | None = spec.instruction(call.instruction, chart or spec.chart_for_axis_type(
            par.data_type or "").id)
    except KeyError:
        ins = None
    args = [par.name, *([f"master {a.parameter(call.master).name}"] if call.master else []),
            *(f"{k}: {e.text}" for k, e in call.operands)]
    return f"{ins.id if ins else call.instruction}({', '.join(args)})", ins


def _name(a: ir.AddOnInstruction, err: int) -> str:
    return next((e.name for e in a.errors if e.code == err), "")


def addon_flowchart(spec: ir.Spec, a: ir.AddOnInstruction) -> Flowchart:
    """One decision per ordered check, each to its ``Sts_ERR``; then the recovery chart takes over."""
    nodes = [FlowNode("start", "terminal", ("Rung-condition-in true",)),
             FlowNode("execute", "process", ("A new execution starts", "(the rung was false before)"))]
    edges, side = [FlowEdge("start", "execute")], list[tuple[str, str]]()
    prev, _ = check_chain(a.checks, "execute", lambda c: c.description or _name(a, c.err) + "?", lambda c, eid: FlowNode(
        eid, "error", ("Sts_ER set", f"Sts_ERR = {c.err}", *paragraph(_name(a, c.err), 34))), nodes, edges, side)
    nodes.append(FlowNode("recovery", "done", ("Every check passed:", f"the recovery chart leaves {a.recovery.initial}")))
    edges.append(FlowEdge(prev, "recovery", "no" if a.checks else ""))
    note = ("The checks run top to bottom when an execution starts; the first that holds sets Sts_ER and its code,",
            f"which stay until the rung goes false; then the recovery chart ({a.id}{RECOVERY_SUFFIX}) runs.")
    return Flowchart(a.id, f"{a.id} {a.name}: execution with rung-condition-in true", note, tuple(nodes),
                     tuple(edges), tuple(side), tuple(n.id for n in nodes if n.kind != "error"))


def recovery_chart(spec: ir.Spec, a: ir.AddOnInstruction, *, ordered: bool = False) -> ir.Chart:
    """The recovery as a chart (see the module docstring).  ``ordered``: the guard of a branch of a
    state with several starts with its try order (``2: ...``), as the diagrams show it."""
    rec, ids, rf, ex_prov, ex_loc = a.recovery, {s.id for s in a.recovery.states}, a.rung_false, \
        a.execution.provenance, a.execution.location
    ex, er = (next(x + "_" * k for k in range(len(ids) + 1) if x + "_" * k not in ids) for x in ("executing", "errored"))

    def state(sid: str, parent: str | None, entry: tuple[str, ...], desc: str, prov: ir.Provenance,
              loc: ir.Location, children: tuple[str, ...] = ()) -> ir.State:
        return ir.State(sid, sid, ir.StateKind.COMPOUND if children else ir.StateKind.ATOMIC, None, parent, children,
                        rec.initial if children else None, None, _acts(*entry), (), desc, prov, loc)

    def entry(s: ir.RecoveryState) -> tuple[str, ...]:
        if s.id == rec.initial:
            return (f"checks 1 to {len(a.checks)} run in order",)
        if s.call is not None:
            return (call_text(spec, a, s.call)[0],)
        return ("Sts_PC = 1; Sts_IP = 0", *(f"{o.set} = 1" + (f" if {o.when.text}" if o.when.text != "True" else "")
                                            for o in a.on_done)) if s.id == "done" else ()

    idle = rec.state(IDLE)
    states = [state(IDLE, None, (), idle.description, idle.provenance, idle.location),
              state(ex, None, (), "one execution, from a rising rung", ex_prov, ex_loc,
                    (*(s.id for s in rec.states if s.id != IDLE), er)),
              *(state(s.id, ex, entry(s), s.description, s.provenance, s.location) for s in rec.states if s.id != IDLE),
              state(er, ex, ("Sts_ER = 1 until the rung goes false",), "a check or a call failed", rec.provenance,
                    rec.location)]
    clears = [f"{m} = 0" for m in rf.clear] + ([f"{rf.abort_call} stops a call in process"] if rf.abort_call else [])
    ts = [ir.Transition("start", IDLE, ex, "rung_true", None, (), 1, ex_prov, ex_loc),
          ir.Transition("rung_false", ex, IDLE, "rung_false", None, _acts(*clears), 1, rf.provenance, rf.location),
          ir.Transition("check_fails", rec.initial, er, None, _text("a check fails"), _acts("Sts_ERR = its code"), 0,
                        rec.provenance, rec.location)]
    for n, t in enumerate(rec.transitions, start=1):
        sibs = [x for x in rec.transitions if x.source == t.source]
        guard = None if t.when.text == "True" else _text(f"{sibs.index(t) + 1}: {t.when.text}") if (
            ordered and len(sibs) > 1) else t.when
        ts.append(ir.Transition(f"t{n}", t.source, t.target, None, guard, (), sibs.index(t) + 1, t.provenance,
                                t.location))
    ts += [ir.Transition(f"{s.id}_fails", s.id, er, None, _text(f"{s.call.instruction} errs"), _acts(
        f"Sts_ERR = {s.error}", f"Sts_EXERR = {s.call.instruction}.ERR"), 0, s.provenance, s.location)
        for s in rec.states if s.call is not None]
    events = (ir.Event("rung_true", "environment", "the rung goes true", (), (), ex_prov),
              ir.Event("rung_false", "environment", "the rung goes false", (), (), rf.provenance))
    return ir.Chart(a.id + RECOVERY_SUFFIX, f"Recovery chart of {a.id}", ir.ChartKind.HANDLER, "", (), (), events,
                    tuple(states), tuple(ts), IDLE, rec.description, rec.provenance, rec.location)


def addon_codes(a: ir.AddOnInstruction, tr: Traceability, p: str) -> list[R.DocumentedCode]:
    """Every code of ``a`` by number, with the checks and calling states that report it."""
    return [R.DocumentedCode(
        (f'<a id="{R.anchor(f"code-{e.code}")}"></a>{e.code}',), e.name, e.description, e.provenance.source, "",
        tuple(filter(None, [e.provenance.interpretation])),
        (*(f"check [`{c.id}`](#{R.anchor('check-' + c.id)}) when {R.code(c.fails_when.text)}" for c in a.checks
           if c.err == e.code),
         *(f"state [`{s.id}`](#{R.anchor('state-' + s.id)}) when its {s.call.instruction} call errs"
           for s in a.recovery.states if s.call is not None and s.error == e.code)),
        R.scenario_links(tr.aoi_producing(e.code), p, 3, tr.link_base) if tr.root is not None else "—")
        for e in sorted(a.errors, key=lambda e: e.code)]


def addon_page(spec: ir.Spec, a: ir.AddOnInstruction, tr: Traceability) -> str:
    """``instructions/<ID>.md``: parameters, status tag, local tags, ordered checks, codes, recovery chart."""
    p, rc, chart, cell = "../", a.id + RECOVERY_SUFFIX, recovery_chart(spec, a), R.cell
    calls = [(s, *call_text(spec, a, s.call)) for s in a.recovery.states if s.call is not None]
    out = [R.GENERATED_NOTE, "", f"# {a.id}: {a.name} (add-on instruction)", "", cell(a.description), "",
           f"- Source: {cell(a.provenance.source)}"]
    out += [f"- Interpretation: {R.interp_link(a.provenance.interpretation, p)}"] if a.provenance.interpretation else []
    out += [f"- Execution: {a.execution.mode} ({cell(a.execution.provenance.source)})",
            f"- Calls: {', '.join(sorted({f'[{i.id}]({i.id}.md)' for _s, _t, i in calls if i}))}",
            f"- Defined at: `{where(spec, a.location)}`", "", "## Flowchart", "", *R.flowchart_section(spec, a, p),
            "", "## Parameters", "", "In Logix order.", ""]
    out += R.sourced_table(spec, ["Parameter", "Usage", "Type", "Data type", "Default", "Meaning"], [(
        [f"`{x.name}`" + (f" (`{x.alias}`)" if x.alias else ""), x.usage, x.type, cell(x.data_type or ""),
         cell("" if x.default is None else str(x.default).lower() if isinstance(x.default, bool) else x.default),
         cell(x.description)], x) for x in a.parameters], p)
    out += ["", "## Status tag", "", *R.sourced_table(spec, ["Member", "Type", "Meaning"], [
        ([f"`{m.name}`", m.type, cell(m.description)], m) for m in a.status], p)]
    out += ["", "## Local tags", "", *R.variables_table(a.local_tags, p), "",
            "## Checks, in the order they are evaluated", "", "When an execution starts, the first check whose "
            "condition holds ends it with `Sts_ER` and its code; when none holds, the recovery chart runs.", ""]
    out += R.checks_table(spec, a.checks, lambda c: (_name(a, c.err), "", "", ""), p, ("Sts_ERR", "Sts_EXERR"))
    out += ["", "## Error codes", "", "Every code the instruction reports in `Sts_ERR`; a call that errs puts "
            "its own `.ERR` in `Sts_EXERR`.", "", *R.documented_codes_table(("Sts_ERR",), addon_codes(a, tr, p), p),
            "", "## Recovery chart", "", *R.diagram_block(
                f"{p}diagrams/{rc}.svg", chart_mermaid(recovery_chart(spec, a, ordered=True)), f"{p}diagrams/{rc}.mmd",
                f"{p}diagrams/{rc}.dot", f"Recovery chart of {a.id}"),
            "", "### States", "", "*Scenarios reaching it*: the scenarios in which an instance was in the state at "
            "the end of a scan; a state left in the scan it is entered (`checking`, a call that completes at once) "
            "is passed through unobserved.", ""]
    out += R.states_table(spec, chart, tr, p, lambda sid: sorted(
        {r for c in chart.state(sid).children or (sid,) for r in tr.aoi_reaching(c)}))
    out += ["", "### Transitions", "", *R.transitions_table(spec, chart, p), "", "## Motion instructions it calls", ""]
    out += R.sourced_table(spec, ["State", "Call", "Instruction page", f"{a.id} code if it errs"], [(
        [f"[`{s.id}`](#{R.anchor('state-' + s.id)})", R.code(text), f"[{i.id}]({i.id}.md)" if i else "—",
         f"[{s.error}](#{R.anchor(f'code-{s.error}')})"], s) for s, text, i in calls], p)
    out += ["", "## Rung false and prescan", "", *R.sourced_table(spec, ["Routine", "Clears", "Also"], [(
        [name, ", ".join(f"`{m}`" for m in r.clear), cell("; ".join(
            [f"a call in process is stopped with {r.abort_call}"] * bool(r.abort_call)
            + [f"forgets {', '.join(r.forget)}"] * bool(r.forget)))], r)
        for name, r in (("rung false", a.rung_false), ("prescan", a.prescan))], p)]
    if tr.root is not None:
        out += ["", f"Scenarios that complete it (`Sts_PC`): {R.scenario_links(tr.aoi_completing(), p, base=tr.link_base)}"]
    out += ["", "## The world it runs in", "", "What the checks and calls read of the objects it is given "
            f"(`phy.faulted`, `handler.mode`, ...), from their charts. Source: {cell(a.world.provenance.source)}.", ""]
    out += R.sourced_table(spec, ["Object", "Chart", "Fact", "Read from"], [(
        [f"`{o.kind}`", f"[{o.chart}]({p}charts/{o.chart}.md)", f"`{f.name}`",
         R.code(f.when.text) if f.when is not None else f"variable `{f.variable}`"], f)
        for o in a.world.objects for f in o.facts], p)
    return "\n".join(out) + "\n"


def addon_uses(a: ir.AddOnInstruction) -> list[tuple[ir.Provenance, str, str]]:
    """(provenance, label, link) of every element of ``a``, for the users of each interpretation."""
    groups: list[tuple[Sequence[Any], str, str]] = [
        ((a,), "add-on instruction", ""), ((a.recovery,), "recovery chart", "recovery-chart"),
        (a.parameters, "parameter {x.name}", "parameters"), (a.status, "status {x.name}", "status-tag"),
        (a.local_tags, "local tag {x.name}", "local-tags"), (a.errors, "error code {x.code}", "code-{x.code}"),
        (a.checks, "check {x.id}", "check-{x.id}"), (a.recovery.states, "recovery state {x.id}", "state-{x.id}"),
        (a.recovery.transitions, "transition {x.source} -> {x.target}", "transitions"),
        (a.on_done, "on done, set {x.set}", "state-done"), ((a.world,), "world", "the-world-it-runs-in"),
        (a.world.objects, "world object {x.kind} ({x.chart})", "the-world-it-runs-in"),
        ([f for o in a.world.objects for f in o.facts], "world fact {x.name}", "the-world-it-runs-in"),
        ((a.rung_false,), "rung-false routine", "rung-false-and-prescan"),
        ((a.prescan,), "prescan routine", "rung-false-and-prescan")]
    return [(x.provenance, f"{a.id} {label.format(x=x)}",
             f"instructions/{a.id}.md" + (f"#{R.anchor(frag.format(x=x))}" if frag else ""))
            for xs, label, frag in groups for x in xs]
