"""Eventless cycles: can the eventless transitions of a chart fire forever in one macrostep?

Pipeline position: a semantic check of :mod:`statecharts.loader`, run on each built
:class:`~statecharts.ir.Chart`.  After every event the engine takes eventless
transitions until none is enabled; a cycle of them whose guards stay true would never
give control back to the scan.  This module decides that question where it can be
decided by enumeration and leaves the rest to the engine's run-time bound
(:data:`statecharts.engine.MAX_MICROSTEPS`).

Method.  The eventless transitions form a graph over the leaf states (a transition of a
compound state applies to each leaf below it; a transition without a target stays in
its leaf).  For each strongly connected part of that graph (networkx), the variables
that matter are those read by the guards of its leaves' eventless transitions, closed
under the assignments (exit, transition and entry actions) that write them.  When each
of them has a finite domain and the product of the domains is at most
:data:`CYCLE_ENUMERATION_LIMIT`, every (leaf, valuation) pair is run as the engine runs
it (first enabled transition, child before ancestor, then priority and spec order),
until no transition is enabled, the run leaves the part, a value leaves its domain, or
a pair repeats: a repeat is a cycle that can run without end, reported with the
transitions it takes and the values it starts from.  Charts with parallel states, and
parts entered through history states, are left to the run-time bound.

Cost: O(leaves x valuations x transitions per leaf) guard evaluations per part.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import networkx as nx

from statecharts import ir
from statecharts.expr import Assignment

#: Most (leaf, valuation) pairs a run starts from, for one strongly connected part.
CYCLE_ENUMERATION_LIMIT = 1_000
#: Most microsteps run for one strongly connected part, over all its runs.
RUN_STEP_LIMIT = 20_000
#: Domains up to this size are enumerated in full; larger ones are sampled.
SMALL_DOMAIN = 8


@dataclass(frozen=True, slots=True)
class EventlessCycle:
    """A run of eventless transitions that returns to where it started."""

    transitions: tuple[ir.Transition, ...]
    start_state: str
    start_values: tuple[tuple[str, object], ...]

    def describe(self) -> str:
        names = " -> ".join(repr(t.id) for t in self.transitions)
        read = {n for t in self.transitions if t.guard is not None for n in t.guard.names}
        values = ", ".join(f"{k}={v!r}" for k, v in self.start_values if k in read)
        start = f"in {self.start_state!r}" + (f" with {values}" if values else "")
        return (f"eventless cycle: transitions {names} can fire forever within one macrostep, starting {start}; "
                "give the cycle a guard that one of its own actions makes false")


class _Chart:
    def __init__(self, chart: ir.Chart) -> None:
        self.chart = chart
        self.by_id = {s.id: s for s in chart.states}
        self.leaves = [s.id for s in chart.leaf_states()]
        eventless: dict[str, list[ir.Transition]] = {}
        for _i, t in sorted(enumerate(chart.transitions), key=lambda it: (it[1].priority, it[0])):
            if t.event is None:
                eventless.setdefault(t.source, []).append(t)
        # what the engine tries in a leaf: the leaf's own transitions first, then each ancestor's
        self.candidates = {
            leaf: [t for a in chart.ancestors(leaf) for t in eventless.get(a, ())] for leaf in self.leaves
        }

    def default_leaf(self, state: str) -> str | None:
        s = self.by_id[state]
        while s.kind is ir.StateKind.COMPOUND and s.initial:
            s = self.by_id[s.initial]
        if s.kind in (ir.StateKind.ATOMIC, ir.StateKind.FINAL):
            return s.id
        return None  # a history or parallel state: not decided here

    def step(self, leaf: str, t: ir.Transition) -> tuple[str | None, list[Assignment]]:
        """(leaf after ``t``, the assignments it runs in order); leaf None: not decided."""
        if t.target is None:
            return leaf, list(t.actions)
        target_leaf = self.default_leaf(t.target)
        if target_leaf is None:
            return None, []
        src_chain = self.chart.ancestors(leaf)
        tgt_chain = self.chart.ancestors(target_leaf)
        tgt_up = self.chart.ancestors(t.target)
        # the transition's domain: the innermost proper ancestor of source and target
        src_anc = self.chart.ancestors(t.source)[1:]
        domain = next((a for a in src_anc if a in tgt_up and a != t.target), None)
        exited = [s for s in src_chain if s != domain and _below(self.chart, s, domain)]
        entered = [s for s in reversed(tgt_chain) if s != domain and _below(self.chart, s, domain)]
        out: list[Assignment] = []
        for s in exited:
            out.extend(self.by_id[s].exit)
        out.extend(t.actions)
        for s in entered:
            out.extend(self.by_id[s].entry)
        return target_leaf, out


def _below(chart: ir.Chart, state: str, domain: str | None) -> bool:
    return domain is None or (domain in chart.ancestors(state) and state != domain)


def eventless_cycles(
    chart: ir.Chart, parameters: Mapping[str, Sequence[object]] | None = None
) -> list[EventlessCycle]:
    """The eventless cycles of ``chart`` that can run without end (one per part)."""
    params = tuple(sorted((k, tuple(v)) for k, v in (parameters or {}).items()))
    try:
        return list(_cycles_cached(chart, params))
    except TypeError:  # a chart holding an unhashable value (a list in a domain)
        return _eventless_cycles(chart, dict(params))


@functools.lru_cache(maxsize=64)
def _cycles_cached(chart: ir.Chart, params: tuple[tuple[str, tuple[object, ...]], ...]) -> tuple[EventlessCycle, ...]:
    return tuple(_eventless_cycles(chart, dict(params)))


def _eventless_cycles(chart: ir.Chart, parameters: Mapping[str, Sequence[object]]) -> list[EventlessCycle]:
    if any(s.kind is ir.StateKind.PARALLEL for s in chart.states):
        return []
    c = _Chart(chart)
    graph: nx.DiGraph[str] = nx.DiGraph()
    graph.add_nodes_from(c.leaves)
    steps: dict[tuple[str, str], tuple[str | None, list[Assignment]]] = {}
    for leaf in c.leaves:
        for t in c.candidates[leaf]:
            nxt, effects = c.step(leaf, t)
            steps[(leaf, t.id)] = (nxt, effects)
            if nxt is not None:
                graph.add_edge(leaf, nxt)
    domains: dict[str, tuple[object, ...] | None] = {v.name: v.domain for v in chart.variables}
    for k, vals in (parameters or {}).items():
        domains[k] = tuple(vals)
    found: list[EventlessCycle] = []
    for part in nx.strongly_connected_components(graph):
        if len(part) == 1:
            (only,) = part
            if not graph.has_edge(only, only):
                continue
        cycle = _search(c, sorted(part), steps, domains)
        if cycle is not None:
            found.append(cycle)
    return found


def _search(
    c: _Chart, part: list[str], steps: Mapping[tuple[str, str], tuple[str | None, list[Assignment]]],
    domains: Mapping[str, tuple[object, ...] | None],
) -> EventlessCycle | None:
    inside = set(part)
    names: set[str] = set()
    for leaf in part:
        for t in c.candidates[leaf]:
            if t.guard is not None:
                names |= t.guard.names
    effects = [a for leaf in part for t in c.candidates[leaf] for a in steps[(leaf, t.id)][1]]
    if any(steps[(leaf, t.id)][0] is None for leaf in part for t in c.candidates[leaf]):
        return None
    changed = True
    while changed:
        changed = False
        for a in effects:
            if a.target in names and not a.value.names <= names:
                names |= a.value.names
                changed = True
    order = sorted(names)
    starts = [_start_values(c.chart, n, domains.get(n)) for n in order]
    if any(not v for v in starts):
        return None
    done: set[tuple[str, tuple[object, ...]]] = set()
    budget = [RUN_STEP_LIMIT]
    per_leaf = max(1, CYCLE_ENUMERATION_LIMIT // len(part))
    for leaf in part:
        for values in itertools.islice(itertools.product(*starts), per_leaf):
            found = _run(c, leaf, values, order, inside, steps, domains, done, budget)
            if found is not None:
                return found
            if budget[0] <= 0:
                return None
    return None


def _start_values(chart: ir.Chart, name: str, domain: tuple[object, ...] | None) -> tuple[object, ...]:
    """The values a run may start from: the whole domain when it is small, else a sample
    (its ends, its middle, the initial value; 0, 1, -1 and the initial value of an
    unbounded number).  A cycle found from a sample is a real one; none found from a
    sample proves nothing, and the engine's bound stays the guard."""
    initial: object = None
    with contextlib.suppress(KeyError):
        initial = chart.variable(name).initial
    if domain is not None:
        if len(domain) <= SMALL_DOMAIN:
            return domain
        picks = [domain[0], domain[-1], domain[len(domain) // 2]]
        if initial in domain:
            picks.append(initial)
        return tuple(dict.fromkeys(picks))
    if isinstance(initial, bool) or not isinstance(initial, (int, float)):
        return ()
    zero: object = 0.0 if isinstance(initial, float) else 0
    return tuple(dict.fromkeys([initial, zero, type(initial)(1), type(initial)(-1)]))


def _run(
    c: _Chart, leaf: str, values: tuple[object, ...], order: list[str], inside: set[str],
    steps: Mapping[tuple[str, str], tuple[str | None, list[Assignment]]],
    domains: Mapping[str, tuple[object, ...] | None], done: set[tuple[str, tuple[object, ...]]],
    budget: list[int],
) -> EventlessCycle | None:
    path: dict[tuple[str, tuple[object, ...]], int] = {}
    taken: list[ir.Transition] = []
    key = (leaf, values)
    wanted = set(order)
    while key not in done:
        if key in path:
            loop = taken[path[key]:]
            first = list(path)[path[key]]
            return EventlessCycle(tuple(loop), first[0], tuple(zip(order, first[1])))
        path[key] = len(taken)
        budget[0] -= 1
        if budget[0] <= 0:
            return None
        here, vals = key
        env = dict(zip(order, vals))
        nxt = _first_enabled(c.candidates[here], env)
        if nxt is None:
            break
        new_leaf, effects = steps[(here, nxt.id)]
        if new_leaf is None or new_leaf not in inside:
            break
        try:
            for a in effects:
                if a.target in wanted:
                    env[a.target] = a.value(env)
        except Exception:
            break
        new_vals = tuple(env[n] for n in order)
        if any(domains.get(n) is not None and v not in (domains.get(n) or ()) for n, v in zip(order, new_vals)):
            break  # a value outside its domain: reported by the domain checks, not a cycle
        taken.append(nxt)
        key = (new_leaf, new_vals)
    done.update(path)
    return None


def _first_enabled(candidates: Sequence[ir.Transition], env: Mapping[str, object]) -> ir.Transition | None:
    for t in candidates:
        try:
            if t.guard is None or t.guard(env):
                return t
        except Exception:
            return None
    return None
