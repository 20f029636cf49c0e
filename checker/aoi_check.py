"""Exhaustive exploration of the add-on instruction raM_Opr_SyncPthPhyAx_CD.

Pipeline position: ``spec/systems/*.yaml`` of ``format: motionchart-aoi-system/1`` ->
**checker.aoi_check** (check the system, build a :class:`statecharts.aoi.World`, explore
it breadth-first, judge properties, measure coverage, write counterexamples as AOI
scenarios) -> :mod:`checker.check_cli` (``motionchart check --system aoi``).

The world (device handlers, the physical and path axes, the AOI instance) is the one the
AOI scenarios run: the same :func:`statecharts.aoi.build_world` and ``World.scan``.  A
state of the search is ``(World.snapshot(), rung)``; every move is one of

* ``scan``: one PLC scan with the rung unchanged;
* ``rung``: the rung changes, then one scan;
* ``prescan``: one prescan pass (program to run); the rung is false afterwards;
* ``set``: one field of a handler or an axis takes another value (``environment:``),
  then one scan with the rung unchanged;
* ``input``: one input of the instance takes another value (``inputs:``), then one
  scan.  Inputs change only while the rung is false: the configuration of one
  execution is fixed while it runs (docs/checker.md, "the add-on instruction").

Breadth-first order makes every counterexample a shortest one.  Properties are
invariants written as expressions over ``Object.field`` names (the observables of
:meth:`World.observe` and the instance's inputs); coverage counts the AOI's error codes,
its recovery states and the system's ``goals``.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from checker.search import progress_wanted
from statecharts.diagnostics import Diagnostic, InputError, locate, node_path
from statecharts.expr import EvalError, Expr, ExprError, check_names, parse_expression
from statecharts.loader import plain_data, read_yaml, schema_diagnostics

AOI_SYSTEM_FORMAT = "motionchart-aoi-system/1"


def schema_object(required: list[str], props: dict[str, Any]) -> dict[str, Any]:
    """A JSON Schema object with exactly ``props``, of which ``required`` must be present."""
    return {"type": "object", "additionalProperties": False, "required": list(required), "properties": dict(props)}
PROGRESS_EVERY = 2000

_SOURCE = {"type": "string", "minLength": 1}
_ID = {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_.]*$"}
_VALUES = {"type": "array", "minItems": 1, "items": {"type": ["boolean", "integer", "number", "string"]}}


AOI_SYSTEM_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/aoi-system-1.json",
    "description": "A world for exploring an add-on instruction: setup, the inputs and environment "
                   "fields the explorer may change, invariants, goals and explained gaps.",
    **schema_object(["format", "name", "source", "setup", "instance", "properties"], {
        "format": {"const": AOI_SYSTEM_FORMAT},
        "name": _ID,
        "description": {"type": "string"},
        "source": _SOURCE,
        "setup": {"type": "object"},
        "instance": _ID,
        "inputs": {"type": "object", "additionalProperties": _VALUES},
        "environment": {"type": "object", "additionalProperties": {"type": "object", "additionalProperties": _VALUES}},
        "properties": {"type": "array", "minItems": 1, "items": schema_object(["id", "always", "source"], {
            "id": _ID, "always": {"type": "string", "minLength": 1}, "description": {"type": "string"},
            "source": _SOURCE, "interpretation": {"type": "string", "pattern": "^INT-[0-9]{3}$"}})},
        "goals": {"type": "array", "items": schema_object(["id", "when", "source"], {
            "id": _ID, "when": {"type": "string", "minLength": 1}, "description": {"type": "string"},
            "source": _SOURCE})},
        "unreached": {"type": "object", "additionalProperties": {"type": "string", "minLength": 1}},
        "max_changes": {"type": "integer", "minimum": 0},
    }),
}


class AoiSystemError(InputError):
    """An AOI system file that cannot be explored; carries located diagnostics."""


@dataclass(frozen=True)
class Invariant:
    id: str
    text: str
    expr: Expr
    description: str
    source: str
    names: tuple[str, ...]


@dataclass(frozen=True)
class Goal:
    id: str
    text: str
    expr: Expr
    description: str
    source: str


@dataclass(frozen=True)
class AoiSystem:
    file: str
    name: str
    description: str
    source: str
    setup: Mapping[str, Any]
    instance: str
    inputs: tuple[tuple[str, tuple[object, ...]], ...]
    environment: tuple[tuple[str, str, tuple[object, ...]], ...]
    properties: tuple[Invariant, ...]
    goals: tuple[Goal, ...]
    unreached: Mapping[str, str]
    instance_inputs: frozenset[str] = frozenset()
    max_changes: int | None = None


def is_aoi_system(path: Path | str) -> bool:
    """True when the YAML file declares ``format: motionchart-aoi-system/1``."""
    errors: list[Diagnostic] = []
    tree = read_yaml(Path(path), errors)
    return isinstance(tree, Mapping) and tree.get("format") == AOI_SYSTEM_FORMAT


def bundled_aoi_systems() -> dict[str, Path]:
    """Bundled AOI system names (``spec/systems/aoi/*.yaml``) -> files."""
    from checker.system import systems_dir

    out: dict[str, Path] = {}
    for p in sorted((systems_dir() / "aoi").glob("*.yaml")):
        tree = read_yaml(p, [])
        name = str(tree.get("name", p.stem)) if isinstance(tree, Mapping) else p.stem
        out[name] = p
    return out


def load_aoi_system(path: Path | str, spec: Any) -> AoiSystem:
    """Read and check an AOI system file; raise :class:`AoiSystemError` with every problem."""
    from statecharts.aoi import SCENARIO_FORMAT, build_world, load_aoi_scenario
    from statecharts.diagnostics import ScenarioError

    f = str(path)
    errors: list[Diagnostic] = []
    tree = read_yaml(Path(path), errors)
    if tree is None or errors:
        raise AoiSystemError(errors or [Diagnostic(f, 1, 1, "", "empty file; expected an AOI system mapping")])
    errors.extend(schema_diagnostics(f, tree, AOI_SYSTEM_SCHEMA, "an add-on instruction system"))
    if errors:
        raise AoiSystemError(errors)

    def err(parts: tuple[Any, ...], message: str) -> None:
        line, col = locate(tree, parts)
        errors.append(Diagnostic(f, line, col, node_path(parts), message))

    # the setup is checked exactly as an AOI scenario's setup is
    probe = {"format": SCENARIO_FORMAT, "name": str(tree["name"]), "setup": tree["setup"], "steps": [{"name": "probe"}]}
    try:
        load_aoi_scenario(f, probe, spec)
    except ScenarioError as exc:
        for d in exc.diagnostics:
            errors.append(Diagnostic(f, *locate(tree, ("setup",)), d.path, d.message) if d.line == 1 else d)
        raise AoiSystemError(errors) from None
    doc = plain_data(tree)
    setup = doc["setup"]
    inst = doc["instance"]
    if inst not in setup.get("aoi", {}):
        err(("instance",), f"unknown instance {inst!r}; setup.aoi has: {', '.join(setup.get('aoi', {}))}")
        raise AoiSystemError(errors)
    try:
        world = build_world(spec, setup)
    except (TypeError, ValueError, KeyError) as exc:
        err(("setup",), f"the setup cannot be built: {exc}")
        raise AoiSystemError(errors) from None
    input_names = {n for n, _, _ in spec.inputs}
    inputs: list[tuple[str, tuple[object, ...]]] = []
    for k, values in doc.get("inputs", {}).items():
        if k not in input_names:
            err(("inputs", k), f"{spec.id} has no input {k!r}; inputs: {', '.join(sorted(input_names))}")
            continue
        inputs.append((k, tuple(values)))
    environment: list[tuple[str, str, tuple[object, ...]]] = []
    pristine = world.snapshot()
    for obj, fields in doc.get("environment", {}).items():
        if obj not in world.handlers and obj not in world.axes:
            err(("environment", obj), f"unknown handler or axis {obj!r}; setup has: "
                f"{', '.join(sorted([*world.handlers, *world.axes]))}")
            continue
        for k, values in fields.items():
            for i, v in enumerate(values):
                world.restore(pristine)
                try:
                    world.set(obj, k, v)
                except (AttributeError, KeyError, TypeError, ValueError) as exc:
                    err(("environment", obj, k, i), f"{obj}.{k} cannot be set to {v!r}: {exc}")
                    break
            environment.append((obj, k, tuple(values)))
    world.restore(pristine)
    env = observation_env(world, inst)
    known = frozenset(env)

    def compile_expr(parts: tuple[Any, ...], text: str) -> Expr | None:
        try:
            e = parse_expression(text)
        except ExprError as exc:
            err(parts, f"bad expression: {exc}")
            return None
        unknown = check_names(e, known)
        if unknown:
            err(parts, f"unknown name(s) {', '.join(n for n, _ in unknown)}; names look like "
                f"{inst}.Sts_ERR, {inst}.Cfg_SyncType, <handler>.eState, <axis>.position")
            return None
        return e

    props: list[Invariant] = []
    seen: set[str] = set()
    for i, p in enumerate(doc["properties"]):
        if p["id"] in seen:
            err(("properties", i, "id"), f"duplicate property id {p['id']!r}")
        seen.add(p["id"])
        e = compile_expr(("properties", i, "always"), p["always"])
        if e is not None:
            names = tuple(sorted({n for n, _ in check_names(e, frozenset())}))
            props.append(Invariant(p["id"], p["always"], e, p.get("description", ""), p["source"], names))
    goals: list[Goal] = []
    for i, g in enumerate(doc.get("goals", [])):
        e = compile_expr(("goals", i, "when"), g["when"])
        if e is not None:
            goals.append(Goal(g["id"], g["when"], e, g.get("description", ""), g["source"]))
    if errors:
        raise AoiSystemError(errors)
    return AoiSystem(f, doc["name"], doc.get("description", ""), doc["source"], setup, inst, tuple(inputs),
                     tuple(environment), tuple(props), tuple(goals), dict(doc.get("unreached", {})),
                     frozenset(input_names), doc.get("max_changes"))


def observation_env(world: Any, instance: str) -> dict[str, object]:
    """``Object.field`` -> value, from the world's observables and the instance's inputs."""
    env: dict[str, object] = {}
    for obj, fields in world.observe().items():
        for k, v in fields.items():
            env[f"{obj}.{k}"] = v
    for k, v in world.instances[instance].inputs.items():
        env[f"{instance}.{k}"] = v
    return env


# --------------------------------------------------------------------------- search


@dataclass(frozen=True, slots=True)
class Move:
    kind: str  # scan | rung | prescan | set | input
    target: str = ""
    field: str = ""
    value: object = None

    def label(self) -> str:
        if self.kind == "scan":
            return "scan"
        if self.kind == "rung":
            return f"rung {'true' if self.value else 'false'}"
        if self.kind == "prescan":
            return "prescan"
        return f"{self.target}.{self.field} = {self.value!r}"


@dataclass
class Verdict:
    prop: Invariant
    holds: bool | None
    state: int | None = None  # the violating state
    env: Mapping[str, object] | None = None
    scenario: Path | None = None


@dataclass
class AoiResult:
    system: AoiSystem
    states: int
    transitions: int
    depth: int
    seconds: float
    complete: bool
    stop_reason: str
    verdicts: list[Verdict]
    parents: list[int]
    moves: list[Move | None]
    rungs: list[bool]
    depths: list[int]
    reached_codes: dict[int, int] = field(default_factory=dict)  # code -> first state
    reached_states: dict[str, int] = field(default_factory=dict)
    reached_goals: dict[str, int] = field(default_factory=dict)
    codes: tuple[int, ...] = ()
    recovery_states: tuple[str, ...] = ()
    error_text: str = ""

    @property
    def exit_code(self) -> int:
        if self.error_text or any(v.holds is False for v in self.verdicts):
            return 1
        return 0 if self.complete else 3

    def path(self, i: int) -> list[Move]:
        out: list[Move] = []
        while self.parents[i] >= 0:
            m = self.moves[i]
            assert m is not None
            out.append(m)
            i = self.parents[i]
        return out[::-1]


def _moves(system: AoiSystem, rung: bool, budget: int | None) -> list[Move]:
    out = [Move("scan"), Move("rung", value=not rung), Move("prescan")]
    if budget == 0:
        return out
    for obj, fld, values in system.environment:
        out.extend(Move("set", obj, fld, v) for v in values)
    if not rung:
        out.extend(Move("input", system.instance, k, v) for k, values in system.inputs for v in values)
    return out


def _apply(world: Any, system: AoiSystem, move: Move, rung: bool) -> bool:
    """Apply one move and run its scan; return the rung afterwards."""
    if move.kind == "prescan":
        world.scan({system.instance: False}, prescan=True)
        return False
    if move.kind == "rung":
        rung = bool(move.value)
    elif move.kind == "set":
        world.set(move.target, move.field, move.value)
    elif move.kind == "input":
        world.instances[system.instance].inputs[move.field] = move.value
    world.scan({system.instance: rung})
    return rung


def explore_aoi(system: AoiSystem, spec: Any, *, max_states: int | None = None, max_seconds: float | None = None,
                progress: bool | None = None) -> AoiResult:
    """Breadth-first search of every reachable (world, rung) state of the system."""
    from statecharts.aoi import build_world

    show = progress_wanted() if progress is None else progress
    start = time.monotonic()
    world = build_world(spec, system.setup)
    rung0 = False
    snaps: list[Any] = [world.snapshot()]
    budgets: list[int | None] = [system.max_changes]
    index: dict[tuple[Any, bool, int | None], int] = {(snaps[0], rung0, system.max_changes): 0}
    moves: list[Move | None] = [None]
    rungs, parents, depths = [rung0], [-1], [0]
    verdicts = [Verdict(p, True) for p in system.properties]
    codes = tuple(sorted(code for code, _name in spec.errors))
    rstates = tuple(s.id for s in spec.add_on.recovery.states)
    result = AoiResult(system, 0, 0, 0, 0.0, True, "", verdicts, parents, moves, rungs, depths,
                       codes=codes, recovery_states=rstates)

    def judge(i: int) -> None:
        env = observation_env(world, system.instance)
        for v in verdicts:
            if v.holds is False:
                continue
            try:
                ok = bool(v.prop.expr(env))
            except EvalError as exc:
                result.error_text = f"property {v.prop.id} cannot be evaluated: {exc}"
                ok = True
            if not ok:
                v.holds, v.state, v.env = False, i, dict(env)
        err = env.get(f"{system.instance}.Sts_ERR")
        if isinstance(err, int) and err and err not in result.reached_codes:
            result.reached_codes[err] = i
        st = env.get(f"{system.instance}.state")
        if isinstance(st, str) and st not in result.reached_states:
            result.reached_states[st] = i
        for g in system.goals:
            if g.id not in result.reached_goals:
                try:
                    if g.expr(env):
                        result.reached_goals[g.id] = i
                except EvalError:
                    pass

    judge(0)
    transitions = 0
    i = 0
    while i < len(snaps):
        if max_states is not None and len(snaps) >= max_states:
            result.complete, result.stop_reason = False, f"state limit of {max_states:,} reached"
            break
        if max_seconds is not None and time.monotonic() - start > max_seconds:
            result.complete, result.stop_reason = False, f"time limit of {max_seconds:g} s reached"
            break
        if show and i % PROGRESS_EVERY == 0:
            print(f"\r  {len(snaps):,} states, depth {depths[i]}, queue {len(snaps) - i:,} ...", end="",
                  file=sys.stderr, flush=True)
        for move in _moves(system, rungs[i], budgets[i]):
            world.restore(snaps[i])
            try:
                rung = _apply(world, system, move, rungs[i])
            except (EvalError, ArithmeticError, TypeError, ValueError) as exc:
                result.error_text = (f"the world cannot take move {move.label()!r} after "
                                     f"{[m.label() for m in result.path(i)]}: {exc}")
                break
            transitions += 1
            budget = budgets[i]
            if budget is not None and move.kind in ("set", "input"):
                budget -= 1
            key = (world.snapshot(), rung, budget)
            if key in index:
                continue
            n = len(snaps)
            index[key] = n
            snaps.append(key[0])
            budgets.append(budget)
            rungs.append(rung)
            parents.append(i)
            moves.append(move)
            depths.append(depths[i] + 1)
            judge(n)
        if result.error_text:
            break
        i += 1
    if show:
        print("\r" + " " * 60 + "\r", end="", file=sys.stderr, flush=True)
    if not result.complete:
        for v in verdicts:
            if v.holds:
                v.holds = None
    result.states, result.transitions = len(snaps), transitions
    result.depth = max(depths)
    result.seconds = time.monotonic() - start
    return result


# --------------------------------------------------------------------------- output


def _y(value: object) -> str:
    """A YAML flow scalar (JSON is YAML, except for the non-finite floats)."""
    import json

    if isinstance(value, float) and not math.isfinite(value):
        return ".nan" if math.isnan(value) else (".inf" if value > 0 else "-.inf")
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_y(str(k))}: {_y(v)}" for k, v in value.items()) + "}"
    return json.dumps(value, ensure_ascii=False)


def scenario_text(result: AoiResult, verdict: Verdict) -> str:
    """The violating run as a ``motionchart-aoi-scenario/1`` file that replays it."""
    from statecharts.aoi import SCENARIO_FORMAT

    system = result.system
    assert verdict.state is not None and verdict.env is not None
    path = result.path(verdict.state)
    inst = system.instance
    lines = [
        f"# Counterexample found by `motionchart check --system {system.name}`.",
        "# Replay it with `motionchart simulate FILE`.",
        f"format: {SCENARIO_FORMAT}",
        f"name: {_y(f'violation: {verdict.prop.id} (system {system.name})')}",
        f"description: {_y(f'A shortest run ({len(path)} moves) that violates {verdict.prop.id}: {verdict.prop.text}')}",
        f"sources: [{_y(verdict.prop.source)}]",
        f"covers: [{_y('property.' + verdict.prop.id)}]",
        "setup:",
    ]
    setup = system.setup
    if "scan_ms" in setup:
        lines.append(f"  scan_ms: {setup['scan_ms']}")
    for part in ("handlers", "axes", "aoi"):
        lines.append(f"  {part}:")
        for name, entry in setup.get(part, {}).items():
            lines.append(f"    {name}: {_y(entry)}")
    lines.append("steps:")
    if not path:
        lines += ["  - name: the initial state already shows it", "    scans: 1"]
    rung = False
    for k, move in enumerate(path):
        lines.append(f"  - name: {_y(move.label())}")
        if move.kind == "prescan":
            lines.append("    prescan: true")
            rung = False
        else:
            if move.kind == "rung":
                rung = bool(move.value)
            elif move.kind == "set":
                lines.append(f"    set: {{{move.target}: {{{move.field}: {_y(move.value)}}}}}")
            elif move.kind == "input":
                lines.append(f"    operands: {{{inst}: {{{move.field}: {_y(move.value)}}}}}")
            lines.append(f"    rungs: {{{inst}: {_y(rung)}}}")
        if k == len(path) - 1:
            expect: dict[str, dict[str, object]] = {}
            for name in verdict.prop.names:
                obj, _, fld = name.partition(".")
                if obj == inst and fld in system.instance_inputs:
                    continue
                expect.setdefault(obj, {})[fld] = verdict.env[name]
            if expect:
                lines.append("    expect:")
                lines.extend(f"      {obj}: {_y(fields)}" for obj, fields in expect.items())
    return "\n".join(lines) + "\n"


def write_counterexamples(result: AoiResult, directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    for v in result.verdicts:
        if v.holds is False:
            p = directory / f"{result.system.name}-{v.prop.id}.yaml"
            p.write_text(scenario_text(result, v), encoding="utf-8")
            v.scenario = p


def coverage(result: AoiResult) -> dict[str, tuple[list[str], list[str]]]:
    """Table -> (reached, unreached) item names."""
    codes = [str(c) for c in result.codes]
    states = list(result.recovery_states)
    goals = [g.id for g in result.system.goals]
    return {
        "error_codes": ([c for c in codes if int(c) in result.reached_codes],
                        [c for c in codes if int(c) not in result.reached_codes]),
        "recovery_states": ([s for s in states if s in result.reached_states],
                            [s for s in states if s not in result.reached_states]),
        "goals": ([g for g in goals if g in result.reached_goals], [g for g in goals if g not in result.reached_goals]),
    }


def as_dict(result: AoiResult) -> dict[str, object]:
    cov = coverage(result)
    return {
        "system": result.system.name, "kind": "add-on instruction", "states": result.states,
        "transitions": result.transitions, "depth": result.depth, "seconds": round(result.seconds, 2),
        "states_per_second": round(result.states / result.seconds) if result.seconds else 0,
        "complete": result.complete, "stop_reason": result.stop_reason, "error": result.error_text or None,
        "properties": [{"name": v.prop.id, "holds": v.holds, "source": v.prop.source, "always": v.prop.text,
                        "counterexample": None if v.state is None else {
                            "moves": [m.label() for m in result.path(v.state)],
                            "scenario": str(v.scenario) if v.scenario else None}}
                       for v in result.verdicts],
        "coverage": {name: {"reached": r, "unreached": u,
                            "explained": {i: result.system.unreached[i] for i in u if i in result.system.unreached}}
                     for name, (r, u) in cov.items()},
        "exit_code": result.exit_code,
    }


def text(result: AoiResult) -> str:
    d = as_dict(result)
    lines = [f"system {d['system']} (add-on instruction {result.system.instance}): "
             f"{len(result.system.inputs)} input(s) and {len(result.system.environment)} environment field(s) varied",
             f"  {d['states']:,} states, {d['transitions']:,} transitions, depth {d['depth']}, "
             f"{d['seconds']} s ({d['states_per_second']:,} states/s)"]
    if not result.complete:
        lines.append(f"  INCOMPLETE: {result.stop_reason}")
    if result.error_text:
        lines.append(f"  ERROR: {result.error_text}")
    lines.append("properties:")
    for v in result.verdicts:
        mark = {True: "holds   ", False: "VIOLATED", None: "unknown "}[v.holds]
        lines.append(f"  {mark} {v.prop.id}: {v.prop.text}")
        if v.holds is False and v.state is not None:
            moves = result.path(v.state)
            lines.append(f"           shortest run ({len(moves)} moves): " + "; ".join(m.label() for m in moves))
            if v.scenario is not None:
                lines.append(f"           counterexample: {v.scenario}")
    lines.append("coverage:")
    for name, (reached, unreached) in coverage(result).items():
        extra = ""
        if unreached:
            extra = "; unreached: " + ", ".join(
                f"{u} ({'explained' if u in result.system.unreached else 'UNEXPLAINED'})" for u in unreached)
        lines.append(f"  {name}: {len(reached)}/{len(reached) + len(unreached)}{extra}")
    lines.append({0: "verdict: every property holds", 1: "verdict: VIOLATED",
                  3: "verdict: INCOMPLETE (raise --max-states / --max-seconds)"}[result.exit_code])
    return "\n".join(lines) + "\n"


def run(path: Path, args: Any, out: TextIO) -> int:
    """``motionchart check --system <aoi system>``."""
    import json

    from statecharts.aoi import load_aoi
    from statecharts.diagnostics import SpecError

    spec_dir = None
    for p in getattr(args, "spec", None) or []:
        if Path(p).is_dir():
            spec_dir = Path(p)
    try:
        spec = load_aoi(spec_dir)
        system = load_aoi_system(path, spec)
    except (SpecError, AoiSystemError) as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        return 1
    if getattr(args, "max_changes", None) is not None:
        system = dataclasses.replace(system, max_changes=args.max_changes)
    progress = False if (args.quiet or args.json) else None
    result = explore_aoi(system, spec, max_states=args.max_states, max_seconds=args.max_seconds, progress=progress)
    if args.counterexamples:
        write_counterexamples(result, Path(args.counterexamples))
    if args.json:
        json.dump(as_dict(result), out, indent=2, sort_keys=True, default=str)
        out.write("\n")
    else:
        out.write(text(result))
    return result.exit_code
