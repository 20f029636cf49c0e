"""Add-on instructions -> reference page, flowchart and recovery-chart diagram.

Pipeline position: ``spec/addons/*.yaml`` -> :func:`statecharts.loader.load_spec` (the
IR, provenance included) -> :func:`statecharts.aoi.load_aoi` -> **this module** ->
``generated/aoi/<ID>.md``, ``generated/flowcharts/<ID>.{dot,mmd,svg}`` and
``generated/diagrams/<ID>_recovery.{dot,mmd,svg}`` (through ``motionchart generate``,
``motionchart docs`` and ``motionchart diagram <ID>`` / ``<ID>_recovery``).  Nothing here
reads YAML: sources, interpretations and lines come from the IR.

Nothing here names the bundled instruction: every page, node and edge is derived from
the loaded data, in spec order (checks, transitions, sub-instruction preconditions) or
sorted order (error codes), so the same spec gives the same bytes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import graphviz

from statecharts import ir
from statecharts.aoi import AoiSpec, SubInstruction, load_aoi
from statecharts.diagnostics import Diagnostic, SpecError
from statecharts.ir import RecoveryState
from statecharts.loader import bundled_spec_dir
from statecharts.render.dot import FONT, MONO, esc, html_lines, html_table, sorted_attrs
from statecharts.render.flowchart import Flowchart, FlowEdge, FlowNode, flowchart_dot
from statecharts.render.labels import paragraph, wrap
from statecharts.render.mermaid import INDENT, flowchart_mermaid, text
from statecharts.render.reference import (
    GENERATED_NOTE,
    Use,
    anchor,
    cell,
    code,
    interp_link,
    scenario_links,
    table,
)
from statecharts.render.traceability import Traceability

#: Suffix of the recovery chart's diagram name (``motionchart diagram <ID>_recovery``).
RECOVERY_SUFFIX = "_recovery"
#: What the ``axis`` / ``master`` of a call refers to.
AXIS_ROLES = {"phy": "physical axis (Ref_AxisPhy)", "pth": "path axis (Ref_AxisPth)"}
_ERROR_NODE = "__error__"


# --------------------------------------------------------------------------- the document


@dataclass(frozen=True, slots=True)
class Prov:
    """Where a record comes from: its documentary source, interpretation and spec line."""

    source: str
    interpretation: str | None
    line: int


@dataclass(frozen=True, slots=True)
class Operand:
    name: str
    type: str
    data_type: str | None
    default: object
    prov: Prov


@dataclass(frozen=True, slots=True)
class ErrorCode:
    code: int
    name: str
    prov: Prov


@dataclass(frozen=True, slots=True)
class CheckRow:
    number: int  # 1-based, the order of evaluation
    id: str
    code: int
    fails: str
    prov: Prov


@dataclass(frozen=True, slots=True)
class StateRow:
    state: RecoveryState
    description: str
    prov: Prov


@dataclass(frozen=True, slots=True)
class TransitionRow:
    number: int
    source: str
    target: str
    when: str
    prov: Prov


@dataclass(frozen=True, slots=True)
class OnDone:
    when: str
    sets: str
    prov: Prov


@dataclass(frozen=True, slots=True)
class Routine:
    """The rung-false or prescan routine: members cleared, a call issued, facts forgotten."""

    clear: tuple[str, ...]
    abort_call: str | None
    forget: tuple[str, ...]
    prov: Prov


@dataclass(frozen=True, slots=True)
class SubCheckRow:
    number: int
    fails: str
    err: int
    prov: Prov


@dataclass(frozen=True, slots=True)
class SubDocument:
    sub: SubInstruction
    file: str  # as shown: spec/instructions/motion/MAH.yaml
    axis_types: tuple[str, ...]
    checks: tuple[SubCheckRow, ...]
    completes: Prov
    prov: Prov


@dataclass(frozen=True, slots=True)
class WorldFact:
    name: str
    read: str  # the expression or variable it is read from, as written
    sets: tuple[str, ...]  # "value: event, event" for each way a scenario can set it
    prov: Prov


@dataclass(frozen=True, slots=True)
class WorldObject:
    """One kind of object of the world (an axis data type, the handler) and the chart that runs it."""

    kind: str
    chart: str
    facts: tuple[WorldFact, ...]
    prov: Prov


@dataclass(frozen=True, slots=True)
class AoiDocument:
    """An add-on instruction as the renderers need it: the loaded spec plus provenance."""

    spec: AoiSpec
    file: str  # as shown: spec/addons/raM_Opr_SyncPthPhyAx_CD.yaml
    prov: Prov
    execution: str
    execution_source: str
    inputs: tuple[Operand, ...]
    outputs: tuple[Operand, ...]
    errors: tuple[ErrorCode, ...]  # spec order
    checks: tuple[CheckRow, ...]  # evaluation order
    recovery: Prov
    states: tuple[StateRow, ...]
    transitions: tuple[TransitionRow, ...]
    on_done: tuple[OnDone, ...]
    rung_false: Routine
    prescan: Routine
    subs: tuple[SubDocument, ...]
    world: tuple[WorldObject, ...] = ()  # empty when the file has no `world` section
    world_prov: Prov | None = None

    @property
    def id(self) -> str:
        return self.spec.id

    def error(self, code: int) -> ErrorCode | None:
        return next((e for e in self.errors if e.code == code), None)

    def error_name(self, code: int) -> str:
        e = self.error(code)
        return e.name if e else ""

    def sub(self, mnemonic: str) -> SubDocument | None:
        return next((s for s in self.subs if s.sub.mnemonic == mnemonic), None)

    def summary(self) -> dict[str, object]:
        """The counts ``motionchart validate`` prints."""
        return {"id": self.id, "file": self.file, "checks": len(self.checks), "error_codes": len(self.errors),
                "recovery_states": len(self.states), "recovery_transitions": len(self.transitions),
                "sub_instructions": [s.sub.mnemonic for s in self.subs]}


def shown_path(path: Path, spec_dir: Path) -> str:
    """``spec/addons/x.yaml`` for the bundled spec, ``<dir name>/addons/x.yaml`` otherwise; never absolute."""
    root = spec_dir.resolve()
    try:
        rel = path.resolve().relative_to(root).as_posix()
    except ValueError:
        return path.name
    try:
        bundled = root == bundled_spec_dir().resolve()
    except (OSError, ModuleNotFoundError):  # pragma: no cover - package data missing
        bundled = False
    return f"{'spec' if bundled else root.name}/{rel}"


def aoi_spec_dirs(paths: Sequence[Path | str] | None) -> list[Path]:
    """The spec directories whose add-on instructions go with a spec given as ``paths``.

    No paths: the bundled spec.  Otherwise every given directory that has an ``addons/``
    or an ``instructions/motion/`` sub-directory (a file or a directory without either
    has no add-on instruction).
    """
    if not paths:
        return [bundled_spec_dir()]
    dirs: list[Path] = []
    for p in paths:
        d = Path(p)
        if (d.is_dir() and ((d / "addons").is_dir() or (d / "instructions" / "motion").is_dir())
                and all(d.resolve() != x.resolve() for x in dirs)):
            dirs.append(d)
    return dirs


def _prov(p: ir.Provenance, at: ir.Location) -> Prov:
    return Prov(p.source, p.interpretation, at.line)


def load_aoi_document(spec_dir: Path | str | None = None) -> AoiDocument:
    """The add-on instruction of ``spec_dir`` (default: bundled) with its provenance, from the IR.

    Raises :class:`SpecError` with every located problem the loader finds.
    """
    root = Path(spec_dir) if spec_dir is not None else bundled_spec_dir()
    spec = load_aoi(None if spec_dir is None else root)
    a = spec.add_on
    subs = tuple(SubDocument(sub, shown_path(Path(sub.location.file), root), sub.axis_types,
                             tuple(SubCheckRow(n, c.fails.text, c.err, _prov(c.provenance, c.location))
                                   for n, c in enumerate(sub.checks, start=1)),
                             _prov(sub.completes, sub.completes_location), _prov(sub.provenance, sub.location))
                 for sub in sorted(spec.instructions, key=lambda x: x.mnemonic))
    rec = a.recovery

    def routine(r: ir.ScanRule) -> Routine:
        return Routine(r.clear, r.abort_call, r.forget, _prov(r.provenance, r.location))

    world = tuple(WorldObject(o.kind, o.chart, tuple(
        WorldFact(fa.name, fa.when.text if fa.when is not None else f"variable {fa.variable}",
                  tuple(f"{_value(x.value)}: {', '.join(x.fire)}" for x in fa.set), _prov(fa.provenance, fa.location))
        for fa in o.facts), _prov(o.provenance, o.location)) for o in a.world.objects)
    return AoiDocument(
        spec=spec, file=shown_path(Path(a.location.file), root), prov=_prov(a.provenance, a.location),
        execution=a.execution.mode, execution_source=a.execution.provenance.source,
        inputs=tuple(Operand(p.name, p.type, p.data_type, p.default, _prov(p.provenance, p.location))
                     for p in a.parameters),
        outputs=tuple(Operand(m.name, m.type, None, None, _prov(m.provenance, m.location)) for m in a.status),
        errors=tuple(ErrorCode(e.code, e.name, _prov(e.provenance, e.location)) for e in a.errors),
        checks=tuple(CheckRow(n, c.id, c.err, c.fails_when.text, _prov(c.provenance, c.location))
                     for n, c in enumerate(a.checks, start=1)),
        recovery=_prov(rec.provenance, rec.location),
        states=tuple(StateRow(st, st.description, _prov(st.provenance, st.location)) for st in rec.states),
        transitions=tuple(TransitionRow(n, t.source, t.target, t.when.text, _prov(t.provenance, t.location))
                          for n, t in enumerate(rec.transitions, start=1)),
        on_done=tuple(OnDone(o.when.text, o.set, _prov(o.provenance, o.location)) for o in a.on_done),
        rung_false=routine(a.rung_false), prescan=routine(a.prescan), subs=subs, world=world,
        world_prov=_prov(a.world.provenance, a.world.location),
    )


def load_aoi_documents(paths: Sequence[Path | str] | None) -> list[AoiDocument]:
    """Every add-on instruction that goes with the spec ``paths`` (see :func:`aoi_spec_dirs`).

    All problems of all directories are raised together as one :class:`SpecError`.
    """
    docs: list[AoiDocument] = []
    errors: list[Diagnostic] = []
    for d in aoi_spec_dirs(paths):
        try:
            docs.append(load_aoi_document(None if paths is None or not paths else d))
        except SpecError as exc:
            errors.extend(exc.diagnostics)
    seen: dict[str, AoiDocument] = {}
    for doc in docs:
        if doc.id in seen:
            errors.append(Diagnostic(doc.file, doc.prov.line, 1, "add_on_instruction.id",
                                     f"add-on instruction {doc.id!r} is also defined in {seen[doc.id].file}"))
        seen.setdefault(doc.id, doc)
    if errors:
        raise SpecError(errors)
    return docs


# --------------------------------------------------------------------------- wording


def call_text(state: RecoveryState) -> str:
    """``MAH on the physical axis (Ref_AxisPhy)``; with a master, ``..., master: ...``."""
    if state.call is None:
        return ""
    c = state.call
    out = f"{c.instruction} on the {AXIS_ROLES.get(c.axis, c.axis)}"
    if c.master:
        out += f", master: the {AXIS_ROLES.get(c.master, c.master)}"
    return out


def operand_lines(state: RecoveryState) -> list[str]:
    return [f"{k} := {e.text}" for k, e in state.call.operands] if state.call else []


def _on_done_text(o: OnDone) -> str:
    return f"set {o.sets}" if o.when == "True" else f"if {o.when}: set {o.sets}"


def flowchart_name(doc: AoiDocument) -> str:
    return doc.id


def recovery_name(doc: AoiDocument) -> str:
    return doc.id + RECOVERY_SUFFIX


def diagram_names(docs: Sequence[AoiDocument]) -> dict[str, tuple[AoiDocument, str]]:
    """``motionchart diagram`` names: ``<ID>`` (flowchart) and ``<ID>_recovery`` (state diagram)."""
    out: dict[str, tuple[AoiDocument, str]] = {}
    for doc in docs:
        out[flowchart_name(doc)] = (doc, "flowchart")
        out[recovery_name(doc)] = (doc, "recovery")
    return out


# --------------------------------------------------------------------------- flowchart


def build_aoi_flowchart(doc: AoiDocument) -> Flowchart:
    """The manual-style flowchart: the ordered checks, each to its code, then the recovery branch.

    Node ids: ``check_<id>`` (one decision per check, in evaluation order) with its
    error box ``err_<id>``; ``route_<n>`` for the transitions out of the initial
    recovery state (tried in spec order); ``state_<id>`` for the recovery states, and
    ``err_state_<id>`` for the code of a state whose call fails.
    """
    nodes: list[FlowNode] = []
    edges: list[FlowEdge] = []
    side: list[tuple[str, str]] = []
    spec = doc.spec

    nodes.append(FlowNode("start", "terminal", ("Rung-condition-in true",)))
    nodes.append(FlowNode("execute", "process", ("A new execution starts", "(the rung was false before)")))
    edges.append(FlowEdge("start", "execute"))
    prev = "execute"
    for check in doc.checks:
        did, eid = f"check_{check.id}", f"err_{check.id}"
        name = doc.error_name(check.code) or check.id
        title = [f"{check.number}. {line}" if i == 0 else line for i, line in enumerate(paragraph(name + "?", 30))]
        nodes.append(FlowNode(did, "decision", tuple(title), tuple(wrap(check.fails, 30))))
        nodes.append(FlowNode(eid, "error", ("Sts_ER set", f"Sts_ERR = {check.code}", *paragraph(name, 34))))
        edges.append(FlowEdge(prev, did, "no" if prev.startswith("check_") else ""))
        edges.append(FlowEdge(did, eid, "yes"))
        side.append((did, eid))
        prev = did

    initial = spec.add_on.recovery.initial
    nodes.append(FlowNode("recovery", "process", ("Every check passed:", f"the recovery leaves {initial}")))
    edges.append(FlowEdge(prev, "recovery", "no" if prev.startswith("check_") else ""))
    prev, label = "recovery", ""
    routes = [t for t in doc.transitions if t.source == initial]
    for t in routes:
        rid = f"route_{t.number}"
        nodes.append(FlowNode(rid, "decision", (f"to {t.target}?",), tuple(wrap(t.when, 30))))
        edges.append(FlowEdge(prev, rid, label))
        edges.append(FlowEdge(rid, f"state_{t.target}", "yes"))
        prev, label = rid, "no"
    nodes.append(FlowNode("no_route", "wait", ("No branch holds:", f"stays in {initial}")))
    edges.append(FlowEdge(prev, "no_route", label))

    for row in doc.states:
        s = row.state
        if s.id in ("idle", initial):
            continue
        sid = f"state_{s.id}"
        if s.id == "done":
            nodes.append(FlowNode(sid, "done", ("done: Sts_PC set",), tuple(_on_done_text(o) for o in doc.on_done)))
            continue
        if s.call is None:
            nodes.append(FlowNode(sid, "process", (s.id, *paragraph(row.description, 34))))
            continue
        sub = doc.sub(s.call.instruction)
        call_title = (f"{s.id}: {s.call.instruction}" + (f" ({sub.sub.name})" if sub else ""),
                      *paragraph(call_text(s).split(" on ", 1)[-1], 40), "Sts_IP set while it is in process")
        nodes.append(FlowNode(sid, "process", call_title, tuple(operand_lines(s))))
        eid = f"err_state_{s.id}"
        nodes.append(FlowNode(eid, "error", ("Sts_ER set", f"Sts_ERR = {s.error}",
                                             f"Sts_EXERR = {s.call.instruction} .ERR",
                                             *paragraph(doc.error_name(int(s.error or 0)), 34))))
        edges.append(FlowEdge(sid, eid, "fails"))
        side.append((sid, eid))
    for t in doc.transitions:
        if t.source == initial:
            continue
        label = "done" if t.when == "call.done" else "" if t.when == "True" else t.when
        edges.append(FlowEdge(f"state_{t.source}", f"state_{t.target}", label))

    note = (
        "The checks run top to bottom when an execution starts; the first that holds sets Sts_ER and its code,",
        "which stay until the rung goes false.",
        "A call's own preconditions fail with the state's code and the call's .ERR in Sts_EXERR.",
    )
    spine = ("start", "execute", *(f"check_{c.id}" for c in doc.checks), "recovery",
             *(f"route_{t.number}" for t in routes), "no_route")
    return Flowchart(doc.id, f"{doc.id}: execution with rung-condition-in true", note, tuple(nodes),
                     tuple(edges), tuple(side), spine)


def aoi_flowchart_dot(doc: AoiDocument) -> str:
    return flowchart_dot(build_aoi_flowchart(doc))


def aoi_flowchart_mermaid(doc: AoiDocument) -> str:
    return flowchart_mermaid(build_aoi_flowchart(doc))


# --------------------------------------------------------------------------- recovery chart

_DERIVED = ("#6b6b6b", "dashed")
_ERROR = ("#a31515", "dashed")


def _state_compartment(doc: AoiDocument, row: StateRow) -> list[str]:
    s = row.state
    lines: list[str] = []
    if s.id == doc.spec.add_on.recovery.initial:
        lines.append(f"checks 1 to {len(doc.checks)} run here, in order" if doc.checks else "no checks")
    if s.call is not None:
        lines.append(f"call {call_text(s)}")
        lines.extend(f"  {x}" for x in operand_lines(s))
        lines.append(f"on error: Sts_ERR = {s.error}, Sts_EXERR = .ERR")
    if s.id == "done":
        lines.append("entry / Sts_PC = 1, Sts_IP = 0")
        lines.extend(f"entry / {_on_done_text(o)}" for o in doc.on_done)
    return lines


def _transition_labels(doc: AoiDocument) -> list[str]:
    """``[when]``, prefixed with the try order ``2:`` when a state has several transitions."""
    out: list[str] = []
    for t in doc.transitions:
        siblings = [x for x in doc.transitions if x.source == t.source]
        order = f"{siblings.index(t) + 1}: " if len(siblings) > 1 else ""
        out.append(f"{order}[{t.when}]")
    return out


def _routine_lines(doc: AoiDocument) -> list[str]:
    rf, ps = doc.rung_false, doc.prescan
    lines = ["Rung false, from any state: back to idle;", f"clears {', '.join(rf.clear)}"]
    if rf.abort_call:
        lines.append(f"a call in process is stopped with {rf.abort_call}")
    lines.append(f"Prescan: clears {', '.join(ps.clear)}")
    if ps.forget:
        lines.append(f"and forgets {', '.join(ps.forget)}")
    return lines


def recovery_dot(doc: AoiDocument) -> str:
    """DOT text of the recovery chart: the spec's states and transitions, plus the entry
    from ``idle``, the error exits and the rung-false rule of the execution (dashed)."""
    spec = doc.spec
    g = graphviz.Digraph(
        name=f"{doc.id}_recovery",
        graph_attr=sorted_attrs({"fontname": FONT, "fontsize": "11", "labelloc": "t", "labeljust": "l",
                                 "rankdir": "TB", "nodesep": "0.5", "ranksep": "0.5", "pad": "0.3",
                                 "bgcolor": "white", "newrank": "true"}),
        node_attr=sorted_attrs({"fontname": FONT, "fontsize": "10"}),
        edge_attr=sorted_attrs({"fontname": FONT, "fontsize": "9", "arrowsize": "0.8"}),
    )
    keys = [f'<FONT COLOR="#000000">{esc("———")}</FONT> {esc("spec transition [condition]")}',
            f'<FONT COLOR="{_DERIVED[0]}">{esc("– – –")}</FONT> {esc("execution rule")}',
            f'<FONT COLOR="{_ERROR[0]}">{esc("– – –")}</FONT> {esc("error exit")}']
    g.attr(label=html_table([html_lines([f"{doc.id}: recovery chart"], bold=True, size=14),
                             '<FONT POINT-SIZE="9">' + "    ".join(keys) + "</FONT>"], separators=False))
    g.node("__initial__", label="", shape="point", width="0.16", color="black")
    for row in doc.states:
        s = row.state
        rows = [html_lines([s.id], bold=True)]
        if row.description:
            rows.append(html_lines(paragraph(row.description, 40), size=9))
        comp = _state_compartment(doc, row)
        if comp:
            rows.append(html_lines([x for line in comp for x in wrap(line, 46)], face=MONO, size=8))
        done = s.id == "done"
        g.node(s.id, **sorted_attrs({
            "label": html_table(rows), "shape": "box", "style": "rounded,filled" + (",bold" if done else ""),
            "fillcolor": "#e6f4ea" if done else "#f4f6fa", "color": "#1e7b34" if done else "#3c4a5c",
            "margin": "0.12,0.06", "tooltip": row.description or s.id,
        }))
    g.node(_ERROR_NODE, **sorted_attrs({
        "label": html_table([html_lines(["error"], bold=True),
                             html_lines(["Sts_ER = 1, Sts_ERR = code, Sts_EXERR", "held until the rung goes false"],
                                        size=9)]),
        "shape": "box", "style": "filled,bold", "fillcolor": "#fde8e8", "color": "#a31515", "margin": "0.12,0.06",
    }))
    g.node("__routines__", **sorted_attrs({
        "label": html_table([html_lines(_routine_lines(doc), size=9)], separators=False), "shape": "note",
        "style": "filled", "fillcolor": "#ffffff", "color": "#8a94a6",
    }))

    def edge(tail: str, head: str, label: list[str], colour: str, style: str, tooltip: str) -> None:
        attrs = {"color": colour, "fontcolor": colour, "style": style, "tooltip": tooltip}
        if label:
            attrs["label"] = "<" + html_lines(label, face=MONO, size=8, color=colour) + ">"
        g.edge(tail, head, **sorted_attrs(attrs))

    g.edge("__initial__", "idle")
    edge("idle", spec.add_on.recovery.initial, ["rung true:", "new execution"], *_DERIVED, "new execution")
    for t, label in zip(doc.transitions, _transition_labels(doc)):
        edge(t.source, t.target, wrap(label, 30), "#000000", "solid", f"transition {t.number}")
    edge(spec.add_on.recovery.initial, _ERROR_NODE, ["[a check fails]", "/ Sts_ERR = its code"], *_ERROR, "a check fails")
    for row in doc.states:
        s = row.state
        if s.call is not None:
            edge(s.id, _ERROR_NODE, [f"[{s.call.instruction} fails]", f"/ Sts_ERR = {s.error}"], *_ERROR,
                 f"{s.call.instruction} fails")
    with g.subgraph() as r:
        r.attr(rank="same")
        r.node("idle")
        r.node("__routines__")
    return str(g.source)


_MERMAID_ERROR = "error_exit"  # cannot clash with a spec state: ``_mid`` gives ``s_<id>``


def _mid(state_id: str) -> str:
    return f"s_{state_id}"


def recovery_mermaid(doc: AoiDocument) -> str:
    """The recovery chart as Mermaid ``stateDiagram-v2`` (same facts as :func:`recovery_dot`)."""
    spec = doc.spec
    title = f"{doc.id}: recovery chart".replace('"', '\\"')
    out = ["---", f'title: "{title}"', "---", "stateDiagram-v2", f"{INDENT}direction TB",
           f"{INDENT}[*] --> {_mid('idle')}"]
    for row in doc.states:
        s = row.state
        out.append(f'{INDENT}state "{text(s.id)}" as {_mid(s.id)}')
        for line in ([row.description] if row.description else []) + _state_compartment(doc, row):
            out.append(f"{INDENT}{_mid(s.id)} : {text(line.strip())}")
    out.append(f'{INDENT}state "error" as {_MERMAID_ERROR}')
    out.append(f"{INDENT}{_MERMAID_ERROR} : {text('Sts_ER = 1, Sts_ERR = code, Sts_EXERR; held until the rung goes false')}")
    out.append(f"{INDENT}{_mid('idle')} --> {_mid(spec.add_on.recovery.initial)} : {text('rung true: new execution')}")
    for t, label in zip(doc.transitions, _transition_labels(doc)):
        out.append(f"{INDENT}{_mid(t.source)} --> {_mid(t.target)} : {text(label)}")
    out.append(f"{INDENT}{_mid(spec.add_on.recovery.initial)} --> {_MERMAID_ERROR} : {text('[a check fails] / Sts_ERR = its code')}")
    for row in doc.states:
        s = row.state
        if s.call is not None:
            label = f"[{s.call.instruction} fails] / Sts_ERR = {s.error}"
            out.append(f"{INDENT}{_mid(s.id)} --> {_MERMAID_ERROR} : {text(label)}")
    out.append(f"{INDENT}note right of {_mid('idle')}")
    out.extend(f"{INDENT * 2}{text(line)}" for line in _routine_lines(doc))
    out.append(f"{INDENT}end note")
    out.append(f"{INDENT}classDef errorState fill:#fde8e8,stroke:#a31515,stroke-width:2px")
    out.append(f"{INDENT}class {_MERMAID_ERROR} errorState")
    out.append(f"{INDENT}classDef doneState fill:#e6f4ea,stroke:#1e7b34,stroke-width:2px")
    out.append(f"{INDENT}class {_mid('done')} doneState")
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------- reference page


def page_path(doc: AoiDocument) -> str:
    return f"aoi/{doc.id}.md"


def _where(doc: AoiDocument, prov: Prov, file: str | None = None) -> str:
    return f"`{file or doc.file}:{prov.line}`"


def _interp(prov: Prov, p: str) -> str:
    return interp_link(prov.interpretation, p)


def _diagram(svg: str, mmd: str, mmd_link: str, dot_link: str, alt: str) -> list[str]:
    return [f"![{alt}]({svg})", "", f"Sources: [Graphviz DOT]({dot_link}), [Mermaid]({mmd_link}).", "",
            "<details><summary>Mermaid version (GitHub renders it without Graphviz)</summary>", "", "```mermaid",
            mmd.rstrip("\n"), "```", "", "</details>"]


def _value(v: object) -> str:
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def reported_by(doc: AoiDocument, code_: int, p: str = "") -> list[str]:
    """Links to what reports ``code_``: checks (``#check-<id>``) and recovery states (``#state-<id>``)."""
    out = [f"[check {c.number} `{c.id}`]({p}#{anchor('check-' + c.id)})" for c in doc.checks if c.code == code_]
    out += [f"[state `{s.state.id}`]({p}#{anchor('state-' + s.state.id)}) ({s.state.call.instruction} fails)"
            for s in doc.states if s.state.call is not None and s.state.error == code_]
    return out


def aoi_page(doc: AoiDocument, tr: Traceability, catalog: dict[int, str] | None = None,
             charts: Sequence[str] = ()) -> str:
    """The Markdown reference page of one add-on instruction (``aoi/<ID>.md``).

    ``catalog`` maps a motion instruction's ``.ERR`` code to its name (the main spec's
    error catalog); codes in it link to ``error-codes.md``.  ``charts``: the chart ids
    that have a page (``charts/<id>.md``), linked from the world section.
    """
    p = "../"
    cat = catalog or {}
    traced = tr.root is not None
    fc, rc = flowchart_name(doc), recovery_name(doc)
    sub_files = sorted({s.file.rsplit("/", 1)[0] + "/" for s in doc.subs})
    out = [GENERATED_NOTE, "", f"# {doc.id} (add-on instruction)", "",
           "An add-on instruction: a routine with its own backing tag (the `Sts_` members below) that "
           "checks its inputs and the device handler in a fixed order, reports the first failure as its own "
           "code, and otherwise runs a recovery made of calls to motion instructions. This page is drawn from "
           "the spec files named below; every row gives its documentary source and the spec line it is "
           "defined at.", ""]
    out += [f"- Source: {cell(doc.prov.source)}"]
    if doc.prov.interpretation:
        out += [f"- Interpretation: {_interp(doc.prov, p)}"]
    out += [
        f"- Execution: {doc.execution}" + (f" ({cell(doc.execution_source)})" if doc.execution_source else ""),
        f"- Defined at: `{doc.file}`; the motion instructions it calls: "
        + ", ".join(f"`{d}`" for d in sub_files),
        f"- Counts: {len(doc.inputs)} inputs, {len(doc.outputs)} status members, {len(doc.checks)} ordered checks, "
        f"{len(doc.errors)} error codes, {len(doc.states)} recovery states, {len(doc.transitions)} transitions, "
        f"{len(doc.subs)} sub-instructions",
        "- The model behind it (world, scan order, scenarios) is described in `docs/aoi.md`.",
        "", "## Flowchart", "",
    ]
    out += _diagram(f"{p}flowcharts/{fc}.svg", aoi_flowchart_mermaid(doc), f"{p}flowcharts/{fc}.mmd",
                    f"{p}flowcharts/{fc}.dot", f"Flowchart of {doc.id}")

    out += ["", "## Inputs", ""]
    out += table(["Input", "Kind", "Data type", "Default", "Source", "Interpretation", "Defined at"], [
        [f"`{i.name}`", i.type, f"`{i.data_type}`" if i.data_type else "—", cell(_value(i.default)),
         cell(i.prov.source), _interp(i.prov, p), _where(doc, i.prov)]
        for i in doc.inputs
    ])
    out += ["", "## Outputs (status members)", ""]
    out += table(["Member", "Type", "Source", "Interpretation", "Defined at"], [
        [f"`{o.name}`", o.type, cell(o.prov.source), _interp(o.prov, p), _where(doc, o.prov)] for o in doc.outputs
    ])

    out += ["", "## Checks, in the order they run", "",
            "When an execution starts (the rung goes true after being false) the checks are tried from the "
            "top. The first whose condition holds ends the execution: `Sts_ER` is set and `Sts_ERR` takes the "
            "check's code. When no check holds, the recovery chart takes over.", ""]
    out += table(["#", "Check", "Code", "Fails when", "Error", "Source", "Interpretation",
                  "Defined at"], [
        [str(c.number), f'<a id="{anchor("check-" + c.id)}"></a>`{c.id}`',
         f"[{c.code}](#{anchor('code-' + str(c.code))})",
         code(c.fails),
         cell(doc.error_name(c.code)), cell(c.prov.source), _interp(c.prov, p), _where(doc, c.prov)]
        for c in doc.checks
    ])

    out += ["", "## Error codes", "",
            "Every code the instruction reports in `Sts_ERR`, by number. A code reported by a recovery state "
            "comes with the failing call's own `.ERR` in `Sts_EXERR`."
            + (" *Scenarios* lists the add-on instruction scenarios that observed the code with `Sts_ER` set."
               if traced else ""), ""]
    rows = []
    for e in sorted(doc.errors, key=lambda e: e.code):
        rows.append([f'<a id="{anchor("code-" + str(e.code))}"></a>{e.code}', cell(e.name),
                     ", ".join(reported_by(doc, e.code)) or "— (reported by nothing)", cell(e.prov.source),
                     _interp(e.prov, p), _where(doc, e.prov)]
                    + ([scenario_links(tr.aoi_producing(e.code), p, 3, tr.link_base)] if traced else []))
    out += table(["Code", "Name", "Reported by", "Source", "Interpretation", "Defined at"]
                 + (["Scenarios"] if traced else []), rows)

    out += ["", "## Recovery chart", "",
            f"Once every check has passed, the execution leaves `{doc.spec.add_on.recovery.initial}` by the first transition "
            "whose condition holds (transitions are tried in the order listed) and moves from state to state. "
            "A state with a call issues one motion instruction; its preconditions are checked first, and the "
            "first that fails ends the execution with the state's code. A call is complete when "
            "`call.done` holds. Dashed edges in the diagram are execution rules rather than spec transitions: "
            "a rung that goes true in `idle` starts an execution, and a rung that goes false returns to `idle` "
            "from any state.", ""]
    out += [f"Source: {cell(doc.recovery.source)}"
            + (f"; interpretation {_interp(doc.recovery, p)}" if doc.recovery.interpretation else "") + ".", ""]
    out += _diagram(f"{p}diagrams/{rc}.svg", recovery_mermaid(doc), f"{p}diagrams/{rc}.mmd",
                    f"{p}diagrams/{rc}.dot", f"Recovery chart of {doc.id}")
    out += ["", "### States", ""]
    if traced:
        out += ["*Scenarios observing it* lists the scenarios in which some instance was in the state at the end "
                "of a scan. A state left in the scan it was entered (checking, a call that completes at once) "
                "is passed through without being observed, so *none* there is no gap in the scenarios.", ""]
    out += table(["State", "Meaning", "Call", "Operands", "Code if the call fails", "Source", "Interpretation",
                  "Defined at"] + (["Scenarios observing it"] if traced else []), [
        [f'<a id="{anchor("state-" + r.state.id)}"></a>`{r.state.id}`'
         + (" (entered first)" if r.state.id == doc.spec.add_on.recovery.initial else ""),
         cell(r.description),
         (f"[{r.state.call.instruction}](#{anchor('sub-' + r.state.call.instruction)}) on the "
          + cell(call_text(r.state).split(" on the ", 1)[1])) if r.state.call else "—",
         code("; ".join(operand_lines(r.state))) if r.state.call and r.state.call.operands else "—",
         f"[{r.state.error}](#{anchor('code-' + str(r.state.error))})" if r.state.error is not None else "—",
         cell(r.prov.source), _interp(r.prov, p), _where(doc, r.prov)]
        + ([scenario_links(tr.aoi_reaching(r.state.id), p, 3, tr.link_base)] if traced else [])
        for r in doc.states
    ])
    out += ["", "### Transitions", ""]
    out += table(["#", "From", "To", "When", "Source", "Interpretation", "Defined at"], [
        [str(t.number), f"`{t.source}`", f"`{t.target}`", code(t.when), cell(t.prov.source), _interp(t.prov, p),
         _where(doc, t.prov)]
        for t in doc.transitions
    ])

    out += ["", "## Sub-instructions", "",
            "The motion instructions the recovery calls, as the model runs them: preconditions in order "
            "(the first that holds makes the call fail with that `.ERR`, which the add-on instruction reports "
            "in `Sts_EXERR`), then how the call completes.", ""]
    for s in doc.subs:
        sub = s.sub
        users = [r.state.id for r in doc.states if r.state.call and r.state.call.instruction == sub.mnemonic]
        called_by = ", ".join(f"[`{u}`](#{anchor('state-' + u)})" for u in users)
        roles = []
        if doc.rung_false.abort_call == sub.mnemonic:
            roles.append("stops a call in process when the rung goes false")
        out += [f'<a id="{anchor("sub-" + sub.mnemonic)}"></a>', "", f"### {sub.mnemonic}: {sub.name}", ""]
        out += [f"- Source: {cell(s.prov.source)}"
                + (f"; interpretation {_interp(s.prov, p)}" if s.prov.interpretation else ""),
                f"- Axis data types: {', '.join(f'`{t}`' for t in s.axis_types) or '—'}",
                f"- Called by: {called_by or '—'}"
                + (f"; {'; '.join(roles)}" if roles else ""),
                f"- Completes: {sub.kind}" + (f" after {sub.scans} scans" if sub.kind == 'home' else "")
                + f" ({cell(s.completes.source)}"
                + (f"; {_interp(s.completes, p)}" if s.completes.interpretation else "") + ")",
                f"- Defined at: `{s.file}`", ""]
        if not s.checks:
            out += ["No preconditions: in the model this call cannot fail.", ""]
            continue
        out += table(["#", "Fails when", ".ERR", "Name", "Source", "Interpretation", "Defined at"], [
            [str(c.number), code(c.fails),
             f"[{c.err}]({p}error-codes.md#{anchor('err-' + str(c.err))})" if c.err in cat else str(c.err),
             f"`{cat[c.err]}`" if c.err in cat else "—", cell(c.prov.source), _interp(c.prov, p),
             _where(doc, c.prov, s.file)]
            for c in s.checks
        ])
        out += [""]

    out += ["## Completion, rung false and prescan", "",
            "When the recovery reaches `done`, `Sts_PC` is set, `Sts_IP` cleared and the following facts are "
            "recorded, each when its condition holds:", ""]
    out += table(["When", "Sets", "Source", "Interpretation", "Defined at"], [
        ["always" if o.when == "True" else code(o.when), f"`{o.sets}`", cell(o.prov.source), _interp(o.prov, p),
         _where(doc, o.prov)]
        for o in doc.on_done
    ])
    rf, ps = doc.rung_false, doc.prescan
    out += ["", "| Routine | Clears | Also | Source | Interpretation | Defined at |", "|---|---|---|---|---|---|",
            f"| rung false (EnableIn false) | {', '.join(f'`{x}`' for x in rf.clear) or '—'} | "
            + (f"a call in process is stopped with [{rf.abort_call}](#{anchor('sub-' + rf.abort_call)}); "
               if rf.abort_call else "")
            + f"members not listed keep their values | {cell(rf.prov.source)} | {_interp(rf.prov, p)} | "
            f"{_where(doc, rf.prov)} |",
            f"| prescan | {', '.join(f'`{x}`' for x in ps.clear) or '—'} | "
            + (f"forgets {', '.join(f'`{x}`' for x in ps.forget)}; " if ps.forget else "")
            + f"runs after the rung-false routine | {cell(ps.prov.source)} | {_interp(ps.prov, p)} | "
            f"{_where(doc, ps.prov)} |"]
    if traced:
        out += ["", f"Scenarios that complete it (`Sts_PC` observed): "
                    f"{scenario_links(tr.aoi_completing(), p, base=tr.link_base)}"]
    if doc.world:
        out += _world_section(doc, p, charts)
    return "\n".join(out) + "\n"


def _world_section(doc: AoiDocument, p: str, charts: Sequence[str]) -> list[str]:
    wp = doc.world_prov
    out = ["", "## The world it runs in", "",
           "The handler and the axes the instruction reads are run by charts of the specification. Each fact "
           "the checks and calls read (`phy.faulted`, `handler.mode`, ...) is read from its object's chart as "
           "shown; *Set by* lists the chart events a scenario's `set:` of that fact fires.", ""]
    if wp is not None:
        out += [f"Source: {cell(wp.source)}" + (f"; interpretation {_interp(wp, p)}" if wp.interpretation else "")
                + f". Defined at {_where(doc, wp)}.", ""]
    out += table(["Object", "Chart", "Facts", "Source", "Interpretation", "Defined at"], [
        [f'<a id="{anchor("world-" + o.kind)}"></a>`{o.kind}`',
         f"[{o.chart}]({p}charts/{o.chart}.md)" if o.chart in charts else f"`{o.chart}`",
         str(len(o.facts)), cell(o.prov.source), _interp(o.prov, p), _where(doc, o.prov)]
        for o in doc.world
    ])
    out += ["", "| Object | Fact | Read from | Set by | Source | Interpretation | Defined at |",
            "|---|---|---|---|---|---|---|"]
    for o in doc.world:
        for f in o.facts:
            out.append(f"| `{o.kind}` | `{f.name}` | {code(f.read)} | {cell('; '.join(f.sets))} | "
                       f"{cell(f.prov.source)} | {_interp(f.prov, p)} | {_where(doc, f.prov)} |")
    return out


def aoi_uses(doc: AoiDocument) -> dict[str, list[Use]]:
    """Every element of the add-on instruction that cites an interpretation, for ``interpretations.md``."""
    page = page_path(doc)
    uses: dict[str, list[Use]] = {}

    def add(prov: Prov, label: str, link: str) -> None:
        if prov.interpretation:
            uses.setdefault(prov.interpretation, []).append(Use(prov.interpretation, label, link))

    add(doc.prov, f"add-on instruction {doc.id}", page)
    for i in doc.inputs:
        add(i.prov, f"{doc.id} input {i.name}", f"{page}#inputs")
    for out in doc.outputs:
        add(out.prov, f"{doc.id} output {out.name}", f"{page}#outputs-status-members")
    for e in doc.errors:
        add(e.prov, f"{doc.id} error code {e.code}", f"{page}#{anchor('code-' + str(e.code))}")
    for c in doc.checks:
        add(c.prov, f"{doc.id} check {c.id}", f"{page}#{anchor('check-' + c.id)}")
    add(doc.recovery, f"{doc.id} recovery chart", f"{page}#recovery-chart")
    for s in doc.states:
        add(s.prov, f"{doc.id} recovery state {s.state.id}", f"{page}#{anchor('state-' + s.state.id)}")
    for t in doc.transitions:
        add(t.prov, f"{doc.id} transition {t.source} -> {t.target}", f"{page}#transitions")
    for n, o in enumerate(doc.on_done, start=1):
        add(o.prov, f"{doc.id} on done {n} (set {o.sets})", f"{page}#completion-rung-false-and-prescan")
    add(doc.rung_false.prov, f"{doc.id} rung-false routine", f"{page}#completion-rung-false-and-prescan")
    add(doc.prescan.prov, f"{doc.id} prescan routine", f"{page}#completion-rung-false-and-prescan")
    if doc.world_prov is not None:
        add(doc.world_prov, f"{doc.id} world", f"{page}#the-world-it-runs-in")
    for obj in doc.world:
        link = f"{page}#{anchor('world-' + obj.kind)}"
        add(obj.prov, f"{doc.id} world object {obj.kind} ({obj.chart})", link)
        for f in obj.facts:
            add(f.prov, f"{doc.id} world fact {obj.kind}.{f.name}", link)
    for sd in doc.subs:
        link = f"{page}#{anchor('sub-' + sd.sub.mnemonic)}"
        add(sd.prov, f"sub-instruction {sd.sub.mnemonic}", link)
        add(sd.completes, f"sub-instruction {sd.sub.mnemonic} completion", link)
        for sc in sd.checks:
            add(sc.prov, f"sub-instruction {sd.sub.mnemonic} precondition {sc.number} (.ERR {sc.err})", link)
    return uses


def index_rows(docs: Sequence[AoiDocument]) -> list[list[str]]:
    """Rows of the index page's add-on instruction table."""
    return [
        [f"[{d.id}]({page_path(d)})", str(len(d.checks)), str(len(d.errors)), str(len(d.states)),
         ", ".join(s.sub.mnemonic for s in d.subs),
         f"[flowchart](flowcharts/{flowchart_name(d)}.svg) ([dot](flowcharts/{flowchart_name(d)}.dot) · "
         f"[mermaid](flowcharts/{flowchart_name(d)}.mmd)) · [recovery chart](diagrams/{recovery_name(d)}.svg) "
         f"([dot](diagrams/{recovery_name(d)}.dot) · [mermaid](diagrams/{recovery_name(d)}.mmd))",
         f"`{d.file}`"]
        for d in docs
    ]


INDEX_HEADER = ("Add-on instruction", "Checks", "Codes", "Recovery states", "Calls", "Diagrams", "Spec file")


__all__ = [
    "INDEX_HEADER",
    "AoiDocument",
    "aoi_flowchart_dot",
    "aoi_flowchart_mermaid",
    "aoi_page",
    "aoi_spec_dirs",
    "aoi_uses",
    "build_aoi_flowchart",
    "diagram_names",
    "flowchart_name",
    "index_rows",
    "load_aoi_document",
    "load_aoi_documents",
    "page_path",
    "recovery_dot",
    "recovery_mermaid",
    "recovery_name",
]
