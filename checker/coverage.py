"""Coverage of a search: chart states, chart transitions, documented error codes, instruction x state cells.

Pipeline position: :mod:`checker.search` -> **checker.coverage** -> :mod:`checker.report`.

The universes come from the IR alone: every non-history state and every transition of
the charts the system uses; every (ERR, EXERR) that a check or abort of an instruction
in the program, or the extended-error catalog for it, documents (written ``MSO:8`` or
``MSO:12/12``); every (instruction, leaf state) pair written ``MSO@AxisReady``.  A
``cover`` property passes when everything not reached is listed in its
``unreachable`` entries with a reason; an entry that *is* reached is reported as a stale
explanation.
"""

from __future__ import annotations

from dataclasses import dataclass

from checker.model import Model
from checker.properties import Property
from checker.search import SearchResult
from statecharts import ir


@dataclass(frozen=True, slots=True)
class CoverageTable:
    name: str
    reached: tuple[str, ...]
    unreached: tuple[str, ...]

    @property
    def total(self) -> int:
        return len(self.reached) + len(self.unreached)


def error_item(mnemonic: str, err: int, exerr: int) -> str:
    return f"{mnemonic}:{err}/{exerr}" if exerr else f"{mnemonic}:{err}"


def _instructions(model: Model, whole_spec: bool = False) -> list[ir.Instruction]:
    if whole_spec:
        return list(model.spec.instructions)
    seen: dict[str, ir.Instruction] = {}
    add_ons = {a.id for a in model.spec.add_ons}
    for _tag, mnemonic, _axis in model.program:
        if mnemonic not in add_ons:
            seen.setdefault(mnemonic, model.spec.instruction(mnemonic))
    return list(seen.values())


def universe(model: Model, what: str, variable: str | None = None, *, whole_spec: bool = False) -> list[str]:
    """The items to cover in this system (or, ``whole_spec``, in every chart and instruction)."""
    spec = model.spec
    charts = list(spec.charts) if whole_spec else list(model.charts.values())
    if what == "states":
        return [f"{c.id}:{s.id}" for c in charts for s in c.states if s.kind is not ir.StateKind.HISTORY]
    if what == "transitions":
        return [f"{c.id}:{t.id}" for c in charts for t in c.transitions]
    if what == "error_codes":
        out: list[str] = []
        add_ons = {a.id: a for a in spec.add_ons}
        for ao in (spec.add_ons if whole_spec else [add_ons[m] for _t, m, _a in model.program if m in add_ons]):
            out += [error_item(ao.id, e.code, 0) for e in ao.errors if error_item(ao.id, e.code, 0) not in out]
        for ins in _instructions(model, whole_spec):
            items = [error_item(ins.id, c.err, c.exerr) for c in (*ins.checks, *ins.aborts)]
            items += [error_item(x.instruction, x.err, x.exerr) for x in spec.extended_errors if x.instruction == ins.id]
            for it in items:
                if it not in out:
                    out.append(it)
        return out
    if what == "cells":
        out = []
        for ins in _instructions(model, whole_spec):
            for c in charts:
                if c.id in ins.charts:
                    out += [f"{ins.id}@{s.id}" for s in c.leaf_states()]
        return out
    if what == "values":
        out = []
        for c in charts:
            for v in c.variables:
                if v.name == variable and v.domain is not None:
                    out += [f"{c.id}:{v.name}={x}" for x in v.domain]
        return out
    raise ValueError(what)


def reached(result: SearchResult, what: str, variable: str | None = None) -> set[str]:
    cov = result.coverage
    if what == "states":
        return {f"{c}:{s}" for c, config in cov.configs for s in config}
    if what == "transitions":
        return {f"{c}:{t}" for c, t in cov.fired}
    if what == "error_codes":
        return {error_item(m, e, x) for m, e, x in cov.errors}
    if what == "cells":
        return {f"{m}@{s}" for m, s in cov.executed}
    if what == "values":
        return {f"{c}:{v}={x}" for c, v, x in cov.values if v == variable}
    raise ValueError(what)


def table(result: SearchResult, what: str, variable: str | None = None) -> CoverageTable:
    items = universe(result.model, what, variable)
    got = reached(result, what, variable)
    return CoverageTable(what, tuple(i for i in items if i in got), tuple(i for i in items if i not in got))


@dataclass(frozen=True, slots=True)
class CoverVerdict:
    holds: bool | None
    unexplained: tuple[str, ...]
    explained: tuple[tuple[str, str], ...]  # (item, reason) listed as unreachable and not reached
    stale: tuple[str, ...]  # listed as unreachable but reached
    unknown_items: tuple[str, ...]  # listed items that are not in the universe at all


def cover_verdict(result: SearchResult, prop: Property) -> CoverVerdict:
    assert prop.cover is not None
    t = table(result, prop.cover, prop.variable)
    listed = {u.item: u.reason for u in prop.unreachable}
    unexplained = tuple(i for i in t.unreached if i not in listed)
    explained = tuple((i, listed[i]) for i in t.unreached if i in listed)
    stale = tuple(i for i in t.reached if i in listed)
    everywhere = set(universe(result.model, prop.cover, prop.variable, whole_spec=True))
    unknown = tuple(i for i in listed if i not in everywhere)  # typos; items of other systems are fine
    if stale or unknown:
        holds: bool | None = False
    elif unexplained:
        holds = False if result.complete else None
    else:
        holds = True
    return CoverVerdict(holds, unexplained, explained, stale, unknown)
