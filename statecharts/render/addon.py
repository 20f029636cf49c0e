"""An add-on instruction as the common renderers draw it.

Pipeline position: IR (:class:`statecharts.ir.AddOnInstruction` in ``spec.add_ons``) ->
**addon** -> the flowchart model of :mod:`statecharts.render.flowchart`, a derived
:class:`statecharts.ir.Chart` of its recovery for :mod:`~statecharts.render.dot` and
:mod:`~statecharts.render.mermaid`, and the tables of :mod:`~statecharts.render.reference`
-> ``instructions/<ID>.md``, ``flowcharts/<ID>.*``, ``diagrams/<ID>_recovery.*``.

Only what is particular to an add-on instruction is here: its status tag (``Sts_ERR``
instead of ``ERR``), its own error codes, and the recovery chart, drawn with the state
``idle`` outside an ``executing`` composite that a false rung leaves, and an ``errored``
state for the failing checks and calls.  A call links to the variant of the motion
instruction for the axis parameter's data type.
"""

from __future__ import annotations

import dataclasses

from statecharts import ir
from statecharts.expr import Assignment, Expr, parse_expression
from statecharts.render.flowchart import Flowchart, FlowEdge, FlowNode, check_chain
from statecharts.render.labels import paragraph, spec_path, where, wrap
from statecharts.render.reference import (
    GENERATED_NOTE,
    DocumentedCode,
    Use,
    anchor,
    cell,
    checks_table,
    code,
    diagram_block,
    documented_codes_table,
    flowchart_section,
    interp_link,
    scenario_links,
    states_table,
    table,
    transitions_table,
    variables_table,
)
from statecharts.render.traceability import Traceability

RECOVERY_SUFFIX = "_recovery"  # diagrams/<ID>_recovery.*, ``motionchart diagram <ID>_recovery``
IDLE = "idle"  # the recovery state outside an execution (the loader requires it)
INDEX_HEADER = ("Add-on instruction", "Name", "Checks", "Codes", "Recovery states", "Calls", "Diagrams", "Spec file")
_TRUE = parse_expression("True")


def _text(text: str) -> Expr:
    return dataclasses.replace(_TRUE, text=text)


def _act(text: str) -> Assignment:
    return Assignment(text, "", _TRUE)


def call_text(spec: ir.Spec, a: ir.AddOnInstruction, call: ir.RecoveryCall) -> tuple[str, ir.Instruction | None]:
    """``MAG_CIP(Ref_AxisPhy, master Ref_AxisPth, Ratio: 1.0)`` and the variant called (None: none fits)."""
    par = a.parameter(call.axis)
    chart = next((o.chart for o in a.world.objects if o.kind == par.data_type), None)  # the chart running the axis
    try:
        ins: ir.Instruction | None = spec.instruction(
            call.instruction, chart or spec.chart_for_axis_type(par.data_type or "").id)
    except KeyError:
        ins = None
    args = [par.name] + ([f"master {a.parameter(call.master).name}"] if call.master else [])
    args += [f"{k}: {e.text}" for k, e in call.operands]
    return f"{ins.id if ins else call.instruction}({', '.join(args)})", ins


def _name(a: ir.AddOnInstruction, err: int) -> str:
    return next((e.name for e in a.errors if e.code == err), "")


def addon_flowchart(spec: ir.Spec, a: ir.AddOnInstruction) -> Flowchart:
    """One decision per ordered check, each to its ``Sts_ERR``; then the branches out of the recovery's first state."""
    nodes = [FlowNode("start", "terminal", ("Rung-condition-in true",)),
             FlowNode("execute", "process", ("A new execution starts", "(the rung was false before)"))]
    edges, side = [FlowEdge("start", "execute")], list[tuple[str, str]]()
    prev, _ = check_chain(a.checks, "execute", lambda c: c.description or _name(a, c.err) + "?", lambda c, eid: FlowNode(
        eid, "error", ("Sts_ER set", f"Sts_ERR = {c.err}", *paragraph(_name(a, c.err), 34))), nodes, edges, side)
    rec = a.recovery
    nodes.append(FlowNode("recovery", "process", ("Every check passed:", f"the recovery chart leaves {rec.initial}")))
    edges.append(FlowEdge(prev, "recovery", "no" if a.checks else ""))
    prev, label = "recovery", ""
    for n, t in enumerate((t for t in rec.transitions if t.source == rec.initial), start=1):
        st = rec.state(t.target)
        what = call_text(spec, a, st.call)[0] if st.call else st.description
        nodes.append(FlowNode(f"route_{n}", "decision", (f"{n}. to {t.target}?",), tuple(wrap(t.when.text, 30))))
        nodes.append(FlowNode(f"state_{n}", "process", (f"{t.target}: calls {st.call.instruction}",), tuple(wrap(
            what, 40))) if st.call else FlowNode(f"state_{n}", "done", (t.target, *paragraph(what, 40))))
        edges += [FlowEdge(prev, f"route_{n}", label), FlowEdge(f"route_{n}", f"state_{n}", "yes")]
        side.append((f"route_{n}", f"state_{n}"))
        prev, label = f"route_{n}", "no"
    nodes.append(FlowNode("no_route", "wait", ("No branch holds:", f"stays in {rec.initial}")))
    edges.append(FlowEdge(prev, "no_route", label))
    note = ("The checks run top to bottom when an execution starts; the first that holds sets Sts_ER and its code,",
            f"which stay until the rung goes false. Each branch continues in the recovery chart ({a.id}{RECOVERY_SUFFIX}).")
    spine = tuple(n.id for n in nodes if n.kind in ("terminal", "decision") or n.id in ("execute", "recovery", "no_route"))
    return Flowchart(a.id, f"{a.id} {a.name}: execution with rung-condition-in true", note, tuple(nodes),
                     tuple(edges), tuple(side), spine)


def recovery_chart(spec: ir.Spec, a: ir.AddOnInstruction, *, ordered: bool = False) -> ir.Chart:
    """The recovery as a chart: ``idle`` and an ``executing`` composite (left when the rung goes false)
    holding the spec's states and ``errored`` (entered when a check or a call fails).  ``ordered``: a
    guard of a state with several transitions starts with its try order (``2: ...``), for diagrams."""
    rec, ids = a.recovery, {s.id for s in a.recovery.states}
    ex, er = (next(x + "_" * k for k in range(len(ids) + 1) if x + "_" * k not in ids) for x in ("executing", "errored"))

    def state(sid: str, parent: str | None, entry: list[str], desc: str, prov: ir.Provenance, loc: ir.Location,
              children: tuple[str, ...] = ()) -> ir.State:
        kind = ir.StateKind.COMPOUND if children else ir.StateKind.ATOMIC
        return ir.State(sid, sid, kind, None, parent, children, rec.initial if children else None, None,
                        tuple(_act(x) for x in entry), (), desc, prov, loc)

    def entry(s: ir.RecoveryState) -> list[str]:
        if s.id == rec.initial:
            return [f"checks 1 to {len(a.checks)} run in order"]
        if s.call is not None:
            return [call_text(spec, a, s.call)[0]]
        return ["Sts_PC = 1; Sts_IP = 0", *(f"{o.set} = 1" + (f" if {o.when.text}" if o.when.text != "True" else "")
                                           for o in a.on_done)] if s.id == "done" else []

    inner = (*tuple(s.id for s in rec.states if s.id != IDLE), er)
    states = [state(IDLE, None, [], rec.state(IDLE).description, rec.state(IDLE).provenance, rec.state(IDLE).location),
              state(ex, None, [], "one execution, from a rising rung", a.execution.provenance, a.execution.location, inner)]
    states += [state(s.id, ex, entry(s), s.description, s.provenance, s.location) for s in rec.states if s.id != IDLE]
    states.append(state(er, ex, ["Sts_ER = 1 until the rung goes false"], "a check or a call failed",
                        rec.provenance, rec.location))
    rf = a.rung_false
    clears = [f"{m} = 0" for m in rf.clear] + ([f"{rf.abort_call} stops a call in process"] if rf.abort_call else [])
    ts = [ir.Transition("start", IDLE, ex, "rung_true", None, (), 1, a.execution.provenance, a.execution.location),
          ir.Transition("rung_false", ex, IDLE, "rung_false", None, tuple(_act(x) for x in clears), 1, rf.provenance,
                        rf.location),
          ir.Transition("check_fails", rec.initial, er, None, _text("a check fails"), (_act("Sts_ERR = its code"),), 0,
                        rec.provenance, rec.location)]
    for n, t in enumerate(rec.transitions, start=1):
        sibs = [x for x in rec.transitions if x.source == t.source]
        guard = None if t.when.text == "True" else _text(f"{sibs.index(t) + 1}: {t.when.text}") if (
            ordered and len(sibs) > 1) else t.when
        ts.append(ir.Transition(f"t{n}", t.source, t.target, None, guard, (), sibs.index(t) + 1, t.provenance,
                                t.location))
    ts += [ir.Transition(f"{s.id}_fails", s.id, er, None, _text(f"{s.call.instruction} errs"),
                         (_act(f"Sts_ERR = {s.error}"), _act(f"Sts_EXERR = {s.call.instruction}.ERR")), 0, s.provenance, s.location)
           for s in rec.states if s.call is not None]
    events = tuple(ir.Event(e, "environment", d, (), (), p) for e, d, p in (
        ("rung_true", "the rung goes true", a.execution.provenance), ("rung_false", "the rung goes false", rf.provenance)))
    return ir.Chart(a.id + RECOVERY_SUFFIX, f"Recovery chart of {a.id}", ir.ChartKind.HANDLER, "", (), (), events,
                    tuple(states), tuple(ts), IDLE, rec.description, rec.provenance, rec.location)


def addon_codes(a: ir.AddOnInstruction, tr: Traceability, p: str) -> list[DocumentedCode]:
    out = []
    for e in sorted(a.errors, key=lambda e: e.code):
        by = [f"check [`{c.id}`](#{anchor('check-' + c.id)}) when {code(c.fails_when.text)}" for c in a.checks
              if c.err == e.code]
        by += [f"state [`{s.id}`](#{anchor('state-' + s.id)}) when its {s.call.instruction} call errs"
               for s in a.recovery.states if s.call is not None and s.error == e.code]
        scen = scenario_links(tr.aoi_producing(e.code), p, 3, tr.link_base) if tr.root is not None else "—"
        out.append(DocumentedCode((f'<a id="{anchor("code-" + str(e.code))}"></a>{e.code}',), e.name, e.description,
                                  e.provenance.source, "", tuple(filter(None, [e.provenance.interpretation])),
                                  tuple(by), scen))
    return out


def addon_page(spec: ir.Spec, a: ir.AddOnInstruction, tr: Traceability) -> str:
    """``instructions/<ID>.md``: parameters, status tag, local tags, ordered checks, codes, recovery chart."""
    p, rc, rec, chart = "../", a.id + RECOVERY_SUFFIX, a.recovery, recovery_chart(spec, a)
    calls = [(s, *call_text(spec, a, s.call)) for s in rec.states if s.call is not None]
    out = [GENERATED_NOTE, "", f"# {a.id}: {a.name} (add-on instruction)", "", cell(a.description), "",
           f"- Source: {cell(a.provenance.source)}"]
    out += [f"- Interpretation: {interp_link(a.provenance.interpretation, p)}"] if a.provenance.interpretation else []
    out += [f"- Execution: {a.execution.mode} ({cell(a.execution.provenance.source)})",
            f"- Calls: {', '.join(sorted({f'[{i.id}]({i.id}.md)' for _s, _t, i in calls if i}))}",
            f"- Defined at: `{where(spec, a.location)}`", "", "## Flowchart", "", *flowchart_section(spec, a, p)]
    out += ["", "## Parameters", "", "In Logix order.", ""]
    out += table(["Parameter", "Usage", "Type", "Data type", "Default", "Meaning", "Source", "Interpretation",
                  "Defined at"], [
        [f"`{x.name}`" + (f" (`{x.alias}`)" if x.alias else ""), x.usage, x.type, cell(x.data_type or ""),
         cell("" if x.default is None else str(x.default).lower() if isinstance(x.default, bool) else x.default),
         cell(x.description), cell(x.provenance.source), interp_link(x.provenance.interpretation, p),
         f"`{where(spec, x.location)}`"] for x in a.parameters])
    out += ["", "## Status tag", ""]
    out += table(["Member", "Type", "Meaning", "Source", "Interpretation", "Defined at"], [
        [f"`{m.name}`", m.type, cell(m.description), cell(m.provenance.source),
         interp_link(m.provenance.interpretation, p), f"`{where(spec, m.location)}`"] for m in a.status])
    out += ["", "## Local tags", "", *variables_table(a.local_tags, p)]
    out += ["", "## Checks, in the order they are evaluated", "",
            "When an execution starts, the first check whose condition holds ends it with `Sts_ER` and its code; "
            "when none holds, the recovery chart runs.", ""]
    out += checks_table(spec, a.checks, lambda c: (_name(a, c.err), "", "", ""), p, ("Sts_ERR", "Sts_EXERR"))
    out += ["", "## Error codes", "", "Every code the instruction reports in `Sts_ERR`; a call that errs puts "
            "its own `.ERR` in `Sts_EXERR`.", "", *documented_codes_table(("Sts_ERR",), addon_codes(a, tr, p), p)]
    out += ["", "## Recovery chart", "", *diagram_block(f"{p}diagrams/{rc}.svg", _mermaid(spec, a),
                                                      f"{p}diagrams/{rc}.mmd", f"{p}diagrams/{rc}.dot",
                                                      f"Recovery chart of {a.id}")]
    out += ["", "### States", "", "*Scenarios reaching it*: the scenarios in which an instance was in the state at "
            "the end of a scan; a state left in the scan it is entered (`checking`, a call that completes at once) "
            "is passed through unobserved.", ""]
    out += states_table(spec, chart, tr, p, lambda sid: sorted(
        {r for c in chart.state(sid).children or (sid,) for r in tr.aoi_reaching(c)}))
    out += ["", "### Transitions", "", *transitions_table(spec, chart, p), "", "## Motion instructions it calls", ""]
    out += table(["State", "Call", "Instruction page", f"{a.id} code if it errs", "Source"], [
        [f"[`{s.id}`](#{anchor('state-' + s.id)})", code(text), f"[{i.id}]({i.id}.md)" if i else "—",
         f"[{s.error}](#{anchor('code-' + str(s.error))})", cell(s.provenance.source)] for s, text, i in calls])
    out += ["", "## Rung false and prescan", ""]
    out += table(["Routine", "Clears", "Also", "Source", "Interpretation"], [
        [name, ", ".join(f"`{m}`" for m in r.clear),
         cell("; ".join(([f"a call in process is stopped with {r.abort_call}"] if r.abort_call else [])
                        + ([f"forgets {', '.join(r.forget)}"] if r.forget else []))),
         cell(r.provenance.source), interp_link(r.provenance.interpretation, p)]
        for name, r in (("rung false", a.rung_false), ("prescan", a.prescan))])
    if tr.root is not None:
        out += ["", f"Scenarios that complete it (`Sts_PC`): {scenario_links(tr.aoi_completing(), p, base=tr.link_base)}"]
    out += ["", "## The world it runs in", "", "What the checks and calls read of the objects it is given "
            f"(`phy.faulted`, `handler.mode`, ...), read from their charts. Source: {cell(a.world.provenance.source)}.", ""]
    out += table(["Object", "Chart", "Fact", "Read from", "Source", "Interpretation"], [
        [f"`{o.kind}`", f"[{o.chart}]({p}charts/{o.chart}.md)", f"`{f.name}`",
         code(f.when.text) if f.when is not None else f"variable `{f.variable}`", cell(f.provenance.source),
         interp_link(f.provenance.interpretation, p)] for o in a.world.objects for f in o.facts])
    return "\n".join(out) + "\n"


def _mermaid(spec: ir.Spec, a: ir.AddOnInstruction) -> str:
    from statecharts.render.mermaid import chart_mermaid
    return chart_mermaid(recovery_chart(spec, a, ordered=True))


def addon_uses(a: ir.AddOnInstruction) -> dict[str, list[Use]]:
    """Every element of ``a`` that cites an interpretation (for ``interpretations.md``)."""
    page, uses = f"instructions/{a.id}.md", dict[str, list[Use]]()
    items = [(a.provenance, f"add-on instruction {a.id}", ""), (a.recovery.provenance, "recovery chart", "recovery-chart")]
    items += [(x.provenance, f"parameter {x.name}", "parameters") for x in a.parameters]
    items += [(x.provenance, f"status {x.name}", "status-tag") for x in a.status]
    items += [(x.provenance, f"local tag {x.name}", "local-tags") for x in a.local_tags]
    items += [(x.provenance, f"error code {x.code}", f"code-{x.code}") for x in a.errors]
    items += [(x.provenance, f"check {x.id}", f"check-{x.id}") for x in a.checks]
    items += [(x.provenance, f"recovery state {x.id}", f"state-{x.id}") for x in a.recovery.states]
    items += [(x.provenance, f"transition {x.source} -> {x.target}", "transitions") for x in a.recovery.transitions]
    items += [(x.provenance, f"on done, set {x.set}", "state-done") for x in a.on_done]
    items += [(x.provenance, f"{n} routine", "rung-false-and-prescan") for n, x in (("rung-false", a.rung_false),
                                                                                ("prescan", a.prescan))]
    items += [(a.world.provenance, "world", "the-world-it-runs-in")]
    items += [(x.provenance, f"world object {x.kind} ({x.chart})", "the-world-it-runs-in") for x in a.world.objects]
    items += [(f.provenance, f"world fact {x.kind}.{f.name}", "the-world-it-runs-in") for x in a.world.objects
              for f in x.facts]
    for prov, label, frag in items:
        if prov.interpretation:
            link = page + (f"#{anchor(frag)}" if frag else "")
            uses.setdefault(prov.interpretation, []).append(Use(prov.interpretation, f"{a.id} {label}", link))
    return uses


def index_rows(spec: ir.Spec) -> list[list[str]]:
    rows = []
    for a in spec.add_ons:
        rc = a.id + RECOVERY_SUFFIX
        calls = sorted({s.call.instruction for s in a.recovery.states if s.call is not None})
        rows.append([f"[{a.id}](instructions/{a.id}.md)", cell(a.name), str(len(a.checks)), str(len(a.errors)),
                     str(len(a.recovery.states)), ", ".join(calls),
                     f"flowchart [svg](flowcharts/{a.id}.svg) · [dot](flowcharts/{a.id}.dot) · "
                     f"[mermaid](flowcharts/{a.id}.mmd); recovery chart [svg](diagrams/{rc}.svg) · "
                     f"[dot](diagrams/{rc}.dot) · [mermaid](diagrams/{rc}.mmd)", f"`{spec_path(spec, a.location.file)}`"])
    return rows
