"""Program systems: a ladder program, its axes and its environment, checked with whole-controller properties.

Pipeline position: a program system file (``format: motionchart-program-system/1``) or
``motionchart check --program FILE`` -> **checker.program_check** ->
:mod:`checker.program_model` + :mod:`checker.program_search` -> the report, the
counterexamples as program scenarios (``motionchart simulate`` replays them) and the
per-scan tables of changed tags.

A system file::

    format: motionchart-program-system/1
    name: Fault recovery of three CIP axes from every start
    program: fault_recovery.L5X          # relative to this file; or {file:, routine:, program:}
    axes:
      X_axis: {type: AXIS_CIP_DRIVE, starts: [Running, Stopped, Faulted, Shutdown], events: [axis_fault]}
    tags: {STATE: 1, NEXTSTATE: 9}       # initial values, before the prescan
    inputs: {START_PB: BOOL, RECIPE: [1, 2, 3]}   # default: the BOOL tags the program reads and never writes
    max_events: 2                        # environment events per run
    max_scans: 200                       # optional: runs explored up to this many scans
    properties:
      - {name: recovers, kind: always_reachable, expr: "NEXTSTATE == 1"}
      - {name: fast, kind: leads_to, expr: "STATE == 9", goal: "NEXTSTATE == 1", within: 10}

A start is a preset name (``Running``, ``Stopped``, ``Faulted``, ``Shutdown`` of an
AXIS_CIP_DRIVE, :data:`statecharts.program.environment.CIP_STARTS`) or ``{state:, variables:}``;
every combination of the axes' starts is a start of the system.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from checker.program_model import AxisSetup, InputRule, ProgramModel, ProgramModelError, Start, State, compiled_leaf
from checker.program_search import (
    KINDS,
    Graph,
    ProgramProperty,
    Verdict,
    check,
    compile_predicate,
    explore,
    names_of,
    parse_property_text,
)
from statecharts import ir as spec_ir
from statecharts.diagnostics import Diagnostic, InputError, locate
from statecharts.program.environment import CIP_STARTS
from statecharts.program.ir import AXIS_UNTYPED, Program
from statecharts.scenario import value_problem

FORMAT = "motionchart-program-system/1"
EXIT_OK, EXIT_VIOLATED, EXIT_USAGE, EXIT_INCOMPLETE = 0, 1, 2, 3
_TOP_KEYS = ("format", "name", "description", "program", "axes", "tags", "inputs", "max_events", "max_scans",
             "scan_ms", "domains", "properties", "sources", "prescan", "unreached")
_AXIS_KEYS = ("type", "starts", "events", "set")
_INPUT_KEYS = ("values", "while", "counted")
_PROP_KEYS = ("name", "kind", "expr", "goal", "within", "final", "description", "source", "interpretation")


@dataclass
class AxisEntry:
    name: str
    type: str
    starts: list[tuple[str, AxisSetup]]
    events: list[str] = field(default_factory=list)
    #: writable chart variables the environment may set, with their values
    sets: dict[str, list[Any]] = field(default_factory=dict)


@dataclass
class ProgramSystem:
    name: str
    file: str
    program: Program
    program_file: Path
    axes: list[AxisEntry]
    tags: list[tuple[str, Any]]
    inputs: list[str]
    int_inputs: dict[str, list[int]]
    max_events: int = 0
    max_scans: int | None = None
    scan_ms: int = 10
    properties: list[ProgramProperty] = field(default_factory=list)
    #: declared integer domains: tag path -> (least, greatest)
    domains: dict[str, tuple[int, int]] = field(default_factory=dict)
    #: inputs that change only while a condition holds, or whose changes are counted
    input_rules: dict[str, InputRule] = field(default_factory=dict)
    #: a run may pass a prescan at any scan (Program mode and back to Run)
    prescan: bool = False
    #: coverage items left unreached on purpose ("X_MSO 13", "X_axis Faulted") -> why
    unreached: dict[str, str] = field(default_factory=dict)

    def starts(self) -> list[Start]:
        out = []
        for combo in itertools.product(*(a.starts for a in self.axes)):
            label = ", ".join(f"{a.name}={lab}" for a, (lab, _s) in zip(self.axes, combo))
            out.append(Start(label, tuple(s for _lab, s in combo), tuple(self.tags)))
        return out

    def model(self, spec: spec_ir.Spec, *, coverage: bool = True) -> ProgramModel:
        return ProgramModel(spec, self.program, axis_types={a.name: a.type for a in self.axes},
                            inputs=self.inputs, int_inputs=self.int_inputs,
                            events={a.name: a.events for a in self.axes if a.events}, max_events=self.max_events,
                            scan_ms=self.scan_ms, coverage=coverage,
                            sets={a.name: a.sets for a in self.axes if a.sets}, input_rules=self.input_rules,
                            prescan=self.prescan)


def bundled_program_systems() -> dict[str, Path]:
    """The program systems shipped with the examples (``examples/programs/*.check.yaml``), by name."""
    root = Path(__file__).resolve().parents[1] / "examples" / "programs"
    return {p.name.removesuffix(".check.yaml"): p for p in sorted(root.glob("*.check.yaml"))}


def is_program_system(path: Path) -> bool:
    """True when ``path`` is a YAML file whose ``format`` is the program-system format."""
    try:
        head = path.read_text(encoding="utf-8", errors="replace")[:4000]
    except OSError:
        return False
    return any(line.strip().startswith("format:") and FORMAT in line for line in head.splitlines())


def _start(axis_type: str, value: Any, err: Any, parts: tuple[Any, ...], axis: str) -> tuple[str, AxisSetup] | None:
    if isinstance(value, str):
        if axis_type == "AXIS_CIP_DRIVE" and value in CIP_STARTS:
            preset = CIP_STARTS[value]
            return value, AxisSetup(axis, axis_type, preset["state"], tuple(preset["variables"].items()))
        return value, AxisSetup(axis, axis_type, value, ())
    if isinstance(value, Mapping) and isinstance(value.get("state"), str):
        variables = value.get("variables", {}) or {}
        if not isinstance(variables, Mapping):
            err((*parts, "variables"), "variables: a mapping of chart variables to values")
            return None
        unknown = set(value) - {"state", "variables", "label"}
        if unknown:
            err(parts, f"unknown key(s) {', '.join(sorted(map(str, unknown)))}; a start has state, variables, label")
            return None
        label = str(value.get("label") or value["state"])
        return label, AxisSetup(axis, axis_type, value["state"], tuple((str(k), v) for k, v in variables.items()))
    err(parts, "a start is a preset name (Running, Stopped, Faulted, Shutdown) or {state:, variables:}")
    return None


def load_program_system(path: Path, spec: spec_ir.Spec) -> ProgramSystem:
    """Read and check a program system file; an :class:`InputError` lists every problem with its line."""
    from statecharts.inputs import shown_name
    from statecharts.loader import plain_data, read_yaml
    from statecharts.program.environment import free_inputs
    from statecharts.program.reader import load_program

    errors: list[Diagnostic] = []
    name = shown_name(path)
    tree = read_yaml(path, errors, what="program system")
    if tree is None or errors:
        raise InputError(errors or [Diagnostic(name, 1, 1, "", "empty program system file")])

    def err(parts: tuple[Any, ...], message: str, key: bool = False) -> None:
        line, col = locate(tree, parts, key=key)
        errors.append(Diagnostic(name, line, col, ".".join(str(p) for p in parts), message))

    doc = plain_data(tree)
    if not isinstance(doc, Mapping):
        raise InputError([Diagnostic(name, 1, 1, "", "a program system is a mapping (format:, program:, axes:, ...)")])
    for k in doc:
        if k not in _TOP_KEYS:
            err((k,), f"unknown key {k!r}; expected one of: {', '.join(_TOP_KEYS)}", key=True)
    if doc.get("format") != FORMAT:
        err(("format",), f"format must be {FORMAT}")
    ref = doc.get("program")
    entry = {"file": ref} if isinstance(ref, str) else dict(ref) if isinstance(ref, Mapping) else None
    if entry is None or not isinstance(entry.get("file"), str):
        err(("program",), "program: the program file (relative to this file) or {file:, routine:, program:}")
        raise InputError(errors)
    pfile = Path(entry["file"])
    pfile = pfile if pfile.is_absolute() else path.parent / pfile
    program = load_program(pfile, spec=spec, routine=entry.get("routine"), program=entry.get("program"))
    axes_doc = doc.get("axes") or {}
    if not isinstance(axes_doc, Mapping):
        err(("axes",), "axes: a mapping from the program's axis tags to {type:, starts:, events:}")
        axes_doc = {}
    axes: list[AxisEntry] = []
    for tag in program.axes():
        a = axes_doc.get(tag.name)
        if a is None:
            a = {}
        if not isinstance(a, Mapping):
            err(("axes", tag.name), "an axis is {type:, starts:, events:}")
            continue
        for k in a:
            if k not in _AXIS_KEYS:
                err(("axes", tag.name, k), f"unknown key {k!r}; expected one of: {', '.join(_AXIS_KEYS)}", key=True)
        axis_type = a.get("type") or (tag.data_type if tag.data_type != AXIS_UNTYPED else None)
        if not isinstance(axis_type, str):
            err(("axes", tag.name), f"axis {tag.name}: give its type (a rung file does not declare it)")
            continue
        try:
            chart = spec.chart_for_axis_type(axis_type)
        except KeyError:
            err(("axes", tag.name, "type"), f"no chart models axis type {axis_type!r}")
            continue
        starts_doc = a.get("starts")
        starts: list[tuple[str, AxisSetup]] = []
        if starts_doc is None:
            starts = [("initial", AxisSetup(tag.name, axis_type, None, ()))]
        elif not isinstance(starts_doc, list) or not starts_doc:
            err(("axes", tag.name, "starts"), "starts: a non-empty list of start states")
        else:
            states = {s.id for s in chart.states}
            for n, sd in enumerate(starts_doc):
                got = _start(axis_type, sd, err, ("axes", tag.name, "starts", n), tag.name)
                if got is None:
                    continue
                if got[1].state not in states:
                    err(("axes", tag.name, "starts", n), f"{got[1].state!r} is not a state of {chart.id}")
                    continue
                starts.append(got)
        events = a.get("events") or []
        if not isinstance(events, list) or not all(isinstance(e, str) for e in events):
            err(("axes", tag.name, "events"), "events: a list of environment event names")
            events = []
        sets: dict[str, list[Any]] = {}
        sdoc = a.get("set") or {}
        if not isinstance(sdoc, Mapping):
            err(("axes", tag.name, "set"), "set: a mapping from writable chart variables to lists of values")
            sdoc = {}
        writable = {v.name: v for v in chart.variables if v.writable}
        for var, vals in sdoc.items():
            if var not in writable:
                err(("axes", tag.name, "set", var), f"{var!r} is not a writable variable of {chart.id}; writable: "
                                                    f"{', '.join(writable) or '(none)'}", key=True)
                continue
            if not isinstance(vals, list) or not vals:
                err(("axes", tag.name, "set", var), f"{var}: a non-empty list of values")
                continue
            for n, value in enumerate(vals):
                problem = value_problem(writable[var].type, writable[var].domain, value)
                if problem:
                    err(("axes", tag.name, "set", var, n), f"{var}: {problem}")
            sets[str(var)] = list(vals)
        axes.append(AxisEntry(tag.name, axis_type, starts, list(events), sets))
    for k in axes_doc:
        if k not in {t.name for t in program.axes()}:
            err(("axes", k), f"{k} is not an axis of the program; its axes: "
                             f"{', '.join(t.name for t in program.axes()) or '(none)'}", key=True)
    tags_doc = doc.get("tags") or {}
    if not isinstance(tags_doc, Mapping):
        err(("tags",), "tags: a mapping from tag paths to initial values")
        tags_doc = {}
    inputs: list[str] = []
    int_inputs: dict[str, list[int]] = {}
    input_rules: dict[str, InputRule] = {}
    if "inputs" in doc:
        idoc = doc.get("inputs") or {}
        if not isinstance(idoc, Mapping):
            err(("inputs",), "inputs: a mapping from tag names to BOOL or a list of integer values")
            idoc = {}
        for k, v in idoc.items():
            if isinstance(v, Mapping):
                for key in v:
                    if key not in _INPUT_KEYS:
                        err(("inputs", k, key), f"unknown key {key!r}; expected one of: {', '.join(_INPUT_KEYS)}",
                            key=True)
                guard, counted = v.get("while", ""), v.get("counted", False)
                if not isinstance(guard, str):
                    err(("inputs", k, "while"), "while: an expression over the state before the scan")
                    guard = ""
                if not isinstance(counted, bool):
                    err(("inputs", k, "counted"), "counted: true or false")
                    counted = False
                input_rules[str(k)] = InputRule(guard, counted)
                v = v.get("values", "BOOL")
            if v == "BOOL":
                inputs.append(str(k))
            elif isinstance(v, list) and v and all(isinstance(x, int) and not isinstance(x, bool) for x in v):
                int_inputs[str(k)] = list(v)
            else:
                err(("inputs", k), "an input is BOOL, a non-empty list of integer values, or {values:, while:, counted:}")
    else:
        inputs = list(free_inputs(program))

    def count(key: str, default: int | None) -> int | None:
        v = doc.get(key, default)
        if v is None:
            return None
        if not isinstance(v, int) or isinstance(v, bool) or v < 0:
            err((key,), f"{key}: a whole number of at least 0")
            return default
        return v
    props = []
    pdoc = doc.get("properties") or []
    if not isinstance(pdoc, list):
        err(("properties",), "properties: a list of {name:, kind:, expr:, ...}")
        pdoc = []
    for n, pd in enumerate(pdoc):
        if not isinstance(pd, Mapping):
            err(("properties", n), "a property is {name:, kind:, expr:, ...}")
            continue
        for k in pd:
            if k not in _PROP_KEYS:
                err(("properties", n, k), f"unknown key {k!r}; expected one of: {', '.join(_PROP_KEYS)}", key=True)
        kind = pd.get("kind")
        if kind not in KINDS:
            err(("properties", n, "kind"), f"kind: one of {', '.join(KINDS)}")
            continue
        line, _col = locate(tree, ("properties", n))
        within = pd.get("within")
        if within is not None and (not isinstance(within, int) or isinstance(within, bool) or within < 0):
            err(("properties", n, "within"), "within: a number of scans")
            within = None
        needs_expr = kind not in ("deadlock", "livelock")
        if needs_expr and not isinstance(pd.get("expr"), str):
            err(("properties", n, "expr"), f"a {kind} property needs expr: (an expression over tags and axes)")
            continue
        if kind == "leads_to" and not isinstance(pd.get("goal"), str):
            err(("properties", n, "goal"), "a leads_to property needs goal:")
            continue
        interp = pd.get("interpretation")
        if interp is not None and not (isinstance(interp, str) and re.fullmatch(r"INT-[0-9]{3}", interp)):
            err(("properties", n, "interpretation"), "interpretation: an interpretation id such as INT-021")
            interp = None
        if interp is not None:
            try:
                spec.interpretation(interp)
            except KeyError:
                err(("properties", n, "interpretation"), f"{interp} is not an interpretation of the spec")
        props.append(ProgramProperty(str(pd.get("name") or f"{kind} {n}"), kind, str(pd.get("expr") or ""),
                                     str(pd.get("goal") or ""), within, str(pd.get("final") or ""), name, line,
                                     str(pd.get("source") or ""), str(interp or ""),
                                     str(pd.get("description") or "")))
    domains: dict[str, tuple[int, int]] = {}
    ddoc = doc.get("domains") or {}
    if not isinstance(ddoc, Mapping):
        err(("domains",), "domains: a mapping from integer tag paths to [least, greatest]")
        ddoc = {}
    for k, v in ddoc.items():
        if (isinstance(v, list) and len(v) == 2 and all(isinstance(x, int) and not isinstance(x, bool) for x in v)
                and v[0] <= v[1]):
            domains[str(k)] = (v[0], v[1])
        else:
            err(("domains", k), "a domain is [least, greatest], two integers")
    prescan = doc.get("prescan", False)
    if not isinstance(prescan, bool):
        err(("prescan",), "prescan: true (a run may pass a prescan at any scan) or false")
        prescan = False
    unreached: dict[str, str] = {}
    udoc = doc.get("unreached") or {}
    if not isinstance(udoc, Mapping) or not all(isinstance(v, str) and v for v in udoc.values()):
        err(("unreached",), "unreached: a mapping from coverage items ('X_MSO 13', 'X_axis Faulted') to the reason")
        udoc = {}
    for k, v in udoc.items():
        unreached[str(k)] = str(v)
    system = ProgramSystem(str(doc.get("name") or path.stem), name, program, pfile, axes,
                           [(str(k), v) for k, v in tags_doc.items()], inputs, int_inputs,
                           count("max_events", 0) or 0, count("max_scans", None), count("scan_ms", 10) or 10, props,
                           domains, input_rules, prescan, unreached)
    for k in input_rules:
        if k not in (*inputs, *int_inputs):
            err(("inputs", k), f"{k}: not a free input")
    items = {x for table in coverage_items(system, spec).values() for x in table}
    for k in unreached:
        if k not in items:
            err(("unreached", k), f"{k!r} is not a coverage item of this system (an instruction tag and one of its "
                                  f"error codes, 'X_MSO 13', or an axis and one of its states, 'X_axis Faulted')",
                key=True)
    if errors:
        raise InputError(errors)
    return system


def documented_codes(spec: spec_ir.Spec, mnemonic: str, chart: str) -> tuple[int, ...]:
    """The error codes the variant of ``mnemonic`` for ``chart`` can end with: its checks' and
    aborts' ERR values (an instruction without a variant for the chart only errs with the tag
    type's wrong-axis-family code, as :meth:`statecharts.scan.System.variant` runs it)."""
    try:
        ins = spec.instruction(mnemonic, chart)
    except KeyError:
        wrong = spec.tag_type.wrong_axis_family
        return (wrong.err,) if wrong is not None else ()
    return tuple(sorted({c.err for c in (*ins.checks, *ins.aborts)}))


def coverage_items(system: ProgramSystem, spec: spec_ir.Spec) -> dict[str, tuple[str, ...]]:
    """What coverage counts, by table: ``error_codes`` (``TAG CODE`` for every documented error code
    of every motion instruction of the program) and ``states`` (``AXIS STATE`` for every leaf state
    of every axis chart)."""
    from statecharts.program.ladder import motion_bindings
    charts = {a.name: spec.chart_for_axis_type(a.type) for a in system.axes}
    codes = [f"{b.tag} {c}" for b in motion_bindings(system.program, []) if b.axis in charts
             for c in documented_codes(spec, b.mnemonic, charts[b.axis].id)]
    states = [f"{a} {st.id}" for a, chart in charts.items() for st in chart.states if not st.children
              and st.kind in (spec_ir.StateKind.ATOMIC, spec_ir.StateKind.FINAL)]
    return {"error_codes": tuple(codes), "states": tuple(states)}


def system_for_program(path: Path, spec: spec_ir.Spec) -> ProgramSystem:
    """The default system of ``--program FILE``: declared axis types (AXIS_CIP_DRIVE for a rung file),
    an AXIS_CIP_DRIVE axis starting in each preset, the free BOOL inputs, no environment event."""
    from statecharts.inputs import shown_name
    from statecharts.program.environment import free_inputs
    from statecharts.program.reader import load_program
    program = load_program(path, spec=spec)
    axes = []
    for tag in program.axes():
        t = tag.data_type if tag.data_type != AXIS_UNTYPED else "AXIS_CIP_DRIVE"
        if t == "AXIS_CIP_DRIVE":
            starts = [(n, AxisSetup(tag.name, t, p["state"], tuple(p["variables"].items()))) for n, p in CIP_STARTS.items()]
        else:
            starts = [("initial", AxisSetup(tag.name, t, None, ()))]
        axes.append(AxisEntry(tag.name, t, starts))
    return ProgramSystem(path.stem, shown_name(path), program, path, axes, [], list(free_inputs(program)), {})


# --------------------------------------------------------------------------- a run, as the engine replays it


def replay(model: ProgramModel, graph: Graph, path: Sequence[int]) -> list[tuple[dict[str, Any], list[str]]]:
    """Run ``path`` (state numbers from a start) in the engine; per scan (the set-up first) the
    observable values and what the program's motion instructions did (rung-level notes).

    Raises AssertionError when the engine's state differs from the checker's (it never should)."""
    start = graph.starts[graph.start_of[path[0]]]
    c = model.engine(start)
    rows: list[tuple[dict[str, Any], list[str]]] = [(_observe(c), [])]
    prev = rows[0][0]
    for u in path[1:]:
        ch = model.choice(graph.via[u])
        events = (ch.event,) if ch.event else ()
        if ch.prescan:
            c.prescan()
        else:
            if ch.set is not None:
                c.system.axes[ch.set[0]].env[ch.set[1]] = ch.set[2]
            c.scan(events=events, **dict(ch.writes))
        now = _observe(c)
        notes = []
        for b in model.bindings:
            er, err_, exerr = (f"{b.tag}.ER", f"{b.tag}.ERR", f"{b.tag}.EXERR")
            if now.get(er) and (not prev.get(er) or now.get(err_) != prev.get(err_)):
                notes.append(f"rung {b.rung}: {b.mnemonic}({b.axis},{b.tag}) erred: ERR {now[err_]}, EXERR {now[exerr]}")
            if now.get(f"{b.tag}.DN") and not prev.get(f"{b.tag}.DN"):
                notes.append(f"rung {b.rung}: {b.mnemonic}({b.axis},{b.tag}) done")
        if ch.event:
            notes.append(f"event {ch.event[1]} on {ch.event[0]}")
        if ch.set is not None:
            notes.append(f"{ch.set[0]}.{ch.set[1]} set to {ch.set[2]!r} before the scan")
        if ch.prescan:
            notes.append("a prescan pass (Program mode and back to Run)")
        mine = model.encode(c.system)[1:]
        want = graph.states[u][1:]
        if mine != want:
            raise AssertionError(f"the engine's scan differs from the checker's at state {u}")
        rows.append((now, notes))
        prev = now
    return rows


def _observe(c: Any) -> dict[str, Any]:
    """What a counterexample table shows: program tags, motion tag members, each axis's state."""
    obs = c.observe()
    axes = set(c.system.axes)
    motion = set(c.system.tags)
    program: dict[str, Any] = {}
    members: dict[str, Any] = {}
    states: dict[str, Any] = {}
    for obj, fields in obs.items():
        if obj in axes:
            states[f"{obj}.state"] = fields["state"]
            continue
        for f, v in fields.items():
            if f == "FLAGS":
                continue
            key = obj if f == "" else (obj + f if str(f).startswith("[") else f"{obj}.{f}")
            (members if obj in motion else program)[key] = v
    return {**program, **members, **states}


def table(model: ProgramModel, graph: Graph, path: Sequence[int]) -> str:
    rows = replay(model, graph, path)
    lines = [f"{'scan':>5}  changes"]
    prev: dict[str, Any] = {}
    for n, (obs, notes) in enumerate(rows):
        changed = [f"{k}={_fmt(v)}" for k, v in obs.items() if prev.get(k) != v]
        if n == 0:
            changed = ["(start: " + graph.starts[graph.start_of[path[0]]].label + ")"]
        else:
            ch = model.choice(graph.via[path[n]])
            ins = [f"{k}={_fmt(v)}" for k, v in ch.writes if prev.get(k) != v]
            changed = ins + [c for c in changed if c.split("=")[0] not in dict(ch.writes)]
        text = "  ".join(changed) or "-"
        lines.append(f"{n:>5}  {text}")
        for note in notes:
            lines.append(f"{'':>5}    ^ {note}")
        prev = obs
    return "\n".join(lines) + "\n"


def _fmt(v: Any) -> str:
    if isinstance(v, bool):
        return "1" if v else "0"
    return str(v)


# --------------------------------------------------------------------------- counterexamples as scenarios


def scenario_document(model: ProgramModel, system: ProgramSystem, graph: Graph, verdict: Verdict,
                      directory: Path) -> dict[str, Any]:
    """The path of ``verdict`` (and its trap or cycle) as a program scenario that ``motionchart
    simulate`` replays: each scan one step with its input writes and events; the last step of
    the path expects the values the property reads; a trap adds quiet scans whose ``always``
    holds what stays the same in it."""
    path = verdict.path
    start = graph.starts[graph.start_of[path[0]]]
    prog = os.path.relpath(system.program_file.resolve(), directory.resolve())
    axes = {a.name: {"type": a.type, **({"state": a.state} if a.state else {}),
                     **({"variables": dict(a.variables)} if a.variables else {})} for a in start.axes}
    doc: dict[str, Any] = {
        "format": "motionchart-scenario/1",
        "name": f"{system.name}: {verdict.prop.name} ({verdict.prop.kind}) {'witness' if verdict.witness else 'violated'}",
        "description": f"{verdict.message}. Start: {start.label}.",
        "sources": [f"MC {system.file} (motionchart check)"],
        "setup": {"program": prog, "axes": axes, **({"tags": dict(start.tags)} if start.tags else {})},
        "steps": [],
    }
    steps: list[dict[str, Any]] = doc["steps"]
    names = sorted({n for t in verdict.prop.texts() for n in names_of(t)})
    s0 = graph.states[path[0]]
    current: dict[str, Any] = {}
    for k in (*model.inputs, *model.int_inputs):
        getter = model.getter(k)
        if not isinstance(getter, str):
            current[k] = getter(s0)
    full = [*path, *verdict.loop]
    for n, u in enumerate(full[1:], start=1):
        ch = model.choice(graph.via[u]) if n < len(path) else _choice_between(model, graph, full[n - 1], u)
        step: dict[str, Any] = {"name": f"scan {n}" + (" (in the cycle)" if n >= len(path) else "")}
        writes = {k: v for k, v in ch.writes if current.get(k) != v}
        current.update(dict(ch.writes))
        if writes:
            step["tags"] = writes
        if ch.event:
            step["events"] = [{"axis": ch.event[0], "event": ch.event[1]}]
        if ch.set is not None:
            step["set"] = {ch.set[0]: {ch.set[1]: ch.set[2]}}
        if ch.prescan:
            step["name"] = f"prescan {n}" + (" (in the cycle)" if n >= len(path) else "")
            step["prescan"] = True
        steps.append(step)
    last = path[-1]
    if steps and len(path) > 1:
        steps[len(path) - 2]["expect"] = _expect(model, graph.states[last], names)
    if verdict.trap and len(verdict.trap) >= 1:
        trap_states = [graph.states[u] for u in verdict.trap]
        shown = [*names, *(f"{a}.state" for a in model.axis_names),
                 *(f"{b.tag}.{m}" for b in model.bindings for m in ("DN", "ER"))]
        constant = [n for n in dict.fromkeys(shown) if len({_value(model, s, n) for s in trap_states}) == 1]
        if constant:
            steps.append({"name": "the trap: the controller stays here whatever the environment does",
                          "scans": 20, "always": _expect(model, trap_states[0], constant)})
    if not steps:
        steps.append({"name": "the start already shows it", "scans": 1})
    return doc


def _choice_between(model: ProgramModel, graph: Graph, u: int, v: int) -> Any:
    from checker.program_search import successor_function
    s = graph.states[u]
    for ch, t in successor_function(model)(s)[0]:
        if graph.index.get(t) == v:
            return model.choice(ch)
    raise AssertionError("no choice leads from u to v")


def _value(model: ProgramModel, s: State, name: str) -> Any:
    g = model.getter(name)
    return None if isinstance(g, str) else g(s)


def _expect(model: ProgramModel, s: State, names: Sequence[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for n in names:
        g = model.getter(n)
        if isinstance(g, str):
            continue
        head, _, member = n.rpartition(".")
        v = g(s)
        if head in model.axis_index:
            out.setdefault(head, {})[member] = v
        else:
            out[n] = v
    return out


def write_scenario(doc: Mapping[str, Any], path: Path) -> None:
    from ruamel.yaml import YAML
    yaml = YAML()
    yaml.default_flow_style = None
    yaml.width = 120
    with path.open("w", encoding="utf-8") as fh:
        yaml.dump(json.loads(json.dumps(doc)), fh)


# --------------------------------------------------------------------------- the report


@dataclass
class ProgramReport:
    system: ProgramSystem
    model: ProgramModel
    graph: Graph
    verdicts: list[Verdict]
    written: dict[str, Path] = field(default_factory=dict)

    @property
    def exit_code(self) -> int:
        if any(v.holds is False and v.prop.kind != "reachable" for v in self.verdicts):
            return EXIT_VIOLATED
        if any(v.holds is False for v in self.verdicts):
            return EXIT_VIOLATED
        if any(v.holds is None for v in self.verdicts) or not self.graph.complete:
            return EXIT_INCOMPLETE
        return EXIT_OK

    def coverage(self) -> dict[str, Any]:
        m, cov = self.model, self.model.cov
        routine = m.program.routine(m.program.main)
        never_true = [r.number for r in routine.rungs if not (cov.rungs_true >> r.number) & 1]
        never_exec = [f"rung {rung}: {ins.mnemonic} (instruction {ins.position})"
                      for k, (rung, ins) in enumerate(m.instructions) if not (cov.executed >> k) & 1]
        errors = sorted({(m.bindings[k].tag, m.bindings[k].mnemonic, m.bindings[k].rung, err, exerr, check)
                         for k, err, exerr, check in cov.errors})
        return {
            "rungs_never_true": never_true,
            "instructions_never_executed": never_exec,
            "motion_errors": [{"tag": t, "instruction": mn, "rung": r, "ERR": e, "EXERR": x, "check": c}
                              for t, mn, r, e, x, c in errors],
            "motion_never_done": [b.tag for k, b in enumerate(m.bindings) if k not in cov.done],
            "domains": self.domains(),
            **self.tables(),
        }

    def tables(self) -> dict[str, dict[str, Any]]:
        """Coverage by table: the documented error codes of every motion instruction (reached when some
        explored scan ended the instruction with that ERR) and the leaf states of every axis (reached
        when some explored state has the axis there); each unreached item with the system's reason, if
        it gives one (``unreached:``)."""
        m, g = self.model, self.graph
        items = coverage_items(self.system, m.spec)
        reached_codes = {f"{m.bindings[k].tag} {err}" for k, err, _x, _c in m.cov.errors}
        reached_states: set[str] = set()
        for i, a in enumerate(m.axis_names):
            leaf = compiled_leaf(m.charts[i])
            pos = m.core_pos[i]
            for c in {s[pos] for s in g.states}:
                reached_states.add(f"{a} {leaf(m.cores[i].values[c][0])}")
        out: dict[str, dict[str, Any]] = {}
        for key, reached in (("error_codes", reached_codes), ("states", reached_states)):
            got = [x for x in items[key] if x in reached]
            missed = [x for x in items[key] if x not in reached]
            out[key] = {"reached": got, "unreached": missed,
                          "explained": {x: self.system.unreached[x] for x in missed if x in self.system.unreached}}
        return out

    def domains(self) -> list[str]:
        from checker.program_model import static_domains
        start = dict(self.system.tags)
        inputs = {*self.model.inputs, *self.model.int_inputs}
        out = []
        for d in static_domains(self.model, start):
            if d.path in inputs:
                continue
            if d.path in self.system.domains:
                lo, hi = self.system.domains[d.path]
                out.append(f"{d.path}: declared {lo}..{hi}" + ("" if d.values is not None else f" ({d.why})"))
            elif d.values is None:
                out.append(f"{d.text()}: declare it (domains:) or bound the search (max_scans)")
            else:
                out.append(d.text())
        return out

    def as_dict(self) -> dict[str, Any]:
        g = self.graph
        return {
            "system": self.system.name, "file": self.system.file, "states": len(g.states),
            "transitions": g.transitions, "seconds": round(g.seconds, 3), "cpu_seconds": round(g.cpu_seconds, 3),
            "complete": g.complete,
            "starts": len(g.starts),
            "properties": [{"name": v.prop.name, "kind": v.prop.kind,
                            "holds": v.holds, "message": v.message,
                            "path_scans": max(0, len(v.path) - 1),
                            "hanging_starts": [g.starts[i].label for i in v.hanging_starts],
                            "trap_states": len(v.trap),
                            "counterexample": str(self.written[v.prop.name]) if v.prop.name in self.written else None}
                           for v in self.verdicts],
            "coverage": self.coverage(),
            "exit_code": self.exit_code,
        }

    def text(self) -> str:
        g, m = self.graph, self.model
        rate = len(g.states) / g.cpu_seconds if g.cpu_seconds > 0 else 0.0
        lines = [f"program system: {self.system.name}  ({self.system.file})",
                 f"program: {m.program.name} ({self.system.program_file.name}), {m.rung_count} rungs, "
                 f"{len(m.axis_names)} axes, {len(m.inputs) + len(m.int_inputs)} free input(s), "
                 f"{len(m.events)} environment event(s) (at most {m.max_events} per run)",
                 f"explored: {len(g.states)} states, {g.transitions} transitions from {len(g.starts)} start(s) in "
                 f"{g.seconds:.2f} s ({g.cpu_seconds:.2f} CPU s, {rate:,.0f} states per CPU-second)"
                 + ("" if g.complete else f"; {g.stopped}"),
                 ""]
        for v in self.verdicts:
            mark = {True: "HOLDS", False: "VIOLATED", None: "UNKNOWN"}[v.holds]
            if v.prop.kind == "reachable" and v.holds:
                mark = "REACHED"
            lines.append(f"{mark:9} {v.prop.name} ({v.prop.kind}): {v.message}")
            if v.hanging_starts and v.holds is False:
                labels = [g.starts[i].label for i in v.hanging_starts]
                lines.append(f"          from {len(labels)} of {len(g.starts)} start(s): "
                             + "; ".join(labels[:8]) + (" ..." if len(labels) > 8 else ""))
                safe = len(g.starts) - len(set(labels))
                lines.append(f"          ({safe} start(s) never lead there)")
            if v.path and (v.holds is False or v.witness):
                lines.append("          counterexample:" if not v.witness else "          witness:")
                try:
                    body = table(m, g, v.path)
                except AssertionError as exc:
                    body = f"(the engine does not replay it: {exc})\n"
                lines.extend("          " + ln for ln in body.rstrip("\n").splitlines())
                if v.loop:
                    lines.append(f"          then {len(v.loop)} scan(s) of a cycle it repeats for ever")
                if v.trap:
                    lines.append(f"          trap: {len(v.trap)} state(s) the controller cannot leave")
                    lines.extend("            " + ln for ln in _trap_summary(m, g, v.trap))
                if v.prop.name in self.written:
                    lines.append(f"          scenario: {self.written[v.prop.name]}")
        cov = self.coverage()
        lines.append("")
        lines.append("coverage of the program:")
        lines.append(f"  rungs never true: {', '.join(map(str, cov['rungs_never_true'])) or 'none'}")
        lines.append(f"  instructions never executed: {'; '.join(cov['instructions_never_executed']) or 'none'}")
        errs = cov["motion_errors"]
        lines.append("  motion instruction errors reachable: " + (
            "; ".join(f"{e['instruction']} {e['tag']} (rung {e['rung']}) ERR {e['ERR']}/EXERR {e['EXERR']} "
                      f"({e['check']})" for e in errs) or "none"))
        lines.append(f"  motion instructions never done: {', '.join(cov['motion_never_done']) or 'none'}")
        mnemonic = {b.tag: b.mnemonic for b in m.bindings}
        for key, what in (("error_codes", "error codes"), ("states", "states")):
            t = cov[key]
            owners: dict[str, tuple[list[str], list[str]]] = {}
            for x in t["reached"]:
                owners.setdefault(x.rsplit(" ", 1)[0], ([], []))[0].append(x.rsplit(" ", 1)[1])
            for x in t["unreached"]:
                owner, item = x.rsplit(" ", 1)
                owners.setdefault(owner, ([], []))[1].append(item + (" (explained)" if x in t["explained"] else ""))
            for owner, (got, missed) in owners.items():
                label = f"{owner} ({mnemonic[owner]})" if owner in mnemonic else owner
                line = f"  {what} of {label}: {len(got)}/{len(got) + len(missed)} reached"
                if missed:
                    line += "; unreached: " + ", ".join(missed)
                lines.append(line)
        lines.append("integer domains (computed from the program" + (", declared" if self.system.domains else "") + "):")
        for d in cov["domains"]:
            lines.append(f"  {d}")
        return "\n".join(lines) + "\n"


def _trap_summary(model: ProgramModel, graph: Graph, trap: Sequence[int]) -> list[str]:
    values = [model.describe(graph.states[u]) for u in trap]

    def fixed(k: str) -> bool:
        return len({repr(v[k]) for v in values}) == 1
    first = values[0]
    axes = [f"{a}={first[f'{a}.state']}" for a in model.axis_names if fixed(f"{a}.state")]
    tags = [f"{model.slot_names[s]}={_fmt(first[model.slot_names[s]])}" for s in model.slots
            if s not in model.input_slots and fixed(model.slot_names[s])]
    motion = []
    for b in model.bindings:
        er, dn = f"{b.tag}.ER", f"{b.tag}.DN"
        if fixed(er) and first[er]:
            motion.append(f"{b.tag} ({b.mnemonic}, rung {b.rung}) erred {first[b.tag + '.ERR']}/{first[b.tag + '.EXERR']}")
        elif fixed(dn) and not first[dn]:
            motion.append(f"{b.tag} ({b.mnemonic}, rung {b.rung}) never done")
    out = ["axes: " + ("  ".join(axes) or "-"), "tags: " + ("  ".join(tags) or "-")]
    if motion:
        out.append("motion: " + "; ".join(motion))
    varying = [k for k in first if not fixed(k)]
    if varying:
        out.append("varies: " + ", ".join(varying))
    return out


def run_system(system: ProgramSystem, spec: spec_ir.Spec, *, extra: Sequence[ProgramProperty] = (),
               max_states: int | None = None, max_seconds: float | None = None,
               counterexamples: Path | None = None, progress: Any = None) -> ProgramReport:
    model = system.model(spec)
    props = [*system.properties, *extra]
    if not props:
        props = [ProgramProperty("deadlock", "deadlock"), ProgramProperty("livelock", "livelock")]
    domain_props = [ProgramProperty(f"domain of {k}", "invariant", f"{lo} <= {k} <= {hi}", file=system.file)
                    for k, (lo, hi) in system.domains.items()]
    props = [*domain_props, *props]
    predicates: dict[str, Any] = {}
    problems = []
    for p in props:
        for t in p.texts():
            pr = compile_predicate(model, t, p)
            if isinstance(pr, Diagnostic):
                problems.append(pr)
            else:
                predicates[t] = pr
    if problems:
        raise InputError(problems)
    graph = explore(model, system.starts(), max_states=max_states, max_scans=system.max_scans,
                    max_seconds=max_seconds, prune=[predicates[p.expr] for p in domain_props], progress=progress)
    verdicts = check(model, graph, props, predicates)
    report = ProgramReport(system, model, graph, verdicts)
    if counterexamples is not None:
        counterexamples.mkdir(parents=True, exist_ok=True)
        for v in verdicts:
            if v.path and (v.holds is False or v.witness):
                safe = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in v.prop.name)[:60]
                out = counterexamples / f"{safe}.yaml"
                write_scenario(scenario_document(model, system, graph, v, counterexamples), out)
                report.written[v.prop.name] = out
    return report


def run(args: argparse.Namespace, system_path: Path | None, out: TextIO) -> int:
    """``motionchart check`` on a program system (``--system FILE``) or a program (``--program FILE``)."""
    import sys

    from statecharts.loader import load_spec
    try:
        spec = load_spec(args.spec)
        if system_path is not None:
            system = load_program_system(system_path, spec)
        else:
            system = system_for_program(Path(args.program), spec)
        if getattr(args, "max_events", None) is not None:
            system.max_events = args.max_events
        if getattr(args, "max_scans", None) is not None:
            system.max_scans = args.max_scans
        extra = []
        for text in getattr(args, "property", None) or []:
            try:
                extra.append(parse_property_text(text))
            except ValueError as exc:
                print(f"motionchart check: --property: {exc}", file=sys.stderr)
                return EXIT_USAGE
        progress = None
        if not (args.quiet or args.json) and sys.stderr.isatty():
            def progress(found: int, expanded: int) -> None:
                print(f"\rexploring: {found:,} states found, {expanded:,} expanded", end="", file=sys.stderr,
                      flush=True)
        report = run_system(system, spec, extra=extra, max_states=args.max_states, max_seconds=args.max_seconds,
                            counterexamples=Path(args.counterexamples) if args.counterexamples else None,
                            progress=progress)
        if progress is not None:
            print("\r\033[K", end="", file=sys.stderr, flush=True)
    except (InputError, ProgramModelError) as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        return EXIT_VIOLATED
    if args.json:
        json.dump(report.as_dict(), out, indent=2, sort_keys=True, default=str)
        out.write("\n")
    else:
        out.write(report.text())
    return report.exit_code
