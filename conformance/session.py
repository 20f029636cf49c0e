"""One run of a conformance vector on the project's own engine: set-up, scans, observations.

Pipeline position: IR + :mod:`statecharts.scan` -> **conformance.session** -> the vector
generator (:mod:`conformance.vectors`, which computes the expected observations with
it), the reference adapter (:mod:`conformance.adapter`, which serves it over the
protocol) and the mutation score (:mod:`conformance.mutation`).

A set-up and the inputs of a scan are the plain JSON objects of the vector format
(``docs/conformance.md``).  The default axis back-end is the python-statemachine engine
(the reference semantics); the model checker's interpreter
(:class:`checker.compile.FastAxis`) can be given instead, and with ``record=True`` the
session also collects what each scan covered (chart states and transitions, instruction
x state cells, error codes, failed checks, check orders and refused guards, see
:mod:`conformance.witness`); recording needs that module's back-end
(:class:`conformance.witness.RecordingAxis`), which reports the transitions it takes
and the guards it refuses.

Example::

    >>> from statecharts.loader import load_spec
    >>> setup = {"scan_ms": 10, "coarse_update_ms": 10,
    ...          "axes": [{"name": "Axis1", "type": "AXIS_SERVO", "family": "AxisNonCIP"}],
    ...          "program": [{"tag": "mso1", "instruction": "MSO", "axis": "Axis1"}]}
    >>> s = Session(load_spec(), setup)
    >>> obs = s.scan({"rungs": {"mso1": True}})
    >>> obs["mso1"]["DN"], obs["Axis1"]["state"]
    (True, 'ServoControl')
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.scan import Done, EnvironmentEvent, Errored, Executed, ProcessEnded, ScanInputs, System


class SetupError(ValueError):
    """A set-up the spec cannot run (unknown axis type, family, state or instruction)."""


@dataclass
class Covered:
    """What runs covered, as the checker names the items (``checker.coverage``)."""

    states: set[str] = field(default_factory=set)
    transitions: set[str] = field(default_factory=set)
    error_codes: set[str] = field(default_factory=set)
    cells: set[str] = field(default_factory=set)
    checks: set[str] = field(default_factory=set)
    #: adjacent checks k and k+1 that both failed where k was the first: ``MSO.shutdown<faulted``
    orders: set[str] = field(default_factory=set)
    #: guarded transitions tried on an event and refused by their guard: ``AxisNonCIP:test_cancelled``
    refusals: set[str] = field(default_factory=set)

    KINDS = ("states", "transitions", "error_codes", "cells", "checks", "orders", "refusals")

    def update(self, other: Covered) -> None:
        for k in self.KINDS:
            getattr(self, k).update(getattr(other, k))

    def as_dict(self, order: Mapping[str, list[str]] | None = None) -> dict[str, list[str]]:
        """Items per kind, in ``order`` (the universe's order) where given, else sorted."""
        out: dict[str, list[str]] = {}
        for k in self.KINDS:
            items = getattr(self, k)
            if order is not None and k in order:
                rank = {it: i for i, it in enumerate(order[k])}
                out[k] = sorted(items, key=lambda it: (rank.get(it, len(rank)), it))
            else:
                out[k] = sorted(items)
        return out


def error_item(mnemonic: str, err: int, exerr: int) -> str:
    return f"{mnemonic}:{err}/{exerr}" if exerr else f"{mnemonic}:{err}"


def plain(obs: Mapping[str, Mapping[str, object]]) -> dict[str, dict[str, object]]:
    return {k: dict(v) for k, v in obs.items()}


class Session:
    """The engine in one vector's set-up; :meth:`scan` runs one scan and observes."""

    def __init__(self, spec: ir.Spec, setup: Mapping[str, Any], *,
                 backend: Callable[..., Any] = AxisInstance, record: bool = False) -> None:
        self.spec = spec
        scan_ms = int(setup.get("scan_ms", 10))
        cu_ms = int(setup.get("coarse_update_ms", scan_ms))
        params = {"scan_ms": scan_ms, "coarse_update_ms": cu_ms}
        axes = []
        for a in setup.get("axes", []):
            try:
                chart = spec.chart_for_axis_type(a["type"])
            except KeyError:
                raise SetupError(f"axis {a['name']}: unknown axis type {a['type']!r}") from None
            family = a.get("family", chart.id)
            if family != chart.id:
                try:
                    chart = spec.chart(family)
                except KeyError:
                    raise SetupError(f"axis {a['name']}: unknown axis family {family!r}") from None
            state = a.get("state")
            if state is not None and state not in {s.id for s in chart.states}:
                raise SetupError(f"axis {a['name']}: chart {chart.id} has no state {state!r}")
            try:
                axes.append(backend(chart, a["name"], state=state, variables=dict(a.get("variables", {})),
                                    parameters=params))
            except (KeyError, ValueError) as exc:
                raise SetupError(f"axis {a['name']}: {exc}") from None
        program = []
        masters: dict[str, str] = {}
        for p in setup.get("program", []):
            if "master" in p:
                if p["master"] not in {a.name for a in axes}:
                    raise SetupError(f"tag {p['tag']}: unknown master axis {p['master']!r}")
                masters[p["tag"]] = p["master"]
            if not self.spec.variants(p["instruction"]):
                try:
                    self.spec.instruction(p["instruction"])
                except KeyError:
                    raise SetupError(f"tag {p['tag']}: unknown instruction {p['instruction']!r}") from None
            if p["axis"] not in {a.name for a in axes}:
                raise SetupError(f"tag {p['tag']}: unknown axis {p['axis']!r}")
            program.append((p["tag"], p["instruction"], p["axis"]))
        try:
            from conformance.witness import RecordingSystem
            cls = RecordingSystem if record else System
            self.system = cls(spec, axes, program, scan_ms=scan_ms, coarse_update_ms=cu_ms, masters=masters)
        except (KeyError, ValueError) as exc:
            raise SetupError(str(exc)) from None
        for p in setup.get("program", []):
            self._write_operands(p["tag"], p.get("operands", {}))
        self.record = record
        self.covered = Covered()
        if record:
            for axis in axes:
                axis.fired = []
            self._note_states()

    def _write_operands(self, tag: str, ops: Mapping[str, object]) -> None:
        known = self.system.tags[tag].operands
        for k in ops:
            if k not in known:
                raise SetupError(f"tag {tag}: {self.system.tags[tag].instruction.id} has no operand {k!r}")
        known.update(ops)

    def observe(self) -> dict[str, dict[str, object]]:
        return plain(self.system.observe())

    def scan(self, inputs: Mapping[str, Any]) -> dict[str, dict[str, object]]:
        """Run one scan with the inputs of a vector's scan entry; return the observations."""
        system = self.system
        rungs = dict(inputs.get("rungs", {}))
        for tag in rungs:
            if tag not in system.tags:
                raise SetupError(f"unknown tag {tag!r} in the rungs")
        operands = {}
        for tag, ops in inputs.get("operands", {}).items():
            if tag not in system.tags:
                raise SetupError(f"unknown tag {tag!r} in the operands")
            operands[tag] = dict(ops)
            for k in ops:
                if k not in system.tags[tag].operands:
                    raise SetupError(f"tag {tag}: no operand {k!r}")
        events = []
        for e in inputs.get("events", []):
            if e["axis"] not in system.axes:
                raise SetupError(f"unknown axis {e['axis']!r} in the events")
            chart = system.axes[e["axis"]].chart
            kind = next((ev.kind for ev in chart.events if ev.name == e["event"]), None)
            if kind not in ("environment", "drive"):
                offered = ", ".join(ev.name for ev in chart.events if ev.kind in ("environment", "drive"))
                what = "no event" if kind is None else f"a {kind} event, not an environment or drive event,"
                raise SetupError(f"axis {e['axis']}: chart {chart.id} has {what} {e['event']!r}; the events a "
                                 f"vector gives are: {offered}")
            events.append(EnvironmentEvent(e["axis"], e["event"]))
        si = ScanInputs(rungs=rungs, operands=operands, events=tuple(events), prescan=bool(inputs.get("prescan", False)))
        if self.record:
            trace: list[Executed | Errored | Done | ProcessEnded] = []
            system.trace = trace
            for axis in system.axes.values():
                axis.fired.clear()  # type: ignore[attr-defined]  # the recording back end's axes keep what fired
            system.advance(si)
            system.trace = None
            self._note(trace)
        else:
            system.advance(si)
        return self.observe()

    def _note_states(self) -> None:
        for axis in self.system.axes.values():
            cid = axis.chart.id
            self.covered.states.update(f"{cid}:{s}" for s in axis.active)

    def _note(self, trace: list[Executed | Errored | Done | ProcessEnded]) -> None:
        cov = self.covered
        from conformance.witness import split_fired
        for axis in self.system.axes.values():
            transitions, orders, refusals = split_fired(axis.chart.id, axis.fired)  # type: ignore[attr-defined]  # see above
            cov.transitions.update(transitions)
            cov.orders.update(orders)
            cov.refusals.update(refusals)
        tags = self.system.tags
        for rec in trace:
            if type(rec) is Executed:
                cov.cells.add(f"{tags[rec.tag].instruction.id}@{rec.axis_state}")
            elif type(rec) is Errored:
                mnemonic = tags[rec.tag].instruction.id
                cov.error_codes.add(error_item(mnemonic, rec.err, rec.exerr))
                cov.checks.add(f"{mnemonic}.{rec.check}")
        self._note_states()
