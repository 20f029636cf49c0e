"""System definitions for the model checker: which axes, which instruction calls, which inputs.

Pipeline position: ``spec/systems/*.yaml`` -> **checker.system** -> :mod:`checker.model`
-> :mod:`checker.search`.

A system (``format: motionchart-system/1``, schema ``spec/schema/system.schema.json``)
chooses axis groups (an axis type, the chart when several charts model that type, how
many identical axes, the initial state and variables, and a list of *configurations*:
alternative initial variable values, each of which is explored), the program (one MOTION_INSTRUCTION tag per instruction per
axis; by default every instruction defined for the axis chart) with the axis bound to
the master-axis operand of a call that has one (``masters:``, MAG's Master Axis: an
axis of another group), operand domains
(the instruction's ``domain`` unless overridden here), the environment events offered
(by default the chart's events of kind ``environment``), whether prescan passes are
offered, the scan and coarse-update periods, and the abstractions the search may use
(see ``docs/checker.md``).  Every problem is reported with file, line and node path.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from statecharts import ir
from statecharts.diagnostics import Diagnostic, InputError, locate, node_path
from statecharts.loader import bundled_spec_dir, plain_data, read_yaml, schema_diagnostics

SYSTEM_FORMAT = "motionchart-system/1"


class SystemError_(InputError):
    """A system definition is malformed."""


@dataclass(frozen=True, slots=True)
class Configuration:
    """Alternative initial variable values of an axis group."""

    name: str
    variables: tuple[tuple[str, object], ...]
    description: str
    #: a device's chart parameters in this configuration (its id, its axes)
    parameters: tuple[tuple[str, object], ...] = ()
    #: the initial state in this configuration (None: the group's)
    state: str | None = None


@dataclass(frozen=True, slots=True)
class AxisGroup:
    """``count`` interchangeable axes of one type with the same program."""

    name: str
    axis_type: str
    chart: str
    count: int
    state: str | None
    variables: tuple[tuple[str, object], ...]
    configurations: tuple[Configuration, ...]
    program: tuple[str, ...]  # instruction mnemonics, one tag each per axis
    #: (instruction, axis) bindings of the master-axis operands of the program's calls
    #: (MAG's MasterAxis); the axis is an axis name of the system or a group's name
    masters: tuple[tuple[str, str], ...] = ()
    #: a device (``devices:``, e.g. a device handler): a chart instance that is no axis
    device: bool = False
    #: instance parameters of the chart (a device handler's id and axes)
    parameters: tuple[tuple[str, object], ...] = ()
    #: environment events sent once the instance is set up
    events: tuple[str, ...] = ()
    #: the environment events offered on these axes (None: the system's ``environment``)
    environment: tuple[str, ...] | None = None

    def axis_names(self) -> tuple[str, ...]:
        if self.count == 1:
            return (self.name,)
        return tuple(f"{self.name}{i}" for i in range(1, self.count + 1))


@dataclass(frozen=True, slots=True)
class AddOnEntry:
    """An add-on instruction tag of the program (``add_ons:``)."""

    tag: str
    instruction: str  # the add-on instruction's id
    operands: tuple[tuple[str, object], ...]
    preset: tuple[tuple[str, object], ...] = ()
    #: input parameters the environment may change while the rung is false, with their values
    inputs: tuple[tuple[str, tuple[object, ...]], ...] = ()


@dataclass(frozen=True, slots=True)
class SystemDef:
    name: str
    description: str
    file: str
    scan_ms: int
    coarse_update_ms: int
    groups: tuple[AxisGroup, ...]
    operand_domains: tuple[tuple[str, str, tuple[object, ...]], ...]  # (instruction, operand, values)
    environment: tuple[str, ...] | None  # None: every environment event of the chart
    prescan: bool
    max_live_calls: int | None  # per axis; None: unbounded
    collapse: tuple[str, ...]  # chart variables left out of the search state
    symmetry: bool
    retire_idle_tags: bool
    add_ons: tuple[AddOnEntry, ...] = ()
    #: at most this many environment events and add-on input changes per run (None: unbounded)
    max_changes: int | None = None
    #: run the drive model (positions, velocities) instead of offering its events as inputs
    motion: bool = False

    def tag_name(self, axis: str, mnemonic: str) -> str:
        return f"{axis}_{mnemonic}"

    def axes(self) -> list[tuple[str, AxisGroup]]:
        return [(name, g) for g in self.groups for name in g.axis_names()]

    def program(self) -> list[tuple[str, str, str]]:
        """(tag, instruction, axis) in program order: axis by axis, instructions as listed, then
        the add-on instruction tags (their axis: the first axis their operands name)."""
        out = [(self.tag_name(a, m), m, a) for a, g in self.axes() for m in g.program]
        axes = {a for a, _g in self.axes()}
        for e in self.add_ons:
            out.append((e.tag, e.instruction, next((str(v) for _k, v in e.operands if v in axes), "")))
        return out

    def masters(self) -> dict[str, str]:
        """tag -> the axis bound to its instruction's master-axis operand (a group's name
        stands for the group's first axis)."""
        first = {g.name: g.axis_names()[0] for g in self.groups}
        names = {a for a, _g in self.axes()}
        out: dict[str, str] = {}
        for a, g in self.axes():
            for m, master in g.masters:
                out[self.tag_name(a, m)] = master if master in names else first.get(master, master)
        return out

    def domain(self, ins: ir.Instruction, op: ir.Operand) -> tuple[object, ...]:
        for i, o, values in self.operand_domains:
            if i == ins.id and o == op.name:
                return values
        if op.domain is not None:
            return tuple(op.domain)
        return (op.default,)

    def scaled(self, count: int) -> SystemDef:
        """The same system with ``count`` axes in every group (``--axes N``)."""
        return replace(self, groups=tuple(replace(g, count=count) for g in self.groups))


def systems_dir() -> Path:
    return bundled_spec_dir() / "systems"


def system_schema() -> dict[str, Any]:
    schema: dict[str, Any] = json.loads((bundled_spec_dir() / "schema" / "system.schema.json").read_text("utf-8"))
    return schema


def bundled_systems() -> dict[str, Path]:
    """Bundled system names -> files (the name is the file's ``name:``, else its stem)."""
    out: dict[str, Path] = {}
    for p in sorted(systems_dir().glob("*.yaml")):
        errors: list[Diagnostic] = []
        tree = read_yaml(p, errors)
        name = str(tree.get("name", p.stem)) if isinstance(tree, dict) else p.stem
        out[name] = p
    return out


def load_system(path: Path | str, spec: ir.Spec) -> SystemDef:
    """Read and check one system definition against the spec; raise SystemError_ with every problem."""
    path = Path(path)
    name = str(path)
    errors: list[Diagnostic] = []
    tree = read_yaml(path, errors, what="system")
    if tree is None:
        if not errors:
            errors.append(Diagnostic(name, 1, 1, "", f"empty system; expected a mapping with `format: {SYSTEM_FORMAT}`"))
        raise SystemError_(errors)
    problems = schema_diagnostics(name, tree, system_schema(), "a system")
    if problems:
        raise SystemError_(problems)
    doc = plain_data(tree)

    def err(parts: tuple[Any, ...], message: str) -> None:
        line, col = locate(tree, parts)
        errors.append(Diagnostic(name, line, col, node_path(parts), message))

    groups: list[AxisGroup] = []
    bindings: list[tuple[int, str, dict[str, str]]] = []  # (group index, group name, masters)
    seen_names: set[str] = set()
    charts_used: dict[str, ir.Chart] = {}
    entries = [("axes", i, g) for i, g in enumerate(doc["axes"])]
    entries += [("devices", i, d) for i, d in enumerate(doc.get("devices", []))]
    axis_entry_names = {str(g["name"]) for g in doc["axes"]}
    for section, i, g in entries:
        p: tuple[Any, ...] = (section, i)
        try:
            chart = spec.chart_for_axis_type(g["type"])
        except KeyError:
            types = sorted({t for c in spec.charts for t in c.axis_types})
            err((*p, "type"), f"unknown axis type {g['type']!r}; expected one of: {', '.join(types)}")
            continue
        if "chart" in g and g["chart"] != chart.id:
            # an axis type several charts name (AXIS_VIRTUAL): the group chooses one of them
            named = [c.id for c in spec.charts if g["type"] in c.axis_types]
            if g["chart"] not in named:
                err((*p, "chart"), f"chart {g['chart']!r} does not model axis type {g['type']!r}; "
                                   f"expected one of: {', '.join(named)}")
                continue
            chart = spec.chart(g["chart"])
        charts_used[chart.id] = chart
        if g["name"] in seen_names:
            err((*p, "name"), f"axis group name {g['name']!r} is used twice")
        seen_names.add(g["name"])
        state = g.get("state")
        if state is not None and state not in {s.id for s in chart.states}:
            err((*p, "state"), f"chart {chart.id} has no state {state!r}")

        def check_vars(values: Mapping[str, object], parts: tuple[Any, ...], chart: ir.Chart = chart) -> None:
            for vname, value in values.items():
                try:
                    var = chart.variable(vname)
                except KeyError:
                    err((*parts, vname), f"chart {chart.id} has no variable {vname!r}")
                    continue
                if var.domain is not None and value not in var.domain:
                    err((*parts, vname), f"{value!r} is not in the domain of {vname}: {list(var.domain)!r}")

        variables = dict(g.get("variables", {}))
        check_vars(variables, (*p, "variables"))
        if "AxisType" in {v.name for v in chart.variables}:
            variables.setdefault("AxisType", g["type"])
        parameters: dict[str, object] = {}
        events: list[str] = []
        params = {cp.name: cp for cp in chart.parameters}

        def check_params(given: Mapping[str, object], parts: tuple[Any, ...],
                         params: Mapping[str, ir.ChartParameter] = params, chart: ir.Chart = chart) -> dict[str, object]:
            out: dict[str, object] = {}
            for pname, value in given.items():
                if pname not in params:
                    err((*parts, pname), f"chart {chart.id} has no parameter {pname!r}; parameters: "
                                         f"{', '.join(params) or '(none)'}")
                elif params[pname].type == "axis" and value not in axis_entry_names:
                    err((*parts, pname), f"{pname}: expected the name of an axis of the system "
                                         f"({', '.join(sorted(axis_entry_names))}), got {value!r}")
                elif params[pname].type == "int" and (isinstance(value, bool) or not isinstance(value, int)):
                    err((*parts, pname), f"{pname}: expected an integer, got {value!r}")
                else:
                    out[pname] = value
            return out
        if section == "devices":
            parameters = {cp.name: cp.default for cp in chart.parameters if cp.default is not None}
            parameters.update(check_params(g.get("parameters", {}), (*p, "parameters")))
            env_events = [ev.name for ev in chart.events if ev.kind == "environment"]
            for j, ev in enumerate(g.get("events", [])):
                if ev not in env_events:
                    err((*p, "events", j), f"{ev!r} is not an environment event of {chart.id}; expected one of: "
                                           f"{', '.join(env_events)}")
                else:
                    events.append(ev)
        configs = []
        for j, c in enumerate(g.get("configurations", [{"name": "default"}])):
            check_vars(c.get("variables", {}), (*p, "configurations", j, "variables"))
            if "parameters" in c and section != "devices":
                err((*p, "configurations", j, "parameters"), "parameters are a device's (`devices:`); an axis has none")
            cparams = check_params(c.get("parameters", {}), (*p, "configurations", j, "parameters"))
            cstate = c.get("state")
            if cstate is not None and cstate not in {st.id for st in chart.states}:
                err((*p, "configurations", j, "state"), f"chart {chart.id} has no state {cstate!r}")
            configs.append(Configuration(str(c["name"]), tuple(sorted(dict(c.get("variables", {})).items())),
                                         str(c.get("description", "")), tuple(sorted(cparams.items())), cstate))
        masters = dict(g.get("masters", {}))
        # an instruction with a master-axis operand (MAG) needs a binding: by default the
        # program is every instruction of the chart that has none, and those bound
        default_program = [ins.id for ins in spec.instructions
                           if chart.id in ins.charts and (ins.master_operand is None or ins.id in masters)]
        program = list(g.get("program", default_program if section == "axes" else []))
        for j, m in enumerate(program):
            try:
                ins = spec.instruction(m)
            except KeyError:
                err((*p, "program", j), f"unknown instruction {m!r}; expected one of: {', '.join(x.id for x in spec.instructions)}")
                continue
            if chart.id not in ins.charts:
                err((*p, "program", j), f"{m} is not defined for chart {chart.id}")
            elif ins.master_operand is not None and m not in masters:
                err((*p, "program", j), f"{m} needs its {ins.master_operand} operand bound to another axis of the "
                                        f"system: `masters: {{{m}: AXIS}}` in this axis group")
        if len(set(program)) != len(program):
            err((*p, "program"), "an instruction is listed twice; each call has its own tag, list it once")
        for m in masters:
            if m not in program:
                err((*p, "masters", m), f"{m} is not in the program of axis group {g['name']!r}; "
                                        f"program: {', '.join(program) or '(none)'}")
                continue
            try:
                if spec.instruction(m).master_operand is None:
                    err((*p, "masters", m), f"{m} has no master-axis operand")
            except KeyError:
                pass  # reported with the program
        bindings.append((i, g["name"], masters))
        groups.append(AxisGroup(
            name=g["name"], axis_type=g["type"], chart=chart.id, count=int(g.get("count", 1)), state=state,
            variables=tuple(sorted(variables.items())), configurations=tuple(configs), program=tuple(program),
            masters=tuple(sorted(masters.items())), device=section == "devices",
            parameters=tuple(sorted(parameters.items())), events=tuple(events),
            environment=tuple(g["environment"]) if "environment" in g else None,
        ))

    # the master axes: another axis of the system (a group's own axes are not its masters)
    axis_names = {a: grp.name for grp in groups for a in grp.axis_names()}
    group_names = {grp.name for grp in groups}
    for i, gname, masters in bindings:
        for m, master in masters.items():
            where = ("axes", i, "masters", m)
            owner = axis_names.get(master, master if master in group_names else None)
            if owner is None:
                err(where, f"unknown axis {master!r}; axes of the system: {', '.join(axis_names)}")
            elif owner == gname:
                err(where, f"the master axis of {m} is an axis of its own group {gname!r}; "
                           "bind it to an axis of another group")

    op_domains: list[tuple[str, str, tuple[object, ...]]] = []
    for mnemonic, ops in doc.get("operands", {}).items():
        p = ("operands", mnemonic)
        try:
            ins = spec.instruction(mnemonic)
        except KeyError:
            err(p, f"unknown instruction {mnemonic!r}")
            continue
        known = {o.name for o in ins.operands if o.type not in ("axis", "tag")}
        for oname, values in ops.items():
            if oname not in known:
                err((*p, oname), f"{mnemonic} has no operand {oname!r}; operands: {', '.join(sorted(known)) or '(none)'}")
                continue
            op_domains.append((mnemonic, oname, tuple(values)))

    add_ons = _add_ons(doc, spec, groups, err)
    max_changes = doc.get("max_changes")

    env_events = doc.get("environment")
    if env_events is not None:
        known_env = {e.name for c in charts_used.values() for e in c.events if e.kind in ("environment", "drive")}
        for j, e in enumerate(env_events):
            if e not in known_env:
                err(("environment", j), f"{e!r} is not an environment event; expected one of: {', '.join(sorted(known_env))}")
    for section, i, g in entries:
        if "environment" not in g:
            continue
        grp = next((x for x in groups if x.name == g["name"]), None)
        if grp is None:
            continue
        mine = {e.name for e in spec.chart(grp.chart).events if e.kind in ("environment", "drive")}
        for j, e in enumerate(g["environment"]):
            if e not in mine:
                err((section, i, "environment", j), f"{e!r} is not an environment event of {grp.chart}; expected one "
                                                    f"of: {', '.join(sorted(mine))}")

    abstraction = doc.get("abstraction", {})
    collapse = tuple(abstraction.get("collapse", []))
    for j, v in enumerate(collapse):
        if not any(v in {x.name for x in c.variables} for c in charts_used.values()):
            err(("abstraction", "collapse", j), f"no axis chart of this system has a variable {v!r}")

    scan_ms = int(doc.get("scan_ms", 10))
    cu_ms = int(doc.get("coarse_update_ms", scan_ms))
    if cu_ms % scan_ms:
        err(("coarse_update_ms",), f"coarse_update_ms ({cu_ms}) must be a multiple of scan_ms ({scan_ms})")
    if errors:
        raise SystemError_(errors)
    return SystemDef(
        name=str(doc["name"]), description=str(doc.get("description", "")), file=name,
        scan_ms=scan_ms, coarse_update_ms=cu_ms, groups=tuple(groups), operand_domains=tuple(op_domains),
        environment=tuple(env_events) if env_events is not None else None,
        prescan=bool(doc.get("prescan", True)),
        max_live_calls=doc.get("max_live_calls"), collapse=collapse,
        symmetry=bool(abstraction.get("symmetry", True)),
        retire_idle_tags=bool(abstraction.get("retire_idle_tags", True)),
        add_ons=add_ons, max_changes=int(max_changes) if max_changes is not None else None,
        motion=bool(doc.get("motion", False)),
    )


def _add_ons(doc: Mapping[str, Any], spec: ir.Spec, groups: Sequence[AxisGroup], err: Any) -> tuple[AddOnEntry, ...]:
    """``add_ons:``: each tag's instruction, operands (checked as a scenario's), preset and inputs."""
    from statecharts import addon

    charts = {a: spec.chart(grp.chart) for grp in groups for a in grp.axis_names()}
    tags = {t for grp in groups for a in grp.axis_names() for t in (f"{a}_{m}" for m in grp.program)}
    defs = {a.id: a for a in spec.add_ons}
    out: list[AddOnEntry] = []
    for i, e in enumerate(doc.get("add_ons", [])):
        p: tuple[Any, ...] = ("add_ons", i)
        ao = defs.get(e["instruction"])
        if ao is None:
            err((*p, "instruction"), f"unknown add-on instruction {e['instruction']!r}; the spec defines: "
                                     f"{', '.join(defs) or '(none)'}")
            continue
        if e["tag"] in tags or e["tag"] in charts:
            err((*p, "tag"), f"tag {e['tag']!r} is used twice (a tag, axis or device of the system has that name)")
        tags.add(e["tag"])
        ops = addon.check_operands(ao, e["operands"], charts, (*p, "operands"), err)
        for par in ao.parameters:
            if par.usage == "InOut" and par.name not in ops:
                err((*p, "operands"), f"{ao.id} needs its InOut parameter {par.name}")
        preset = addon.check_preset(ao, e.get("preset", {}), (*p, "preset"), err)
        inputs: list[tuple[str, tuple[object, ...]]] = []
        for name, values in e.get("inputs", {}).items():
            given = next((x for x in ao.parameters if x.name == name), None)
            if given is None or given.usage != "Input":
                err((*p, "inputs", name), f"{ao.id} has no input parameter {name!r}; inputs: "
                                          f"{', '.join(x.name for x in ao.parameters if x.usage == 'Input')}")
                continue
            checked = [addon.check_operands(ao, {name: v}, charts, (*p, "inputs", name, j), err)
                       for j, v in enumerate(values)]
            inputs.append((name, tuple(c[name] for c in checked if name in c)))
        out.append(AddOnEntry(e["tag"], ao.id, tuple(ops.items()), tuple(preset.items()), tuple(inputs)))
    return tuple(out)


def initial_assignments(sysdef: SystemDef) -> list[tuple[int, ...]]:
    """Every choice of one configuration per axis (index into its group's list).  In a system
    that counts its changes (``max_changes``), a configuration other than its group's first
    is a change made before the first scan: it spends one of them, so only the assignments
    with at most ``max_changes`` such configurations are starts."""
    per_axis = [range(len(g.configurations)) for _a, g in sysdef.axes()]
    out = [tuple(c) for c in itertools.product(*per_axis)]
    if sysdef.max_changes is not None:
        out = [a for a in out if sum(1 for c in a if c) <= sysdef.max_changes]
    return out


def operand_choices(sysdef: SystemDef, ins: ir.Instruction) -> list[dict[str, object]]:
    """Every assignment of the instruction's operands from their (finite) domains."""
    ops = [o for o in ins.operands if o.type not in ("axis", "tag")]
    domains: Sequence[tuple[object, ...]] = [sysdef.domain(ins, o) for o in ops]
    return [dict(zip((o.name for o in ops), values)) for values in itertools.product(*domains)]
