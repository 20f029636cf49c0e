"""Counterexamples: a witness of the search replayed concretely, written as a scenario file.

Pipeline position: :mod:`checker.search` -> **checker.counterexample** -> scenario files
(``format: motionchart-scenario/1``) that ``motionchart simulate`` replays on the engine,
and a per-scan table.

The search stores abstract, canonical states.  To turn a path of them into a run, the
run is replayed on the concrete system (no abstraction, no symmetry): from the initial
state of the witness's configuration, at each step the first input choice whose
successor has the recorded abstract state is taken (abstractions are exact for control,
so one always exists; if none does, :class:`ReplayError` says so -- that would be a bug
in an abstraction).  The last step is one that violates the property (or reaches the
goal).  Every scan's observations are recorded as the scenario's expectations, so the
engine must reproduce them exactly.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from checker.model import Choice
from checker.properties import Property
from checker.search import SearchResult, Witness
from statecharts.outputs import atomic_write_text
from statecharts.scenario import SCENARIO_FORMAT, scan_cell


class ReplayError(RuntimeError):
    """An abstract path has no concrete counterpart (an abstraction is not exact)."""


@dataclass(frozen=True, slots=True)
class TraceStep:
    """One scan of a counterexample: the input change and what was observed after it."""

    index: int
    choice: Choice
    coarse_update: bool
    observations: Mapping[str, Mapping[str, object]]
    changes: tuple[tuple[str, str, object, object], ...]  # (object, field, before, after)


@dataclass(frozen=True, slots=True)
class Trace:
    prop: str
    kind: str  # "violation" | "witness" | "deadlock"
    assignment: tuple[int, ...]
    initial: Mapping[str, Mapping[str, object]]
    steps: tuple[TraceStep, ...]


def replay(result: SearchResult, prop: str, witness: Witness | None, *, end_state: int | None = None,
           kind: str = "violation", properties: tuple[Property, ...] = ()) -> Trace:
    """Concrete run for a witness (a decided transition) or, with ``end_state``, a path to a state."""
    model = result.model
    if end_state is not None:
        path = result.path(end_state)
    elif witness is not None and witness.parent >= 0:
        path = result.path(witness.parent)
    else:
        path = []
    if path:
        a_index = path[0][1]
    else:
        assert witness is not None
        a_index = witness.choice
    assignment = model.assignments[a_index]
    model.initial(assignment)
    system = model.system
    concrete = system.snapshot()
    monitors = list(model.monitor_values)
    budget = model.budget
    before = _plain(system.observe())
    initial = before
    steps: list[TraceStep] = []

    def try_choices(accept: Callable[[tuple[object, ...], list[Property], list[Property]], bool]) -> bool:
        nonlocal concrete, monitors, before, budget
        system.restore(concrete)
        model.monitor_values = list(monitors)
        model.budget = budget
        options = model.enabled()
        for c in options:
            system.restore(concrete)
            model.monitor_values = list(monitors)
            model.budget = budget
            index_before = system.index
            flat, bad, good, _facts = model.step(c)
            if accept(flat, bad, good):
                obs = _plain(system.observe())
                changes = tuple((o, f, before.get(o, {}).get(f), v) for o, fields in obs.items() for f, v in fields.items()
                                if before.get(o, {}).get(f) != v)
                coarse = not c.inputs.prescan and index_before % model.spu == 0
                steps.append(TraceStep(len(steps), c, coarse, obs, changes))
                before = obs
                concrete = system.snapshot()
                monitors = list(model.monitor_values)
                budget = model.budget
                return True
        return False

    codec = result.codec
    for state, _via in path[1:]:
        target = result.encoded[state]
        def reaches(flat: tuple[object, ...], bad: list[Property], good: list[Property], t: bytes = target) -> bool:
            return bool(codec.encode(flat) == t)

        if not try_choices(reaches):
            raise ReplayError(f"no input reproduces step {len(steps) + 1} of the path to state {state}")
    if end_state is None and witness is not None and witness.parent >= 0:
        if kind == "violation":
            ok = try_choices(lambda flat, bad, good: any(p.name == prop for p in bad))
        else:
            ok = try_choices(lambda flat, bad, good: any(p.name == prop for p in good))
        if not ok:
            raise ReplayError(f"no input reproduces the last step of the counterexample for {prop}")
    return Trace(prop, kind, tuple(assignment), initial, tuple(steps))


def _plain(obs: Mapping[str, Mapping[str, object]]) -> dict[str, dict[str, object]]:
    return {k: dict(v) for k, v in obs.items()}


# --------------------------------------------------------------------------- scenario text


def _y(value: object) -> str:
    """A YAML flow scalar/collection (JSON is valid YAML)."""
    return json.dumps(value, sort_keys=False, ensure_ascii=False)


def scenario_text(result: SearchResult, trace: Trace, prop: Property | None) -> str:
    model = result.model
    sd = model.sysdef
    lines = [
        f"# Counterexample found by `motionchart check --system {sd.name}`.",
        "# Replay it on the engine with `motionchart simulate FILE`.",
        f"format: {SCENARIO_FORMAT}",
        f"name: {_y(f'{trace.kind}: {trace.prop} (system {sd.name})')}",
    ]
    what = {"violation": "violates", "witness": "reaches", "deadlock": "ends in a state without successors for"}[trace.kind]
    desc = f"A shortest run ({len(trace.steps)} scans) that {what} property {trace.prop}."
    if prop is not None and prop.description:
        desc += f" Property: {prop.description}"
    lines.append(f"description: {_y(desc)}")
    if prop is not None:
        lines.append(f"sources: [{_y(prop.source)}]")
    lines.append(f"covers: [{_y('property.' + trace.prop)}]")
    lines += ["setup:", f"  scan_ms: {sd.scan_ms}", f"  coarse_update_ms: {sd.coarse_update_ms}"]
    for section, devices in (("axes", False), ("devices", True)):
        chosen = [(name, g, ci) for (name, g), ci in zip(model.axis_defs, trace.assignment) if g.device is devices]
        if not chosen:
            continue
        lines.append(f"  {section}:")
        for name, g, ci in chosen:
            variables = dict(g.variables)
            variables.update(dict(g.configurations[ci].variables))
            entry: dict[str, object] = {"type": g.axis_type}
            if g.chart != model.spec.chart_for_axis_type(g.axis_type).id:
                entry["chart"] = g.chart
            if g.state is not None:
                entry["state"] = g.state
            if variables:
                entry["variables"] = dict(sorted(variables.items()))
            parameters = {**dict(g.parameters), **dict(g.configurations[ci].parameters)}
            if parameters:
                entry["parameters"] = dict(sorted(parameters.items()))
            if g.events:
                entry["events"] = list(g.events)
            lines.append(f"    {name}: {_y(entry)}  # configuration {g.configurations[ci].name}")
    lines.append("  program:")
    add_ons = {e.tag: e for e in sd.add_ons}
    for tag, mnemonic, axis in model.program:
        if tag in add_ons:
            e = add_ons[tag]
            item: dict[str, object] = {"tag": tag, "instruction": mnemonic, "operands": dict(e.operands)}
            if e.preset:
                item["preset"] = dict(e.preset)
            lines.append(f"    - {_y(item)}")
            continue
        lines.append(f"    - {_y({'tag': tag, 'instruction': mnemonic, 'axis': axis})}")
    internal = {s.tag.name for s in model.slots if s.internal}
    lines.append("steps:")
    if not trace.steps:
        lines += ["  - name: the initial state already shows it", "    scans: 1"]
    for st in trace.steps:
        c = st.choice
        lines.append(f"  - name: {_y(c.label())}")
        if c.kind == "raise":
            lines.append(f"    rungs: {_y({c.tag: True})}")
            if c.operands:
                lines.append(f"    operands: {_y({c.tag: dict(c.operands)})}")
        elif c.kind == "drop":
            lines.append(f"    rungs: {_y({c.tag: False})}")
        elif c.kind == "input":
            lines.append(f"    operands: {_y({c.tag: dict(c.operands)})}")
        if c.kind == "event" or c.drive:
            events = [{"axis": e.axis, "event": e.event} for e in c.inputs.events]
            lines.append(f"    events: [{', '.join(_y(e) for e in events)}]")
        if c.kind == "prescan":
            lines.append("    prescan: true")
        lines.append("    expect:")
        for obj, fields in st.observations.items():
            if obj not in internal:  # the calls of an add-on instruction are its own, not the program's tags
                # a chart state without a number (a device's) has no state attribute value to expect
                lines.append(f"      {obj}: {_y({k: v for k, v in fields.items() if v is not None})}")
    return "\n".join(lines) + "\n"


def write_scenario(result: SearchResult, trace: Trace, prop: Property | None, directory: Path) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{result.model.sysdef.name}-{trace.prop}.yaml"
    atomic_write_text(path, scenario_text(result, trace, prop))
    return path


def table_text(trace: Trace) -> str:
    """The run as a per-scan table: input and the observations that changed."""
    rows = [f"{'scan':>5}  {'input':<36}  changes"]
    for st in trace.steps:
        changes = "  ".join(f"{o}.{f}={scan_cell(a)}" for o, f, _b, a in st.changes if f != "FLAGS") or "-"
        cu = "" if st.coarse_update else " (no coarse update)"
        rows.append(f"{st.index:>5}  {st.choice.label()[:36]:<36}  {changes}{cu}")
    return "\n".join(rows) + "\n"
