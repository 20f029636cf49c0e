"""raM_Opr_SyncPthPhyAx_CD: the codes of its sub-instructions that fail **later in a
multi-scan recovery** (1020 MAH, 1022 MAM, 1023 MAG) are produced if and only if the
sub-instruction's condition holds when the recovery issues it; a fault of the physical
axis during the recovery produces no code of its own and the next execution meets it
(1010).  The codes of the first scan are checked against an independent oracle in
``tests/test_aoi.py``.

Written by hand from 003 (§1.2: the object may home the axis before the recovery,
§2.2: the physical axis is geared to the path axis, §2.4: 1020, 1022, 1023 carry the
sub-instruction's .ERR in Sts_EXERR, 1010 for a faulted physical axis), domain-facts §4
(MAH, MAM, MAG; Direct Control makes planner instructions err, a MAG while the master
homes fails with 16) and INT-030 (87 in Direct Control, 16 while homing), INT-046,
INT-071.  Nothing is read from ``spec/``.  The recovery runs on the main scan (its calls
are the main MAH, MAM and MAG charts, answering at the coarse update; docs/semantics.md,
the level rung), in the worlds of tests/aoi_helpers.py.
"""

from __future__ import annotations

from typing import Any

import aoi_helpers as ah
from hypothesis import given
from hypothesis import strategies as st

from statecharts.scan import System

DIRECT_CONTROL, HOMING_IN_PROCESS = 87, 16  # domain-facts §1a (INT-030)
#: scans an execution with nothing to travel takes to end: each call answers at the
#: coarse update of the scan that issues it, read in the next scan
SETTLE_SCANS = 6


def _world(phy: dict[str, Any], pth: dict[str, Any], sync_type: int) -> System:
    ax = {"unwind": 360.0, "velocity": 0.0, "homed": True, "energized": True, "faulted": False, "shutdown": False,
          "homing": False, "control_mode": "position", "direct_control": False, "home_config_ok": True}
    axes = {"P1": {**ax, "type": "AXIS_CIP_DRIVE", "position": 100.0, **phy},
            "T1": {**ax, "type": "AXIS_VIRTUAL", "position": 100.0, **pth}}
    handlers = {"H1": {"id": 1, "registered": 2, "capacity": 8, "eState": 7, "mode": "physical",
                       "phy_axis": "P1", "pth_axis": "T1"}}
    inst = {"Ref_AxisPhy": "P1", "Ref_AxisPth": "T1", "Ref_Handle": "H1", "Cfg_SyncType": sync_type,
            "Cfg_AllowHome": True, "Cfg_TravelLIM": 0.0, "Cfg_RotaryShortestTOL": 0.0, "Cfg_MoveType": 0,
            "Set_Speed": 200.0, "path_verified": True}
    return ah.build(handlers, axes, inst)


def _outcome(system: System) -> tuple[int, int, str]:
    return ah.outcome(system)


def expected(homed: bool, distance: float, disturbance: str) -> tuple[int, int, str]:
    """How a SyncType 1 recovery that is in process after its first scan ends, when
    ``disturbance`` appears after that scan (003 §1.2: home if needed, then move to the
    path position, then gear to the path axis)."""
    if disturbance == "direct_control":
        # the next planner instruction the recovery issues meets Direct Control: MAM
        # after the homing that the first scan started, else MAG after the move that
        # the first scan started
        if not homed:
            return 1022, DIRECT_CONTROL, "error"
        return 1023, DIRECT_CONTROL, "error"
    if disturbance == "path_homing":
        return 1023, HOMING_IN_PROCESS, "error"  # MAG while its master homes
    if disturbance == "fault":
        return 0, 0, "none"  # INT-046: the call ends without a code; Sts_IP cleared
    return 0, 0, "complete"


@given(homed=st.booleans(), distance=st.sampled_from([0.0, 3.0, 40.0]),
       disturbance=st.sampled_from(["none", "direct_control", "path_homing", "fault"]))
def test_later_sub_instruction_failures_if_and_only_if(homed: bool, distance: float, disturbance: str) -> None:
    system = _world({"homed": homed}, {"position": 100.0 + distance}, 1)
    ah.scan(system, True)
    first = _outcome(system)
    if homed and not distance:
        # nothing to home or move: the recovery completes once its calls have answered (INT-070)
        for _ in range(SETTLE_SCANS):
            ah.scan(system, True)
        assert _outcome(system) == (0, 0, "complete")
        return
    assert first == (0, 0, "in_process")
    p1, t1 = system.axes["P1"], system.axes["T1"]
    if disturbance == "direct_control":
        p1.env["DirectControlStatus"] = True
    elif disturbance == "fault":
        ah.event(system, "P1", "axis_fault")
    for _ in range(200):
        if disturbance == "path_homing":
            # a homing sequence in process on the path axis at every scan (the drive
            # model's Immediate homing ends at each coarse update, INT-085)
            t1.env["HomingStatus"] = True
        ah.scan(system, True)
        if _outcome(system)[2] != "in_process":
            break
    assert _outcome(system) == expected(homed, distance, disturbance)
    if disturbance == "fault":
        # the next execution meets the fault in its checks: 1010 in Physical mode (003 §2.4)
        ah.scan(system, False)
        ah.scan(system, True)
        assert _outcome(system)[:2] == (1010, 0)


@given(direct_control=st.booleans())
def test_sync_type_0_ends_with_mag_1023_iff_the_physical_axis_is_in_direct_control(direct_control: bool) -> None:
    # INT-071: MRP on the path axis, then MAG of the physical axis onto the path axis
    system = _world({"direct_control": direct_control, "position": 42.0}, {"position": 7.0}, 0)
    for _ in range(SETTLE_SCANS):
        ah.scan(system, True)
    assert system.axes["T1"].env["ActualPosition"] == 42.0  # MRP redefined the path position
    assert _outcome(system) == ((1023, DIRECT_CONTROL, "error") if direct_control else (0, 0, "complete"))
    assert system.axes["H1"].env["OnPath"] is (not direct_control)  # 003 §1.3.1: OnPath once geared
