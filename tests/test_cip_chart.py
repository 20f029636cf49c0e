"""The CIP axis chart (AXIS_CIP_DRIVE): state values, scenario coverage of every
transition, and the Fault Reset precedence as a property.

Expectations here are written from the documents, not read from the spec:

* the CIPAxisState values and names (001 CIP operating states; domain-facts §3b);
* the Fault Reset precedence Faulted > Shutdown > Pre-Charge > Start Inhibited >
  Stopped (domain-facts §3d, RA37 motion-control-axis-behavior-model, C), written as an
  independent function :func:`documented_fault_reset_target`;
* the transitions named in the issue, each of which some hand-written scenario under
  ``scenarios/cip/`` must declare it covers.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

try:
    import statecharts  # noqa: F401
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scenario import load_scenario, run_scenario

CIP_DIR = Path(__file__).resolve().parents[1] / "scenarios" / "cip"
MRHD_DIR = Path(__file__).resolve().parents[1] / "scenarios" / "mrhd"

#: CIPAxisState values (001; domain-facts §3b).  16 Waiting for Group is not modelled.
DOCUMENTED_VALUES = {
    0: "Initializing", 1: "PreCharge", 2: "Stopped", 3: "Starting", 4: "Running",
    5: "Testing", 6: "Stopping", 7: "Aborting", 8: "Faulted", 9: "StartInhibited",
    10: "Shutdown", 11: "AxisInhibited", 12: "NotGrouped", 13: "NoDevice",
    14: "Configuring", 15: "Synchronizing",
}

#: Transitions the issue and the documents name (001; domain-facts §3d incl. the
#: feedback-only table), as the cover ids the scenarios declare.
DOCUMENTED_TRANSITIONS = (
    # DC bus
    "CIP.bus_up", "CIP.bus_down_stopped", "CIP.bus_down_inhibited", "CIP.bus_down_active",
    # Enable / Disable / Run Test / start and stop complete / flying start
    "CIP.enable", "CIP.run_test", "CIP.start_complete", "CIP.start_complete_test",
    "CIP.disable_starting", "CIP.disable_running", "CIP.disable_testing", "CIP.test_complete",
    "CIP.stop_complete", "CIP.stop_complete_shutdown", "CIP.flying_start",
    # start inhibits
    "CIP.start_inhibited", "CIP.start_inhibits_cleared",
    # faults
    "CIP.major_fault_starting", "CIP.major_fault_running", "CIP.major_fault_testing",
    "CIP.major_fault_stopping", "CIP.minor_fault_stopping", "CIP.abort_complete",
    "CIP.major_fault_precharge", "CIP.major_fault_stopped", "CIP.major_fault_inhibited",
    "CIP.major_fault_shutdown", "CIP.safety_fault_stop", "CIP.safety_fault_shutdown",
    "CIP.init_fault", "CIP.power_cycle",
    # shutdown and shutdown reset
    "CIP.shutdown_stopped", "CIP.shutdown_running", "CIP.shutdown_testing", "CIP.shutdown_reset",
    "CIP.shutdown_reset_faulted", "CIP.shutdown_action.drop_dc_bus", "CIP.shutdown_action.keep_dc_bus",
    # fault reset
    "CIP.fault_reset_shutdown", "CIP.fault_reset_precharge", "CIP.fault_reset_inhibited",
    "CIP.fault_reset_stopped", "CIP.fault_reset_aborting", "CIP.fault_reset_persisting",
    # connection, inhibit, self-test
    "CIP.connection_close", "CIP.connection_loss", "CIP.reconnection",
    "CIP.inhibit_operational", "CIP.uninhibit", "CIP.qualify_not_grouped", "CIP.qualify_no_device",
    "CIP.connect", "CIP.configured", "CIP.init_complete",
    # feedback-only table
    "CIP.init_complete_feedback_only", "CIP.feedback_only_inhibits_cleared",
    "CIP.shutdown_running_feedback_only", "CIP.shutdown_reset_feedback_only",
    "CIP.major_fault_feedback_only", "CIP.fault_reset_running_feedback_only",
    # instructions
    "MSO.PreCharge.err12_16", "MSO.Shutdown.err12_12", "MSO.Faulted.err20", "MSO.StartInhibited.err12_16",
    "MDS.direct_control_status.set", "MSO.direct_control_status.cleared_from_stopped", "MDS.Running.err82",
)


def documented_fault_reset_target(*, unrecoverable: bool, shutdown: bool, bus_up: bool, start_inhibit: bool) -> str:
    """Where a Fault Reset takes a Faulted CIP axis, by the documented precedence."""
    if unrecoverable:
        return "Faulted"
    if shutdown:
        return "Shutdown"
    if not bus_up:
        return "PreCharge"
    if start_inhibit:
        return "StartInhibited"
    return "Stopped"


@pytest.fixture(scope="module")
def spec() -> ir.Spec:
    return load_spec()


def _covers(spec: ir.Spec) -> set[str]:
    files = sorted(CIP_DIR.glob("*.yaml")) + sorted(MRHD_DIR.glob("*.yaml"))
    return {c for p in files for c in load_scenario(p, spec).covers}


def test_cip_state_values_are_the_documented_ones(spec: ir.Spec) -> None:
    chart = spec.chart("AxisCIP")
    assert chart.state_attribute == "CIPAxisState"
    got = {s.value: s.id for s in chart.leaf_states()}
    assert got == DOCUMENTED_VALUES


def test_every_documented_transition_is_covered(spec: ir.Spec) -> None:
    covers = _covers(spec)
    missing = [c for c in DOCUMENTED_TRANSITIONS if c not in covers]
    assert not missing, f"documented CIP transitions no scenario covers: {missing}"


def test_every_chart_transition_is_covered(spec: ir.Spec) -> None:
    covers = _covers(spec)
    missing = [t.id for t in spec.chart("AxisCIP").transitions if f"CIP.{t.id}" not in covers]
    assert not missing, f"AxisCIP transitions no scenario declares: {missing}"


@pytest.mark.parametrize("path", sorted(CIP_DIR.glob("*.yaml")), ids=lambda p: p.stem)
def test_cip_scenario_passes(path: Path, spec: ir.Spec) -> None:
    result = run_scenario(load_scenario(path, spec), spec)
    assert result.passed, "\n".join(str(m) for m in result.mismatches)


_FAULTS = ("axis_fault", "module_fault", "group_fault", "configuration_fault")


@given(
    unrecoverable=st.sampled_from(["none", "initialization", "connection"]),
    shutdown=st.booleans(), bus_up=st.booleans(), start_inhibit=st.booleans(),
    faults=st.lists(st.sampled_from(_FAULTS + ("safety_fault", "motion_fault")), max_size=4),
)
def test_fault_reset_precedence_from_faulted(
    spec: ir.Spec, unrecoverable: str, shutdown: bool, bus_up: bool, start_inhibit: bool, faults: list[str]
) -> None:
    """A Faulted axis with any combination of shutdown, bus, inhibit and latched faults."""
    axis = AxisInstance(spec.chart("AxisCIP"), "A", state="Faulted", variables={
        "Connected": unrecoverable != "connection", "InitializationFault": unrecoverable == "initialization",
        "ModuleFault": unrecoverable == "connection", "MajorFault": True,
        "ShutdownRequested": shutdown, "DCBusUp": bus_up, "StartInhibit": start_inhibit,
    })
    for f in faults:
        axis.apply_event_actions(f)
        axis.send(f)
    assert axis.leaf.id == "Faulted"
    axis.send("fault_reset")
    want = documented_fault_reset_target(
        unrecoverable=unrecoverable != "none", shutdown=shutdown, bus_up=bus_up, start_inhibit=start_inhibit)
    assert axis.leaf.id == want


_STEPS = st.sampled_from([
    ("env", "start_inhibit_set"), ("env", "start_inhibit_cleared"), ("env", "dc_bus_down"),
    ("env", "dc_bus_up"), ("req", "shutdown"), ("req", "shutdown_reset"), ("req", "fault_reset"),
    ("env", "safety_fault"), ("env", "motion_fault"), *(("env", f) for f in _FAULTS), ("clock", "tick"),
])


@given(steps=st.lists(_STEPS, max_size=12), final_fault=st.sampled_from(_FAULTS))
def test_fault_reset_precedence_after_random_history(
    spec: ir.Spec, steps: list[tuple[str, str]], final_fault: str
) -> None:
    """Random shutdown / inhibit / bus / fault histories, then a major fault and a Fault Reset.

    The test keeps its own record of the documented conditions: a Shutdown request
    stays in force until a Shutdown Reset; the bus and the start inhibits follow their
    last event.
    """
    axis = AxisInstance(spec.chart("AxisCIP"), "A", state="Stopped", variables={"Connected": True, "DCBusUp": True})
    shutdown, bus_up, inhibit = False, True, False
    for kind, name in steps:
        if kind == "env":
            axis.apply_event_actions(name)
        axis.send(name)
        if name == "shutdown":
            shutdown = True
        elif name == "shutdown_reset":
            shutdown = False
        elif name in ("dc_bus_up", "dc_bus_down"):
            bus_up = name == "dc_bus_up"
        elif name in ("start_inhibit_set", "start_inhibit_cleared"):
            inhibit = name == "start_inhibit_set"
    axis.apply_event_actions("axis_fault" if final_fault == "axis_fault" else final_fault)
    axis.send(final_fault)
    assert axis.leaf.id == "Faulted"  # no power structure was ever enabled: straight to Faulted
    axis.send("fault_reset")
    assert axis.leaf.id == documented_fault_reset_target(
        unrecoverable=False, shutdown=shutdown, bus_up=bus_up, start_inhibit=inhibit)
