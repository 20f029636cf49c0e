"""The motion abstraction is sound: every run of the drive model is a path of the checker.

The engine runs the drive model of :mod:`statecharts.drive` (positions, velocities, a
move reaching its target at the update its distance runs out).  The model checker does
not: it collapses the numbers and offers the drive events (``move_complete``,
``home_complete``, ``stopping_complete``) as inputs at any coarse update, alone or
together with a rung change or an environment event (docs/motion.md).  Two checks:

* random runs of the ``motion`` system on the engine, drive model on, driven by the
  program's inputs only (the drive events come from the arithmetic): after every scan
  the engine's state mapped through the abstraction is one of the checker's
  successors of the previous abstract state;
* the move scenarios (several axes, gearing, a fault): at every scan, the checker's
  back-end with the drive model off, loaded with the engine's state and given the
  scan's inputs plus the drive events the engine's drive model produced, ends in the
  engine's state, the collapsed numbers aside.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from checker.compile import FastAxis
from checker.model import Model
from checker.properties import load_properties
from checker.search import Codec
from checker.system import bundled_systems, load_system
from statecharts import drive, ir
from statecharts.engine import AxisInstance
from statecharts.scan import EnvironmentEvent, ScanInputs, System
from statecharts.scenario import build_system, load_scenario

ROOT = Path(__file__).resolve().parents[1]
MOVE_SCENARIOS = sorted((ROOT / "scenarios" / "move").glob("*.yaml"))
#: the numbers the drive model keeps and the checker collapses
NUMBERS = ("ActualPosition", "CommandVelocity", "MoveCommand", "MoveSpeed", "MoveRemaining", "MovePlanned",
           "MoveType", "JogVelocity", "GearRatio", "StopDecel", "RedefinePosition", "RedefineType",
           "HomePosition", "PositionUnwind")


@pytest.fixture(scope="module")
def motion_model(spec: ir.Spec) -> Model:
    sd = load_system(bundled_systems()["motion"], spec)
    # fast moves, so that a run of a few scans sees moves arrive, stops end and homing finish
    ops = tuple((m, o, (1000.0, 10000.0) if o == "Speed" else v) for m, o, v in sd.operand_domains)
    ops += (("MAM_CIP", "Position", (20.0, 90.0)), ("MAS_CIP", "ChangeDecel", (0, 1)), ("MAS_CIP", "DecelRate", (50000.0,)))
    return Model(spec, dataclasses.replace(sd, operand_domains=ops), load_properties(spec))


def _abstract(model: Model, codec: Codec, snapshot: tuple[object, ...], monitors: list[tuple[int, ...]]
              ) -> tuple[bytes, list[tuple[int, ...]]]:
    model.system.restore(snapshot)
    model.monitor_values = list(monitors)
    model.evaluate()
    return codec.encode(model.extract()), list(model.monitor_values)


def _successors(model: Model, codec: Codec, code: bytes) -> set[bytes]:
    flat = codec.decode(code)
    model.load(flat)
    out = set()
    for choice in model.enabled():
        model.load(flat)
        succ, _bad, _good, _facts = model.step(choice)
        out.add(codec.encode(succ))
    return out


def test_the_checker_offers_every_drive_event_with_every_program_input(motion_model: Model) -> None:
    drive_inputs = {c.drive for c in motion_model.choices if c.drive}
    assert drive_inputs == set(drive.EVENTS)
    for tag_choices in motion_model.raise_choices:
        for c in tag_choices:
            assert {x.drive for x in motion_model.drive_combos[c.index]} == set(drive.EVENTS)


@settings(max_examples=40)
@given(data=st.data())
def test_every_drive_model_run_is_a_path_of_the_checker(motion_model: Model, data: st.DataObject) -> None:
    model = motion_model
    codec = Codec(model)
    assignment = model.assignments[data.draw(st.integers(0, len(model.assignments) - 1), label="configuration")]
    engine = model.build_system(assignment, backend=AxisInstance)
    engine.motion = True  # the drive model's arithmetic decides when motion ends
    fast = model.build_system(assignment, backend=FastAxis)
    fast.motion = True
    flat0, _bad, _good = model.initial(assignment)
    code = codec.encode(flat0)
    monitors = list(model.monitor_values)
    assert _abstract(model, codec, engine.snapshot(), monitors)[0] == code
    for step in range(data.draw(st.integers(1, 30), label="scans")):
        succs = _successors(model, codec, code)
        model.system.restore(engine.snapshot())
        offered = [c.index for c in model.enabled() if c.drive is None and c.event not in drive.EVENTS]
        choice = model.choices[data.draw(st.sampled_from(offered), label=f"choice {step}")]
        r_engine = engine.scan(choice.inputs)
        r_fast = fast.scan(choice.inputs)
        assert dict(r_engine.observations) == dict(r_fast.observations), f"scan {step}: back-ends differ"
        code, monitors = _abstract(model, codec, engine.snapshot(), monitors)
        assert code in succs, (
            f"scan {step} ({choice.label()}): the drive model's state, mapped through the motion "
            "abstraction, is not a successor in the checker")


def _masked(system: System) -> tuple[object, ...]:
    """The system's state with the drive model's numbers left out."""
    axes = []
    for a in system.axes.values():
        values = tuple(None if v.name in NUMBERS else a.env[v.name] for v in a.chart.variables)
        axes.append((a.active, values))
    return (tuple(axes), tuple(t.snapshot() for t in system.tags.values()), tuple(system.queue))


class _Recording(System):
    """The engine's system, remembering the drive events its drive model produced."""

    fired: list[tuple[str, str]]

    def _drive_events(self, held: Sequence[EnvironmentEvent]) -> dict[str, list[str]]:
        out = super()._drive_events(held)
        self.fired.extend((axis, ev) for axis, evs in out.items() for ev in evs)
        return out


@pytest.mark.parametrize("path", MOVE_SCENARIOS, ids=lambda p: p.stem)
def test_move_scenarios_step_like_the_checker_given_the_drive_events(spec: ir.Spec, path: Path) -> None:
    scenario = load_scenario(path, spec)
    engine = build_system(scenario, spec)
    engine.__class__ = _Recording
    assert isinstance(engine, _Recording)
    checker = build_system(scenario, spec)
    params = {"scan_ms": scenario.scan_ms, "coarse_update_ms": scenario.coarse_update_ms}
    checker.axes = {a.name: FastAxis(spec.chart(a.chart), a.name, state=a.state, variables=dict(a.variables),
                                     parameters=params) for a in scenario.axes}
    for a in checker.axes.values():
        a.env["scan_ms"] = scenario.scan_ms
        a.env["coarse_update_ms"] = scenario.coarse_update_ms
    checker.motion = False
    for step in scenario.steps:
        assert not step.sets and step.within is None, "not used by the move scenarios"
        for k in range(step.scans):
            inputs = step.inputs if k == 0 else ScanInputs(prescan=step.inputs.prescan)
            checker.restore(engine.snapshot())
            engine.fired = []
            engine.scan(inputs)
            given_drive = tuple(EnvironmentEvent(a, e) for a, e in engine.fired)
            FIRED.update(e for _a, e in engine.fired)
            checker.scan(dataclasses.replace(inputs, events=(*inputs.events, *given_drive)))
            assert _masked(checker) == _masked(engine), f"{path.name}, step {step.name!r}: the abstraction differs"


#: the drive events the scenarios above saw the drive model produce
FIRED: set[str] = set()


def test_the_scenarios_exercise_every_drive_event() -> None:
    assert set(drive.EVENTS) == FIRED


def test_the_move_transitions_the_cip_explanations_send_to_the_motion_system_are_reached_there(spec: ir.Spec) -> None:
    """spec/properties/cip.yaml explains AxisCIP's move transitions as explored by the
    ``motion`` system (or as outside its operand choices); that claim is checked here:
    the first group is reached by a full check of ``motion``, the second is not."""
    from checker.coverage import table
    from checker.search import explore

    props = load_properties(spec)
    cover = next(p for p in props if p.name == "cip_every_transition_taken")
    in_motion = {u.item for u in cover.unreachable if "spec/systems/motion.yaml" in u.source}
    model = Model(spec, load_system(bundled_systems()["motion"], spec), props)
    r = explore(model, progress=False)
    assert r.complete and not r.violations
    reached = set(table(r, "transitions").reached)
    moves = {"AxisCIP:" + t for t in ("mah", "homed", "mam", "move_done", "maj", "mas_all", "mas_move",
                                      "stopping_done", "mrp")}
    outside = {"AxisCIP:" + t for t in ("mam_merge", "maj_merge", "mag", "mas_jog", "mas_gear", "mas_home")}
    assert moves | outside <= in_motion
    assert moves <= reached, f"explained as reached by the motion system but not reached: {sorted(moves - reached)}"
    assert not outside & reached, f"explained as outside the motion system but reached: {sorted(outside & reached)}"
