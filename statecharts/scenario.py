"""Scenarios: load, validate and run a set-up plus scans with expected observations.

Pipeline position: IR + scan semantics -> **scenario runner** -> CLI ``simulate`` and the
tests.  A scenario file (YAML or JSON, ``format: motionchart-scenario/1``, schema in
``spec/schema/scenario.schema.json``) is checked against the schema and then against
the spec (known axis types, states, variables, instructions, operands and observation
fields); every problem is reported with its file, line and node path, all at once.

Running it gives a :class:`ScenarioResult`: the record of every scan and the list of
expectation failures, each naming the step, the object and the field.
"""

from __future__ import annotations

import difflib
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from statecharts import addon, expectations, ir
from statecharts.diagnostics import Diagnostic, ScenarioError, locate, node_path
from statecharts.engine import AxisInstance
from statecharts.expr import EvalError
from statecharts.loader import bundled_spec_dir, plain_data, read_document, schema_diagnostics, tree_diagnostics
from statecharts.scan import EnvironmentEvent, ScanInputs, ScanRecord, System

SCENARIO_FORMAT = "motionchart-scenario/1"


@dataclass(frozen=True, slots=True)
class AxisSetup:
    name: str
    axis_type: str
    chart: str
    state: str | None
    variables: tuple[tuple[str, object], ...]
    #: instance parameters of the chart (a device handler's id and axes)
    parameters: tuple[tuple[str, object], ...] = ()
    #: events sent once the instance is set up (a device's mode selection)
    events: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class ProgramEntry:
    tag: str
    instruction: str
    axis: str
    operands: tuple[tuple[str, object], ...]
    #: MOTION_INSTRUCTION members set before the first scan (``preset:``)
    preset: tuple[tuple[str, object], ...] = ()
    #: the axis of the instruction's master operand (MAG's MasterAxis), ``master:``
    master: str | None = None


@dataclass(frozen=True, slots=True)
class Step:
    index: int
    name: str
    scans: int
    inputs: ScanInputs
    expect: tuple[tuple[str, str, object], ...]  # (object, field, value or expectations.Approx / Not / PassesThrough)
    line: int
    #: attribute writes before the step's first scan, as SSV does: (axis, variable, value)
    sets: tuple[tuple[str, str, object], ...] = ()
    #: with ``within: N`` the step lasts until its expectations hold, at most N scans
    within: int | None = None
    #: checked after each of the step's scans (scenarios with a ladder program: docs/programs.md)
    always: tuple[tuple[str, str, object], ...] = ()


@dataclass(frozen=True, slots=True)
class Scenario:
    file: str
    name: str
    description: str
    sources: tuple[str, ...]
    covers: tuple[str, ...]
    scan_ms: int
    coarse_update_ms: int
    axes: tuple[AxisSetup, ...]
    program: tuple[ProgramEntry, ...]
    steps: tuple[Step, ...]


@dataclass(frozen=True, slots=True)
class Mismatch:
    step: int
    step_name: str
    scan: int
    target: str
    field: str
    expected: object
    actual: object
    line: int

    def __str__(self) -> str:
        label = f"step {self.step + 1}" + (f" ({self.step_name})" if self.step_name else "")
        return (f"line {self.line}: {label}, scan {self.scan}: {scan_label(self.target, self.field)} "
                f"expected {_yaml_value(self.expected)}, got {_yaml_value(self.actual)}")

    def located(self, file: str) -> str:
        """``file:line: step ...``, the form editors and CI annotations understand."""
        return f"{file}:{self}".replace(":line ", ":", 1)


def _yaml_value(value: object) -> str:
    """Spell a value as it is written in a scenario (true/false, not True/False)."""
    return expectations.yaml_value(value)


def scan_label(obj: str, field: str) -> str:
    """How an observed value is named: ``mso1.DN``, ``Axis1.state``; program tags ``STATE``, ``Arr[2]``, ``T1.DN``."""
    if not field:
        return obj
    return obj + field if field.startswith("[") else f"{obj}.{field}"


def scan_cell(value: object) -> str:
    """Spell a value in a per-scan table: bits as 1/0, reals without trailing zeros."""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


@dataclass(frozen=True, slots=True)
class ScanRow:
    """One scan of a run, with the step it belongs to and what changed."""

    step: int
    step_name: str
    record: ScanRecord
    changes: tuple[tuple[str, str, object, object], ...]  # (object, field, before, after)


@dataclass(frozen=True, slots=True)
class ScenarioResult:
    scenario: Scenario
    rows: tuple[ScanRow, ...]
    mismatches: tuple[Mismatch, ...]
    #: scans run (``len(rows)`` unless the run was asked not to keep its rows)
    scan_count: int | None = None

    @property
    def scans(self) -> int:
        return len(self.rows) if self.scan_count is None else self.scan_count

    @property
    def passed(self) -> bool:
        return not self.mismatches


def scenario_schema() -> dict[str, Any]:
    schema: dict[str, Any] = json.loads(
        (bundled_spec_dir() / "schema" / "scenario.schema.json").read_text(encoding="utf-8")
    )
    return schema


def _read(path: Path, errors: list[Diagnostic]) -> Any:
    """Parse a scenario file; a ``.json`` file must be JSON, anything else YAML."""
    return read_document(path, errors, what="scenario")


def _coerce_operand(operand: ir.Operand, value: object) -> object:
    if isinstance(value, str) and operand.text_values:
        names = {k.lower(): v for k, v in operand.text_values}
        if value.lower() in names:
            return names[value.lower()]
    return value


def load_scenario(path: Path | str, spec: ir.Spec) -> Scenario:
    """Read and check a scenario against the spec; raise ScenarioError with every problem."""
    path = Path(path)
    errors: list[Diagnostic] = []
    tree = _read(path, errors)
    if tree is None or errors:
        if not errors:
            errors.append(Diagnostic(str(path), 1, 1, "", f"empty scenario; expected a mapping with `format: {SCENARIO_FORMAT}`"))
        raise ScenarioError(errors)
    return _scenario(path, tree, spec)


def load_scenario_document(name: str, tree: Any, spec: ir.Spec) -> Scenario:
    """Check a scenario given as parsed data (a YAML tree or plain dicts and lists), as
    :func:`load_scenario` checks a file; ``name`` is the file named in diagnostics."""
    if tree is None:
        raise ScenarioError([Diagnostic(name, 1, 1, "", f"empty scenario; expected a mapping with `format: {SCENARIO_FORMAT}`")])
    problems, _fatal = tree_diagnostics(name, tree, what="scenario")
    if problems:
        raise ScenarioError(problems)
    return _scenario(Path(name), tree, spec)


def _scenario(path: Path, tree: Any, spec: ir.Spec) -> Scenario:
    name = str(path)
    errors: list[Diagnostic] = []
    errors.extend(schema_diagnostics(name, tree, scenario_schema(), "a scenario"))
    if errors:
        raise ScenarioError(errors)
    doc = plain_data(tree)

    def err(parts: tuple[Any, ...], message: str) -> None:
        line, col = locate(tree, parts) if hasattr(tree, "lc") else (1, 1)
        errors.append(Diagnostic(name, line, col, node_path(parts), message))

    setup = doc["setup"]
    axis_types = sorted({t for c in spec.charts for t in c.axis_types})
    axes: list[AxisSetup] = []
    charts: dict[str, ir.Chart] = {}
    untyped: set[str] = set()  # axes of an unknown type: their uses are not errors of their own
    instances = [("axes", n, a) for n, a in setup["axes"].items()] + [("devices", n, d) for n, d in setup.get("devices", {}).items()]
    for group, axis_name, a in instances:
        p: tuple[str | int, ...] = ("setup", group, axis_name)
        if group == "devices" and axis_name in setup["axes"]:
            err(p, f"{axis_name!r} is both an axis and a device")
        try:
            chart = spec.chart_for_axis_type(a["type"])
        except KeyError:
            err((*p, "type"), f"unknown axis type {a['type']!r}; expected one of: {', '.join(axis_types)}")
            untyped.add(axis_name)
            continue
        if "chart" in a and a["chart"] != chart.id:
            # an axis type several charts model (AXIS_VIRTUAL): the axis chooses one of them
            named = [c.id for c in spec.charts if a["type"] in c.axis_types]
            if a["chart"] not in named:
                err((*p, "chart"), f"chart {a['chart']!r} does not model axis type {a['type']!r}; "
                                   f"expected one of: {', '.join(named)}")
                untyped.add(axis_name)
                continue
            chart = spec.chart(a["chart"])
        charts[axis_name] = chart
        state = a.get("state")
        startable = [s.id for s in chart.states if s.kind not in (ir.StateKind.HISTORY, ir.StateKind.PARALLEL)]
        if state is not None and state not in startable:
            what = "no state" if state not in {s.id for s in chart.states} else "a history or parallel state"
            err((*p, "state"), f"chart {chart.id} has {what} {state!r}; an axis can start in: {', '.join(startable)}")
        variables = dict(a.get("variables", {}))
        for vname, value in variables.items():
            try:
                var = chart.variable(vname)
            except KeyError:
                err((*p, "variables", vname), f"chart {chart.id} has no variable {vname!r}; variables: {', '.join(v.name for v in chart.variables)}")
                continue
            problem = value_problem(var.type, var.domain, value)
            if problem:
                err((*p, "variables", vname), f"{vname}: {problem}")
        if state in startable:
            # the drive-model values the start state implies (a connected drive with its
            # DC bus up for a Stopped CIP axis...); the scenario's own values win
            variables = {**_implied(chart, state), **variables}
        if "AxisType" in {v.name for v in chart.variables}:
            variables.setdefault("AxisType", a["type"])
        params = {cp.name: cp for cp in chart.parameters}
        for pname, value in a.get("parameters", {}).items():
            if pname not in params:
                err((*p, "parameters", pname), f"chart {chart.id} has no parameter {pname!r}; parameters: {', '.join(params) or '(none)'}")
            elif params[pname].type == "axis" and value not in setup["axes"]:
                err((*p, "parameters", pname), f"{pname}: expected the name of an axis ({', '.join(setup['axes'])}), got {value!r}")
            elif params[pname].type == "int" and (isinstance(value, bool) or not isinstance(value, int)):
                err((*p, "parameters", pname), f"{pname}: expected an integer, got {value!r}")
        given = {cp.name: cp.default for cp in chart.parameters if cp.default is not None}
        given.update(a.get("parameters", {}))
        env_events = [ev.name for ev in chart.events if ev.kind == "environment"]
        for j, ev in enumerate(a.get("events", [])):
            if ev not in env_events:
                err((*p, "events", j), f"{ev!r} is not an environment event of {chart.id}; expected one of: {', '.join(env_events)}")
        axes.append(AxisSetup(axis_name, a["type"], chart.id, state, tuple(sorted(variables.items())),
                              tuple(sorted(given.items())), tuple(a.get("events", []))))

    if isinstance(setup.get("program"), (str, Mapping)):
        # a ladder program file: docs/programs.md
        return _load_ladder_scenario(path, tree, doc, spec, err, errors, axes)
    program: list[ProgramEntry] = []
    tag_ins: dict[str, ir.Instruction] = {}
    add_on_defs = {a.id: a for a in spec.add_ons}
    add_on_tags: dict[str, ir.AddOnInstruction] = {}
    for i, entry in enumerate(setup.get("program", [])):
        p = ("setup", "program", i)
        if entry["tag"] in tag_ins or entry["tag"] in add_on_tags:
            err((*p, "tag"), f"tag {entry['tag']!r} is used twice; each instruction needs its own MOTION_INSTRUCTION tag")
        if entry["instruction"] in add_on_defs:
            ao = add_on_tags[entry["tag"]] = add_on_defs[entry["instruction"]]
            for key in ("axis", "master"):
                if key in entry:
                    err((*p, key), f"{ao.id} takes its axes as operands (its InOut parameters), not `{key}:`")
            ops = addon.check_operands(ao, entry.get("operands", {}), charts, (*p, "operands"), err)
            for par in ao.parameters:
                if par.usage == "InOut" and par.name not in entry.get("operands", {}):
                    err((*p, "operands"), f"{ao.id} needs its InOut parameter {par.name}")
            preset = addon.check_preset(ao, entry.get("preset", {}), (*p, "preset"), err)
            program.append(ProgramEntry(entry["tag"], ao.id, "", tuple(sorted(ops.items())), tuple(preset.items())))
            continue
        if "axis" not in entry:
            err(p, f"{entry['instruction']} needs `axis:`, the axis it acts on")
            continue
        variants = spec.variants(entry["instruction"])
        if not variants:
            err((*p, "instruction"), f"unknown instruction {entry['instruction']!r}; expected one of: {', '.join(spec.mnemonics())}")
            continue
        ins = variants[0]
        if entry["axis"] not in setup["axes"]:
            err((*p, "axis"), f"unknown axis {entry['axis']!r}; axes: {', '.join(setup['axes'])}")
        elif entry["axis"] in charts:
            # an axis family without a variant is legal: the instruction errs at run time
            ins = next((v for v in variants if charts[entry["axis"]].id in v.charts), variants[0])
        tag_ins[entry["tag"]] = ins
        master = entry.get("master")
        if ins.master_operand is not None and master is None:
            err(p, f"{ins.mnemonic} needs `master:`, the axis of its {ins.master_operand} operand")
        elif master is not None and ins.master_operand is None:
            err((*p, "master"), f"{ins.mnemonic} has no master axis operand")
        elif master is not None and master not in setup["axes"]:
            err((*p, "master"), f"unknown axis {master!r}; axes: {', '.join(setup['axes'])}")
        elif master is not None and master == entry["axis"]:
            err((*p, "master"), f"the master axis of {entry['tag']!r} is its own axis {master!r}")
        ops = _operands(ins, entry.get("operands", {}), (*p, "operands"), err)
        preset = _preset(spec, entry.get("preset", {}), (*p, "preset"), err)
        program.append(ProgramEntry(entry["tag"], ins.mnemonic, entry["axis"], tuple(sorted(ops.items())),
                                    tuple(preset.items()), master))

    steps: list[Step] = []
    for i, s in enumerate(doc["steps"]):
        p = ("steps", i)
        for tag in s.get("rungs", {}):
            if tag not in tag_ins and tag not in add_on_tags:
                err((*p, "rungs", tag), f"unknown tag {tag!r}; program tags: {', '.join([*tag_ins, *add_on_tags]) or '(none)'}")
        operands: dict[str, Mapping[str, object]] = {}
        for tag, ops in s.get("operands", {}).items():
            if tag in add_on_tags:
                for pname in ops:
                    if any(par.name == pname and par.type == "axis" for par in add_on_tags[tag].parameters):
                        err((*p, "operands", tag, pname), f"{pname} names the axis the instruction's calls are bound "
                                                           "to when the program is set up; a step cannot change it")
                operands[tag] = addon.check_operands(add_on_tags[tag], ops, charts, (*p, "operands", tag), err)
                continue
            if tag not in tag_ins:
                err((*p, "operands", tag), f"unknown tag {tag!r}")
                continue
            operands[tag] = _operands(tag_ins[tag], ops, (*p, "operands", tag), err)
        events = []
        for j, e in enumerate(s.get("events", [])):
            event_chart = charts.get(e["axis"])
            if event_chart is None:
                if e["axis"] not in untyped:
                    err((*p, "events", j, "axis"), f"unknown axis {e['axis']!r}; axes: {', '.join(setup['axes'])}")
                continue
            env_events = [ev.name for ev in event_chart.events if ev.kind in ("environment", "drive")]
            if e["event"] not in env_events:
                err((*p, "events", j, "event"),
                    f"{e['event']!r} is not an environment event of {event_chart.id}; expected one of: {', '.join(env_events)}")
            events.append(EnvironmentEvent(e["axis"], e["event"]))
        for key in ("tags", "always"):
            if key in s:
                err((*p, key), f"`{key}:` needs a ladder program (setup.program naming a program file)")
        expect: list[tuple[str, str, object]] = []
        for target, fields in s.get("expect", {}).items():
            if not isinstance(fields, Mapping):
                err((*p, "expect", target), (f"expected a mapping of observables for {target!r}; a tag path with a "
                                             f"value needs a ladder program (setup.program naming a program file)"))
                continue
            if target in add_on_tags:
                ao = add_on_tags[target]
                for fname, value in fields.items():
                    problem = addon.observable_problem(ao, fname, value)
                    if problem:
                        err((*p, "expect", target, fname), f"{target}.{fname}: {problem}")
                    else:
                        expect.append((target, fname, value))
                continue
            if target in tag_ins:
                allowed = [m.name for m in spec.tag_type.members] + ["FLAGS"]
            elif target in charts:
                c = charts[target]
                allowed = ["state", c.state_attribute] + [v.name for v in c.variables]
            else:
                if target not in untyped:
                    err((*p, "expect", target), (f"unknown tag or axis {target!r}; tags: {', '.join(tag_ins) or '(none)'}; "
                                                 f"axes: {', '.join(setup['axes'])}"))
                continue
            for fname, value in fields.items():
                if fname == expectations.PASSES_THROUGH and target in charts:
                    expect.append((target, fname, passes_through_expectation(charts[target], value, (*p, "expect", target, fname), err)))
                    continue
                if fname not in allowed:
                    err((*p, "expect", target, fname), f"{target} has no observable {fname!r}; expected one of: {', '.join(allowed)}")
                    continue
                matcher, problem = expectations.parse(value, numeric=numeric_observable(spec, charts.get(target), fname))
                if problem is None and not isinstance(matcher, expectations.Approx):
                    # a plain value, or the value after `not:`, must be one the observable can take
                    plain = matcher.value if isinstance(matcher, expectations.Not) else matcher
                    problem = _expectation_problem(spec, charts.get(target) if target not in tag_ins else None, fname, plain)
                if problem:
                    err((*p, "expect", target, fname), f"{target}.{fname}: {problem}")
                expect.append((target, fname, matcher))
        line, _ = locate(tree, p) if hasattr(tree, "lc") else (1, 1)
        sets = _sets(charts, untyped, setup["axes"], s.get("set", {}), (*p, "set"), err)
        within = s.get("within")
        if within is not None and "scans" in s:
            err((*p, "within"), "a step gives either `scans:` (a fixed count) or `within:` (at most that many), not both")
        if within is not None and not s.get("expect"):
            err((*p, "within"), "`within:` needs expectations to wait for")
        steps.append(Step(
            index=i, name=str(s.get("name", "")), scans=int(within if within is not None else s.get("scans", 1)),
            inputs=ScanInputs(rungs=dict(s.get("rungs", {})), operands=operands, events=tuple(events),
                              prescan=bool(s.get("prescan", False))),
            expect=tuple(expect), line=line, sets=sets, within=int(within) if within is not None else None,
        ))
    if not any(s.expect for s in steps) and steps:
        err(("steps",), "no step has `expect:`; a scenario must check at least one observation")
    scan_ms = int(setup.get("scan_ms", 10))
    cu_ms = int(setup.get("coarse_update_ms", scan_ms))
    if cu_ms % scan_ms:
        err(("setup", "coarse_update_ms"), f"coarse_update_ms ({cu_ms}) must be a multiple of scan_ms ({scan_ms})")
    if errors:
        raise ScenarioError(errors)
    return Scenario(
        file=name, name=doc["name"], description=str(doc.get("description", "")),
        sources=tuple(doc.get("sources", [])), covers=tuple(doc.get("covers", [])),
        scan_ms=scan_ms, coarse_update_ms=cu_ms, axes=tuple(axes), program=tuple(program), steps=tuple(steps),
    )


#: Value ranges of the Logix integer types of the MOTION_INSTRUCTION members.
LOGIX_INTEGER_RANGES: dict[str, tuple[int, int]] = {
    "SINT": (-(2**7), 2**7 - 1), "INT": (-(2**15), 2**15 - 1), "DINT": (-(2**31), 2**31 - 1),
    "LINT": (-(2**63), 2**63 - 1),
}


def _expectation_problem(spec: ir.Spec, chart: ir.Chart | None, field: str, value: object) -> str | None:
    """Why ``value`` can never be observed in ``field`` (of a tag when ``chart`` is None)."""
    if isinstance(value, float) and value != value:
        return "NaN is never equal to anything; expect a number"
    if chart is None:
        if field == "FLAGS":
            return _integer_problem("DINT", value)
        member = next((m for m in spec.tag_type.members if m.name == field), None)
        if member is None:
            return None
        if member.type.upper() == "BOOL":
            return None if isinstance(value, bool) else f"expected true or false, got {_yaml_value(value)}"
        return _integer_problem(member.type.upper(), value)
    if field == "state":
        ids = [st.id for st in chart.leaf_states()]
        if value in ids:
            return None
        hint = difflib.get_close_matches(str(value), ids, n=1, cutoff=0.6)
        did = f" (did you mean {hint[0]!r}?)" if hint else ""
        return f"chart {chart.id} has no state {_yaml_value(value)}{did}; states: {', '.join(ids)}"
    if field == chart.state_attribute:
        values = sorted({st.value for st in chart.states if st.value is not None})
        if isinstance(value, bool) or not isinstance(value, int):
            return f"expected an integer state value, got {_yaml_value(value)}"
        return None if value in values else f"{value} is not a state value of {chart.id}; values: {', '.join(map(str, values))}"
    try:
        var = chart.variable(field)
    except KeyError:
        return None
    if var.type == "int":
        # an observation may lie outside the declared domain (a faulty spec or another
        # implementation produces it); an expectation is checked against the type only
        return value_problem("int", None, value) or _integer_problem("DINT", value)
    return value_problem(var.type, var.domain, value)


def _integer_problem(logix_type: str, value: object) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int):
        return f"expected an integer ({logix_type}), got {_yaml_value(value)}"
    lo, hi = LOGIX_INTEGER_RANGES.get(logix_type, LOGIX_INTEGER_RANGES["DINT"])
    if not lo <= value <= hi:
        return f"{value if value.bit_length() <= 128 else 'the integer'} is outside the {logix_type} range [{lo}, {hi}]"
    return None


def _load_ladder_scenario(path: Path, tree: Any, doc: Mapping[str, Any], spec: ir.Spec, err: Any,
                          errors: list[Diagnostic], axes: list[AxisSetup]) -> Scenario:
    from statecharts.program.scenario import load_program_scenario

    setup = doc["setup"]
    for key in ("tags", "prescan"):
        if key in setup and not isinstance(setup.get("program"), (str, Mapping)):
            err(("setup", key), f"setup.{key} needs a ladder program")
    charts = {a.name: spec.chart(a.chart) for a in axes}
    steps = tuple(Step(index=i, name=str(s.get("name", "")), scans=int(s.get("within", s.get("scans", 1))),
                       inputs=ScanInputs(), expect=(), line=locate(tree, ("steps", i))[0],
                       sets=_sets(charts, set(), setup["axes"], s.get("set", {}), ("steps", i, "set"), err),
                       within=int(s["within"]) if "within" in s else None)
                  for i, s in enumerate(doc["steps"]))
    scan_ms = int(setup.get("scan_ms", 10))
    cu_ms = int(setup.get("coarse_update_ms", scan_ms))
    if cu_ms % scan_ms:
        err(("setup", "coarse_update_ms"), f"coarse_update_ms ({cu_ms}) must be a multiple of scan_ms ({scan_ms})")
    base = Scenario(file=str(path), name=doc["name"], description=str(doc.get("description", "")),
                    sources=tuple(doc.get("sources", [])), covers=tuple(doc.get("covers", [])), scan_ms=scan_ms,
                    coarse_update_ms=cu_ms, axes=tuple(axes), program=(), steps=steps)
    return load_program_scenario(path, tree, doc, spec, err, errors, base)


def _domain_text(domain: Sequence[object]) -> str:
    """A domain as a reader wants it: a contiguous integer range as ``[lo..hi]``."""
    values = list(domain)
    ints = [v for v in values if isinstance(v, int) and not isinstance(v, bool)]
    if len(ints) == len(values) > 8 and ints == list(range(ints[0], ints[-1] + 1)):
        return f"[{ints[0]}..{ints[-1]}]"
    return repr(values)


def value_problem(vtype: str, domain: Sequence[object] | None, value: object) -> str | None:
    """Why ``value`` cannot be given to a variable of ``vtype``, or None."""
    if vtype == "bool":
        return None if isinstance(value, bool) else f"expected true or false, got {value!r}"
    if vtype == "int" and (isinstance(value, bool) or not isinstance(value, int)):
        return f"expected an integer, got {value!r}"
    if vtype == "real" and (isinstance(value, bool) or not isinstance(value, (int, float))):
        return f"expected a number, got {value!r}"
    if domain is not None and value not in domain:
        return f"{value!r} is not in the domain {_domain_text(domain)}"
    return None


def _operands(ins: ir.Instruction, given: Mapping[str, object], parts: tuple[Any, ...], err: Any) -> dict[str, object]:
    known = {o.name: o for o in ins.operands if o.type not in ("axis", "tag")}
    out: dict[str, object] = {}
    for oname, value in given.items():
        if oname not in known:
            err((*parts, oname), f"{ins.id} has no operand {oname!r}; operands: {', '.join(known) or '(none)'}")
            continue
        operand = known[oname]
        value = _coerce_operand(operand, value)
        # any number is allowed (out-of-range values are how checks are exercised); text
        # only when it names a value ("enter as text" names were turned into numbers above)
        textual = isinstance(value, str) and operand.domain is not None and value in operand.domain
        if isinstance(value, float) and not math.isfinite(value):
            err((*parts, oname), f"operand {oname} of {ins.id}: {value} is not a finite number")
            continue
        if isinstance(value, int) and not isinstance(value, bool) and not -(2**63) <= value < 2**63:
            err((*parts, oname), f"operand {oname} of {ins.id}: the integer is beyond 64 bits")
            continue
        if not textual and (isinstance(value, bool) or not isinstance(value, (int, float))):
            names = [k for k, _ in operand.text_values]
            extra = f" or one of: {', '.join(names)}" if names else ""
            err((*parts, oname), f"operand {oname} of {ins.id}: expected a number{extra}, got {value!r}")
            continue
        out[oname] = value
    return out


def build_system(scenario: Scenario, spec: ir.Spec) -> System:
    params = {"scan_ms": scenario.scan_ms, "coarse_update_ms": scenario.coarse_update_ms}
    axes = []
    for a in scenario.axes:
        axis = AxisInstance(spec.chart(a.chart), a.name, state=a.state, variables=dict(a.variables),
                            parameters={**params, **dict(a.parameters)})
        for event in a.events:
            axis.apply_event_actions(event)
            axis.send(event)
        axes.append(axis)
    add_ons = {a.id for a in spec.add_ons}
    system = System(spec, axes, [(p.tag, p.instruction, p.axis) for p in scenario.program],
                    scan_ms=scenario.scan_ms, coarse_update_ms=scenario.coarse_update_ms,
                    masters={p.tag: p.master for p in scenario.program if p.master is not None},
                    add_ons={p.tag: dict(p.operands) for p in scenario.program if p.instruction in add_ons})
    for p in scenario.program:
        if p.tag in system.add_ons:
            system.add_ons[p.tag].preset(dict(p.preset))
            continue
        system.tags[p.tag].operands.update(dict(p.operands))
        system.tags[p.tag].values.update(dict(p.preset))
    return system


def same_value(expected: object, actual: object) -> bool:
    """Whether an observed value meets an expected one (a bool only equals a bool; numbers compare as numbers)."""
    if isinstance(expected, bool) or isinstance(actual, bool):
        return expected is actual or (isinstance(expected, bool) and isinstance(actual, bool) and expected == actual)
    if isinstance(expected, int) and isinstance(actual, int):
        return expected == actual
    if isinstance(expected, (int, float)) and isinstance(actual, (int, float)):
        if abs(expected) > 1e300 or abs(actual) > 1e300:  # beyond any REAL: no float() of a huge int
            return expected == actual
        return abs(float(expected) - float(actual)) <= 1e-9 * max(1.0, abs(float(expected)))
    return expected == actual


def run_scenario(
    scenario: Scenario, spec: ir.Spec, *, on_row: Callable[[ScanRow], object] | None = None, keep_rows: bool = True,
) -> ScenarioResult:
    """Run every step; an expression that cannot be evaluated on the scenario's values
    (e.g. a division by zero) is a ScenarioError naming the step.

    ``on_row`` sees each scan's row as soon as it is run (a table can be printed while a
    long scenario runs); with ``keep_rows=False`` the result holds no rows, only what the
    verdict needs (the latest observations and the mismatches), so a run of a million
    scans takes constant memory."""
    from statecharts.program.scenario import ProgramScenario, run_program_scenario
    if isinstance(scenario, ProgramScenario):
        return run_program_scenario(scenario, spec, on_row=on_row, keep_rows=keep_rows)
    try:
        system = build_system(scenario, spec)
    except (EvalError, ValueError) as exc:
        raise ScenarioError([Diagnostic(scenario.file, 1, 1, "setup", f"cannot set up the scenario: {exc}")]) from None
    return run_steps(system, scenario, on_row=on_row, keep_rows=keep_rows)


def run_steps(
    system: System, scenario: Scenario, *, on_row: Callable[[ScanRow], object] | None = None, keep_rows: bool = True,
    faults: tuple[type[Exception], ...] = (EvalError,),
) -> ScenarioResult:
    """The steps of ``scenario`` on ``system`` (set up by the caller): per step its ``set:``
    writes, then its scans (the first with the step's inputs), a row per scan, ``always:``
    checked after each scan and ``expect:`` after the last (or, with ``within:``, after the
    first scan where it holds).  ``faults`` raised by a scan become a ScenarioError naming
    the step; ``on_row`` and ``keep_rows`` as in :func:`run_scenario`."""
    before = system.observe()
    rows: list[ScanRow] = []
    mismatches: list[Mismatch] = []
    visits = visit_recorders(system, scenario)
    count, last_index = 0, 0
    for step in scenario.steps:
        for axis, log in visits.items():
            log.clear()
            ax = system.axes[axis]
            log.extend(reversed(ax.chart.ancestors(ax.leaf.id)))
        for axis, var, value in step.sets:
            system.axes[axis].env[var] = value
        for k in range(step.scans):
            inputs = step.inputs if k == 0 else ScanInputs(prescan=step.inputs.prescan)
            try:
                record = system.scan(inputs)
            except faults as exc:
                label = f"step {step.index + 1}" + (f" ({step.name})" if step.name else "")
                what = f"the spec cannot be evaluated on these values: {exc}" if isinstance(exc, EvalError) else str(exc)
                raise ScenarioError([Diagnostic(scenario.file, step.line, 1, f"steps[{step.index}]",
                                                f"{label}, scan {system.index}: {what}")]) from None
            changes = tuple(
                (obj, fld, before.get(obj, {}).get(fld), val)
                for obj, fields in record.observations.items()
                for fld, val in fields.items()
                if before.get(obj, {}).get(fld) != val or (obj not in before)
            )
            row = ScanRow(step.index, step.name, record, changes)
            count += 1
            last_index = record.index
            if keep_rows:
                rows.append(row)
            if on_row is not None:
                on_row(row)
            before = record.observations
            for target, fld, expected in step.always:
                actual = before[target][fld]
                if not expectations.holds(expected, actual):
                    mismatches.append(Mismatch(step.index, step.name, last_index, target, fld, expected, actual, step.line))
            if step.within is not None and not step_mismatches(step, before, visits, last_index):
                break
        mismatches.extend(step_mismatches(step, before, visits, last_index))
    return ScenarioResult(scenario, tuple(rows), tuple(mismatches), None if keep_rows else count)


def step_mismatches(step: Step, observed: Mapping[str, Mapping[str, object]], visits: Mapping[str, list[str]],
                    scan: int) -> list[Mismatch]:
    """The ``expect:`` of ``step`` that does not hold on ``observed`` (after scan ``scan``);
    ``visits`` holds the states each axis entered during the step (:func:`visit_recorders`)."""
    out = []
    for target, fld, expected in step.expect:
        if isinstance(expected, expectations.PassesThrough):
            actual: object = tuple(_leaf_visits(visits.get(target, [])))
            ok = expectations.passes_through(expected.states, visits.get(target, []))
        else:
            actual = observed[target][fld]
            ok = expectations.holds(expected, actual)
        if not ok:
            out.append(Mismatch(step.index, step.name, scan, target, fld, expected, actual, step.line))
    return out


def _leaf_visits(visited: Sequence[str]) -> list[str]:
    """The visited states without immediate repeats, for a failure message."""
    out: list[str] = []
    for v in visited:
        if not out or out[-1] != v:
            out.append(v)
    return out


class _VisitRecorder:
    """A python-statemachine listener that notes each state an axis enters."""

    def __init__(self, log: list[str]) -> None:
        self.log = log

    def on_enter_state(self, target: Any = None, **_: Any) -> None:
        if target is not None:
            self.log.append(str(target.id))


def visit_recorders(system: System, scenario: Scenario) -> dict[str, list[str]]:
    """For each axis that a ``passes_through`` names, the list its recorder appends to."""
    wanted = {t for step in scenario.steps for t, _, e in step.expect if isinstance(e, expectations.PassesThrough)}
    logs: dict[str, list[str]] = {}
    for axis in sorted(wanted):
        log: list[str] = []
        system.axes[axis].machine.add_listener(_VisitRecorder(log))  # type: ignore[no-untyped-call]  # python-statemachine leaves it untyped
        logs[axis] = log
    return logs


def _implied(chart: ir.Chart, state: str) -> dict[str, object]:
    """The variables a set-up in ``state`` implies: those of its ancestors, then its own,
    then those of the initial states it starts in (a compound state starts in its
    initial child)."""
    chain = list(reversed(chart.ancestors(state)))
    target = chart.state(state)
    while target.kind is ir.StateKind.COMPOUND and target.initial is not None:
        target = chart.state(target.initial)
        chain.append(target.id)
    out: dict[str, object] = {}
    for sid in chain:
        out.update(dict(chart.state(sid).implies))
    return out


def _preset(spec: ir.Spec, given: Mapping[str, object], parts: tuple[Any, ...], err: Any) -> dict[str, object]:
    """``preset:`` of a program entry: MOTION_INSTRUCTION members and their first values."""
    members = {m.name: m for m in spec.tag_type.members}
    out: dict[str, object] = {}
    for name, value in given.items():
        m = members.get(name)
        if m is None:
            err((*parts, name), f"{name!r} is not a MOTION_INSTRUCTION member; members: {', '.join(members)}")
        elif m.type == "BOOL" and not isinstance(value, bool):
            err((*parts, name), f"{name} is a BOOL: expected true or false, got {value!r}")
        elif m.type != "BOOL" and (isinstance(value, bool) or not isinstance(value, int)):
            err((*parts, name), f"{name} is an integer member: got {value!r}")
        else:
            out[name] = value
    return out


def _sets(charts: Mapping[str, ir.Chart], untyped: set[str], axes: Mapping[str, Any], given: Mapping[str, Any],
          parts: tuple[Any, ...], err: Any) -> tuple[tuple[str, str, object], ...]:
    """``set:`` of a step: attributes a program may write (variables marked ``writable``)."""
    out: list[tuple[str, str, object]] = []
    for axis, fields in given.items():
        chart = charts.get(axis)
        if chart is None:
            if axis not in untyped:
                err((*parts, axis), f"unknown axis {axis!r}; axes: {', '.join(axes)}")
            continue
        writable = [v.name for v in chart.variables if v.writable]
        for vname, value in fields.items():
            try:
                var = chart.variable(vname)
            except KeyError:
                var = None
            if var is None or not var.writable:
                what = "no variable" if var is None else "no writable attribute"
                err((*parts, axis, vname), f"chart {chart.id} has {what} {vname!r}; a program may write: {', '.join(writable) or '(none)'}")
                continue
            problem = value_problem(var.type, var.domain, value)
            if problem:
                err((*parts, axis, vname), f"{vname}: {problem}")
                continue
            out.append((axis, vname, value))
    return tuple(out)


def numeric_observable(spec: ir.Spec, chart: ir.Chart | None, field: str) -> bool:
    """Whether an observable holds a number (tolerances apply to numbers only)."""
    if chart is None:
        member = next((m for m in spec.tag_type.members if m.name == field), None)
        return field == "FLAGS" or (member is not None and member.type != "BOOL")
    if field == chart.state_attribute:
        return True
    try:
        return chart.variable(field).type in ("int", "real")
    except KeyError:
        return False


def passes_through_expectation(chart: ir.Chart, value: object, parts: tuple[Any, ...], err: Any) -> expectations.PassesThrough:
    """The ``passes_through:`` expectation ``value`` (a list of state ids of ``chart``); a
    problem goes to ``err(parts, message)``."""
    states = {s.id for s in chart.states}
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        err(parts, "passes_through: expected a non-empty list of state ids")
        return expectations.PassesThrough(())
    for j, v in enumerate(value):
        if v not in states:
            err((*parts, j), f"chart {chart.id} has no state {v!r}; states: {', '.join(sorted(states))}")
    return expectations.PassesThrough(tuple(value))


def scenario_files(paths: Sequence[Path | str]) -> list[Path]:
    """The scenario files of ``paths``: files as given, folders searched for ``*.yaml``, ``*.yml`` and ``*.json``."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            out.extend(sorted(x for x in p.rglob("*") if x.suffix in (".yaml", ".yml", ".json") and x.is_file()))
        else:
            out.append(p)
    return out
