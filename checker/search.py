"""Exhaustive breadth-first exploration of a :class:`checker.model.Model`.

Pipeline position: :mod:`checker.model` -> **checker.search** -> :mod:`checker.counterexample`,
:mod:`checker.coverage`, :mod:`checker.check_cli`.

Algorithm
---------
Breadth-first search with parent links (Holzmann, *The SPIN Model Checker*, ch. 8; the
plain-tuple core of ``shared/reference/tooling-notes.md`` §5).  States are numbered in
the order they are found, which is also the order they are expanded, so the list of
states doubles as the BFS queue and the first violation of a property found is at the
least depth: counterexamples are shortest.  The search is iterative; nothing recurses.

Memory: a state is stored once, as ``bytes`` -- every slot of the flat state is replaced
by its index in a per-slot value table (2 bytes a slot; a tuple of Python objects
would take about 8 bytes a slot plus the objects).  The visited set maps those bytes to
the state number; parents and choices are ``array`` columns of machine integers.

Symmetry reduction: blocks of interchangeable axes (same group of the system: same
chart, type, configurations and program) share their value tables, so a state is
canonicalised by sorting those blocks' byte strings (Ip & Dill, *Better verification
through symmetry*, 1996).  Properties are quantified over all axes and tags, hence
invariant under the permutation.

Complexity: O(S * C) scans for S reachable (canonical) states and C choices per state;
memory O(S * W) bytes for W slots per state.

Limits: ``max_states`` and ``max_seconds`` end the search early with
``complete=False``; violations found until then are real, "holds" becomes "unknown".

Example::

    >>> from statecharts.loader import load_spec
    >>> from checker.system import load_system, bundled_systems
    >>> from checker.model import Model
    >>> spec = load_spec()
    >>> model = Model(spec, load_system(bundled_systems()["noncip"], spec))
    >>> result = explore(model, max_states=500, progress=False)
    >>> result.complete, result.states, result.stop_reason
    (False, 500, 'state limit of 500 reached')
"""

from __future__ import annotations

import gc
import os
import resource
import struct
import sys
import time
from array import array
from collections.abc import Callable
from dataclasses import dataclass, field

from checker.core import CompiledModel
from checker.model import Flat, Model, StepFacts
from checker.properties import Property

#: states expanded between two looks at the clock and the progress bar
CHECK_EVERY = 256


@dataclass(frozen=True, slots=True)
class Witness:
    """Where a property was decided: the transition (parent state, choice) that showed it.

    ``parent`` is -1 for an initial state; then ``choice`` is the configuration
    assignment index."""

    prop: str
    parent: int
    choice: int
    depth: int


@dataclass
class Coverage:
    configs: set[tuple[str, frozenset[str]]] = field(default_factory=set)
    fired: set[tuple[str, str]] = field(default_factory=set)
    executed: set[tuple[str, str]] = field(default_factory=set)
    errors: set[tuple[str, int, int]] = field(default_factory=set)
    values: set[tuple[str, str, object]] = field(default_factory=set)
    #: (instruction, check id) of every check or abort that failed first in some step
    checks: set[tuple[str, str]] = field(default_factory=set)
    #: with ``explore(witnesses=True)``: every coverage item -> ``(state, choice)`` of the
    #: first step (in BFS order, hence of least depth) that showed it; items are
    #: ``("transition", chart, id)``, ``("cell", instruction, state)``,
    #: ``("error", instruction, ERR, EXERR)`` and ``("check", instruction, check id)``
    first: dict[tuple[object, ...], tuple[int, int]] = field(default_factory=dict)


@dataclass
class SearchResult:
    model: Model
    states: int
    transitions: int
    depth: int
    seconds: float
    complete: bool
    stop_reason: str | None
    violations: dict[str, Witness]
    reached: dict[str, Witness]
    deadlocks: list[int]
    coverage: Coverage
    peak_rss_kb: int
    codec: Codec | CoreCodec
    encoded: list[bytes]
    parent: array[int]
    via: array[int]
    depth_of: array[int]
    edges: array[int] | None
    initial_assignment: dict[int, int]
    #: bytes of the visited set's table (the compiled core's search; 0 otherwise)
    visited_bytes: int = 0
    #: the compiled core the search ran on (None for the interpreter back-end)
    core: object = None

    @property
    def states_per_second(self) -> float:
        return self.states / self.seconds if self.seconds > 0 else float(self.states)

    def state(self, i: int) -> Flat:
        return self.codec.decode(self.encoded[i])

    def path(self, i: int) -> list[tuple[int, int]]:
        """[(state, choice that led to it)] from an initial state to state ``i``; the
        initial state's entry carries its configuration assignment index."""
        out = []
        while True:
            p = self.parent[i]
            out.append((i, self.via[i]))
            if p < 0:
                break
            i = p
        out.reverse()
        return out


class Codec:
    """Flat states <-> compact, canonical ``bytes``."""

    def __init__(self, model: Model) -> None:
        width = model.width
        tables: list[tuple[dict[object, int], list[object]]] = [({}, [])]  # slot 0: phase
        slot_table = [0] * width
        owner: dict[tuple[int, int], int] = {}
        for ai in range(len(model.axes)):
            group = next((g for g in model.symmetric_groups if ai in g), None)
            leader = group[0] if group else ai
            start = model.block_start[ai]
            for k in range(model.block_len[ai]):
                key = (leader, k)
                if key not in owner:
                    owner[key] = len(tables)
                    tables.append(({}, []))
                slot_table[start + k] = owner[key]
        self.slots = [tables[t] for t in slot_table]
        self.groups = [
            [(4 * model.block_start[a], 4 * (model.block_start[a] + model.block_len[a])) for a in g]
            for g in model.symmetric_groups
        ]

    def encode(self, flat: Flat) -> bytes:
        codes = []
        for (table, values), v in zip(self.slots, flat):
            c = table.get(v)
            if c is None:
                c = len(values)
                if c > 0xFFFFFFFF:
                    raise OverflowError("more than 2**32 distinct values in one state slot")
                table[v] = c
                values.append(v)
            codes.append(c)
        raw = array("I", codes).tobytes()
        if self.groups:
            raw = self.canonical(raw)
        return raw

    def canonical(self, raw: bytes) -> bytes:
        for ranges in self.groups:
            blocks = sorted(raw[a:b] for a, b in ranges)
            parts = []
            last = 0
            for (a, b), blk in zip(ranges, blocks):
                parts.append(raw[last:a])
                parts.append(blk)
                last = b
            parts.append(raw[last:])
            raw = b"".join(parts)
        return raw

    def decode(self, raw: bytes) -> Flat:
        codes = array("I")
        codes.frombytes(raw)
        return tuple([values[c] for (_t, values), c in zip(self.slots, codes)])


def progress_wanted() -> bool:
    """Whether long work shows a progress bar: on a terminal, and not under CI."""
    return sys.stderr.isatty() and os.environ.get("CI", "").lower() not in ("true", "1")


def explore_interpreted(
    model: Model,
    *,
    max_states: int | None = None,
    max_seconds: float | None = None,
    keep_graph: bool = False,
    progress: bool | None = None,
    on_progress: Callable[[int, int, float], None] | None = None,
    stop_on_violation: bool = False,
    witnesses: bool = False,
) -> SearchResult:
    """The interpreter back-end of the search: every step loads a whole
    :class:`statecharts.scan.System`, scans it and extracts the successor.  Kept as the
    reference the compiled core (:func:`explore`) is tested against.

    With ``stop_on_violation`` the search ends (incomplete) after the expansion in which
    the first invariant or response violation was found; that violation is still one of
    least depth.  With ``witnesses`` the coverage records, for every item, the first
    step that covered it (:attr:`Coverage.first`), from which a shortest run is replayed."""
    start = time.perf_counter()
    codec = Codec(model)
    index: dict[bytes, int] = {}
    encoded: list[bytes] = []
    parent = array("i")
    via = array("i")
    depth_of = array("H")
    edges = array("I") if keep_graph else None
    violations: dict[str, Witness] = {}
    reached: dict[str, Witness] = {}
    deadlocks: list[int] = []
    cov = Coverage()
    initial_assignment: dict[int, int] = {}
    transitions = 0
    watched = {p.name for p in model.properties if p.kind in ("invariant", "response", "reachable")}

    seen_axis_parts: set[object] = set()

    def note_state(flat: Flat) -> None:
        for ai, axis in enumerate(model.axes):
            part = flat[model.block_start[ai]]
            if part in seen_axis_parts:
                continue
            seen_axis_parts.add(part)
            cid = axis.chart.id
            cov.configs.add((cid, part[0]))
            for v, x in zip(axis.c.variables, part[1]):
                cov.values.add((cid, v, x))

    for ai_index, assignment in enumerate(model.assignments):
        flat, bad, good = model.initial(assignment)
        code = codec.encode(flat)
        if code in index:
            continue
        sid = len(encoded)
        index[code] = sid
        encoded.append(code)
        parent.append(-1)
        via.append(ai_index)
        depth_of.append(0)
        initial_assignment[sid] = ai_index
        note_state(flat)
        for p in bad:
            violations.setdefault(p.name, Witness(p.name, -1, ai_index, 0))
        for p in good:
            reached.setdefault(p.name, Witness(p.name, -1, ai_index, 0))

    show = progress_wanted() if progress is None else progress
    bar = None
    task = None
    if show:
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        bar = Progress(TextColumn("[bold]check[/bold] {task.fields[system]}"), BarColumn(),
                       TextColumn("{task.completed:,} expanded / {task.total:,} found  {task.fields[rate]}"),
                       TimeElapsedColumn(), transient=True)
        bar.start()
        task = bar.add_task("explore", total=len(encoded), system=model.sysdef.name, rate="")
    stop_reason: str | None = None
    i = 0
    steps = model.step
    load = model.load
    try:
        while i < len(encoded):
            if i % CHECK_EVERY == 0:
                elapsed = time.perf_counter() - start
                if max_seconds is not None and elapsed > max_seconds:
                    stop_reason = f"time limit of {max_seconds:g} s reached"
                    break
                if bar is not None and task is not None:
                    bar.update(task, completed=i, total=len(encoded), rate=f"{len(encoded) / max(elapsed, 1e-9):,.0f} states/s")
                if on_progress is not None:
                    on_progress(i, len(encoded), elapsed)
            flat = codec.decode(encoded[i])
            d = depth_of[i] + 1
            load(flat)
            succs: set[int] = set()
            first = True
            for ch in model.enabled():
                if not first:
                    load(flat)
                first = False
                succ, bad, good, facts = steps(ch)
                code = codec.encode(succ)
                j = index.get(code)
                if j is None:
                    if max_states is not None and len(encoded) >= max_states:
                        stop_reason = f"state limit of {max_states:,} reached"
                        raise _Stop
                    j = len(encoded)
                    index[code] = j
                    encoded.append(code)
                    parent.append(i)
                    via.append(ch.index)
                    depth_of.append(d)
                    note_state(succ)
                if j not in succs:
                    succs.add(j)
                    if edges is not None:
                        edges.append(i)
                        edges.append(j)
                if facts.fired:
                    cov.fired.update(facts.fired)
                if facts.executed:
                    cov.executed.update(facts.executed)
                if facts.errors:
                    cov.errors.update(facts.errors)
                if facts.checks:
                    cov.checks.update(facts.checks)
                if witnesses and (facts.fired or facts.executed or facts.errors or facts.checks):
                    _note_witnesses(cov.first, facts, i, ch.index)
                if bad:
                    for p in bad:
                        if p.name not in violations:
                            violations[p.name] = Witness(p.name, i, ch.index, d)
                if good:
                    for p in good:
                        if p.name not in reached:
                            reached[p.name] = Witness(p.name, i, ch.index, d)
            transitions += len(succs)
            if not succs - {i}:
                deadlocks.append(i)
            i += 1
            if stop_on_violation and violations:
                stop_reason = "stopped at the first violation"
                break
    except _Stop:
        pass
    finally:
        if bar is not None:
            bar.stop()
    del watched
    seconds = time.perf_counter() - start
    complete = stop_reason is None
    return SearchResult(
        model=model, states=len(encoded), transitions=transitions,
        depth=max(depth_of) if len(depth_of) else 0, seconds=seconds, complete=complete,
        stop_reason=stop_reason, violations=violations, reached=reached, deadlocks=deadlocks, coverage=cov,
        peak_rss_kb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, codec=codec, encoded=encoded,
        parent=parent, via=via, depth_of=depth_of, edges=edges, initial_assignment=initial_assignment,
    )


class _Stop(Exception):
    pass


def _note_witnesses(first: dict[tuple[object, ...], tuple[int, int]], facts: StepFacts, state: int, choice: int) -> None:
    where = (state, choice)
    for c, t in facts.fired:
        first.setdefault(("transition", c, t), where)
    for m, s in facts.executed:
        first.setdefault(("cell", m, s), where)
    for m, e, x in facts.errors:
        first.setdefault(("error", m, e, x), where)
    for m, c in facts.checks:
        first.setdefault(("check", m, c), where)


@dataclass(frozen=True)
class WitnessRun:
    """A shortest run that shows one coverage item: start in configuration assignment
    ``assignment`` (an index of ``model.assignments``), then scan with each choice of
    ``choices`` (indices of ``model.choices``) in turn; the last scan shows the item.
    ``states`` are the numbers of the states the run passes through, the start first."""

    item: tuple[object, ...]
    assignment: int
    choices: tuple[int, ...]
    states: tuple[int, ...]


def witness_run(result: SearchResult, item: tuple[object, ...]) -> WitnessRun:
    """The shortest run to coverage ``item`` of a search made with ``witnesses=True``
    (:func:`explore` or :func:`explore_interpreted`; :attr:`Coverage.first` lists the
    items).  The run's length is the least number of scans that shows the item.

    Raises ``KeyError`` for an item the search did not cover (or recorded no witnesses)."""
    state, choice = result.coverage.first[item]
    path = result.path(state)
    return WitnessRun(item=item, assignment=path[0][1], choices=(*(c for _s, c in path[1:]), choice),
                      states=tuple(s for s, _c in path))


def is_property_decided(result: SearchResult, p: Property) -> bool:
    return p.name in result.violations or p.name in result.reached or result.complete


# --------------------------------------------------------------------------- the compiled core


class CoreCodec:
    """States of the compiled core <-> packed ``bytes`` (2 bytes a slot, 4 once a slot
    has more than 65,536 values) and interpreter flat states."""

    def __init__(self, core: CompiledModel) -> None:
        self.core = core
        self.set_format("H")

    def set_format(self, code: str) -> None:
        self.format = code
        st = struct.Struct(f"<{self.core.width}{code}")
        self.pack = st.pack
        self.unpack = st.unpack

    def encode(self, flat: Flat) -> bytes:
        return self.pack(*self.core.encode_flat(flat))

    def decode(self, raw: bytes) -> Flat:
        return self.core.decode(self.unpack(raw))


def stored_bytes(result: SearchResult) -> int:
    """Bytes held by the stored states: the visited set, the packed states, the BFS
    list and the parent / choice / depth columns."""
    total = sys.getsizeof(result.encoded) + sum(sys.getsizeof(c) for c in result.encoded)
    total += result.visited_bytes
    for col in (result.parent, result.via, result.depth_of):
        total += col.buffer_info()[1] * col.itemsize
    return total


def explore(
    model: Model,
    *,
    max_states: int | None = None,
    max_seconds: float | None = None,
    keep_graph: bool = False,
    progress: bool | None = None,
    on_progress: Callable[[int, int, float], None] | None = None,
    stop_on_violation: bool = False,
    witnesses: bool = False,
) -> SearchResult:
    """Explore every state of ``model`` reachable from its initial states, breadth first,
    on the compiled core (:mod:`checker.core`).

    With ``stop_on_violation`` the search ends (incomplete) after the expansion in which
    the first invariant or response violation was found; that violation is still one of
    least depth.  With ``witnesses`` the coverage records, for every item, a step of
    least depth that covered it (:attr:`Coverage.first`; :func:`witness_run` gives the
    run to it)."""
    if model.add_ons or model.max_changes is not None:
        # the compiled core's blocks are axes and their tags; an add-on instruction reads and
        # drives several of them in one scan, so its systems are searched on the interpreter
        return explore_interpreted(model, max_states=max_states, max_seconds=max_seconds, keep_graph=keep_graph,
                                   progress=progress, on_progress=on_progress, stop_on_violation=stop_on_violation,
                                   witnesses=witnesses)
    start = time.perf_counter()
    # the search allocates millions of small acyclic objects (tuples, bytes) and keeps
    # most of them: the cyclic collector would walk the growing heap again and again
    # for nothing (about a fifth of the time), so it is off while the search runs
    collecting = gc.isenabled()
    gc.disable()
    try:
        return _explore(model, start, max_states=max_states, max_seconds=max_seconds, keep_graph=keep_graph,
                        progress=progress, on_progress=on_progress, stop_on_violation=stop_on_violation,
                        witnesses=witnesses)
    finally:
        if collecting:
            gc.enable()


def _explore(
    model: Model,
    start: float,
    *,
    max_states: int | None,
    max_seconds: float | None,
    keep_graph: bool,
    progress: bool | None,
    on_progress: Callable[[int, int, float], None] | None,
    stop_on_violation: bool,
    witnesses: bool,
) -> SearchResult:
    core = CompiledModel(model)
    codec = CoreCodec(core)
    pack = codec.pack
    unpack = codec.unpack
    index: dict[bytes, int] = {}
    seen: set[bytes] = set()
    encoded: list[bytes] = []
    parent = array("i")
    via = array("i")
    depth_of = array("H")
    edges = array("I") if keep_graph else None
    violations: dict[str, Witness] = {}
    reached: dict[str, Witness] = {}
    deadlocks: list[int] = []
    initial_assignment: dict[int, int] = {}
    transitions = 0

    def widen() -> None:
        nonlocal pack, unpack
        old = codec.unpack
        codec.set_format("I")
        pack, unpack = codec.pack, codec.unpack
        for n, raw in enumerate(encoded):
            encoded[n] = pack(*old(raw))
        seen.clear()
        seen.update(encoded)
        if keep_graph:
            index.clear()
            index.update((c, n) for n, c in enumerate(encoded))

    def encode(state: tuple[int, ...]) -> bytes:
        try:
            return pack(*state)
        except struct.error:
            widen()
            return pack(*state)

    for ai_index, (state, bad0, good0) in enumerate(core.initial_states()):
        code = encode(state)
        if code in seen:
            continue
        sid = len(encoded)
        seen.add(code)
        if keep_graph:
            index[code] = sid
        encoded.append(code)
        parent.append(-1)
        via.append(ai_index)
        depth_of.append(0)
        initial_assignment[sid] = ai_index
        for p in bad0:
            violations.setdefault(p.name, Witness(p.name, -1, ai_index, 0))
        for p in good0:
            reached.setdefault(p.name, Witness(p.name, -1, ai_index, 0))

    show = progress_wanted() if progress is None else progress
    bar = None
    task = None
    if show:
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        bar = Progress(TextColumn("[bold]check[/bold] {task.fields[system]}"), BarColumn(),
                       TextColumn("{task.fields[found]:,} states  {task.fields[rate]}  queue {task.fields[queue]:,}"),
                       TimeElapsedColumn(), transient=True)
        bar.start()
        task = bar.add_task("explore", total=len(encoded), system=model.sysdef.name, rate="", found=len(encoded),
                            queue=len(encoded))
    stop_reason: str | None = None
    i = 0
    successors = core.successors
    try:
        while i < len(encoded):
            if i % CHECK_EVERY == 0:
                elapsed = time.perf_counter() - start
                if max_seconds is not None and elapsed > max_seconds:
                    stop_reason = f"time limit of {max_seconds:g} s reached"
                    break
                if bar is not None and task is not None:
                    bar.update(task, completed=i, total=len(encoded), found=len(encoded), queue=len(encoded) - i,
                               rate=f"{len(encoded) / max(elapsed, 1e-9):,.0f} states/s")
                if on_progress is not None:
                    on_progress(i, len(encoded), elapsed)
            own = encoded[i]
            d = depth_of[i] + 1
            core.current = i
            succs: set[bytes] = set()
            for c, succ, bad, good in successors(unpack(own)):
                try:
                    code = pack(*succ)
                except struct.error:
                    old_unpack = unpack
                    widen()
                    code = pack(*succ)
                    own = encoded[i]
                    succs = {pack(*old_unpack(x)) for x in succs}
                if code not in seen:
                    if max_states is not None and len(encoded) >= max_states:
                        stop_reason = f"state limit of {max_states:,} reached"
                        raise _Stop
                    if keep_graph:
                        index[code] = len(encoded)
                    seen.add(code)
                    encoded.append(code)
                    parent.append(i)
                    via.append(c)
                    depth_of.append(d)
                if bad:
                    for p in bad:
                        if p.name not in violations:
                            violations[p.name] = Witness(p.name, i, c, d)
                if good:
                    for p in good:
                        if p.name not in reached:
                            reached[p.name] = Witness(p.name, i, c, d)
                succs.add(code)
            transitions += len(succs)
            if edges is not None:
                for code in succs:
                    edges.append(i)
                    edges.append(index[code])
            if not succs or (len(succs) == 1 and own in succs):
                deadlocks.append(i)
            i += 1
            if stop_on_violation and violations:
                stop_reason = "stopped at the first violation"
                break
    except _Stop:
        pass
    finally:
        if bar is not None:
            bar.stop()
    seconds = time.perf_counter() - start
    cov = core.cov
    coverage = Coverage(set(cov.configs), set(cov.fired), set(cov.executed), set(cov.errors), set(cov.values),
                        set(cov.checks), dict(cov.first) if witnesses else {})
    return SearchResult(
        model=model, states=len(encoded), transitions=transitions,
        depth=max(depth_of) if len(depth_of) else 0, seconds=seconds, complete=stop_reason is None,
        stop_reason=stop_reason, violations=violations, reached=reached, deadlocks=deadlocks, coverage=coverage,
        peak_rss_kb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, codec=codec, encoded=encoded,
        parent=parent, via=via, depth_of=depth_of, edges=edges, initial_assignment=initial_assignment,
        visited_bytes=sys.getsizeof(index if keep_graph else seen), core=core,
    )
