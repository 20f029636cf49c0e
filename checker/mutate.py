"""Seeded faults: small mutations of the spec IR that a checker run must notice.

Pipeline position: IR -> **checker.mutate** -> mutated IR -> :mod:`checker.model` (tests and a
future ``motionchart mutate``).  Each mutation returns a new frozen :class:`ir.Spec`
(the IR is immutable; ``dataclasses.replace`` rebuilds the path to the changed
element) and a :class:`Mutation` record saying what changed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from statecharts import ir


@dataclass(frozen=True, slots=True)
class Mutation:
    kind: str  # "drop_guard" | "swap_target" | "error_code"
    where: str  # e.g. "AxisNonCIP:enable_delay" or "MSO:faulted"
    detail: str

    def __str__(self) -> str:
        return f"{self.kind} {self.where}: {self.detail}"


def _replace_chart(spec: ir.Spec, chart: ir.Chart) -> ir.Spec:
    charts = tuple(chart if c.id == chart.id else c for c in spec.charts)
    instructions = spec.instructions  # instructions refer to charts by id only
    return dataclasses.replace(spec, charts=charts, instructions=instructions)


def _replace_transition(spec: ir.Spec, chart_id: str, tid: str, **changes: Any) -> ir.Spec:
    chart = spec.chart(chart_id)
    found = [t for t in chart.transitions if t.id == tid]
    if not found:
        raise KeyError(f"chart {chart_id} has no transition {tid!r}")
    ts = tuple(dataclasses.replace(t, **changes) if t.id == tid else t for t in chart.transitions)
    return _replace_chart(spec, dataclasses.replace(chart, transitions=ts))


def drop_guard(spec: ir.Spec, chart_id: str, tid: str) -> tuple[ir.Spec, Mutation]:
    t = next(t for t in spec.chart(chart_id).transitions if t.id == tid)
    if t.guard is None:
        raise ValueError(f"{chart_id}:{tid} has no guard")
    return (_replace_transition(spec, chart_id, tid, guard=None),
            Mutation("drop_guard", f"{chart_id}:{tid}", f"guard {t.guard.text!r} removed"))


def swap_target(spec: ir.Spec, chart_id: str, tid: str, target: str) -> tuple[ir.Spec, Mutation]:
    t = next(t for t in spec.chart(chart_id).transitions if t.id == tid)
    spec.chart(chart_id).state(target)  # KeyError for an unknown state
    return (_replace_transition(spec, chart_id, tid, target=target),
            Mutation("swap_target", f"{chart_id}:{tid}", f"target {t.target} -> {target}"))


def set_error_code(spec: ir.Spec, mnemonic: str, check_id: str, err: int, exerr: int | None = None
                   ) -> tuple[ir.Spec, Mutation]:
    ins = spec.instruction(mnemonic)
    hits = [c for c in (*ins.checks, *ins.aborts) if c.id == check_id]
    if not hits:
        raise KeyError(f"{mnemonic} has no check or abort {check_id!r}")
    old = hits[0]
    new_exerr = old.exerr if exerr is None else exerr

    def fix(cs: tuple[ir.Check, ...]) -> tuple[ir.Check, ...]:
        return tuple(dataclasses.replace(c, err=err, exerr=new_exerr) if c.id == check_id else c for c in cs)

    new_ins = dataclasses.replace(ins, checks=fix(ins.checks), aborts=fix(ins.aborts))
    instructions = tuple(new_ins if i.id == mnemonic else i for i in spec.instructions)
    return (dataclasses.replace(spec, instructions=instructions),
            Mutation("error_code", f"{mnemonic}:{check_id}", f"{old.err}/{old.exerr} -> {err}/{new_exerr}"))


def single_mutants(spec: ir.Spec) -> Iterator[tuple[ir.Spec, Mutation]]:
    """Every guard dropped, every target swapped to each other leaf state, every error
    code replaced by 0 (one at a time), in spec order."""
    for chart in spec.charts:
        leaves = [s.id for s in chart.leaf_states()]
        for t in chart.transitions:
            if t.guard is not None:
                yield drop_guard(spec, chart.id, t.id)
            if t.target is not None:
                for leaf in leaves:
                    if leaf != t.target:
                        yield swap_target(spec, chart.id, t.id, leaf)
    for ins in spec.instructions:
        for c in (*ins.checks, *ins.aborts):
            yield set_error_code(spec, ins.id, c.id, 0)
