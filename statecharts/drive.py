"""The drive model of motion: position, velocity, reaching a target, gearing, homing.

Pipeline position: :mod:`statecharts.scan` calls :func:`advance` for every axis whose
chart declares ``drive_model: motion``, at every coarse update, right after the chart
receives ``tick`` (the same clock: ``coarse_update_ms``).  The chart keeps the motion
state in ordinary chart variables (:data:`VARIABLES`); the status bits (MoveStatus,
JogStatus, GearingStatus, HomingStatus, StoppingStatus, AxisHomedStatus) are set and
cleared by the chart's own transitions, written in YAML.  This module only does the
arithmetic the chart language cannot (integrating velocity, the rotary distance of a
move) and reports the outcomes as the chart's ``drive`` events (:data:`EVENTS`):

* ``move_complete`` when a move has travelled its whole distance;
* ``home_complete`` when an active homing sequence has ended (the sequence this model
  knows is Immediate: it ends at the next coarse update);
* ``stopping_complete`` when a stop has brought the commanded velocity to zero.

The model checker does not run this module.  It treats the three events as free inputs
at any coarse update (``docs/checker.md``, "The motion abstraction"): the chart's
guards only let them fire while the process they end is running, so every run of this
model is a run of the checker's model (``tests/test_drive_abstraction.py``).

Units: positions in position units, speeds in units per second, decelerations in units
per second squared; the time step is ``coarse_update_ms / 1000`` seconds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, MutableMapping

from statecharts import rotary

#: The chart variables of the drive model and their types (the loader checks them).
VARIABLES: Mapping[str, str] = {
    "MoveStatus": "bool",
    "JogStatus": "bool",
    "GearingStatus": "bool",
    "HomingStatus": "bool",
    "StoppingStatus": "bool",
    "AxisHomedStatus": "bool",
    "Moving": "bool",
    "AtTarget": "bool",
    "PositioningMode": "enum",
    "HomePosition": "real",
    "ActualPosition": "real",
    "CommandVelocity": "real",
    "MoveType": "int",
    "MoveCommand": "real",
    "MoveSpeed": "real",
    "MoveRemaining": "real",
    "MovePlanned": "bool",
    "JogVelocity": "real",
    "GearRatio": "real",
    "StopDecel": "real",
    "PositionUnwind": "real",
}

#: The drive events a chart with the drive model declares (kind ``drive``).
EVENTS = ("move_complete", "home_complete", "stopping_complete")

#: Move types of MAM's Move Type operand.
ABSOLUTE, INCREMENTAL, SHORTEST, POSITIVE, NEGATIVE = 0, 1, 2, 3, 4


def planned_distance(position: float, command: float, move_type: int, unwind: float) -> float:
    """The signed distance a move of ``move_type`` to ``command`` travels from ``position``.

    Incremental travels ``command`` itself; absolute travels to ``command`` (on a rotary
    axis, ``unwind > 0``, positions are compared unwound); the rotary types travel forward,
    backward, or the shorter way round (:func:`statecharts.rotary.signed_distance`)."""
    if move_type == INCREMENTAL:
        return command
    kind = {ABSOLUTE: rotary.ABSOLUTE, SHORTEST: rotary.SHORTEST, POSITIVE: rotary.POSITIVE,
            NEGATIVE: rotary.NEGATIVE}.get(move_type, rotary.ABSOLUTE)
    if unwind <= 0:
        return command - position
    return rotary.signed_distance(position, command, unwind, kind)


def _f(env: Mapping[str, object], name: str) -> float:
    value = env[name]
    return float(value) if isinstance(value, (int, float)) else 0.0


def _unwind(env: Mapping[str, object]) -> float:
    """The unwind of a rotary axis; 0 for a linear one."""
    return _f(env, "PositionUnwind") if env["PositioningMode"] == "Rotary" else 0.0


def advance(env: MutableMapping[str, object], dt: float, master_velocity: float | None = None) -> list[str]:
    """Advance one axis's motion variables by ``dt`` seconds; return the drive events due.

    ``env`` is the axis's chart variables (changed in place); ``master_velocity`` the
    commanded velocity of the master of a gearing slave (None: no master)."""
    due: list[str] = []
    position = _f(env, "ActualPosition")
    velocity = 0.0
    if env["StoppingStatus"]:
        v = _f(env, "CommandVelocity")
        decel = _f(env, "StopDecel")
        step = decel * dt if math.isfinite(decel) and decel > 0 else math.inf
        if abs(v) <= step:
            position += v * dt / 2.0 if math.isfinite(step) else 0.0
            due.append("stopping_complete")
        else:
            nv = v - math.copysign(step, v)
            position += (v + nv) * dt / 2.0
            velocity = nv
    else:
        if env["MoveStatus"]:
            if not env["MovePlanned"]:
                env["MoveRemaining"] = planned_distance(
                    position, _f(env, "MoveCommand"), int(_f(env, "MoveType")), _unwind(env))
                env["MovePlanned"] = True
            remaining = _f(env, "MoveRemaining")
            step = abs(_f(env, "MoveSpeed")) * dt
            if not math.isfinite(remaining) or abs(remaining) <= step:
                position += remaining if math.isfinite(remaining) else 0.0
                env["MoveRemaining"] = 0.0
                due.append("move_complete")
            else:
                travel = math.copysign(step, remaining)
                position += travel
                env["MoveRemaining"] = remaining - travel
                velocity = travel / dt
        if env["JogStatus"]:
            velocity += _f(env, "JogVelocity")
            position += _f(env, "JogVelocity") * dt
        if env["GearingStatus"] and master_velocity is not None:
            gear = _f(env, "GearRatio") * master_velocity
            velocity += gear
            position += gear * dt
        if env["HomingStatus"]:
            due.append("home_complete")
    unwind = _unwind(env)
    env["ActualPosition"] = rotary.unwind(position, unwind) if unwind > 0 else position
    env["CommandVelocity"] = velocity
    return due
