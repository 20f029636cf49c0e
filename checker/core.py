"""The compiled checker core: states as flat vectors of small integers, scans as table look-ups.

Pipeline position: :mod:`checker.model` (the system, its alphabet and abstractions) ->
**checker.core** -> :mod:`checker.search`.

A state is a tuple of small integers: the phase of the coarse-update clock, then per
axis the number of its *axis part* (configuration, chart variables, queued requests,
held environment events) followed by the number of each of its tags' *tag part*
(members, rung, operands, response monitors).  The numbers index interning tables of
exactly the parts :meth:`checker.model.Model.extract` produces, so a state of the core
decodes to the interpreter's flat state (:meth:`CompiledModel.decode`) and counterexamples
are replayed by the interpreter unchanged.

A scan is composed of **pieces**, each a pure function of a few numbers and memoised in
a dict the first time it is needed: a tag's execution-table row, an instruction's
execution (its checks against its axis), the clock tick of an axis, the finishing of a
pending instruction, the delivery of a queued request, an environment event, and the
evaluation of properties and abstractions on a tag or axis after the scan.  A piece is
computed once by the one implementation of the scan rules (:class:`statecharts.scan.System`
and :class:`checker.compile.FastAxis`, loaded with just the parts the piece reads), so the
hot loop never constructs, restores or snapshots chart objects: it is integer and dict
work only.  Coverage facts (transitions fired, instruction x state cells, error codes)
are recorded when a piece is first computed: a piece's facts are the same every time it
runs.

Ordering rules (the same as ``statecharts/scan.py``, ``System.advance`` and
``System._coarse_update``, written out in ``docs/semantics.md``); :meth:`CompiledModel._block`
composes the pieces in this order, per axis block:

1. the input change of the scan: a rung raised with its operands, a rung dropped, or an
   environment event held for the next coarse update;
2. program: every tag of the axis in program order runs the row of its execution table
   for its condition (``rung_true`` / ``rung_false``, ``prescan`` on a prescan pass); a
   row that executes runs the instruction's checks of stage ``execute`` against the
   axis, and an accepted request moves to the end of the queue;
3. coarse update (phase 0 of the clock, not on a prescan pass): the axis gets ``tick``;
   delivered, still pending instructions are finished in program order; the queued
   requests of the axis are delivered in queue order (all checks again, request
   actions, request event, finish); the held environment events are applied in order;
   then every delivered, pending instruction is finished again in program order;
4. after the scan: properties are evaluated on the concrete parts, then the
   abstractions (collapse, dead operands, idle-tag retirement) give the stored parts.

Axes do not interact within a scan (a piece reads one tag and its own axis), so each axis
block is stepped on its own and, on systems of several axes, the step of a block under
no input is memoised per block.  Symmetry: blocks of interchangeable axes are sorted.

A call that reads a second axis (MAG's checks read its master axis, ``master.X``) breaks
that independence: its execution reads the master as it is before the coarse update, its
delivery the master as the coarse update has left it so far.  When the master comes
after its slave in axis order, both see the master's core at the start of the scan,
which is part of the state: the slave's pieces are then memoised per master core (the
slave's tables are swapped for the master core's before its block is stepped,
:meth:`CompiledModel._bind_master`), and a choice on either block still changes that
block only.  Otherwise (a master listed before its slave, a slave with two masters,
interchangeable axes, a completion condition that reads the master and so sees it after
the whole update), and in a system with add-on instruction tags (an instance reads and
drives several axes and devices in one scan; its part and the changes left follow the
axis blocks in the state) the successors are computed as the interpreter back-end computes them
(:meth:`CompiledModel._coupled_successors`: decode, load, scan each enabled choice,
encode); the states are still numbered, stored and searched by the core, and coverage
is credited the same way.

Complexity: one dict look-up per piece per scan once the pieces are known; the tables
grow with the number of distinct parts, not with the number of states.

Example::

    >>> from statecharts.loader import load_spec
    >>> from checker.system import load_system, bundled_systems
    >>> from checker.model import Model
    >>> spec = load_spec()
    >>> core = CompiledModel(Model(spec, load_system(bundled_systems()["noncip"], spec)))
    >>> start = core.initial_states()[0][0]
    >>> len(core.decode(start)) == len(start)
    True
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

from checker.model import Flat, Model
from checker.properties import Property
from statecharts import drive, ir
from statecharts.scan import Done, Errored, Executed

#: scan modes of a block
NORMAL, COARSE, PRESCAN = 0, 1, 2
#: input kinds of a choice (PRESCAN_PASS applies to every block)
NOTHING, RAISE, DROP, EVENT, PRESCAN_PASS = 0, 1, 2, 3, 4
#: a RAISE, DROP or EVENT together with a drive event of the axis: kind + WITH_DRIVE,
#: argument (the base argument, the drive event)
WITH_DRIVE = 10
_CONDITIONS = ("rung_false", "rung_true", "prescan")

State = tuple[int, ...]
#: a block's step under no input: (block, violated, reached)
BlockStep = tuple[tuple[int, ...], list["Property"], list["Property"]]
#: the moves of a block's own choices: (choice, block, violated, reached)
Moves = list[tuple[int, tuple[int, ...], list["Property"], list["Property"]]]
#: the moves of the environment events at the end of a block's choices (kept in a memo)
EventMoves = tuple[tuple[int, tuple[int, ...], list["Property"], list["Property"]], ...]
#: a choice offered: (choice, kind, local tag, argument)
Choice = tuple[int, int, int, object]
#: what a block's context decides (CompiledModel._ctx_memo)
Context = tuple[tuple[int, ...], tuple[int, ...], tuple[Choice, ...], tuple[tuple[str, int, frozenset[int]], ...],
                int, tuple[str, ...], dict[int, tuple[Choice, ...]]]
_NONE: tuple[Property, ...] = ()


@dataclass
class CoreCoverage:
    """Coverage facts gathered while pieces are computed (same shape as the search's)."""

    configs: set[tuple[str, frozenset[str]]] = field(default_factory=set)
    fired: set[tuple[str, str]] = field(default_factory=set)
    executed: set[tuple[str, str]] = field(default_factory=set)
    errors: set[tuple[str, int, int]] = field(default_factory=set)
    values: set[tuple[str, str, object]] = field(default_factory=set)
    #: (instruction, check id) of every check or abort that failed first in some step
    checks: set[tuple[str, str]] = field(default_factory=set)
    #: every coverage item -> ``(state, choice)`` of the step that first showed it (the
    #: state being expanded, :attr:`CompiledModel.current`, when the piece was computed);
    #: items as :attr:`checker.search.Coverage.first` writes them
    first: dict[tuple[object, ...], tuple[int, int]] = field(default_factory=dict)


class Intern:
    """Values <-> dense small integers."""

    __slots__ = ("index", "values")

    def __init__(self) -> None:
        self.index: dict[Any, int] = {}
        self.values: list[Any] = []

    def id(self, value: Any) -> int:
        i = self.index.get(value)
        if i is None:
            i = len(self.values)
            self.index[value] = i
            self.values.append(value)
        return i

    def __len__(self) -> int:
        return len(self.values)


class CompiledModel:
    """The transition system of a :class:`~checker.model.Model` over integer vectors."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.system = model.system
        self.spu = model.spu
        self.naxes = len(model.axes)
        self.width = model.width
        self.block_start = list(model.block_start)
        self.block_len = list(model.block_len)
        self.cores = Intern()  # concrete axis cores: FastAxis snapshots
        self.parts = Intern()  # abstract axis parts, as Model.extract writes them
        self.tags = Intern()  # tag parts (values, rung, operands, monitors)
        #: the parts after the axis blocks (add-on instruction tags, the changes left), interned
        self.extra = Intern()
        self.axis_end = model.block_start[-1] + model.block_len[-1] if model.block_start else 1
        self.nextra = self.width - self.axis_end
        self.cov = CoreCoverage()
        #: number of the state being expanded (set by the search; coverage witnesses)
        self.current = -1
        #: (state, choice) a newly computed piece's coverage facts are credited to
        self.where: tuple[int, int] = (-1, -1)
        self.tis: list[tuple[int, ...]] = [tuple(t) for t in model.tags_of_axis]
        self.chart_of = [a.chart.id for a in model.axes]
        fields = model.slots[0].fields if model.slots else ()
        self._pending_pos = fields.index("pending") if "pending" in fields else -1
        self.symmetric_groups = [list(g) for g in model.symmetric_groups]
        self.max_live = model.sysdef.max_live_calls
        self.has_prescan = model.prescan is not None
        self.prescan_index = model.prescan.index if model.prescan is not None else -1
        self.nothing_index = model.nothing.index

        # the alphabet, per axis: (choice index, kind, local tag, argument)
        local_of = {ti: (s.axis_index, s.local) for ti, s in enumerate(model.slots)}
        self.raises: list[list[tuple[int, int]]] = [[] for _ in model.slots]  # per tag: (choice, op index)
        self.raise_ops: list[list[tuple[object, ...]]] = [[] for _ in model.slots]
        for ti, chs in enumerate(model.raise_choices):
            for k, c in enumerate(chs):
                self.raises[ti].append((c.index, k))
                self.raise_ops[ti].append(tuple(v for _n, v in c.operands))
        self.drops = [c.index for c in model.drop_choice]
        axis_no = {name: i for i, (name, _g) in enumerate(model.axis_defs)}
        self.events: list[tuple[int, int, str]] = []  # (choice, axis, event)
        for c in model.event_choices:
            assert c.axis is not None and c.event is not None
            self.events.append((c.index, axis_no[c.axis], c.event))
        self.tag_local = local_of
        #: base choice -> its combinations with a drive event: (choice, drive event)
        self.combos: dict[int, list[tuple[int, str]]] = {
            b: [(c.index, str(c.drive)) for c in cs] for b, cs in model.drive_combos.items()}

        # per-tag derived facts of tag parts, computed on first use
        self._rung: list[bool] = []
        self._pending: list[bool] = []
        self._live0: list[dict[int, bool]] = [{} for _ in model.slots]
        # memo tables of the pieces
        self._rows: list[dict[int, tuple[int, bool]]] = [{} for _ in model.slots]
        self._exec: list[dict[tuple[int, int], tuple[int, bool]]] = [{} for _ in model.slots]
        self._finish: list[dict[tuple[int, int], int]] = [{} for _ in model.slots]
        self._deliver: list[dict[tuple[int, int], tuple[int, int]]] = [{} for _ in model.slots]
        self._raise: list[dict[tuple[int, int], int]] = [{} for _ in model.slots]
        self._drop: list[dict[int, int]] = [{} for _ in model.slots]
        self._tick: list[dict[int, int]] = [{} for _ in model.axes]
        self._event: list[dict[tuple[int, str], int]] = [{} for _ in model.axes]
        #: per axis, its chart's drive events in the order the scan applies them (after the tick)
        self._drive: list[tuple[str, ...]] = [
            tuple(e for e in drive.EVENTS if any(x.name == e and x.kind == "drive" for x in a.chart.events))
            for a in model.axes]
        self._tag_post: list[dict[tuple[int, bool, int], tuple[int, tuple[Property, ...], tuple[Property, ...]]]] = [
            {} for _ in model.slots]
        self._axis_post: list[dict[int, tuple[int, tuple[Property, ...], tuple[Property, ...]]]] = [
            {} for _ in model.axes]
        self._join: list[dict[tuple[int, tuple[int, ...], tuple[str, ...]], int]] = [{} for _ in model.axes]
        self._split: list[tuple[int, tuple[int, ...], tuple[str, ...]]] = []
        self._busy: list[bool] = []  # per axis part: requests queued or events held
        self._reads_axis = [s.reads_axis for s in model.slots]
        self._axis_names = [tuple(sorted({n for p in (*s.inv, *s.reach, *s.monitors) for n in p.names()
                                          if n.startswith("axis.")})) for s in model.slots]
        # tags whose properties read the same axis names (on the same axis) share views
        shared: dict[tuple[object, ...], tuple[dict[int, int], Intern, list[int]]] = {}
        self._view: list[dict[int, int]] = []
        self._views: list[Intern] = []
        self._view_core: list[list[int]] = []
        for ti, sl in enumerate(model.slots):
            v = shared.setdefault((sl.axis_index, self._axis_names[ti]), ({}, Intern(), []))
            self._view.append(v[0])
            self._views.append(v[1])
            self._view_core.append(v[2])
        self._inert: list[dict[int, bool]] = [{} for _ in model.slots]
        # per axis: (queue, tag parts) -> (active tags, watched tags, choices offered, the
        # drive events offered with the choices that give each, where the trailing
        # environment events start, the drive events offered, and the choices to scan by
        # which of those drive events are idle (a bit each; -1 outside a coarse update))
        self._ctx_memo: list[dict[tuple[tuple[int, ...], tuple[int, ...]], Context]] = [{} for _ in model.axes]
        #: per axis: (axis part, drive events offered) -> which of them are idle (_idle_drive)
        self._idle_memo: list[dict[tuple[int, tuple[str, ...]], int]] = [{} for _ in model.axes]
        self._tail_memo: list[dict[tuple[object, ...], dict[int, tuple[
            int, tuple[int, ...], list[Property], list[Property], tuple[int, ...]]]]] = [{} for _ in model.axes]
        self._exec_by_view: list[dict[tuple[int, tuple[object, ...]], tuple[int, bool]]] = [{} for _ in model.slots]
        self._finish_by_view: list[dict[tuple[int, tuple[object, ...]], int]] = [{} for _ in model.slots]
        self._exec_proj: list[Callable[[int], tuple[object, ...]] | None] = [None] * len(model.slots)
        self._finish_proj: list[Callable[[int], tuple[object, ...]] | None] = [None] * len(model.slots)
        self._view_proj: list[Callable[[int], tuple[object, ...]] | None] = [None] * len(model.slots)
        self._watch_memo: list[dict[tuple[tuple[int, ...], int], tuple[tuple[int, ...], tuple[Property, ...],
                                                                  tuple[Property, ...]]]] = [{} for _ in model.axes]
        self._quiet: list[dict[int, bool]] = [{} for _ in model.slots]
        #: per tag: (tag part, queued, axis core) -> its part after a prescan pass (prescan_block)
        self._prescan_tag: list[dict[tuple[int, bool, int], tuple[int, tuple[Property, ...], tuple[Property, ...]]
                                     | tuple[()]]] = [{} for _ in model.slots]
        #: per axis: axis part -> (axis part, violated, reached) after a prescan pass
        self._prescan_axis: list[dict[int, tuple[int, tuple[Property, ...], tuple[Property, ...]]]] = [
            {} for _ in model.axes]
        #: per axis: the base scan up to the deliveries (axis core, tags, events, tags
        #: scanned, tags watched) -> the moves of the environment events at the end of the choices
        self._event_moves: list[dict[tuple[object, ...], EventMoves]] = [{} for _ in model.axes]
        #: per axis: (axis core, held events) -> (choice, core) of the trailing
        #: environment events that change the core (_event_cores)
        self._suffix_cores: list[dict[tuple[int, tuple[str, ...]], tuple[tuple[int, int], ...]]] = [
            {} for _ in model.axes]
        self._block_memo: list[dict[tuple[object, ...], tuple[BlockStep, Moves]]] = [{} for _ in model.axes]
        self.use_block_memo = self.naxes > 1
        self._own_memo: list[dict[tuple[object, ...], tuple[BlockStep, Moves]]] = [{} for _ in model.axes]
        # blocks of interchangeable axes share their move tables (the leader's choices)
        self._leader = list(range(self.naxes))
        self._remap: list[dict[int, int]] = [{} for _ in model.axes]
        self._remap_back: list[dict[int, int]] = [{} for _ in model.axes]
        for group in self.symmetric_groups:
            lead = group[0]
            for ai in group[1:]:
                own = self._alphabet(ai)
                theirs = self._alphabet(lead)
                if len(own) != len(theirs):
                    continue
                self._leader[ai] = lead
                self._remap[ai] = dict(zip(theirs, own))
                self._remap_back[ai] = dict(zip(own, theirs))
        self.canonical_fast = self._canonical_function()
        self._single = self.naxes == 1 and not self.symmetric_groups and not self.use_block_memo
        self._group_of = [-1] * self.naxes
        for g, group in enumerate(self.symmetric_groups):
            for ai in group:
                self._group_of[ai] = g
        # every axis in one group of interchangeable one-slot blocks, no prescan choice:
        # a state is the phase then the sorted axis parts (_flat_successors)
        groups = self.symmetric_groups
        self._flat = (not self.has_prescan and len(groups) == 1 and len(groups[0]) == self.naxes > 1
                      and all(n == 1 for n in self.block_len) and not self.nextra)
        #: a call reads another axis than its own (a bound master axis), or an add-on
        #: instruction tag drives several axes and devices in one scan
        self.coupled = bool(model.masters) or bool(self.nextra)
        #: slave axis -> its master axis, when the slave's pieces can be memoised per
        #: master core (_bind_master); None: successors come from the interpreter
        self._couple: dict[int, int] | None = None if self.nextra else self._couplings() if self.coupled else {}
        self._bound: dict[int, int] = {}  # slave axis -> master core its tables are for
        self._bundles: dict[tuple[int, int], tuple[list[dict[Any, Any]], list[dict[Any, Any]]]] = {}

    # ------------------------------------------------------------------ interning

    def tag_id(self, part: tuple[object, ...]) -> int:
        tags = self.tags
        i = tags.index.get(part)
        if i is None:
            i = tags.id(part)
            self._rung.append(bool(part[1]))
            pos = self._pending_pos
            values = cast("tuple[object, ...]", part[0])  # the member and internal values
            self._pending.append(bool(values[pos]) if pos >= 0 else False)
        return i

    def part_id(self, ai: int, part: tuple[object, ...]) -> int:
        parts = self.parts
        i = parts.index.get(part)
        if i is None:
            i = parts.id(part)
            core = (part[0], part[1], part[2]) if len(part) > 4 else (part[0], part[1])
            queue = cast("tuple[int, ...]", part[-2])  # queued requests, local tag numbers
            held = cast("tuple[str, ...]", part[-1])  # held environment events
            self._split.append((self.cores.id(core), tuple(queue), tuple(held)))
            self._busy.append(bool(queue or held))
            cid = self.chart_of[ai]
            self.cov.configs.add((cid, cast("frozenset[str]", part[0])))  # the configuration
            for v, x in zip(self.model.axes[ai].c.variables, cast("tuple[object, ...]", part[1])):  # variable values
                self.cov.values.add((cid, v, x))
        return i

    def encode_flat(self, flat: Flat) -> State:
        """The core's state for an interpreter flat state (canonicalised)."""
        out: list[int] = [flat[0]]
        for ai in range(self.naxes):
            start = self.block_start[ai]
            out.append(self.part_id(ai, flat[start]))
            for k in range(1, self.block_len[ai]):
                out.append(self.tag_id(flat[start + k]))
        if self.nextra:
            out.extend(self.extra.id(x) for x in flat[self.axis_end:])
        return self.canonical(out)

    def decode(self, state: Sequence[int]) -> Flat:
        """The interpreter's flat state for a state of the core."""
        out: list[object] = [state[0]]
        for ai in range(self.naxes):
            start = self.block_start[ai]
            out.append(self.parts.values[state[start]])
            for k in range(1, self.block_len[ai]):
                out.append(self.tags.values[state[start + k]])
        if self.nextra:
            out.extend(self.extra.values[i] for i in state[self.axis_end:])
        return tuple(out)

    def _alphabet(self, ai: int) -> list[int]:
        """Choice numbers of axis ``ai``'s own inputs, in a fixed order."""
        out: list[int] = []
        for ti in self.tis[ai]:
            out.append(self.drops[ti])
            out.extend(c for c, _k in self.raises[ti])
        out.extend(c for c, a, _e in self.events if a == ai)
        return out

    def _canonical_function(self) -> Callable[[list[int]], State]:
        """The canonicalisation for this layout: nothing to do without symmetry, a plain
        sort when the axes are one group of one-slot blocks, else :meth:`canonical`."""
        groups = self.symmetric_groups
        if not groups:
            return tuple
        if (len(groups) == 1 and len(groups[0]) == self.naxes and self.block_len[groups[0][0]] == 1):
            def one_group(vec: list[int]) -> State:
                return (vec[0], *sorted(vec[1:]))
            return one_group
        return self.canonical

    def canonical(self, vec: list[int]) -> State:
        """Sort the blocks of each group of interchangeable axes (``vec`` is not changed)."""
        vec = list(vec)
        for group in self.symmetric_groups:
            bl = self.block_len[group[0]]
            if bl == 1:
                pos = [self.block_start[a] for a in group]
                vals = sorted(vec[p] for p in pos)
                for p, v in zip(pos, vals):
                    vec[p] = v
            else:
                blocks = sorted(tuple(vec[self.block_start[a]:self.block_start[a] + bl]) for a in group)
                for a, blk in zip(group, blocks):
                    s = self.block_start[a]
                    vec[s:s + bl] = blk
        return tuple(vec)

    # ------------------------------------------------------------------ initial states

    def initial_states(self) -> list[tuple[State, tuple[Property, ...], tuple[Property, ...]]]:
        """(state, violated, reached) per configuration assignment, in assignment order."""
        out = []
        for assignment in self.model.assignments:
            flat, bad, good = self.model.initial(assignment)
            out.append((self.encode_flat(flat), tuple(bad), tuple(good)))
        return out

    # ------------------------------------------------------------------ loading (cold path)

    def _load_core(self, ai: int, core: int) -> Any:
        axis = self.model.axes[ai]
        axis.restore(self.cores.values[core])
        return axis

    def _load_tag(self, ti: int, tid: int) -> Any:
        s = self.model.slots[ti]
        tag = s.tag
        values, rung, ops, mon = self.tags.values[tid]
        tag.values.update(zip(s.fields, values))
        tag.rung = rung
        tag.operands.update(zip(s.op_names, ops))
        self.model.monitor_values[ti] = mon
        return tag

    def _read_tag(self, ti: int) -> int:
        s = self.model.slots[ti]
        tag = s.tag
        return self.tag_id((tuple(tag.values.values()), tag.rung, tuple(tag.operands.values()),
                            self.model.monitor_values[ti]))

    def _read_core(self, ai: int) -> int:
        return self.cores.id(self.model.axes[ai].snapshot())

    def _begin(self, ai: int) -> None:
        """Clear the fired-transition and trace records before a piece runs."""
        self.model.fired[ai].clear()
        self.model.trace.clear()
        self.system.trace = self.model.trace

    def _facts(self, ai: int) -> None:
        """Record the coverage facts of the piece that just ran, each credited to the
        step being computed (:attr:`where`) if no earlier step showed it."""
        cov = self.cov
        first = cov.first
        where = self.where
        cid = self.chart_of[ai]
        for t in self.model.fired[ai]:
            cov.fired.add((cid, t))
            first.setdefault(("transition", cid, t), where)
        for rec in self.model.trace:
            if type(rec) is Executed:
                mnemonic = self.system.tags[rec.tag].instruction.id
                cov.executed.add((mnemonic, rec.axis_state))
                first.setdefault(("cell", mnemonic, rec.axis_state), where)
            elif type(rec) is Errored:
                mnemonic = self.system.tags[rec.tag].instruction.id
                cov.errors.add((mnemonic, rec.err, rec.exerr))
                cov.checks.add((mnemonic, rec.check))
                first.setdefault(("error", mnemonic, rec.err, rec.exerr), where)
                first.setdefault(("check", mnemonic, rec.check), where)
            elif type(rec) is Done:
                pass
        self.system.trace = None

    # ------------------------------------------------------------------ projections of axis cores

    def projector(self, ai: int, names: Sequence[str]) -> Callable[[int], tuple[object, ...]]:
        """A function of an axis core's number giving the values of ``names``
        (``axis.X`` names as :meth:`checker.compile.FastAxis.expression_env` writes
        them; other names are ignored) read straight from the core's snapshot, so that
        a piece reading only those names is memoised by them rather than by the core.
        A name the snapshot does not hold falls back to loading the core."""
        axis = self.model.axes[ai]
        c = axis.c
        chart = axis.chart
        variables = list(c.variables)
        getters: list[tuple[int, int]] = []  # (kind, index): 0 variable, 1 leaf id, 2 leaf value, 3 configuration
        slow = False
        for n in sorted({n for n in names if n.startswith("axis.")}):
            x = n[5:]
            if x == "state":
                getters.append((1, 0))
            elif x == "active":
                getters.append((3, 0))
            elif x == "chart":
                continue  # the same for every core of the axis
            elif x == chart.state_attribute:
                getters.append((2, 0))
            elif x in variables:
                getters.append((0, variables.index(x)))
            else:
                slow = True
        cores = self.cores.values
        if slow:
            allnames = sorted({n for n in names if n.startswith("axis.")})

            def load(core: int) -> tuple[object, ...]:
                env = self._load_core(ai, core).expression_env()
                return tuple(env.get(n) for n in allnames)
            return load
        leaf = c.leaf

        def project(core: int) -> tuple[object, ...]:
            snap = cores[core]
            out: list[object] = []
            for kind, i in getters:
                if kind == 0:
                    out.append(snap[1][i])
                elif kind == 1:
                    out.append(leaf(snap[0]).id)
                elif kind == 2:
                    out.append(leaf(snap[0]).value)
                else:
                    out.append(snap[0])
            return tuple(out)
        return project

    def _exec_view(self, ti: int, ai: int, core: int) -> tuple[object, ...]:
        """What tag ``ti``'s execution reads of its axis core: the ``execute`` checks'
        names and the leaf state (the instruction x state cell)."""
        f = self._exec_proj[ti]
        if f is None:
            ins = self.model.slots[ti].tag.instruction
            names = {"axis.state"}
            for ch in ins.checks:
                if ch.stage is ir.Stage.EXECUTE:
                    names |= ch.fails_when.names
            f = self._exec_proj[ti] = self.projector(ai, sorted(names))
        return f(core)

    def _finish_view(self, ti: int, ai: int, core: int) -> tuple[object, ...]:
        """What finishing tag ``ti`` reads of its axis core: the completion condition's
        and the aborts' names."""
        f = self._finish_proj[ti]
        if f is None:
            ins = self.model.slots[ti].tag.instruction
            names: set[str] = set()
            if ins.done_when is not None:
                names |= ins.done_when.names
            for ab in ins.aborts:
                names |= ab.fails_when.names
            if ins.process is not None:
                # finishing a tag whose process runs reads its completion and end conditions
                for e in (ins.process.complete_when, ins.process.ends_when):
                    if e is not None:
                        names |= e.names
            f = self._finish_proj[ti] = self.projector(ai, sorted(names))
        return f(core)

    # ------------------------------------------------------------------ pieces (cold path)

    def live0(self, ti: int, tid: int) -> bool:
        """Live without counting the queue: rung high, pending, or a rise would not execute."""
        memo = self._live0[ti]
        v = memo.get(tid)
        if v is None:
            s = self.model.slots[ti]
            values, rung, _ops, _mon = self.tags.values[tid]
            vals = dict(zip(s.fields, values))
            v = bool(rung or vals.get("pending") or (s.rise_guard is not None and not s.rise_guard(vals)))
            memo[tid] = v
        return v

    def piece_raise(self, ti: int, tid: int, k: int) -> int:
        s = self.model.slots[ti]
        values, _rung, ops, mon = self.tags.values[tid]
        new_ops = dict(zip(s.op_names, ops))
        new_ops.update(zip((n for n, _v in self.model.raise_choices[ti][k].operands), self.raise_ops[ti][k]))
        r = self.tag_id((values, True, tuple(new_ops[n] for n in s.op_names), mon))
        self._raise[ti][(tid, k)] = r
        return r

    def piece_drop(self, ti: int, tid: int) -> int:
        values, _rung, ops, mon = self.tags.values[tid]
        r = self.tag_id((values, False, ops, mon))
        self._drop[ti][tid] = r
        return r

    def piece_row(self, ti: int, tid: int, cond: int) -> tuple[int, bool]:
        """The row's actions (without the execution); whether the row executes."""
        tag = self._load_tag(ti, tid)
        row = tag.instruction.table.row(_CONDITIONS[cond])
        executes = False
        if row is not None and (row.guard is None or row.guard(tag.values)):
            tag.run(row.actions)
            executes = row.execute
        r = (self._read_tag(ti), executes)
        self._rows[ti][tid * 3 + cond] = r
        return r

    def piece_exec(self, ti: int, ai: int, tid: int, core: int) -> tuple[int, bool]:
        """The instruction executes: checks of stage execute; (tag, accepted).  Cores
        that look the same to the checks share the result (and its coverage facts)."""
        vkey = (tid, self._exec_view(ti, ai, core))
        r = self._exec_by_view[ti].get(vkey)
        if r is not None:
            self._exec[ti][(tid, core)] = r
            return r
        self._load_core(ai, core)
        tag = self._load_tag(ti, tid)
        system = self.system
        system.queue = []
        self._begin(ai)
        system._execute(tag)
        self._facts(ai)
        accepted = tag.name in system.queue
        system.queue = []
        r = (self._read_tag(ti), accepted)
        self._exec[ti][(tid, core)] = r
        self._exec_by_view[ti][vkey] = r
        return r

    def piece_finish(self, ti: int, ai: int, tid: int, core: int) -> int:
        """A pending instruction is finished: DN, ER by an abort, or still pending.
        Cores that look the same to its completion and aborts share the result."""
        vkey = (tid, self._finish_view(ti, ai, core))
        r = self._finish_by_view[ti].get(vkey)
        if r is not None:
            self._finish[ti][(tid, core)] = r
            return r
        self._load_core(ai, core)
        tag = self._load_tag(ti, tid)
        self._begin(ai)
        self.system._finish(tag)
        self._facts(ai)
        r = self._read_tag(ti)
        self._finish[ti][(tid, core)] = r
        self._finish_by_view[ti][vkey] = r
        return r

    def piece_deliver(self, ti: int, ai: int, tid: int, core: int) -> tuple[int, int]:
        axis = self._load_core(ai, core)
        tag = self._load_tag(ti, tid)
        self._begin(ai)
        self.system._deliver(axis, tag)
        self._facts(ai)
        r = (self._read_tag(ti), self._read_core(ai))
        self._deliver[ti][(tid, core)] = r
        return r

    def piece_tick(self, ai: int, core: int) -> int:
        axis = self._load_core(ai, core)
        self._begin(ai)
        axis.send("tick")
        self._facts(ai)
        r = self._read_core(ai)
        self._tick[ai][core] = r
        return r

    def piece_event(self, ai: int, core: int, event: str) -> int:
        axis = self._load_core(ai, core)
        self._begin(ai)
        self.system._environment(axis, event)
        self._facts(ai)
        r = self._read_core(ai)
        self._event[ai][(core, event)] = r
        return r

    def view(self, ti: int, ai: int, core: int) -> int:
        """The number of what tag ``ti``'s properties read of its axis (the ``axis.X``
        names) in axis core ``core``: cores that look the same to them share it."""
        f = self._view_proj[ti]
        if f is None:
            f = self._view_proj[ti] = self.projector(ai, self._axis_names[ti])
        seen = f(core)
        views = self._views[ti]
        v = views.index.get(seen)
        if v is None:
            v = views.id(seen)
            self._view_core[ti].append(core)
        self._view[ti][core] = v
        return v

    def piece_tag_post(self, ti: int, ai: int, tid: int, queued: bool, view: int) -> tuple[
            int, tuple[Property, ...], tuple[Property, ...]]:
        """Properties of a tag after the scan, then its abstract part."""
        model = self.model
        if view >= 0:
            self._load_core(ai, self._view_core[ti][view])
        self._load_tag(ti, tid)
        bad: list[Property] = []
        good: list[Property] = []
        model.evaluate_tag(ti, queued, {}, bad, good)
        r = (self.tag_id(model.extract_tag(ti, queued)), tuple(bad), tuple(good))
        self._tag_post[ti][(tid, queued, view)] = r
        return r

    def piece_axis_post(self, ai: int, core: int) -> tuple[int, tuple[Property, ...], tuple[Property, ...]]:
        """Properties of an axis after the scan, then its collapsed core."""
        model = self.model
        self._load_core(ai, core)
        bad: list[Property] = []
        good: list[Property] = []
        model.evaluate_axis(ai, bad, good)
        snap = self.cores.values[core]
        values = model.extract_axis_values(ai, snap[1])
        collapsed = (snap[0], values, *snap[2:])
        r = (self.cores.id(collapsed), tuple(bad), tuple(good))
        self._axis_post[ai][core] = r
        return r

    def join(self, ai: int, core: int, q: tuple[int, ...], h: tuple[str, ...]) -> int:
        key = (core, q, h)
        r = self._join[ai].get(key)
        if r is None:
            snap = self.cores.values[core]
            r = self.part_id(ai, (*snap, q, h))
            self._join[ai][key] = r
        return r

    # ------------------------------------------------------------------ the scan of one axis block

    def inert(self, ti: int, tid: int) -> bool:
        """An inert tag takes no part in a scan: rung low, nothing pending, and its
        rung-false row changes nothing and does not execute."""
        memo = self._inert[ti]
        v = memo.get(tid)
        if v is None:
            rr = self._rows[ti].get(tid * 3)
            if rr is None:
                rr = self.piece_row(ti, tid, 0)
            v = not self._rung[tid] and not self._pending[tid] and rr == (tid, False)
            memo[tid] = v
        return v

    def quiet(self, ti: int, tid: int) -> bool:
        """An inert tag whose post-scan evaluation is the identity whatever its axis does."""
        memo = self._quiet[ti]
        v = memo.get(tid)
        if v is None:
            v = False
            if not self._reads_axis[ti]:
                p = self._tag_post[ti].get((tid, False, -1))
                if p is None:
                    p = self.piece_tag_post(ti, self.model.slots[ti].axis_index, tid, False, -1)
                v = p == (tid, (), ())
            memo[tid] = v
        return v

    def context(self, ai: int, state: Sequence[int]) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """(tags that take part in a scan, inert tags whose properties must still be
        evaluated) of axis ``ai``'s block in ``state``, as local tag numbers."""
        start = self.block_start[ai] + 1
        q = self._split[state[start - 1]][1]
        active: list[int] = []
        watch: list[int] = []
        for j, ti in enumerate(self.tis[ai]):
            tid = state[start + j]
            if j in q or not self.inert(ti, tid):
                active.append(j)
            elif not self.quiet(ti, tid):
                watch.append(j)
        return tuple(active), tuple(watch)

    def _watch_post(self, ai: int, watch: tuple[int, ...], tags: list[int], core: int) -> tuple[
            tuple[int, ...], tuple[Property, ...], tuple[Property, ...]]:
        out: list[int] = []
        bad: list[Property] = []
        good: list[Property] = []
        for j in watch:
            ti = self.tis[ai][j]
            tid = tags[j]
            view = self._view[ti].get(core) if self._reads_axis[ti] else -1
            if view is None:
                view = self.view(ti, ai, core)
            p = self._tag_post[ti].get((tid, False, view))
            if p is None:
                p = self.piece_tag_post(ti, ai, tid, False, view)
            out.append(p[0])
            bad.extend(p[1])
            good.extend(p[2])
        return tuple(out), tuple(bad), tuple(good)

    def _block(self, ai: int, aid: int, tags: list[int], mode: int, kind: int, k: int, arg: object,
               active: tuple[int, ...] | None = None, watch: tuple[int, ...] = ()
               ) -> tuple[int, list[int], list[Property], list[Property]]:
        """One scan of axis ``ai``'s block: its axis part ``aid`` and tag parts ``tags``
        (changed in place), in scan mode ``mode``, with local input (``kind``, tag ``k``, ``arg``).
        Returns (axis part, tags, violated, reached).

        ``active`` lists the tags that are not inert (None: every tag) and ``watch`` the
        inert ones whose properties are evaluated; the others are left as they are
        (:meth:`context`).  A prescan pass always runs every tag.  The scan is
        :meth:`_prefix` (steps 1 to 3 up to the deliveries), then at a coarse update
        :meth:`_apply_events` and :meth:`_finish_all`, then :meth:`_post` (step 4)."""
        core, q, h, events, order, watch = self._prefix(ai, aid, tags, mode, kind, k, arg, active, watch)
        if mode == COARSE:
            core = self._apply_events(ai, core, events)
            a2, t2, bad, good, _blk = self._tail(ai, tags, core, order, watch)
            tags[:] = t2
            return a2, tags, list(bad), list(good)
        return self._post(ai, tags, core, q, h, order, watch)

    def prescan_block(self, ai: int, aid: int, tags: Sequence[int]) -> tuple[int, list[int], list[Property], list[Property]]:
        """A prescan pass of axis ``ai``'s block (axis part ``aid``, tag parts ``tags``):
        the same as :meth:`_block` in mode PRESCAN, composed per tag.  A prescan pass
        runs no coarse update and leaves the axis core alone, so each tag's part after
        it is a function of its own part, whether it is queued and the core (its prescan
        row, then its properties and abstraction), and the axis part is a function of
        the axis part; if a tag's prescan row executes, the whole block is scanned by
        :meth:`_block` (an accepted request changes the queue)."""
        core, q, h = self._split[aid]
        tis = self.tis[ai]
        memo = self._prescan_tag
        out: list[int] = []
        bad: list[Property] = []
        good: list[Property] = []
        for j, tid in enumerate(tags):
            ti = tis[j]
            key = (tid, j in q, core)
            p = memo[ti].get(key)
            if p is None:
                p = self._prescan_piece(ti, ai, tid, key[1], core)
            if not p:
                return self._block(ai, aid, list(tags), PRESCAN, NOTHING, 0, None)
            out.append(p[0])
            if p[1]:
                bad.extend(p[1])
            if p[2]:
                good.extend(p[2])
        pa = self._prescan_axis[ai].get(aid)
        if pa is None:
            ap = self._axis_post[ai].get(core)
            if ap is None:
                ap = self.piece_axis_post(ai, core)
            pa = self._prescan_axis[ai][aid] = (self.join(ai, ap[0], q, h), ap[1], ap[2])
        if pa[1]:
            bad.extend(pa[1])
        if pa[2]:
            good.extend(pa[2])
        return pa[0], out, bad, good

    def _prescan_piece(self, ti: int, ai: int, tid: int, queued: bool, core: int
                       ) -> tuple[int, tuple[Property, ...], tuple[Property, ...]] | tuple[()]:
        """Tag ``ti``'s part after a prescan pass (its prescan row, then :meth:`piece_tag_post`),
        or ``()`` when the row executes."""
        rr = self._rows[ti].get(tid * 3 + 2)
        if rr is None:
            rr = self.piece_row(ti, tid, 2)
        r: tuple[int, tuple[Property, ...], tuple[Property, ...]] | tuple[()] = ()
        if not rr[1]:
            tid2 = rr[0]
            view = -1
            if self._reads_axis[ti]:
                v = self._view[ti].get(core)
                view = v if v is not None else self.view(ti, ai, core)
            p = self._tag_post[ti].get((tid2, queued, view))
            r = p if p is not None else self.piece_tag_post(ti, ai, tid2, queued, view)
        self._prescan_tag[ti][(tid, queued, core)] = r
        return r

    def _tail(self, ai: int, mid: list[int], core: int, order: tuple[int, ...], watch: tuple[int, ...]
              ) -> tuple[int, tuple[int, ...], list[Property], list[Property], tuple[int, ...]]:
        """The end of a coarse-update scan once its events are applied: the pending
        instructions finished, then step 4 (the queue and held events are empty by
        then).  Memoised by (tag parts, tags scanned, tags watched), then by axis core:
        the scans of many states and choices end alike.  ``mid`` is not changed.
        Returns (axis part, tag parts, violated, reached, the block: axis part then tag parts)."""
        inner = self._tail_inner(ai, tuple(mid), order, watch)
        r = inner.get(core)
        if r is None:
            r = self._tail_compute(ai, mid, core, order, watch, inner)
        return r

    def _tail_inner(self, ai: int, mid: tuple[int, ...], order: tuple[int, ...], watch: tuple[int, ...]
                    ) -> dict[int, tuple[int, tuple[int, ...], list[Property], list[Property], tuple[int, ...]]]:
        """The memo of :meth:`_tail` for these tag parts, by axis core."""
        memo = self._tail_memo[ai]
        key = (mid, order, watch)
        inner = memo.get(key)
        if inner is None:
            if len(memo) > 300_000:  # bounded: a cache, not state
                memo.clear()
            inner = memo[key] = {}
        return inner

    def _tail_compute(self, ai: int, mid: list[int] | tuple[int, ...], core: int, order: tuple[int, ...],
                      watch: tuple[int, ...],
                      inner: dict[int, tuple[int, tuple[int, ...], list[Property], list[Property], tuple[int, ...]]]
                      ) -> tuple[int, tuple[int, ...], list[Property], list[Property], tuple[int, ...]]:
        t = list(mid)
        self._finish_all(ai, t, core, order)
        a2, t2, bad, good = self._post(ai, t, core, (), (), order, watch)
        r = (a2, tuple(t2), bad, good, (a2, *t2))
        inner[core] = r
        return r

    def _prefix(self, ai: int, aid: int, tags: list[int], mode: int, kind: int, k: int, arg: object,
                active: tuple[int, ...] | None, watch: tuple[int, ...]) -> tuple[
                    int, tuple[int, ...], tuple[str, ...], tuple[str, ...], tuple[int, ...], tuple[int, ...]]:
        """Steps 1 and 2 of a scan and, at a coarse update, step 3 up to the deliveries
        (tick, finishing, queued requests).  ``tags`` are changed in place; returns
        (axis core, queue, held events, events to apply now, tags scanned, tags watched)."""
        core, q, h = self._split[aid]
        tis = self.tis[ai]
        extra: str | None = None
        if kind >= WITH_DRIVE:
            kind -= WITH_DRIVE
            assert type(arg) is tuple  # a combined choice's argument is (base argument, drive event)
            arg, extra = arg
        if active is None or mode == PRESCAN:
            order: tuple[int, ...] = tuple(range(len(tis)))
            watch = ()
        elif kind in (RAISE, DROP):
            order = active if k in active else tuple(sorted((*active, k)))
            if k in watch:
                watch = tuple(x for x in watch if x != k)
        else:
            order = active
        if kind in (RAISE, DROP):
            tags[k] = self._rung_input(tis[k], tags[k], kind, arg)
        elif kind == EVENT:
            assert type(arg) is str  # an EVENT choice's argument is its event name
            h = (*h, arg)
        if extra is not None:
            h = (*h, extra)
        # 2. program, in program order
        q, _acc = self._step2(ai, tags, order, core, q, mode == PRESCAN)
        if mode != COARSE:
            return core, q, h, (), order, watch
        core, events = self._step3(ai, core, q, h, tags, order)
        return core, (), (), events, order, watch

    def _rung_input(self, ti: int, tid: int, kind: int, arg: object) -> int:
        """Tag ``ti``'s part ``tid`` after a RAISE (``arg``: the operand index) or a DROP
        choice of step 1."""
        if kind == RAISE:
            assert type(arg) is int  # a RAISE choice's argument is its operand index
            r = self._raise[ti].get((tid, arg))
            return r if r is not None else self.piece_raise(ti, tid, arg)
        r = self._drop[ti].get(tid)
        return r if r is not None else self.piece_drop(ti, tid)

    def _step2(self, ai: int, tags: list[int], order: tuple[int, ...], core: int, q: tuple[int, ...],
               prescan: bool) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Step 2 of a scan, the program: the rows of the tags of ``order`` in program
        order (``tags`` changed in place); (queue after it, tags whose request was accepted)."""
        tis = self.tis[ai]
        rung = self._rung
        rows = self._rows
        acc: tuple[int, ...] = ()
        for j in order:
            ti = tis[j]
            tid = tags[j]
            cond = 2 if prescan else (1 if rung[tid] else 0)
            rr = rows[ti].get(tid * 3 + cond)
            if rr is None:
                rr = self.piece_row(ti, tid, cond)
            tid, executes = rr
            if executes:
                ex = self._exec[ti].get((tid, core))
                if ex is None:
                    ex = self.piece_exec(ti, ai, tid, core)
                tid, accepted = ex
                if accepted:
                    q = (*(x for x in q if x != j), j)
                    acc = (*acc, j)
            tags[j] = tid
        return q, acc

    def _choice_coarse(self, ai: int, aid: int, tags: Sequence[int], s2: tuple[int, ...], acc: tuple[int, ...],
                       kind: int, k: int, arg: object, active: tuple[int, ...], watch: tuple[int, ...]
                       ) -> tuple[int, list[int], tuple[str, ...], tuple[int, ...], tuple[int, ...]]:
        """Steps 1 to 3 up to the deliveries of a coarse-update scan under a choice that
        is not a held environment event, the program's step reused from the base scan:
        in step 2 a tag's row is a function of its own part and the axis core, which
        step 2 leaves alone, so only tag ``k`` (the one the choice touches) is scanned
        anew.  ``tags`` are the parts before the scan, ``s2`` after the base scan's step
        2, ``acc`` the tags whose request the base scan accepted.  Returns (axis core, tag
        parts, events to apply now, tags scanned, tags watched), as :meth:`_prefix`."""
        core, q, h = self._split[aid]
        extra: str | None = None
        if kind >= WITH_DRIVE:
            kind -= WITH_DRIVE
            assert type(arg) is tuple  # a combined choice's argument is (base argument, drive event)
            arg, extra = arg
        tl = list(s2)
        if kind == EVENT:
            assert type(arg) is str  # an EVENT choice's argument is its event name
            order = active
            h = (*h, arg)
            for j in acc:
                q = (*(x for x in q if x != j), j)
        else:
            order = active if k in active else tuple(sorted((*active, k)))
            if k in watch:
                watch = tuple(x for x in watch if x != k)
            tl[k] = self._rung_input(self.tis[ai][k], tags[k], kind, arg)
            # tag k's row (as in _step2, inlined: this is the search's innermost loop)
            ti = self.tis[ai][k]
            tid = tl[k]
            cond = 1 if self._rung[tid] else 0
            rr = self._rows[ti].get(tid * 3 + cond)
            if rr is None:
                rr = self.piece_row(ti, tid, cond)
            tid, executes = rr
            acc_k = False
            if executes:
                ex = self._exec[ti].get((tid, core))
                if ex is None:
                    ex = self.piece_exec(ti, ai, tid, core)
                tid, acc_k = ex
            tl[k] = tid
            if acc:
                for j in order:
                    if (acc_k if j == k else j in acc):
                        q = (*(x for x in q if x != j), j)
            elif acc_k:
                q = (*(x for x in q if x != k), k)
        if extra is not None:
            h = (*h, extra)
        core, events = self._step3(ai, core, q, h, tl, order)
        return core, tl, events, order, watch

    def _step3(self, ai: int, core: int, q: tuple[int, ...], h: tuple[str, ...], tags: list[int],
               order: tuple[int, ...]) -> tuple[int, tuple[str, ...]]:
        """Step 3 of a coarse-update scan up to the deliveries (tick, the drive model's
        outcomes, finishing, queued requests; ``tags`` changed in place): (axis core, the
        held environment events still to apply)."""
        tis = self.tis[ai]
        pending = self._pending
        events = h
        t = self._tick[ai].get(core)
        core = t if t is not None else self.piece_tick(ai, core)
        drive_events = self._drive[ai]
        if drive_events and events:
            # the drive model's outcomes come right after the tick (System._coarse_update)
            for ev in drive_events:
                if ev in events:
                    e = self._event[ai].get((core, ev))
                    core = e if e is not None else self.piece_event(ai, core, ev)
            events = tuple(ev for ev in events if ev not in drive_events)
        finish = self._finish
        for j in order:
            tid = tags[j]
            if pending[tid] and j not in q:
                ti = tis[j]
                f = finish[ti].get((tid, core))
                tags[j] = f if f is not None else self.piece_finish(ti, ai, tid, core)
        for j in q:
            tid = tags[j]
            if pending[tid]:
                ti = tis[j]
                d = self._deliver[ti].get((tid, core))
                if d is None:
                    d = self.piece_deliver(ti, ai, tid, core)
                tags[j], core = d
        return core, events

    def _apply_events(self, ai: int, core: int, events: tuple[str, ...]) -> int:
        """Step 3, the held environment events applied in order to axis core ``core``."""
        memo = self._event[ai]
        for ev in events:
            e = memo.get((core, ev))
            core = e if e is not None else self.piece_event(ai, core, ev)
        return core

    def _finish_all(self, ai: int, tags: list[int], core: int, order: tuple[int, ...]) -> None:
        """The end of step 3: every pending instruction of ``order`` finished, in program order."""
        pending = self._pending
        finish = self._finish
        tis = self.tis[ai]
        for j in order:
            tid = tags[j]
            if pending[tid]:
                ti = tis[j]
                f = finish[ti].get((tid, core))
                tags[j] = f if f is not None else self.piece_finish(ti, ai, tid, core)

    def _post(self, ai: int, tags: list[int], core: int, q: tuple[int, ...], h: tuple[str, ...],
              order: tuple[int, ...], watch: tuple[int, ...]) -> tuple[int, list[int], list[Property], list[Property]]:
        """Step 4: properties on the concrete parts, then the abstractions; (axis part,
        tags (changed in place), violated, reached)."""
        tis = self.tis[ai]
        bad: list[Property] = []
        good: list[Property] = []
        if watch:
            # inert tags are not touched by the scan: their post-scan evaluation is one
            # look-up for all of them, keyed by their parts and the axis core
            wkey = (tuple([tags[j] for j in watch]), core)
            wr = self._watch_memo[ai].get(wkey)
            if wr is None:
                wr = self._watch_post(ai, watch, tags, core)
                self._watch_memo[ai][wkey] = wr
            for j, t in zip(watch, wr[0]):
                tags[j] = t
            if wr[1]:
                bad.extend(wr[1])
            if wr[2]:
                good.extend(wr[2])
        reads = self._reads_axis
        posts = self._tag_post
        views = self._view
        for j in order:
            ti = tis[j]
            tid = tags[j]
            if reads[ti]:
                view = views[ti].get(core)
                if view is None:
                    view = self.view(ti, ai, core)
            else:
                view = -1
            key = (tid, j in q, view)
            p = posts[ti].get(key)
            if p is None:
                p = self.piece_tag_post(ti, ai, tid, key[1], view)
            tags[j] = p[0]
            if p[1]:
                bad.extend(p[1])
            if p[2]:
                good.extend(p[2])
        ap = self._axis_post[ai].get(core)
        if ap is None:
            ap = self.piece_axis_post(ai, core)
        if ap[1]:
            bad.extend(ap[1])
        if ap[2]:
            good.extend(ap[2])
        key2 = (ap[0], q, h)
        aid2 = self._join[ai].get(key2)
        if aid2 is None:
            aid2 = self.join(ai, ap[0], q, h)
        return aid2, tags, bad, good

    # ------------------------------------------------------------------ successors of a state

    def local_choices(self, ai: int, state: Sequence[int]) -> list[tuple[int, int, int, object]]:
        """The choices of axis ``ai``'s block offered in ``state``: (choice, kind, local tag,
        argument), tags in program order then the axis's environment events."""
        out: list[tuple[int, int, int, object]] = []
        limit = self.max_live
        rung = self._rung
        start = self.block_start[ai]
        q = self._split[state[start]][1]
        tis = self.tis[ai]
        live_flags = None
        nlive = 0
        if limit is not None:
            live_flags = [self.live0(ti, state[start + 1 + j]) or j in q for j, ti in enumerate(tis)]
            nlive = sum(live_flags)
        combos = self.combos
        for j, ti in enumerate(tis):
            if rung[state[start + 1 + j]]:
                out.append((self.drops[ti], DROP, j, None))
                for c2, d in combos.get(self.drops[ti], ()):
                    out.append((c2, DROP + WITH_DRIVE, j, (None, d)))
            elif limit is None or nlive < limit or (live_flags is not None and live_flags[j]):
                for c, kk in self.raises[ti]:
                    out.append((c, RAISE, j, kk))
                    for c2, d in combos.get(c, ()):
                        out.append((c2, RAISE + WITH_DRIVE, j, (kk, d)))
        for c, a, ev in self.events:
            if a == ai:
                out.append((c, EVENT, 0, ev))
                for c2, d in combos.get(c, ()):
                    out.append((c2, EVENT + WITH_DRIVE, 0, (ev, d)))
        return out

    def moves(self, ai: int, state: Sequence[int], mode: int) -> tuple[
            tuple[tuple[int, ...], list[Property], list[Property]],
            list[tuple[int, tuple[int, ...], list[Property], list[Property]]]]:
        """Axis ``ai``'s block under no input, and the moves of its own choices that
        differ from that: (choice, block, violated, reached).  Memoised per block on
        systems of several axes (blocks of interchangeable axes share the table; the
        choice numbers are then mapped to axis ``ai``'s)."""
        start = self.block_start[ai]
        n = self.block_len[ai]
        key = None
        if self.use_block_memo:
            key = (state[start:start + n], mode)
            r = self._own_memo[ai].get(key)
            if r is not None:
                return r
            leader = self._leader[ai]
            if leader != ai:
                r = self._block_memo[leader].get(key)
                if r is not None:
                    remap = self._remap[ai]
                    r2 = (r[0], [(remap[c], b, x, y) for c, b, x, y in r[1]])
                    self._remember(ai, key, r2)
                    return r2
        aid = state[start]
        tags = tuple(state[start + 1:start + n])
        q = self._split[aid][1]
        ckey = (q, tags)
        cc = self._ctx_memo[ai].get(ckey)
        if cc is None:
            chs = tuple(self.local_choices(ai, state))
            esplit = len(chs)
            while esplit > 0 and chs[esplit - 1][1] == EVENT and chs[esplit - 1][3] not in self._drive[ai]:
                esplit -= 1
            firsts0 = self._drive_firsts(ai, chs)
            cc = (*self.context(ai, state), chs, firsts0, esplit, tuple(d for d, _f, _w in firsts0), {})
            self._ctx_memo[ai][ckey] = cc
        active, watch, choices, firsts, esplit, dnames, scanned = cc
        cur = self.current
        self.where = (cur, self.nothing_index)
        # the base (no input); an event choice shares its steps 1 to 3 up to the
        # deliveries (an event is only held in step 1), so those are scanned once
        mid = list(tags)
        coarse = mode == COARSE
        s2: tuple[int, ...] = ()
        acc: tuple[int, ...] = ()
        if coarse:
            core_m, q_m, h_m = self._split[aid]
            q_m, acc = self._step2(ai, mid, active, core_m, q_m, False)
            s2 = tuple(mid)
            core_m, events = self._step3(ai, core_m, q_m, h_m, mid, active)
            order, w = active, watch
        else:
            core_m, q_m, h_m, events, order, w = self._prefix(ai, aid, mid, mode, NOTHING, 0, None, active, watch)
        t2: Sequence[int]
        if coarse:
            core_b = self._apply_events(ai, core_m, events) if events else core_m
            mid_t = tuple(mid)
            inner = self._tail_inner(ai, mid_t, order, w)
            rt = inner.get(core_b)
            if rt is None:
                rt = self._tail_compute(ai, mid_t, core_b, order, w, inner)
            base_blk = rt[4]
            bad = rt[2]
            good = rt[3]
        else:
            core_b = core_m
            a2, t2, bad, good = self._post(ai, list(mid), core_b, q_m, h_m, order, w)
            base_blk = (a2, *t2)
        base = (base_blk, bad, good)
        out = []
        evmemo = self._event[ai]
        drive_events = self._drive[ai]
        # the choices scanned one by one: at a coarse update, those before the trailing
        # environment events, less the ones whose drive event leaves the ticked core as
        # it is (their scan is their base choice's, or the nothing choice's, which comes
        # earlier); the drive events' idleness is a function of the axis part, memoised
        mask = -1
        if coarse:
            mask = 0
            if firsts:
                ik = (aid, dnames)
                im = self._idle_memo[ai].get(ik)
                mask = im if im is not None else self._idle_mask(ai, aid, firsts, cur, ik)
        todo = scanned.get(mask)
        if todo is None:
            todo = self._scanned(choices, esplit, firsts, mask)
            scanned[mask] = todo
        # the environment events at the end of the choices: at a coarse update their
        # moves are a function of the base scan up to the deliveries, memoised by it
        ekey: tuple[object, ...] | None = None
        hit: EventMoves | None = None
        suffix: tuple[tuple[int, int, int, object], ...] = ()
        if coarse and esplit < len(choices):
            ekey = (core_m, mid_t, events, order, w)
            hit = self._event_moves[ai].get(ekey)
            if hit is None:
                suffix = choices[esplit:]
        tail_memo = self._tail_memo[ai]
        for c, kind, k, arg in todo:
            self.where = (cur, c)
            # a drive event acts right after the tick, before the deliveries: no shortcut
            if kind == EVENT and arg not in drive_events:
                assert type(arg) is str  # an EVENT choice's argument is its event name
                if coarse:
                    if events:
                        core_e = self._apply_events(ai, core_m, (*events, arg))
                    else:
                        e = evmemo.get((core_m, arg))
                        core_e = e if e is not None else self.piece_event(ai, core_m, arg)
                    if core_e == core_b:
                        continue  # the same scan as the base's
                    te = inner.get(core_e)
                    if te is None:
                        te = self._tail_compute(ai, mid_t, core_e, order, w, inner)
                    if te[4] == base_blk and not te[2] and not te[3]:
                        continue
                    out.append((c, te[4], te[2], te[3]))
                    continue
                else:
                    # the event is held: only the axis part's held events differ
                    h_e = (*h_m, arg)
                    ap_core = self._axis_post[ai][core_b][0]
                    a2 = self._join[ai].get((ap_core, q_m, h_e)) or self.join(ai, ap_core, q_m, h_e)
                    out.append((c, (a2, *base_blk[1:]), base[1], base[2]))
                    continue
            elif coarse:
                # the end of the scan comes from the tail memo with its block
                mc, tl, evs, order_c, watch_c = self._choice_coarse(ai, aid, tags, s2, acc, kind, k, arg, active, watch)
                if evs:
                    mc = self._apply_events(ai, mc, evs)
                tkey = (tuple(tl), order_c, watch_c)
                tinner = tail_memo.get(tkey)
                if tinner is None:
                    tinner = self._tail_inner(ai, tkey[0], order_c, watch_c)
                te = tinner.get(mc)
                if te is None:
                    te = self._tail_compute(ai, tkey[0], mc, order_c, watch_c, tinner)
                if te[4] == base_blk and not te[2] and not te[3]:
                    continue
                out.append((c, te[4], te[2], te[3]))
                continue
            else:
                a2, t2, bad, good = self._block(ai, aid, list(tags), mode, kind, k, arg, active, watch)
            blk = (a2, *t2)
            if blk == base_blk and not bad and not good:
                continue
            out.append((c, blk, bad, good))
        if ekey is not None:
            if hit is None:
                n_out = len(out)
                # the events that change the core, and the core each gives: a function
                # of the core before them and the events held (memoised by those)
                ck = (core_m, events)
                moved = self._suffix_cores[ai].get(ck)
                if moved is None:
                    moved = self._event_cores(ai, core_m, events, core_b, suffix, cur, ck)
                for c, core_e in moved:
                    te = inner.get(core_e)
                    if te is None:
                        self.where = (cur, c)
                        te = self._tail_compute(ai, mid_t, core_e, order, w, inner)
                    if te[4] == base_blk and not te[2] and not te[3]:
                        continue
                    out.append((c, te[4], te[2], te[3]))
                memo = self._event_moves[ai]
                if len(memo) > 200_000:  # bounded: a cache, not state
                    memo.clear()
                memo[ekey] = tuple(out[n_out:])
            else:
                out.extend(hit)
        if key is not None:
            self._remember(ai, key, (base, out))
            leader = self._leader[ai]
            if leader != ai:
                back = self._remap_back[ai]
                self._block_memo[leader][key] = (base, [(back[c], b, x, y) for c, b, x, y in out])
            else:
                self._block_memo[ai][key] = (base, out)
        return base, out

    def _event_cores(self, ai: int, core: int, events: tuple[str, ...], core_b: int,
                     suffix: tuple[Choice, ...], cur: int, key: tuple[int, tuple[str, ...]]
                     ) -> tuple[tuple[int, int], ...]:
        """(choice, axis core) for each trailing environment event of ``suffix`` that,
        applied after the held ``events`` to axis core ``core``, gives another core than
        the held events alone (``core_b``); memoised by ``key``, (core, events).  The
        trailing environment events are the axis's own, the same in every context."""
        out: list[tuple[int, int]] = []
        evmemo = self._event[ai]
        for c, _kind, _j, arg in suffix:
            self.where = (cur, c)
            assert type(arg) is str  # an EVENT choice's argument is its event name
            if events:
                core_e = self._apply_events(ai, core, (*events, arg))
            else:
                e = evmemo.get((core, arg))
                core_e = e if e is not None else self.piece_event(ai, core, arg)
            if core_e != core_b:
                out.append((c, core_e))
        memo = self._suffix_cores[ai]
        if len(memo) > 300_000:  # bounded: a cache, not state
            memo.clear()
        r = memo[key] = tuple(out)
        return r

    def _drive_core(self, ai: int, core: int, events: tuple[str, ...]) -> int:
        """The drive events among ``events`` applied to the ticked core ``core``, in the
        order the scan applies them (as :meth:`_prefix` does)."""
        memo = self._event[ai]
        for ev in self._drive[ai]:
            if ev in events:
                e = memo.get((core, ev))
                core = e if e is not None else self.piece_event(ai, core, ev)
        return core

    def _drive_firsts(self, ai: int, choices: tuple[tuple[int, int, int, object], ...]
                      ) -> tuple[tuple[str, int, frozenset[int]], ...]:
        """(drive event, the first of ``choices`` that gives it, every choice that gives
        it) for each drive event offered."""
        out: list[tuple[str, int, frozenset[int]]] = []
        for d in self._drive[ai]:
            with_d = [c for c, kind, _k, arg in choices
                      if (kind >= WITH_DRIVE and cast("tuple[object, str]", arg)[1] == d) or (kind == EVENT and arg == d)]
            if with_d:
                out.append((d, with_d[0], frozenset(with_d)))
        return tuple(out)

    def _idle_mask(self, ai: int, aid: int, firsts: tuple[tuple[str, int, frozenset[int]], ...], cur: int,
                   key: tuple[int, tuple[str, ...]]) -> int:
        """Which of the drive events of ``firsts`` are idle in a coarse-update scan of axis
        part ``aid`` (bit ``i`` for ``firsts[i]``; see :meth:`_idle_drive`), memoised by
        ``key``, (axis part, drive events offered)."""
        idle = self._idle_drive(ai, aid, firsts, cur)
        mask = 0
        for i, (_d, _first, with_d) in enumerate(firsts):
            if with_d <= idle:
                mask |= 1 << i
        memo = self._idle_memo[ai]
        if len(memo) > 300_000:  # bounded: a cache, not state
            memo.clear()
        memo[key] = mask
        return mask

    @staticmethod
    def _scanned(choices: tuple[Choice, ...], esplit: int, firsts: tuple[tuple[str, int, frozenset[int]], ...],
                 mask: int) -> tuple[Choice, ...]:
        """The choices :meth:`moves` scans one by one: all of them outside a coarse update
        (``mask`` -1), else those before ``esplit`` less the ones giving an idle drive
        event (bit ``i`` of ``mask`` for ``firsts[i]``)."""
        if mask < 0:
            return choices
        idle: frozenset[int] = frozenset()
        for i, (_d, _first, with_d) in enumerate(firsts):
            if mask >> i & 1:
                idle = idle | with_d
        return tuple(ch for ch in choices[:esplit] if ch[0] not in idle)

    def _idle_drive(self, ai: int, aid: int, firsts: tuple[tuple[str, int, frozenset[int]], ...], cur: int
                    ) -> frozenset[int]:
        """The choices whose drive event changes nothing in this coarse-update scan of
        axis part ``aid``: applied after the tick (with the held ones), the event leaves
        the core as the held ones alone leave it, so each such choice scans as its base
        choice (or as the nothing choice), which comes earlier.  ``firsts`` pairs each
        offered drive event with the first choice that gives it and all that give it;
        pieces computed here are credited to that first choice, as its scan would."""
        core, _q, h = self._split[aid]
        t = self._tick[ai].get(core)
        if t is None:
            t = self.piece_tick(ai, core)
        base = self._drive_core(ai, t, h)
        out: frozenset[int] = frozenset()
        for d, first, with_d in firsts:
            if d not in h:
                self.where = (cur, first)
                if self._drive_core(ai, t, (*h, d)) != base:
                    continue
            out = out | with_d
        return out

    def _remember(self, ai: int, key: tuple[object, ...], value: tuple[BlockStep, Moves]) -> None:
        memo = self._own_memo[ai]
        if len(memo) > 300_000:  # bounded: a block memo is a cache, not state
            memo.clear()
            self._block_memo[self._leader[ai]].clear()
        memo[key] = value

    def _flat_successors(self, state: State, mode: int, nphase: int
                         ) -> list[tuple[int, State, Sequence[Property], Sequence[Property]]]:
        """:meth:`successors` when every axis is one interchangeable one-slot block: the
        state's axis parts are sorted, so equal parts are neighbours and only the first of
        each run is expanded, and a successor is the phase then the parts sorted."""
        own = self._own_memo
        rest: list[int] = []
        base_bad: list[Property] = []
        base_good: list[Property] = []
        expand: list[tuple[int, Moves]] = []
        prev = -1
        for ai in range(self.naxes):
            v = state[ai + 1]
            r = own[ai].get(((v,), mode))
            if r is None:
                r = self.moves(ai, state, mode)
            (blk, bad, good), mv = r
            rest.append(blk[0])
            if bad:
                base_bad.extend(bad)
            if good:
                base_good.extend(good)
            if mv and v != prev:
                expand.append((ai, mv))
            prev = v
        out: list[tuple[int, State, Sequence[Property], Sequence[Property]]] = [
            (self.nothing_index, (nphase, *sorted(rest)), base_bad, base_good)]
        for ai, mv in expand:
            for c, blk, bad, good in mv:
                v2 = rest.copy()
                v2[ai] = blk[0]
                v2.sort()
                out.append((c, (nphase, *v2), bad, good))
        return out

    def successors(self, state: State) -> list[tuple[int, State, Sequence[Property], Sequence[Property]]]:
        """(choice index, canonical successor, violated, reached) for the enabled choices.

        Choices whose successor is the same as the nothing choice's (and that violate
        or reach nothing) are left out: they add no state and no transition.  On systems
        of several axes the properties decided in the blocks a choice does not touch are
        reported with the nothing choice only (same parent, same depth)."""
        couple = self._couple
        if couple is None:
            return self._coupled_successors(state)
        phase = state[0]
        mode = COARSE if phase % self.spu == 0 else NORMAL
        nphase = (phase + 1) % self.spu
        naxes = self.naxes
        if self._single:
            # one axis, no symmetry: a successor is the phase followed by the block
            (blk, b0, g0), mv = self.moves(0, state, mode)
            head = (nphase,)
            out1: list[tuple[int, State, Sequence[Property], Sequence[Property]]] = [
                (self.nothing_index, head + blk, b0, g0)]
            for c, b, x, y in mv:
                out1.append((c, head + b, x, y))
            if self.has_prescan and not self._busy[state[1]]:
                self.where = (self.current, self.prescan_index)
                n = self.block_len[0]
                a2, t2, pb, pg = self.prescan_block(0, state[1], state[2:1 + n])
                out1.append((self.prescan_index, (nphase, a2, *t2), pb, pg))
            return out1
        if self._flat:
            return self._flat_successors(state, mode, nphase)
        busy = False
        vec = [nphase]
        base_bad: list[Property] = []
        base_good: list[Property] = []
        all_moves = []
        own = self._own_memo
        starts = self.block_start
        lens = self.block_len
        group_of = self._group_of
        expanded: set[tuple[int, object]] = set()
        for ai in range(naxes):
            start = starts[ai]
            n = lens[ai]
            key = (state[start:start + n], mode)
            if couple and ai in couple:
                self._bind_master(ai, state)
            r = own[ai].get(key)
            if r is None:
                r = self.moves(ai, state, mode)
            (blk, bad, good), mv = r
            vec.extend(blk)
            if bad:
                base_bad.extend(bad)
            if good:
                base_good.extend(good)
            if mv:
                g = group_of[ai]
                if g >= 0:
                    # interchangeable axes in equal blocks have the same moves, up to the
                    # permutation that canonicalisation undoes: expand one of them
                    gk = (g, key)
                    if gk in expanded:
                        mv = []
                    else:
                        expanded.add(gk)
            all_moves.append(mv)
            if not busy and self._busy[state[start]]:
                busy = True
        canonical = self.canonical_fast
        out: list[tuple[int, State, Sequence[Property], Sequence[Property]]] = [
            (self.nothing_index, canonical(vec), base_bad, base_good)]
        for ai, mv in enumerate(all_moves):
            if not mv:
                continue
            start = starts[ai]
            if lens[ai] == 1:
                for c, blk, bad, good in mv:
                    v = vec.copy()
                    v[start] = blk[0]
                    out.append((c, canonical(v), bad, good))
            else:
                end = start + lens[ai]
                for c, blk, bad, good in mv:
                    v = vec.copy()
                    v[start:end] = blk
                    out.append((c, canonical(v), bad, good))
        if self.has_prescan and not busy:
            v = [nphase]
            p_bad: list[Property] = []
            p_good: list[Property] = []
            self.where = (self.current, self.prescan_index)
            for ai in range(naxes):
                start = self.block_start[ai]
                n = self.block_len[ai]
                if couple and ai in couple:
                    self._bind_master(ai, state)
                a2, t2, pb, pg = self.prescan_block(ai, state[start], state[start + 1:start + n])
                v.append(a2)
                v.extend(t2)
                p_bad.extend(pb)
                p_good.extend(pg)
            out.append((self.prescan_index, canonical(v), p_bad, p_good))
        return out

    def _coupled_successors(self, state: State) -> list[tuple[int, State, Sequence[Property], Sequence[Property]]]:
        """:meth:`successors` of a system in which a call reads a second axis: every
        enabled choice scanned by the model's own system from the decoded state (the
        interpreter back-end's step), its successor encoded; coverage facts credited to
        (:attr:`current`, choice) as the pieces credit theirs."""
        model = self.model
        flat = self.decode(state)
        cov = self.cov
        first = cov.first
        out: list[tuple[int, State, Sequence[Property], Sequence[Property]]] = []
        model.load(flat)
        for n, ch in enumerate(model.enabled()):
            if n:
                model.load(flat)
            succ, bad, good, facts = model.step(ch)
            where = (self.current, ch.index)
            for c, t in facts.fired:
                cov.fired.add((c, t))
                first.setdefault(("transition", c, t), where)
            for m, st in facts.executed:
                cov.executed.add((m, st))
                first.setdefault(("cell", m, st), where)
            for m, e, x in facts.errors:
                cov.errors.add((m, e, x))
                first.setdefault(("error", m, e, x), where)
            for m, c in facts.checks:
                cov.checks.add((m, c))
                first.setdefault(("check", m, c), where)
            out.append((ch.index, self.encode_flat(succ), bad, good))
        return out

    #: the memo tables of a tag's pieces that read its master axis (per tag, swapped)
    _MASTER_TAG_TABLES = ("_exec", "_exec_by_view", "_finish", "_finish_by_view", "_deliver", "_prescan_tag")
    #: the memo tables of an axis block's scan composed of those pieces (per axis, swapped)
    _MASTER_AXIS_TABLES = ("_tail_memo", "_event_moves", "_block_memo", "_own_memo")

    def _couplings(self) -> dict[int, int] | None:
        """slave axis -> master axis when every slave's pieces can be memoised per master
        core: each slave has one master, listed after it (so that at the slave's delivery
        the coarse update has not reached the master yet), no axes are interchangeable,
        and no completion condition, abort or process condition of a slave's call reads
        the master (the last finishing of a scan comes after the master's update)."""
        model = self.model
        if self.symmetric_groups:
            return None
        index = {name: i for i, (name, _g) in enumerate(model.axis_defs)}
        out: dict[int, int] = {}
        for s in model.slots:
            master = s.tag.master
            if master is None:
                continue
            ai, mi = s.axis_index, index[master]
            if mi <= ai or out.setdefault(ai, mi) != mi:
                return None
            ins = s.tag.instruction
            conds = [c.fails_when for c in ins.aborts] + [e for e in (ins.done_when,) if e is not None]
            if ins.process is not None:
                conds += [e for e in (ins.process.complete_when, ins.process.ends_when) if e is not None]
            if any(n.startswith("master.") for e in conds for n in e.names):
                return None
        return out

    def _bind_master(self, ai: int, state: Sequence[int]) -> None:
        """Make slave axis ``ai``'s memo tables those of its master's core in ``state``,
        and load the master's axis with that core (what the slave's pieces read)."""
        assert self._couple is not None
        mi = self._couple[ai]
        mcore = self._split[state[self.block_start[mi]]][0]
        self._load_core(mi, mcore)
        if self._bound.get(ai) == mcore:
            return
        tis = self.tis[ai]
        bundle = self._bundles.get((ai, mcore))
        if bundle is None:
            bundle = ([{} for _ in self._MASTER_TAG_TABLES for _t in tis], [{} for _ in self._MASTER_AXIS_TABLES])
            self._bundles[(ai, mcore)] = bundle
        per_tag, per_axis = bundle
        k = 0
        for name in self._MASTER_TAG_TABLES:
            tables = getattr(self, name)
            for ti in tis:
                tables[ti] = per_tag[k]
                k += 1
        for name, table in zip(self._MASTER_AXIS_TABLES, per_axis):
            getattr(self, name)[ai] = table
        self._bound[ai] = mcore
