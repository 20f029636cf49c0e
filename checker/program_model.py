"""A ladder program with its axes as a transition system over integer vectors: the program checker's core.

Pipeline position: program IR (:mod:`statecharts.program`) + a program system
(:mod:`checker.program_system`) -> **checker.program_model** -> :mod:`checker.program_search`.

A state is a flat tuple: the number of environment events spent so far, one number
per axis (its interned axis core: configuration and chart variables), one number per
motion instruction of the program (its interned MOTION_INSTRUCTION tag part: members,
internal values, operands), then one value per slot of the program's tag database
(BOOL as ``False``/``True``; SINT, INT, DINT, LINT as integers; TIMER and COUNTER
members), the free inputs included.  It is the engine's state
(:meth:`statecharts.scan.System.snapshot` with a ladder) written as numbers, nothing
abstracted away: :meth:`ProgramModel.encode` turns an engine state into it.

One scan, the successor function, is *compiled* from the program IR into Python code
whose only identifiers are generated (``x12`` for database slot 12, ``p3`` for motion
instruction 3, ``c0`` for axis 0) and whose only literals are integers the compiler
formats itself: names, rungs and expressions of the program are data of the compiler,
never text of the generated code.  The code follows the ladder interpreter
(:mod:`statecharts.program.ladder`) instruction by instruction (the same rules, the
same order: rung-condition-in, left to right, branch legs top to bottom, every
instruction scanned also when its rung is false); a differential test
(``tests/test_program_check.py``) runs random programs on both and compares every scan.
Constant rung conditions are folded at compile time: with the free inputs of a choice
known, a false contact removes the code after it.

What a motion instruction does is not compiled: it is a *piece*, computed the first time
it is needed by the one implementation of the scan rules, :class:`statecharts.scan.System`
with :class:`checker.compile.FastAxis` axes, loaded with just the parts it reads, and
memoised: the row of a motion instruction's execution table for its rung condition
(with its checks against the axis when the row executes), and the coarse update of one
axis (tick, pending completions, queued requests in program order, the environment
event of the choice).  Axes do not interact within a scan, so the coarse update is one
piece per axis.

The environment's choices at every scan: each free BOOL input takes either value (any
combination of them may change between two scans), each free integer input one of its
listed values, and at most one environment event of the system, while fewer than the
system's ``max_events`` have happened.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from checker.compile import FastAxis
from checker.core import Intern
from statecharts import ir as spec_ir
from statecharts.diagnostics import Diagnostic, InputError
from statecharts.engine import AxisInstance
from statecharts.program.ir import (
    Branch,
    Element,
    Instruction,
    Member,
    Name,
    Number,
    Operand,
    Program,
    Reference,
    Scalar,
)
from statecharts.program.ladder import DINT_MAX, DINT_MIN, Ladder, MotionBinding, canonical
from statecharts.program.tags import INTEGER_BITS, STRUCTURES, wrap
from statecharts.scan import Done, EnvironmentEvent, Errored, Executed, ScanInputs, System, TagInstance
from statecharts.scenario import value_problem

MOTION_MEMBERS = tuple(m for m, _t in STRUCTURES["MOTION_INSTRUCTION"])

State = tuple[Any, ...]


class ProgramModelError(InputError):
    """The program uses something the program checker does not model; says where and what."""


@dataclass(frozen=True, slots=True)
class AxisSetup:
    """An axis the program is bound to, in one start."""

    name: str
    type: str
    state: str | None
    variables: tuple[tuple[str, Any], ...] = ()


@dataclass(frozen=True, slots=True)
class Start:
    """One start of the system: a label (``X_axis=Running, Y_axis=Shutdown``), axes and tag values."""

    label: str
    axes: tuple[AxisSetup, ...]
    tags: tuple[tuple[str, Scalar], ...] = ()


@dataclass(frozen=True, slots=True)
class Choice:
    """What the environment does before and during one scan."""

    writes: tuple[tuple[str, Scalar], ...]  # free input values
    event: tuple[str, str] | None  # (axis, event)
    #: (axis, variable, value): a writable chart variable set before the scan
    set: tuple[str, str, Any] | None = None
    #: a prescan pass instead of a scan (the controller to Program mode and back to Run)
    prescan: bool = False


@dataclass(frozen=True, slots=True)
class InputRule:
    """How the environment may change one free input: only in states where ``while_`` holds
    (an expression over the state before the scan; empty: always), and, when ``counted``,
    each change spends one of the run's environment changes (``max_events``)."""

    while_: str = ""
    counted: bool = False


@dataclass
class Coverage:
    """Program coverage gathered while exploring."""

    rungs_true: int = 0  # bit r: rung r's condition at its end was true in some scan
    executed: int = 0  # bit k: instruction k's rung-condition-in was true in some scan
    motion_executed: set[tuple[int, str]] = field(default_factory=set)  # (binding, axis state)
    errors: set[tuple[int, int, int, str]] = field(default_factory=set)  # (binding, ERR, EXERR, check)
    done: set[int] = field(default_factory=set)  # bindings that completed with DN


def _error(program: Program, ins: Instruction | None, rung: int | None, message: str) -> Diagnostic:
    if ins is not None:
        loc = ins.location
        return Diagnostic(loc.file or program.file, loc.line, loc.column, f"rung {rung}: instruction {ins.position}",
                          message)
    return Diagnostic(program.file, 1, 1, "", message)


#: instructions the program checker compiles (motion instructions are pieces)
SUPPORTED = ("XIC", "XIO", "OTE", "OTL", "OTU", "ONS", "OSR", "OSF", "TON", "TOF", "RTO", "CTU", "CTD", "RES",
             "EQU", "NEQ", "LES", "LEQ", "GRT", "GEQ", "LIM", "MOV", "CLR", "ADD", "SUB", "MUL", "NEG", "NOP", "AFI")


class ProgramModel:
    """The program, its axes and the environment's choices, compiled into a successor function."""

    def __init__(self, spec: spec_ir.Spec, program: Program, *, axis_types: Mapping[str, str],
                 inputs: Sequence[str] = (), int_inputs: Mapping[str, Sequence[int]] | None = None,
                 events: Mapping[str, Sequence[str]] | None = None, max_events: int = 0,
                 scan_ms: int = 10, coarse_update_ms: int | None = None, coverage: bool = True,
                 sets: Mapping[str, Mapping[str, Sequence[Any]]] | None = None,
                 input_rules: Mapping[str, InputRule] | None = None, prescan: bool = False) -> None:
        self.spec = spec
        self.program = program
        self.scan_ms = scan_ms
        coarse = coarse_update_ms or scan_ms
        if coarse != scan_ms:
            raise ProgramModelError([_error(program, None, None, (
                f"coarse_update_ms {coarse} differs from scan_ms {scan_ms}: the program checker models a coarse "
                f"update in every scan; give coarse_update_ms equal to scan_ms"))])
        self.max_events = max_events
        problems: list[Diagnostic] = []
        self.ladder = Ladder(program, scan_ms=scan_ms)
        problems.extend(self.ladder.binding_problems)
        self.db = self.ladder.db
        self.axis_names = tuple(t.name for t in program.axes())
        self.axis_types = dict(axis_types)
        for a in self.axis_names:
            if a not in self.axis_types:
                problems.append(_error(program, None, None, f"axis {a}: its type is not given"))
        if problems:
            raise ProgramModelError(problems)
        self.charts = [spec.chart_for_axis_type(self.axis_types[a]) for a in self.axis_names]
        self.axis_index = {a: i for i, a in enumerate(self.axis_names)}
        self.bindings: list[MotionBinding] = [b for b in self.ladder.bindings if b.axis in self.axis_index]
        self.binding_index = {b.tag: k for k, b in enumerate(self.bindings)}
        self.tags_of_axis = [tuple(k for k, b in enumerate(self.bindings) if b.axis == a) for a in self.axis_names]
        # the program slots of the database (MOTION_INSTRUCTION slots of used tags are the parts)
        motion_slots: set[int] = set()
        self.slot_names: dict[int, str] = {}
        self.slot_types: dict[int, str] = {}
        for name, layout in self.db.layouts.items():
            for suffix, slot, t in self.db.leaves(name):
                label = name if not suffix else (name + suffix if suffix.startswith("[") else f"{name}.{suffix}")
                if layout.data_type == "MOTION_INSTRUCTION":
                    motion_slots.add(slot)
                    continue
                self.slot_names[slot] = label
                self.slot_types[slot] = t
        self.slots = sorted(self.slot_names)
        self.naxes = len(self.axis_names)
        self.nmotion = len(self.bindings)
        self.core_pos = [1 + i for i in range(self.naxes)]
        self.part_pos = [1 + self.naxes + k for k in range(self.nmotion)]
        self.slot_pos = {s: 1 + self.naxes + self.nmotion + j for j, s in enumerate(self.slots)}
        self.width = 1 + self.naxes + self.nmotion + len(self.slots)
        for s in self.slots:
            if self.slot_types[s] == "REAL":
                problems.append(_error(program, None, None, (
                    f"tag {self.slot_names[s]} is a REAL: the program checker explores BOOL and integer tags only")))
        # the environment
        self.inputs = tuple(inputs)
        self.int_inputs = {k: tuple(int(v) for v in vs) for k, vs in (int_inputs or {}).items()}
        self.input_slots: list[int] = []
        for name in (*self.inputs, *self.int_inputs):
            try:
                slot, t, bit = self.ladder.slot(name)
            except KeyError as exc:
                problems.append(_error(program, None, None, f"free input {name}: {exc.args[0]}"))
                continue
            if bit is not None:
                problems.append(_error(program, None, None, f"free input {name}: give a BOOL or integer tag, not a bit"))
                continue
            want_bool = name in self.inputs
            if want_bool != (t == "BOOL"):
                problems.append(_error(program, None, None, (
                    f"free input {name} is a {t}: list BOOL inputs by name and integer inputs with their values")))
                continue
            self.input_slots.append(slot)
        self.events: list[tuple[int, str]] = []
        for axis, evs in (events or {}).items():
            if axis not in self.axis_index:
                problems.append(_error(program, None, None, f"events for {axis}: not an axis of the program; axes: "
                                                            f"{', '.join(self.axis_names)}"))
                continue
            chart = self.charts[self.axis_index[axis]]
            known = [e.name for e in chart.events if e.kind == "environment"]
            for ev in evs:
                if ev not in known:
                    problems.append(_error(program, None, None, (
                        f"{ev!r} is not an environment event of {chart.id} (axis {axis}); expected one of: "
                        f"{', '.join(known)}")))
                    continue
                self.events.append((self.axis_index[axis], ev))
        #: (axis index, variable, value): the chart-variable writes the environment may make
        self.sets: list[tuple[int, str, Any]] = []
        for axis, variables in (sets or {}).items():
            if axis not in self.axis_index:
                problems.append(_error(program, None, None, f"set for {axis}: not an axis of the program; axes: "
                                                            f"{', '.join(self.axis_names)}"))
                continue
            chart = self.charts[self.axis_index[axis]]
            writable = [v.name for v in chart.variables if v.writable]
            for var, vals in variables.items():
                if var not in writable:
                    problems.append(_error(program, None, None, (
                        f"{var!r} is not a writable variable of {chart.id} (axis {axis}); writable: "
                        f"{', '.join(writable) or '(none)'}")))
                    continue
                v = chart.variable(var)
                for value in vals:
                    problem = value_problem(v.type, v.domain, value)
                    if problem:
                        problems.append(_error(program, None, None, f"set {axis}.{var} = {value!r}: {problem}"))
                        continue
                    self.sets.append((self.axis_index[axis], var, value))
        self.input_rules = {k: r for k, r in (input_rules or {}).items() if r.while_ or r.counted}
        for k in self.input_rules:
            if k not in (*self.inputs, *self.int_inputs):
                problems.append(_error(program, None, None, f"input rule for {k}: not a free input of the system"))
        self.prescan_choice = prescan
        #: sets, prescans or input rules: the choices are completed by :meth:`expand`
        self.extended = bool(self.sets or self.input_rules or prescan)
        self.SET: list[dict[tuple[int, str, Any], int]] = [{} for _ in self.axis_names]
        self.PRESCAN: dict[State, State] = {}
        self._cold: System | None = None
        if problems:
            raise ProgramModelError(problems)
        values = [(False, True)] * len(self.inputs) + [self.int_inputs[n] for n in self.int_inputs]
        self.combos: list[tuple[Any, ...]] = list(itertools.product(*values)) if values else [()]
        self.nchoices = len(self.combos) * (1 + len(self.events))

        # the interning tables and the piece systems (one System per axis, FastAxis back-end)
        self.cores = [Intern() for _ in self.axis_names]
        self.parts = Intern()
        self.MV: list[tuple[Any, ...]] = []  # part id -> MOTION_INSTRUCTION members in MOTION_MEMBERS order
        self.AV: list[list[tuple[Any, ...]]] = [[] for _ in self.axis_names]  # axis core id -> readable members
        self.readable: list[tuple[str, ...]] = []
        self.piece_axes: list[FastAxis] = []
        self.piece_systems: list[System] = []
        self.piece_tags: list[TagInstance] = []
        params = {"scan_ms": scan_ms, "coarse_update_ms": coarse}
        for i, a in enumerate(self.axis_names):
            chart = self.charts[i]
            self.readable.append((chart.state_attribute,
                                  *(v.name for v in chart.variables if v.type in ("bool", "int", "real"))))
            fa = FastAxis(chart, a, parameters=params)
            one: list[Any] = [fa]  # FastAxis offers the axis interface System uses
            sysi = System(spec, one, [(self.bindings[k].tag, self.bindings[k].mnemonic, a)
                                       for k in self.tags_of_axis[i]], scan_ms=scan_ms, coarse_update_ms=coarse)
            self.piece_axes.append(fa)
            self.piece_systems.append(sysi)
        for b in self.bindings:
            self.piece_tags.append(self.piece_systems[self.axis_index[b.axis]].tags[b.tag])
        self.ROW: list[dict[tuple[int, int, bool], tuple[int, bool]]] = [{} for _ in self.bindings]
        # rows by part: (part, queued) when the row does not execute (its axis is not read), else a
        # dict by axis core; None while unknown.  Grown by part_id as parts are interned.
        self.RT: list[list[Any]] = [[] for _ in self.bindings]
        self.RF: list[list[Any]] = [[] for _ in self.bindings]
        self.OPS: list[dict[tuple[int, tuple[Any, ...]], int]] = [{} for _ in self.bindings]
        self.CO: list[dict[tuple[Any, ...], tuple[int, ...]]] = [{} for _ in self.axis_names]
        self.cov = Coverage()
        self.coverage_on = coverage
        self._last_executed = False
        self.instructions: list[tuple[int, Instruction]] = []  # (rung, instruction) in program order
        self.rung_count = 0
        source, rung_bits = _Generator(self).generate()
        self.source = source
        namespace: dict[str, Any] = {
            "MV": self.MV, "AV": self.AV, "ROW": self.ROW, "CO": self.CO, "OPS": self.OPS,
            "row": self.piece_row, "rowc": self.piece_rowc, "coarse": self.piece_coarse, "setops": self.piece_ops,
            **{f"RT{k}": self.RT[k] for k in range(len(self.bindings))},
            **{f"RF{k}": self.RF[k] for k in range(len(self.bindings))},
            "COMBOS": self.combos, "wrap": wrap, "setbit": _setbit, "fault": self._fault,
            "DINT_MAX": DINT_MAX, "DINT_MIN": DINT_MIN,
        }
        code = compile(source, "<program-checker>", "exec")
        exec(code, namespace)
        self.successors: Callable[[State], tuple[list[tuple[int, State]], int, int]] = namespace["successors"]
        self.rung_bits = rung_bits

    # -- pieces (the cold path: the scan module itself) ------------------------------------------

    def _load_core(self, i: int, core: int) -> FastAxis:
        fa = self.piece_axes[i]
        fa.restore(self.cores[i].values[core])
        return fa

    def core_id(self, i: int, snap: tuple[Any, ...]) -> int:
        cores = self.cores[i]
        n = len(cores.values)
        c = cores.id(snap)
        if c == n:
            fa = self.piece_axes[i]
            fa.restore(snap)
            obs = fa.observe()
            env = fa.env
            chart = self.charts[i]
            self.AV[i].append(tuple((fa.value or 0) if m == chart.state_attribute else env[m]
                                    for m in self.readable[i]))
            del obs
        return c

    def part_id(self, snap: tuple[Any, ...], tag: TagInstance) -> int:
        n = len(self.parts.values)
        p = self.parts.id(snap)
        if p == n:
            tag.restore(snap)
            obs = tag.observe()
            self.MV.append(tuple(obs[m] for m in MOTION_MEMBERS))
            for lst in (*self.RT, *self.RF):
                lst.append(None)
        return p

    def _facts(self, system: System, i: int) -> None:
        trace = system.trace or []
        system.trace = None
        self._last_executed = any(isinstance(rec, Executed) for rec in trace)
        if not self.coverage_on:
            return
        for rec in trace:
            k = self.binding_index[rec.tag]
            if isinstance(rec, Executed):
                self.cov.motion_executed.add((k, rec.axis_state))
            elif isinstance(rec, Errored):
                self.cov.errors.add((k, rec.err, rec.exerr, rec.check))
            elif isinstance(rec, Done):
                self.cov.done.add(k)

    def piece_row(self, k: int, p: int, c: int, r: bool) -> tuple[int, bool]:
        """Motion instruction ``k`` with tag part ``p`` on its axis in core ``c``, rung ``r``: (part, queued)."""
        b = self.bindings[k]
        i = self.axis_index[b.axis]
        system = self.piece_systems[i]
        self._load_core(i, c)
        tag = self.piece_tags[k]
        tag.restore(self.parts.values[p])
        system.queue = []
        system.trace = []
        system.motion_row(tag, "rung_true" if r else "rung_false")
        self._facts(system, i)
        queued = tag.name in system.queue
        system.queue = []
        out = (self.part_id(tag.snapshot(), tag), queued)
        self.ROW[k][(p, c, r)] = out
        return out

    def piece_rowc(self, k: int, p: int, c: int, r: bool, known: Any) -> tuple[int, bool]:
        """The row of motion instruction ``k`` by part: computed once when it does not read the axis."""
        if known is not None:
            hit: tuple[int, bool] | None = known.get(c)
            if hit is not None:
                return hit
        system = self.piece_systems[self.axis_index[self.bindings[k].axis]]
        system.trace = []
        out = self.piece_row(k, p, c, r)
        executed = self._last_executed
        table = self.RT[k] if r else self.RF[k]
        if executed:
            d = known if known is not None else {}
            d[c] = out
            table[p] = d
        else:
            table[p] = out
        return out

    def piece_ops(self, k: int, p: int, values: tuple[Any, ...]) -> int:
        """Motion instruction ``k``'s operands set from the program before its row."""
        tag = self.piece_tags[k]
        tag.restore(self.parts.values[p])
        names = [o.name for o in tag.instruction.operands if o.type not in ("axis", "tag")]
        for n, v in zip(names, values):
            tag.operands[n] = v
        out = self.part_id(tag.snapshot(), tag)
        self.OPS[k][(p, values)] = out
        return out

    def piece_coarse(self, i: int, key: tuple[Any, ...]) -> tuple[int, ...]:
        """The coarse update of axis ``i``: key (core, parts of its tags..., queued mask, event or -1)."""
        c, *parts, qmask, ev = key
        system = self.piece_systems[i]
        axis = self._load_core(i, c)
        ks = self.tags_of_axis[i]
        for k, p in zip(ks, parts):
            self.piece_tags[k].restore(self.parts.values[p])
        system.queue = [self.bindings[k].tag for j, k in enumerate(ks) if qmask >> j & 1]
        system.held_events = [EnvironmentEvent(axis.name, self.events[ev][1])] if ev >= 0 else []
        system.trace = []
        system._coarse_update()
        self._facts(system, i)
        out = (self.core_id(i, axis.snapshot()), *(self.part_id(self.piece_tags[k].snapshot(), self.piece_tags[k])
                                                   for k in ks))
        self.CO[i][key] = out
        return out

    def _fault(self, position: int, message: str) -> None:
        rung, ins = self.instructions[position]
        raise ProgramModelError([_error(self.program, ins, rung, f"major fault: {message}")])

    # -- states -------------------------------------------------------------------------------

    def encode(self, system: System) -> State:
        """The state of an engine :class:`~statecharts.scan.System` running this program, as a vector
        (the count of environment events is 0: the caller sets it)."""
        ladder = system.ladder
        assert ladder is not None
        out: list[Any] = [0]
        for i, a in enumerate(self.axis_names):
            out.append(self.core_id(i, system.axes[a].snapshot()))
        for k, b in enumerate(self.bindings):
            tag = system.tags[b.tag]
            out.append(self.part_id(tag.snapshot(), self.piece_tags[k]))
        values = ladder.db.values
        for s in self.slots:
            out.append(values[s])
        return tuple(out)

    def engine(self, start: Start) -> Any:
        """The engine (:class:`statecharts.program.Controller`, python-statemachine axes) in ``start``,
        after its set-up and prescan: what ``motionchart simulate`` runs."""
        from statecharts.program.api import Controller
        axes = {a.name: {"type": a.type, "state": a.state, "variables": dict(a.variables)} for a in start.axes}
        return Controller(self.program, axes=axes, spec=self.spec, scan_ms=self.scan_ms, tags=dict(start.tags))

    def initial(self, start: Start) -> State:
        """The state after the set-up of ``start`` and the prescan, built as the engine's
        :class:`~statecharts.program.Controller` builds it, on the checker's axis back-end."""
        params = {"scan_ms": self.scan_ms, "coarse_update_ms": self.scan_ms}
        axes: list[Any] = []  # FastAxis offers the axis interface System uses
        for a in start.axes:
            chart = self.spec.chart_for_axis_type(a.type)
            variables = dict(a.variables)
            if "AxisType" in {v.name for v in chart.variables}:
                variables.setdefault("AxisType", a.type)
            axes.append(FastAxis(chart, a.name, state=a.state, variables=variables, parameters=params))
        ladder = Ladder(self.program, scan_ms=self.scan_ms)
        system = System(self.spec, axes, [], scan_ms=self.scan_ms, coarse_update_ms=self.scan_ms, ladder=ladder)
        for path, value in start.tags:
            ladder.write(path, value)
        ladder.prescan()
        return self.encode(system)

    def choice(self, index: int) -> Choice:
        """The environment's choice number ``index``: as the successor function numbers them
        (input combination, event), then the sets (each with every input combination), then
        the prescan."""
        ncombo = len(self.combos)
        names = (*self.inputs, *self.int_inputs)
        if index >= self.nchoices:
            j = index - self.nchoices
            if j >= len(self.sets) * ncombo:
                return Choice((), None, prescan=True)
            i, var, value = self.sets[j // ncombo]
            return Choice(tuple(zip(names, self.combos[j % ncombo])), None, (self.axis_names[i], var, value))
        combo, ev = index % ncombo, index // ncombo - 1
        writes = tuple(zip(names, self.combos[combo]))
        event = None
        if ev >= 0:
            i, name = self.events[ev]
            event = (self.axis_names[i], name)
        return Choice(writes, event)

    # -- the choices the compiled scan does not make: sets and prescans (the cold path) ---------------

    def expand(self, s: State) -> tuple[list[tuple[int, State]], int, int]:
        """The successors of ``s`` with the sets and the prescan (input rules are the search's):
        what :attr:`successors` gives, then per set of a chart variable (while fewer than
        ``max_events`` changes have happened) the scans after it, then the prescan pass."""
        outs, cv, ex = self.successors(s)
        if not self.extended:
            return outs, cv, ex
        outs = list(outs)
        ncombo = len(self.combos)
        if s[0] < self.max_events:
            for j, (i, var, value) in enumerate(self.sets):
                pos = self.core_pos[i]
                c = s[pos]
                key = (c, var, value)
                c2 = self.SET[i].get(key)
                if c2 is None:
                    fa = self._load_core(i, c)
                    fa.env[var] = value
                    c2 = self.SET[i][key] = self.core_id(i, fa.snapshot())
                s2 = (s[0] + 1, *s[1:pos], c2, *s[pos + 1:])
                more, cv2, ex2 = self.successors(s2)
                cv |= cv2
                ex |= ex2
                base = self.nchoices + j * ncombo
                outs.extend((base + ch, t) for ch, t in more if ch < ncombo)
        if self.prescan_choice:
            outs.append((self.nchoices + len(self.sets) * ncombo, self.prescanned(s)))
        return outs, cv, ex

    def _system_of(self, s: State) -> System:
        """An engine system (checker axis back-end) in state ``s``."""
        if self._cold is None:
            params = {"scan_ms": self.scan_ms, "coarse_update_ms": self.scan_ms}
            axes: list[Any] = [FastAxis(c, a, parameters=params) for c, a in zip(self.charts, self.axis_names)]
            self._cold = System(self.spec, axes, [], scan_ms=self.scan_ms, coarse_update_ms=self.scan_ms,
                                ladder=Ladder(self.program, scan_ms=self.scan_ms))
        system = self._cold
        for i, a in enumerate(self.axis_names):
            system.axes[a].restore(self.cores[i].values[s[self.core_pos[i]]])
        for k, b in enumerate(self.bindings):
            system.tags[b.tag].restore(self.parts.values[s[self.part_pos[k]]])
        assert system.ladder is not None
        values = system.ladder.db.values
        for slot in self.slots:
            values[slot] = s[self.slot_pos[slot]]
        system.queue, system.held_events, system.index = [], [], 0
        return system

    def prescanned(self, s: State) -> State:
        """The state after a prescan pass from ``s`` (the scan module's own prescan, remembered)."""
        hit = self.PRESCAN.get(s)
        if hit is None:
            system = self._system_of(s)
            system.advance(ScanInputs(prescan=True))
            hit = self.PRESCAN[s] = (s[0], *self.encode(system)[1:])
        return hit

    # -- reading a state -------------------------------------------------------------------------

    def getter(self, path: str) -> Callable[[State], Any] | str:
        """A function reading ``path`` from a state vector, or why ``path`` names nothing.

        Paths: program tags (``STATE``, ``Arr[2]``, ``T1.DN``, ``Flags.3``), motion tag members
        (``X_STAT[0].DN``, ``.ERR``), axis members (``X_axis.state``, ``X_axis.CIPAxisState`` and
        the chart variables), and ``events`` (the environment events spent)."""
        if path == "events":
            return lambda s: s[0]
        head, _, member = path.rpartition(".")
        if head in self.axis_index:
            i = self.axis_index[head]
            pos = self.core_pos[i]
            cores = self.cores[i]
            chart = self.charts[i]
            if member == "state":
                cc = compiled_leaf(chart)
                return lambda s: cc(cores.values[s[pos]][0])
            if member in self.readable[i]:
                j = self.readable[i].index(member)
                av = self.AV[i]
                return lambda s: av[s[pos]][j]
            return (f"axis {head} ({chart.id}) has no member {member!r}; members: state, "
                    f"{', '.join(self.readable[i])}")
        if head in self.binding_index:
            k = self.binding_index[head]
            if member not in MOTION_MEMBERS:
                return f"{path}: a MOTION_INSTRUCTION has no member {member!r}; members: {', '.join(MOTION_MEMBERS)}"
            j = MOTION_MEMBERS.index(member)
            ppos = self.part_pos[k]
            mv = self.MV
            return lambda s: mv[s[ppos]][j]
        try:
            slot, _t, bit = self.ladder.slot(path)
        except KeyError as exc:
            return str(exc.args[0])
        if slot not in self.slot_pos:
            return f"{path} is not a program value"
        spos = self.slot_pos[slot]
        if bit is not None:
            b = bit
            return lambda s: bool((int(s[spos]) >> b) & 1)
        return lambda s: s[spos]

    def controller_part(self, s: State) -> State:
        """The state without the free inputs and the event count: what the controller holds."""
        free = {self.slot_pos[x] for x in self.input_slots}
        return tuple(v for j, v in enumerate(s) if j and j not in free)

    def program_part(self, s: State) -> State:
        """The program's tags alone (no free input, no motion tag, no axis)."""
        free = {self.slot_pos[x] for x in self.input_slots}
        first = 1 + self.naxes + self.nmotion
        return tuple(v for j, v in enumerate(s) if j >= first and j not in free)

    def waiting(self, s: State) -> bool:
        """Some motion instruction is enabled and neither done nor erred (it waits for its axis)."""
        en, dn, er = MOTION_MEMBERS.index("EN"), MOTION_MEMBERS.index("DN"), MOTION_MEMBERS.index("ER")
        for k in range(self.nmotion):
            m = self.MV[s[self.part_pos[k]]]
            if m[en] and not m[dn] and not m[er]:
                return True
        return False

    def describe(self, s: State) -> dict[str, Any]:
        """Every value of a state by its path (axes by state and members, motion tags by member)."""
        out: dict[str, Any] = {}
        for i, a in enumerate(self.axis_names):
            snap = self.cores[i].values[s[self.core_pos[i]]]
            out[f"{a}.state"] = compiled_leaf(self.charts[i])(snap[0])
            for m, v in zip(self.readable[i], self.AV[i][s[self.core_pos[i]]]):
                out[f"{a}.{m}"] = v
        for k, b in enumerate(self.bindings):
            for m, v in zip(MOTION_MEMBERS, self.MV[s[self.part_pos[k]]]):
                out[f"{b.tag}.{m}"] = v
        for slot in self.slots:
            out[self.slot_names[slot]] = s[self.slot_pos[slot]]
        return out


def compiled_leaf(chart: spec_ir.Chart) -> Callable[[frozenset[str]], str]:
    from checker.compile import compiled
    cc = compiled(chart)
    return lambda config: cc.leaf(config).id


def _setbit(word: int, bit: int, value: bool, width: int) -> int:
    word = int(word)
    return wrap(word | (1 << bit) if value else word & ~(1 << bit), width)


def axis_instances(spec: spec_ir.Spec, start: Start, scan_ms: int) -> list[AxisInstance]:
    params = {"scan_ms": scan_ms, "coarse_update_ms": scan_ms}
    return [AxisInstance(spec.chart_for_axis_type(a.type), a.name, state=a.state, variables=dict(a.variables),
                         parameters=params) for a in start.axes]


# --------------------------------------------------------------------------- the code generator


class _Unsupported(Exception):
    pass


Cond = bool | str  # a rung condition known at compile time, or the local variable holding it


class _Generator:
    """Writes the successor function of a :class:`ProgramModel` as Python text.

    Identifiers: ``x<slot>`` database slots, ``p<k>`` motion tag parts, ``c<i>`` axis
    cores, ``q<i>`` queued masks, ``r<n>`` rung conditions, ``t<n>`` temporaries; every
    literal is an ``int`` formatted with ``%d``.  The function body, for each input
    combination (``COMBOS``), writes the inputs, runs every rung, composes the coarse
    update pieces and appends the successors."""

    def __init__(self, model: ProgramModel) -> None:
        self.m = model
        self.lines: list[str] = []
        self.indent = 2
        self.n = 0
        self.problems: list[Diagnostic] = []
        self.rung = 0
        self.position = 0
        self.combo: tuple[Any, ...] = ()
        self.input_value: dict[int, Any] = {}
        self.coverage: dict[str, dict[str, int]] = {}

    def emit(self, line: str) -> None:
        self.lines.append("    " * self.indent + line)

    def var(self, prefix: str = "r") -> str:
        self.n += 1
        return f"{prefix}{self.n}"

    def generate(self) -> tuple[str, int]:
        m = self.m
        names = ["e", *(f"c{i}" for i in range(m.naxes)), *(f"p{k}" for k in range(m.nmotion)),
                 *(f"x{s}" for s in m.slots)]
        head = ["def successors(s):", "    " + ", ".join(names) + (", = s" if len(names) == 1 else " = s"),
                "    out = []", "    cv = 0", "    ex = 0"]
        self.lines = []
        # one specialised body per input combination: constants fold
        routine = m.program.routine(m.program.main)
        for ci, combo in enumerate(m.combos):
            self.indent = 1
            self.emit(f"# input combination {ci:d}")
            self.input_value = dict(zip(m.input_slots, combo))
            self.indent = 1
            self.emit("if True:")
            self.indent = 2
            for k in range(m.nmotion):
                self.emit(f"P{k} = p{k}")
            for i in range(m.naxes):
                self.emit(f"q{i} = 0")
            for s in m.slots:
                if s in self.input_value:
                    self.emit(f"X{s} = {_lit(self.input_value[s])}")
                else:
                    self.emit(f"X{s} = x{s}")
            self.position = 0
            m.instructions = []
            for rung in routine.rungs:
                self.rung = rung.number
                rc: Cond = True
                for e in rung.elements:
                    rc = self.element(e, rc)
                if m.coverage_on:
                    self.cover(rc, "cv", rung.number)
            m.rung_count = len(routine.rungs)
            self.flush()
            self.finish(ci)
        for r in m.program.routines:
            if r.name != m.program.main:
                self.problems.append(_error(m.program, None, None, (
                    f"routine {r.name}: the program checker scans the main routine only (JSR is not modelled)")))
        if self.problems:
            raise ProgramModelError(self.problems)
        tail = ["    return out, cv, ex"]
        return "\n".join(head + self.lines + tail) + "\n", m.rung_count

    def cover(self, rc: Cond, acc: str, bit: int) -> None:
        """Note that ``bit`` of ``acc`` is set when ``rc`` holds (emitted once per condition by :meth:`flush`)."""
        if rc is False:
            return
        masks = self.coverage.setdefault(acc, {})
        masks[str(rc)] = masks.get(str(rc), 0) | (1 << bit)

    def flush(self) -> None:
        for acc, masks in self.coverage.items():
            for rc, mask in masks.items():
                self.emit(f"{acc} |= {mask:d}" if rc == "True" else f"if {rc}: {acc} |= {mask:d}")
        self.coverage = {}

    def finish(self, ci: int) -> None:
        m = self.m
        ncombo = len(m.combos)
        # the coarse update of every axis, no event
        for i in range(m.naxes):
            ks = m.tags_of_axis[i]
            key = ", ".join([f"c{i}", *(f"P{k}" for k in ks), f"q{i}", "-1"])
            self.emit(f"k{i} = ({key},)")
            names = ", ".join([f"C{i}", *(f"Q{k}" for k in ks)])
            self.emit(f"{names}, = CO[{i:d}].get(k{i}) or coarse({i:d}, k{i})")
        parts_of: dict[int, str] = {}
        for i in range(m.naxes):
            for k in m.tags_of_axis[i]:
                parts_of[k] = f"Q{k}"
        slots = ", ".join(f"X{s}" for s in m.slots)
        cores = [f"C{i}" for i in range(m.naxes)]
        parts = [parts_of[k] for k in range(m.nmotion)]

        def vector(ev: str, cores: list[str], parts: list[str]) -> str:
            items = [ev, *cores, *parts] + ([slots] if slots else [])
            return "(" + ", ".join(items) + ",)"
        self.emit(f"out.append(({ci:d}, {vector('e', cores, parts)}))")
        if m.events:
            self.emit(f"if e < {m.max_events:d}:")
            self.indent += 1
            for ev, (i, _name) in enumerate(m.events):
                ks = m.tags_of_axis[i]
                key = ", ".join([f"c{i}", *(f"P{k}" for k in ks), f"q{i}", f"{ev:d}"])
                self.emit(f"kk = ({key},)")
                self.emit(f"oo = CO[{i:d}].get(kk) or coarse({i:d}, kk)")
                c2 = list(cores)
                c2[i] = "oo[0]"
                p2 = list(parts)
                for j, k in enumerate(ks):
                    p2[k] = f"oo[{j + 1:d}]"
                self.emit(f"out.append(({ci + (ev + 1) * ncombo:d}, {vector('e + 1', c2, p2)}))")
            self.indent -= 1

    # -- elements ---------------------------------------------------------------------------------

    def element(self, e: Element, rc: Cond) -> Cond:
        if isinstance(e, Branch):
            outs: list[Cond] = []
            for leg in e.legs:
                r = rc
                for x in leg:
                    r = self.element(x, r)
                outs.append(r)
            if any(o is True for o in outs):
                return True
            live = [o for o in outs if o is not False]
            if not live:
                return False
            if len(live) == 1:
                return live[0]
            v = self.var()
            self.emit(f"{v} = {' or '.join(str(o) for o in live)}")
            return v
        return self.instruction(e, rc)

    def fresh(self, expr: str) -> str:
        v = self.var()
        self.emit(f"{v} = {expr}")
        return v

    def instruction(self, ins: Instruction, rc: Cond) -> Cond:
        m = self.m
        position = self.position
        self.position += 1
        m.instructions.append((self.rung, ins))
        if m.coverage_on:
            self.cover(rc, "ex", position)
        mn = ins.mnemonic
        try:
            if mn in _motion_mnemonics():
                return self.motion(ins, rc)
            if mn not in SUPPORTED:
                raise _Unsupported(f"{mn} is not modelled by the program checker; it models "
                                   f"{', '.join(SUPPORTED)} and the motion instructions")
            out: Cond = getattr(self, f"i_{mn}")(ins, rc)
            return out
        except _Unsupported as exc:
            self.problems.append(_error(m.program, ins, self.rung, str(exc)))
            return rc

    # operands ---------------------------------------------------------------------------------

    def resolve(self, op: Operand) -> tuple[str, Any, Any]:
        """("const", value, None) | ("slot", slot, bit) | ("motion", k, member) | ("axis", i, j)."""
        m = self.m
        if isinstance(op, Number):
            if not isinstance(op.value, int) or isinstance(op.value, bool):
                raise _Unsupported(f"{op.text or op.value}: the program checker models integer values only")
            return "const", int(op.value), None
        if not isinstance(op, Reference):
            raise _Unsupported(f"operand {op} is not modelled by the program checker (a tag or an integer)")
        if not op.constant:
            raise _Unsupported(f"{op}: computed subscripts are not modelled by the program checker")
        if op.base in m.axis_index:
            i = m.axis_index[op.base]
            if len(op.selectors) != 1 or not isinstance(op.selectors[0], Member):
                raise _Unsupported(f"{op}: read one member of axis {op.base}")
            name = op.selectors[0].name
            if name not in m.readable[i]:
                raise _Unsupported(f"{op}: axis {op.base} has no readable member {name!r}; readable members: "
                                   f"{', '.join(m.readable[i])}")
            return "axis", i, m.readable[i].index(name)
        layout = m.db.layouts.get(op.base)
        if layout is None:
            raise _Unsupported(f"undefined tag {op.base!r}")
        if layout.data_type == "MOTION_INSTRUCTION":
            sels = op.selectors
            if not sels or not isinstance(sels[-1], Member) or sels[-1].name not in MOTION_MEMBERS:
                raise _Unsupported(f"{op}: read a member of the MOTION_INSTRUCTION tag ({', '.join(MOTION_MEMBERS)})")
            element = canonical(Reference(op.base, tuple(sels[:-1])))
            member = MOTION_MEMBERS.index(sels[-1].name)
            if element not in m.binding_index:
                return "const", 0 if sels[-1].name not in ("EN", "DN", "ER", "PC", "IP") else False, None
            return "motion", m.binding_index[element], member
        try:
            slot, _t, bit = m.ladder.slot(str(op))
        except KeyError as exc:
            raise _Unsupported(str(exc.args[0])) from None
        return "slot", slot, bit

    def read(self, op: Operand) -> str:
        kind, a, b = self.resolve(op)
        if kind == "const":
            return _lit(a)
        if kind == "motion":
            return f"MV[P{a:d}][{b:d}]"
        if kind == "axis":
            return f"AV[{a:d}][c{a:d}][{b:d}]"
        if a in self.input_value and b is None:
            return _lit(self.input_value[a])
        if b is not None:
            return f"((X{a:d} >> {b:d}) & 1 == 1)"
        return f"X{a:d}"

    def constant(self, op: Operand) -> Any:
        """The value of ``op`` when it is known at compile time (an immediate or this combination's input)."""
        kind, a, b = self.resolve(op)
        if kind == "const":
            return a
        if kind == "slot" and b is None and a in self.input_value:
            return self.input_value[a]
        return None

    def write_bool(self, op: Operand, value: str) -> None:
        kind, a, b = self.resolve(op)
        if kind != "slot":
            raise _Unsupported(f"{op} cannot be written by the program")
        t = self.m.slot_types[a]
        if b is not None:
            self.emit(f"X{a:d} = setbit(X{a:d}, {b:d}, {value}, {INTEGER_BITS[t]:d})")
            return
        if t != "BOOL":
            raise _Unsupported(f"{op} is a {t}; the instruction writes a BOOL")
        self.emit(f"X{a:d} = {value}")

    def dest(self, op: Operand) -> tuple[int, str]:
        kind, a, b = self.resolve(op)
        if kind != "slot" or b is not None:
            raise _Unsupported(f"{op} cannot be the destination")
        t = self.m.slot_types[a]
        if t not in INTEGER_BITS:
            raise _Unsupported(f"{op} is a {t}; the program checker models integer destinations only")
        return a, t

    def bool_expr(self, op: Operand) -> str:
        kind, a, b = self.resolve(op)
        if kind == "slot" and b is None and self.m.slot_types[a] != "BOOL":
            raise _Unsupported(f"{op} is a {self.m.slot_types[a]}; the instruction examines a BOOL")
        return self.read(op)

    # instructions -------------------------------------------------------------------------------

    def guarded(self, rc: Cond) -> bool:
        """Open ``if rc:`` (returns True) unless rc is a constant; False when the body never runs."""
        if rc is False:
            return False
        if rc is True:
            self.emit("if True:")
        else:
            self.emit(f"if {rc}:")
        self.indent += 1
        return True

    def close(self) -> None:
        self.indent -= 1

    def i_XIC(self, ins: Instruction, rc: Cond) -> Cond:
        v = self.bool_expr(ins.operands[0])
        known = self.constant(ins.operands[0])
        if rc is False:
            return False
        if known is not None:
            return rc if known else False
        if rc is True:
            return self.fresh(v)
        return self.fresh(f"{rc} and {v}")

    def i_XIO(self, ins: Instruction, rc: Cond) -> Cond:
        v = self.bool_expr(ins.operands[0])
        known = self.constant(ins.operands[0])
        if rc is False:
            return False
        if known is not None:
            return False if known else rc
        if rc is True:
            return self.fresh(f"not {v}")
        return self.fresh(f"{rc} and not {v}")

    def i_OTE(self, ins: Instruction, rc: Cond) -> Cond:
        self.write_bool(ins.operands[0], str(rc))
        return rc

    def i_OTL(self, ins: Instruction, rc: Cond) -> Cond:
        if self.guarded(rc):
            self.write_bool(ins.operands[0], "True")
            self.close()
        else:
            self.resolve(ins.operands[0])
        return rc

    def i_OTU(self, ins: Instruction, rc: Cond) -> Cond:
        if self.guarded(rc):
            self.write_bool(ins.operands[0], "False")
            self.close()
        else:
            self.resolve(ins.operands[0])
        return rc

    def i_ONS(self, ins: Instruction, rc: Cond) -> Cond:
        # out = rci and not storage; storage = rci  (RM003N p103, as the interpreter)
        s = self.bool_expr(ins.operands[0])
        if rc is False:
            self.write_bool(ins.operands[0], "False")
            return False
        out = self.fresh(f"not {s}" if rc is True else f"{rc} and not {s}")
        self.write_bool(ins.operands[0], str(rc))
        return out

    def i_OSR(self, ins: Instruction, rc: Cond) -> Cond:
        s = self.bool_expr(ins.operands[0])
        out = "False" if rc is False else self.fresh(f"not {s}" if rc is True else f"{rc} and not {s}")
        self.write_bool(ins.operands[0], str(rc))
        self.write_bool(ins.operands[1], out)
        return rc

    def i_OSF(self, ins: Instruction, rc: Cond) -> Cond:
        s = self.bool_expr(ins.operands[0])
        out = "False" if rc is True else self.fresh(s if rc is False else f"(not {rc}) and {s}")
        self.write_bool(ins.operands[1], out)
        self.write_bool(ins.operands[0], str(rc))
        return rc

    def structure(self, op: Operand, kinds: tuple[str, ...]) -> tuple[int, str]:
        if not isinstance(op, Reference) or op.base not in self.m.db.layouts or not op.constant:
            raise _Unsupported(f"{op}: expected a {' or '.join(kinds)} tag with immediate subscripts")
        layout = self.m.db.layouts[op.base]
        if layout.data_type not in kinds:
            raise _Unsupported(f"{op} is a {layout.data_type}; a {' or '.join(kinds)} is needed")
        try:
            slot, _t, _bit = self.m.ladder.slot(f"{op}.PRE")
        except KeyError as exc:
            raise _Unsupported(str(exc.args[0])) from None
        return slot, layout.data_type

    def timer(self, ins: Instruction, rc: Cond, kind: str) -> Cond:
        b, _t = self.structure(ins.operands[0], ("TIMER",))
        pre, acc, en, tt, dn = (f"X{b + j:d}" for j in range(5))
        dt = self.m.scan_ms
        pos = self.position - 1

        def check() -> None:
            self.emit(f"if {pre} < 0 or {acc} < 0: fault({pos:d}, 'negative timer preset or accumulator')")

        def timing() -> None:
            self.emit(f"if not {dn}:")
            self.indent += 1
            self.emit(f"if not {en}:")
            self.emit(f"    {en} = True; {tt} = True")
            self.emit("else:")
            self.emit(f"    {acc} = {acc} + {dt:d}")
            self.emit(f"    if {acc} > DINT_MAX: {acc} = DINT_MAX")
            self.emit(f"    if {acc} >= {pre}: {dn} = True; {tt} = False")
            self.emit(f"    else: {tt} = True")
            self.indent -= 1

        def when(cond: Cond, body: Callable[[], None], other: Callable[[], None]) -> None:
            if cond is True:
                body()
            elif cond is False:
                other()
            else:
                self.emit(f"if {cond}:")
                self.indent += 1
                body()
                self.indent -= 1
                self.emit("else:")
                self.indent += 1
                other()
                self.indent -= 1

        if kind == "TON":
            def ton_on() -> None:
                check()
                timing()

            def ton_off() -> None:
                self.emit(f"{en} = False; {tt} = False; {dn} = False; {acc} = 0")
            when(rc, ton_on, ton_off)
        elif kind == "RTO":
            def rto_on() -> None:
                check()
                timing()

            def rto_off() -> None:
                self.emit(f"{en} = False; {tt} = False")
            when(rc, rto_on, rto_off)
        else:
            def tof_on() -> None:
                self.emit(f"{en} = True; {tt} = False; {dn} = True; {acc} = 0")

            def tof_off() -> None:
                check()
                self.emit(f"if not {dn}: {en} = False")
                self.emit(f"elif {en}: {en} = False; {tt} = True")
                self.emit("else:")
                self.emit(f"    {acc} = {acc} + {dt:d}")
                self.emit(f"    if {acc} > DINT_MAX: {acc} = DINT_MAX")
                self.emit(f"    if {acc} >= {pre}: {dn} = False; {tt} = False")
                self.emit(f"    else: {tt} = True")
            when(rc, tof_on, tof_off)
        return rc

    def i_TON(self, ins: Instruction, rc: Cond) -> Cond:
        return self.timer(ins, rc, "TON")

    def i_TOF(self, ins: Instruction, rc: Cond) -> Cond:
        return self.timer(ins, rc, "TOF")

    def i_RTO(self, ins: Instruction, rc: Cond) -> Cond:
        return self.timer(ins, rc, "RTO")

    def counter(self, ins: Instruction, rc: Cond, up: bool) -> Cond:
        b, _t = self.structure(ins.operands[0], ("COUNTER",))
        pre, acc, cu, cd, dn, ov, un = (f"X{b + j:d}" for j in range(7))
        edge = cu if up else cd
        same, other = (ov, un) if up else (un, ov)
        if rc is False:
            self.emit(f"{edge} = False")
            return rc
        if rc is not True:
            self.emit(f"if not {rc}: {edge} = False")
            self.emit("else:")
        else:
            self.emit("if True:")
        self.indent += 1
        self.emit(f"if not {edge}:")
        self.emit(f"    {edge} = True")
        self.emit(f"    t = {acc} {'+' if up else '-'} 1")
        self.emit("    if t > DINT_MAX or t < DINT_MIN:")
        self.emit("        t = wrap(t, 32)")
        self.emit(f"        if {other}: {other} = False")
        self.emit(f"        else: {same} = True")
        self.emit(f"    {acc} = t")
        self.emit(f"if {ov} or {un}: {dn} = False")
        self.emit(f"else: {dn} = {acc} >= {pre}")
        self.indent -= 1
        return rc

    def i_CTU(self, ins: Instruction, rc: Cond) -> Cond:
        return self.counter(ins, rc, True)

    def i_CTD(self, ins: Instruction, rc: Cond) -> Cond:
        return self.counter(ins, rc, False)

    def i_RES(self, ins: Instruction, rc: Cond) -> Cond:
        b, t = self.structure(ins.operands[0], ("TIMER", "COUNTER"))
        bits = (2, 3, 4) if t == "TIMER" else (2, 3, 4, 5, 6)
        if self.guarded(rc):
            self.emit(f"X{b + 1:d} = 0; " + "; ".join(f"X{b + k:d} = False" for k in bits))
            self.close()
        return rc

    def compare(self, ins: Instruction, rc: Cond, op: str) -> Cond:
        a, b = self.read(ins.operands[0]), self.read(ins.operands[1])
        if rc is False:
            return False
        ka, kb = self.constant(ins.operands[0]), self.constant(ins.operands[1])
        if ka is not None and kb is not None:
            known = {"==": ka == kb, "!=": ka != kb, "<": ka < kb, "<=": ka <= kb, ">": ka > kb, ">=": ka >= kb}[op]
            return rc if known else False
        test = f"({a} {op} {b})"
        return self.fresh(test if rc is True else f"{rc} and {test}")

    def i_EQU(self, ins: Instruction, rc: Cond) -> Cond:
        return self.compare(ins, rc, "==")

    def i_NEQ(self, ins: Instruction, rc: Cond) -> Cond:
        return self.compare(ins, rc, "!=")

    def i_LES(self, ins: Instruction, rc: Cond) -> Cond:
        return self.compare(ins, rc, "<")

    def i_LEQ(self, ins: Instruction, rc: Cond) -> Cond:
        return self.compare(ins, rc, "<=")

    def i_GRT(self, ins: Instruction, rc: Cond) -> Cond:
        return self.compare(ins, rc, ">")

    def i_GEQ(self, ins: Instruction, rc: Cond) -> Cond:
        return self.compare(ins, rc, ">=")

    def i_LIM(self, ins: Instruction, rc: Cond) -> Cond:
        lo, t, hi = (self.read(o) for o in ins.operands)
        if rc is False:
            return False
        test = f"(({lo} <= {t} <= {hi}) if {lo} <= {hi} else ({t} >= {lo} or {t} <= {hi}))"
        return self.fresh(test if rc is True else f"{rc} and {test}")

    def store(self, dst: Operand, value: str, rc: Cond, *, same_width: bool = False) -> None:
        slot, t = self.dest(dst)
        if self.guarded(rc):
            if same_width:
                self.emit(f"X{slot:d} = {value}")
            else:
                self.emit(f"X{slot:d} = wrap(int({value}), {INTEGER_BITS[t]:d})")
            self.close()

    def source_same_width(self, src: Operand, dst: Operand) -> bool:
        kind, a, b = self.resolve(src)
        _slot, t = self.dest(dst)
        if kind == "const":
            return bool(wrap(a, INTEGER_BITS[t]) == a)
        if kind == "slot" and b is None:
            st = self.m.slot_types[a]
            return st in INTEGER_BITS and INTEGER_BITS[st] <= INTEGER_BITS[t]
        return False

    def i_MOV(self, ins: Instruction, rc: Cond) -> Cond:
        src, dst = ins.operands[0], ins.operands[1]
        self.store(dst, self.read(src), rc, same_width=self.source_same_width(src, dst))
        return rc

    def i_CLR(self, ins: Instruction, rc: Cond) -> Cond:
        self.store(ins.operands[0], "0", rc, same_width=True)
        return rc

    def arith(self, ins: Instruction, rc: Cond, op: str) -> Cond:
        a, b = self.read(ins.operands[0]), self.read(ins.operands[1])
        self.store(ins.operands[2], f"({a} {op} {b})", rc)
        return rc

    def i_ADD(self, ins: Instruction, rc: Cond) -> Cond:
        return self.arith(ins, rc, "+")

    def i_SUB(self, ins: Instruction, rc: Cond) -> Cond:
        return self.arith(ins, rc, "-")

    def i_MUL(self, ins: Instruction, rc: Cond) -> Cond:
        return self.arith(ins, rc, "*")

    def i_NEG(self, ins: Instruction, rc: Cond) -> Cond:
        self.store(ins.operands[1], f"(-{self.read(ins.operands[0])})", rc)
        return rc

    def i_NOP(self, ins: Instruction, rc: Cond) -> Cond:
        return rc

    def i_AFI(self, ins: Instruction, rc: Cond) -> Cond:
        return False

    def motion(self, ins: Instruction, rc: Cond) -> Cond:
        m = self.m
        axis, tagref = ins.operands[0], ins.operands[1]
        if not isinstance(axis, Reference) or axis.base not in m.axis_index:
            raise _Unsupported(f"{ins.mnemonic}: the first operand must be an axis of the program")
        if not isinstance(tagref, Reference) or canonical(tagref) not in m.binding_index:
            raise _Unsupported(f"{ins.mnemonic}: the second operand must be its own MOTION_INSTRUCTION tag")
        k = m.binding_index[canonical(tagref)]
        i = m.axis_index[axis.base]
        operands = ins.operands[2:]
        if operands:
            tag = m.piece_tags[k]
            spec_ops = [o for o in tag.instruction.operands if o.type not in ("axis", "tag")]
            values: list[str] = []
            for spec_op, op in zip(spec_ops, operands):
                if isinstance(op, Name):
                    table = dict(spec_op.text_values)
                    if op.text not in table:
                        raise _Unsupported(f"{op.text!r} is not a value of {spec_op.name}; values: {', '.join(table)}")
                    v = table[op.text]
                    if isinstance(v, bool) or not isinstance(v, int):
                        raise _Unsupported(f"{spec_op.name} = {op.text}: integer operand values only")
                    values.append(_lit(v))
                else:
                    values.append(self.read(op))
            if values:
                self.emit(f"t = ({', '.join(values)},)")
                self.emit(f"P{k} = OPS[{k:d}].get((P{k}, t)) or setops({k:d}, P{k}, t)")
        j = m.tags_of_axis[i].index(k)
        if rc is True or rc is False:
            tname = f"RT{k:d}" if rc else f"RF{k:d}"
            self.emit(f"t = {tname}[P{k}]")
            cond = "True" if rc else "False"
        else:
            self.emit(f"t = RT{k:d}[P{k}] if {rc} else RF{k:d}[P{k}]")
            cond = rc
        self.emit("if t.__class__ is not tuple:")
        self.emit(f"    t = (t and t.get(c{i})) or rowc({k:d}, P{k}, c{i}, {cond}, t)")
        self.emit(f"P{k}, tq = t")
        self.emit(f"if tq: q{i} |= {1 << j:d}")
        return rc


def _lit(value: Any) -> str:
    if isinstance(value, bool):
        return "True" if value else "False"
    if isinstance(value, int):
        return f"{int(value):d}"
    raise _Unsupported(f"value {value!r}: the program checker models BOOL and integer values only")


def _motion_mnemonics() -> tuple[str, ...]:
    from statecharts.program.table import instruction_table
    return tuple(instruction_table().motion)


# --------------------------------------------------------------------------- integer domains


@dataclass(frozen=True, slots=True)
class Domain:
    """The values an integer tag can take, as computed from the program: a finite set, or open."""

    path: str
    values: frozenset[int] | None  # None: open (arithmetic or a counter writes it)
    why: str = ""  # what makes it open, or how it was computed

    def text(self) -> str:
        if self.values is None:
            return f"{self.path}: open ({self.why})"
        vs = sorted(self.values)
        if len(vs) > 6 and all(b - a == vs[1] - vs[0] for a, b in itertools.pairwise(vs)):
            return f"{self.path}: {vs[0]}..{vs[-1]} in steps of {vs[1] - vs[0]} ({self.why})" if self.why else \
                f"{self.path}: {vs[0]}..{vs[-1]} in steps of {vs[1] - vs[0]}"
        return f"{self.path}: {{{', '.join(map(str, vs))}}}" + (f" ({self.why})" if self.why else "")


def static_domains(model: ProgramModel, initial: Mapping[str, Any] | None = None) -> list[Domain]:
    """Integer domains computed from the program: the initial value, the constants and tags moved
    into a tag (MOV, CLR, RES), the listed values of an integer input; a timer's accumulator
    counted in scans up to its preset; open when arithmetic (ADD, SUB, MUL, NEG) or a counter
    writes the tag."""
    from statecharts.program.tags import convert
    names = model.slot_names
    values: dict[int, set[int]] = {}
    open_: dict[int, str] = {}
    moves: list[tuple[int, int]] = []  # (source slot, destination slot)
    written_pre: set[int] = set()
    start = dict(initial or {})
    for s in model.slots:
        t = model.slot_types[s]
        if t not in INTEGER_BITS:
            continue
        # the value the set-up gives it (written before the prescan), else its initial value
        v = start[names[s]] if names[s] in start else model.db.initial[s]
        values[s] = {int(convert(t, v))}
    for name, vs in model.int_inputs.items():
        slot = model.ladder.slot(name)[0]
        values.setdefault(slot, set()).update(vs)
    timers: list[tuple[int, str]] = []
    for rung, ins in model.instructions:
        mn, ops = ins.mnemonic, ins.operands

        def slot_of(op: Operand) -> int | None:
            if isinstance(op, Reference) and op.constant and op.base in model.db.layouts:
                try:
                    return model.ladder.slot(str(op))[0]
                except KeyError:
                    return None
            return None
        if mn == "MOV":
            d = slot_of(ops[1])
            if d is None or d not in values:
                continue
            if isinstance(ops[0], Number) and isinstance(ops[0].value, int):
                values[d].add(int(convert(model.slot_types[d], ops[0].value)))
            else:
                src = slot_of(ops[0])
                if src is not None and src in values:
                    moves.append((src, d))
                else:
                    open_[d] = f"MOV from {ops[0]} in rung {rung}"
        elif mn == "CLR":
            d = slot_of(ops[0])
            if d is not None and d in values:
                values[d].add(0)
        elif mn in ("ADD", "SUB", "MUL", "NEG"):
            d = slot_of(ops[-1])
            if d is not None:
                open_.setdefault(d, f"{mn} in rung {rung}")
        elif mn in ("CTU", "CTD") and isinstance(ops[0], Reference):
            try:
                b = model.ladder.slot(f"{ops[0]}.PRE")[0]
            except KeyError:
                continue
            open_.setdefault(b + 1, f"{mn} in rung {rung}")
        elif mn in ("TON", "TOF", "RTO") and isinstance(ops[0], Reference):
            try:
                b = model.ladder.slot(f"{ops[0]}.PRE")[0]
            except KeyError:
                continue
            timers.append((b, f"{mn} in rung {rung}"))
        for op in ops:
            if mn in ("MOV", "CLR") and op is ops[-1]:
                d = slot_of(op)
                if d is not None and names.get(d, "").endswith(".PRE"):
                    written_pre.add(d)
    changed = True
    while changed:
        changed = False
        for src, d in moves:
            if src in open_ and d not in open_:
                open_[d] = f"MOV from the open {names[src]}"
                changed = True
            new = values[src] - values[d]
            if new:
                values[d] |= new
                changed = True
    out = []
    dt = model.scan_ms
    for b, why in timers:
        acc = b + 1
        if b in written_pre or b in open_ or len(values.get(b, ())) != 1:
            open_.setdefault(acc, f"{why}, with a preset the program changes")
            continue
        pre = next(iter(values[b]))
        top = max(0, -(-pre // dt) * dt)
        values[acc] = values.get(acc, set()) | set(range(0, top + 1, dt))
        values[acc] = {v for v in values[acc] if v % dt == 0 or v == 0}
        open_.pop(acc, None)
        out_why = f"counted in scans of {dt} ms up to the preset {pre}"
        out.append(Domain(names[acc], frozenset(values[acc]), out_why))
    done = {d.path for d in out}
    for s in sorted(values):
        if names[s] in done:
            continue
        if s in open_:
            out.append(Domain(names[s], None, open_[s]))
        else:
            out.append(Domain(names[s], frozenset(values[s])))
    return sorted(out, key=lambda d: d.path)
