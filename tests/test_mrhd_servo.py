"""MRHD on servo-module axes (AXIS_SERVO, AXIS_SERVO_DRIVE): the In Process law over
random event sequences, every Test Status value and every error found by hypothesis
exploration, the 2 s time-out, the preconditions, and bad operand input.

Written from 000 (MRHD, "Description - AXIS_SERVO, AXIS_SERVO_DRIVE"): Test Status 0
success, 1 in process, 2 aborted, 3 time-out after 2 s, 4 servo fault, 5 insufficient
test increment; .IP set when the instruction starts and cleared when the test ends or is
terminated; PC and DN set together, IP cleared, on success; the extended errors 1, 12
and 16 under Servo Message Failure (12).  The codes chosen where 000 is silent are those
of INT-056 (preconditions) and INT-057 (how a test ends): they are written out by hand
below, never read from spec/.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest
from hypothesis import find, given, settings
from hypothesis import strategies as st

try:
    import statecharts  # noqa: F401  # only whether the project is installed
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from conftest import sampled

from statecharts import ir
from statecharts.diagnostics import ScenarioError
from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scan import EnvironmentEvent, ScanInputs, System
from statecharts.scenario import load_scenario

SPEC = load_spec()
#: a 1 s coarse update makes the 2 s time-out two updates long, so that random runs reach it
SCAN_MS = COARSE_MS = 1000
TAGS = ("mrhd", "msf", "masd", "mafr", "masr", "mso", "mdo", "mdf")
ENV = ("test_moved_forward", "test_moved_reverse", "marker_detected", "test_increment_insufficient",
       "test_cancelled", "servo_fault", "fault_cleared", "motion_started", "motion_stopped")
#: 000 Test Status (servo axes)
SUCCESS, IN_PROCESS, ABORTED, TIME_OUT, SERVO_FAULT, INCREMENT_FAULT = range(6)
#: how the instruction ends for each final Test Status (000 extended error 1; INT-057)
END_CODE = {ABORTED: (12, 1), TIME_OUT: (15, 0), SERVO_FAULT: (15, 0), INCREMENT_FAULT: (15, 0)}
#: 001 / domain-facts §3a AxisState values
AXIS_READY, DIRECT_DRIVE, SERVO_CONTROL, AXIS_FAULTED, SHUTDOWN = range(5)


def _system(start: str, variables: dict[str, object], coarse_ms: int = COARSE_MS) -> System:
    params = {"scan_ms": coarse_ms, "coarse_update_ms": coarse_ms}
    axis = AxisInstance(SPEC.chart("AxisNonCIP"), "A", state=start, variables=variables, parameters=params)
    program = [("mrhd", "MRHD", "A"), ("msf", "MSF", "A"), ("masd", "MASD", "A"), ("mafr", "MAFR", "A"),
               ("masr", "MASR", "A"), ("mso", "MSO", "A"), ("mdo", "MDO", "A"), ("mdf", "MDF", "A")]
    system = System(SPEC, [axis], program, scan_ms=coarse_ms, coarse_update_ms=coarse_ms)
    system.tags["mdo"].operands.update({"DriveOutput": 2.5, "DriveUnits": 0})
    return system


# MRHD's own rung and plain scans (which let the 2 s time-out run) are drawn more often
_STEP = st.one_of(
    st.tuples(st.just("rung"), st.sampled_from(("mrhd",) * 4 + TAGS[1:]), st.booleans()),
    st.tuples(st.just("event"), st.sampled_from(ENV), st.just(True)),
    st.tuples(st.just("idle"), st.just(""), st.just(True)),
    st.tuples(st.just("idle"), st.just(""), st.just(True)),
)
_RUN = st.fixed_dictionaries({
    "start": st.sampled_from(["AxisReady", "AxisReady", "AxisReady", "ServoControl", "DirectDriveControl",
                              "Shutdown", "AxisFaulted"]),
    "test": st.sampled_from([0, 0, 1, 2, 3, 7]),
    "axis_type": st.sampled_from(["AXIS_SERVO", "AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_VIRTUAL"]),
    "feedback_only": st.sampled_from([False, False, False, True]),
    "fault_action": st.sampled_from(["DisableDrive", "Shutdown", "StatusOnly"]),
    "increment": st.sampled_from([1.0, 1.0, 1.0, 0.0]),
    "configured": st.sampled_from([True, True, True, False]),
    "steps": st.lists(_STEP, max_size=14),
})


def _run(run: dict[str, object], check_law: bool = False) -> list[dict[str, dict[str, object]]]:
    variables: dict[str, object] = {
        "AxisType": run["axis_type"], "FaultAction": run["fault_action"],
        "MotorEncoderTestIncrement": run["increment"], "Configured": run["configured"],
    }
    if run["feedback_only"]:
        variables["AxisConfiguration"] = "FeedbackOnly"
    if run["start"] == "AxisFaulted":
        variables["ServoFault"] = True
    system = _system(str(run["start"]), variables)
    system.tags["mrhd"].operands.update({"DiagnosticTest": run["test"]})
    rungs = dict.fromkeys(TAGS, False)
    seen = []
    for kind, name, value in run["steps"]:
        events: tuple[EnvironmentEvent, ...] = ()
        if kind == "rung":
            rungs[name] = value
        elif kind == "event":
            events = (EnvironmentEvent("A", name),)
        record = system.scan(ScanInputs(rungs=dict(rungs), events=events))
        obs = {k: dict(v) for k, v in record.observations.items()}
        seen.append(obs)
        if check_law:
            _laws(obs)
    return seen


def _laws(obs: dict[str, dict[str, object]]) -> None:
    a, t = obs["A"], obs["mrhd"]
    status = a["TestStatus"]
    # Test Status is 1 exactly while the test is in process (IP) -- no prescan in these runs
    assert (status == IN_PROCESS) == bool(t["IP"]), obs
    assert SUCCESS <= status <= INCREMENT_FAULT
    # the TestStatus status bit: the axis is running a testing process
    assert a["TestStatusBit"] == (status == IN_PROCESS)
    # PC and DN together; IP never with DN, PC or ER
    assert bool(t["PC"]) == bool(t["DN"]) and not (t["IP"] and (t["DN"] or t["ER"] or t["PC"]))
    # a test in process: the motor/encoder test with the drive enabled (Drive Control
    # state), the encoder and marker tests in Axis Ready with the drive off
    if status == IN_PROCESS:
        if a["RunningTest"] == "MotorEncoder":
            assert a["AxisState"] == DIRECT_DRIVE and a["DriveEnableStatus"] is True
        else:
            assert a["AxisState"] == AXIS_READY and a["DriveEnableStatus"] is False
    # how the instruction ended matches the Test Status the module reported
    if t["DN"]:
        assert status == SUCCESS
    if t["ER"] and (t["ERR"], t["EXERR"]) == (12, 1):
        assert status == ABORTED
    if t["ER"] and t["ERR"] == 15:
        assert status in (TIME_OUT, SERVO_FAULT, INCREMENT_FAULT)


@given(run=_RUN)
def test_test_status_is_one_exactly_while_in_process(run: dict[str, object]) -> None:
    _run(run, check_law=True)


def _final(run: dict[str, object]) -> tuple[dict[str, object], dict[str, object]]:
    seen = _run(run)
    if not seen:
        return {}, {}
    return seen[-1]["A"], seen[-1]["mrhd"]


@pytest.mark.parametrize("status", sampled(range(6), fast={0, 1}))
def test_every_test_status_is_found_by_exploration(status: int) -> None:
    found = find(_RUN, lambda r: _final(r)[0].get("TestStatus") == status,
                 settings=settings(max_examples=5000, database=None, derandomize=True))
    axis, tag = _final(found)
    assert axis["TestStatus"] == status
    if status in END_CODE and tag["ER"] and tag["ERR"] in (12, 15) and not tag["IP"]:
        assert (tag["ERR"], tag["EXERR"]) in (END_CODE[status], (12, 12), (12, 16))


@pytest.mark.parametrize("err, exerr", sampled([(12, 1), (12, 12), (12, 16), (13, 2), (8, 0), (11, 0), (15, 0), (20, 0)], fast={(12, 16)}))
def test_every_mrhd_error_is_found_by_exploration(err: int, exerr: int) -> None:
    found = find(_RUN, lambda r: (lambda t: t.get("ER") and t.get("ERR") == err and t.get("EXERR") == exerr)(_final(r)[1]),
                 settings=settings(max_examples=5000, database=None, derandomize=True))
    assert (_final(found)[1]["ERR"], _final(found)[1]["EXERR"]) == (err, exerr)


def _first_scan(start: str, variables: dict[str, object], test: int) -> dict[str, dict[str, object]]:
    system = _system(start, variables, coarse_ms=10)
    system.tags["mrhd"].operands.update({"DiagnosticTest": test})
    return {k: dict(v) for k, v in system.scan(ScanInputs(rungs={"mrhd": True})).observations.items()}


# (start state, set-up variables, Diagnostic Test) -> (ERR, EXERR); INT-001, 002, 005, 056
PRECONDITIONS = [
    ("AxisReady", {"AxisType": "AXIS_VIRTUAL"}, 1, (8, 0)),
    ("AxisReady", {"AxisType": "AXIS_GENERIC"}, 0, (8, 0)),
    ("AxisReady", {"Configured": False}, 1, (11, 0)),
    ("AxisReady", {}, 7, (13, 2)),
    ("AxisReady", {}, -1, (13, 2)),
    ("AxisReady", {}, 3, (8, 0)),
    ("AxisReady", {"AxisType": "AXIS_SERVO_DRIVE"}, 3, (8, 0)),
    ("AxisReady", {"AxisConfiguration": "FeedbackOnly"}, 0, (8, 0)),
    ("Shutdown", {}, 2, (12, 12)),
    ("AxisFaulted", {"ServoFault": True}, 1, (20, 0)),
    ("ServoControl", {}, 1, (12, 16)),
    ("DirectDriveControl", {}, 0, (12, 16)),
    # order: the axis type before the module, the module before the test number,
    # the configuration before Shutdown, Shutdown before the state
    ("AxisReady", {"AxisType": "AXIS_VIRTUAL", "Configured": False}, 7, (8, 0)),
    ("AxisReady", {"Configured": False}, 7, (11, 0)),
    ("Shutdown", {"AxisConfiguration": "FeedbackOnly"}, 0, (8, 0)),
]


@pytest.mark.parametrize("start, variables, test, code", PRECONDITIONS)
def test_each_precondition_failure(start: str, variables: dict[str, object], test: int, code: tuple[int, int]) -> None:
    obs = _first_scan(start, variables, test)
    t = obs["mrhd"]
    assert (t["ER"], t["ERR"], t["EXERR"], t["IP"], t["DN"]) == (True, *code, False, False)
    assert obs["A"]["TestStatus"] == SUCCESS and obs["A"]["TestStatusBit"] is False


@pytest.mark.parametrize("axis_type", ["AXIS_SERVO", "AXIS_SERVO_DRIVE"])
@pytest.mark.parametrize("configuration, test", [("Servo", 0), ("Servo", 1), ("Servo", 2),
                                                  ("FeedbackOnly", 1), ("FeedbackOnly", 2)])
def test_tests_that_run(axis_type: str, configuration: str, test: int) -> None:
    obs = _first_scan("AxisReady", {"AxisType": axis_type, "AxisConfiguration": configuration}, test)
    assert obs["mrhd"]["IP"] is True and obs["mrhd"]["ER"] is False
    assert obs["A"]["TestStatus"] == IN_PROCESS and obs["A"]["TestStatusBit"] is True
    # only the motor/encoder test enables the drive
    assert obs["A"]["DriveEnableStatus"] is (test == 0)
    assert obs["A"]["AxisState"] == (DIRECT_DRIVE if test == 0 else AXIS_READY)


@pytest.mark.parametrize("coarse_ms", [10, 20, 30, 100, 250, 300, 500, 700])
def test_motor_encoder_time_out_is_two_seconds_of_coarse_updates(coarse_ms: int) -> None:
    system = _system("AxisReady", {}, coarse_ms=coarse_ms)
    system.tags["mrhd"].operands.update({"DiagnosticTest": 0})
    updates = math.ceil(2000 / coarse_ms)  # 000: 2 s; INT-057: counted from the starting update
    obs = system.scan(ScanInputs(rungs={"mrhd": True})).observations
    for _ in range(updates - 1):
        obs = system.scan(ScanInputs(rungs={"mrhd": True})).observations
        assert obs["A"]["TestStatus"] == IN_PROCESS and obs["mrhd"]["IP"] is True
    obs = system.scan(ScanInputs(rungs={"mrhd": True})).observations
    assert obs["A"]["TestStatus"] == TIME_OUT and obs["A"]["AxisState"] == AXIS_READY
    assert (obs["mrhd"]["ER"], obs["mrhd"]["ERR"], obs["mrhd"]["IP"]) == (True, 15, False)
    assert updates * coarse_ms >= 2000 > (updates - 1) * coarse_ms


@pytest.mark.parametrize("event, forward", [("test_moved_forward", True), ("test_moved_reverse", False)])
@pytest.mark.parametrize("test", [0, 1])
def test_direction_is_reported(event: str, forward: bool, test: int) -> None:
    system = _system("AxisReady", {"TestDirectionForward": not forward}, coarse_ms=10)
    system.tags["mrhd"].operands.update({"DiagnosticTest": test})
    system.scan(ScanInputs(rungs={"mrhd": True}))
    obs = system.scan(ScanInputs(rungs={"mrhd": True}, events=(EnvironmentEvent("A", event),))).observations
    assert obs["A"]["TestStatus"] == SUCCESS and obs["A"]["TestDirectionForward"] is forward
    assert (obs["mrhd"]["DN"], obs["mrhd"]["PC"], obs["mrhd"]["IP"]) == (True, True, False)
    assert obs["A"]["AxisState"] == AXIS_READY and obs["A"]["DriveEnableStatus"] is False


def test_marker_test_ignores_motion_and_ends_on_a_marker() -> None:
    system = _system("AxisReady", {}, coarse_ms=10)
    system.tags["mrhd"].operands.update({"DiagnosticTest": 2})
    system.scan(ScanInputs(rungs={"mrhd": True}))
    obs = system.scan(ScanInputs(rungs={"mrhd": True}, events=(EnvironmentEvent("A", "test_moved_forward"),))).observations
    assert obs["A"]["TestStatus"] == IN_PROCESS and obs["mrhd"]["IP"] is True
    obs = system.scan(ScanInputs(rungs={"mrhd": True}, events=(EnvironmentEvent("A", "marker_detected"),))).observations
    assert obs["A"]["TestStatus"] == SUCCESS and obs["mrhd"]["DN"] is True


def test_unknown_diagnostic_test_text_is_a_clear_scenario_error(tmp_path: Path) -> None:
    p = tmp_path / "bad.yaml"
    p.write_text(
        "format: motionchart-scenario/1\nname: bad\n"
        "setup:\n  axes:\n    A: {type: AXIS_SERVO}\n"
        "  program:\n    - {tag: t, instruction: MRHD, axis: A, operands: {DiagnosticTest: hookup}}\n"
        "steps:\n  - rungs: {t: true}\n", encoding="utf-8")
    with pytest.raises(ScenarioError) as exc:
        load_scenario(p, SPEC)
    text = str(exc.value)
    assert "DiagnosticTest" in text and "motor_encoder" in text and "marker" in text


def test_mrhd_variants() -> None:
    assert [i.id for i in SPEC.variants("MRHD")] == ["MRHD", "MRHD_SERVO"]
    servo = SPEC.instruction("MRHD", "AxisNonCIP")
    assert isinstance(servo, ir.Instruction) and servo.id == "MRHD_SERVO" and servo.mnemonic == "MRHD"
    assert set(servo.axis_types) == {"AXIS_SERVO", "AXIS_SERVO_DRIVE"}
    assert SPEC.instruction("MRHD", "AxisCIP").id == "MRHD"
