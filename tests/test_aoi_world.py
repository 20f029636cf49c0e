"""The add-on instruction's world on its charts (docs/aoi.md "The world"; INT-065 .. INT-070).

* ``World.snapshot`` / ``World.restore`` / ``World.set`` (the interface the model checker
  explores): a restored world, even a freshly built one, behaves exactly like the world
  that produced the snapshot;
* the memoised chart runner agrees with a fresh engine ``AxisInstance`` on every event;
* the mapping from the charts to what the instruction reads, with expectations written
  by hand from 003 §2.4 and 001 (a fault fired on the CIP chart gives 1010 in Physical
  mode, a Shutdown through the chart 1010, a Stopped axis 1118, a faulted or shut-down
  virtual axis 1011, a stopped handler 1001, ...);
* bad set-up, ``set:`` and ``events:`` entries are located errors, never tracebacks.
"""

from __future__ import annotations

import copy
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from statecharts import aoi
from statecharts.diagnostics import ScenarioError
from statecharts.engine import AxisInstance
from statecharts.loader import load_spec, read_yaml

PROJECT = Path(__file__).resolve().parents[1]
#: scenarios in the world's own format (motionchart-aoi-scenario/1), which the model checker's
#: counterexamples are written in
OLD_FORMAT = Path(__file__).resolve().parent / "aoi_world_scenarios"
SPEC = aoi.load_aoi()
MAIN = aoi.bundled_aoi().main

#: 003 §4, typed in by hand: handler 1 with two methods registered, physical at 100, path at 120.
SETUP: dict[str, Any] = {
    "scan_ms": 50,
    "handlers": {"AH_Hndl": {"id": 1, "registered": 2, "capacity": 8, "eState": 7, "mode": "physical",
                             "phy_axis": "Axis_Phy", "pth_axis": "Axis_PTH"}},
    "axes": {"Axis_Phy": {"type": "AXIS_CIP_DRIVE", "position": 100.0, "unwind": 360.0, "homed": True,
                          "energized": True},
             "Axis_PTH": {"type": "AXIS_VIRTUAL", "position": 120.0, "unwind": 360.0}},
    "aoi": {"Sync": {"Ref_AxisPhy": "Axis_Phy", "Ref_AxisPth": "Axis_PTH", "Ref_Handle": "AH_Hndl",
                     "Cfg_SyncType": 1, "Cfg_AllowHome": True, "Cfg_TravelLIM": 30.0,
                     "Cfg_RotaryShortestTOL": 2.0, "Cfg_MoveType": 3, "Set_Speed": 20.0, "path_verified": True}},
}


def world(**changes: dict[str, Any]) -> aoi.World:
    setup = copy.deepcopy(SETUP)
    for obj, fields in changes.items():
        for part in ("handlers", "axes", "aoi"):
            if obj in setup[part]:
                setup[part][obj].update(fields)
    return aoi.build_world(SPEC, setup)


def code_after_rung_true(w: aoi.World) -> int:
    w.scan({"Sync": True})
    return int(w.instances["Sync"].outputs["Sts_ERR"])


# --------------------------------------------------------------------------- snapshot / restore / set

MOVES = st.one_of(
    st.tuples(st.just("scan"), st.booleans()),
    st.tuples(st.just("prescan")),
    st.tuples(st.just("set"), st.sampled_from([
        ("Axis_Phy", "faulted", True), ("Axis_Phy", "faulted", False), ("Axis_Phy", "shutdown", True),
        ("Axis_Phy", "shutdown", False), ("Axis_Phy", "energized", True), ("Axis_Phy", "energized", False),
        ("Axis_Phy", "homed", False), ("Axis_Phy", "direct_control", True), ("Axis_Phy", "direct_control", False),
        ("Axis_PTH", "velocity", 20.0), ("Axis_PTH", "velocity", 0.0), ("Axis_PTH", "faulted", True),
        ("Axis_PTH", "faulted", False), ("Axis_PTH", "homing", True), ("Axis_PTH", "homing", False),
        ("Axis_PTH", "shutdown", True), ("Axis_PTH", "shutdown", False), ("AH_Hndl", "eState", 3),
        ("AH_Hndl", "eState", 7), ("AH_Hndl", "mode", "virtual"), ("AH_Hndl", "mode", "physical"),
        ("AH_Hndl", "mode", "none"), ("AH_Hndl", "OnPath", False), ("AH_Hndl", "pth_axis", "Axis_Phy"),
        ("AH_Hndl", "pth_axis", "Axis_PTH")])),
    st.tuples(st.just("fire"), st.sampled_from([
        ("Axis_Phy", "axis_fault"), ("Axis_Phy", "fault_reset"), ("Axis_Phy", "disable"), ("Axis_Phy", "enable"),
        ("Axis_Phy", "dc_bus_down"), ("Axis_Phy", "dc_bus_up"), ("Axis_Phy", "start_inhibit_set"),
        ("Axis_Phy", "start_inhibit_cleared"), ("Axis_PTH", "axis_fault"), ("Axis_PTH", "fault_reset"),
        ("AH_Hndl", "stop"), ("AH_Hndl", "start"), ("AH_Hndl", "off_path")])),
    st.tuples(st.just("input"), st.sampled_from([("Cfg_SyncType", 0), ("Cfg_SyncType", 1), ("Set_Speed", -1.0),
                                                  ("Set_Speed", 20.0), ("Cfg_AllowHome", False)])),
)


def apply(w: aoi.World, move: tuple[Any, ...], rung: list[bool]) -> None:
    kind = move[0]
    if kind == "scan":
        rung[0] = move[1]
        w.scan({"Sync": rung[0]})
    elif kind == "prescan":
        rung[0] = False
        w.scan({}, prescan=True)
    elif kind == "set":
        w.set(*move[1])
        w.scan({"Sync": rung[0]})
    elif kind == "fire":
        w.fire(*move[1])
        w.scan({"Sync": rung[0]})
    else:
        w.instances["Sync"].inputs[move[1][0]] = move[1][1]
        w.scan({"Sync": rung[0]})


def run(w: aoi.World, moves: list[tuple[Any, ...]], rung: bool) -> list[dict[str, dict[str, object]]]:
    r = [rung]
    out = []
    for m in moves:
        apply(w, m, r)
        out.append(w.observe())
    return out


@settings(max_examples=150)
@given(st.lists(MOVES, max_size=25), st.lists(MOVES, min_size=1, max_size=25), st.booleans())
def test_restore_then_the_same_scans_give_the_same_world(before: list[Any], after: list[Any], rung: bool) -> None:
    w = world()
    run(w, before, False)
    snap = w.snapshot()
    hash(snap)
    first = run(w, after, rung)
    end = w.snapshot()
    w.restore(snap)
    assert w.snapshot() == snap
    assert run(w, after, rung) == first
    assert w.snapshot() == end
    # a freshly built world restored from the snapshot is the same world
    fresh = world()
    fresh.restore(snap)
    assert fresh.snapshot() == snap
    assert run(fresh, after, rung) == first
    assert fresh.snapshot() == end


def test_snapshots_are_deterministic_and_hashable() -> None:
    a, b = world(), world()
    assert a.snapshot() == b.snapshot() and hash(a.snapshot()) == hash(b.snapshot())
    for w in (a, b):
        for _ in range(7):
            w.scan({"Sync": True})
    assert a.snapshot() == b.snapshot()
    assert a.snapshot() != world().snapshot()


def test_snapshot_holds_every_part_of_the_state() -> None:
    """Changing any one part of the world changes the snapshot (the scan index excepted)."""
    base = world()
    ref = base.snapshot()
    changes = [
        lambda w: w.fire("Axis_Phy", "axis_fault"),
        lambda w: w.set("Axis_Phy", "position", 101.0),
        lambda w: w.set("Axis_Phy", "homed", False),
        lambda w: w.set("Axis_PTH", "velocity", 5.0),
        lambda w: w.set("AH_Hndl", "eState", 3),
        lambda w: w.set("AH_Hndl", "phy_axis", "Axis_PTH"),
        lambda w: w.instances["Sync"].inputs.update(Set_Speed=5.0),
        lambda w: w.instances["Sync"].outputs.update(Sts_ER=True),
        lambda w: setattr(w.instances["Sync"], "state", "checking"),
        lambda w: setattr(w.instances["Sync"], "path_verified", False),
        lambda w: w.instances["Sync"].registrations.update(AH_Hndl=1003),
    ]
    for change in changes:
        w = world()
        change(w)
        assert w.snapshot() != ref
    w = world()
    w.index = 99
    assert w.snapshot() == ref


def test_set_is_what_a_scenario_set_does(tmp_path: Path) -> None:
    """run_aoi_scenario applies `set:` through World.set: a fault set in a step is the chart's."""
    text = (OLD_FORMAT / "fault_during_recovery.yaml").read_text(encoding="utf-8")
    s = aoi.load_aoi_scenario("x.yaml", read_yaml(OLD_FORMAT / "fault_during_recovery.yaml", []), SPEC)
    assert "set: {Axis_Phy: {faulted: true}}" in text
    w = world()
    for _ in range(5):
        w.scan({"Sync": True})
    w.set("Axis_Phy", "faulted", True)
    w.scan({"Sync": True})
    result = aoi.run_aoi_scenario(s, SPEC)
    row = result.rows[5].record.observations
    assert row == w.observe()


# --------------------------------------------------------------------------- the chart runner

CIP_EVENTS = ["enable", "disable", "shutdown", "shutdown_reset", "fault_reset", "axis_fault", "motion_fault",
              "dc_bus_down", "dc_bus_up", "start_inhibit_set", "start_inhibit_cleared", "tick", "tick",
              "connection_loss", "connection_established", "run_test"]


@settings(max_examples=60)
@given(st.lists(st.sampled_from(CIP_EVENTS), max_size=30), st.sampled_from(["Running", "Stopped", "Faulted", "Shutdown"]))
def test_memoised_runner_agrees_with_a_fresh_engine_instance(events: list[str], state: str) -> None:
    chart = MAIN.chart("AxisCIP")
    variables = {"Connected": True, "DCBusUp": True}
    runner = aoi.chart_runner(chart, 50)
    snap = runner.initial(state, variables)
    ref = AxisInstance(chart, "ref", state=state, variables=variables,
                       parameters={"scan_ms": 50, "coarse_update_ms": 50})
    assert snap == ref.snapshot()
    for e in events:
        snap = runner.send(snap, e)
        ref.apply_event_actions(e)
        ref.send(e)
        assert snap == ref.snapshot(), e


def test_cip_axis_state_observable_is_the_charts() -> None:
    """CIPAxisState and `state` are the AxisCIP chart's, event by event (values from 001)."""
    w = world()
    chart = MAIN.chart("AxisCIP")
    ref = AxisInstance(chart, "ref", state="Running", variables={"Connected": True, "DCBusUp": True},
                       parameters={"scan_ms": 50, "coarse_update_ms": 50})
    expected = {"axis_fault": 7, "tick": 8, "fault_reset": 2, "enable": 3}  # Aborting, Faulted, Stopped, Starting
    assert w.observe()["Axis_Phy"]["CIPAxisState"] == 4
    for e, value in expected.items():
        w.fire("Axis_Phy", e)
        ref.apply_event_actions(e)
        ref.send(e)
        obs = w.observe()["Axis_Phy"]
        assert obs["CIPAxisState"] == ref.value == value
        assert obs["state"] == ref.leaf.id


# --------------------------------------------------------------------------- the mapping (hand-written from 003, 001)

def test_major_fault_fired_on_the_cip_chart_gives_1010_in_physical_mode() -> None:
    w = world()
    w.fire("Axis_Phy", "axis_fault")
    assert w.observe()["Axis_Phy"]["CIPAxisState"] == 7  # Aborting: faulted for the instruction
    assert w.axes["Axis_Phy"].faulted is True
    assert code_after_rung_true(w) == 1010
    assert w.observe()["Axis_Phy"]["CIPAxisState"] == 8  # the stop took one coarse update


def test_fault_on_the_physical_axis_does_not_matter_in_virtual_mode() -> None:
    w = world(AH_Hndl={"mode": "virtual"})
    w.fire("Axis_Phy", "axis_fault")
    assert code_after_rung_true(w) == 0  # 1010 only applies in Physical mode (003 §2.4 1010)
    assert w.instances["Sync"].outputs["Sts_PC"] is True


def test_minor_fault_does_not_fault_the_axis() -> None:
    """An axis exception configured as minor only latches (001 Aborting/Faulted): no 1010."""
    w = world(Axis_Phy={"variables": {"AxisExceptionAction": "Minor"}})
    w.set("Axis_Phy", "faulted", True)  # the chart refuses: the field keeps its value
    assert w.axes["Axis_Phy"].faulted is False and w.axes["Axis_Phy"].variable("MinorFault") is True
    assert code_after_rung_true(w) == 0
    assert w.instances["Sync"].outputs["Sts_IP"] is True


def test_shutdown_through_the_chart_gives_1010() -> None:
    w = world()
    w.fire("Axis_Phy", "shutdown")
    obs = w.observe()["Axis_Phy"]
    assert (obs["CIPAxisState"], obs["shutdown"], obs["energized"]) == (6, True, True)  # Stopping, shutdown in force
    assert code_after_rung_true(w) == 1010
    assert w.observe()["Axis_Phy"]["CIPAxisState"] == 10


@pytest.mark.parametrize("how", ["setup", "disable"])
def test_stopped_axis_gives_1118(how: str) -> None:
    if how == "setup":
        w = world(Axis_Phy={"energized": False})
    else:
        w = world()
        w.set("Axis_Phy", "energized", False)  # MSF: Stopping, then Stopped at the next coarse update
        w.scan({})
    assert w.observe()["Axis_Phy"]["CIPAxisState"] == 2
    assert code_after_rung_true(w) == 1118


def test_fault_reset_leaves_a_cip_axis_stopped_and_1118_follows() -> None:
    w = world(Axis_Phy={"faulted": True})
    assert w.observe()["Axis_Phy"]["CIPAxisState"] == 8
    assert code_after_rung_true(w) == 1010
    w.scan({})
    w.set("Axis_Phy", "faulted", False)
    assert w.observe()["Axis_Phy"]["CIPAxisState"] == 2
    assert code_after_rung_true(w) == 1118


def test_set_does_nothing_when_the_field_already_has_the_value() -> None:
    w = world(Axis_Phy={"faulted": True})
    before = w.snapshot()
    w.set("Axis_Phy", "shutdown", False)  # a Shutdown Reset would clear the fault: not sent
    w.set("Axis_Phy", "faulted", True)
    assert w.snapshot() == before


def test_disable_during_the_move_ends_it() -> None:
    """MSF during the recovery: Stopping, then Stopped; the move ends like a fault's (INT-068)."""
    w = world()
    for _ in range(3):
        w.scan({"Sync": True})
    w.set("Axis_Phy", "energized", False)
    w.scan({"Sync": True})
    w.scan({"Sync": True})
    o = w.instances["Sync"].outputs
    assert (o["Sts_IP"], o["Sts_PC"], o["Sts_ER"]) == (False, False, False)
    assert w.axes["Axis_Phy"].position == 103.0 and w.observe()["Axis_Phy"]["CIPAxisState"] == 2


@pytest.mark.parametrize(("event", "axis_state"), [("axis_fault", 3), ("shutdown", 4)])
def test_faulted_or_shut_down_virtual_axis_gives_1011(event: str, axis_state: int) -> None:
    w = world()
    w.fire("Axis_PTH", event)
    assert w.observe()["Axis_PTH"]["AxisState"] == axis_state
    assert code_after_rung_true(w) == 1011


def test_fault_stops_a_moving_path_axis() -> None:
    w = world(Axis_PTH={"velocity": 20.0})
    assert w.axes["Axis_PTH"].variable("Moving") is True
    w.set("Axis_PTH", "faulted", True)
    assert w.axes["Axis_PTH"].velocity == 0.0 and w.axes["Axis_PTH"].variable("Moving") is False
    w.set("Axis_PTH", "velocity", 5.0)  # refused while faulted
    assert w.axes["Axis_PTH"].velocity == 0.0


def test_virtual_axis_has_no_power_structure_to_set() -> None:
    w = world()
    assert w.axes["Axis_PTH"].energized is True
    with pytest.raises(ValueError, match="energized"):
        w.set("Axis_PTH", "energized", False)


def test_handler_chart_decides_1001_1000_and_the_mode() -> None:
    w = world()
    w.fire("AH_Hndl", "stop")
    assert w.observe()["AH_Hndl"]["running"] is False
    assert code_after_rung_true(w) == 1001
    w.scan({})
    w.set("AH_Hndl", "eState", 7)
    assert w.observe()["AH_Hndl"]["running"] is True
    w.set("AH_Hndl", "mode", "none")
    assert code_after_rung_true(w) == 1002
    full = world(AH_Hndl={"registered": 8})
    assert code_after_rung_true(full) == 1000
    assert full.observe()["AH_Hndl"]["registered"] == 8


def test_method_registers_through_the_handler_chart() -> None:
    w = world()
    w.scan({})
    assert w.handlers["AH_Hndl"].variable("Registered") == 3
    assert w.instances["Sync"].outputs["Sts_MtdID"] == 1003


def test_sts_pc_is_one_scan_after_the_target_is_reached() -> None:
    """INT-070: the motion update of scan k brings the position to 120; Sts_PC in scan k + 1."""
    w = world()
    reached = None
    for k in range(40):
        w.scan({"Sync": True})
        o = w.instances["Sync"].outputs
        if reached is None and w.axes["Axis_Phy"].position == 120.0:
            reached = k
            assert o["Sts_PC"] is False and o["Sts_IP"] is True
        if o["Sts_PC"]:
            assert reached is not None and k == reached + 1
            return
    pytest.fail("no Sts_PC")


# --------------------------------------------------------------------------- bad input

BASE = (OLD_FORMAT / "app_example_s4.yaml").read_text(encoding="utf-8")
PHY = "Axis_Phy: {type: AXIS_CIP_DRIVE, position: 100.0, unwind: 360.0, homed: true, energized: true}"
PTH = "Axis_PTH: {type: AXIS_VIRTUAL, position: 120.0, unwind: 360.0}"


@pytest.mark.parametrize(("old", "new", "message"), [
    (PHY, "Axis_Phy: {type: AXIS_CIP_DRIVE, state: Running, faulted: true}", "give either `state:`"),
    (PHY, "Axis_Phy: {type: AXIS_CIP_DRIVE, state: Flying}", "has no state 'Flying'"),
    (PHY, "Axis_Phy: {type: AXIS_CIP_DRIVE, variables: {Velocityy: 1}}", "has no variable 'Velocityy'"),
    (PHY, "Axis_Phy: {type: AXIS_CIP_DRIVE, variables: {StoppingUpdates: 9}}", "not in the domain of StoppingUpdates"),
    (PHY, "Axis_Phy: {type: AXIS_CIP_DRIVE, events: [explode]}", "has no event 'explode'"),
    (PTH, "Axis_PTH: {type: AXIS_VIRTUAL, energized: false}", "cannot be False at set-up"),
    ("AH_Hndl: {id: 1,", "AH_Hndl: {state: Running, id: 1,", "parallel regions"),
    ("set: {Axis_PTH: {velocity: 20.0}}", "set: {Axis_PTH: {energized: false}}", "cannot be set"),
    ("set: {Axis_PTH: {velocity: 20.0}}", "events: {Axis_PTH: [enable]}", "has no event 'enable'"),
    ("set: {Axis_PTH: {velocity: 20.0}}", "events: {Nobody: [enable]}", "unknown handler or axis 'Nobody'"),
])
def test_bad_chart_entries_are_located_errors(tmp_path: Path, old: str, new: str, message: str) -> None:
    assert old in BASE
    p = tmp_path / "bad.yaml"
    p.write_text(BASE.replace(old, new, 1), encoding="utf-8")
    from statecharts.scenario import load_scenario
    with pytest.raises(ScenarioError) as exc:
        load_scenario(p, load_spec())
    assert message in str(exc.value)
    assert f"{p}:" in str(exc.value)


def test_cli_reports_a_bad_event_without_traceback(tmp_path: Path) -> None:
    p = tmp_path / "bad.yaml"
    p.write_text(BASE.replace("set: {Axis_PTH: {velocity: 20.0}}", "events: {Axis_Phy: [explode]}"), encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "checker", "simulate", str(p)], capture_output=True, text=True, cwd=PROJECT)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr and "bad.yaml" in r.stderr and "explode" in r.stderr


def test_world_section_errors_are_located(tmp_path: Path) -> None:
    import shutil

    from statecharts.diagnostics import SpecError
    root = tmp_path / "spec"
    shutil.copytree(PROJECT / "spec", root, ignore=shutil.ignore_patterns("__pycache__", "*.py", "schema"))
    f = root / "addons" / "raM_Opr_SyncPthPhyAx_CD.yaml"
    text = f.read_text(encoding="utf-8")
    for old, new in [("fire: [axis_fault]}, {value: false, fire: [fault_reset]}], source: \"SYNC-RM §2.4 1010",
                      "fire: [axis_faults]}, {value: false, fire: [fault_reset]}], source: \"SYNC-RM §2.4 1010"),
                     ("{name: direct_control, variable: DirectControlStatus,", "{name: direct_control, variable: DirectControl,"),
                     ("chart: AxisVirtual", "chart: AxisVirtually"),
                     ("{name: tracking, when: \"'Running' in active\"", "{name: tracking, when: \"'Running' in activ\""),
                     ("- {when: \"energized\", state: Running}", "- {when: \"energized\", state: Runing}")]:
        assert old in text, old
        text = text.replace(old, new, 1)
    f.write_text(text, encoding="utf-8")
    with pytest.raises(SpecError) as exc:
        aoi.load_aoi(root)
    msg = str(exc.value)
    for needle in ("no event 'axis_faults'", "no variable 'DirectControl'", "unknown chart 'AxisVirtually'",
                   "activ", "no state 'Runing'"):
        assert needle in msg, (needle, msg)
    assert "raM_Opr_SyncPthPhyAx_CD.yaml:" in msg
