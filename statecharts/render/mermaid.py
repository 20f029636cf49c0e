"""IR -> Mermaid text: ``stateDiagram-v2`` for charts, ``flowchart`` for instructions.

Pipeline position: IR -> **mermaid** -> ``generated/diagrams/*.mmd``,
``generated/flowcharts/*.mmd`` and the ```` ```mermaid ```` blocks of the reference
pages.  GitHub (and any Mermaid renderer) draws them with no Graphviz binary.

The text carries the same facts as the DOT diagrams (:mod:`statecharts.render.dot`,
:mod:`statecharts.render.flowchart`): compound states as composite states, parallel
regions separated by ``--``, history pseudo-states as ``H`` / ``H*`` states, state
values in the titles, ``event [guard] / actions`` on transitions, entry/exit actions
and internal transitions as state descriptions (notes for composite states, which
Mermaid does not give descriptions).  Characters Mermaid would read as syntax are
written as its numeric entity codes (``#35;``).  Statements follow spec order, so the
same spec gives the same bytes.
"""

from __future__ import annotations

from statecharts import ir
from statecharts.render.flowchart import Flowchart, Routine, build_flowchart
from statecharts.render.labels import children, internal_transitions, state_title

INDENT = "    "
#: Characters written as entity codes in Mermaid text.
_SPECIAL = {'"': "#34;", "#": "#35;", "%": "#37;", ";": "#59;", "<": "#60;", ">": "#62;",
            "{": "#123;", "}": "#125;", "|": "#124;", "`": "#96;"}


def text(s: str) -> str:
    """Mermaid-safe text (entity codes for characters Mermaid would parse)."""
    out = []
    for ch in " ".join(s.split()):
        out.append(_SPECIAL.get(ch, ch))
    return "".join(out)


def _front_matter(title: str) -> list[str]:
    """YAML front matter with the diagram's title (quoted: titles contain colons)."""
    quoted = " ".join(title.split()).replace("\\", "\\\\").replace('"', '\\"')
    return ["---", f'title: "{quoted}"', "---"]


def _sid(state_id: str) -> str:
    return state_id


def _transition_label(t: ir.Transition) -> str:
    parts = []
    if t.event:
        parts.append(t.event)
    if t.guard is not None:
        parts.append(f"[{t.guard.text}]")
    if t.actions:
        parts.append("/ " + ", ".join(a.text for a in t.actions))
    return text(" ".join(parts))


def _descriptions(chart: ir.Chart, s: ir.State) -> list[str]:
    lines = [f"entry / {a.text}" for a in s.entry] + [f"exit / {a.text}" for a in s.exit]
    for t in internal_transitions(chart, s.id):
        head = " ".join(x for x in (t.event or "", f"[{t.guard.text}]" if t.guard else "") if x)
        lines.append(f"{head} / " + ", ".join(a.text for a in t.actions))
    return lines


def chart_mermaid(chart: ir.Chart) -> str:
    """The ``stateDiagram-v2`` text of ``chart``."""
    out = [*_front_matter(f"{chart.name} ({chart.id})"), "stateDiagram-v2", f"{INDENT}direction TB"]
    finals: list[str] = []
    history: list[str] = []

    def emit(states: list[ir.State], depth: int) -> None:
        pad = INDENT * depth
        for s in states:
            title = text(state_title(s))
            if s.kind is ir.StateKind.COMPOUND:
                out.append(f'{pad}state "{title}" as {_sid(s.id)} {{')
                assert s.initial is not None
                out.append(f"{pad}{INDENT}[*] --> {_sid(s.initial)}")
                emit(children(chart, s.id), depth + 1)
                out.append(f"{pad}}}")
            elif s.kind is ir.StateKind.PARALLEL:
                out.append(f'{pad}state "{title}" as {_sid(s.id)} {{')
                regions = children(chart, s.id)
                for j, r in enumerate(regions):
                    if j:
                        out.append(f"{pad}{INDENT}--")
                    emit([r], depth + 1)
                out.append(f"{pad}}}")
            elif s.kind is ir.StateKind.HISTORY:
                label = "H*" if s.history_type == "deep" else "H"
                out.append(f'{pad}state "{label}" as {_sid(s.id)}')
                history.append(s.id)
            else:
                out.append(f'{pad}state "{title}" as {_sid(s.id)}')
                if s.kind is ir.StateKind.FINAL:
                    finals.append(s.id)
            desc = _descriptions(chart, s)
            if desc and s.kind in (ir.StateKind.COMPOUND, ir.StateKind.PARALLEL):
                out.append(f"{pad}note right of {_sid(s.id)}")
                out.extend(f"{pad}{INDENT}{text(d)}" for d in desc)
                out.append(f"{pad}end note")
            else:
                out.extend(f"{pad}{_sid(s.id)} : {text(d)}" for d in desc)

    out.append(f"{INDENT}[*] --> {_sid(chart.root_initial)}")
    emit(children(chart, None), 1)
    for t in chart.transitions:
        if t.target is None:
            continue
        label = _transition_label(t)
        arrow = f"{INDENT}{_sid(t.source)} --> {_sid(t.target)}"
        out.append(f"{arrow} : {label}" if label else arrow)
    if finals:
        out.append(f"{INDENT}classDef finalState fill:#222,color:#fff,stroke-width:3px")
        out.append(f"{INDENT}class {','.join(finals)} finalState")
    if history:
        out.append(f"{INDENT}classDef historyState fill:#fff,stroke:#333")
        out.append(f"{INDENT}class {','.join(history)} historyState")
    return "\n".join(out) + "\n"


_FLOW_SHAPES = {
    "terminal": ('(["', '"])'), "process": ('["', '"]'), "decision": ('{"', '"}'),
    "error": ('["', '"]'), "done": ('(["', '"])'), "wait": ('(["', '"])'), "note": ('["', '"]'),
}
_FLOW_CLASSES = {
    "decision": "fill:#fff8e1,stroke:#9a7b00",
    "error": "fill:#fde8e8,stroke:#a31515,stroke-width:2px",
    "done": "fill:#e6f4ea,stroke:#1e7b34,stroke-width:2px",
}


def flowchart_mermaid(fc: Flowchart) -> str:
    """Mermaid ``flowchart TD`` text of a flowchart: top to bottom in check order."""
    out = [*_front_matter(fc.title), "flowchart TD"]
    for n in fc.nodes:
        lines = [text(x) for x in n.title] + [f"<code>{text(x)}</code>" for x in n.detail]
        left, right = _FLOW_SHAPES[n.kind]
        out.append(f"{INDENT}{n.id}{left}{'<br/>'.join(lines)}{right}")
    for e in fc.edges:
        arrow = "-.->" if e.back else "-->"
        if e.label:
            label = text(e.label)
            arrow = f"-. {label} .->" if e.back else f"-- {label} -->"
        out.append(f"{INDENT}{e.source} {arrow} {e.target}")
    for kind, style in _FLOW_CLASSES.items():
        ids = [n.id for n in fc.nodes if n.kind == kind]
        if ids:
            out.append(f"{INDENT}classDef {kind} {style}")
            out.append(f"{INDENT}class {','.join(ids)} {kind}")
    return "\n".join(out) + "\n"


def instruction_mermaid(spec: ir.Spec, ins: Routine) -> str:
    """The Mermaid flowchart of ``ins``."""
    return flowchart_mermaid(build_flowchart(spec, ins))
