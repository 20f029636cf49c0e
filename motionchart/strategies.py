"""Hypothesis strategies built from the IR, for property tests of the spec, of a user's
programs and scenarios, and of other implementations.

* :func:`scenarios` / :func:`scenario_documents` -- valid scenarios for a chart and a set
  of instructions (set-up, program, steps with rungs, operands and events; no
  expectations: a property test states those);
* :func:`input_sequences` -- scan inputs (rung patterns, operand values, environment
  events) for a program on a set of axes;
* :func:`fault_injections` -- environment events (faults, shutdowns, ...) scheduled at
  scans, for a set of axes;
* :func:`mutated_specs` -- the spec with one seeded fault (a dropped guard, a swapped
  target, a changed error code), to check that a test notices;
* the building blocks they are made of (:func:`axis_setups`, :func:`programs`,
  :func:`operand_sets`, :func:`environment_events`, :func:`scan_timings`...).

``docs/api.md`` has an example property test for each.

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

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from hypothesis import strategies as st

from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.scan import EnvironmentEvent, ScanInputs
from statecharts.scenario import Scenario, load_scenario_document

__all__ = [
    "SCAN_TIMINGS",
    "AxisSetup",
    "axis_setups",
    "checking_systems",
    "environment_event_names",
    "environment_events",
    "fault_injections",
    "input_sequences",
    "instruction_names",
    "instructions_for",
    "mutated_specs",
    "operand_sets",
    "operand_values",
    "programs",
    "rung_patterns",
    "scan_timings",
    "scenario_documents",
    "scenarios",
    "tag_name",
    "value_operands",
]

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
    def bound(i: ir.Instruction) -> st.SearchStrategy[tuple[str, str, str]]:
        return st.sampled_from(list(axis_names)).map(lambda ax: (tag_name(i.id), i.id, ax))

    return st.tuples(*(bound(i) for i in instructions_for(spec, chart)))


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
        initial_leaf = chart.state(initial_leaf).initial or initial_leaf
    leaves = [s.id for s in chart.leaf_states()]
    drawn = st.fixed_dictionaries({n: _variable_values(known[n]) for n in variables if n in known})
    return st.builds(
        AxisSetup,
        name=st.just(name),
        axis_type=_biased(chart.axis_types, preferred_type),
        state=_biased(leaves, initial_leaf),
        variables=drawn.map(lambda d: tuple(sorted(d.items()))),
    )


# --------------------------------------------------------------------------- scan inputs


def input_sequences(
    spec: ir.Spec,
    chart: ir.Chart,
    axis_names: Sequence[str],
    program: Sequence[tuple[str, str, str]] | None = None,
    *,
    min_size: int = 1,
    max_size: int = 12,
) -> st.SearchStrategy[list[ScanInputs]]:
    """Inputs for consecutive scans of ``program`` (``(tag, mnemonic, axis)`` triples; by
    default one tag per instruction of ``chart`` on the first axis): each scan changes
    some rungs, may set operands of the tags whose rung it raises, and may bring
    environment events for ``axis_names``."""
    if program is None:
        program = [(tag_name(i.mnemonic), i.mnemonic, axis_names[0]) for i in _by_mnemonic(spec, chart)]
    tags = [t for t, _m, _a in program]
    by_tag = {t: _variant(spec, chart, m) for t, m, _a in program}

    @st.composite
    def one(draw: st.DrawFn) -> ScanInputs:
        rungs = draw(rung_patterns(tags)) if tags else {}
        operands = {t: draw(operand_sets(by_tag[t])) for t, on in rungs.items() if on and value_operands(by_tag[t])}
        events = draw(environment_events(chart, axis_names, max_size=1)) if axis_names else ()
        return ScanInputs(rungs=rungs, operands=operands, events=events)

    return st.lists(one(), min_size=min_size, max_size=max_size)


def fault_injections(
    chart: ir.Chart,
    axis_names: Sequence[str],
    *,
    events: Sequence[str] | None = None,
    max_faults: int = 3,
    max_scan: int = 20,
) -> st.SearchStrategy[list[tuple[int, EnvironmentEvent]]]:
    """Up to ``max_faults`` environment events (by default every event of ``chart`` of
    kind ``environment``: faults, shutdowns, connection losses...), each on one of
    ``axis_names`` at a scan in ``0..max_scan``; sorted by scan."""
    names = list(events) if events is not None else [e.name for e in chart.events if e.kind == "environment"]
    one = st.tuples(st.integers(0, max_scan),
                    st.builds(EnvironmentEvent, st.sampled_from(list(axis_names)), st.sampled_from(names)))
    return st.lists(one, max_size=max_faults).map(lambda xs: sorted(xs, key=lambda x: (x[0], x[1].axis, x[1].event)))


# --------------------------------------------------------------------------- whole scenarios


def _by_mnemonic(spec: ir.Spec, chart: ir.Chart) -> list[ir.Instruction]:
    seen: dict[str, ir.Instruction] = {}
    for i in instructions_for(spec, chart):
        seen.setdefault(i.mnemonic, i)
    return list(seen.values())


def _variant(spec: ir.Spec, chart: ir.Chart, mnemonic: str) -> ir.Instruction:
    for i in instructions_for(spec, chart):
        if i.mnemonic == mnemonic or i.id == mnemonic:
            return i
    raise KeyError(f"no instruction {mnemonic!r} for chart {chart.id}")


def _plain_value(value: object) -> bool | int | float | str:
    if isinstance(value, bool | int | float | str):
        return value
    return str(value)


def scenario_documents(
    spec: ir.Spec,
    chart: ir.Chart,
    instructions: Sequence[str] | None = None,
    *,
    axes: int = 1,
    max_steps: int = 6,
    max_scans: int = 3,
    expect: Mapping[str, Mapping[str, object]] | None = None,
) -> st.SearchStrategy[dict[str, Any]]:
    """Scenario documents (``format: motionchart-scenario/1``, as a YAML or JSON file
    holds them) for ``chart``: ``axes`` axes (``Axis1``...) with drawn set-ups, one tag
    per instruction of ``instructions`` (mnemonics; default every instruction of the
    chart) on a drawn axis, and up to ``max_steps`` steps of rungs, operands, events and
    scan counts.

    A scenario must check something: the last step expects ``expect`` (object -> field
    -> value), by default only that every axis keeps the data type it was configured
    with (configuration, which no instruction writes).  A property test states the
    behaviour it checks on the run itself."""
    variants = [_variant(spec, chart, m) for m in instructions] if instructions else _by_mnemonic(spec, chart)
    names = [f"Axis{k + 1}" for k in range(axes)]
    if expect is None and "AxisType" not in {v.name for v in chart.variables}:
        raise ValueError(f"chart {chart.id} has no AxisType to expect by default; give `expect`")

    @st.composite
    def build(draw: st.DrawFn) -> dict[str, Any]:
        scan_ms, coarse_ms = draw(scan_timings())
        setup_axes: dict[str, Any] = {}
        for n in names:
            a = draw(axis_setups(chart, n))
            entry: dict[str, Any] = {"type": a.axis_type, "state": a.state}
            if a.variables:
                entry["variables"] = {k: _plain_value(v) for k, v in a.variables}
            setup_axes[n] = entry
        program = [{"tag": tag_name(i.mnemonic), "instruction": i.mnemonic, "axis": draw(st.sampled_from(names))}
                   for i in variants]
        tags = {p["tag"]: i for p, i in zip(program, variants)}
        steps: list[dict[str, Any]] = []
        for _ in range(draw(st.integers(1, max_steps))):
            step: dict[str, Any] = {}
            if tags:
                rungs = draw(rung_patterns(list(tags)))
                step["rungs"] = rungs
                ops = {t: {k: _plain_value(v) for k, v in draw(operand_sets(tags[t])).items()}
                       for t, on in rungs.items() if on and value_operands(tags[t])}
                if ops:
                    step["operands"] = ops
            events = draw(environment_events(chart, names, max_size=1))
            if events:
                step["events"] = [{"axis": e.axis, "event": e.event} for e in events]
            scans = draw(st.integers(1, max_scans))
            if scans > 1:
                step["scans"] = scans
            steps.append(step or {"scans": 1})
        steps[-1]["expect"] = ({n: {"AxisType": setup_axes[n]["type"]} for n in names} if expect is None
                               else {o: dict(f) for o, f in expect.items()})
        return {"format": "motionchart-scenario/1", "name": "drawn scenario",
                "setup": {"scan_ms": scan_ms, "coarse_update_ms": coarse_ms, "axes": setup_axes, "program": program},
                "steps": steps}

    return build()


def _load_document(spec: ir.Spec, doc: Mapping[str, Any]) -> Scenario:
    return load_scenario_document("<drawn scenario>", json.loads(json.dumps(doc)), spec)


def scenarios(
    spec: ir.Spec,
    chart: ir.Chart,
    instructions: Sequence[str] | None = None,
    **options: Any,
) -> st.SearchStrategy[Scenario]:
    """Loaded scenarios (what :func:`statecharts.scenario.run_scenario` takes) drawn by
    :func:`scenario_documents`; ``options`` are its ``axes``, ``max_steps``, ``max_scans``
    and ``expect``."""
    return scenario_documents(spec, chart, instructions, **options).map(lambda d: _load_document(spec, d))


# --------------------------------------------------------------------------- mutated specs


def mutated_specs(
    spec: ir.Spec, *, kinds: Sequence[str] | None = None, where: str = ""
) -> st.SearchStrategy[tuple[ir.Spec, Any]]:
    """``(mutant, mutation)``: ``spec`` with one seeded fault from
    :func:`checker.mutate.single_mutants` (``kinds`` among ``drop_guard``,
    ``swap_target``, ``error_code``; default all), of the element whose ``where``
    starts with ``where`` (``"MSO:"``, ``"AxisNonCIP:"``...).  A test that passes on
    ``spec`` and on every mutant checks nothing those faults change."""
    from checker.mutate import single_mutants

    mutants = [(m, how) for m, how in single_mutants(spec)
               if (kinds is None or how.kind in kinds) and how.where.startswith(where)]
    if not mutants:
        raise ValueError("the spec has no mutants of the requested kinds")
    return st.sampled_from(mutants)
# --------------------------------------------------------------------------- checking systems


def checking_systems(spec: ir.Spec, base: Any) -> st.SearchStrategy[Any]:
    """Small model-checking systems (:class:`checker.system.SystemDef`) varied from ``base``:
    an axis chart and type, one or two interchangeable axes, a start state and set-up
    variables, up to three instruction calls, up to three environment events, the
    scan timing, the live-call bound, prescan passes and the abstractions."""
    import dataclasses

    from checker.system import AxisGroup, Configuration

    charts = [c for c in spec.charts if instructions_for(spec, c)]

    @st.composite
    def build(draw: st.DrawFn) -> Any:
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
