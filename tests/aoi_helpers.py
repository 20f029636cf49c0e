"""The worlds of the add-on instruction tests, built on the main scan.

The tests describe a world in the words of 003 (a handler with its eState, mode,
registry and axes; axes that are faulted, shut down, energized, homed, moving at a
velocity, in a control mode; the instance's configuration).  This module is the one
place that says how each of those words is set on the main charts: the CIP axis
(docs/cip.md: Faulted, Shutdown, Running, Stopped; AxisHomedStatus, DirectControlStatus,
HomeConfigValid, ControlMode), the virtual path axis (Axis Faulted, Shutdown, Servo
Control; a velocity is a jog in progress; HomingStatus) and the device handler
(eState, Registered, Capacity, the mode events).
"""

from __future__ import annotations

from typing import Any

from statecharts import ir
from statecharts.engine import SETTLE_EVENT, AxisInstance
from statecharts.loader import load_spec
from statecharts.scan import ScanInputs, System

AOI = "raM_Opr_SyncPthPhyAx_CD"
SPEC = load_spec()
MODE_EVENTS = {"physical": "select_physical", "virtual": "select_virtual", "none": "select_none",
               "maintenance": "select_maintenance"}
CONTROL_MODES = {"position": "Position", "velocity": "Velocity", "torque": "Torque", "frequency": "Frequency",
                 "none": "NoControl"}


def _rotary(a: dict[str, Any]) -> dict[str, object]:
    u = float(a.get("unwind", 0.0))
    return {"PositioningMode": "Rotary", "PositionUnwind": u} if u > 0 else {"PositioningMode": "Linear"}


def axis_setup(a: dict[str, Any]) -> tuple[str, str, dict[str, object]]:
    """(chart, starting state, variables) of an axis of the world."""
    if a["type"] == "AXIS_CIP_DRIVE":
        v: dict[str, object] = {"Connected": True, "DCBusUp": True, "ActualPosition": float(a.get("position", 0.0)),
                                "AxisHomedStatus": bool(a.get("homed", True)),
                                "DirectControlStatus": bool(a.get("direct_control", False)),
                                "HomeConfigValid": bool(a.get("home_config_ok", True)),
                                "ControlMode": CONTROL_MODES[a.get("control_mode", "position")], **_rotary(a)}
        if a.get("faulted"):
            state = "Faulted"
            v.update(PhysicalAxisFault=True, MajorFault=True, ShutdownRequested=bool(a.get("shutdown")))
        else:
            state = "Shutdown" if a.get("shutdown") else "Running" if a.get("energized", True) else "Stopped"
        return "AxisCIP", state, v
    v = {"ActualPosition": float(a.get("position", 0.0)), "HomePosition": float(a.get("position", 0.0)),
         "HomingStatus": bool(a.get("homing", False)), **_rotary(a)}
    velocity = float(a.get("velocity", 0.0))
    if velocity:
        v.update(JogStatus=True, JogVelocity=velocity, CommandVelocity=velocity, Moving=True)
    if a.get("shutdown"):
        state, v["MotionFault"] = "Shutdown", bool(a.get("faulted"))
    elif a.get("faulted"):
        state, v["MotionFault"] = "AxisFaulted", True
    else:
        state = "ServoControl"
    return "AxisVirtual", state, v


def handler_setup(h: dict[str, Any]) -> tuple[dict[str, object], dict[str, object], list[str]]:
    """(variables, chart parameters, events at set-up) of a handler of the world."""
    mode = h.get("mode", "physical")
    return ({"eState": h.get("eState", 7), "Registered": h.get("registered", 0), "Capacity": h.get("capacity", 10)},
            {"id": h.get("id", 1), "phy_axis": h["phy_axis"], "pth_axis": h["pth_axis"]},
            [MODE_EVENTS[mode]] if mode != "physical" else [])


#: (chart, state) -> the configuration of a fresh instance starting there (building a
#: python-statemachine instance is what costs; a set-up is that configuration with its
#: variables, settled, as AxisInstance itself sets one up)
_STARTS: dict[tuple[object, ...], tuple[frozenset[str], tuple[object, ...]]] = {}
#: (handle, phy, pth, axis names, handler names, scan_ms) -> a system and its first state
_SYSTEMS: dict[tuple[object, ...], tuple[System, tuple[object, ...]]] = {}


def _start(inst: AxisInstance, state: str | None, variables: dict[str, object]) -> None:
    flags = tuple(sorted((k, v) for k, v in variables.items() if not isinstance(v, float)))
    key = (inst.chart.id, state, flags)
    if key not in _STARTS:
        _STARTS[key] = AxisInstance(inst.chart, "start", state=state, variables=dict(flags)).snapshot()
    inst.restore(_STARTS[key])
    inst.env.update(variables)
    inst.send(SETTLE_EVENT)


def build(handlers: dict[str, dict[str, Any]], axes: dict[str, dict[str, Any]], inst: dict[str, Any],
          scan_ms: int = 10, spec: ir.Spec = SPEC) -> System:
    """A system with one instance ``I`` of the add-on instruction, in its first state."""
    params: dict[str, object] = {"scan_ms": scan_ms, "coarse_update_ms": scan_ms}
    ops = {k: v for k, v in inst.items() if k != "path_verified"}
    key = (ops["Ref_Handle"], ops["Ref_AxisPhy"], ops["Ref_AxisPth"], tuple((n, a["type"]) for n, a in axes.items()),
           tuple(handlers), scan_ms, id(spec))
    if key not in _SYSTEMS:
        objs = [AxisInstance(SPEC.chart(axis_setup(a)[0]), n, parameters=params) for n, a in axes.items()]
        objs += [AxisInstance(SPEC.chart("DeviceHandler"), n, parameters={**params, **handler_setup(h)[1]})
                 for n, h in handlers.items()]
        made = System(spec, objs, [("I", AOI, "")], scan_ms=scan_ms, coarse_update_ms=scan_ms, add_ons={"I": ops})
        _SYSTEMS[key] = (made, made.snapshot())
    system, first = _SYSTEMS[key]
    system.restore(first)
    for n, a in axes.items():
        _chart, state, variables = axis_setup(a)
        _start(system.axes[n], state, variables)
    for n, h in handlers.items():
        variables, parameters, events = handler_setup(h)
        system.axes[n].env.update(parameters)
        _start(system.axes[n], None, variables)  # the chart's initial configuration (both regions)
        for e in events:
            event(system, n, e)
    system.add_ons["I"].inputs.update(ops)
    system.add_ons["I"].preset({"path_verified": bool(inst.get("path_verified", False))})
    return system


def scan(system: System, rung: bool, prescan: bool = False) -> None:
    system.scan(ScanInputs(rungs={"I": rung}, prescan=prescan))


def outcome(system: System) -> tuple[int, int, str]:
    o = system.add_ons["I"].status
    state = "error" if o["Sts_ER"] else "complete" if o["Sts_PC"] else "in_process" if o["Sts_IP"] else "none"
    return int(str(o["Sts_ERR"])), int(str(o["Sts_EXERR"])), state


def event(system: System, obj: str, name: str) -> None:
    """An event reaches a chart at once (the environment acting between scans)."""
    system.axes[obj].apply_event_actions(name)
    system.axes[obj].send(name)


def set_velocity(system: System, obj: str, velocity: float) -> None:
    """The path axis jogs at ``velocity`` (0: it is at rest)."""
    system.axes[obj].env.update(JogStatus=velocity != 0, JogVelocity=velocity, CommandVelocity=velocity,
                                Moving=velocity != 0)
