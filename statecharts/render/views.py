"""Views of a large chart that fit on a page: an overview and one part per composite state.

Pipeline position: IR chart -> **views** -> derived IR charts -> :mod:`statecharts.render.dot`.

A chart with more than :data:`SPLIT_LEAVES` leaf states is drawn three ways:

* **whole**: every state and transition (the diagram ``diagram CHART`` draws by default);
* **overview**: each *leaf composite* (a compound state whose children are all simple
  states) collapsed to one box that names the states inside it; transitions between
  states of one collapsed box disappear, the others run between the boxes (edges with the
  same ends and kind are merged into one whose label lists the events);
* **one part per leaf composite**: that composite drawn in full, and each state outside
  it that a transition links to it drawn as a grey stub (a collapsed box where the
  overview has one).

Each view is an ordinary :class:`statecharts.ir.Chart` derived from the chart (states
and transitions filtered and re-targeted), so the one diagram builder draws them all.
Nothing here names a chart of the bundled spec: the split follows the chart's structure.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from statecharts import ir

#: A chart with more leaf states than this is also drawn as an overview and parts.
SPLIT_LEAVES = 12
#: Name of the overview view (``diagram CHART --part overview``).
OVERVIEW = "overview"
#: Name of the whole chart (``diagram CHART --part whole``, the default).
WHOLE = "whole"


@dataclass(frozen=True, slots=True)
class View:
    """A derived chart to draw and what the diagram should say about it."""

    name: str  # "whole", "overview" or the id of the composite drawn in full
    chart: ir.Chart  # the derived chart
    collapsed: dict[str, tuple[str, ...]]  # box id -> names of the states it stands for
    stubs: frozenset[str]  # states outside the part, drawn as grey stubs
    title: str  # caption under the chart's name


def leaf_composites(chart: ir.Chart) -> tuple[ir.State, ...]:
    """Compound states whose children are all simple (atomic or final) states."""
    by_id = {s.id: s for s in chart.states}
    return tuple(
        s for s in chart.states
        if s.kind is ir.StateKind.COMPOUND and s.children
        and all(by_id[c].kind in (ir.StateKind.ATOMIC, ir.StateKind.FINAL, ir.StateKind.HISTORY)
                for c in s.children)
        and not any(by_id[a].kind is ir.StateKind.PARALLEL for a in chart.ancestors(s.id)[1:])
    )


def is_split(chart: ir.Chart) -> bool:
    """Whether ``chart`` is large enough to be drawn as an overview and parts."""
    return len(chart.leaf_states()) > SPLIT_LEAVES and bool(leaf_composites(chart))


def view_names(chart: ir.Chart) -> tuple[str, ...]:
    """``whole``, and for a split chart ``overview`` and the id of each part."""
    if not is_split(chart):
        return (WHOLE,)
    return (WHOLE, OVERVIEW, *(s.id for s in leaf_composites(chart)))


def stem(chart: ir.Chart, name: str) -> str:
    """File stem of a view in ``generated/diagrams/``: ``AxisCIP``, ``AxisCIP.overview``, ``AxisCIP.Standby``."""
    return chart.id if name == WHOLE else f"{chart.id}.{name}"


def _descendants(chart: ir.Chart, state_id: str) -> set[str]:
    return {s.id for s in chart.states if state_id in chart.ancestors(s.id)[1:]}


def _representative(chart: ir.Chart, boxes: set[str]) -> dict[str, str]:
    """Each state -> the collapsed box that contains it, or itself."""
    rep: dict[str, str] = {}
    for s in chart.states:
        anc = [a for a in chart.ancestors(s.id) if a in boxes]
        rep[s.id] = anc[-1] if anc else s.id
    return rep


def _as_box(state: ir.State, parent: str | None) -> ir.State:
    return dataclasses.replace(state, kind=ir.StateKind.ATOMIC, children=(), initial=None, entry=(), exit=(),
                               parent=parent)


def _names(chart: ir.Chart, state_id: str) -> tuple[str, ...]:
    by_id = {s.id: s for s in chart.states}
    return tuple(by_id[c].name for c in by_id[state_id].children if by_id[c].kind is not ir.StateKind.HISTORY)


def _retarget(chart: ir.Chart, rep: dict[str, str], keep: set[str]) -> tuple[ir.Transition, ...]:
    """Transitions with both ends mapped through ``rep``, those not touching ``keep`` dropped,
    those running inside one collapsed box dropped."""
    out: list[ir.Transition] = []
    for t in chart.transitions:
        src = rep[t.source]
        if t.target is None:
            if src == t.source and src in keep:
                out.append(t)
            continue
        tgt = rep[t.target]
        if src not in keep and tgt not in keep:
            continue
        if src == tgt and (src != t.source or tgt != t.target):
            continue  # a move between states of one collapsed box
        out.append(dataclasses.replace(t, source=src, target=tgt))
    return tuple(out)


def overview(chart: ir.Chart) -> View:
    """The chart with each leaf composite collapsed to one box."""
    boxes = {s.id for s in leaf_composites(chart)}
    rep = _representative(chart, boxes)
    states = []
    for s in chart.states:
        if rep[s.id] != s.id:
            continue
        states.append(_as_box(s, s.parent) if s.id in boxes else s)
    kept = {s.id for s in states}
    derived = dataclasses.replace(chart, states=tuple(states), transitions=_retarget(chart, rep, kept),
                                  root_initial=rep[chart.root_initial])
    collapsed = {b: _names(chart, b) for b in sorted(boxes, key=[s.id for s in chart.states].index)}
    return View(OVERVIEW, derived, collapsed, frozenset(),
                "overview: each composite of simple states drawn as one box (its own diagram shows it in full)")


def part(chart: ir.Chart, composite: str) -> View:
    """Composite ``composite`` in full, with stubs for the states outside it it is linked to."""
    boxes = {s.id for s in leaf_composites(chart)} - {composite}
    rep = _representative(chart, boxes)
    inside = _descendants(chart, composite) | {composite}
    by_id = {s.id: s for s in chart.states}
    linked: list[str] = []
    for t in chart.transitions:
        if t.target is None:
            continue
        a, b = t.source in inside, t.target in inside
        if a != b:
            other = rep[t.target] if a else rep[t.source]
            if other not in linked:
                linked.append(other)
    order = [s.id for s in chart.states]
    linked.sort(key=order.index)
    states: list[ir.State] = []
    for s in chart.states:
        if s.id in inside:
            states.append(dataclasses.replace(s, parent=None) if s.id == composite else s)
    for sid in linked:
        states.append(_as_box(by_id[sid], None))
    keep = inside | set(linked)
    transitions = tuple(t for t in _retarget(chart, rep, keep)
                        if t.source in inside or (t.target is not None and t.target in inside))
    derived = dataclasses.replace(chart, states=tuple(states), transitions=transitions, root_initial=composite)
    collapsed = {sid: _names(chart, sid) for sid in linked if sid in boxes}
    name = by_id[composite].name
    return View(composite, derived, collapsed, frozenset(linked),
                f"part: {name} and its transitions; grey boxes are states outside it")


def view(chart: ir.Chart, name: str = WHOLE) -> View:
    """The view called ``name`` (see :func:`view_names`); KeyError for another name."""
    if name == WHOLE:
        return View(WHOLE, chart, {}, frozenset(), "")
    if name == OVERVIEW and is_split(chart):
        return overview(chart)
    for s in leaf_composites(chart):
        if s.id == name or (s.id.casefold() == name.casefold()):
            return part(chart, s.id)
    raise KeyError(name)


__all__ = ["OVERVIEW", "SPLIT_LEAVES", "WHOLE", "View", "is_split", "leaf_composites", "overview", "part", "stem",
           "view", "view_names"]
