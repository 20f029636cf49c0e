"""The environment of a program: named start states of an axis, and the program's free inputs.

Used by the hypothesis strategies (:mod:`statecharts.program.strategies`) and by the
program checker's systems (``starts: [Running, Shutdown]``, the default free inputs), so
that both mean the same thing by "an axis starting in Shutdown" and "a free input".
"""

from __future__ import annotations

from typing import Any

from statecharts.program.ir import Program, Reference
from statecharts.program.reader import operand_kinds

#: start states of an AXIS_CIP_DRIVE axis with the drive-model variables that hold in them
CIP_STARTS: dict[str, dict[str, Any]] = {
    "Running": {"state": "Running", "variables": {"Connected": True, "DCBusUp": True, "TrackingCommand": True,
                                                  "ServoActionStatus": True, "DriveEnableStatus": True,
                                                  "PowerStructureEnabled": True}},
    "Stopped": {"state": "Stopped", "variables": {"Connected": True, "DCBusUp": True}},
    "Faulted": {"state": "Faulted", "variables": {"Connected": True, "DCBusUp": True, "MajorFault": True,
                                                  "PhysicalAxisFault": True}},
    "Shutdown": {"state": "Shutdown", "variables": {"Connected": True, "DCBusUp": True, "ShutdownRequested": True,
                                                    "ShutdownStatus": True}},
}


def free_inputs(program: Program) -> tuple[str, ...]:
    """BOOL tags (not arrays) that the program reads and never writes."""
    read: set[str] = set()
    written: set[str] = set()
    for ins in program.instructions():
        for op, kind in zip(ins.operands, operand_kinds(ins, None)):
            if isinstance(op, Reference):
                (written if kind in ("bit_out", "dest", "timer", "counter", "timer_or_counter", "motion")
                 else read).add(op.base)
    bools = {t.name for t in program.tags if t.data_type == "BOOL" and not t.dimensions}
    return tuple(sorted((read - written) & bools))
