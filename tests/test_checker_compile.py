"""The checker's IR interpreter (checker.compile.FastAxis) against python-statemachine.

Two independent encodings of the same charts: python-statemachine's SCXML processing
model (the engine, the reference semantics) and the checker's own run-to-completion
interpreter of the IR.  They must agree, event by event, on the active configuration
and every variable -- on every bundled chart, on a chart written here that uses
what the bundled spec does not yet (compound and parallel states, shallow history,
eventless and targetless transitions, priorities, entry/exit actions whose order shows
in a variable), and scan by scan when the one :class:`statecharts.scan.System` runs
either back-end: on axes of every bundled chart and on every bundled system.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from checker.compile import FastAxis
from checker.system import SystemDef, bundled_systems, load_system
from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.scan import EnvironmentEvent, ScanInputs, System

RICH_CHART = """\
format: motionchart-spec/1
chart:
  id: Rich
  name: Chart using compound, parallel and history states
  kind: axis
  state_attribute: S
  axis_types: [RICH_AXIS]
  initial: Run
  source: "MC tests/t"
  variables:
    - {name: x, type: int, initial: 0, domain: [0, 1, 2, 3], source: "MC tests/t"}
    - {name: log, type: int, initial: 0, range: [0, 100000], source: "MC tests/t"}
    - {name: go, type: bool, initial: false, source: "MC tests/t"}
  events:
    - {name: a, kind: environment, source: "MC tests/t"}
    - {name: b, kind: environment, source: "MC tests/t"}
    - {name: c, kind: environment, source: "MC tests/t"}
    - {name: d, kind: environment, actions: ["go = not go"], source: "MC tests/t"}
    - {name: tick, kind: clock, source: "MC tests/t"}
  states:
    - id: Run
      kind: compound
      initial: P
      source: "MC tests/t"
      entry: ["log = (log * 3 + 1) % 100000"]
      exit: ["log = (log * 3 + 2) % 100000"]
      states:
        - id: P
          kind: parallel
          source: "MC tests/t"
          entry: ["log = (log * 5 + 1) % 100000"]
          states:
            - id: R1
              kind: compound
              initial: A1
              source: "MC tests/t"
              states:
                - {id: A1, value: 1, source: "MC tests/t", entry: ["log = (log * 7 + 1) % 100000"], exit: ["log = (log * 7 + 2) % 100000"]}
                - {id: B1, value: 2, source: "MC tests/t", entry: ["log = (log * 7 + 3) % 100000"]}
                - {id: H1, kind: history, history: shallow, source: "MC tests/t"}
            - id: R2
              kind: compound
              initial: A2
              source: "MC tests/t"
              states:
                - {id: A2, value: 3, source: "MC tests/t", entry: ["log = (log * 11 + 1) % 100000"]}
                - {id: B2, value: 4, source: "MC tests/t", exit: ["log = (log * 11 + 5) % 100000"]}
        - {id: Q, value: 5, source: "MC tests/t", entry: ["log = (log * 13 + 1) % 100000"]}
    - {id: Off, value: 6, source: "MC tests/t", entry: ["log = (log * 17 + 1) % 100000"]}
  transitions:
    - {id: t1, from: A1, event: a, to: B1, actions: ["x = (x + 1) % 4"], source: "MC tests/t"}
    - {id: t2, from: B1, event: a, to: A1, source: "MC tests/t"}
    - {id: t3, from: A2, event: a, to: B2, guard: "x >= 1", source: "MC tests/t"}
    - {id: t4, from: B2, event: b, to: A2, source: "MC tests/t"}
    - {id: t5, from: P, event: b, to: Q, priority: 1, source: "MC tests/t"}
    - {id: t6, from: Q, event: a, to: H1, source: "MC tests/t"}
    - {id: t7, from: Run, event: c, to: Off, source: "MC tests/t"}
    - {id: t8, from: Off, event: c, to: Run, source: "MC tests/t"}
    - {id: t9, from: Off, guard: "go", to: Q, actions: ["go = False"], source: "MC tests/t"}
    - {id: t10, from: R1, event: b, actions: ["x = (x + 2) % 4"], source: "MC tests/t"}
    - {id: t11, from: P, event: tick, to: P, guard: "x == 3", actions: ["x = 0"], source: "MC tests/t"}
"""


@pytest.fixture(scope="module")
def rich_chart(tmp_path_factory: pytest.TempPathFactory) -> ir.Chart:
    path = Path(tmp_path_factory.mktemp("rich")) / "rich.yaml"
    path.write_text(RICH_CHART, encoding="utf-8")
    return load_spec([bundled_spec_dir(), path]).chart("Rich")


def _agree(a: AxisInstance, b: FastAxis, where: str) -> None:
    assert a.active == b.active, f"{where}: configurations differ: {sorted(a.active)} vs {sorted(b.active)}"
    assert a.observe() == b.observe(), f"{where}: observations differ"


def _run_events(chart: ir.Chart, events: list[str], kwargs: dict[str, object]) -> None:
    a = AxisInstance(chart, "A", **kwargs)
    b = FastAxis(chart, "A", **kwargs)
    _agree(a, b, "after start")
    for i, ev in enumerate(events):
        a.apply_event_actions(ev)
        b.apply_event_actions(ev)
        a.send(ev)
        b.send(ev)
        _agree(a, b, f"after event {i + 1} ({ev}) of {events}")


#: Every bundled chart: the axis charts and the device handler of the add-on instruction.
BUNDLED_CHARTS = ("AxisCIP", "AxisNonCIP", "AxisVirtual", "DeviceHandler")


def test_every_bundled_chart_is_covered(spec: ir.Spec) -> None:
    assert {c.id for c in spec.charts} == set(BUNDLED_CHARTS)


@pytest.mark.parametrize("chart_id", BUNDLED_CHARTS)
@given(data=st.data())
def test_fast_axis_matches_engine_on_every_bundled_chart(spec: ir.Spec, chart_id: str, data: st.DataObject) -> None:
    chart = spec.chart(chart_id)
    kwargs: dict[str, object] = {"parameters": {"coarse_update_ms": data.draw(st.sampled_from([10, 250, 500]))}}
    variables = {}
    for v in chart.variables:
        if v.domain is not None and len(v.domain) <= 8 and data.draw(st.booleans()):
            variables[v.name] = data.draw(st.sampled_from(v.domain))
    kwargs["variables"] = variables
    startable = [s.id for s in chart.leaf_states()
                 if not any(chart.state(a).kind is ir.StateKind.PARALLEL for a in chart.ancestors(s.id))]
    if startable and data.draw(st.booleans()):
        kwargs["state"] = data.draw(st.sampled_from(startable))
    events = data.draw(st.lists(st.sampled_from([e.name for e in chart.events]), max_size=25))
    _run_events(chart, events, kwargs)


@given(events=st.lists(st.sampled_from(["a", "b", "c", "d", "tick"]), max_size=40))
def test_fast_axis_matches_engine_on_parallel_and_history_states(rich_chart: ir.Chart, events: list[str]) -> None:
    _run_events(rich_chart, events, {})


def test_snapshot_restore_round_trip(spec: ir.Spec) -> None:
    chart = spec.chart("AxisNonCIP")
    for make in (AxisInstance, FastAxis):
        axis = make(chart, "A")
        before = axis.snapshot()
        axis.send("drive_on")
        during = axis.snapshot()
        axis.send("shutdown")
        assert axis.leaf.id == "Shutdown"
        axis.restore(during)
        assert axis.leaf.id == "DirectDriveControl" and axis.snapshot() == during
        axis.restore(before)
        assert axis.snapshot() == before


@st.composite
def _scan_inputs(draw: st.DrawFn, spec: ir.Spec, tags: dict[str, str], axes: list[str],
                 chart_id: str = "AxisNonCIP", sysdef: SystemDef | None = None) -> ScanInputs:
    """Several rung changes, operands, events at once: more than the checker's alphabet.
    Operands take the values of their domains, or those ``sysdef`` gives them."""
    chart = spec.chart(chart_id)
    rungs = draw(st.dictionaries(st.sampled_from(sorted(tags)), st.booleans(), max_size=3)) if tags else {}
    operands: dict[str, dict[str, object]] = {}
    for tag in rungs:
        ins = spec.instruction(tags[tag], chart_id)
        ops = {o.name: draw(st.sampled_from(sysdef.domain(ins, o) if sysdef else o.domain))
               for o in ins.operands if o.domain or sysdef}
        if ops:
            operands[tag] = ops
    env = [e.name for e in chart.events if e.kind == "environment"]
    events = draw(st.lists(st.tuples(st.sampled_from(axes), st.sampled_from(env)), max_size=2)) if env else []
    return ScanInputs(rungs=rungs, operands=operands,
                      events=tuple(EnvironmentEvent(a, e) for a, e in events),
                      prescan=draw(st.integers(0, 15)) == 0)


@pytest.mark.parametrize("chart_id", BUNDLED_CHARTS)
@settings(max_examples=examples(40))  # make deep: the deep profile's count
@given(data=st.data())
def test_system_gives_the_same_observations_on_both_back_ends(spec: ir.Spec, chart_id: str,
                                                              data: st.DataObject) -> None:
    chart = spec.chart(chart_id)
    scan_ms, coarse_ms = data.draw(st.sampled_from([(10, 10), (10, 20), (125, 250)]))
    params = {"scan_ms": scan_ms, "coarse_update_ms": coarse_ms}
    axes = ["A1", "A2"]
    fault_action = "FaultAction" in {v.name for v in chart.variables}
    setups = {a: {"FaultAction": data.draw(st.sampled_from(["Shutdown", "DisableDrive", "StatusOnly"]))}
              if fault_action else {} for a in axes}
    program = [(f"{a}_{i.id}", i.mnemonic, a) for a in axes for i in spec.instructions if chart.id in i.charts]
    tags = {t: m for t, m, _a in program}
    # an instruction with a second axis operand (MAG's master) follows the other axis
    masters = {f"{a}_{i.id}": b for a, b in zip(axes, reversed(axes)) for i in spec.instructions
               if chart.id in i.charts and i.master_operand is not None}

    def build(make: type) -> System:
        return System(spec, [make(chart, a, variables=setups[a], parameters=params) for a in axes], program,
                      scan_ms=scan_ms, coarse_update_ms=coarse_ms, masters=masters)

    engine, fast = build(AxisInstance), build(FastAxis)
    for k in range(data.draw(st.integers(1, 30))):
        inputs = data.draw(_scan_inputs(spec, tags, axes, chart_id))
        r1, r2 = engine.scan(inputs), fast.scan(inputs)
        assert r1.coarse_update == r2.coarse_update
        assert dict(r1.observations) == dict(r2.observations), f"scan {k}: {inputs}"
        assert engine.snapshot() == fast.snapshot()


# --------------------------------------------------------------------------- every bundled system

#: Every bundled checking system (spec/systems/*.yaml) of axes of one chart and their tags.
BUNDLED_SYSTEMS = ("cip", "motion", "noncip", "noncip_pairs")
#: The bundled systems with add-on instruction tags (their axes and devices of several charts).
ADD_ON_SYSTEMS = ("aoi",)


def test_every_bundled_system_is_covered() -> None:
    assert set(bundled_systems()) == set(BUNDLED_SYSTEMS) | set(ADD_ON_SYSTEMS)


@pytest.fixture(scope="module")
def systems(spec: ir.Spec) -> dict[str, SystemDef]:
    return {name: load_system(path, spec) for name, path in bundled_systems().items()}


def _same_run_on_both_back_ends(spec: ir.Spec, sd: SystemDef, data: st.DataObject, max_scans: int) -> None:
    """The system's axes (in a drawn configuration), program and clock on both back-ends, with
    or without the drive model's arithmetic, driven by inputs richer than the checker's: any
    environment event of the chart, several rung changes and operands at once, prescans."""
    motion = data.draw(st.booleans(), label="drive model")
    axes: list[tuple[str, str, dict[str, object], str | None]] = []
    for name, g in sd.axes():
        variables = dict(g.variables)
        conf = data.draw(st.sampled_from(g.configurations), label=f"{name} configuration")
        variables.update(dict(conf.variables))
        axes.append((name, g.chart, variables, g.state))
    program = sd.program()
    params = {"scan_ms": sd.scan_ms, "coarse_update_ms": sd.coarse_update_ms}

    def build(make: type) -> System:
        return System(spec, [make(spec.chart(c), n, state=st_, variables=v, parameters=params)
                             for n, c, v, st_ in axes], program,
                      scan_ms=sd.scan_ms, coarse_update_ms=sd.coarse_update_ms, masters=sd.masters(), motion=motion)

    engine, fast = build(AxisInstance), build(FastAxis)
    assert engine.snapshot() == fast.snapshot()
    (chart_id,) = {c for _n, c, _v, _s in axes}  # the bundled systems have axes of one chart
    tags = {t: m for t, m, _a in program}
    names = [n for n, _c, _v, _s in axes]
    for k in range(data.draw(st.integers(1, max_scans), label="scans")):
        inputs = data.draw(_scan_inputs(spec, tags, names, chart_id, sd), label=f"scan {k}")
        r1, r2 = engine.scan(inputs), fast.scan(inputs)
        assert r1.coarse_update == r2.coarse_update
        assert dict(r1.observations) == dict(r2.observations), f"scan {k}: {inputs}"
        assert engine.snapshot() == fast.snapshot(), f"scan {k}: {inputs}"


@pytest.mark.parametrize("name", BUNDLED_SYSTEMS)
@settings(max_examples=30)
@given(data=st.data())
def test_bundled_system_gives_the_same_observations_on_both_back_ends(
        spec: ir.Spec, systems: dict[str, SystemDef], name: str, data: st.DataObject) -> None:
    _same_run_on_both_back_ends(spec, systems[name], data, max_scans=30)


@pytest.mark.deep
@pytest.mark.parametrize("name", BUNDLED_SYSTEMS)
@given(data=st.data())
def test_bundled_system_gives_the_same_observations_on_both_back_ends_deep(
        spec: ir.Spec, systems: dict[str, SystemDef], name: str, data: st.DataObject) -> None:
    _same_run_on_both_back_ends(spec, systems[name], data, max_scans=150)


@pytest.mark.parametrize("name", ADD_ON_SYSTEMS)
@settings(max_examples=examples(8, 200))
@given(data=st.data())
def test_the_add_on_instruction_system_runs_on_both_back_ends(spec: ir.Spec, systems: dict[str, SystemDef],
                                                              name: str, data: st.DataObject) -> None:
    """An add-on instruction system (its axes, device handler, add-on tag and the tags of its
    calls) on both back-ends, with the drive model, driven by any of the checker's inputs at
    any scan (events on any axis, inputs with the rung up or down, prescans)."""
    from checker.model import Model
    model = Model(spec, systems[name])
    assignment = data.draw(st.sampled_from(model.assignments), label="configuration")
    engine = model.build_system(assignment, backend=AxisInstance)
    fast = model.build_system(assignment, backend=FastAxis)
    assert engine.snapshot() == fast.snapshot()
    for k in range(data.draw(st.integers(1, 30), label="scans")):
        choice = data.draw(st.sampled_from(model.choices), label=f"scan {k}")
        r1, r2 = engine.scan(choice.inputs), fast.scan(choice.inputs)
        assert r1.coarse_update == r2.coarse_update
        assert dict(r1.observations) == dict(r2.observations), f"scan {k}: {choice.label()}"
        assert engine.snapshot() == fast.snapshot(), f"scan {k}: {choice.label()}"
