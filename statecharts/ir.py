"""The frozen, typed intermediate representation (IR) of a motionchart specification.

Pipeline position: ``spec/*.yaml`` -> :mod:`statecharts.loader` -> **IR** -> engine,
checker, renderers.  Every consumer downstream of the loader reads these records and
nothing else; no module below the loader ever sees YAML.

Records are small frozen slotted dataclasses.  Collections are tuples (ordered, as in
the spec) so that the IR is hashable and generated artefacts are deterministic.
Expressions are already parsed and compiled (see :mod:`statecharts.expr`); their
source text is kept for documentation.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from statecharts.expr import Assignment, Expr


class Confidence(enum.Enum):
    """Confidence marks of ``shared/reference/domain-facts.md``."""

    CONFIRMED = "C"  # read in a vendor manual page
    THIRD_PARTY = "C3"  # confirmed by a third-party source only
    INFERRED = "I"  # follows from confirmed facts or sibling instructions
    UNCERTAIN = "U"  # weak hint or conflicting sources


class StateKind(enum.Enum):
    ATOMIC = "atomic"
    COMPOUND = "compound"
    PARALLEL = "parallel"
    HISTORY = "history"
    FINAL = "final"


class ChartKind(enum.Enum):
    AXIS = "axis"
    HANDLER = "handler"  # a device handler an add-on instruction is given


class Stage(enum.Enum):
    """When an instruction's precondition check is evaluated."""

    EXECUTE = "execute"  # in the scan, when the instruction executes
    MESSAGE = "message"  # at the coarse update, when the axis answers the request


@dataclass(frozen=True, slots=True)
class Location:
    """Where an element was written: file, 1-based line and column, node path."""

    file: str
    line: int
    column: int
    path: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}: {self.path}"


@dataclass(frozen=True, slots=True)
class Provenance:
    """The documentary basis of an element: a citation and, where we chose, why."""

    source: str
    interpretation: str | None = None  # id of an Interpretation, e.g. "INT-007"


@dataclass(frozen=True, slots=True)
class Interpretation:
    """A choice made where the documents are silent, garbled or contradictory."""

    id: str
    title: str
    text: str
    confidence: Confidence
    evidence: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class DocumentedValue:
    """One documented value of a variable (a status code): what it means and where it is documented."""

    value: bool | int | str
    meaning: str
    confidence: Confidence
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class Variable:
    """A typed variable with a finite domain (``None`` domain means unbounded real)."""

    name: str
    type: str  # "bool" | "int" | "enum" | "real"
    initial: bool | int | float | str
    domain: tuple[bool | int | str, ...] | None
    description: str
    provenance: Provenance
    location: Location
    #: a program may write it (SSV), so a scenario step may ``set:`` it
    writable: bool = False
    #: documented values (status codes) with their meanings, in spec order
    values: tuple[DocumentedValue, ...] = ()


@dataclass(frozen=True, slots=True)
class State:
    id: str
    name: str
    kind: StateKind
    value: int | None
    parent: str | None
    children: tuple[str, ...]
    initial: str | None  # id of the initial child (compound states)
    history_type: str | None  # "shallow" | "deep" for history pseudo-states
    entry: tuple[Assignment, ...]
    exit: tuple[Assignment, ...]
    description: str
    provenance: Provenance
    location: Location
    #: drive-model values an axis set up in this state has (scenario set-ups apply them)
    implies: tuple[tuple[str, object], ...] = ()


@dataclass(frozen=True, slots=True)
class Transition:
    id: str
    source: str
    target: str | None  # None: targetless (actions only, no exit/entry)
    event: str | None  # None: eventless (taken as soon as the guard holds)
    guard: Expr | None
    actions: tuple[Assignment, ...]
    priority: int  # lower is tried first among transitions of one state and event
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class Event:
    name: str
    kind: str  # "request" (from an instruction) | "environment" | "clock" | "drive"
    description: str
    parameters: tuple[str, ...]
    actions: tuple[Assignment, ...]  # drive-model changes applied before the chart sees it
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class Chart:
    id: str
    name: str
    kind: ChartKind
    state_attribute: str  # the axis attribute holding the active state's value
    axis_types: tuple[str, ...]
    variables: tuple[Variable, ...]
    events: tuple[Event, ...]
    states: tuple[State, ...]
    transitions: tuple[Transition, ...]
    root_initial: str
    description: str
    provenance: Provenance
    location: Location
    #: "motion": the chart carries the variables of the drive model of
    #: :mod:`statecharts.drive`, which advances them at every coarse update
    drive_model: str | None = None
    #: instance parameters (configuration of each instance, given in a set-up)
    parameters: tuple[ChartParameter, ...] = ()

    def state(self, state_id: str) -> State:
        for s in self.states:
            if s.id == state_id:
                return s
        raise KeyError(state_id)

    def variable(self, name: str) -> Variable:
        for v in self.variables:
            if v.name == name:
                return v
        raise KeyError(name)

    def ancestors(self, state_id: str) -> tuple[str, ...]:
        """``state_id`` and its ancestors, innermost first."""
        chain = []
        current: str | None = state_id
        while current is not None:
            chain.append(current)
            current = self.state(current).parent
        return tuple(chain)

    def leaf_states(self) -> tuple[State, ...]:
        return tuple(
            s for s in self.states if s.kind in (StateKind.ATOMIC, StateKind.FINAL)
        )


@dataclass(frozen=True, slots=True)
class TagMember:
    """A member of the MOTION_INSTRUCTION data type (a bit or an integer)."""

    name: str
    type: str  # "BOOL" | "INT" | "SINT"
    bit: int | None  # bit number in FLAGS for BOOL members
    description: str
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class TagType:
    name: str  # "MOTION_INSTRUCTION"
    members: tuple[TagMember, ...]
    internal: tuple[Variable, ...]  # model-only members (e.g. the pending request)
    provenance: Provenance
    #: the error of an instruction called on an axis whose chart none of its variants
    #: lists (e.g. MDO on a CIP axis); None: such a program is refused at load time
    wrong_axis_family: Check | None = None


@dataclass(frozen=True, slots=True)
class TableRow:
    """One row of an execution table: when the guard holds, do the actions."""

    condition: str  # "prescan" | "rung_false" | "rung_true" | "postscan"
    guard: Expr | None
    actions: tuple[Assignment, ...]
    execute: bool  # the row runs the instruction (checks, then request)
    description: str
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class ExecutionTable:
    id: str
    rows: tuple[TableRow, ...]
    on_execute: tuple[Assignment, ...]  # done before the checks when the instruction runs
    on_error: tuple[Assignment, ...]  # done when a check fails (besides ERR/EXERR)
    on_accept: tuple[Assignment, ...]  # done when the request is posted
    on_done: tuple[Assignment, ...]  # done when the completion condition holds
    provenance: Provenance
    #: done when the process an instruction started completes (PC)
    on_complete: tuple[Assignment, ...] = ()
    #: done when that process ends without completing (stopped, superseded, faulted)
    on_end: tuple[Assignment, ...] = ()

    def row(self, condition: str) -> TableRow | None:
        for r in self.rows:
            if r.condition == condition:
                return r
        return None


@dataclass(frozen=True, slots=True)
class Operand:
    name: str
    type: str  # "axis" | "tag" | "real" | "int" | "enum"
    domain: tuple[int | float | str, ...] | None  # finite values the checker explores
    range: tuple[float, float] | None  # documented valid range, if any
    text_values: tuple[tuple[str, int], ...]  # "enter as text" names with their numbers
    default: int | float | str | None
    description: str
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class Check:
    """An ordered precondition: when ``fails_when`` holds the instruction errs."""

    id: str
    fails_when: Expr
    err: int
    exerr: int
    stage: Stage
    description: str
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class Request:
    """What an accepted instruction asks of the axis chart at the coarse update."""

    event: str
    actions: tuple[Assignment, ...]  # applied to the axis before the event is sent


@dataclass(frozen=True, slots=True)
class Process:
    """The process a motion instruction starts once the axis accepts it (IP until it ends).

    After DN the tag stays pending; at every coarse update the process completes (the
    table's ``on_complete``: PC) when ``complete_when`` holds, else ends (``on_end``: IP
    cleared, no PC) when ``ends_when`` holds.  Accepting another request of the same
    ``kind`` on the same axis ends it too (superseded)."""

    kind: str  # "move" | "jog" | "gear" | "home" | "stop" | ...
    complete_when: Expr | None  # None: the process never completes (MAJ, MAG)
    ends_when: Expr | None
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class Instruction:
    """One variant of an instruction: its behaviour on the axes of the charts it lists.

    An instruction whose documents describe different behaviour on different axis
    families (MSO on a servo-module axis and on a CIP drive axis) has one variant per
    family; the variants share the ``mnemonic`` and have distinct ``id`` values.
    """

    id: str  # unique variant id, e.g. "MSO" or "MSO_CIP"
    mnemonic: str  # the instruction as the program calls it, e.g. "MSO"
    name: str
    charts: tuple[str, ...]  # axis charts this instruction is defined for
    axis_types: tuple[str, ...]
    operands: tuple[Operand, ...]
    execution: str  # "transitional" | "level"
    table: ExecutionTable
    checks: tuple[Check, ...]
    aborts: tuple[Check, ...]  # end a pending request with ER when they hold
    request: Request | None
    done_when: Expr | None  # None: done as soon as the request is accepted by the axis
    status_bits: tuple[tuple[str, bool], ...]  # documented status-bit changes
    description: str
    provenance: Provenance
    done_provenance: Provenance
    location: Location
    process: Process | None = None
    #: the operand naming a second axis (MAG's MasterAxis), read as ``master.X``
    master_operand: str | None = None


@dataclass(frozen=True, slots=True)
class ErrorCode:
    code: int
    name: str
    meaning: str
    confidence: Confidence
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class ExtendedError:
    instruction: str
    err: int
    exerr: int
    name: str
    meaning: str
    confidence: Confidence
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class Spec:
    """A whole loaded specification."""

    charts: tuple[Chart, ...]
    instructions: tuple[Instruction, ...]
    tag_type: TagType
    tables: tuple[ExecutionTable, ...]
    errors: tuple[ErrorCode, ...]
    extended_errors: tuple[ExtendedError, ...]
    interpretations: tuple[Interpretation, ...]
    files: tuple[str, ...] = field(default=())
    add_ons: tuple[AddOnInstruction, ...] = ()

    def add_on(self, add_on_id: str | None = None) -> AddOnInstruction:
        """The add-on instruction ``add_on_id`` (the only one when None); KeyError when there is none."""
        for a in self.add_ons:
            if add_on_id is None or a.id == add_on_id:
                return a
        raise KeyError(add_on_id)

    def chart(self, chart_id: str) -> Chart:
        for c in self.charts:
            if c.id == chart_id:
                return c
        raise KeyError(chart_id)

    def instruction(self, key: str, chart: str | None = None) -> Instruction:
        """The variant with id ``key``; else the variant of mnemonic ``key`` for ``chart``
        (or its only variant when ``chart`` is None).  KeyError when there is none."""
        if chart is None:
            for i in self.instructions:
                if i.id == key:
                    return i
            variants = self.variants(key)
            if len(variants) == 1:
                return variants[0]
            raise KeyError(key)
        for i in self.instructions:
            if i.id == key and chart in i.charts:
                return i
        for i in self.instructions:
            if i.mnemonic == key and chart in i.charts:
                return i
        raise KeyError(f"{key} on {chart}")

    def variants(self, mnemonic: str) -> tuple[Instruction, ...]:
        """Every variant of an instruction, in id order."""
        return tuple(i for i in self.instructions if i.mnemonic == mnemonic)

    def mnemonics(self) -> tuple[str, ...]:
        return tuple(sorted({i.mnemonic for i in self.instructions}))

    def chart_for_axis_type(self, axis_type: str) -> Chart:
        for c in self.charts:
            if axis_type in c.axis_types:
                return c
        raise KeyError(axis_type)

    def error(self, code: int) -> ErrorCode:
        for e in self.errors:
            if e.code == code:
                return e
        raise KeyError(code)

    def interpretation(self, interp_id: str) -> Interpretation:
        for i in self.interpretations:
            if i.id == interp_id:
                return i
        raise KeyError(interp_id)


# --------------------------------------------------------------------------- add-on instructions


@dataclass(frozen=True, slots=True)
class ChartParameter:
    """An instance parameter of a chart: configuration each instance is given (a handler's id, its axes)."""

    name: str
    type: str  # "int" | "axis" (the name of an axis of the set-up)
    default: bool | int | float | str | None
    description: str
    provenance: Provenance


@dataclass(frozen=True, slots=True)
class AddOnParameter:
    """A parameter of an add-on instruction, in Logix order."""

    name: str
    usage: str  # "Input" | "Output" | "InOut"
    type: str  # "axis" | "handle" | "BOOL" | "DINT" | "REAL"
    data_type: str | None
    alias: str | None  # the short name expressions use (phy, pth, handler)
    default: bool | int | float | str | None
    description: str
    provenance: Provenance
    location: Location
    #: the only values a program may give a DINT parameter (None: any DINT)
    values: tuple[int, ...] | None = None


@dataclass(frozen=True, slots=True)
class StatusMember:
    """A member of an add-on instruction's own status tag."""

    name: str
    type: str  # "BOOL" | "DINT"
    description: str
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class AddOnError:
    code: int
    name: str
    description: str
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class RecoveryCall:
    """A motion instruction a recovery state issues on an axis parameter (by alias)."""

    instruction: str
    axis: str
    master: str | None
    operands: tuple[tuple[str, Expr], ...]


@dataclass(frozen=True, slots=True)
class RecoveryState:
    id: str
    call: RecoveryCall | None
    error: int | None  # the add-on's code when the call errs (its ERR becomes Sts_EXERR)
    description: str
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class RecoveryTransition:
    source: str
    target: str
    when: Expr
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class Recovery:
    """The chart of one execution after the checks pass."""

    initial: str
    states: tuple[RecoveryState, ...]
    transitions: tuple[RecoveryTransition, ...]
    description: str
    provenance: Provenance
    location: Location

    def state(self, sid: str) -> RecoveryState:
        return next(s for s in self.states if s.id == sid)


@dataclass(frozen=True, slots=True)
class OnDone:
    when: Expr
    set: str  # "path_verified" | "handler.OnPath"
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class ScanRule:
    """What a false rung or a prescan does to an add-on instance."""

    clear: tuple[str, ...]
    abort_call: str | None
    forget: tuple[str, ...]
    description: str
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class FactSet:
    value: bool | int | float | str
    fire: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class Fact:
    """One fact of a world object, read from its chart (``when`` or ``variable``), and how it is set."""

    name: str
    when: Expr | None
    variable: str | None
    set: tuple[FactSet, ...]
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class SetupRule:
    when: Expr
    state: str | None
    variables: tuple[tuple[str, Expr], ...]


@dataclass(frozen=True, slots=True)
class WorldSetup:
    variables: tuple[tuple[str, Expr], ...]
    rules: tuple[SetupRule, ...]
    then_set: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class WorldObject:
    """How the objects of one kind (an axis data type, or the handler) are read from their chart."""

    kind: str
    chart: str
    facts: tuple[Fact, ...]
    on_scan: tuple[str, ...]
    stop: tuple[str, ...]
    register: tuple[str, ...]
    setup: WorldSetup
    provenance: Provenance
    location: Location

    def fact(self, name: str) -> Fact | None:
        return next((f for f in self.facts if f.name == name), None)


@dataclass(frozen=True, slots=True)
class World:
    objects: tuple[WorldObject, ...]
    provenance: Provenance
    location: Location

    def object(self, kind: str) -> WorldObject:
        return next(o for o in self.objects if o.kind == kind)


@dataclass(frozen=True, slots=True)
class Execution:
    mode: str  # "level"
    provenance: Provenance
    location: Location


@dataclass(frozen=True, slots=True)
class AddOnInstruction:
    """An add-on instruction: a routine with parameters, its own status tag, ordered checks and a recovery chart."""

    id: str
    name: str
    execution: Execution
    parameters: tuple[AddOnParameter, ...]
    status: tuple[StatusMember, ...]
    local_tags: tuple[Variable, ...]
    errors: tuple[AddOnError, ...]
    checks: tuple[Check, ...]
    recovery: Recovery
    on_done: tuple[OnDone, ...]
    rung_false: ScanRule
    prescan: ScanRule
    world: World
    description: str
    provenance: Provenance
    location: Location

    def parameter(self, name: str) -> AddOnParameter:
        return next(p for p in self.parameters if p.name == name or p.alias == name)

    def error(self, code: int) -> AddOnError:
        return next(e for e in self.errors if e.code == code)
