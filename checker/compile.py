"""Compile an IR chart into a fast run-to-completion interpreter: the checker's axis back-end.

Pipeline position: IR -> **checker.compile** -> :mod:`statecharts.scan` (as an axis
back-end) -> :mod:`checker.system` -> :mod:`checker.search`.

python-statemachine is the reference semantics of the charts, but its ``send()`` costs
about 100 us; a model checker calls it millions of times.  :class:`FastAxis` offers the
same axis interface as :class:`statecharts.engine.AxisInstance` (so that the one
:class:`statecharts.scan.System` runs either back-end) and interprets the IR directly,
following the SCXML processing model that python-statemachine implements:

* a macrostep per event: for each active atomic state in document order, the first
  enabled transition of that state or, failing that, of its nearest ancestor that has
  one (child transitions before their ancestors'); within one state, ascending
  ``priority`` and then spec order;
* conflicting transitions (parallel regions whose exit sets overlap) are removed as in
  SCXML ``removeConflictingTransitions``;
* a microstep exits the exit set (descendants of the transition domain, innermost
  first, recording history), runs the transition actions, then enters the entry set
  (outermost first, completing compound states with their initial child, parallel
  states with every region, history states with their memory or, without one, the
  parent's initial child);
* targetless transitions run their actions only;
* after every event (also one that enables no transition) eventless transitions run
  until none is enabled, bounded by :data:`MAX_EVENTLESS_STEPS`.

Configurations are interned frozensets of state ids; the exit/entry work of a
transition in a configuration is computed once and cached.  Every walk over the state
tree is iterative.

Example::

    >>> from statecharts.loader import load_spec
    >>> axis = FastAxis(load_spec().chart("AxisNonCIP"), "Axis1")
    >>> axis.send("servo_on"); sorted(axis.active), axis.value
    (['Operating', 'ServoControl'], 2)
    >>> snap = axis.snapshot(); axis.send("shutdown"); axis.leaf.id
    'Shutdown'
    >>> axis.restore(snap); axis.leaf.id
    'ServoControl'
"""

from __future__ import annotations

import functools
import operator
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import cast

from statecharts import ir
from statecharts.engine import chart_event_actions, initial_env
from statecharts.expr import Assignment

#: Most eventless microsteps after one event before the chart is declared divergent.
MAX_EVENTLESS_STEPS = 100

Action = tuple[str, Callable[[Mapping[str, object]], object]]


class DivergenceError(RuntimeError):
    """Eventless transitions kept firing: the chart has an eventless loop."""


@dataclass(frozen=True, slots=True)
class CompiledTransition:
    index: int  # position in chart.transitions
    id: str
    source: str
    target: str | None
    event: str | None
    guard: Callable[[Mapping[str, object]], object] | None
    actions: tuple[Action, ...]


def _tuple_getter(names: tuple[str, ...]) -> Callable[[Mapping[str, object]], tuple[object, ...]]:
    """A function giving the values of ``names`` in a mapping, as a tuple, in one C call."""
    if len(names) > 1:
        return cast("Callable[[Mapping[str, object]], tuple[object, ...]]", operator.itemgetter(*names))
    if names:
        get = operator.itemgetter(names[0])
        return lambda env: (get(env),)
    return lambda env: ()


def _actions(assignments: Iterable[Assignment]) -> tuple[Action, ...]:
    return tuple((a.target, a.value.fn) for a in assignments)


class CompiledChart:
    """Tables derived once from an IR chart: document order, ancestors, ordered transitions."""

    def __init__(self, chart: ir.Chart) -> None:
        self.chart = chart
        by_parent: dict[str | None, list[ir.State]] = {}
        for s in chart.states:
            by_parent.setdefault(s.parent, []).append(s)
        order: list[ir.State] = []
        stack = list(reversed(by_parent.get(None, [])))
        while stack:  # pre-order = document order
            s = stack.pop()
            order.append(s)
            stack.extend(reversed(by_parent.get(s.id, [])))
        self.doc = {s.id: i for i, s in enumerate(order)}
        self.state = {s.id: s for s in chart.states}
        self.children = {s.id: tuple(c.id for c in by_parent.get(s.id, [])) for s in chart.states}
        self.proper_ancestors = {s.id: chart.ancestors(s.id)[1:] for s in chart.states}
        self.entry = {s.id: _actions(s.entry) for s in chart.states}
        self.exit = {s.id: _actions(s.exit) for s in chart.states}
        self.history_of = {
            s.id: tuple(c for c in self.children[s.id] if self.state[c].kind is ir.StateKind.HISTORY)
            for s in chart.states
        }
        self.has_history = any(s.kind is ir.StateKind.HISTORY for s in chart.states)
        self.atomic = frozenset(s.id for s in chart.states if s.kind in (ir.StateKind.ATOMIC, ir.StateKind.FINAL))
        self.variables = tuple(v.name for v in chart.variables)
        #: the variables' values out of an environment, as a tuple (snapshot's hot path)
        self.values_of: Callable[[Mapping[str, object]], tuple[object, ...]] = _tuple_getter(self.variables)
        indexed = sorted(enumerate(chart.transitions), key=lambda it: (it[1].priority, it[0]))
        table: dict[tuple[str, str | None], list[CompiledTransition]] = {}
        by_index: dict[int, CompiledTransition] = {}
        for i, t in indexed:
            ct = CompiledTransition(
                i, t.id, t.source, t.target, t.event, t.guard.fn if t.guard is not None else None, _actions(t.actions)
            )
            by_index[i] = ct
            table.setdefault((t.source, t.event), []).append(ct)
        self.transitions: list[CompiledTransition] = [by_index[i] for i in range(len(chart.transitions))]
        self.by_source_event = {k: tuple(v) for k, v in table.items()}
        self.event_actions = {k: _actions(v) for k, v in chart_event_actions(chart).items()}
        self._configs: dict[frozenset[str], frozenset[str]] = {}
        self._candidates: dict[tuple[frozenset[str], str | None], tuple[tuple[CompiledTransition, ...], ...]] = {}
        self._steps: dict[tuple[object, ...], tuple[tuple[str, ...], tuple[str, ...], frozenset[str]]] = {}
        self._leaf: dict[frozenset[str], ir.State] = {}

    # -- configurations --------------------------------------------------------

    def intern(self, config: frozenset[str]) -> frozenset[str]:
        return self._configs.setdefault(config, config)

    def leaf(self, config: frozenset[str]) -> ir.State:
        """The leaf state reported for a configuration (as the engine reports it)."""
        leaf = self._leaf.get(config)
        if leaf is None:
            leaf = next(s for s in self.chart.leaf_states() if s.id in config)
            self._leaf[config] = leaf
        return leaf

    def is_descendant(self, state: str, ancestor: str | None) -> bool:
        return ancestor is None or ancestor in self.proper_ancestors[state]

    def candidates(self, config: frozenset[str], event: str | None) -> tuple[tuple[CompiledTransition, ...], ...]:
        """Per active atomic state (document order): its transitions on ``event`` then its
        ancestors', innermost first, each group in priority order."""
        key = (config, event)
        found = self._candidates.get(key)
        if found is None:
            groups = []
            for leaf in sorted((s for s in config if s in self.atomic), key=self.doc.__getitem__):
                group: list[CompiledTransition] = []
                for s in (leaf, *self.proper_ancestors[leaf]):
                    group.extend(self.by_source_event.get((s, event), ()))
                if group:
                    groups.append(tuple(group))
            found = tuple(groups)
            self._candidates[key] = found
        return found

    # -- SCXML microstep pieces --------------------------------------------------

    def domain(self, t: CompiledTransition) -> str | None:
        """Transition domain: the least common compound ancestor of source and target."""
        assert t.target is not None
        for anc in self.proper_ancestors[t.source]:
            if self.state[anc].kind is not ir.StateKind.COMPOUND:
                continue
            if self.is_descendant(t.target, anc):
                return anc
        return None

    def exit_set(self, t: CompiledTransition, config: frozenset[str]) -> tuple[str, ...]:
        if t.target is None:
            return ()
        dom = self.domain(t)
        return tuple(sorted((s for s in config if self.is_descendant(s, dom)), key=self.doc.__getitem__, reverse=True))

    def entry_set(self, t: CompiledTransition, history: Mapping[str, frozenset[str]]) -> tuple[str, ...]:
        assert t.target is not None
        dom = self.domain(t)
        enter: set[str] = set()
        pending = [t.target]
        while pending:  # resolve history pseudo-states into the states they stand for
            s = pending.pop()
            st = self.state[s]
            if st.kind is ir.StateKind.HISTORY:
                parent = st.parent
                assert parent is not None
                remembered = history.get(s)
                targets = tuple(remembered) if remembered else (self.state[parent].initial,)
                for r in targets:
                    assert r is not None
                    pending.append(r)
                    for anc in self.proper_ancestors[r]:
                        if anc == parent:
                            break
                        enter.add(anc)
                enter.add(parent)
                continue
            enter.add(s)
        for s in list(enter):
            for anc in self.proper_ancestors[s]:
                if anc == dom:
                    break
                enter.add(anc)
        changed = True
        while changed:  # complete compound states and parallel regions by default entry
            changed = False
            for s in list(enter):
                st = self.state[s]
                if st.kind is ir.StateKind.COMPOUND:
                    kids = [c for c in self.children[s] if self.state[c].kind is not ir.StateKind.HISTORY]
                    if not any(c in enter for c in kids):
                        assert st.initial is not None
                        enter.add(st.initial)
                        changed = True
                elif st.kind is ir.StateKind.PARALLEL:
                    for c in self.children[s]:
                        if self.state[c].kind is not ir.StateKind.HISTORY and c not in enter:
                            enter.add(c)
                            changed = True
        return tuple(sorted(enter, key=self.doc.__getitem__))

    def step(
        self, ts: tuple[CompiledTransition, ...], config: frozenset[str], history: Mapping[str, frozenset[str]]
    ) -> tuple[tuple[str, ...], tuple[str, ...], frozenset[str]]:
        """(states to exit, states to enter, resulting configuration) for one microstep."""
        key: tuple[object, ...] = (config, tuple(t.index for t in ts))
        if self.has_history:
            key = (*key, tuple(sorted(history.items())))
        found = self._steps.get(key)
        if found is None:
            exits: set[str] = set()
            enters: set[str] = set()
            for t in ts:
                if t.target is not None:
                    exits.update(self.exit_set(t, config))
                    enters.update(self.entry_set(t, history))
            exit_order = tuple(sorted(exits, key=self.doc.__getitem__, reverse=True))
            entry_order = tuple(sorted(enters, key=self.doc.__getitem__))
            found = (exit_order, entry_order, self.intern((config - exits) | enters))
            self._steps[key] = found
        return found

    def initial_entry(self) -> tuple[str, ...]:
        """States entered when the chart starts, outermost first."""
        enter = {self.chart.root_initial, *self.proper_ancestors[self.chart.root_initial]}
        changed = True
        while changed:
            changed = False
            for s in list(enter):
                st = self.state[s]
                if st.kind is ir.StateKind.COMPOUND and not any(c in enter for c in self.children[s]):
                    assert st.initial is not None
                    enter.add(st.initial)
                    changed = True
                elif st.kind is ir.StateKind.PARALLEL:
                    for c in self.children[s]:
                        if self.state[c].kind is not ir.StateKind.HISTORY and c not in enter:
                            enter.add(c)
                            changed = True
        return tuple(sorted(enter, key=self.doc.__getitem__))


@functools.cache
def compiled(chart: ir.Chart) -> CompiledChart:
    return CompiledChart(chart)


class FastAxis:
    """One axis run by the IR interpreter; the interface of :class:`~statecharts.engine.AxisInstance`
    plus :meth:`snapshot` / :meth:`restore` and an optional trace of fired transitions."""

    def __init__(
        self,
        chart: ir.Chart,
        name: str,
        *,
        state: str | None = None,
        variables: Mapping[str, object] | None = None,
        parameters: Mapping[str, int] | None = None,
    ) -> None:
        self.chart = chart
        self.name = name
        self.c = compiled(chart)
        self.env = initial_env(chart, parameters)
        self._axis_keys: tuple[str, ...] = ()
        self.history: dict[str, frozenset[str]] = {}
        #: when a list, the ids of the transitions taken are appended to it
        self.fired: list[str] | None = None
        if variables:
            self.env.update(variables)
        preset = dict(self.env)
        self.config: frozenset[str] = frozenset()
        self._enter(self.c.initial_entry())
        self._eventless()
        if state is not None and state not in self.config:
            self.env.clear()
            self.env.update(preset)
            chain = list(reversed(chart.ancestors(state)))
            target = chart.state(state)
            while target.kind in (ir.StateKind.COMPOUND, ir.StateKind.PARALLEL):
                if target.kind is ir.StateKind.PARALLEL:
                    raise ValueError(f"cannot start in parallel state {state!r}; name a leaf state")
                assert target.initial is not None
                target = chart.state(target.initial)
                chain.append(target.id)
            self.config = self.c.intern(frozenset(chain))
            env = self.env
            for sid in chain:
                for tgt, fn in self.c.entry[sid]:
                    env[tgt] = fn(env)
        if variables:
            self.env.update(variables)
        # as the engine does: eventless transitions enabled by the set-up run before the
        # first scan, whether the axis starts in its initial state or in a named one
        self._eventless()

    # -- the interface the scan uses --------------------------------------------

    @property
    def active(self) -> frozenset[str]:
        return self.config

    @property
    def leaf(self) -> ir.State:
        return self.c.leaf(self.config)

    @property
    def value(self) -> int | None:
        return self.c.leaf(self.config).value

    def send(self, event: str) -> None:
        chosen = self._select(event)
        if chosen:
            self._microstep(chosen)
        self._eventless()

    def apply_event_actions(self, event: str) -> None:
        env = self.env
        for tgt, fn in self.c.event_actions.get(event, ()):
            env[tgt] = fn(env)

    def observe(self) -> dict[str, object]:
        leaf = self.c.leaf(self.config)
        out: dict[str, object] = {"state": leaf.id, self.chart.state_attribute: leaf.value}
        env = self.env
        for v in self.c.variables:
            out[v] = env[v]
        return out

    def expression_env(self) -> dict[str, object]:
        own = self.env
        keys = self._axis_keys
        if len(keys) != len(own):  # the environment only gains names, in order
            keys = self._axis_keys = tuple(f"axis.{k}" for k in own)
        env: dict[str, object] = dict(zip(keys, own.values()))
        leaf = self.c.leaf(self.config)
        env["axis.active"] = self.config
        env["axis.state"] = leaf.id
        env["axis.chart"] = self.chart.id
        env[f"axis.{self.chart.state_attribute}"] = leaf.value
        return env

    def snapshot(self) -> tuple[object, ...]:
        """(configuration, variable values) -- plus the history memory when the chart has
        history states.  Same shape as :meth:`AxisInstance.snapshot` for charts without."""
        values = self.c.values_of(self.env)
        if self.c.has_history:
            return self.config, values, tuple(sorted(self.history.items()))
        return self.config, values

    def restore(self, snap: tuple[object, ...]) -> None:
        self.config = self.c.intern(cast("frozenset[str]", snap[0]))
        self.env.update(zip(self.c.variables, cast("tuple[object, ...]", snap[1])))
        if self.c.has_history:
            self.history = dict(cast("tuple[tuple[str, frozenset[str]], ...]", snap[2])) if len(snap) > 2 else {}

    # -- run-to-completion ----------------------------------------------------------

    def _select(self, event: str | None) -> tuple[CompiledTransition, ...]:
        env = self.env
        groups = self.c.candidates(self.config, event)
        if not groups:
            return ()
        chosen: list[CompiledTransition] = []
        for group in groups:
            for t in group:
                if t.guard is None or t.guard(env):
                    if t not in chosen:
                        chosen.append(t)
                    break
        if len(chosen) > 1:
            return self._without_conflicts(chosen)
        return tuple(chosen)

    def _without_conflicts(self, enabled: list[CompiledTransition]) -> tuple[CompiledTransition, ...]:
        filtered: list[CompiledTransition] = []
        for t1 in enabled:
            exit1 = set(self.c.exit_set(t1, self.config))
            preempted = False
            remove: list[CompiledTransition] = []
            for t2 in filtered:
                if exit1 & set(self.c.exit_set(t2, self.config)):
                    if self.c.is_descendant(t1.source, t2.source) and t1.source != t2.source:
                        remove.append(t2)
                    else:
                        preempted = True
                        break
            if not preempted:
                filtered = [t for t in filtered if t not in remove]
                filtered.append(t1)
        return tuple(filtered)

    def _microstep(self, ts: tuple[CompiledTransition, ...]) -> None:
        env = self.env
        c = self.c
        exits, enters, new_config = c.step(ts, self.config, self.history)
        if c.has_history:
            for s in exits:
                for h in c.history_of[s]:
                    if c.state[h].history_type == "deep":
                        self.history[h] = frozenset(x for x in self.config if x in c.atomic and c.is_descendant(x, s))
                    else:
                        self.history[h] = frozenset(x for x in self.config if x in c.children[s])
        for s in exits:
            for tgt, fn in c.exit[s]:
                env[tgt] = fn(env)
        for t in ts:
            for tgt, fn in t.actions:
                env[tgt] = fn(env)
        if self.fired is not None:
            self.fired.extend(t.id for t in ts)
        self.config = new_config
        for s in enters:
            for tgt, fn in c.entry[s]:
                env[tgt] = fn(env)

    def _enter(self, states: tuple[str, ...]) -> None:
        env = self.env
        for s in states:
            for tgt, fn in self.c.entry[s]:
                env[tgt] = fn(env)
        self.config = self.c.intern(frozenset(states))

    def _eventless(self) -> None:
        chosen: tuple[CompiledTransition, ...] = ()
        for _ in range(MAX_EVENTLESS_STEPS):
            chosen = self._select(None)
            if not chosen:
                return
            self._microstep(chosen)
        where = ", ".join(f"{t.id!r} ({self.chart.transitions[t.index].location})" for t in chosen)
        raise DivergenceError(
            f"axis {self.name}: eventless transitions still enabled after {MAX_EVENTLESS_STEPS} microsteps "
            f"in {sorted(self.config)} (an eventless loop in chart {self.chart.id}; last taken: {where})"
        )
