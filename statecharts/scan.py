"""PLC scan semantics: the one module that says when what happens.

Pipeline position: engine (python-statemachine charts) -> **scan** -> scenarios, CLI.
The model checker (a later stage) must follow these same rules; they are written out
in ``docs/semantics.md``.  In short, one call of :meth:`System.scan` is one PLC scan:

1. Program: every instruction of the program is scanned in program order with its
   current rung-condition-in.  The row of its execution table for that condition runs
   (``rung_true`` / ``rung_false``; ``prescan`` on a prescan pass).  A row marked
   ``execute`` runs the instruction: ``on_execute``, then the checks of stage
   ``execute`` in spec order; the first that fails sets ERR / EXERR and ``on_error``;
   if none fails, ``on_accept`` and the request is queued for its axis.
2. Coarse update (every ``coarse_update_ms / scan_ms`` scans, the first scan included):
   for each axis in set-up order,
   o. the drive model advances to the time of this update: the chart receives
      ``tick`` (so a delay started by a request at this update counts from now), and
      instructions delivered earlier and still pending are finished (DN / ER / still
      pending), so what the passing time completed is done before new requests act;
   a. queued requests in program order: every check of the instruction is evaluated
      again, in order (stage ``message`` included); the first failing one ends the
      instruction with ER; otherwise the request's actions are applied, its event is
      sent to the axis chart, and the instruction is finished at once (DN when its
      completion condition holds, else ER when an abort holds, else it stays
      pending) before the next request is processed;
   b. environment events for the axis are applied (their actions, then the event);
   then every instruction still pending whose request was delivered is finished the
   same way (this is how a delayed completion such as MDO's arrives).  Environment events given on a scan without a coarse update wait for the
   next one.

The same :class:`System` runs every axis back-end that offers the axis interface of
:class:`~statecharts.engine.AxisInstance` (``name``, ``env``, ``send``,
``apply_event_actions``, ``expression_env``, ``observe``, ``snapshot``, ``restore``):
the python-statemachine engine (the reference) and the model checker's IR interpreter
(:mod:`checker.compile`).  The checker restores a state with :meth:`System.restore`,
runs one :meth:`System.advance` (a scan without the observation record) and takes the
successor with :meth:`System.snapshot`, so there is exactly one implementation of these
rules.  With :attr:`System.trace` set to a list, a scan appends explicit
:class:`Executed`, :class:`Errored` and :class:`Done` records to it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, cast

from statecharts import drive, ir
from statecharts.addon import AddOnInstance
from statecharts.engine import AxisInstance
from statecharts.expr import Assignment

if TYPE_CHECKING:
    from statecharts.program.ladder import Ladder

#: MOTION_INSTRUCTION members reported in observations, in display order.
TAG_FIELDS = ("EN", "DN", "ER", "PC", "IP", "ERR", "EXERR", "FLAGS")


@dataclass(frozen=True, slots=True)
class EnvironmentEvent:
    axis: str
    event: str


@dataclass(frozen=True, slots=True)
class Executed:
    """Trace record: ``tag``'s instruction executed with its axis in leaf state ``axis_state``."""

    tag: str
    axis_state: str


@dataclass(frozen=True, slots=True)
class Errored:
    """Trace record: ``tag`` ended with ER because check (or abort) ``check`` failed."""

    tag: str
    check: str
    err: int
    exerr: int


@dataclass(frozen=True, slots=True)
class Done:
    """Trace record: ``tag`` completed with DN."""

    tag: str


@dataclass(frozen=True, slots=True)
class ProcessEnded:
    """Trace record: the process ``tag`` started completed (PC) or ended without completing."""

    tag: str
    complete: bool


def _is_drive_event(axis: AxisInstance, event: str) -> bool:
    return any(e.name == event and e.kind == "drive" for e in axis.chart.events)


@dataclass(frozen=True, slots=True)
class ScanInputs:
    """What the outside world sets for one scan."""

    rungs: Mapping[str, bool] = field(default_factory=dict)
    operands: Mapping[str, Mapping[str, object]] = field(default_factory=dict)
    events: tuple[EnvironmentEvent, ...] = ()
    prescan: bool = False
    #: program tag writes made before the scan (push buttons, limit switches): path -> value
    writes: Mapping[str, bool | int | float] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class ScanRecord:
    """What one scan did and what could be observed after it."""

    index: int
    coarse_update: bool
    observations: Mapping[str, Mapping[str, object]]


class TagInstance:
    """One MOTION_INSTRUCTION tag bound to one instruction call in the program."""

    def __init__(
        self, name: str, instruction: ir.Instruction, tag_type: ir.TagType, axis: str, master: str | None = None,
    ) -> None:
        self.name = name
        self.instruction = instruction
        self.tag_type = tag_type
        self.axis = axis
        #: the axis bound to the instruction's master operand (MAG's MasterAxis), if any
        self.master = master
        self.values: dict[str, object] = {}
        for m in tag_type.members:
            self.values[m.name] = False if m.type == "BOOL" else 0
        for v in tag_type.internal:
            self.values[v.name] = v.initial
        self.operands: dict[str, object] = {
            o.name: o.default for o in instruction.operands if o.type not in ("axis", "tag")
        }
        self.rung = False

    def run(self, actions: Sequence[Assignment]) -> None:
        for a in actions:
            a.apply(self.values)

    def snapshot(self) -> tuple[tuple[object, ...], tuple[object, ...], bool]:
        """(member and internal values, operand values, rung) in declaration order."""
        return tuple(self.values.values()), tuple(self.operands.values()), self.rung

    def restore(self, snap: tuple[tuple[object, ...], tuple[object, ...], bool]) -> None:
        values, operands, self.rung = snap
        self.values.update(zip(self.values, values))
        self.operands.update(zip(self.operands, operands))

    @property
    def flags(self) -> int:
        word = 0
        for m in self.tag_type.members:
            if m.bit is not None and self.values[m.name]:
                word |= 1 << m.bit
        # FLAGS is a DINT: bit 31 makes it negative
        return word - (1 << 32) if word & (1 << 31) else word

    def observe(self) -> dict[str, object]:
        out = {m.name: self.values[m.name] for m in self.tag_type.members}
        out["FLAGS"] = self.flags
        return out


class System:
    """Axes, a program of instruction tags, and the scan clock.

    With ``ladder`` (a :class:`~statecharts.program.ladder.Ladder`), step 1 of the scan
    is that ladder program: its routines run rung by rung, and each motion instruction
    in them runs its execution-table row inline, in rung order, on its
    MOTION_INSTRUCTION tag (``program`` then lists nothing; the ladder's motion
    instructions become the tags).  Without it, every tag's rung is set from outside.
    """

    def __init__(
        self,
        spec: ir.Spec,
        axes: Sequence[AxisInstance],
        program: Sequence[tuple[str, str, str]],
        *,
        scan_ms: int = 10,
        coarse_update_ms: int = 10,
        ladder: Ladder | None = None,
        masters: Mapping[str, str] | None = None,
        motion: bool = True,
        add_ons: Mapping[str, Mapping[str, object]] | None = None,
    ) -> None:
        if scan_ms <= 0 or coarse_update_ms <= 0:
            raise ValueError("scan_ms and coarse_update_ms must be positive")
        self.spec = spec
        self.axes = {a.name: a for a in axes}
        for a in axes:
            # the clock parameters are the system's; axis-chart expressions read them
            a.env["scan_ms"] = scan_ms
            a.env["coarse_update_ms"] = coarse_update_ms
        self.tags: dict[str, TagInstance] = {}
        calls = list(program)
        if ladder is not None:
            calls.extend((b.tag, b.mnemonic, b.axis) for b in ladder.bindings if b.axis in self.axes)
        masters = dict(masters or {})
        #: the add-on instruction tags of the program (statecharts/addon.py)
        self.add_ons: dict[str, AddOnInstance] = {}
        #: the program in order: MOTION_INSTRUCTION tags and add-on instruction tags (the
        #: tags of the calls an add-on instruction makes are in :attr:`tags` only)
        self.program: list[TagInstance | AddOnInstance] = []
        add_on_defs = {a.id: a for a in spec.add_ons}
        for tag, mnemonic, axis in calls:
            if mnemonic in add_on_defs:
                inst = AddOnInstance(tag, add_on_defs[mnemonic], self, (add_ons or {}).get(tag, {}))
                self.add_ons[tag] = inst
                self.program.append(inst)
                continue
            ins = self.variant(mnemonic, axis)
            master = masters.get(tag)
            if ins.master_operand is not None and master not in self.axes:
                raise ValueError(f"{tag}: {mnemonic} needs its {ins.master_operand} bound to an axis of the system")
            self.tags[tag] = TagInstance(tag, ins, spec.tag_type, axis, master)
            self.program.append(self.tags[tag])
        #: run the drive model of :mod:`statecharts.drive` (the checker offers its events instead)
        self.motion = motion
        #: gearing slave axis -> its master axis, set when a MAG is accepted
        self.gear_masters: dict[str, str] = {}
        self.scan_ms = scan_ms
        self.coarse_update_ms = coarse_update_ms
        self.scans_per_update = max(1, coarse_update_ms // scan_ms)
        self.index = 0
        self.queue: list[str] = []
        self.held_events: list[EnvironmentEvent] = []
        #: when a list, scans append Executed / Errored / Done records to it
        self.trace: list[Executed | Errored | Done | ProcessEnded] | None = None
        self.ladder = ladder
        if ladder is not None:
            ladder.scan_ms = scan_ms
            ladder.attach(self)

    def variant(self, mnemonic: str, axis: str) -> ir.Instruction:
        """The variant of ``mnemonic`` for the axis's chart.

        An instruction with no variant for that chart keeps the operands and execution
        table of its first variant but only ever errs, with the tag type's
        ``wrong_axis_family`` error (ERR 8, Wrong Axis Type; INT-001)."""
        chart = self.axes[axis].chart.id
        try:
            return self.spec.instruction(mnemonic, chart)
        except KeyError:
            pass
        variants = self.spec.variants(mnemonic) or (self.spec.instruction(mnemonic),)
        wrong = self.spec.tag_type.wrong_axis_family
        if wrong is None:
            raise ValueError(f"{mnemonic} has no variant for chart {chart}")
        return dataclasses.replace(variants[0], checks=(wrong,), aborts=(), request=None, done_when=None)

    # -- the scan ---------------------------------------------------------------

    def scan(self, inputs: ScanInputs) -> ScanRecord:
        """One PLC scan; returns what it did and what could be observed after it."""
        coarse = self.advance(inputs)
        return ScanRecord(self.index - 1, coarse, self.observe())

    def advance(self, inputs: ScanInputs) -> bool:
        """One PLC scan without the observation record; True when it had a coarse update."""
        if self.ladder is not None:
            return self._advance_ladder(inputs)
        for name, rung in inputs.rungs.items():
            (self.add_ons.get(name) or self.tags[name]).rung = rung
        for name, ops in inputs.operands.items():
            if name in self.add_ons:
                self.add_ons[name].inputs.update(ops)
            else:
                self.tags[name].operands.update(ops)
        self.held_events.extend(inputs.events)
        coarse = False
        for entry in self.program:
            condition = "prescan" if inputs.prescan else "rung_true" if entry.rung else "rung_false"
            if isinstance(entry, AddOnInstance):
                entry.scan(condition)
            else:
                self._row(entry, condition)
        if not inputs.prescan:
            coarse = self.index % self.scans_per_update == 0
            if coarse:
                self._coarse_update()
        self.index += 1
        return coarse

    def _advance_ladder(self, inputs: ScanInputs) -> bool:
        """A scan whose program is the ladder: tag writes, then the routines, then the coarse update."""
        ladder = self.ladder
        assert ladder is not None
        for path, value in inputs.writes.items():
            ladder.write(path, value)
        self.held_events.extend(inputs.events)
        coarse = False
        if inputs.prescan:
            ladder.prescan()
        else:
            ladder.scan()
            coarse = self.index % self.scans_per_update == 0
            if coarse:
                self._coarse_update()
        self.index += 1
        return coarse

    def motion_row(self, tag: TagInstance, condition: str) -> None:
        """Run one execution-table row of a motion instruction (the ladder calls this inline)."""
        self._row(tag, condition)

    # -- state ----------------------------------------------------------------------

    def snapshot(self) -> tuple[object, ...]:
        """The whole state as nested tuples: (phase of the coarse-update clock, axes,
        tags, request queue, held environment events), with a ladder program the
        values of its tag database, and with add-on instruction tags their states last.
        The scan counter itself is not state; only its phase decides when the next
        coarse update comes."""
        snap: tuple[object, ...] = (
            self.index % self.scans_per_update,
            tuple(a.snapshot() for a in self.axes.values()),
            tuple(t.snapshot() for t in self.tags.values()),
            tuple(self.queue),
            tuple((e.axis, e.event) for e in self.held_events),
        )
        if self.ladder is not None:
            snap += (self.ladder.db.snapshot(),)
        if self.add_ons:
            snap += (tuple(a.snapshot() for a in self.add_ons.values()),)
        return snap

    def restore(self, snap: tuple[object, ...]) -> None:
        """Make the system be in a state taken by :meth:`snapshot`."""
        phase, axes, tags, queue, held = cast(
            "tuple[int, tuple[Any, ...], tuple[Any, ...], tuple[str, ...], tuple[tuple[str, str], ...]]", snap[:5])
        if self.ladder is not None:
            self.ladder.db.restore(cast("tuple[bool | int | float, ...]", snap[5]))
        if self.add_ons:
            for inst, a in zip(self.add_ons.values(), cast("tuple[Any, ...]", snap[-1])):
                inst.restore(a)
        self.index = phase
        for axis, a in zip(self.axes.values(), axes):
            axis.restore(a)
        for tag, t in zip(self.tags.values(), tags):
            tag.restore(t)
        self.queue = list(queue)
        self.held_events = [EnvironmentEvent(a, e) for a, e in held]

    def _row(self, tag: TagInstance, condition: str) -> None:
        row = tag.instruction.table.row(condition)
        if row is None:
            return
        if row.guard is not None and not row.guard(tag.values):
            return
        tag.run(row.actions)
        if row.execute:
            self._execute(tag)

    def _check_env(self, tag: TagInstance) -> dict[str, object]:
        env = self.axes[tag.axis].expression_env()
        for k, v in tag.operands.items():
            env[f"op.{k}"] = v
        if tag.master is not None:
            for k, v in self.axes[tag.master].expression_env().items():
                env["master." + k.removeprefix("axis.")] = v
        return env

    def _first_failure(self, tag: TagInstance, stages: tuple[ir.Stage, ...]) -> ir.Check | None:
        env = self._check_env(tag)
        for check in tag.instruction.checks:
            if check.stage in stages and check.fails_when(env):
                return check
        return None

    def _fail(self, tag: TagInstance, check: ir.Check) -> None:
        if self.trace is not None:
            self.trace.append(Errored(tag.name, check.id, check.err, check.exerr))
        tag.values["ERR"] = check.err
        tag.values["EXERR"] = check.exerr
        tag.run(tag.instruction.table.on_error)

    def _execute(self, tag: TagInstance) -> None:
        table = tag.instruction.table
        if self.trace is not None:
            self.trace.append(Executed(tag.name, self.axes[tag.axis].leaf.id))
        tag.run(table.on_execute)
        failed = self._first_failure(tag, (ir.Stage.EXECUTE,))
        if failed is not None:
            self._fail(tag, failed)
            return
        tag.run(table.on_accept)
        if tag.name in self.queue:
            self.queue.remove(tag.name)
        self.queue.append(tag.name)

    def _coarse_update(self) -> None:
        events, self.held_events = self.held_events, []
        due = self._drive_events(events)
        for axis in self.axes.values():
            axis.send("tick")
            # the drive model's outcomes of the time that passed (docs/semantics.md)
            for name in due.get(axis.name, ()):
                self._environment(axis, name)
            # what the passing time completed is done before this update's requests
            self._finish_pending(axis.name)
            for tag_name in [n for n in self.queue if self.tags[n].axis == axis.name]:
                self.queue.remove(tag_name)
                tag = self.tags[tag_name]
                if tag.values.get("pending"):
                    self._deliver(axis, tag)
            for ev in events:
                if ev.axis == axis.name and not _is_drive_event(axis, ev.event):
                    self._environment(axis, ev.event)
        self._finish_pending(None)

    def _drive_events(self, held: Sequence[EnvironmentEvent]) -> dict[str, list[str]]:
        """The drive events of this update per axis: those the drive model computes (when
        :attr:`motion` is on; gearing masters advance before their slaves, so a slave
        follows its master's velocity of this update) and those given as inputs, each
        once, in the order of :data:`statecharts.drive.EVENTS`."""
        out: dict[str, list[str]] = {}
        order = sorted(self.axes.values(), key=lambda a: a.name in self.gear_masters)
        for axis in order:
            if axis.chart.drive_model is None:
                continue
            due = {ev.event for ev in held if ev.axis == axis.name and _is_drive_event(axis, ev.event)}
            if self.motion:
                master = self.gear_masters.get(axis.name)
                mv = self.axes[master].env.get("CommandVelocity") if master is not None else None
                due.update(drive.advance(axis.env, self.coarse_update_ms / 1000.0,
                                         float(mv) if isinstance(mv, (int, float)) else None))
            out[axis.name] = [e for e in drive.EVENTS if e in due]
        return out

    def _deliver(self, axis: AxisInstance, tag: TagInstance) -> None:
        """The axis answers one queued, pending request (step a of the coarse update)."""
        failed = self._first_failure(tag, (ir.Stage.EXECUTE, ir.Stage.MESSAGE))
        if failed is not None:
            self._fail(tag, failed)
            return
        request = tag.instruction.request
        if request is not None:
            env = self._check_env(tag)
            for a in request.actions:
                axis.env[a.target.removeprefix("axis.")] = a.value(env)
            axis.send(request.event)
        process = tag.instruction.process
        if process is not None:
            # a new process of a kind supersedes the axis's older one of that kind
            for other in self.tags.values():
                op = other.instruction.process
                if (other is not tag and other.axis == tag.axis and op is not None and op.kind == process.kind
                        and other.values.get("pending") and other.values.get("DN")):
                    self._end_process(other, complete=False)
            if tag.master is not None:
                self.gear_masters[tag.axis] = tag.master
        # the axis answers this request before it processes the next one
        self._finish(tag)

    @staticmethod
    def _environment(axis: AxisInstance, event: str) -> None:
        """One environment event reaches the axis (step b): its actions, then the event."""
        axis.apply_event_actions(event)
        axis.send(event)

    def _finish_pending(self, axis: str | None) -> None:
        """Finish every delivered, still pending instruction (of one axis, or of all)."""
        for tag in self.tags.values():
            if (axis is None or tag.axis == axis) and tag.values.get("pending") and tag.name not in self.queue:
                self._finish(tag)

    def _finish(self, tag: TagInstance) -> None:
        """DN when the completion condition holds, else ER when an abort holds; for an
        instruction with a process, once DN is set: PC when the process completes, IP
        cleared when it ends."""
        ins = tag.instruction
        env = self._check_env(tag)
        if ins.process is not None and tag.values.get("DN"):
            self._update_process(tag, env)
            return
        if ins.done_when is None or ins.done_when(env):
            if self.trace is not None:
                self.trace.append(Done(tag.name))
            tag.run(ins.table.on_done)
            if ins.process is not None:
                self._update_process(tag, env)
            return
        for ab in ins.aborts:
            if ab.fails_when(env):
                self._fail(tag, ab)
                return

    def _update_process(self, tag: TagInstance, env: Mapping[str, object]) -> None:
        process = tag.instruction.process
        assert process is not None
        if process.complete_when is not None and process.complete_when(env):
            self._end_process(tag, complete=True)
        elif process.ends_when is not None and process.ends_when(env):
            self._end_process(tag, complete=False)

    def _end_process(self, tag: TagInstance, *, complete: bool) -> None:
        """The process of ``tag`` completes (``on_complete``: PC) or ends (``on_end``)."""
        if self.trace is not None:
            self.trace.append(ProcessEnded(tag.name, complete))
        table = tag.instruction.table
        tag.run(table.on_complete if complete else table.on_end)
        tag.values["pending"] = False

    # -- observation --------------------------------------------------------------

    def observe(self) -> Mapping[str, Mapping[str, object]]:
        out: dict[str, Mapping[str, object]] = {}
        for name, tag in self.tags.items():
            out[name] = MappingProxyType(tag.observe())
        for name, inst in self.add_ons.items():
            out[name] = MappingProxyType(inst.observe())
        for name, axis in self.axes.items():
            out[name] = MappingProxyType(axis.observe())
        if self.ladder is not None:
            for name, fields in self.ladder.observe().items():
                out[name] = MappingProxyType(fields)
        return MappingProxyType(out)
