"""IR chart -> Graphviz DOT text of its state diagram, byte-for-byte stable.

Pipeline position: IR -> **dot** -> ``generated/diagrams/*.dot`` and, through the
``dot`` program (:mod:`statecharts.render.graphviz_bin`), ``*.svg`` / ``*.png``.

The DOT is written here from the IR with the ``graphviz`` Python package, not taken
from python-statemachine (whose DOT embeds memory addresses and draws a stray anchor
node).  Node ids are the spec's state ids; pseudo-states get ids derived from their
parent's (``Operating__initial``, ``Operating__border__mafr``); statements come in spec order (which is also the
order the layout engine sees, so the diagram reads as the spec is written) and the
attributes of every statement are sorted.  The same spec therefore always gives the
same bytes.

Drawing conventions (UML state machine notation, as in the manuals):

* a state is a rounded box titled ``Name (value)``; its entry and exit actions and
  its internal (targetless) transitions are listed in a compartment below the title;
* a compound state is a cluster with its own initial pseudo-state (a black dot);
* a parallel state is a cluster whose regions are dashed sub-clusters side by side;
* a history pseudo-state is a circle ``H`` (shallow) or ``H*`` (deep);
* a final state is a bull's-eye with its name beside it;
* a transition is labelled ``event [guard] / actions``.  Requests from instructions
  are solid black, environment events blue, the clock grey and dotted; eventless
  (automatic) transitions -- the fault exits -- are dashed dark red.  A legend under
  the title says so.

How much text a diagram carries is its *label level* (:data:`LABEL_LEVELS`):
``events`` (the trigger alone: the event, or the guard of an eventless transition;
edges with the same ends and kind are merged into one listing their events), ``guards``
(``event [guard]``, the default: what makes a transition fire) and ``full`` (with the
actions, and the entry/exit actions in the state boxes).  Large charts are also drawn as
an overview and parts (:mod:`statecharts.render.views`); a collapsed box lists the
states it stands for, and a state outside the part drawn is a grey dashed stub.
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence

import graphviz

from statecharts import ir
from statecharts.render.labels import (
    children,
    internal_transitions,
    is_container,
    state_title,
    transition_kind,
    transition_lines,
    wrap,
)

FONT = "Helvetica"
MONO = "Courier"

#: Edge style per transition kind: (colour, style, legend text).
EDGE_STYLES: dict[str, tuple[str, str, str]] = {
    "request": ("#000000", "solid", "instruction request"),
    "environment": ("#1f4e9a", "solid", "environment event"),
    "clock": ("#6b6b6b", "dotted", "coarse-update clock"),
    "automatic": ("#a31515", "dashed", "automatic (eventless, guard only)"),
}

STATE_FILL = "#f4f6fa"
CLUSTER_FILL = "#fbfbfd"
BOX_FILL = "#e8edf5"
STUB_FILL = "#eeeeee"

#: How much text diagrams carry, least first; :data:`DEFAULT_LABELS` is what
#: ``motionchart diagram`` and ``generated/`` use.
LABEL_LEVELS = ("events", "guards", "full")
DEFAULT_LABELS = "guards"


# --------------------------------------------------------------------------- HTML-like labels


def esc(text: str) -> str:
    """Escape text for a Graphviz HTML-like label."""
    return html.escape(text, quote=False).replace('"', "&quot;")


def html_lines(lines: Sequence[str], *, size: int | None = None, face: str | None = None,
               bold: bool = False, color: str | None = None) -> str:
    """Lines joined with left-aligned breaks, in one font."""
    body = '<BR ALIGN="LEFT"/>'.join(esc(line) for line in lines)
    if len(lines) > 1:
        body += '<BR ALIGN="LEFT"/>'
    if bold:
        body = f"<B>{body}</B>"
    attrs = []
    if face:
        attrs.append(f'FACE="{face}"')
    if size:
        attrs.append(f'POINT-SIZE="{size}"')
    if color:
        attrs.append(f'COLOR="{color}"')
    if attrs:
        body = f"<FONT {' '.join(attrs)}>{body}</FONT>"
    return body


def html_table(rows: Sequence[str], *, separators: bool = True) -> str:
    """A borderless table of rows (each already HTML), separated by rules."""
    cells = [f'<TR><TD ALIGN="LEFT" BALIGN="LEFT">{r}</TD></TR>' for r in rows]
    joiner = "<HR/>" if separators else ""
    return '<<TABLE BORDER="0" CELLBORDER="0" CELLSPACING="0" CELLPADDING="3">' + joiner.join(cells) + "</TABLE>>"


def sorted_attrs(attrs: dict[str, str]) -> dict[str, str]:
    return dict(sorted(attrs.items()))


# --------------------------------------------------------------------------- chart diagrams


def check_labels(labels: str) -> str:
    if labels not in LABEL_LEVELS:
        raise ValueError(f"unknown label level {labels!r}; use one of {', '.join(LABEL_LEVELS)}")
    return labels


def _compartment(chart: ir.Chart, state: ir.State, labels: str = "full") -> list[str]:
    """UML compartment lines: ``entry / a``, ``exit / b``, ``event [g] / c``.

    Level ``full`` lists them all; ``guards`` the internal transitions without their
    actions; ``events`` the events of the internal transitions."""
    lines: list[str] = []
    if labels == "full":
        for a in state.entry:
            lines.extend(wrap(f"entry / {a.text}", 44))
        for a in state.exit:
            lines.extend(wrap(f"exit / {a.text}", 44))
    seen: set[str] = set()
    for t in internal_transitions(chart, state.id):
        head = t.event or ""
        if labels == "events":
            head = head or "(automatic)"
            if head not in seen:
                seen.add(head)
                lines.append(f"{head} / …")
            continue
        if t.guard is not None:
            head = f"{head} [{t.guard.text}]".strip()
        if labels == "guards":
            lines.extend(wrap(f"{head} / …", 44))
            continue
        acts = "; ".join(a.text for a in t.actions)
        lines.extend(wrap(f"{head} / {acts}", 44))
    return lines


def _state_label(chart: ir.Chart, state: ir.State, labels: str = "full") -> str:
    rows = [html_lines([state_title(state)], bold=True, size=12)]
    comp = _compartment(chart, state, labels)
    if comp:
        rows.append(html_lines(comp, size=9, face=MONO))
    return html_table(rows)


def _box_label(state: ir.State, names: tuple[str, ...]) -> str:
    """A collapsed composite: its title and the states it stands for."""
    rows = [html_lines([state_title(state)], bold=True, size=12)]
    if names:
        rows.append(html_lines(wrap(", ".join(names), 34), size=9))
    return html_table(rows)


class _ChartDiagram:
    """Builds one chart's graph.  Edges are computed first (they decide which invisible
    border points each cluster needs), then the states, clusters and edges are emitted."""

    def __init__(self, chart: ir.Chart, *, labels: str = DEFAULT_LABELS,
                 collapsed: dict[str, tuple[str, ...]] | None = None, stubs: frozenset[str] = frozenset(),
                 caption: str = "", merge: bool | None = None) -> None:
        self.chart = chart
        self.labels = check_labels(labels)
        self.collapsed = collapsed or {}
        self.stubs = stubs
        self.caption = caption
        self.overview = bool(merge)
        self.box_labels = "events" if self.overview else labels
        self.merge = labels != "full" if merge is None else merge
        self.by_id = {s.id: s for s in chart.states}
        self.cluster_points: dict[str, list[str]] = {}
        self.exit_points: dict[str, list[str]] = {}
        self.initial_edges: dict[str | None, tuple[str, str, dict[str, str]]] = {}
        self._depth: dict[str, int] = {}
        self.graph = graphviz.Digraph(
            name=chart.id,
            graph_attr=sorted_attrs({
                "compound": "true", "fontname": FONT, "fontsize": "11", "labeljust": "l",
                "labelloc": "t", "nodesep": "0.3", "ranksep": "0.9", "rankdir": "TB",
                "newrank": "true", "pad": "0.3", "bgcolor": "white",
            }),
            node_attr=sorted_attrs({"fontname": FONT, "fontsize": "11"}),
            edge_attr=sorted_attrs({"fontname": FONT, "fontsize": "9", "arrowsize": "0.8"}),
        )

    # -- ids ---------------------------------------------------------------------

    def endpoint(self, state_id: str, transition_id: str) -> str:
        """Where transition ``transition_id`` attaches to ``state_id``.

        A state is its own node.  A cluster gets one invisible point per transition
        that starts or ends on it, so that those edges cross its border at different
        places instead of sharing one point and running on top of each other.
        """
        s = self.by_id[state_id]
        if not is_container(s):
            return s.id
        node = f"{s.id}__border__{transition_id}"
        self.cluster_points.setdefault(s.id, []).append(node)
        return node

    def depths(self) -> dict[str, int]:
        """How many transitions it takes, at least, to reach each state.

        Entering a compound state enters its initial child and a parallel state its
        regions at no cost.  An edge that does not lead further away (``depth[target]
        < depth[source]``) is a return edge: it is laid out reversed (see
        :meth:`transition`), so that the diagram flows from the initial state down to
        the fault states and the ways back do not stretch it.
        """
        chart = self.chart
        free: dict[str, list[str]] = {s.id: [] for s in chart.states}
        paid: dict[str, list[str]] = {s.id: [] for s in chart.states}
        for s in chart.states:
            if s.kind is ir.StateKind.COMPOUND and s.initial:
                free[s.id].append(s.initial)
            elif s.kind is ir.StateKind.PARALLEL:
                free[s.id].extend(s.children)
            if s.parent is not None:
                # a transition leaving an ancestor also leaves this state
                paid[s.id].extend(t.target for t in chart.transitions
                                  if t.target is not None and t.source in chart.ancestors(s.id)[1:])
        for t in chart.transitions:
            if t.target is not None:
                paid[t.source].append(t.target)
        depth: dict[str, int] = {}
        frontier = [chart.root_initial]
        level = 0
        while frontier:
            stack, nxt = list(frontier), []
            while stack:  # close over free moves at this level
                sid = stack.pop()
                if sid in depth:
                    continue
                depth[sid] = level
                stack.extend(x for x in free[sid] if x not in depth)
                nxt.extend(paid[sid])
            frontier = [x for x in nxt if x not in depth]
            level += 1
        return depth

    def descends(self, state_id: str, ancestor: str) -> bool:
        return ancestor in self.chart.ancestors(state_id)

    # -- drawing -------------------------------------------------------------------

    def build(self) -> str:
        chart = self.chart
        g = self.graph
        self._depth = self.depths()
        legend = [html_lines([f"{chart.name} ({chart.id})"], bold=True, size=14)]
        if self.caption:
            legend.append(html_lines([self.caption], size=10))
        used = sorted({transition_kind(chart, t) for t in chart.transitions if t.target is not None},
                      key=list(EDGE_STYLES).index)
        keys = []
        for kind in used:
            colour, style, text = EDGE_STYLES[kind]
            mark = {"solid": "———", "dashed": "– – –", "dotted": "·······"}[style]
            keys.append(f'<FONT COLOR="{colour}">{esc(mark)}</FONT> {esc(text)}')
        if keys:
            legend.append('<FONT POINT-SIZE="9">' + "    ".join(keys) + "</FONT>")
        g.attr(label=html_table(legend, separators=False))
        # Edges first: they decide which border points each cluster needs.
        root = self.by_id[chart.root_initial]
        # Into a compound state the arrow points at its own initial dot, cut at the border:
        # the two dots line up and the arrow meets the top of the cluster.
        head = f"{root.id}__initial" if root.kind is ir.StateKind.COMPOUND else self.endpoint(root.id, "_initial")
        self.initial_edges[None] = ("__initial__", head, self._clip(None, chart.root_initial))
        for s in chart.states:
            if s.kind is ir.StateKind.COMPOUND and s.initial is not None:
                self.initial_edges[s.id] = (f"{s.id}__initial", self.endpoint(s.initial, f"_initial_{s.id}"),
                                            self._clip(s.id, s.initial))
        edges = [self.transition(t) for t in self.drawn_transitions()]
        entry = chart.root_initial not in self.stubs and not self.stubs
        if entry:
            g.node("__initial__", label="", shape="point", width="0.16", color="black")
        self.states(g, children(chart, None))
        if entry:
            tail, head, attrs = self.initial_edges[None]
            g.edge(tail, head, **attrs)
        for tail, head, attrs in edges:
            g.edge(tail, head, **attrs)
        if self.stubs:
            with g.subgraph(name="stubs") as row:
                row.attr(rank="sink")
                for sid in self.chart.states:
                    if sid.id in self.stubs:
                        row.node(sid.id)
        return str(g.source)

    def states(self, g: graphviz.Digraph, states: Iterable[ir.State]) -> None:
        for s in states:
            if s.kind is ir.StateKind.COMPOUND:
                self.compound(g, s)
            elif s.kind is ir.StateKind.PARALLEL:
                self.parallel(g, s)
            elif s.kind is ir.StateKind.HISTORY:
                g.node(s.id, **sorted_attrs({
                    "label": "H*" if s.history_type == "deep" else "H", "shape": "circle",
                    "width": "0.35", "fixedsize": "true", "fontsize": "10", "tooltip": s.name,
                }))
            elif s.kind is ir.StateKind.FINAL:
                g.node(s.id, **sorted_attrs({
                    "label": "", "shape": "doublecircle", "style": "filled", "fillcolor": "black",
                    "width": "0.18", "fixedsize": "true", "xlabel": state_title(s), "tooltip": s.name,
                }))
            elif s.id in self.stubs:
                g.node(s.id, **sorted_attrs({
                    "label": _box_label(s, self.collapsed.get(s.id, ())), "shape": "box",
                    "style": "rounded,filled,dashed", "fillcolor": STUB_FILL, "color": "#8a94a6",
                    "fontcolor": "#555555", "margin": "0.12,0.06", "tooltip": s.description or s.name,
                }))
            elif s.id in self.collapsed:
                g.node(s.id, **sorted_attrs({
                    "label": _box_label(s, self.collapsed[s.id]), "shape": "box",
                    "style": "rounded,filled,bold", "fillcolor": BOX_FILL, "color": "#3c4a5c",
                    "margin": "0.12,0.06", "tooltip": s.description or s.name,
                }))
            else:
                g.node(s.id, **sorted_attrs({
                    "label": _state_label(self.chart, s, self.box_labels), "shape": "box", "style": "rounded,filled",
                    "fillcolor": STATE_FILL, "color": "#3c4a5c", "margin": "0.12,0.06",
                    "tooltip": s.description or s.name,
                }))

    def _cluster_attrs(self, s: ir.State, *, region: bool = False) -> dict[str, str]:
        attrs = {
            "label": _state_label(self.chart, s, self.box_labels),
            "style": "rounded,dashed" if region else "rounded,filled",
            "fillcolor": CLUSTER_FILL, "color": "#8a94a6" if region else "#3c4a5c",
            "fontname": FONT, "margin": "14", "tooltip": s.description or s.name, "labeljust": "l",
        }
        return sorted_attrs(attrs)

    def compound(self, g: graphviz.Digraph, s: ir.State, *, region: bool = False) -> None:
        with g.subgraph(name=f"cluster_{s.id}") as c:
            c.attr(**self._cluster_attrs(s, region=region))
            self.border_points(c, s)
            c.node(f"{s.id}__initial", label="", shape="point", width="0.14", color="black")
            self.states(c, children(self.chart, s.id))
            tail, head, attrs = self.initial_edges[s.id]
            c.edge(tail, head, **attrs)
            self.sink_exits(c, s)

    def parallel(self, g: graphviz.Digraph, s: ir.State) -> None:
        with g.subgraph(name=f"cluster_{s.id}") as c:
            attrs = self._cluster_attrs(s)
            attrs["style"] = "rounded,filled,bold"
            c.attr(**attrs)
            self.border_points(c, s)
            for region in children(self.chart, s.id):
                if region.kind is ir.StateKind.COMPOUND:
                    self.compound(c, region, region=True)
                else:  # the loader refuses this; draw it rather than fail
                    self.states(c, [region])
            self.sink_exits(c, s)

    def border_points(self, g: graphviz.Digraph, s: ir.State) -> None:
        for node in self.cluster_points.get(s.id, []):
            g.node(node, label="", shape="point", style="invis", width="0.01")

    def sink_exits(self, g: graphviz.Digraph, s: ir.State) -> None:
        """Rank the exit points of cluster ``s`` below everything inside it.

        Edges that leave a compound state for a state further from the initial one then
        cross its bottom border side by side, the states they lead to sit under it, and
        the ways back climb up its side: the layout has no crossings to sort out.
        """
        exits = self.exit_points.get(s.id, [])
        if not exits:
            return
        inner = [d.id for d in self.chart.states
                 if d.id != s.id and s.id in self.chart.ancestors(d.id) and not is_container(d)]
        for point in exits:
            for node in inner:
                g.edge(node, point, style="invis")

    def _clip(self, source: str | None, target: str) -> dict[str, str]:
        """lhead/ltail so that an edge to or from a cluster stops at its border."""
        attrs: dict[str, str] = {}
        t = self.by_id[target]
        if is_container(t) and (source is None or not self.descends(source, target)):
            attrs["lhead"] = f"cluster_{target}"
        if source is not None:
            s = self.by_id[source]
            if is_container(s) and not self.descends(target, source):
                attrs["ltail"] = f"cluster_{source}"
        return sorted_attrs(attrs)

    def drawn_transitions(self) -> list[ir.Transition | list[ir.Transition]]:
        """The transitions to draw: one by one, or (when merging) grouped by ends and kind."""
        ts = [t for t in self.chart.transitions if t.target is not None]
        if not self.merge and not self.stubs:
            return list(ts)
        groups: dict[tuple[str, str | None, str], list[ir.Transition]] = {}
        out: list[ir.Transition | list[ir.Transition]] = []
        for t in ts:
            if not self.merge and t.source not in self.stubs and t.target not in self.stubs:
                out.append(t)  # inside the part drawn: at the label level asked for
                continue
            key = (t.source, t.target, transition_kind(self.chart, t))
            if key not in groups:
                groups[key] = []
                out.append(groups[key])
            groups[key].append(t)
        return out

    def _label_parts(self, ts: list[ir.Transition], colour: str) -> list[str]:
        t = ts[0]
        crossing = t.source in self.stubs or t.target in self.stubs
        if self.labels == "guards" and not crossing and not self.overview:
            parts = []
            for x in ts:
                if x.event:
                    parts.append(html_lines([x.event], bold=True, color=colour))
                if x.guard is not None:
                    parts.append(html_lines(wrap(f"[{x.guard.text}]"), face=MONO, size=8, color=colour))
            return parts
        if len(ts) > 1 or self.labels == "events" or crossing:
            events: list[str] = []
            for x in ts:
                name = x.event or ""
                if name and name not in events:
                    events.append(name)
            parts = [html_lines(wrap(", ".join(events), 30), bold=True, color=colour)] if events else []
            if any(x.event is None for x in ts):
                guards = [x.guard.text for x in ts if x.event is None and x.guard is not None]
                if len(ts) == 1 and guards:
                    parts.append(html_lines(wrap(f"[{guards[0]}]", 30), face=MONO, size=8, color=colour))
                else:
                    n = sum(1 for x in ts if x.event is None)
                    parts.append(html_lines([f"{n} automatic" if n > 1 else "automatic"], size=8, color=colour))
            return parts
        lines = transition_lines(t) if self.labels == "full" else [
            *([t.event] if t.event else []), *(wrap(f"[{t.guard.text}]") if t.guard is not None else [])]
        parts = []
        if t.event:
            parts.append(html_lines([t.event], bold=True, color=colour))
        rest = lines[1:] if t.event else lines
        if rest:
            parts.append(html_lines(rest, face=MONO, size=8, color=colour))
        return parts

    def transition(self, group: ir.Transition | list[ir.Transition]) -> tuple[str, str, dict[str, str]]:
        ts = group if isinstance(group, list) else [group]
        t = ts[0]
        assert t.target is not None
        kind = transition_kind(self.chart, t)
        colour, style, _ = EDGE_STYLES[kind]
        parts = self._label_parts(ts, colour)
        label = "<" + "<BR/>".join(parts) + ">" if parts else ""
        attrs = {"color": colour, "style": style, "fontcolor": colour,
                 "tooltip": t.id if len(ts) == 1 else ", ".join(x.id for x in ts)}
        if label:
            attrs["label"] = label
        tail, head = self.endpoint(t.source, t.id), self.endpoint(t.target, t.id)
        clip = self._clip(t.source, t.target)
        depth = self._depth
        if self.stubs and (t.source in self.stubs or t.target in self.stubs):
            # In a part, the states outside it sit in a row under it: an edge from one of
            # them is laid out reversed, like a return edge.
            reverse = t.source in self.stubs
        else:
            reverse = (t.source in depth and t.target in depth and depth[t.target] < depth[t.source]
                       and not self.descends(t.target, t.source))
        if reverse:
            # A return edge: declared the other way round and drawn with its arrow at
            # the tail, so the layout ranks it like the forward edges and keeps its
            # label beside it instead of looping it around the diagram.
            tail, head = head, tail
            clip = {{"lhead": "ltail", "ltail": "lhead"}[k]: v for k, v in clip.items()}
            attrs.update(dir="back", arrowtail="normal")
        elif is_container(self.by_id[t.source]) and "ltail" in clip:
            self.exit_points.setdefault(t.source, []).append(tail)
        attrs.update(clip)
        return tail, head, sorted_attrs(attrs)


def chart_dot(chart: ir.Chart, *, labels: str = DEFAULT_LABELS, part: str = "whole") -> str:
    """The DOT text of ``chart``'s state diagram (same chart, same bytes).

    ``labels``: one of :data:`LABEL_LEVELS`.  ``part``: ``whole`` (every state),
    ``overview`` or the id of a composite state (:func:`statecharts.render.views.view`;
    KeyError for a name that is none of these)."""
    from statecharts.render.views import OVERVIEW, view

    v = view(chart, part)
    merge = True if v.name == OVERVIEW else None
    if v.name == OVERVIEW:
        labels = "events"  # the overview shows the structure: its edges list their events
    return _ChartDiagram(v.chart, labels=check_labels(labels) if merge is None else labels, collapsed=v.collapsed, stubs=v.stubs, caption=v.title,
                         merge=merge).build()
