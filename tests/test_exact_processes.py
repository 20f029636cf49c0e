"""The codes that end an instruction after it was accepted, each produced **if and only
if** its documented condition holds: MDO's 12/1 (the axis left direct drive before the
output was applied), MRHD's 12/1 (the test was cancelled) and 15 (the test failed) on
servo and CIP axes, the CIP MSO and MDS 12/1 (the axis left Starting other than for
Running) and the CIP MSF 12/1 (an enable restarted the axis before the stop ended).

Each test accepts the instruction, then gives one disturbance at a chosen scan, and
predicts by hand, from the documents, how the instruction ends: DN, ER with which code,
or still in process.  Nothing is read from ``spec/``.

Sources: 000 (Test Status 0-5 servo, Hookup Test Status 0-6 CIP; extended error 1: a
test followed by a shutdown/disable or a motion stop is cancelled; .IP cleared when the
test is terminated by a stop, a shutdown or a servo fault), 001 (Starting, Stopping,
Testing, Aborting), 002 (500 ms enable delay, DN when the output is applied),
domain-facts §1a (15 Test Process Error), §3d (CIP transition table) and INT-013,
INT-044, INT-048, INT-057, INT-073, INT-075.
"""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scan import EnvironmentEvent, ScanInputs, System

SPEC = load_spec()
DN, ABORTED, FAILED, IN_PROCESS = "DN", (12, 1), (15, 0), "in process"


def _system(chart: str, state: str, variables: dict[str, object], program: list[tuple[str, str]],
            coarse_ms: int) -> System:
    axis = AxisInstance(SPEC.chart(chart), "A", state=state, variables=variables,
                        parameters={"scan_ms": coarse_ms, "coarse_update_ms": coarse_ms})
    assert axis.leaf.id == state
    return System(SPEC, [axis], [(t, m, "A") for t, m in program], scan_ms=coarse_ms, coarse_update_ms=coarse_ms)


def _outcome(tag: dict[str, object]) -> object:
    if tag["ER"]:
        return (int(tag["ERR"]), int(tag["EXERR"]))
    return DN if tag["DN"] else IN_PROCESS


def _drive(system: System, tag: str, disturbance: str, at: int, then: int, events: set[str]) -> object:
    """Raise ``tag``'s rung at scan 0, apply ``disturbance`` (an event of the axis, or the
    tag of another instruction whose rung goes true) at scan ``at``; the outcome of
    ``tag`` after ``then`` more scans."""
    rungs = dict.fromkeys(system.tags, False)
    rungs[tag] = True
    obs: Any = None
    before: object = IN_PROCESS  # an instruction that ended before the disturbance keeps its end
    for k in range(at + then + 1):
        evs: tuple[EnvironmentEvent, ...] = ()
        if k == at and disturbance != "none":
            if disturbance in events:
                evs = (EnvironmentEvent("A", disturbance),)
            else:
                rungs[disturbance] = True
        obs = system.scan(ScanInputs(rungs=dict(rungs), events=evs)).observations
        if k == at - 1:
            before = _outcome(obs[tag])
    return before if before != IN_PROCESS else _outcome(obs[tag])


# ------------------------------------------------------------------------ MDO 12/1

@given(disturbance=st.sampled_from(["none", "servo_fault", "msf", "mdf", "masd"]),
       action=st.sampled_from(["DisableDrive", "Shutdown", "StatusOnly", "StopMotion"]),
       at=st.integers(1, 8))
def test_mdo_ends_12_1_iff_the_axis_leaves_direct_drive_before_the_output(disturbance: str, action: str, at: int) -> None:
    # 002: the output is applied, and DN set, about 500 ms after the drive is enabled:
    # with 100 ms coarse updates, at the 5th update after the enabling one (scan 0)
    applied_at = 5
    leaves = disturbance in ("msf", "mdf", "masd") or (disturbance == "servo_fault" and action in ("DisableDrive", "Shutdown"))
    if disturbance == "none" or not leaves:
        expected: object = DN  # a Status Only or Stop Motion fault keeps direct drive (INT-003)
    else:
        expected = ABORTED if at < applied_at else DN  # INT-013
    system = _system("AxisNonCIP", "AxisReady", {"FaultAction": action},
                     [("mdo", "MDO"), ("msf", "MSF"), ("mdf", "MDF"), ("masd", "MASD")], 100)
    system.tags["mdo"].operands.update({"DriveOutput": 2.0, "DriveUnits": 0})
    assert _drive(system, "mdo", disturbance, at, max(0, applied_at - at) + 1, {"servo_fault"}) == expected


# ------------------------------------------------------------------------ MRHD on a servo axis

SERVO_EVENTS = {"test_moved_forward", "test_moved_reverse", "marker_detected", "test_increment_insufficient",
                "test_cancelled", "servo_fault"}


def servo_mrhd_expected(test: int, disturbance: str) -> object:
    """000: the motor/encoder and encoder tests end when the axis has moved the test
    increment (either way), the marker test on a marker pulse (Test Status 0: DN); a
    too small increment (5) or a servo fault (4) fails the test (15, INT-057); a motion
    stop, a shutdown or a disable cancels it (2: 12/1)."""
    if disturbance in ("test_moved_forward", "test_moved_reverse"):
        return DN if test in (0, 1) else IN_PROCESS
    if disturbance == "marker_detected":
        return DN if test == 2 else IN_PROCESS
    if disturbance == "test_increment_insufficient":
        return FAILED if test in (0, 1) else IN_PROCESS
    if disturbance == "servo_fault":
        return FAILED
    if disturbance in ("test_cancelled", "msf", "mdf", "masd"):
        return ABORTED
    return IN_PROCESS


@given(test=st.sampled_from([0, 1, 2]), disturbance=st.sampled_from([*sorted(SERVO_EVENTS), "msf", "mdf", "masd", "none"]),
       at=st.integers(1, 12))
def test_servo_mrhd_ends_12_1_or_15_iff_documented(test: int, disturbance: str, at: int) -> None:
    # 100 ms coarse updates: the 2 s time-out of the motor/encoder test is 20 updates
    # away, beyond the 14 scans of this run
    system = _system("AxisNonCIP", "AxisReady", {}, [("t", "MRHD"), ("msf", "MSF"), ("mdf", "MDF"), ("masd", "MASD")], 100)
    system.tags["t"].operands["DiagnosticTest"] = test
    assert _drive(system, "t", disturbance, at, 1, SERVO_EVENTS) == servo_mrhd_expected(test, disturbance)


@pytest.mark.parametrize("coarse_ms", [100, 250, 500])
def test_servo_motor_encoder_test_fails_exactly_at_two_seconds(coarse_ms: int) -> None:
    # 000: no sufficient motion within 2 s: time-out (Test Status 3), the test fails (15)
    updates = 2000 // coarse_ms
    system = _system("AxisNonCIP", "AxisReady", {}, [("t", "MRHD")], coarse_ms)
    outcomes = [_outcome(system.scan(ScanInputs(rungs={"t": True})).observations["t"]) for _ in range(updates + 1)]
    assert outcomes[:updates] == [IN_PROCESS] * updates and outcomes[updates] == FAILED


# ------------------------------------------------------------------------ MRHD on a CIP axis

CIP_EVENTS = {"test_moved_positive", "test_moved_negative", "marker_detected", "test_no_counts",
              "commutation_phasing_normal", "commutation_phasing_inverted", "axis_fault"}


def cip_mrhd_expected(test: int, disturbance: str) -> object:
    """000: the motor/encoder and encoder tests succeed on the test distance seen in
    either direction, the marker test on a marker pulse, the commutation test when it has
    found the phasing (Normal or Inverted, INT-075); no feedback counts (5, 6) or a fault
    (4) fail it (15); a disable or a shutdown cancels it (2: 12/1)."""
    if disturbance in ("test_moved_positive", "test_moved_negative"):
        return DN if test in (0, 1) else IN_PROCESS
    if disturbance == "marker_detected":
        return DN if test == 2 else IN_PROCESS
    if disturbance in ("commutation_phasing_normal", "commutation_phasing_inverted"):
        return DN if test == 3 else IN_PROCESS
    if disturbance in ("test_no_counts", "axis_fault"):
        return FAILED
    if disturbance in ("msf", "masd"):
        return ABORTED
    return IN_PROCESS


@given(test=st.sampled_from([0, 1, 2, 3]), feedback_only=st.booleans(),
       disturbance=st.sampled_from([*sorted(CIP_EVENTS), "msf", "masd", "none"]), at=st.integers(2, 10))
def test_cip_mrhd_ends_12_1_or_15_iff_documented(test: int, feedback_only: bool, disturbance: str, at: int) -> None:
    if feedback_only and test in (0, 3):
        test = 1  # 000: only the encoder and marker tests run on a feedback-only axis
    state = "Running" if feedback_only else "Stopped"
    variables: dict[str, object] = {"Connected": True, "DCBusUp": not feedback_only,
                                    "AxisConfiguration": "FeedbackOnly" if feedback_only else "Servo"}
    system = _system("AxisCIP", state, variables, [("t", "MRHD"), ("msf", "MSF"), ("masd", "MASD")], 10)
    system.tags["t"].operands["DiagnosticTest"] = test
    # with 10 ms coarse updates the motor/encoder time-out (2 s) is 200 updates away
    assert _drive(system, "t", disturbance, at, 2, CIP_EVENTS) == cip_mrhd_expected(test, disturbance)


# ------------------------------------------------------------------------ CIP MSO / MDS 12/1, MSF 12/1

STARTING_EVENTS = {"axis_fault", "safety_fault", "connection_loss", "start_inhibit_set"}


@given(mnemonic=st.sampled_from(["MSO", "MDS"]),
       disturbance=st.sampled_from(["none", "msf", "masd", *sorted(STARTING_EVENTS)]))
def test_cip_enable_ends_12_1_iff_the_axis_leaves_starting_other_than_to_running(mnemonic: str, disturbance: str) -> None:
    # 001 Starting: with the starting conditions met the axis goes to Running (DN); a
    # disable, a shutdown (through Stopping), a major fault (Aborting), a safety fault
    # (Stopped) or a lost connection take it elsewhere, and the request ends with 12/1
    # (INT-044).  An induction motor's flux-up keeps it in Starting for a second update.
    system = _system("AxisCIP", "Stopped", {"Connected": True, "DCBusUp": True, "MotorType": "Induction"},
                     [("t", mnemonic), ("msf", "MSF"), ("masd", "MASD")], 10)
    if mnemonic == "MDS":
        system.tags["t"].operands.update({"Speed": 10.0, "SpeedUnits": 0})
    leaves = disturbance in ("msf", "masd", "axis_fault", "safety_fault", "connection_loss")
    # a start inhibit appearing in Starting does not stop the start (001: Start Inhibited
    # is entered from Stopped)
    expected = ABORTED if leaves else DN
    assert _drive(system, "t", disturbance, 1, 3, STARTING_EVENTS) == expected


@given(flying=st.booleans(), enable=st.sampled_from(["none", "mso", "mds"]))
def test_cip_msf_ends_12_1_iff_an_enable_restarts_the_stopping_axis(flying: bool, enable: str) -> None:
    # 001 Starting: an Enable while Stopping with Flying Start restarts the axis
    # (domain-facts §3d Stopping/Enable, Flying Start Enable = 1); the MSF then never sees
    # Stopped and ends with 12/1 (INT-044); without Flying Start the enable is refused and
    # the stop completes (DN)
    system = _system("AxisCIP", "Running", {"Connected": True, "DCBusUp": True, "FlyingStartEnable": flying,
                                            "StoppingUpdates": 2},
                     [("msf", "MSF"), ("mso", "MSO"), ("mds", "MDS")], 10)
    system.tags["mds"].operands.update({"Speed": 10.0, "SpeedUnits": 0})
    expected = ABORTED if (flying and enable != "none") else DN
    assert _drive(system, "msf", enable, 1, 3, set()) == expected
