"""Hypothesis strategies built from the IR, shared by the property tests.

Everything here is *derived from the loaded spec* (instruction names, operand domains,
environment events, axis types, leaf states, variable domains), so a new instruction,
event or state is explored without touching the tests.  The strategies only say what
may be *tried*; they never say what the result should be (that would restate the
spec, see DESIGN.md "Quality rules").

Set-up values are biased towards the chart's initial values (``AXIS_SERVO``,
``Configured``, ``Servo``...) so that most instructions are accepted and the runs get
past the precondition checks; every other value of the domain is still drawn.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from hypothesis import strategies as st

from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.scan import EnvironmentEvent

#: Axis variables a set-up draws, besides the axis type and the initial state.
SETUP_VARIABLES = ("FaultAction", "Configured", "AxisConfiguration")

#: (scan_ms, coarse_update_ms) pairs: coarse update as fast as the scan, or slower
#: (requests then wait scans for their coarse update), and long periods that make the
#: 500 ms enable delay of direct drive last only one or two coarse updates.
SCAN_TIMINGS: tuple[tuple[int, int], ...] = (
    (10, 10),
    (10, 20),
    (10, 40),
    (250, 250),
    (250, 500),
    (500, 500),
)

#: Operand types that name the axis or the tag rather than carry a value.
_REFERENCE_OPERANDS = ("axis", "tag")


def _biased(values: Sequence[object], preferred: object | None = None) -> st.SearchStrategy[object]:
    """Any of ``values``, with ``preferred`` (a documented default) drawn about half the time."""
    values = list(values)
    if preferred is None or preferred not in values:
        return st.sampled_from(values)
    # sampled_from shrinks towards its first element: put the preferred value there
    ordered = [preferred] + [v for v in values if v != preferred]
    return st.one_of(st.just(preferred), st.sampled_from(ordered))


# --------------------------------------------------------------------------- instructions


def instructions_for(spec: ir.Spec, chart: ir.Chart) -> tuple[ir.Instruction, ...]:
    """The instructions defined for ``chart``, in spec order."""
    return tuple(i for i in spec.instructions if chart.id in i.charts)


def instruction_names(spec: ir.Spec, chart: ir.Chart | None = None) -> st.SearchStrategy[str]:
    """Mnemonics of the spec's instructions (of one chart if given)."""
    ins = instructions_for(spec, chart) if chart is not None else spec.instructions
    return st.sampled_from([i.id for i in ins])


def value_operands(instruction: ir.Instruction) -> tuple[ir.Operand, ...]:
    """The operands that carry a value (not the axis or the tag)."""
    return tuple(o for o in instruction.operands if o.type not in _REFERENCE_OPERANDS)


def operand_values(operand: ir.Operand) -> st.SearchStrategy[object]:
    """Values for one operand: its finite ``domain`` (the values the checker explores).

    An operand without a domain gets numbers from its documented range, or else its
    default only.
    """
    if operand.domain is not None:
        return _biased(operand.domain, operand.default)
    if operand.range is not None:
        lo, hi = operand.range
        if operand.type == "int":
            return st.integers(int(lo), int(hi))
        return st.floats(lo, hi, allow_nan=False, allow_infinity=False)
    return st.just(operand.default)


def operand_sets(instruction: ir.Instruction) -> st.SearchStrategy[dict[str, object]]:
    """A value for every value operand of ``instruction`` (``{}`` when it has none)."""
    return st.fixed_dictionaries({o.name: operand_values(o) for o in value_operands(instruction)})


# --------------------------------------------------------------------------- programs and rungs


def tag_name(mnemonic: str) -> str:
    """The MOTION_INSTRUCTION tag used for ``mnemonic`` in generated programs."""
    return f"{mnemonic}_Ctrl"


def programs(
    spec: ir.Spec, chart: ir.Chart, axis_names: Sequence[str]
) -> st.SearchStrategy[tuple[tuple[str, str, str], ...]]:
    """One tag per instruction of ``chart``, each bound to one of ``axis_names``.

    The result is a program as :class:`statecharts.scan.System` takes it:
    ``(tag, mnemonic, axis)`` triples in spec order.
    """
    ins = instructions_for(spec, chart)
    return st.tuples(
        *(st.sampled_from(list(axis_names)).map(lambda ax, i=i: (tag_name(i.id), i.id, ax)) for i in ins)
    )


def rung_patterns(tags: Sequence[str]) -> st.SearchStrategy[dict[str, bool]]:
    """New rung conditions for a non-empty subset of ``tags`` (the others keep theirs)."""
    return st.dictionaries(st.sampled_from(list(tags)), st.booleans(), min_size=1)


def scan_timings() -> st.SearchStrategy[tuple[int, int]]:
    """``(scan_ms, coarse_update_ms)``; the first (equal periods) is the shrink target."""
    return st.sampled_from(SCAN_TIMINGS)


# --------------------------------------------------------------------------- environment


def environment_event_names(chart: ir.Chart) -> st.SearchStrategy[str]:
    """Events of ``chart`` that the outside world sends (``kind == "environment"``)."""
    names = [e.name for e in chart.events if e.kind == "environment"]
    return st.sampled_from(names)


def environment_events(
    chart: ir.Chart, axis_names: Sequence[str], *, max_size: int = 2
) -> st.SearchStrategy[tuple[EnvironmentEvent, ...]]:
    """Up to ``max_size`` environment events, each for one of ``axis_names``."""
    one = st.builds(EnvironmentEvent, st.sampled_from(list(axis_names)), environment_event_names(chart))
    return st.lists(one, max_size=max_size).map(tuple)


# --------------------------------------------------------------------------- axis set-ups


@dataclass(frozen=True)
class AxisSetup:
    """How one axis starts: its data type, its initial leaf state and some variables."""

    name: str
    axis_type: str
    state: str
    variables: tuple[tuple[str, object], ...]

    def build(self, chart: ir.Chart, parameters: Mapping[str, int] | None = None) -> AxisInstance:
        variables = dict(self.variables)
        if "AxisType" in {v.name for v in chart.variables}:
            variables["AxisType"] = self.axis_type
        return AxisInstance(chart, self.name, state=self.state, variables=variables, parameters=parameters)


def _variable_values(var: ir.Variable) -> st.SearchStrategy[object]:
    if var.domain is not None:
        return _biased(var.domain, var.initial)
    return st.just(var.initial)


def axis_setups(
    chart: ir.Chart, name: str, *, variables: Sequence[str] = SETUP_VARIABLES
) -> st.SearchStrategy[AxisSetup]:
    """An axis of ``chart``: type from its ``axis_types``, state from its leaf states,
    and each of ``variables`` (those the chart has) from the variable's domain."""
    known = {v.name: v for v in chart.variables}
    preferred_type = known["AxisType"].initial if "AxisType" in known else None
    initial_leaf = chart.root_initial
    while chart.state(initial_leaf).kind is ir.StateKind.COMPOUND:
        initial_leaf = chart.state(initial_leaf).initial  # type: ignore[assignment]
    leaves = [s.id for s in chart.leaf_states()]
    drawn = st.fixed_dictionaries({n: _variable_values(known[n]) for n in variables if n in known})
    return st.builds(
        AxisSetup,
        name=st.just(name),
        axis_type=_biased(chart.axis_types, preferred_type),
        state=_biased(leaves, initial_leaf),
        variables=drawn.map(lambda d: tuple(sorted(d.items()))),
    )


# --------------------------------------------------------------------------- checking systems


def checking_systems(spec: ir.Spec, base: object) -> st.SearchStrategy[object]:
    """Small model-checking systems (:class:`checker.system.SystemDef`) varied from ``base``:
    an axis chart and type, one or two interchangeable axes, a start state and set-up
    variables, up to three instruction calls, up to three environment events, the
    scan timing, the live-call bound, prescan passes and the abstractions."""
    import dataclasses

    from checker.system import AxisGroup, Configuration

    charts = [c for c in spec.charts if instructions_for(spec, c)]

    @st.composite
    def build(draw: st.DrawFn) -> object:
        chart = draw(st.sampled_from(charts))
        setup = draw(axis_setups(chart, "Axis"))
        ids = [i.id for i in instructions_for(spec, chart)]
        program = draw(st.lists(st.sampled_from(ids), min_size=1, max_size=3, unique=True))
        events = [e.name for e in chart.events if e.kind == "environment"]
        env = draw(st.lists(st.sampled_from(events), max_size=3, unique=True)) if events else []
        scan_ms, cu_ms = draw(scan_timings())
        variables = dict(setup.variables)
        if "AxisType" in {v.name for v in chart.variables}:
            variables["AxisType"] = setup.axis_type
        group = AxisGroup(name="Axis", axis_type=setup.axis_type, chart=chart.id,
                          count=draw(st.integers(1, 2)), state=setup.state,
                          variables=tuple(sorted(variables.items())),
                          configurations=(Configuration("drawn", (), ""),), program=tuple(program))
        # every operand of a call takes its first documented value or two
        domains = []
        for m in program:
            ins = spec.instruction(m)
            for op in value_operands(ins):
                if op.domain is not None:
                    domains.append((ins.id, op.name, tuple(op.domain[:2])))
        return dataclasses.replace(
            base, name="drawn", groups=(group,), scan_ms=scan_ms, coarse_update_ms=cu_ms,
            operand_domains=tuple(domains), environment=tuple(env), prescan=draw(st.booleans()),
            max_live_calls=draw(st.sampled_from([1, 2, None])), collapse=(),
            symmetry=draw(st.booleans()), retire_idle_tags=draw(st.booleans()))

    return build()
