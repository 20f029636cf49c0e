"""What a conformance run records beyond the checker's coverage: check orders and refused guards.

Pipeline position: :mod:`statecharts.scan` and :class:`checker.compile.FastAxis` ->
**conformance.witness** -> the breadth-first search of the vector generator
(:class:`WitnessModel` in :func:`checker.search.explore_interpreted`) and the coverage a
vector is measured to have (:class:`conformance.session.Session` with ``record=True``).

Two kinds of item, each the place where one kind of faulty specification shows:

* an **order** ``MSO.shutdown<faulted``: checks *k* and *k*+1 of an instruction are
  evaluated at the same point (the execution in the scan, or the delivery of the request
  at the coarse update), check *k* fails first and check *k*+1 fails too.  Only there
  does the order of the two decide the reported code: a run in which check *k* fails and
  *k*-1 passes does not tell a swap of *k* and *k*+1 apart, a run in which both fail does.
* a **refusal** ``AxisNonCIP:test_cancelled``: an event reached the axis, the transition
  was tried (its state active, no transition before it in the selection order enabled)
  and its guard was false.  Only there does a transition without its guard behave
  differently.

:class:`RecordingSystem` and :class:`RecordingAxis` note both among the transitions an
axis reports as fired (its ``fired`` list), marked with :data:`ORDERED` and
:data:`REFUSED`: whatever collects fired transitions then carries them unchanged, the
checker's interpreter and its compiled core alike, so the search records a shortest
witness of each (``("transition", chart, mark + name)``, which :func:`decode` turns back
into the item).  :func:`split_fired` separates them again.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from checker.compile import FastAxis
from checker.model import Model
from statecharts import ir
from statecharts.scan import System, TagInstance

#: marks a refused guard among an axis's fired transitions: ``"!refused:" + transition id``
REFUSED = "!refused:"
#: marks a check order among an axis's fired transitions: ``"!order:" + MSO.shutdown<faulted``
ORDERED = "!order:"


def order_name(instruction: str, first: str, second: str) -> str:
    return f"{instruction}.{first}<{second}"


class RecordingSystem(System):
    """The scan rules unchanged; a failed check also notes whether the next one failed too."""

    def _first_failure(self, tag: TagInstance, stages: tuple[ir.Stage, ...]) -> ir.Check | None:
        failed = super()._first_failure(tag, stages)
        if failed is not None:
            fired = getattr(self.axes[tag.axis], "fired", None)
            checks = tag.instruction.checks
            k = next((i for i, c in enumerate(checks) if c is failed), None)
            if fired is not None and k is not None and k + 1 < len(checks):
                nxt = checks[k + 1]
                if nxt.stage in stages and nxt.fails_when(self._check_env(tag)):
                    fired.append(ORDERED + order_name(tag.instruction.id, failed.id, nxt.id))
        return failed


class RecordingAxis(FastAxis):
    """The checker's chart interpreter; a transition tried on an event and refused by its
    guard is noted among the fired ones (when they are recorded)."""

    def _select(self, event: str | None) -> Any:
        fired = self.fired
        if fired is not None and event is not None:
            env = self.env
            for group in self.c.candidates(self.config, event):
                for t in group:
                    if t.guard is None or t.guard(env):
                        break
                    fired.append(REFUSED + t.id)
        return super()._select(event)


class WitnessModel(Model):
    """The checker's model of a system on the recording back-ends."""

    def __init__(self, spec: ir.Spec, sysdef: Any, properties: Sequence[Any] = ()) -> None:
        super().__init__(spec, sysdef, properties, axis_backend=RecordingAxis)

    def build_system(self, assignment: Sequence[int], backend: Any = None) -> System:
        plain = super().build_system(assignment, backend)
        # the model's scan rules unchanged: the drive model's outcomes stay inputs (motion off)
        return RecordingSystem(self.spec, list(plain.axes.values()), self.program, scan_ms=self.sysdef.scan_ms,
                               coarse_update_ms=self.sysdef.coarse_update_ms, masters=self.masters,
                               motion=plain.motion)


def split_fired(chart: str, fired: Sequence[str]) -> tuple[list[str], list[str], list[str]]:
    """(transitions ``Chart:id``, orders, refusals ``Chart:id``) of an axis's fired list."""
    transitions, orders, refusals = [], [], []
    for t in fired:
        if t.startswith(ORDERED):
            orders.append(t[len(ORDERED):])
        elif t.startswith(REFUSED):
            refusals.append(f"{chart}:{t[len(REFUSED):]}")
        else:
            transitions.append(f"{chart}:{t}")
    return transitions, orders, refusals


def decode(item: tuple[object, ...]) -> tuple[str, str] | None:
    """(kind, name) of an order or refusal item of the search's coverage, else None."""
    if item[0] != "transition":
        return None
    name = str(item[2])
    if name.startswith(REFUSED):
        return "refusals", f"{item[1]}:{name[len(REFUSED):]}"
    if name.startswith(ORDERED):
        return "orders", name[len(ORDERED):]
    return None


def refusal_universe(spec: ir.Spec) -> list[str]:
    """Every transition on an event with a guard, ``Chart:id``, in document order."""
    return [f"{c.id}:{t.id}" for c in spec.charts for t in c.transitions if t.event is not None and t.guard is not None]
