"""Hypothesis strategies for property tests of a ladder program (needs ``hypothesis``).

Pipeline position: a user's test -> these strategies -> :class:`~statecharts.program.api.Controller`.

* :func:`free_inputs` names the BOOL tags a program only reads (push buttons, limit
  switches: nothing in the program writes them), the inputs the outside world drives;
* :func:`input_sequences` draws, per scan, values for such inputs;
* :func:`fault_injections` draws environment events (faults, shutdowns, connection
  loss) with the scan they happen in;
* :func:`axis_starts` draws a start state (with the drive-model variables that go with
  it) for each axis, from :data:`CIP_STARTS` or presets of one's own.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from hypothesis import strategies as st

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


def input_sequences(program: Program, inputs: Sequence[str] | None = None, *, min_scans: int = 1,
                    max_scans: int = 50) -> st.SearchStrategy[list[dict[str, bool]]]:
    """Per scan, a dict of input writes (only the inputs that change need be there)."""
    names = tuple(inputs) if inputs is not None else free_inputs(program)
    if not names:
        return st.lists(st.just({}), min_size=min_scans, max_size=max_scans)
    return st.lists(st.dictionaries(st.sampled_from(names), st.booleans(), max_size=len(names)),
                    min_size=min_scans, max_size=max_scans)


def fault_injections(axes: Sequence[str], events: Sequence[str], *, max_events: int = 2,
                     max_scan: int = 50) -> st.SearchStrategy[list[tuple[int, str, str]]]:
    """Sorted (scan, axis, event) triples: environment events to inject."""
    one = st.tuples(st.integers(0, max_scan), st.sampled_from(tuple(axes)), st.sampled_from(tuple(events)))
    return st.lists(one, max_size=max_events).map(sorted)


def axis_starts(axes: Sequence[str], presets: Mapping[str, Mapping[str, Any]] | None = None
                ) -> st.SearchStrategy[dict[str, Mapping[str, Any]]]:
    """For each axis, one start (``{state:, variables:}``) from ``presets`` (default: :data:`CIP_STARTS`)."""
    table = dict(presets or CIP_STARTS)
    names = tuple(table)
    return st.fixed_dictionaries({a: st.sampled_from(names) for a in axes}).map(
        lambda chosen: {a: {"type": "AXIS_CIP_DRIVE", **table[s]} if presets is None else dict(table[s])
                        for a, s in chosen.items()})
