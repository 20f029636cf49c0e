"""Exploring a program model, and the property kinds of whole-controller properties.

Pipeline position: :mod:`checker.program_model` (the successor function) -> **checker.program_search**
-> :mod:`checker.program_check` (systems, reports, counterexamples).

:func:`explore` builds the reachable state graph breadth first (so the path the search
found to every state is a shortest one) from every start of the system, keeping for each
state its distinct successors and its *quiet* successor: the scan in which the
environment leaves every free input as it is and sends no event, the program's own
progress.  :func:`check` then decides each property on that graph:

* ``invariant``: the expression holds in every reachable state (a violation: a shortest path);
* ``reachable``: some reachable state satisfies it (a witness: a shortest path);
* ``always_reachable``: from every reachable state a state satisfying it stays reachable
  (the hang detector; a violation: a shortest path into a *trap*, the set of states from
  which the goal can never be reached again, and the starts from which a trap can be
  entered);
* ``leads_to``: whenever ``expr`` holds, ``goal`` holds within ``within`` scans on every path;
* ``eventually``: on every run that takes the quiet scan infinitely often (weak fairness
  of the program's own progress: the quiet scan is always possible, so a run that never
  takes it is unfair), a state satisfying the expression comes; a violation is a path to
  a cycle of states without it that contains a quiet scan;
* ``deadlock``: no reachable state (unless ``final`` holds in it) from which no choice of
  the environment changes the controller (program tags, motion tags, axes);
* ``livelock``: no reachable cycle in which the program's tags never change while a
  motion instruction waits (enabled, neither done nor erred) in every state of it.

Cycles are found as strongly connected components (networkx).
"""

from __future__ import annotations

import operator
import re
import time
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from checker.program_model import ProgramModel, ProgramModelError, Start, State
from statecharts.diagnostics import Diagnostic
from statecharts.expr import Expr, ExprError, parse_expression

KINDS = ("invariant", "reachable", "always_reachable", "leads_to", "eventually", "deadlock", "livelock")
_SUBSCRIPT = re.compile(r"\[\s*(\d+(?:\s*,\s*\d+)*)\s*\]")
_BACK = re.compile(r"__((?:\d+_)*\d+)__")


@dataclass(frozen=True)
class ProgramProperty:
    """A property over the whole controller, as data."""

    name: str
    kind: str
    expr: str = ""  # invariant / reachable / always_reachable / eventually: the condition; leads_to: the trigger
    goal: str = ""  # leads_to: what must follow
    within: int | None = None  # leads_to: in at most this many scans
    final: str = ""  # deadlock: states where standing still is the intended end
    file: str = ""
    line: int = 1
    source: str = ""  # the documents the property comes from
    interpretation: str = ""  # INT-nnn when the property rests on an interpretation
    description: str = ""

    def texts(self) -> list[str]:
        return [t for t in (self.expr, self.goal, self.final) if t]


def parse_property_text(text: str, *, name: str = "") -> ProgramProperty:
    """``KIND: TEXT`` from the command line: ``invariant: not (A and B)``,
    ``leads_to: STATE == 9 -> NEXTSTATE == 1 within 50``, ``deadlock``, ``deadlock: STATE == 1``."""
    kind, _, rest = text.partition(":")
    kind = kind.strip().replace("-", "_")
    rest = rest.strip()
    if kind not in KINDS:
        raise ValueError(f"unknown property kind {kind!r} in {text!r}; kinds: {', '.join(KINDS)}")
    label = name or text
    if kind == "leads_to":
        m = re.fullmatch(r"(.+?)\s*(?:->|leads_to)\s*(.+?)(?:\s+within\s+(\d+)(?:\s+scans?)?)?", rest)
        if m is None:
            raise ValueError(f"write a leads_to property as 'leads_to: P -> Q within N', not {text!r}")
        within = int(m.group(3)) if m.group(3) else None
        return ProgramProperty(label, kind, m.group(1), m.group(2), within)
    if kind == "deadlock":
        return ProgramProperty(label, kind, final=rest)
    if kind == "livelock":
        return ProgramProperty(label, kind)
    if not rest:
        raise ValueError(f"property {text!r}: give the expression after '{kind}:'")
    return ProgramProperty(label, kind, rest)


def to_expr_text(text: str) -> str:
    """Subscripts written as data names: ``X_STAT[1].DN`` -> ``X_STAT__1__.DN`` (the expression
    language has no subscripts; the names are mapped back by :func:`from_expr_name`)."""
    return _SUBSCRIPT.sub(lambda m: "__" + "_".join(x.strip() for x in m.group(1).split(",")) + "__", text)


def from_expr_name(name: str) -> str:
    return _BACK.sub(lambda m: "[" + ",".join(m.group(1).split("_")) + "]", name)


Predicate = Callable[[State], bool]


def compile_predicate(model: ProgramModel, text: str, prop: ProgramProperty) -> Predicate | Diagnostic:
    """A state predicate from an expression over tags, motion members and axes (statecharts.expr)."""
    try:
        e: Expr = parse_expression(to_expr_text(text))
    except ExprError as exc:
        return Diagnostic(prop.file, prop.line, 1, f"property {prop.name}", str(exc))
    getters: list[tuple[str, Callable[[State], Any]]] = []
    constants: dict[str, Any] = {}
    states = {st.id for chart in model.charts for st in chart.states}
    for n in sorted(e.names):
        path = from_expr_name(n)
        g = model.getter(path)
        if isinstance(g, str):
            if n in states:
                constants[n] = n
                continue
            return Diagnostic(prop.file, prop.line, 1, f"property {prop.name}", f"{path}: {g}")
        getters.append((n, g))
    fn = e.fn
    memo: dict[tuple[Any, ...], bool] = {}
    fetch = [g for _n, g in getters]
    keys = [n for n, _g in getters]

    def pred(s: State) -> bool:
        values = tuple([g(s) for g in fetch])
        hit = memo.get(values)
        if hit is None:
            env = dict(constants)
            env.update(zip(keys, values))
            hit = memo[values] = bool(fn(env))
        return hit
    return pred


def names_of(text: str) -> list[str]:
    try:
        return sorted(from_expr_name(n) for n in parse_expression(to_expr_text(text)).names)
    except ExprError:
        return []


# --------------------------------------------------------------------------- the graph


@dataclass
class Graph:
    states: list[State] = field(default_factory=list)
    index: dict[State, int] = field(default_factory=dict)
    parent: list[int] = field(default_factory=list)
    via: list[int] = field(default_factory=list)  # the choice taken from the parent
    depth: list[int] = field(default_factory=list)
    succ: list[tuple[int, ...]] = field(default_factory=list)  # distinct successors (empty: not expanded)
    quiet: list[int] = field(default_factory=list)  # the quiet successor, -1 when not expanded
    start_of: list[int] = field(default_factory=list)  # the start each state was first reached from
    starts: list[Start] = field(default_factory=list)
    start_states: list[int] = field(default_factory=list)
    complete: bool = True
    stopped: str = ""
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    transitions: int = 0
    computed: int = 0  # transitions computed by the successor function (once per controller state)
    controller_states: int = 0  # states without the free inputs' last values

    def path(self, target: int) -> list[int]:
        out = [target]
        while self.parent[out[-1]] >= 0:
            out.append(self.parent[out[-1]])
        return out[::-1]

    def predecessors(self) -> list[list[int]]:
        pred: list[list[int]] = [[] for _ in self.states]
        for u, ts in enumerate(self.succ):
            for v in ts:
                pred[v].append(u)
        return pred


def explore(model: ProgramModel, starts: Sequence[Start], *, max_states: int | None = None,
            max_scans: int | None = None, max_seconds: float | None = None,
            progress: Callable[[int, int], None] | None = None, prune: Sequence[Predicate] = ()) -> Graph:
    """Every state reachable from ``starts``, breadth first.  A state failing one of ``prune`` (a
    declared integer domain left) is kept but not expanded, and the graph is then incomplete."""
    g = Graph(starts=list(starts))
    t0 = time.perf_counter()
    c0 = time.process_time()
    states, index, parent, via, depth = g.states, g.index, g.parent, g.via, g.depth
    succ, quiet, start_of = g.succ, g.quiet, g.start_of
    for n, st in enumerate(starts):
        s = model.initial(st)
        if s in index:
            g.start_states.append(index[s])
            continue
        index[s] = len(states)
        g.start_states.append(len(states))
        states.append(s)
        parent.append(-1)
        via.append(-1)
        depth.append(0)
        start_of.append(n)
    successors = successor_function(model)
    cov = model.cov
    combo_index = {c: i for i, c in enumerate(model.combos)}
    input_pos = [model.slot_pos[x] for x in model.input_slots]
    inputs_of = operator.itemgetter(*input_pos) if input_pos else (lambda _s: ())
    # the free inputs are written before each scan: the successors of a state do not depend on
    # the values its inputs had in the previous scan, so they are computed once per controller state
    # (unless an input rule reads them or a prescan keeps them: then once per state)
    free = set(input_pos) if not (model.input_rules or model.prescan_choice) else set()
    kept = [j for j in range(model.width) if j not in free]
    controller_of = operator.itemgetter(*kept)
    single = len(input_pos) == 1
    memo: dict[Any, tuple[tuple[int, ...], dict[int, int]]] = {}
    computed = 0
    rungs = executed = 0
    transitions = 0
    frontier = 0
    while frontier < len(states):
        if max_states is not None and len(states) >= max_states:
            g.complete = False
            g.stopped = f"stopped after {max_states} states (--max-states)"
            break
        if max_seconds is not None and (frontier & 1023) == 0 and time.perf_counter() - t0 > max_seconds:
            g.complete = False
            g.stopped = f"stopped after {max_seconds:g} s (--max-seconds)"
            break
        u = frontier
        frontier += 1
        s = states[u]
        d = depth[u] + 1
        if max_scans is not None and d > max_scans:
            succ.append(())
            quiet.append(-1)
            g.complete = False
            g.stopped = f"bounded: runs explored up to {max_scans} scans (max_scans)"
            continue
        if prune and not all(p(s) for p in prune):
            succ.append(())
            quiet.append(-1)
            g.complete = False
            g.stopped = "a declared integer domain was left (its states are not explored further)"
            continue
        ins = inputs_of(s)
        qc = combo_index[(ins,) if single else ins]
        key = controller_of(s)
        hit = memo.get(key)
        if hit is None:
            outs, cv, ex = successors(s)
            rungs |= cv
            executed |= ex
            by_choice: dict[int, int] = {}
            src = start_of[u]
            for choice, t in outs:
                v = index.get(t)
                if v is None:
                    v = len(states)
                    index[t] = v
                    states.append(t)
                    parent.append(u)
                    via.append(choice)
                    depth.append(d)
                    start_of.append(src)
                by_choice[choice] = v
            hit = (tuple(set(by_choice.values())), by_choice)
            memo[key] = hit
            computed += len(outs)
        transitions += len(hit[1])
        succ.append(hit[0])
        quiet.append(hit[1][qc])
        if progress is not None and (u & 4095) == 0:
            progress(len(states), u)
    while len(succ) < len(states):
        succ.append(())
        quiet.append(-1)
    cov.rungs_true |= rungs
    cov.executed |= executed
    g.transitions = transitions
    g.computed = computed
    g.controller_states = len(memo)
    g.seconds = time.perf_counter() - t0
    g.cpu_seconds = time.process_time() - c0
    return g


def successor_function(model: ProgramModel) -> Callable[[State], tuple[list[tuple[int, State]], int, int]]:
    """The successors of a state as the search takes them: the compiled scan, completed by the
    model's sets, prescan and input rules when it has any."""
    return model.successors if not model.extended else _constrained(model)


def _constrained(model: ProgramModel) -> Callable[[State], tuple[list[tuple[int, State]], int, int]]:
    """The successor function with the model's sets and prescan (:meth:`ProgramModel.expand`) and its
    input rules: an input with ``while`` changes only in a state where that holds; each change of a
    counted input spends one environment change, and a choice that would spend more than
    ``max_events`` is not offered."""
    names = (*model.inputs, *model.int_inputs)
    ncombo = len(model.combos)
    rules: list[tuple[int, int, Predicate | None, bool]] = []  # (input number, state position, while, counted)
    for n, name in enumerate(names):
        rule = model.input_rules.get(name)
        if rule is None:
            continue
        guard = None
        if rule.while_:
            pr = compile_predicate(model, rule.while_, ProgramProperty(f"input {name}", "invariant", rule.while_))
            if isinstance(pr, Diagnostic):
                raise ProgramModelError([pr])
            guard = pr
        rules.append((n, model.slot_pos[model.input_slots[n]], guard, rule.counted))
    limit = model.max_events
    prescan = model.nchoices + len(model.sets) * ncombo

    def successors(s: State) -> tuple[list[tuple[int, State]], int, int]:
        outs, cv, ex = model.expand(s)
        if not rules:
            return outs, cv, ex
        frozen = [(n, s[pos]) for n, pos, guard, _c in rules if guard is not None and not guard(s)]
        counted = [(n, s[pos]) for n, pos, _g, c in rules if c]
        kept: list[tuple[int, State]] = []
        for ch, t in outs:
            if ch == prescan and model.prescan_choice:
                kept.append((ch, t))
                continue
            combo = model.combos[(ch - model.nchoices if ch >= model.nchoices else ch) % ncombo]
            if any(combo[n] != v for n, v in frozen):
                continue
            cost = sum(1 for n, v in counted if combo[n] != v)
            if cost:
                if t[0] + cost > limit:
                    continue
                t = (t[0] + cost, *t[1:])
            kept.append((ch, t))
        return kept, cv, ex
    return successors


# --------------------------------------------------------------------------- verdicts


@dataclass
class Verdict:
    prop: ProgramProperty
    holds: bool | None  # None: unknown (the search was bounded or stopped)
    message: str
    path: list[int] = field(default_factory=list)  # from a start to the state shown
    loop: list[int] = field(default_factory=list)  # for a hang or a cycle: states after the path
    trap: list[int] = field(default_factory=list)  # for always_reachable: the trap entered
    hanging_starts: list[int] = field(default_factory=list)  # starts from which the violation can be reached
    witness: bool = False  # the path shows the property holding (reachable)


def _forward(g: Graph, sources: Iterable[int], allowed: Callable[[int], bool] | None = None) -> set[int]:
    seen = set(sources)
    todo = deque(seen)
    while todo:
        u = todo.popleft()
        for v in g.succ[u]:
            if v not in seen and (allowed is None or allowed(v)):
                seen.add(v)
                todo.append(v)
    return seen


class Reverse:
    """The graph's edges backwards, by successor set: states that share their set of successors
    (every state of one controller state does) are one group, so a backward search visits each
    group once instead of each edge."""

    def __init__(self, g: Graph) -> None:
        groups: dict[int, int] = {}
        self.members: list[list[int]] = []
        self.of: list[list[int]] = [[] for _ in g.states]  # state -> groups whose successors include it
        for u, ts in enumerate(g.succ):
            if not ts:
                continue
            k = groups.get(id(ts))
            if k is None:
                k = groups[id(ts)] = len(self.members)
                self.members.append([])
                for v in ts:
                    self.of[v].append(k)
            self.members[k].append(u)


def _backward(g: Graph, rev: Reverse, targets: Iterable[int]) -> set[int]:
    """Every state from which one of ``targets`` is reachable (the targets included)."""
    seen = set(targets)
    todo = deque(seen)
    done: set[int] = set()
    members, of = rev.members, rev.of
    while todo:
        v = todo.popleft()
        for k in of[v]:
            if k in done:
                continue
            done.add(k)
            for u in members[k]:
                if u not in seen:
                    seen.add(u)
                    todo.append(u)
    return seen


def _starts_reaching(g: Graph, rev: Reverse, targets: Iterable[int]) -> list[int]:
    back = _backward(g, rev, targets)
    return [n for n, s in enumerate(g.start_states) if s in back]


def _cycle_in(g: Graph, members: set[int], first: int) -> list[int]:
    """The states of a shortest cycle from ``first`` back to it inside ``members`` (``first`` last)."""
    prev: dict[int, int] = {}
    todo: deque[int] = deque()
    for v in g.succ[first]:
        if v == first:
            return [first]
        if v in members and v not in prev:
            prev[v] = first
            todo.append(v)
    while todo:
        u = todo.popleft()
        for v in g.succ[u]:
            if v == first:
                out = [u]
                while prev[out[-1]] != first:
                    out.append(prev[out[-1]])
                return [*out[::-1], first]
            if v in members and v not in prev:
                prev[v] = u
                todo.append(v)
    return []


def _into_trap(g: Graph, first: int) -> tuple[list[int], list[int], list[int]]:
    """From ``first``: a shortest path into the nearest bottom strongly connected component (a set
    of states the controller cannot leave), a cycle through it, and the component."""
    import networkx as nx
    region = _forward(g, [first])
    dg: nx.DiGraph[int] = nx.DiGraph()
    dg.add_nodes_from(region)
    for u in region:
        for v in g.succ[u]:
            dg.add_edge(u, v)
    cond = nx.condensation(dg)
    bottom: set[int] = set()
    for c in cond.nodes:
        if cond.out_degree(c) == 0:
            bottom |= set(cond.nodes[c]["members"])
    prev = {first: -1}
    todo = deque([first])
    hit = first
    while todo:
        u = todo.popleft()
        if u in bottom:
            hit = u
            break
        for v in g.succ[u]:
            if v not in prev:
                prev[v] = u
                todo.append(v)
    tail = [hit]
    while prev[tail[-1]] >= 0:
        tail.append(prev[tail[-1]])
    path = g.path(first) + tail[::-1][1:]
    comp = next(set(cond.nodes[c]["members"]) for c in cond.nodes if hit in cond.nodes[c]["members"])
    return path, _cycle_in(g, comp, hit), sorted(comp)


def check(model: ProgramModel, g: Graph, props: Sequence[ProgramProperty],
          predicates: dict[str, Predicate]) -> list[Verdict]:
    out: list[Verdict] = []
    pred_cache: Reverse | None = None

    def preds() -> Reverse:
        nonlocal pred_cache
        if pred_cache is None:
            pred_cache = Reverse(g)
        return pred_cache

    def holds_in(text: str) -> list[bool]:
        p = predicates[text]
        return [p(s) for s in g.states]

    n = len(g.states)
    for prop in props:
        kind = prop.kind
        if kind == "invariant":
            values = holds_in(prop.expr)
            bad = next((u for u in range(n) if not values[u]), None)  # BFS order: a shortest path
            if bad is None:
                out.append(Verdict(prop, True if g.complete else None,
                                   "holds in every reachable state" if g.complete else
                                   f"holds in the {n} states explored ({g.stopped})"))
            else:
                out.append(Verdict(prop, False, f"violated after {g.depth[bad]} scan(s)", g.path(bad),
                                   hanging_starts=_starts_reaching(g, preds(), [u for u in range(n) if not values[u]])))
        elif kind == "reachable":
            values = holds_in(prop.expr)
            hit = next((u for u in range(n) if values[u]), None)
            if hit is not None:
                out.append(Verdict(prop, True, f"reached after {g.depth[hit]} scan(s)", g.path(hit), witness=True))
            else:
                out.append(Verdict(prop, False if g.complete else None, "never reached" if g.complete else
                                   f"not reached in the {n} states explored ({g.stopped})"))
        elif kind == "always_reachable":
            values = holds_in(prop.expr)
            can = _backward(g, preds(), [u for u in range(n) if values[u]])
            unknown = _backward(g, preds(), [u for u in range(n) if not g.succ[u]])
            stuck = [u for u in range(n) if u not in can and u not in unknown]
            if not stuck:
                out.append(Verdict(prop, True if g.complete else None,
                                   "the goal stays reachable from every reachable state" if g.complete else
                                   f"no trap among the {n} states explored ({g.stopped})"))
                continue
            first = min(stuck, key=lambda u: (g.depth[u], u))
            hang = _starts_reaching(g, preds(), stuck)
            path, loop, trap = _into_trap(g, first)
            out.append(Verdict(prop, False, (
                f"from scan {g.depth[first]} on, {prop.expr} can never hold again; after {len(path) - 1} scan(s) "
                f"the controller is in a trap of {len(trap)} state(s) it cannot leave"), path, loop=loop, trap=trap,
                hanging_starts=hang))
        elif kind == "leads_to":
            out.append(_leads_to(g, prop, holds_in(prop.expr), holds_in(prop.goal), preds))
        elif kind == "eventually":
            out.append(_eventually(g, prop, holds_in(prop.expr), preds))
        elif kind == "deadlock":
            final = holds_in(prop.final) if prop.final else [False] * n
            parts = [model.controller_part(s) for s in g.states]
            dead = [u for u in range(n) if g.succ[u] and not final[u] and all(parts[v] == parts[u] for v in g.succ[u])]
            if not dead:
                out.append(Verdict(prop, True if g.complete else None, "no reachable state stands still for ever"
                                   if g.complete else f"none among the {n} states explored ({g.stopped})"))
            else:
                first = min(dead, key=lambda u: (g.depth[u], u))
                out.append(Verdict(prop, False, (
                    f"after {g.depth[first]} scan(s) no choice of the environment changes the controller any more"),
                    g.path(first), loop=[first], trap=[first], hanging_starts=_starts_reaching(g, preds(), dead)))
        elif kind == "livelock":
            out.append(_livelock(model, g, prop, preds))
    return out


def _leads_to(g: Graph, prop: ProgramProperty, trigger: list[bool], goal: list[bool],
              preds: Callable[[], Reverse]) -> Verdict:
    n = len(g.states)
    bound = prop.within
    if bound is None:
        # unbounded: from every trigger state, every fair run reaches the goal (as eventually)
        sub = _EventuallyFrom(g, goal, [u for u in range(n) if trigger[u]])
        v = sub.find()
        if v is None:
            return Verdict(prop, True if g.complete else None, "every trigger is followed by the goal"
                           if g.complete else f"not contradicted in the {n} states explored ({g.stopped})")
        return Verdict(prop, False, f"{prop.expr} holds after {g.depth[v[0][-1]]} scan(s) and a fair cycle "
                                    f"without {prop.goal} follows", v[0], loop=v[1])
    cap = bound + 1
    # longest[u]: states on the longest goal-free path from u, capped at bound + 1
    longest = [0 if goal[u] else 1 for u in range(n)]
    live = [u for u in range(n) if not goal[u]]
    for _ in range(bound):
        changed = False
        new = list(longest)
        for u in live:
            best = max((longest[v] for v in g.succ[u]), default=0)
            value = min(cap, 1 + best)
            if value != longest[u]:
                new[u] = value
                changed = True
        longest = new
        if not changed:
            break
    bad = [u for u in range(n) if trigger[u] and longest[u] >= cap]
    if not bad:
        return Verdict(prop, True if g.complete else None, f"{prop.goal} follows {prop.expr} within {bound} scan(s)"
                       if g.complete else f"not contradicted in the {n} states explored ({g.stopped})")
    first = min(bad, key=lambda u: (g.depth[u], u))
    loop: list[int] = []
    u, remaining = first, bound
    while remaining > 0:
        nxt = next((v for v in g.succ[u] if not goal[v] and longest[v] >= remaining), None)
        if nxt is None:
            break
        loop.append(nxt)
        u, remaining = nxt, remaining - 1
    return Verdict(prop, False, f"{prop.expr} holds after {g.depth[first]} scan(s) and {prop.goal} does not "
                                f"follow within {bound} scan(s)", g.path(first), loop=loop,
                   hanging_starts=_starts_reaching(g, preds(), bad))


class _EventuallyFrom:
    """Fair cycles of goal-free states reachable from ``sources`` through goal-free states."""

    def __init__(self, g: Graph, goal: list[bool], sources: list[int]) -> None:
        self.g, self.goal, self.sources = g, goal, [u for u in sources if not goal[u]]
        self.doomed: set[int] = set()  # goal-free states from which a fair goal-free cycle is reachable

    def find(self) -> tuple[list[int], list[int]] | None:
        import networkx as nx
        g, goal = self.g, self.goal
        region = _forward(g, self.sources, lambda v: not goal[v])
        if not region:
            return None
        dg: nx.DiGraph[int] = nx.DiGraph()
        dg.add_nodes_from(region)
        for u in region:
            for v in g.succ[u]:
                if v in region:
                    dg.add_edge(u, v)
        fair_comps = []
        for comp in nx.strongly_connected_components(dg):
            fair = [u for u in comp if g.quiet[u] in comp and (len(comp) > 1 or g.quiet[u] == u)]
            if fair:
                fair_comps.append((min(g.depth[u] for u in comp), comp, fair))
        if not fair_comps:
            return None
        _d, comp, fair = min(fair_comps, key=lambda c: (c[0], min(c[1])))
        entry = min(comp, key=lambda u: (g.depth[u], u))
        path = _path_within(g, self.sources, entry, region)
        # a cycle through the quiet scan: entry -> u, u -> quiet[u], quiet[u] -> entry
        u = min(fair, key=lambda x: (g.depth[x], x))
        loop = [*_steps(g, comp, entry, u), g.quiet[u]]
        if g.quiet[u] != entry:
            loop += _steps(g, comp, g.quiet[u], entry)
        cyclic: set[int] = set()
        for _d2, c, _f in fair_comps:
            cyclic |= c
        self.doomed = _backward_within(dg, cyclic)
        return path, loop


def _steps(g: Graph, members: set[int], a: int, b: int) -> list[int]:
    """The states after ``a`` on a shortest path from ``a`` to ``b`` inside ``members`` (``b`` last)."""
    if a == b:
        return []
    prev = {a: -1}
    todo = deque([a])
    while todo:
        u = todo.popleft()
        for v in g.succ[u]:
            if v in members and v not in prev:
                prev[v] = u
                if v == b:
                    out = [v]
                    while prev[out[-1]] != a:
                        out.append(prev[out[-1]])
                    return out[::-1]
                todo.append(v)
    return [b]


def _backward_within(dg: Any, targets: set[int]) -> set[int]:
    seen = set(targets)
    todo = deque(seen)
    while todo:
        v = todo.popleft()
        for u in dg.predecessors(v):
            if u not in seen:
                seen.add(u)
                todo.append(u)
    return seen


def _path_within(g: Graph, sources: list[int], target: int, region: set[int]) -> list[int]:
    prev: dict[int, int] = dict.fromkeys(sources, -1)
    todo = deque(sources)
    while todo:
        u = todo.popleft()
        if u == target:
            break
        for v in g.succ[u]:
            if v in region and v not in prev:
                prev[v] = u
                todo.append(v)
    inner = [target]
    while prev.get(inner[-1], -1) >= 0:
        inner.append(prev[inner[-1]])
    inner.reverse()
    return g.path(inner[0])[:-1] + inner


def _eventually(g: Graph, prop: ProgramProperty, goal: list[bool], preds: Callable[[], Reverse]) -> Verdict:
    search = _EventuallyFrom(g, goal, list(dict.fromkeys(g.start_states)))
    found = search.find()
    if found is None:
        return Verdict(prop, True if g.complete else None, "every fair run reaches it" if g.complete else
                       f"not contradicted in the {len(g.states)} states explored ({g.stopped})")
    path, loop = found
    return Verdict(prop, False, f"a fair run stays without it for ever: a cycle of {len(set(loop))} state(s) is "
                                f"entered after {len(path) - 1} scan(s)", path, loop=loop,
                   hanging_starts=[n for n, s in enumerate(g.start_states) if s in search.doomed])


def _livelock(model: ProgramModel, g: Graph, prop: ProgramProperty, preds: Callable[[], Reverse]) -> Verdict:
    import networkx as nx
    n = len(g.states)
    waiting = [u for u in range(n) if model.waiting(g.states[u])]
    wset = set(waiting)
    prog = {u: model.program_part(g.states[u]) for u in waiting}
    dg: nx.DiGraph[int] = nx.DiGraph()
    dg.add_nodes_from(waiting)
    for u in waiting:
        for v in g.succ[u]:
            if v in wset and prog[v] == prog[u]:
                dg.add_edge(u, v)
    for comp in nx.strongly_connected_components(dg):
        if len(comp) == 1:
            (u,) = comp
            if not dg.has_edge(u, u):
                continue
        entry = min(comp, key=lambda u: (g.depth[u], u))
        loop = _cycle_in(g, set(comp), entry) if len(comp) > 1 else [entry]
        return Verdict(prop, False, (f"after {g.depth[entry]} scan(s) a cycle of {len(comp)} state(s) begins in "
                                     f"which the program's tags never change while a motion instruction waits"),
                       g.path(entry), loop=loop, hanging_starts=_starts_reaching(g, preds(), list(comp)))
    return Verdict(prop, True if g.complete else None, "no such cycle" if g.complete else
                   f"none among the {n} states explored ({g.stopped})")
