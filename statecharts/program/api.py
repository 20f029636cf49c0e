"""The Python API for a ladder program on the motion model: load, bind to axes, scan, read, write.

Pipeline position: the user's own code and tests -> **Controller** -> the scan module.
A :class:`Controller` is a program (any form :func:`load_program` reads) bound to axes
of the specification's axis charts; every :meth:`Controller.scan` is one PLC scan of
:class:`statecharts.scan.System` with the program as its ladder.

    >>> from statecharts.program import Controller
    >>> c = Controller("examples/programs/state_machine.L5X",
    ...                axes={"Axis1": {"state": "Stopped", "variables": {"Connected": True, "DCBusUp": True}}})
    >>> c.scan().scan(START_PB=True).read("State")
    10
    >>> c.scan(START_PB=False).read("MSO_1.DN"), c.axis_state("Axis1")
    (True, 'Running')
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from statecharts import ir as spec_ir
from statecharts.diagnostics import Diagnostic
from statecharts.engine import AxisInstance
from statecharts.program.ir import AXIS_UNTYPED, Program, Scalar
from statecharts.program.ladder import Ladder
from statecharts.program.reader import ProgramError, load_program
from statecharts.scan import EnvironmentEvent, ScanInputs, ScanRecord, System

AxisSetup = str | Mapping[str, Any]  # an axis type, or {type:, state:, variables:}


class Controller:
    """A program bound to axes, with the scan clock; the tags are read and written by path."""

    def __init__(self, program: Program | str | Path, axes: Mapping[str, AxisSetup] | None = None, *,
                 spec: spec_ir.Spec | None = None, scan_ms: int = 10, coarse_update_ms: int | None = None,
                 tags: Mapping[str, Scalar] | None = None, prescan: bool = True) -> None:
        if spec is None:
            from statecharts.loader import load_spec
            spec = load_spec()
        self.spec = spec
        self.program = program if isinstance(program, Program) else load_program(program, spec=spec)
        coarse = coarse_update_ms or scan_ms
        params = {"scan_ms": scan_ms, "coarse_update_ms": coarse}
        given = dict(axes or {})
        instances = []
        problems: list[Diagnostic] = []
        for tag in self.program.axes():
            setup = given.pop(tag.name, None)
            entry: dict[str, Any] = {"type": setup} if isinstance(setup, str) else dict(setup or {})
            axis_type = entry.get("type") or (tag.data_type if tag.data_type != AXIS_UNTYPED else None)
            if axis_type is None:
                problems.append(Diagnostic(self.program.file, tag.location.line, tag.location.column, "", (
                    f"axis {tag.name}: give its type (axes={{{tag.name!r}: 'AXIS_CIP_DRIVE'}}); a rung file does not declare it")))
                continue
            try:
                chart = spec.chart_for_axis_type(axis_type)
            except KeyError:
                problems.append(Diagnostic(self.program.file, 1, 1, "", f"axis {tag.name}: no chart models {axis_type!r}"))
                continue
            variables = dict(entry.get("variables", {}))
            if "AxisType" in {v.name for v in chart.variables}:
                variables.setdefault("AxisType", axis_type)
            instances.append(AxisInstance(chart, tag.name, state=entry.get("state"), variables=variables,
                                          parameters=params))
        if given:
            problems.append(Diagnostic(self.program.file, 1, 1, "", (
                f"axes {', '.join(sorted(given))} are not axes of the program; its axes: "
                f"{', '.join(t.name for t in self.program.axes()) or '(none)'}")))
        if problems:
            raise ProgramError(problems)
        self.ladder = Ladder(self.program, scan_ms=scan_ms)
        self.system = System(spec, instances, [], scan_ms=scan_ms, coarse_update_ms=coarse, ladder=self.ladder)
        for path, value in (tags or {}).items():
            self.write(path, value)
        if prescan:
            self.ladder.prescan()
        self.last: ScanRecord | None = None

    # -- the clock -----------------------------------------------------------------------------

    def scan(self, scans: int = 1, *, events: tuple[tuple[str, str], ...] = (), **writes: Scalar) -> Controller:
        """Write ``writes`` to program tags, then run ``scans`` scans (environment ``events`` in the first)."""
        for axis, event in events:
            if axis not in self.system.axes:
                raise KeyError(f"no axis {axis!r}; axes: {', '.join(self.system.axes)}")
            chart = self.system.axes[axis].chart
            known = [ev.name for ev in chart.events if ev.kind == "environment"]
            if event not in known:
                raise KeyError(f"{event!r} is not an environment event of {chart.id}; expected one of: {', '.join(known)}")
        inputs = ScanInputs(writes=writes, events=tuple(EnvironmentEvent(a, e) for a, e in events))
        for _ in range(scans):
            self.last = self.system.scan(inputs)
            inputs = ScanInputs()
        return self

    def prescan(self) -> Controller:
        self.last = self.system.scan(ScanInputs(prescan=True))
        return self

    def run_until(self, condition: Callable[[Controller], bool], max_scans: int) -> int | None:
        """Scan until ``condition(self)`` holds; the number of scans it took, or None after ``max_scans``."""
        for n in range(1, max_scans + 1):
            self.scan()
            if condition(self):
                return n
        return None

    # -- tags and axes ---------------------------------------------------------------------------

    def read(self, path: str) -> Scalar:
        """A program tag (``STATE``, ``T1.ACC``, ``Arr[2]``), a motion tag member (``X_STAT[0].DN``)
        or an axis member (``X_axis.CIPAxisState``)."""
        return self.ladder.read(path)

    def write(self, path: str, value: Scalar) -> None:
        self.ladder.write(path, value)

    def axis_state(self, axis: str) -> str:
        """The leaf state of an axis chart, e.g. ``Running``."""
        return self.system.axes[axis].leaf.id

    def observe(self) -> Mapping[str, Mapping[str, object]]:
        return self.system.observe()

    def snapshot(self) -> tuple[object, ...]:
        """The whole state (axes, motion tags, queues, tag database) as nested tuples."""
        return self.system.snapshot()

    def restore(self, snap: tuple[object, ...]) -> None:
        self.system.restore(snap)
