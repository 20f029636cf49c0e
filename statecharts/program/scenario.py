"""Scenarios with a ladder program: the program decides the rungs, the scenario the world around it.

Pipeline position: scenario file -> :func:`statecharts.scenario.load_scenario` (which
hands a scenario whose ``setup.program`` names a file to this module) -> program
reader + axes -> :class:`~statecharts.scan.System` with a
:class:`~statecharts.program.ladder.Ladder` -> the per-scan rows and verdict of
:func:`statecharts.scenario.run_scenario`.  The format is the one scenario format
(``docs/scenarios.md``) with these keys (``docs/programs.md`` has examples):

* ``setup.program``: the program file, relative to the scenario (``.rll``/``.txt``
  rung text, or ``.L5X``), or ``{file: ..., routine: ..., program: ...}``;
* ``setup.tags``: initial values of program tags (``STATE: 1``, ``T1.PRE: 500``);
* ``setup.prescan`` (default true): the set-up ends with the prescan the controller
  makes on entering Run mode (it is not counted as a scan);
* per step ``tags``: tag writes made before the step's first scan (push buttons, limit
  switches); ``events``, ``scans`` and ``prescan`` as in every scenario;
* ``expect`` (checked after the step's last scan) and ``always`` (checked after each
  of its scans): besides ``axis: {field: value}`` and ``motion_tag: {member: value}``,
  a tag path with its value (``NEXTSTATE: 1``, ``X_STAT[1].DN: true``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from statecharts import expectations
from statecharts import ir as spec_ir
from statecharts.diagnostics import Diagnostic, InputError, ScenarioError
from statecharts.engine import AxisInstance
from statecharts.expr import EvalError
from statecharts.program.ir import AXIS_UNTYPED, Program, Scalar
from statecharts.program.ladder import Ladder, ProgramFault
from statecharts.program.reader import load_program
from statecharts.scan import EnvironmentEvent, ScanInputs, System
from statecharts.scenario import (
    AxisSetup,
    ScanRow,
    Scenario,
    ScenarioResult,
    Step,
    numeric_observable,
    passes_through_expectation,
    run_steps,
    value_problem,
)

Expectation = tuple[str, str, object]  # (observation object, field, value)


@dataclass(frozen=True, slots=True)
class ProgramScenario(Scenario):
    ladder_program: Program | None = None
    initial_tags: tuple[tuple[str, Scalar], ...] = ()
    prescan: bool = True


def is_program_scenario(doc: Mapping[str, Any]) -> bool:
    setup = doc.get("setup")
    return isinstance(setup, Mapping) and isinstance(setup.get("program"), (str, Mapping))


def load_program_scenario(path: Path, tree: Any, doc: Mapping[str, Any], spec: spec_ir.Spec,
                          err: Any, errors: list[Diagnostic], base: Scenario) -> ProgramScenario:
    """The rest of a program scenario, once the schema and the axes have been checked."""
    setup = doc["setup"]
    ref = setup["program"]
    entry = {"file": ref} if isinstance(ref, str) else dict(ref)
    file = (path.parent / entry["file"]) if not Path(entry["file"]).is_absolute() else Path(entry["file"])
    try:
        program = load_program(file, spec=spec, routine=entry.get("routine"), program=entry.get("program"))
    except InputError as exc:
        raise ScenarioError([*errors, *exc.diagnostics]) from None

    axes = {a.name: a for a in base.axes}
    setup_axes = setup["axes"]
    for tag in program.axes():
        if tag.name not in setup_axes:
            if tag.data_type == AXIS_UNTYPED:
                err(("setup", "axes"), f"the program uses axis {tag.name!r}; give it in setup.axes with its type "
                                       f"(a rung file does not declare axis types)")
            else:
                try:
                    chart = spec.chart_for_axis_type(tag.data_type)
                except KeyError:
                    err(("setup", "program"), f"axis {tag.name} of the program has type {tag.data_type}, which no chart models")
                    continue
                variables = (("AxisType", tag.data_type),) if "AxisType" in {v.name for v in chart.variables} else ()
                axes[tag.name] = AxisSetup(tag.name, tag.data_type, chart.id, None, variables)
        elif tag.data_type != AXIS_UNTYPED and setup_axes[tag.name]["type"] != tag.data_type:
            err(("setup", "axes", tag.name, "type"), (f"axis {tag.name} is a {tag.data_type} in the program, "
                                                      f"not a {setup_axes[tag.name]['type']}"))
    probe = Ladder(program)
    for d in probe.binding_problems:
        errors.append(d)
    motion_tags = {b.tag for b in probe.bindings}
    paths = probe.paths()

    def check_tag_values(values: Mapping[str, object], parts: tuple[Any, ...]) -> tuple[tuple[str, Scalar], ...]:
        out = []
        for tpath, value in values.items():
            try:
                _slot, t, bit = probe.slot(tpath)
            except KeyError as exc:
                err((*parts, tpath), f"cannot write {tpath!r}: {exc.args[0]}")
                continue
            kind = "bool" if t == "BOOL" or bit is not None else ("real" if t == "REAL" else "int")
            problem = value_problem(kind, None, value)
            if problem:
                err((*parts, tpath), f"{tpath} is a {'BOOL' if bit is not None else t}: {problem}")
                continue
            assert isinstance(value, (bool, int, float))  # value_problem accepts nothing else
            out.append((tpath, value))
        return tuple(out)

    charts = {a.name: spec.chart(a.chart) for a in axes.values()}

    def resolve(target: str, fields: object, parts: tuple[Any, ...]) -> list[Expectation]:
        out: list[Expectation] = []
        if isinstance(fields, Mapping):
            if target in charts:
                c = charts[target]
                allowed = ["state", c.state_attribute] + [v.name for v in c.variables]
            elif target in motion_tags:
                allowed = [m.name for m in spec.tag_type.members] + ["FLAGS"]
            else:
                for fname, value in fields.items():
                    out.extend(resolve(f"{target}{fname}" if str(fname).startswith("[") else f"{target}.{fname}",
                                       value, (*parts, fname)))
                return out
            for fname, value in fields.items():
                if fname == expectations.PASSES_THROUGH and target in charts:
                    out.append((target, fname, passes_through_expectation(charts[target], value, (*parts, fname), err)))
                    continue
                if fname not in allowed:
                    err((*parts, fname), f"{target} has no observable {fname!r}; expected one of: {', '.join(allowed)}")
                    continue
                # tolerances and `not:` as in every scenario (docs/scenarios.md)
                matcher, problem = expectations.parse(value, numeric=numeric_observable(spec, charts.get(target), fname))
                if problem:
                    err((*parts, fname), f"{target}.{fname}: {problem}")
                    continue
                out.append((target, fname, matcher))
            return out
        if target in paths:
            obj, fld = paths[target]
            return [(obj, fld, fields)]
        head, _, member = target.rpartition(".")
        if head in motion_tags:
            return resolve(head, {member: fields}, parts)
        if head in charts:
            return resolve(head, {member: fields}, parts)
        known = sorted(set(paths) | motion_tags | set(charts))
        err(parts, f"{target!r} is not a program tag, motion tag or axis; known: {', '.join(known[:40])}"
                   + (" ..." if len(known) > 40 else ""))
        return out

    initial = check_tag_values(setup.get("tags", {}), ("setup", "tags"))
    steps: list[Step] = []
    for i, s in enumerate(doc["steps"]):
        p = ("steps", i)
        for key in ("rungs", "operands"):
            if key in s:
                err((*p, key), f"with a program, the program decides the rungs and operands; write program tags "
                               f"with `tags:` instead of `{key}:`")
        writes = check_tag_values(s.get("tags", {}), (*p, "tags"))
        events = []
        for j, e in enumerate(s.get("events", [])):
            event_chart = charts.get(e["axis"])
            if event_chart is None:
                err((*p, "events", j, "axis"), f"unknown axis {e['axis']!r}; axes: {', '.join(charts)}")
                continue
            env_events = [ev.name for ev in event_chart.events if ev.kind == "environment"]
            if e["event"] not in env_events:
                err((*p, "events", j, "event"), f"{e['event']!r} is not an environment event of {event_chart.id}; "
                                                f"expected one of: {', '.join(env_events)}")
            events.append(EnvironmentEvent(e["axis"], e["event"]))
        expect: list[Expectation] = []
        for target, fields in s.get("expect", {}).items():
            expect.extend(resolve(target, fields, (*p, "expect", target)))
        always: list[Expectation] = []
        for target, fields in s.get("always", {}).items():
            always.extend(resolve(target, fields, (*p, "always", target)))
        old = base.steps[i]
        steps.append(Step(
            index=i, name=old.name, scans=old.scans,
            inputs=ScanInputs(events=tuple(events), prescan=bool(s.get("prescan", False)), writes=dict(writes)),
            expect=tuple(expect), line=old.line, always=tuple(always), sets=old.sets, within=old.within))
    if errors:
        raise ScenarioError(errors)
    return ProgramScenario(
        file=base.file, name=base.name, description=base.description, sources=base.sources, covers=base.covers,
        scan_ms=base.scan_ms, coarse_update_ms=base.coarse_update_ms, axes=tuple(axes.values()), program=(),
        steps=tuple(steps), ladder_program=program, initial_tags=initial, prescan=bool(setup.get("prescan", True)))


def build_program_system(scenario: ProgramScenario, spec: spec_ir.Spec) -> System:
    assert scenario.ladder_program is not None
    params = {"scan_ms": scenario.scan_ms, "coarse_update_ms": scenario.coarse_update_ms}
    axes = [AxisInstance(spec.chart(a.chart), a.name, state=a.state, variables=dict(a.variables), parameters=params)
            for a in scenario.axes]
    ladder = Ladder(scenario.ladder_program, scan_ms=scenario.scan_ms)
    system = System(spec, axes, [], scan_ms=scenario.scan_ms, coarse_update_ms=scenario.coarse_update_ms, ladder=ladder)
    for tpath, value in scenario.initial_tags:
        ladder.write(tpath, value)
    if scenario.prescan:
        ladder.prescan()
    return system


def run_program_scenario(scenario: ProgramScenario, spec: spec_ir.Spec, *, on_row: Callable[[ScanRow], object] | None = None,
                         keep_rows: bool = True) -> ScenarioResult:
    """Run a program scenario (``on_row`` and ``keep_rows`` as in :func:`statecharts.scenario.run_scenario`)."""
    try:
        system = build_program_system(scenario, spec)
    except (EvalError, ValueError) as exc:
        if isinstance(exc, InputError):
            raise
        raise ScenarioError([Diagnostic(scenario.file, 1, 1, "setup", f"cannot set up the scenario: {exc}")]) from None
    return run_steps(system, scenario, on_row=on_row, keep_rows=keep_rows, faults=(EvalError, ProgramFault))
