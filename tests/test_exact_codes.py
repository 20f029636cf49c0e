"""Every documented error code of the state instructions, MDO, MDS and MRHD (servo and
CIP variants) is produced **if and only if** its condition holds.

For each instruction the conditions and their order are written here by hand, from
the documents and the recorded interpretations, each with its source; nothing is read
from ``spec/``.  An instruction is executed once (rung false to true) on an axis set up
in a state with a configuration and operands, in a scan that is also a coarse update
(so the checks the motion module makes on the request are answered in that scan), and
its (ERR, EXERR) must be what the hand-written conditions give: the code of the first
condition that holds, or none.  Equality over every set-up is the if-and-only-if:
a code appears exactly where its condition holds and every earlier one fails.

Two ways of choosing set-ups: hypothesis draws them (with real-valued operands), and a
finite grid of the discrete values is enumerated completely, which also shows that
every listed code is reached.  The codes that end an instruction later (process
terminated, test failed) are in ``tests/test_exact_processes.py``.

Sources: 000 (MRHD), 001 (state instructions, CIP states), 002 (MDO), domain-facts §1a
(code numbers), §1b (EXERR 12, 16; ERR 13 operand index), §4 (per instruction), and
INT-001, 002, 004-009, 011, 042, 043, 045, 049, 054, 056, 076.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Mapping
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scan import ScanInputs, System

SPEC = load_spec()
Code = tuple[int, int] | None
PARAMS = {"scan_ms": 10, "coarse_update_ms": 10}

# ------------------------------------------------------------------------ the documents, by hand

#: domain-facts §4 MSO axis types (ControlLogix): servo-capable non-CIP data types
SERVO_TYPES = ("AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_GENERIC")
#: every non-CIP motion axis data type (MASD, MASR, MAFR act on any of them)
NONCIP_TYPES = ("AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_GENERIC", "AXIS_VIRTUAL")
#: 000 Operands: MRHD on AXIS_SERVO and AXIS_SERVO_DRIVE (besides AXIS_CIP_DRIVE)
MRHD_TYPES = ("AXIS_SERVO", "AXIS_SERVO_DRIVE")
NONCIP_STATES = ("AxisReady", "DirectDriveControl", "ServoControl", "AxisFaulted", "Shutdown")
NONCIP_INSTRUCTIONS = ("MSO", "MSF", "MASD", "MASR", "MAFR", "MDO", "MDF", "MRHD")


def first(checks: list[tuple[bool, tuple[int, int]]]) -> Code:
    """The code an ordered list of (condition, code) gives.

    ERR 12 (Servo Message Failure) is the motion module's (or drive's) reply to the
    request, so it arrives at the coarse update that delivers the request (INT-004);
    the other codes are found by the controller when the instruction executes, in the
    program scan before it.  So the first failing condition whose code is not 12 wins;
    if there is none, the first failing condition of all."""
    for holds, code in checks:
        if holds and code[0] != 12:
            return code
    for holds, code in checks:
        if holds:
            return code
    return None


def noncip_expected(mnemonic: str, s: Mapping[str, Any]) -> Code:
    """(ERR, EXERR) of ``mnemonic`` executed on a non-CIP axis set up as ``s``."""
    state, kind, servo, configured = s["state"], s["type"], s["config"] == "Servo", s["configured"]
    shutdown = state == "Shutdown"
    if mnemonic == "MDS":
        return (8, 0)  # domain-facts §4 MDS: AXIS_CIP_DRIVE only (INT-001)
    if mnemonic in ("MASD", "MASR", "MAFR"):
        return first([(kind not in NONCIP_TYPES, (8, 0)), (not configured, (11, 0))])  # §1a 11, INT-002
    if mnemonic == "MSF":
        return first([
            (kind not in SERVO_TYPES, (8, 0)),  # AXIS_VIRTUAL is not accepted (domain-facts §4 MSF, MSO)
            (not configured, (11, 0)),
            (shutdown, (12, 12)),  # Object Mode conflict, axis shut down (INT-009)
        ])
    if mnemonic == "MSO":
        return first([
            (kind not in SERVO_TYPES, (8, 0)),
            (not configured, (11, 0)),
            (not servo, (8, 0)),  # no servo loop on a feedback-only axis (INT-001)
            (shutdown, (12, 12)),  # RM002H-p79: Object Mode conflict
            (state == "AxisFaulted", (20, 0)),  # INT-005
            (state == "DirectDriveControl", (6, 0)),  # INT-006
            (s["moving"] and state == "AxisReady", (22, 0)),  # RM002H-p78: Axis In Motion (INT-008)
        ])
    if mnemonic == "MDF":
        return first([
            (kind != "AXIS_SERVO", (8, 0)),  # pair of MDO, AXIS_SERVO only
            (not configured, (11, 0)),
            (shutdown, (12, 12)),
            (state == "ServoControl", (4, 0)),  # INT-007
        ])
    if mnemonic == "MDO":
        out, units, limit = s["DriveOutput"], s["DriveUnits"], s["OutputLimit"]
        return first([
            (kind != "AXIS_SERVO", (8, 0)),  # 002 Operands: AXIS_SERVO only
            (not configured, (11, 0)),
            (not servo, (8, 0)),  # 002: the axis must be configured for Servo
            # 002 .ER: a Drive Output that is too large; the bound is the Output Limit in
            # volts and 100 % in percent (INT-011); Drive Output is operand 2 (§1b)
            (limit >= 0.0 and abs(out) > (limit if units == 0 else 100.0), (13, 2)),
            (units not in (0, 1), (13, 3)),  # 002 Operands: 0 Volts, 1 Percent; operand 3
            (shutdown, (12, 12)),  # 002 Extended Error Codes: 12, axis shut down
            (not limit >= 0.0, (12, 3)),  # a negative or NaN Output Limit: Invalid value (INT-054)
            (state == "ServoControl", (4, 0)),  # 002: servo action must be off
            (state == "DirectDriveControl", (6, 0)),
            (state == "AxisFaulted", (20, 0)),  # 002: Axis Ready only
        ])
    if mnemonic == "MRHD":
        test = s["DiagnosticTest"]
        return first([
            (kind not in MRHD_TYPES, (8, 0)),
            (not configured, (11, 0)),
            (test not in (0, 1, 2, 3), (13, 2)),  # 000 Operands; operand 2 (INT-056)
            (test == 3, (8, 0)),  # 000: the commutation test only on AXIS_CIP_DRIVE
            (test == 0 and not servo, (8, 0)),  # 000: the motor/encoder test needs a Servo axis
            (shutdown, (12, 12)),  # 000 extended error 12
            (state == "AxisFaulted", (20, 0)),
            (state != "AxisReady", (12, 16)),  # 000: Axis Ready; Device in wrong state (INT-076)
        ])
    raise AssertionError(mnemonic)


#: What each CIP start state needs to hold through one coarse update (001: Stopped has
#: its DC bus up, Shutdown is left only by a Shutdown Reset, faults are latched, ...).
CIP_START: dict[str, dict[str, object]] = {
    "Stopped": {"Connected": True, "DCBusUp": True},
    "Running": {"Connected": True, "DCBusUp": True},
    "PreCharge": {"Connected": True, "DCBusUp": False},
    "StartInhibited": {"Connected": True, "DCBusUp": True, "StartInhibit": True},
    "Shutdown": {"Connected": True, "DCBusUp": True, "ShutdownRequested": True},
    "Faulted": {"Connected": True, "DCBusUp": True, "MajorFault": True, "PhysicalAxisFault": True},
    "Aborting": {"Connected": True, "DCBusUp": True, "MajorFault": True, "PhysicalAxisFault": True,
                 "StoppingUpdates": 2, "Timer": 2},
    "Stopping": {"Connected": True, "DCBusUp": True, "StoppingUpdates": 2, "Timer": 2},
    "Testing": {"Connected": True, "DCBusUp": True, "TestRequested": True, "Timer": 2},
    "AxisInhibited": {"Inhibited": True},
    "NotGrouped": {"Grouped": False},
    "NoDevice": {"DeviceAssociated": False},
    "Initializing": {},
    "WaitingForGroup": {"Connected": True, "GroupSynchronized": False},
}
#: a feedback-only axis has no power structure: it is never Stopped, Starting, Testing...
#: (domain-facts §3d feedback-only table)
FEEDBACK_ONLY_STATES = ("Running", "StartInhibited", "Shutdown", "Faulted", "AxisInhibited", "NotGrouped",
                        "NoDevice", "Initializing", "WaitingForGroup")
STANDBY = ("Stopped", "PreCharge", "StartInhibited", "Shutdown", "Faulted")
CONNECTING = ("Initializing", "WaitingForGroup")
CIP_INSTRUCTIONS = ("MSO", "MSF", "MASD", "MASR", "MAFR", "MDS", "MRHD", "MDO", "MDF")


def cip_expected(mnemonic: str, s: Mapping[str, Any]) -> Code:
    """(ERR, EXERR) of ``mnemonic`` executed on a CIP axis set up as ``s``."""
    state, fb = s["state"], s["config"] == "FeedbackOnly"
    if mnemonic in ("MDO", "MDF"):
        return (8, 0)  # 002 Operands: AXIS_SERVO only (INT-001)
    checks: list[tuple[bool, tuple[int, int]]] = []
    if mnemonic in ("MSO", "MDS"):
        checks.append((fb, (8, 0)))  # no power structure to enable (INT-001)
    if mnemonic == "MDS":
        checks.append((s["SpeedUnits"] != 0, (13, 3)))  # units per second only; operand 3 (INT-045)
    if mnemonic == "MRHD":
        test = s["DiagnosticTest"]
        checks += [
            (test not in (0, 1, 2, 3), (13, 2)),  # 000 Operands; operand 2
            (fb and test in (0, 3), (8, 0)),  # 000: motor/encoder needs Servo; commutation applies current
            (test == 3 and s["MotorType"] != "PM", (8, 0)),  # 000: the commutation test is for PM motors
        ]
    # 001 Axis Inhibited, No Device / Not Grouped, Initializing (INT-042, INT-060)
    checks += [
        (state == "AxisInhibited", (53, 0)),
        (state in ("NoDevice", "NotGrouped"), (11, 0)),
        (state in CONNECTING, (82, 0)),
    ]
    if mnemonic in ("MASD", "MASR", "MAFR"):
        return first(checks)
    checks.append((state == "Shutdown", (12, 12)))  # Object Mode conflict (RM002H-p79, 000)
    if mnemonic == "MSF":
        return first(checks)
    checks.append((state in ("Faulted", "Aborting") or s["SafetyFault"], (20, 0)))  # INT-005
    if mnemonic == "MRHD":
        # 000: a servo axis must be Stopped (Run Test from Stopped, 001), a feedback-only
        # axis in its operating state; otherwise Device in wrong state (INT-049, INT-076)
        checks.append((state != ("Running" if fb else "Stopped"), (12, 16)))
        return first(checks)
    if mnemonic == "MDS":
        # RM002H-p578: MDS errs under planner control (INT-045)
        checks.append((state == "Running" and not s["DirectControlStatus"], (82, 0)))
    # 001 Pre-Charge: an enable is refused; Start Inhibited, a stop without flying start and
    # a running test likewise (INT-043)
    checks += [
        (state == "PreCharge", (12, 16)),
        (state == "StartInhibited", (12, 16)),
        ((state == "Stopping" and not s["FlyingStartEnable"]) or state == "Testing", (12, 16)),
    ]
    return first(checks)


# ------------------------------------------------------------------------ running one execution

def _execute(chart: str, state: str, variables: dict[str, object], mnemonic: str,
             operands: dict[str, object]) -> tuple[Code, dict[str, object]]:
    axis = AxisInstance(SPEC.chart(chart), "A", state=state, variables=variables, parameters=PARAMS)
    assert axis.leaf.id == state, f"set-up does not hold: {state} became {axis.leaf.id} with {variables}"
    system = System(SPEC, [axis], [("t", mnemonic, "A")], scan_ms=10, coarse_update_ms=10)
    system.tags["t"].operands.update(operands)
    obs = system.scan(ScanInputs(rungs={"t": True})).observations
    t = obs["t"]
    code = (int(t["ERR"]), int(t["EXERR"])) if t["ER"] else None
    if code is None:
        assert (t["ERR"], t["EXERR"]) == (0, 0)
    return code, dict(obs["A"])


def noncip_run(mnemonic: str, s: Mapping[str, Any]) -> Code:
    variables: dict[str, object] = {
        "AxisType": s["type"], "AxisConfiguration": s["config"], "Configured": s["configured"],
        "Moving": s["moving"], "OutputLimit": s["OutputLimit"],
    }
    if s["state"] == "AxisFaulted":
        variables["ServoFault"] = True  # 001 Axis Faulted: a servo fault is present
    operands: dict[str, object] = {}
    if mnemonic == "MDO":
        operands = {"DriveOutput": s["DriveOutput"], "DriveUnits": s["DriveUnits"]}
    if mnemonic == "MRHD":
        operands = {"DiagnosticTest": s["DiagnosticTest"]}
    return _execute("AxisNonCIP", s["state"], variables, mnemonic, operands)[0]


def cip_run(mnemonic: str, s: Mapping[str, Any]) -> Code:
    variables = dict(CIP_START[s["state"]])
    variables.update({"AxisConfiguration": s["config"], "FlyingStartEnable": s["FlyingStartEnable"],
                      "MotorType": s["MotorType"], "SafetyFault": s["SafetyFault"],
                      "DirectControlStatus": s["DirectControlStatus"]})
    operands: dict[str, object] = {}
    if mnemonic == "MDS":
        operands = {"Speed": s["Speed"], "SpeedUnits": s["SpeedUnits"]}
    if mnemonic == "MRHD":
        operands = {"DiagnosticTest": s["DiagnosticTest"]}
    return _execute("AxisCIP", s["state"], variables, mnemonic, operands)[0]


# ------------------------------------------------------------------------ set-ups

noncip_setups = st.fixed_dictionaries({
    "state": st.sampled_from(NONCIP_STATES),
    "type": st.sampled_from(NONCIP_TYPES),
    "config": st.sampled_from(["Servo", "Servo", "FeedbackOnly"]),
    "configured": st.sampled_from([True, True, False]),
    "moving": st.booleans(),
    "OutputLimit": st.one_of(st.floats(-2.0, 10.0, allow_nan=False), st.just(math.nan), st.sampled_from([0.0, 5.0])),
    "DriveOutput": st.one_of(st.floats(-200.0, 200.0, allow_nan=False), st.sampled_from([0.0, 5.0, -5.0, 100.0])),
    "DriveUnits": st.sampled_from([0, 0, 1, 1, 2, 5]),
    "DiagnosticTest": st.sampled_from([0, 1, 2, 3, 4, 7, -1]),
})


@st.composite
def cip_setups(draw: Any) -> dict[str, Any]:
    fb = draw(st.sampled_from([False, False, True]))
    state = draw(st.sampled_from(FEEDBACK_ONLY_STATES if fb else tuple(CIP_START)))
    return {
        "state": state, "config": "FeedbackOnly" if fb else "Servo",
        "FlyingStartEnable": draw(st.booleans()),
        "MotorType": draw(st.sampled_from(["PM", "Induction"])),
        # a safety fault ends in Stopped (001): latched only in a standby state here
        "SafetyFault": draw(st.booleans()) if state in STANDBY else False,
        "DirectControlStatus": draw(st.booleans()) if state == "Running" else False,
        "Speed": draw(st.floats(-100.0, 100.0, allow_nan=False)),
        "SpeedUnits": draw(st.sampled_from([0, 0, 0, 1, 2])),
        "DiagnosticTest": draw(st.sampled_from([0, 1, 2, 3, 7])),
    }


@pytest.mark.parametrize("mnemonic", (*NONCIP_INSTRUCTIONS, "MDS"))
@given(s=noncip_setups)
def test_noncip_codes_if_and_only_if(mnemonic: str, s: dict[str, Any]) -> None:
    assert noncip_run(mnemonic, s) == noncip_expected(mnemonic, s), s


@pytest.mark.parametrize("mnemonic", CIP_INSTRUCTIONS)
@given(s=cip_setups())
def test_cip_codes_if_and_only_if(mnemonic: str, s: dict[str, Any]) -> None:
    assert cip_run(mnemonic, s) == cip_expected(mnemonic, s), s


# ------------------------------------------------------------------------ the complete grid

#: every documented (ERR, EXERR) of each instruction, as listed by the documents and the
#: interpretations above; the grid must reach each one
NONCIP_CODES = {
    "MSO": {(8, 0), (11, 0), (12, 12), (20, 0), (6, 0), (22, 0)},
    "MSF": {(8, 0), (11, 0), (12, 12)},
    "MASD": {(11, 0)}, "MASR": {(11, 0)}, "MAFR": {(11, 0)},
    "MDF": {(8, 0), (11, 0), (12, 12), (4, 0)},
    "MDO": {(8, 0), (11, 0), (13, 2), (13, 3), (12, 12), (12, 3), (4, 0), (6, 0), (20, 0)},
    "MRHD": {(8, 0), (11, 0), (13, 2), (12, 12), (20, 0), (12, 16)},
    "MDS": {(8, 0)},
}
CIP_CODES = {
    "MSO": {(8, 0), (53, 0), (11, 0), (82, 0), (12, 12), (20, 0), (12, 16)},
    "MDS": {(8, 0), (13, 3), (53, 0), (11, 0), (82, 0), (12, 12), (20, 0), (12, 16)},
    "MSF": {(53, 0), (11, 0), (82, 0), (12, 12)},
    "MASD": {(53, 0), (11, 0), (82, 0)}, "MASR": {(53, 0), (11, 0), (82, 0)}, "MAFR": {(53, 0), (11, 0), (82, 0)},
    "MRHD": {(13, 2), (8, 0), (53, 0), (11, 0), (82, 0), (12, 12), (20, 0), (12, 16)},
    "MDO": {(8, 0)}, "MDF": {(8, 0)},
}


def _noncip_grid(mnemonic: str) -> Iterator[dict[str, Any]]:
    base = {"OutputLimit": 5.0, "DriveOutput": 1.0, "DriveUnits": 0, "DiagnosticTest": 0}
    if mnemonic == "MDO":
        extra = [{"DriveOutput": d, "DriveUnits": u, "OutputLimit": lim}
                 for d, u, lim in itertools.product([1.0, 6.0, 150.0], [0, 1, 2], [5.0, -1.0])]
    elif mnemonic == "MRHD":
        extra = [{"DiagnosticTest": t} for t in (0, 1, 3, 7)]
    else:
        extra = [{}]
    for state, kind, config, configured, moving in itertools.product(
            NONCIP_STATES, NONCIP_TYPES, ("Servo", "FeedbackOnly"), (True, False), (False, True)):
        if not configured and (kind != "AXIS_SERVO" or config != "Servo" or moving):
            continue  # enough to show 11
        for e in extra:
            yield {**base, "state": state, "type": kind, "config": config, "configured": configured,
                   "moving": moving, **e}


def _cip_grid(mnemonic: str) -> Iterator[dict[str, Any]]:
    extra: list[dict[str, Any]] = [{}]
    if mnemonic == "MDS":
        extra = [{"SpeedUnits": u} for u in (0, 1)]
    if mnemonic == "MRHD":
        extra = [{"DiagnosticTest": t, "MotorType": m} for t, m in
                 [(0, "PM"), (1, "PM"), (3, "PM"), (3, "Induction"), (7, "PM")]]
    for state in CIP_START:
        for fb in (False, True):
            if fb and state not in FEEDBACK_ONLY_STATES:
                continue
            for flying, safety, direct in itertools.product((False, True), repeat=3):
                if (safety and state not in STANDBY) or (direct and state != "Running"):
                    continue
                if flying and state != "Stopping":
                    continue
                for e in extra:
                    yield {"state": state, "config": "FeedbackOnly" if fb else "Servo", "FlyingStartEnable": flying,
                           "MotorType": "PM", "SafetyFault": safety, "DirectControlStatus": direct,
                           "Speed": 10.0, "SpeedUnits": 0, "DiagnosticTest": 0, **e}


@pytest.mark.parametrize("mnemonic", sorted(NONCIP_CODES))
def test_noncip_grid_every_code_exactly_where_documented(mnemonic: str) -> None:
    seen = set()
    for s in _noncip_grid(mnemonic):
        expected = noncip_expected(mnemonic, s)
        assert noncip_run(mnemonic, s) == expected, s
        seen.add(expected)
    assert NONCIP_CODES[mnemonic] <= seen, f"codes the grid never reaches: {NONCIP_CODES[mnemonic] - seen}"


@pytest.mark.parametrize("mnemonic", sorted(CIP_CODES))
def test_cip_grid_every_code_exactly_where_documented(mnemonic: str) -> None:
    seen = set()
    for s in _cip_grid(mnemonic):
        expected = cip_expected(mnemonic, s)
        assert cip_run(mnemonic, s) == expected, s
        seen.add(expected)
    assert CIP_CODES[mnemonic] <= seen, f"codes the grid never reaches: {CIP_CODES[mnemonic] - seen}"


def test_every_catalogued_extended_error_of_these_instructions_is_covered() -> None:
    """Each (instruction, ERR, EXERR) of errors.yaml for these instructions is either a
    code checked here or one that ends a process (tests/test_exact_processes.py)."""
    ended_later = {("MSO", 12, 1), ("MDS", 12, 1), ("MSF", 12, 1), ("MRHD", 12, 1), ("MDO", 12, 1),
                   # SERCOS-only reasons of MSO (RM002H-p79) that no modelled axis produces
                   ("MSO", 12, 15), ("MSO", 12, 16)}
    checked = {(m, e, x) for m, codes in NONCIP_CODES.items() for (e, x) in codes}
    checked |= {(m, e, x) for m, codes in CIP_CODES.items() for (e, x) in codes}
    these = {m for m, _e, _x in checked | ended_later}
    for ext in SPEC.extended_errors:
        key = (ext.instruction, ext.err, ext.exerr)
        if ext.instruction not in these:
            continue  # another instruction family (the move instructions): not this file's grid
        assert key in checked or key in ended_later, key
