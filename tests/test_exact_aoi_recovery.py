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
INT-071.  Nothing is read from ``spec/``.
"""

from __future__ import annotations

from typing import Any

from hypothesis import given
from hypothesis import strategies as st

from statecharts import aoi

SPEC = aoi.load_aoi()
DIRECT_CONTROL, HOMING_IN_PROCESS = 87, 16  # domain-facts §1a (INT-030)


def _world(phy: dict[str, Any], pth: dict[str, Any], sync_type: int) -> aoi.World:
    ax = {"unwind": 360.0, "velocity": 0.0, "homed": True, "energized": True, "faulted": False, "shutdown": False,
          "homing": False, "control_mode": "position", "direct_control": False, "home_config_ok": True}
    axes = {"P1": {**ax, "type": "AXIS_CIP_DRIVE", "position": 100.0, **phy},
            "T1": {**ax, "type": "AXIS_VIRTUAL", "position": 100.0, **pth}}
    handlers = {"H1": {"id": 1, "registered": 2, "capacity": 8, "eState": 7, "mode": "physical",
                       "phy_axis": "P1", "pth_axis": "T1"}}
    inst = {"Ref_AxisPhy": "P1", "Ref_AxisPth": "T1", "Ref_Handle": "H1", "Cfg_SyncType": sync_type,
            "Cfg_AllowHome": True, "Cfg_TravelLIM": 0.0, "Cfg_RotaryShortestTOL": 0.0, "Cfg_MoveType": 0,
            "Set_Speed": 200.0, "path_verified": True}
    return aoi.build_world(SPEC, {"scan_ms": 10, "handlers": handlers, "axes": axes, "aoi": {"I": inst}})


def _outcome(world: aoi.World) -> tuple[int, int, str]:
    o = world.instances["I"].outputs
    state = "error" if o["Sts_ER"] else "complete" if o["Sts_PC"] else "in_process" if o["Sts_IP"] else "none"
    return int(o["Sts_ERR"]), int(o["Sts_EXERR"]), state


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
    world = _world({"homed": homed}, {"position": 100.0 + distance}, 1)
    world.scan({"I": True})
    first = _outcome(world)
    if homed and not distance:
        # nothing to home or move: MAG at once and complete in the first scan (INT-070)
        assert first == (0, 0, "complete")
        return
    assert first == (0, 0, "in_process")
    if disturbance == "direct_control":
        world.axes["P1"].direct_control = True
    elif disturbance == "path_homing":
        world.axes["T1"].homing = True
    elif disturbance == "fault":
        world.axes["P1"].faulted = True
    for _ in range(200):
        world.scan({"I": True})
        if _outcome(world)[2] != "in_process":
            break
    assert _outcome(world) == expected(homed, distance, disturbance)
    if disturbance == "fault":
        # the next execution meets the fault in its checks: 1010 in Physical mode (003 §2.4)
        world.scan({"I": False})
        world.scan({"I": True})
        assert _outcome(world)[:2] == (1010, 0)


@given(direct_control=st.booleans())
def test_sync_type_0_ends_with_mag_1023_iff_the_physical_axis_is_in_direct_control(direct_control: bool) -> None:
    # INT-071: MRP on the path axis, then MAG of the physical axis onto the path axis
    world = _world({"direct_control": direct_control, "position": 42.0}, {"position": 7.0}, 0)
    world.scan({"I": True})
    assert world.axes["T1"].position == 42.0  # MRP redefined the path position
    assert _outcome(world) == ((1023, DIRECT_CONTROL, "error") if direct_control else (0, 0, "complete"))
    assert world.handlers["H1"].OnPath is (not direct_control)  # 003 §1.3.1: OnPath once geared
