"""The transition system the search explores: states as flat tuples, inputs as choices, one scan per step.

Pipeline position: IR + :mod:`checker.system` + :mod:`checker.properties` -> **checker.model**
-> :mod:`checker.search`.

A :class:`Model` owns one :class:`statecharts.scan.System` whose axes are
:class:`checker.compile.FastAxis` interpreters.  A step is: :meth:`Model.load` a state,
run :meth:`System.advance` with the inputs of one :class:`Choice`, evaluate the
properties on the concrete successor, and :meth:`Model.extract` the successor's
abstract state.  The scan rules are therefore exactly the engine's (one module).

The abstract state is a flat tuple: the phase of the coarse-update clock, then one block
per axis -- its configuration, its chart variables, its queued requests and held
environment events, and for each of its tags the MOTION_INSTRUCTION members, the rung,
the operands and the response monitors.  Blocks of interchangeable axes have the same
layout, which lets the search canonicalise states by sorting them (symmetry reduction).

The abstractions (``docs/checker.md``; each is exact for what properties and control
can observe, and ``tests/test_checker_soundness.py`` checks that every engine run maps
onto a path of this model):

* program: one input change per scan (:class:`Choice`): raise one tag's rung with one
  choice of operand values, drop one tag's rung, one environment event on one axis, a
  prescan pass, or nothing; optionally at most ``max_live_calls`` calls live per axis;
* collapse: chart variables no guard, check, completion condition, abort, request or
  property depends on (the cone of influence, computed here) are left out of the state;
* dead operands: the operands of a tag whose rung is low and that is neither pending
  nor queued are reset to their defaults (the next execution needs a rise, and a rise
  overwrites them; a rung held through a prescan re-executes with the old ones);
* idle tags retire: a tag whose rung is low, that is neither pending nor queued and
  whose next rise executes is stored with its initial values.  This is verified per
  execution table by enumeration (:func:`retirement_check`); properties of a tag are
  checked over each call's lifetime, from the rise until the tag is idle again.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from checker.compile import FastAxis
from checker.properties import Property
from checker.system import SystemDef, initial_assignments, operand_choices
from statecharts import ir
from statecharts.diagnostics import Diagnostic
from statecharts.expr import Expr
from statecharts.scan import Done, EnvironmentEvent, Errored, Executed, ProcessEnded, ScanInputs, System, TagInstance

#: An abstract state: the clock phase, then axis and tag parts of several shapes (see
#: :meth:`Model.extract`).
Flat = tuple[Any, ...]


@dataclass(frozen=True, slots=True)
class Choice:
    """One input change for one scan (the most general program's alphabet)."""

    index: int
    kind: str  # "raise" | "drop" | "event" | "prescan" | "nothing" | "input" (an add-on input, rung down)
    tag: str | None
    axis: str | None
    event: str | None
    operands: tuple[tuple[str, object], ...]
    inputs: ScanInputs = field(compare=False, repr=False)
    #: a drive event of the axis (a move reaching its target...) in the same scan as
    #: this raise, drop or environment event: the drive model's outcome is not an input
    #: a program chooses, so it may come together with one (docs/motion.md)
    drive: str | None = None

    def label(self) -> str:
        if self.kind == "raise":
            ops = ", ".join(f"{k}={v}" for k, v in self.operands)
            text = f"{self.tag} rung up" + (f" ({ops})" if ops else "")
        elif self.kind == "drop":
            text = f"{self.tag} rung down"
        elif self.kind == "event":
            text = f"{self.event} on {self.axis}"
        elif self.kind == "input":
            text = ", ".join(f"{self.tag}.{k} = {v!r}" for k, v in self.operands)
        else:
            text = "prescan" if self.kind == "prescan" else "scan"
        return text + (f" + {self.drive}" if self.drive else "")


@dataclass(frozen=True, slots=True)
class StepFacts:
    """What one step did, for coverage: transitions fired, calls executed, results."""

    fired: tuple[tuple[str, str], ...]  # (chart, transition id)
    executed: tuple[tuple[str, str], ...]  # (instruction, axis leaf state)
    errors: tuple[tuple[str, int, int], ...]  # (instruction, ERR, EXERR)
    checks: tuple[tuple[str, str], ...] = ()  # (instruction, id of the check or abort that failed)


class ModelError(ValueError):
    """The system cannot be checked as defined (e.g. a collapse that would be unsound)."""

    def __init__(self, diagnostics: Sequence[Diagnostic]) -> None:
        self.diagnostics = tuple(diagnostics)
        super().__init__("\n".join(str(d) for d in diagnostics))


# --------------------------------------------------------------------------- analyses


def relevant_variables(spec: ir.Spec, chart: ir.Chart, instructions: Iterable[ir.Instruction],
                       properties: Iterable[Property], followers: Iterable[ir.Instruction] = ()) -> frozenset[str]:
    """Cone of influence: chart variables that guards, checks, completion conditions,
    aborts, request actions or properties read, closed under the actions that assign them.
    ``followers`` are the instructions called on other axes whose master-axis operand is
    bound to an axis of this chart: what they read of their master (``master.X``) counts."""
    names = {v.name for v in chart.variables}
    need: set[str] = set()

    def axis_reads(expr_names: Iterable[str]) -> set[str]:
        return {n[5:] for n in expr_names if n.startswith("axis.") and n[5:] in names}

    for ins in followers:
        exprs = [c.fails_when for c in (*ins.checks, *ins.aborts)]
        exprs += [e for e in (ins.done_when,) if e is not None]
        if ins.process is not None:
            exprs += [e for e in (ins.process.complete_when, ins.process.ends_when) if e is not None]
        if ins.request is not None:
            exprs += [a.value for a in ins.request.actions]
        for read in exprs:
            need |= {n[7:] for n in read.names if n.startswith("master.") and n[7:] in names}

    for t in chart.transitions:
        if t.guard is not None:
            need |= t.guard.names & names
    writers: list[tuple[str, frozenset[str]]] = []
    for s in chart.states:
        writers += [(a.target, a.value.names & names) for a in (*s.entry, *s.exit)]
    for t in chart.transitions:
        writers += [(a.target, a.value.names & names) for a in t.actions]
    for e in chart.events:
        writers += [(a.target, a.value.names & names) for a in e.actions]
    for ins in instructions:
        for c in (*ins.checks, *ins.aborts):
            need |= axis_reads(c.fails_when.names)
        if ins.done_when is not None:
            need |= axis_reads(ins.done_when.names)
        if ins.process is not None:
            for cond in (ins.process.complete_when, ins.process.ends_when):
                if cond is not None:
                    need |= axis_reads(cond.names)
        if ins.request is not None:
            for a in ins.request.actions:
                writers.append((a.target[5:], frozenset(axis_reads(a.value.names))))
    for p in properties:
        if p.scope == "axis" or p.kind == "cover":
            need |= p.names() & names
        need |= axis_reads(p.names())
    changed = True
    while changed:  # close under "read by an action that assigns a needed variable"
        changed = False
        for target, reads in writers:
            if target in need and not reads <= need:
                need |= reads
                changed = True
    return frozenset(need)


def _tag_field_domains(spec: ir.Spec, ins: ir.Instruction) -> list[tuple[str, tuple[object, ...]]]:
    out: list[tuple[str, tuple[object, ...]]] = []
    for m in spec.tag_type.members:
        if m.type == "BOOL":
            out.append((m.name, (False, True)))
        else:
            codes = {0, 1} | {c.err for c in (*ins.checks, *ins.aborts)} | {c.exerr for c in (*ins.checks, *ins.aborts)}
            out.append((m.name, tuple(sorted(codes))))
    for v in spec.tag_type.internal:
        out.append((v.name, tuple(v.domain) if v.domain is not None else (v.initial,)))
    return out


#: retirement_check's answers by (instruction, tag type), each kept with the two objects
#: so that an id reused by another object is a miss
_RETIREMENT: dict[tuple[int, int], tuple[ir.Instruction, object, str | None]] = {}


def retirement_check(spec: ir.Spec, ins: ir.Instruction) -> str | None:
    """None when an idle tag of ``ins`` may be stored with its initial values; else why not
    (:func:`_retirement_check`, whose answer depends on the instruction and the tag type
    only, once per process for each)."""
    key = (id(ins), id(spec.tag_type))
    hit = _RETIREMENT.get(key)
    if hit is not None and hit[0] is ins and hit[1] is spec.tag_type:
        return hit[2]
    why = _retirement_check(spec, ins)
    if len(_RETIREMENT) > 256:
        _RETIREMENT.clear()
    _RETIREMENT[key] = (ins, spec.tag_type, why)
    return why


def _retirement_check(spec: ir.Spec, ins: ir.Instruction) -> str | None:
    """None when an idle tag of ``ins`` may be stored with its initial values; else why not.

    Idle: not pending, and the rung-true row would execute.  By enumeration over the
    tag's members (BOOL both values, integers 0, 1 and the instruction's codes): from
    every idle valuation and from the initial one, the rung-false and prescan rows reach
    states that are both idle or else equal, and a rise (the rung-true row and, when it
    executes, ``on_execute``) reaches equal states.
    """
    table = ins.table
    fields = _tag_field_domains(spec, ins)
    probe = TagInstance("probe", ins, spec.tag_type, "probe")
    initial = dict(probe.values)
    rise_row = table.row("rung_true")

    def idle(vals: Mapping[str, object]) -> bool:
        if vals.get("pending"):
            return False
        return rise_row is None or rise_row.guard is None or bool(rise_row.guard(vals))

    def run_row(cond: str, vals: dict[str, object]) -> tuple[dict[str, object], bool]:
        out = dict(vals)
        row = table.row(cond)
        if row is None or (row.guard is not None and not row.guard(out)):
            return out, False
        for a in row.actions:
            a.apply(out)
        if row.execute:
            for a in table.on_execute:
                a.apply(out)
        return out, row.execute

    if not idle(initial):
        return "a fresh tag's rise would not execute"
    # the rows from the initial values, the same for every valuation
    from_initial = {cond: run_row(cond, initial) for cond in ("rung_false", "prescan", "rung_true")}
    names = tuple(n for n, _d in fields)
    for combo in itertools.product(*(d for _n, d in fields)):
        vals = dict(zip(names, combo))
        if not idle(vals):
            continue
        for cond in ("rung_false", "prescan"):
            a, ea = run_row(cond, vals)
            b, eb = from_initial[cond]
            if ea or eb:
                return f"the {cond} row executes the instruction"
            if idle(a) != idle(b) or (not idle(a) and a != b):
                return f"the {cond} row depends on the values an idle tag keeps ({sorted(vals.items())})"
        a, _ = run_row("rung_true", vals)
        b = from_initial["rung_true"][0]
        if a != b:
            return f"a rise depends on the values an idle tag keeps ({sorted(vals.items())})"
    return None


# --------------------------------------------------------------------------- the model


class _TagSlot:
    """Per-tag constants the model uses in its inner loops."""

    __slots__ = (
        "axis_index",
        "default_ops",
        "fields",
        "initial",
        "ins",
        "internal",
        "inv",
        "local",
        "monitors",
        "op_names",
        "reach",
        "reads_axis",
        "retire",
        "retired",
        "rise_guard",
        "tag",
    )
    tag: TagInstance
    ins: ir.Instruction
    axis_index: int
    local: int
    fields: tuple[str, ...]
    initial: tuple[object, ...]
    op_names: tuple[str, ...]
    default_ops: tuple[object, ...]
    retire: bool
    rise_guard: Callable[[Mapping[str, object]], object] | None
    reads_axis: bool
    retired: tuple[object, ...]

    def __init__(self) -> None:
        self.monitors: tuple[Property, ...] = ()
        self.inv: tuple[Property, ...] = ()
        self.reach: tuple[Property, ...] = ()
        #: a call an add-on instruction makes (its tag is no input of the program and is kept exactly)
        self.internal = False


class Model:
    """The checker's transition system for one system definition and a set of properties."""

    def __init__(
        self,
        spec: ir.Spec,
        sysdef: SystemDef,
        properties: Sequence[Property] = (),
        *,
        axis_backend: Callable[..., object] = FastAxis,
        symmetry: bool | None = None,
    ) -> None:
        self.spec = spec
        self.sysdef = sysdef
        self.properties = tuple(properties)
        self.axis_backend = axis_backend
        self.axis_defs = sysdef.axes()
        self.program = sysdef.program()
        self.params = {"scan_ms": sysdef.scan_ms, "coarse_update_ms": sysdef.coarse_update_ms}
        self.assignments = initial_assignments(sysdef)
        #: tag -> the axis bound to its master-axis operand (MAG's MasterAxis)
        self.masters = sysdef.masters()
        self.system = self.build_system(self.assignments[0])
        self.spu = self.system.scans_per_update
        # AxisInstance or the back end's axes (FastAxis), used through their common interface
        self.axes: list[Any] = list(self.system.axes.values())
        self.charts = {g.chart: spec.chart(g.chart) for _a, g in self.axis_defs}
        #: per axis: the chart parameters its configurations choose (kept in the state after its variables)
        self.param_names: list[tuple[str, ...]] = [
            tuple(sorted({k for c in g.configurations for k, _v in c.parameters})) for _a, g in self.axis_defs]
        # a property tied to a chart the system has no axis of does not apply to it
        ao_ids = {a.add_on.id for a in getattr(self.system, "add_ons", {}).values()}
        self.properties = tuple(p for p in self.properties if (p.chart is None or p.chart in self.charts)
                                and (not p.systems or sysdef.name in p.systems)
                                and (p.scope != "add_on" or (p.instruction or "") in ao_ids | ({""} if ao_ids else set())))
        self.notes: list[str] = []

        # cone of influence and the collapse abstraction
        problems: list[Diagnostic] = []
        self.collapse_index: dict[str, dict[int, object]] = {}
        group_of = dict(self.axis_defs)
        for cid, chart in self.charts.items():
            instructions = [spec.instruction(m) for _a, g in self.axis_defs if g.chart == cid for m in g.program]
            followers = [self.system.tags[t].instruction for t, master in self.masters.items()
                         if group_of[master].chart == cid]
            relevant = relevant_variables(spec, chart, instructions, self.properties, followers)
            idx: dict[int, object] = {}
            for name in sysdef.collapse:
                if name not in {v.name for v in chart.variables}:
                    continue
                if name in relevant:
                    problems.append(Diagnostic(sysdef.file, 1, 1, "abstraction.collapse", (
                        f"cannot collapse {name}: a guard, check, completion condition, request or property "
                        f"of chart {cid} depends on it")))
                    continue
                pos = [v.name for v in chart.variables].index(name)
                idx[pos] = chart.variables[pos].initial
            self.collapse_index[cid] = idx
        if problems:
            raise ModelError(problems)

        # retirement of idle tags, verified per instruction
        retire_ok: dict[str, bool] = {}
        #: the add-on instruction tags of the program (statecharts/addon.py) and the tags of their calls
        self.add_ons: list[Any] = list(getattr(self.system, "add_ons", {}).values())
        program_tags = {t for t, _m, _a in self.program}
        called = {m for _t, m, _a in self.program}
        for ins in spec.instructions:
            if ins.id not in called:  # no tag of it: nothing to retire
                continue
            why = retirement_check(spec, ins) if sysdef.retire_idle_tags else "disabled in the system"
            retire_ok[ins.id] = why is None
            if why is not None and sysdef.retire_idle_tags and any(m == ins.id for _t, m, _a in self.program):
                self.notes.append(f"idle {ins.id} tags are kept exactly: {why}")

        # per-tag slots
        axis_index = {name: i for i, (name, _g) in enumerate(self.axis_defs)}
        self.tags: list[TagInstance] = list(self.system.tags.values())
        self.slots: list[_TagSlot] = []
        self.tags_of_axis: list[list[int]] = [[] for _ in self.axis_defs]
        for ti, tag in enumerate(self.tags):
            s = _TagSlot()
            s.tag = tag
            s.ins = tag.instruction
            s.axis_index = axis_index[tag.axis]
            s.local = len(self.tags_of_axis[s.axis_index])
            self.tags_of_axis[s.axis_index].append(ti)
            s.fields = tuple(tag.values)
            s.initial = tuple(tag.values.values())
            s.op_names = tuple(tag.operands)
            s.default_ops = tuple(tag.operands.values())
            s.internal = tag.name not in program_tags
            s.retire = retire_ok.get(tag.instruction.id, False) and not s.internal
            row = tag.instruction.table.row("rung_true")
            s.rise_guard = row.guard.fn if row is not None and row.guard is not None else None
            chart = self.charts[self.axis_defs[s.axis_index][1].chart]
            tag_props = [p for p in self.properties if p.scope == "tag" and p.applies_to_tag(tag.instruction, chart)]
            s.monitors = tuple(p for p in tag_props if p.kind == "response")
            s.inv = tuple(p for p in tag_props if p.kind == "invariant")
            s.reach = tuple(p for p in tag_props if p.kind == "reachable")
            s.reads_axis = any(n.startswith("axis.") for p in tag_props for n in p.names())
            self.slots.append(s)
        self.queue_local = {tag.name: self.slots[ti].local for ti, tag in enumerate(self.tags)}
        self.tag_axis = {tag.name: self.slots[ti].axis_index for ti, tag in enumerate(self.tags)}
        ao_props = [p for p in self.properties if p.scope == "add_on"]
        #: per add-on instruction tag: its invariants and goals
        self.add_on_props: list[tuple[tuple[Property, ...], tuple[Property, ...]]] = []
        for inst in self.add_ons:
            mine = [p for p in ao_props if p.instruction in (None, inst.add_on.id)]
            self.add_on_props.append((tuple(p for p in mine if p.kind == "invariant"),
                                      tuple(p for p in mine if p.kind == "reachable")))
        self.axis_props: list[tuple[tuple[Property, ...], tuple[Property, ...]]] = []
        for _name, g in self.axis_defs:
            chart = self.charts[g.chart]
            ps = [p for p in self.properties if p.scope == "axis" and p.applies_to_axis(chart)]
            self.axis_props.append((tuple(p for p in ps if p.kind == "invariant"),
                                    tuple(p for p in ps if p.kind == "reachable")))

        for s in self.slots:
            s.retired = (s.initial, False, s.default_ops, tuple(0 for _ in s.monitors))
        # layout: [phase] + per axis block [axis part, tag parts...]
        self.block_start: list[int] = []
        self.block_len: list[int] = []
        pos = 1
        for ai in range(len(self.axis_defs)):
            n = 1 + len(self.tags_of_axis[ai])
            self.block_start.append(pos)
            self.block_len.append(n)
            pos += n
        self.width = pos
        use_symmetry = sysdef.symmetry if symmetry is None else symmetry
        self.symmetric_groups: list[list[int]] = []
        if use_symmetry:
            for g in sysdef.groups:
                members = [i for i, (_n, gg) in enumerate(self.axis_defs) if gg is g]
                if len(members) > 1 and not self._breaks_symmetry(members):
                    self.symmetric_groups.append(members)

        # the alphabet
        self.choices: list[Choice] = []
        self.raise_choices: list[list[Choice]] = []
        self.drop_choice: list[Choice] = []
        for tag, s in zip(self.tags, self.slots):
            if s.internal:  # rows run by its add-on instruction, never by a rung of the program
                self.raise_choices.append([])
                self.drop_choice.append(self._choice("drop", tag=tag.name, inputs=ScanInputs()))
                continue
            raises = []
            for ops in operand_choices(sysdef, tag.instruction):
                raises.append(self._choice("raise", tag=tag.name, operands=tuple(ops.items()),
                                           inputs=ScanInputs(rungs={tag.name: True}, operands={tag.name: ops})))
            self.raise_choices.append(raises)
            self.drop_choice.append(self._choice("drop", tag=tag.name, inputs=ScanInputs(rungs={tag.name: False})))
        self.event_choices: list[Choice] = []
        for name, g in self.axis_defs:
            chart = self.charts[g.chart]
            # drive events (a move reaching its target...) are free inputs: the motion abstraction
            kinds = ("environment",) if sysdef.motion else ("environment", "drive")
            offered = {e.name for e in chart.events if e.kind in kinds}
            events = g.environment if g.environment is not None else sysdef.environment if \
                sysdef.environment is not None else tuple(e.name for e in chart.events if e.kind in ("environment", "drive"))
            for ev in events:
                if ev in offered:
                    self.event_choices.append(self._choice(
                        "event", axis=name, event=ev, inputs=ScanInputs(events=(EnvironmentEvent(name, ev),))))
        # the drive events of each axis also come together with a raise, a drop or an
        # environment event of that axis (base choice index -> its combined choices)
        self.drive_combos: dict[int, list[Choice]] = {}
        drive_of: dict[str, list[str]] = {}
        for c in self.event_choices:
            assert c.axis is not None
            chart = self.charts[dict(self.axis_defs)[c.axis].chart]
            if any(e.name == c.event and e.kind == "drive" for e in chart.events):
                drive_of.setdefault(c.axis, []).append(str(c.event))
        bases: list[tuple[str, Choice]] = []
        for tag, raises, drop, s in zip(self.tags, self.raise_choices, self.drop_choice, self.slots):
            if not s.internal:
                bases.extend((tag.axis, c) for c in (*raises, drop))
        bases.extend((str(c.axis), c) for c in self.event_choices if c.event not in drive_of.get(str(c.axis), ()))
        for axis, base in bases:
            for d in drive_of.get(axis, ()):
                inputs = dataclasses.replace(base.inputs, events=(*base.inputs.events, EnvironmentEvent(axis, d)))
                combo = self._choice(base.kind, tag=base.tag, axis=base.axis if base.kind == "event" else axis,
                                     event=base.event, operands=base.operands, inputs=inputs, drive=d)
                self.drive_combos.setdefault(base.index, []).append(combo)
        self.fixed_choices = list(self.event_choices)
        for c in self.event_choices:
            self.fixed_choices.extend(self.drive_combos.get(c.index, ()))
        self.prescan = self._choice("prescan", inputs=ScanInputs(prescan=True)) if sysdef.prescan else None
        self.nothing = self._choice("nothing", inputs=ScanInputs())
        self.fixed_choices.append(self.nothing)
        # the add-on instruction tags: their rung up or down, and (while it is down) one input changed
        self.add_on_raise: list[Choice] = []
        self.add_on_drop: list[Choice] = []
        self.add_on_inputs: list[list[Choice]] = []
        entries = {e.tag: e for e in sysdef.add_ons}
        for inst in self.add_ons:
            self.add_on_raise.append(self._choice("raise", tag=inst.name, inputs=ScanInputs(rungs={inst.name: True})))
            self.add_on_drop.append(self._choice("drop", tag=inst.name, inputs=ScanInputs(rungs={inst.name: False})))
            # an input written while the rung is down, with the rung staying down or going up in the same scan
            changes = []
            for name, values in entries[inst.name].inputs:
                for v in values:
                    for up in (False, True):
                        rungs = {inst.name: True} if up else {}
                        changes.append(self._choice("raise" if up else "input", tag=inst.name, operands=((name, v),),
                                                    inputs=ScanInputs(rungs=rungs, operands={inst.name: {name: v}})))
            self.add_on_inputs.append(changes)
        #: environment events and input changes still allowed in the run (None: unbounded)
        self.max_changes = sysdef.max_changes
        self.budget = self.max_changes
        self.counted = {c.index for c in self.event_choices if self._is_environment(c)}
        self.counted |= {c.index for b in list(self.counted) for c in self.drive_combos.get(b, ())}
        self.counted |= {c.index for cs in self.add_on_inputs for c in cs}
        # layout, continued: one part per add-on instruction tag, then the changes left
        self.width += len(self.add_ons) + (self.max_changes is not None)

        # run-time buffers and memo tables
        self.monitor_values: list[tuple[int, ...]] = [tuple(0 for _ in s.monitors) for s in self.slots]
        self.trace: list[Executed | Errored | Done | ProcessEnded] = []
        self.fired: list[list[str]] = [[] for _ in self.axes]
        for axis, f in zip(self.axes, self.fired):
            axis.fired = f
        self._axis_memo: dict[tuple[object, ...], tuple[tuple[bool, ...], tuple[bool, ...]]] = {}
        self._tag_memo: dict[tuple[object, ...], tuple[tuple[bool, ...], tuple[bool, ...], tuple[int, ...], tuple[bool, ...]]] = {}
        self._add_on_memo: dict[tuple[object, ...], tuple[tuple[bool, ...], tuple[bool, ...]]] = {}

    # -- construction helpers ----------------------------------------------------

    def _is_environment(self, c: Choice) -> bool:
        chart = self.charts[dict(self.axis_defs)[str(c.axis)].chart]
        return any(e.name == c.event and e.kind == "environment" for e in chart.events)

    def _choice(self, kind: str, *, tag: str | None = None, axis: str | None = None, event: str | None = None,
                operands: tuple[tuple[str, object], ...] = (), inputs: ScanInputs, drive: str | None = None) -> Choice:
        c = Choice(len(self.choices), kind, tag, axis, event, operands, inputs, drive)
        self.choices.append(c)
        return c

    def _breaks_symmetry(self, members: list[int]) -> bool:
        """Axis-specific properties would break symmetry (ours are all quantified); an axis
        that another axis's call names as its master is not interchangeable with the
        others of its group."""
        names = {self.axis_defs[i][0] for i in members}
        return any(master in names for master in self.masters.values())

    def build_system(self, assignment: Sequence[int], backend: Callable[..., object] | None = None) -> System:
        """A fresh concrete system in the initial state chosen by ``assignment``."""
        make = backend or self.axis_backend
        axes: list[Any] = []
        for (name, g), ci in zip(self.axis_defs, assignment):
            variables = dict(g.variables)
            variables.update(dict(g.configurations[ci].variables))
            parameters = {**self.params, **dict(g.parameters), **dict(g.configurations[ci].parameters)}
            state = g.configurations[ci].state or g.state
            axis: Any = make(self.spec.chart(g.chart), name, state=state, variables=variables,
                             parameters=parameters)
            for event in g.events:  # a device's set-up events (its mode selection)
                axis.apply_event_actions(event)
                axis.send(event)
            axes.append(axis)
        # motion=False: the drive model's arithmetic is abstracted away (its events are inputs)
        extra: dict[str, Any] = {}
        if self.sysdef.add_ons:
            extra["add_ons"] = {e.tag: dict(e.operands) for e in self.sysdef.add_ons}
        system = System(self.spec, axes, self.program, scan_ms=self.sysdef.scan_ms,
                        coarse_update_ms=self.sysdef.coarse_update_ms, masters=self.masters,
                        motion=self.sysdef.motion, **extra)
        for e in self.sysdef.add_ons:
            system.add_ons[e.tag].preset(dict(e.preset))
        return system

    # -- state <-> system -----------------------------------------------------------

    def extract(self) -> Flat:
        """The abstract state of the model's system (after the abstractions).

        A flat tuple of parts: the clock phase, then per axis its axis part
        ``(configuration, variable values[, history], queued tags, held events)`` followed
        by one part per tag ``(member values, rung, operands, monitors)``."""
        system = self.system
        flat: list[object] = [system.index % self.spu]
        queue = system.queue
        held = system.held_events
        slots = self.slots
        for ai, axis in enumerate(self.axes):
            snap = axis.snapshot()
            values = self.extract_axis_values(ai, snap[1])
            if self.param_names[ai]:
                env = axis.env
                values = (*values, *(env[n] for n in self.param_names[ai]))
            q = tuple([self.queue_local[n] for n in queue if self.tag_axis[n] == ai]) if queue else ()
            h = tuple([e.event for e in held if e.axis == axis.name]) if held else ()
            if len(snap) > 2:
                flat.append((snap[0], values, snap[2], q, h))
            else:
                flat.append((snap[0], values, q, h))
            for ti in self.tags_of_axis[ai]:
                flat.append(self.extract_tag(ti, slots[ti].tag.name in queue if queue else False))
        for inst in self.add_ons:
            flat.append(inst.snapshot())
        if self.max_changes is not None:
            flat.append(self.budget)
        return tuple(flat)

    def extract_axis_values(self, ai: int, values: tuple[object, ...]) -> tuple[object, ...]:
        """An axis's chart variable values with the collapsed ones replaced by their initial values."""
        collapse = self.collapse_index[self.axes[ai].chart.id]
        return tuple([collapse.get(i, v) for i, v in enumerate(values)]) if collapse else values

    def extract_tag(self, ti: int, queued: bool) -> tuple[object, ...]:
        """The abstract part of tag ``ti`` as loaded (dead operands reset, idle tags retired)."""
        s = self.slots[ti]
        tag = s.tag
        vals = tag.values
        if s.internal:
            return (tuple(vals.values()), tag.rung, tuple(tag.operands.values()), self.monitor_values[ti])
        busy = vals.get("pending") or queued
        if s.retire and not tag.rung and not busy and (s.rise_guard is None or s.rise_guard(vals)):
            return s.retired
        # operands are dead when nothing is pending and the rung is low: the next
        # execution needs a rise, and a rise sets every operand
        return (tuple(vals.values()), tag.rung,
                tuple(tag.operands.values()) if busy or tag.rung else s.default_ops,
                self.monitor_values[ti])

    def load(self, flat: Flat) -> None:
        """Make the model's system be in abstract state ``flat``."""
        system = self.system
        system.index = flat[0]
        i = 1
        queue: list[str] = []
        held: list[EnvironmentEvent] = []
        slots = self.slots
        for ai, axis in enumerate(self.axes):
            part = flat[i]
            i += 1
            if len(part) > 4:
                config, values, hist, q, e = part
                axis.restore((config, values, hist))
            else:
                config, values, q, e = part
                axis.restore((config, values))
            pnames = self.param_names[ai]
            if pnames:
                axis.env.update(zip(pnames, values[len(values) - len(pnames):]))
            if q:
                names = self.tags_of_axis[ai]
                queue.extend([self.tags[names[k]].name for k in q])
            if e:
                held.extend([EnvironmentEvent(axis.name, ev) for ev in e])
            for ti in self.tags_of_axis[ai]:
                s = slots[ti]
                tag = s.tag
                fields, rung, ops, mon = flat[i]
                i += 1
                tag.values.update(zip(s.fields, fields))
                tag.rung = rung
                tag.operands.update(zip(s.op_names, ops))
                self.monitor_values[ti] = mon
        for inst in self.add_ons:
            inst.restore(flat[i])
            i += 1
        if self.max_changes is not None:
            self.budget = flat[i]
        system.queue = queue
        system.held_events = held

    def enabled(self) -> list[Choice]:
        """The choices offered in the loaded state."""
        out: list[Choice] = []
        limit = self.sysdef.max_live_calls
        queue = self.system.queue
        live = [0] * len(self.axes)
        if limit is not None:
            for s in self.slots:
                if self._live(s, queue):
                    live[s.axis_index] += 1
        combos = self.drive_combos
        for ti, s in enumerate(self.slots):
            if s.internal:
                continue
            if s.tag.rung:
                out.append(self.drop_choice[ti])
                out.extend(combos.get(self.drop_choice[ti].index, ()))
            elif limit is None or live[s.axis_index] < limit or self._live(s, queue):
                for c in self.raise_choices[ti]:
                    out.append(c)
                    out.extend(combos.get(c.index, ()))
        out.extend(self.fixed_choices)
        for k, inst in enumerate(self.add_ons):
            if inst.rung:
                out.append(self.add_on_drop[k])
            else:
                out.append(self.add_on_raise[k])
                if self.budget is None or self.budget > 0:
                    out.extend(c for c in self.add_on_inputs[k] if inst.inputs[c.operands[0][0]] != c.operands[0][1])
        if self.budget is not None and self.budget <= 0:
            out = [c for c in out if c.index not in self.counted]
        # A prescan pass counts as a scan of the coarse-update clock but runs no coarse
        # update; offered only when nothing waits for one, so that requests and events
        # cannot pile up without bound behind repeated prescans.
        if self.prescan is not None and not queue and not self.system.held_events:
            out.append(self.prescan)
        return out

    @staticmethod
    def _live(s: _TagSlot, queue: list[str]) -> bool:
        tag = s.tag
        vals = tag.values
        return bool(tag.rung or vals.get("pending") or tag.name in queue
                    or (s.rise_guard is not None and not s.rise_guard(vals)))

    # -- one step ---------------------------------------------------------------------

    def initial(self, assignment: Sequence[int]) -> tuple[Flat, list[Property], list[Property]]:
        """Abstract initial state for one configuration assignment, with the properties
        violated and the goals reached in it."""
        fresh = self.build_system(assignment)
        for axis, f, names in zip(fresh.axes.values(), self.axes, self.param_names):
            f.restore(axis.snapshot())
            f.env.update({n: axis.env[n] for n in names})
        for tag, s in zip(self.tags, self.slots):
            tag.values.update(zip(s.fields, s.initial))
            tag.rung = False
            tag.operands.update(zip(s.op_names, s.default_ops))
        for inst, other in zip(self.add_ons, getattr(fresh, "add_ons", {}).values()):
            inst.restore(other.snapshot())
        # a configuration other than its group's first is a change made before the first scan
        self.budget = None if self.max_changes is None else self.max_changes - sum(1 for c in assignment if c)
        self.system.queue = []
        self.system.held_events = []
        self.system.index = 0
        self.monitor_values = [tuple(0 for _ in s.monitors) for s in self.slots]
        violated, reached = self.evaluate()
        return self.extract(), violated, reached

    def step(self, choice: Choice) -> tuple[Flat, list[Property], list[Property], StepFacts]:
        """Run one scan with ``choice`` from the loaded state; return the successor, the
        properties it violates, the goals it reaches, and what the step did."""
        trace = self.trace
        trace.clear()
        for f in self.fired:
            f.clear()
        system = self.system
        system.trace = trace
        errs = [inst.status.get("Sts_ERR") if inst.status.get("Sts_ER") else None for inst in self.add_ons]
        system.advance(choice.inputs)
        system.trace = None
        if self.budget is not None and choice.index in self.counted:
            self.budget -= 1
        violated, reached = self.evaluate()
        facts = self.facts()
        if self.add_ons:
            # an add-on instruction's error: its Sts_ERR once Sts_ER is set (an item of error_codes)
            new = tuple((inst.add_on.id, int(inst.status["Sts_ERR"]), 0) for inst, before in zip(self.add_ons, errs)
                        if inst.status.get("Sts_ER") and inst.status.get("Sts_ERR") != before)
            if new:
                facts = dataclasses.replace(facts, errors=(*facts.errors, *new))
        return self.extract(), violated, reached, facts

    def facts(self) -> StepFacts:
        fired = tuple((axis.chart.id, t) for axis, f in zip(self.axes, self.fired) for t in f)
        executed: list[tuple[str, str]] = []
        errors: list[tuple[str, int, int]] = []
        checks: list[tuple[str, str]] = []
        for rec in self.trace:
            if type(rec) is Executed:
                executed.append((self.system.tags[rec.tag].instruction.id, rec.axis_state))
            elif type(rec) is Errored:
                mnemonic = self.system.tags[rec.tag].instruction.id
                errors.append((mnemonic, rec.err, rec.exerr))
                checks.append((mnemonic, rec.check))
        return StepFacts(fired, tuple(executed), tuple(errors), tuple(checks))

    # -- properties ---------------------------------------------------------------------

    def axis_env(self, ai: int) -> dict[str, object]:
        axis = self.axes[ai]
        env: dict[str, object] = dict(axis.env)
        leaf = axis.leaf
        env["state"] = leaf.id
        env["active"] = axis.active
        env["axis"] = axis.name
        env[axis.chart.state_attribute] = leaf.value
        return env

    def tag_env(self, ti: int, axis_env: dict[str, object] | None, queued: bool | None = None) -> dict[str, object]:
        s = self.slots[ti]
        tag = s.tag
        env: dict[str, object] = dict(axis_env) if axis_env else {}
        env.update(tag.values)
        env["rung"] = tag.rung
        env["queued"] = tag.name in self.system.queue if queued is None else queued
        env["instruction"] = tag.instruction.id
        env["tag"] = tag.name
        return env

    def evaluate(self) -> tuple[list[Property], list[Property]]:
        """Invariants violated, goals reached; updates the response monitors."""
        violated: list[Property] = []
        reached: list[Property] = []
        for ai in range(len(self.axes)):
            self.evaluate_axis(ai, violated, reached)
        axis_envs: dict[int, dict[str, object]] = {}
        queue = self.system.queue
        for ti in range(len(self.slots)):
            self.evaluate_tag(ti, self.slots[ti].tag.name in queue, axis_envs, violated, reached)
        for k in range(len(self.add_ons)):
            self.evaluate_add_on(k, violated, reached)
        return violated, reached

    def add_on_env(self, k: int) -> dict[str, object]:
        """What a ``scope: add_on`` property reads of add-on instruction tag ``k``."""
        inst = self.add_ons[k]
        env: dict[str, object] = dict(inst.env())
        env.update(inst.status)
        env.update(state=inst.state, rung=inst.rung, tag=inst.name)
        for par in inst.add_on.parameters:
            obj = self.system.axes.get(str(inst.inputs.get(par.name))) if par.alias else None
            if obj is not None:
                for v in obj.chart.variables:
                    env.setdefault(f"{par.alias}.{v.name}", obj.env[v.name])
        return env

    def evaluate_add_on(self, k: int, violated: list[Property], reached: list[Property]) -> None:
        inv, reach = self.add_on_props[k]
        if not inv and not reach:
            return
        # what the properties read: the instance and the chart instances (with their parameters)
        key = (k, self.add_ons[k].snapshot(), tuple(a.snapshot() for a in self.axes),
               tuple(tuple(a.env[n] for n in names) for a, names in zip(self.axes, self.param_names) if names))
        _evaluate(self._add_on_memo, key, lambda: self.add_on_env(k), inv, reach, violated, reached)

    def evaluate_axis(self, ai: int, violated: list[Property], reached: list[Property]) -> None:
        """Axis ``ai``'s invariants violated and goals reached, appended to the lists."""
        inv, reach = self.axis_props[ai]
        if not inv and not reach:
            return
        _evaluate(self._axis_memo, self.axes[ai].snapshot(), lambda: self.axis_env(ai), inv, reach, violated, reached)

    def evaluate_tag(self, ti: int, queued: bool, axis_envs: dict[int, dict[str, object]],
                     violated: list[Property], reached: list[Property]) -> None:
        """Tag ``ti``'s invariants violated and goals reached, appended to the lists; its
        response monitors updated.  ``axis_envs`` caches expression environments per axis."""
        s = self.slots[ti]
        if not s.inv and not s.reach and not s.monitors:
            return
        tag = s.tag
        key: tuple[object, ...] = (ti, tuple(tag.values.values()), tag.rung, queued, self.monitor_values[ti])
        if s.reads_axis:
            key = (*key, self.axes[s.axis_index].snapshot())
        memo2 = self._tag_memo.get(key)
        if memo2 is None:
            aenv = None
            if s.reads_axis:
                aenv = axis_envs.get(s.axis_index)
                if aenv is None:
                    aenv = self.axes[s.axis_index].expression_env()
                    axis_envs[s.axis_index] = aenv
            env = self.tag_env(ti, aenv, queued)
            inv_ok = tuple(_holds(p, env, p.holds) for p in s.inv)
            goals = tuple(_holds(p, env, p.goal) for p in s.reach)
            mons: list[int] = []
            bad: list[bool] = []
            for p, m in zip(s.monitors, self.monitor_values[ti]):
                m2, b = _monitor(p, env, m)
                mons.append(m2)
                bad.append(b)
            memo2 = (inv_ok, goals, tuple(mons), tuple(bad))
            self._tag_memo[key] = memo2
        for p, ok in zip(s.inv, memo2[0]):
            if not ok:
                violated.append(p)
        for p, ok in zip(s.reach, memo2[1]):
            if ok:
                reached.append(p)
        if s.monitors:
            self.monitor_values[ti] = memo2[2]
            for p, b in zip(s.monitors, memo2[3]):
                if b:
                    violated.append(p)


def _evaluate(memo: dict[Any, tuple[tuple[bool, ...], tuple[bool, ...]]], key: Any,
              env: Callable[[], Mapping[str, object]], inv: Sequence[Property], reach: Sequence[Property],
              violated: list[Property], reached: list[Property]) -> None:
    """Invariants ``inv`` violated and goals ``reach`` reached in the environment ``env()``
    gives, appended to the lists; the verdicts remembered in ``memo`` under ``key``."""
    verdicts = memo.get(key)
    if verdicts is None:
        e = env()
        verdicts = (tuple(_holds(p, e, p.holds) for p in inv), tuple(_holds(p, e, p.goal) for p in reach))
        memo[key] = verdicts
    violated.extend(p for p, ok in zip(inv, verdicts[0]) if not ok)
    reached.extend(p for p, ok in zip(reach, verdicts[1]) if ok)


def _holds(p: Property, env: Mapping[str, object], e: Expr | None) -> bool:
    if p.where is not None and not p.where(env):
        return p.kind != "reachable"
    if e is None:  # the property loader gives every invariant `holds` and every goal `goal`
        raise ValueError(f"property {p.name} has no condition to evaluate")
    return bool(e(env))


#: monitor value of a response obligation that was met (or excused) while the trigger holds
DISCHARGED = -1


def _monitor(p: Property, env: Mapping[str, object], m: int) -> tuple[int, bool]:
    """Next monitor value and whether the bound was exceeded."""
    assert p.trigger is not None and p.response is not None
    if not p.trigger(env) or (p.where is not None and not p.where(env)):
        return 0, False
    if m == DISCHARGED:
        return DISCHARGED, False
    if p.response(env) or (p.unless is not None and p.unless(env)):
        return DISCHARGED, False
    m += 1
    if m >= p.within:
        return p.within, True
    return m, False
