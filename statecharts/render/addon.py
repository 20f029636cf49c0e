"""The recovery of an add-on instruction as a chart, for the common renderers.

Pipeline position: IR (``spec.add_ons``) -> **addon** -> an :class:`~statecharts.ir.Chart`
that :mod:`~statecharts.render.dot`, :mod:`~statecharts.render.mermaid` and the chart
tables of :mod:`~statecharts.render.reference` draw like any chart.  The IR keeps the
recovery as its own record (states that call motion instructions, guarded
transitions); here it becomes ``idle`` beside an ``executing`` composite that a false
rung leaves, with an ``errored`` state for a failing check or call, and each call named
by the variant of the motion instruction for the axis it is given.  The flowchart and
the page of an add-on instruction are the common ones
(:func:`~statecharts.render.flowchart.build_flowchart`,
:func:`~statecharts.render.reference.add_on_page`).
"""

from __future__ import annotations

import dataclasses

from statecharts import ir
from statecharts.expr import Assignment, Expr, parse_expression
from statecharts.render.labels import error_tags

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


def transition_id(n: int) -> str:
    """The id of the ``n``-th (from 1) transition of the recovery, as its chart names it."""
    return f"t{n}"


def recovery_chart(spec: ir.Spec, a: ir.AddOnInstruction, *, ordered: bool = False) -> ir.Chart:
    """The recovery as a chart (see the module docstring).  ``ordered``: the guard of a branch of a
    state with several starts with its try order (``2: ...``), as the diagrams show it."""
    rec, ids, rf, ex_prov, ex_loc = a.recovery, {s.id for s in a.recovery.states}, a.rung_false, \
        a.execution.provenance, a.execution.location
    flag, err, exerr = error_tags(a)
    tag = flag.removesuffix("ER")  # the status tag's prefix: Sts_PC, Sts_IP
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
        return (f"{tag}PC = 1; {tag}IP = 0", *(f"{o.set} = 1" + (f" if {o.when.text}" if o.when.text != "True" else "")
                                            for o in a.on_done)) if s.id == "done" else ()

    idle = rec.state(IDLE)
    states = [state(IDLE, None, (), idle.description, idle.provenance, idle.location),
              state(ex, None, (), "one execution, from a rising rung", ex_prov, ex_loc,
                    (*(s.id for s in rec.states if s.id != IDLE), er)),
              *(state(s.id, ex, entry(s), s.description, s.provenance, s.location) for s in rec.states if s.id != IDLE),
              state(er, ex, (f"{flag} = 1 until the rung goes false",), "a check or a call failed", rec.provenance,
                    rec.location)]
    clears = [f"{m} = 0" for m in rf.clear] + ([f"{rf.abort_call} stops a call in process"] if rf.abort_call else [])
    ts = [ir.Transition("start", IDLE, ex, "rung_true", None, (), 1, ex_prov, ex_loc),
          ir.Transition("rung_false", ex, IDLE, "rung_false", None, _acts(*clears), 1, rf.provenance, rf.location),
          ir.Transition("check_fails", rec.initial, er, None, _text("a check fails"), _acts(f"{err} = its code"), 0,
                        rec.provenance, rec.location)]
    for n, t in enumerate(rec.transitions, start=1):
        sibs = [x for x in rec.transitions if x.source == t.source]
        guard = None if t.when.text == "True" else _text(f"{sibs.index(t) + 1}: {t.when.text}") if (
            ordered and len(sibs) > 1) else t.when
        ts.append(ir.Transition(transition_id(n), t.source, t.target, None, guard, (), sibs.index(t) + 1, t.provenance,
                                t.location))
    ts += [ir.Transition(f"{s.id}_fails", s.id, er, None, _text(f"{s.call.instruction} errs"), _acts(
        f"{err} = {s.error}", f"{exerr} = {s.call.instruction}.ERR"), 0, s.provenance, s.location)
        for s in rec.states if s.call is not None]
    events = (ir.Event("rung_true", "environment", "the rung goes true", (), (), ex_prov),
              ir.Event("rung_false", "environment", "the rung goes false", (), (), rf.provenance))
    return ir.Chart(a.id + RECOVERY_SUFFIX, f"Recovery chart of {a.id}", ir.ChartKind.HANDLER, "", (), (), events,
                    tuple(states), tuple(ts), IDLE, rec.description, rec.provenance, rec.location)
