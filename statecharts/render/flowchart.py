"""IR instruction -> manual-style flowchart: its ordered checks, each failure to its ERR box.

Pipeline position: IR -> **flowchart** (a small neutral model) -> DOT here and Mermaid in
:mod:`statecharts.render.mermaid` -> ``generated/flowcharts/<MNEMONIC>.{dot,mmd,svg}``.

The flowchart is what a motion manual calls the instruction's "Flow Chart (True)",
derived entirely from the IR, so every instruction -- and any instruction added to the
spec later -- gets one:

1. the rung-condition-in true row of the execution table: its guard (``not EN``) as a
   decision, its actions and the ``on_execute`` actions as one box;
2. one decision per precondition check, top to bottom in the documented order; the
   failing branch of each goes right, to a box with its ``ERR`` (and ``EXERR``), the
   error's name from the catalog and the ``on_error`` actions.  A check of stage
   ``message`` is marked as answered by the motion task at the coarse update;
3. the accepted request (``on_accept``), the event the axis chart receives at the
   coarse update, the completion condition (``DN``), the aborts (``ER``), and the loop
   of a request still in progress.

An add-on instruction (:data:`Routine`) gets the same flowchart with its own status tag
(``Sts_ER``, ``Sts_ERR``) and codes: its execution starts on a rising rung, its ordered
checks follow, and where an instruction sends its request the add-on instruction's
recovery chart takes over (drawn as a chart, :mod:`statecharts.render.addon`).

The order of decisions is the spec's order of checks, which is the order in which
:mod:`statecharts.scan` evaluates them; the flowchart is drawn from the same IR the
engine runs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import graphviz

from statecharts import ir
from statecharts.render.addon import RECOVERY_SUFFIX
from statecharts.render.dot import FONT, MONO, html_lines, html_table, sorted_attrs
from statecharts.render.labels import error_tags, paragraph, wrap

#: Anything that runs ordered checks when it executes: an instruction, whose request
#: follows them, or an add-on instruction, whose recovery chart follows them.
Routine = ir.Instruction | ir.AddOnInstruction
#: Node kinds of a flowchart and what they mean.
KINDS = ("terminal", "process", "decision", "error", "done", "wait", "note")


@dataclass(frozen=True, slots=True)
class FlowNode:
    id: str
    kind: str  # one of KINDS
    title: tuple[str, ...]  # prose lines
    detail: tuple[str, ...] = ()  # expression or action lines (monospace)


@dataclass(frozen=True, slots=True)
class FlowEdge:
    source: str
    target: str
    label: str = ""  # "yes" / "no" on decisions
    back: bool = False  # a loop back up the chart


@dataclass(frozen=True, slots=True)
class Flowchart:
    id: str
    title: str
    note: tuple[str, ...]
    nodes: tuple[FlowNode, ...]
    edges: tuple[FlowEdge, ...]
    side: tuple[tuple[str, str], ...]  # (decision, error box) pairs drawn side by side
    spine: tuple[str, ...]  # the main flow, drawn on one vertical line


def error_name(spec: ir.Spec, owner: Routine, check: ir.Check) -> str:
    """The name of the code a failing ``check`` of ``owner`` reports: an add-on
    instruction's own, else the extended code's or the catalog's."""
    if isinstance(owner, ir.AddOnInstruction):
        return next((e.name for e in owner.errors if e.code == check.err), "")
    if check.exerr:
        for x in spec.extended_errors:
            if (x.instruction, x.err, x.exerr) == (owner.id, check.err, check.exerr):
                return x.name
    try:
        return spec.error(check.err).name
    except KeyError:
        return ""


def _error_box(spec: ir.Spec, owner: Routine, check: ir.Check, node_id: str) -> FlowNode:
    flag, err, exerr = error_tags(owner)
    code = f"{err} = {check.err}" + (f", {exerr} = {check.exerr}" if check.exerr else "")
    name = error_name(spec, owner, check)
    on_error = owner.table.on_error if isinstance(owner, ir.Instruction) else ()
    detail = tuple(a.text for a in on_error if a.text != f"{flag} = True")
    return FlowNode(node_id, "error", (f"{flag} set", code, *(paragraph(name, 34) if name else ())), detail)


def check_chain(checks: Sequence[ir.Check], prev: str, title: Callable[[ir.Check], str],
                box: Callable[[ir.Check, str], FlowNode], nodes: list[FlowNode], edges: list[FlowEdge],
                side: list[tuple[str, str]]) -> tuple[str, bool]:
    """One decision per check after ``prev``, in order, each failing right to its ``box``:
    the last decision, and whether a check is answered at the coarse update."""
    message = False
    for n, check in enumerate(checks, start=1):
        did, eid = f"check_{check.id}", f"err_{check.id}"
        lines = [f"{n}. {line}" if i == 0 else line for i, line in enumerate(paragraph(title(check), 30))]
        if check.stage is ir.Stage.MESSAGE:
            lines.append("(answered at the coarse update)")
            message = True
        nodes.append(FlowNode(did, "decision", tuple(lines), tuple(wrap(check.fails_when.text, 30))))
        nodes.append(box(check, eid))
        edges.append(FlowEdge(prev, did, "no" if prev.startswith("check_") else ""))
        edges.append(FlowEdge(did, eid, "yes"))
        side.append((did, eid))
        prev = did
    return prev, message


def build_flowchart(spec: ir.Spec, ins: Routine, labels: str = "full") -> Flowchart:
    """The flowchart of ``ins`` (see the module docstring for what it shows).

    ``labels`` (:data:`statecharts.render.dot.LABEL_LEVELS`): ``full`` shows every
    condition and action, ``guards`` the conditions without the actions, ``events`` the
    prose alone."""
    fc = _build_flowchart(spec, ins)
    if labels == "full":
        return fc
    keep_conditions = labels == "guards"
    nodes = tuple(
        replace(n, detail=n.detail if (keep_conditions and n.kind == "decision") else ()) for n in fc.nodes)
    return replace(fc, nodes=nodes)


def _build_flowchart(spec: ir.Spec, ins: Routine) -> Flowchart:
    """Head (the rung condition), the ordered checks, then the tail: what follows once
    every check passed (an instruction's request, an add-on instruction's chart)."""
    nodes: list[FlowNode] = [FlowNode("start", "terminal", ("Rung-condition-in true",))]
    edges: list[FlowEdge] = []
    side: list[tuple[str, str]] = []
    prev = _head(ins, nodes, edges, side)
    prev, message = check_chain(ins.checks, prev, lambda c: c.description or f"{error_name(spec, ins, c)}?",
                                lambda c, eid: _error_box(spec, ins, c, eid), nodes, edges, side)
    if isinstance(ins, ir.AddOnInstruction):
        note, tail = _chart_tail(ins, prev, nodes, edges)
    else:
        note, tail = _request_tail(spec, ins, prev, message, nodes, edges, side)
    spine = tuple(n.id for n in nodes if n.kind in ("terminal", "process", "decision") and n.id != "row_skip")
    return Flowchart(ins.id, f"{ins.id} {ins.name}: execution with rung-condition-in true",
                     note, tuple(nodes), tuple(edges), tuple(side), spine + tail)


def _head(ins: Routine, nodes: list[FlowNode], edges: list[FlowEdge], side: list[tuple[str, str]]) -> str:
    """The rung-condition-in true row of the execution table (its guard, its actions); an
    add-on instruction of level execution starts an execution on a rising rung."""
    prev = "start"
    if isinstance(ins, ir.AddOnInstruction):
        nodes.append(FlowNode("execute", "process", ("A new execution starts", "(the rung was false before)")))
        edges.append(FlowEdge(prev, "execute"))
        return "execute"
    table = ins.table
    row = table.row("rung_true")
    if row is not None and row.guard is not None:
        nodes.append(FlowNode("row_guard", "decision", ("Execute now?",), (row.guard.text,)))
        nodes.append(FlowNode("row_skip", "terminal", ("No action",)))
        edges.append(FlowEdge(prev, "row_guard"))
        edges.append(FlowEdge("row_guard", "row_skip", "no"))
        side.append(("row_guard", "row_skip"))
        prev = "row_guard"
    acts = tuple(a.text for a in (row.actions if row else ())) + tuple(a.text for a in table.on_execute)
    nodes.append(FlowNode("execute", "process", ("Instruction executes",), acts))
    edges.append(FlowEdge(prev, "execute", "yes" if prev == "row_guard" else ""))
    return "execute"


def _chart_tail(a: ir.AddOnInstruction, prev: str, nodes: list[FlowNode],
                edges: list[FlowEdge]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Every check passed: the recovery chart takes over (its diagram is the add-on
    instruction's ``<id>_recovery``)."""
    flag = error_tags(a)[0]
    nodes.append(FlowNode("recovery", "done", ("Every check passed:", f"the recovery chart leaves {a.recovery.initial}")))
    edges.append(FlowEdge(prev, "recovery", "no" if a.checks else ""))
    return (f"The checks run top to bottom when an execution starts; the first that holds sets {flag} and its code,",
            f"which stay until the rung goes false; then the recovery chart ({a.id}{RECOVERY_SUFFIX}) runs."), ("recovery",)


def _request_tail(spec: ir.Spec, ins: ir.Instruction, prev: str, message_note: bool, nodes: list[FlowNode],
                  edges: list[FlowEdge], side: list[tuple[str, str]]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Every check passed: the request, its completion (DN), the aborts (ER) and the loop
    of a request still in progress."""
    table = ins.table
    accept = ["Request accepted"]
    accept_detail = [a.text for a in table.on_accept]
    if ins.request is not None:
        accept.append(f"the axis receives {ins.request.event} at the coarse update")
        accept_detail.extend(a.text for a in ins.request.actions)
    accept_lines = [line for text in accept_detail for line in wrap(text, 44)]
    nodes.append(FlowNode("accept", "process", tuple(accept), tuple(accept_lines)))
    edges.append(FlowEdge(prev, "accept", "no" if prev.startswith("check_") else ""))
    prev = "accept"

    done_actions = tuple(a.text for a in table.on_done)
    if ins.done_when is None:
        nodes.append(FlowNode("done", "done", ("DN set", "done when the axis accepts the request"), done_actions))
        edges.append(FlowEdge(prev, "done"))
    else:
        nodes.append(FlowNode("done_when", "decision", ("Completed?",), tuple(wrap(ins.done_when.text, 30))))
        nodes.append(FlowNode("done", "done", ("DN set",), done_actions))
        edges.append(FlowEdge(prev, "done_when"))
        edges.append(FlowEdge("done_when", "done", "yes"))
        prev, label = "done_when", "no"
        for abort in ins.aborts:
            did, eid = f"abort_{abort.id}", f"err_{abort.id}"
            nodes.append(FlowNode(did, "decision", tuple(paragraph(abort.description, 30)),
                                  tuple(wrap(abort.fails_when.text, 30))))
            nodes.append(_error_box(spec, ins, abort, eid))
            edges.append(FlowEdge(prev, did, label))
            edges.append(FlowEdge(did, eid, "yes"))
            side.append((did, eid))
            prev, label = did, "no"
        nodes.append(FlowNode("wait", "wait", ("Request in progress", "checked again at the next coarse update")))
        edges.append(FlowEdge(prev, "wait", label))
        edges.append(FlowEdge("wait", "done_when", back=True))
        side.append(("done_when", "done"))
        if ins.aborts:  # the loop comes back up beside the aborts; else straight below
            side.append(("wait", "done_when"))

    note: list[str] = [
        "Checks are evaluated top to bottom; the first that holds sets ER with its code.",
    ]
    if message_note:
        note.append("When the motion task processes the request at the coarse update, every check is")
        note.append("evaluated again in this order against the axis as it is then.")
    return tuple(note), ()


# --------------------------------------------------------------------------- parts

#: A flowchart with more checks and aborts than this is also drawn in parts, each with
#: at most this many (so that each fits a page).
PART_CHECKS = 7


def split_flowchart(fc: Flowchart) -> list[tuple[str, Flowchart]]:
    """``[("part1", ...), ("part2", ...)]`` for a long flowchart, ``[]`` for a short one.

    The checks are shared out evenly in their order; the first part starts at the rung
    condition, the last ends with the request and its completion; a connector at the foot
    of a part and at the head of the next says where the flow continues."""
    checks = [n.id for n in fc.nodes if n.id.startswith("check_")]
    aborts = [n.id for n in fc.nodes if n.id.startswith("abort_")]
    if len(checks) + len(aborts) <= PART_CHECKS or len(checks) < 2:
        return []
    count = -(-(len(checks) + len(aborts)) // PART_CHECKS)
    count = min(count, len(checks))
    size = -(-len(checks) // count)
    chunks = [checks[i:i + size] for i in range(0, len(checks), size)]
    errors = {d: b for d, b in fc.side if d.startswith("check_")}
    first_check = fc.nodes.index(next(n for n in fc.nodes if n.id == checks[0]))
    head = {n.id for n in fc.nodes[:first_check]}
    tail_start = max(fc.nodes.index(next(n for n in fc.nodes if n.id == c)) for c in checks) + 2
    tail = {n.id for n in fc.nodes[tail_start:]}
    parts: list[tuple[str, Flowchart]] = []
    for k, chunk in enumerate(chunks, start=1):
        ids = set(chunk) | {errors[c] for c in chunk if c in errors}
        if k == 1:
            ids |= head
        if k == len(chunks):
            ids |= tail
        nodes = [n for n in fc.nodes if n.id in ids]
        edges = [e for e in fc.edges if e.source in ids and e.target in ids]
        if k > 1:
            nodes.insert(0, FlowNode("from_previous", "terminal", (f"From part {k - 1}:", "every check so far passed")))
            edges.insert(0, FlowEdge("from_previous", chunk[0]))
        if k < len(chunks):
            nodes.append(FlowNode("to_next", "terminal", (f"Continued in part {k + 1}",)))
            edges.append(FlowEdge(chunk[-1], "to_next", "no"))
        spine = tuple(x for x in ("from_previous", *fc.spine, "to_next") if x in {n.id for n in nodes})
        side = tuple((a, b) for a, b in fc.side if a in ids and b in ids)
        parts.append((f"part{k}", replace(fc, title=f"{fc.title} (part {k} of {len(chunks)})", nodes=tuple(nodes),
                                          edges=tuple(edges), side=side, spine=spine)))
    return parts


def flowchart_part_names(spec: ir.Spec, ins: Routine) -> tuple[str, ...]:
    """``whole``, and ``part1`` ... for a flowchart long enough to be split."""
    return ("whole", *(name for name, _fc in split_flowchart(build_flowchart(spec, ins))))


# --------------------------------------------------------------------------- DOT

_FILLS = {
    "terminal": "#e8edf5", "process": "#f4f6fa", "decision": "#fff8e1", "error": "#fde8e8",
    "done": "#e6f4ea", "wait": "#f4f6fa", "note": "#ffffff",
}
_BORDERS = {
    "terminal": "#3c4a5c", "process": "#3c4a5c", "decision": "#9a7b00", "error": "#a31515",
    "done": "#1e7b34", "wait": "#3c4a5c", "note": "#8a94a6",
}
_SHAPES = {
    "terminal": ("box", "rounded,filled"), "process": ("box", "filled"), "decision": ("diamond", "filled"),
    "error": ("box", "filled,bold"), "done": ("box", "rounded,filled,bold"), "wait": ("box", "rounded,filled,dashed"),
    "note": ("note", "filled"),
}


def _node_label(node: FlowNode) -> str:
    rows = [html_lines(list(node.title), bold=node.kind in ("error", "done", "terminal"))]
    if node.detail:
        rows.append(html_lines(list(node.detail), face=MONO, size=9))
    if node.kind == "decision":
        # a rule inside a diamond looks like a strike-through: stack without rules
        return html_table(rows, separators=False)
    return html_table(rows)


def flowchart_dot(fc: Flowchart) -> str:
    """DOT text of a flowchart: main flow top to bottom, failures to the right."""
    g = graphviz.Digraph(
        name=f"{fc.id}_flowchart",
        graph_attr=sorted_attrs({
            "fontname": FONT, "fontsize": "11", "labelloc": "t", "labeljust": "l", "rankdir": "TB",
            "nodesep": "0.5", "ranksep": "0.45", "pad": "0.3", "bgcolor": "white", "newrank": "true",
            "splines": "spline",
        }),
        node_attr=sorted_attrs({"fontname": FONT, "fontsize": "10", "margin": "0.12,0.06"}),
        edge_attr=sorted_attrs({"fontname": FONT, "fontsize": "9", "arrowsize": "0.8"}),
    )
    title = [html_lines([fc.title], bold=True, size=14)]
    if fc.note:
        title.append(html_lines(list(fc.note), size=9))
    g.attr(label=html_table(title, separators=False))
    main = set(fc.spine)
    for node in fc.nodes:
        shape, style = _SHAPES[node.kind]
        attrs = {
            "label": _node_label(node), "shape": shape, "style": style,
            "fillcolor": _FILLS[node.kind], "color": _BORDERS[node.kind],
        }
        if node.kind == "decision":
            attrs["margin"] = "0.02,0.02"
        if node.id in main:
            attrs["group"] = "main"  # keeps the main flow on one vertical line
        g.node(node.id, **sorted_attrs(attrs))
    for decision, box in fc.side:
        with g.subgraph() as s:
            s.attr(rank="same")
            s.node(decision)
            s.node(box)
    for e in fc.edges:
        attrs = {}
        if e.label:
            attrs["label"] = e.label
            attrs["fontcolor"] = "#a31515" if e.label == "yes" and e.target.startswith("err_") else "#333333"
        if e.target.startswith("err_"):
            attrs["color"] = "#a31515"
        if e.back:
            attrs["style"] = "dashed"
        g.edge(e.source, e.target, **sorted_attrs(attrs))
    return str(g.source)


def instruction_dot(spec: ir.Spec, ins: Routine, *, labels: str | None = None, part: str = "whole") -> str:
    """The DOT text of ``ins``'s flowchart (``part``: ``whole`` or a name of
    :func:`flowchart_parts`; KeyError for another)."""
    from statecharts.render.dot import DEFAULT_LABELS, check_labels

    fc = build_flowchart(spec, ins, check_labels(labels or DEFAULT_LABELS))
    if part != "whole":
        fc = dict(split_flowchart(fc))[part]
    return flowchart_dot(fc)


__all__ = ["PART_CHECKS", "FlowEdge", "FlowNode", "Flowchart", "Routine", "build_flowchart", "check_chain",
           "error_name", "flowchart_dot",
           "flowchart_part_names", "instruction_dot", "split_flowchart"]
