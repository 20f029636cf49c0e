"""The raM_Opr_SyncPthPhyAx_CD add-on instruction: spec loader, world model and runner.

Pipeline position: ``spec/aoi/*.yaml`` (``format: motionchart-aoi/1``) and
``spec/instructions/motion/*.yaml`` (``format: motionchart-subinstruction/1``) ->
**this module** (schema + expression checks -> frozen :class:`AoiSpec`) -> :class:`World`
(device handlers, a physical and a path axis, AOI instances, one PLC scan at a time) ->
scenarios of ``format: motionchart-aoi-scenario/1`` (run by ``motionchart simulate``
through :mod:`statecharts.scenario`).  The main spec loader skips these formats.

Per scan and per AOI instance, in program order: registration with the handler named by
Ref_Handle (if not yet registered); then the prescan routine, the rung-false routine, or
the rung-true logic (a new execution runs the ordered checks, then the recovery chart's
states issue sub-instruction calls); then the motion update advances the axes and the
calls in process.  See docs/aoi.md and INT-021..INT-030.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jsonschema

from statecharts.diagnostics import Diagnostic, ScenarioError, SpecError, locate, node_path
from statecharts.expr import Expr, ExprError, EvalError, check_names, parse_expression
from statecharts.loader import _plain, bundled_spec_dir, read_yaml, schema_diagnostics
from statecharts.rotary import effective_move_type, signed_distance, unwind

AOI_FORMAT = "motionchart-aoi/1"
SUB_FORMAT = "motionchart-subinstruction/1"
SCENARIO_FORMAT = "motionchart-aoi-scenario/1"

_ID = {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_]*$"}
_EXPR = {"type": "string", "minLength": 1}
_SOURCE = {"type": "string", "minLength": 1}
_INTERP = {"type": "string", "pattern": "^INT-[0-9]{3}$"}
_SCALAR = {"type": ["boolean", "integer", "number", "string"]}
_PROV = {"source": _SOURCE, "interpretation": _INTERP}


def _obj(required: Sequence[str], props: Mapping[str, Any]) -> dict[str, Any]:
    return {"type": "object", "additionalProperties": False, "required": list(required), "properties": dict(props)}


AOI_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/aoi-1.json",
    "description": "An add-on instruction: operands, tag type, error codes, ordered checks, recovery chart.",
    **_obj(["format", "aoi"], {
        "format": {"const": AOI_FORMAT},
        "aoi": _obj(["id", "source", "execution", "inputs", "outputs", "errors", "checks", "recovery", "on_done",
                     "rung_false", "prescan"], {
            "id": _ID, **_PROV, "execution": {"enum": ["level", "edge"]}, "execution_source": _SOURCE,
            "inputs": {"type": "array", "items": _obj(["name", "type", "source"], {
                "name": _ID, "type": {"enum": ["axis", "handle", "BOOL", "DINT", "REAL"]}, "data_type": _ID,
                "default": _SCALAR, **_PROV})},
            "outputs": {"type": "array", "items": _obj(["name", "type", "source"], {
                "name": _ID, "type": {"enum": ["BOOL", "DINT"]}, **_PROV})},
            "errors": {"type": "array", "items": _obj(["code", "name", "source"], {
                "code": {"type": "integer"}, "name": {"type": "string"}, **_PROV})},
            "checks": {"type": "array", "items": _obj(["id", "code", "fails", "source"], {
                "id": _ID, "code": {"type": "integer"}, "applies": {"type": "integer"}, "fails": _EXPR, **_PROV})},
            "recovery": _obj(["initial", "states", "transitions", "source"], {
                "initial": _ID, **_PROV,
                "states": {"type": "array", "items": _obj(["id", "source"], {
                    "id": _ID, "description": {"type": "string"}, "error": {"type": "integer"},
                    "call": _obj(["instruction", "axis"], {
                        "instruction": _ID, "axis": {"enum": ["phy", "pth"]}, "master": {"enum": ["phy", "pth"]},
                        "operands": {"type": "object", "additionalProperties": {"type": ["number", "string"]}}}),
                    **_PROV})},
                "transitions": {"type": "array", "items": _obj(["from", "to", "when", "source"], {
                    "from": _ID, "to": _ID, "when": _EXPR, **_PROV})}}),
            "on_done": {"type": "array", "items": _obj(["when", "set", "source"], {
                "when": _EXPR, "set": {"enum": ["path_verified", "handler.OnPath"]}, **_PROV})},
            "rung_false": _obj(["clear", "source"], {
                "clear": {"type": "array", "items": _ID}, "abort_call": _ID, **_PROV}),
            "prescan": _obj(["clear", "source"], {
                "clear": {"type": "array", "items": _ID}, "forget": {"type": "array", "items": _ID}, **_PROV}),
        }),
    }),
}

SUB_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/subinstruction-1.json",
    "description": "A motion instruction as the add-on instruction calls it: ordered preconditions and completion.",
    **_obj(["format", "instruction"], {
        "format": {"const": SUB_FORMAT},
        "instruction": _obj(["mnemonic", "name", "source", "axis_types", "checks", "completes"], {
            "mnemonic": _ID, "name": {"type": "string"}, **_PROV,
            "axis_types": {"type": "array", "items": _ID},
            "checks": {"type": "array", "items": _obj(["fails", "err", "source"], {
                "fails": _EXPR, "err": {"type": "integer", "minimum": 1}, **_PROV})},
            "completes": _obj(["kind", "source"], {
                "kind": {"enum": ["home", "move", "gear", "redefine", "stop"]},
                "scans": {"type": "integer", "minimum": 1}, **_PROV}),
        }),
    }),
}

_AXIS_PROPS = {
    "type": {"enum": ["AXIS_CIP_DRIVE", "AXIS_VIRTUAL"]},
    "position": {"type": "number"}, "velocity": {"type": "number"}, "unwind": {"type": "number", "minimum": 0},
    "homed": {"type": "boolean"}, "energized": {"type": "boolean"}, "faulted": {"type": "boolean"},
    "shutdown": {"type": "boolean"}, "control_mode": {"enum": ["position", "velocity", "torque", "frequency", "none"]},
    "direct_control": {"type": "boolean"}, "home_config_ok": {"type": "boolean"}, "home_position": {"type": "number"},
    "homing": {"type": "boolean"},
}
_HANDLER_PROPS = {
    "id": {"type": "integer", "minimum": 0}, "registered": {"type": "integer", "minimum": 0},
    "capacity": {"type": "integer", "minimum": 0}, "eState": {"type": "integer"},
    "mode": {"enum": ["physical", "virtual", "none", "maintenance"]},
    "phy_axis": _ID, "pth_axis": _ID, "OnPath": {"type": "boolean"},
}
_INPUT_VALUES = {"type": ["boolean", "integer", "number", "string"]}
SCENARIO_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/aoi-scenario-1.json",
    "description": "Handlers, axes and add-on instruction instances, then scans with expected observations.",
    **_obj(["format", "name", "setup", "steps"], {
        "format": {"const": SCENARIO_FORMAT}, "name": {"type": "string", "minLength": 1},
        "description": {"type": "string"}, "sources": {"type": "array", "items": {"type": "string"}},
        "covers": {"type": "array", "items": {"type": "string"}},
        "setup": _obj(["handlers", "axes", "aoi"], {
            "scan_ms": {"type": "integer", "minimum": 1},
            "handlers": {"type": "object", "minProperties": 1, "propertyNames": _ID,
                         "additionalProperties": _obj(["id"], _HANDLER_PROPS)},
            "axes": {"type": "object", "minProperties": 1, "propertyNames": _ID,
                     "additionalProperties": _obj(["type"], _AXIS_PROPS)},
            "aoi": {"type": "object", "minProperties": 1, "propertyNames": _ID,
                    "additionalProperties": {"type": "object", "propertyNames": _ID,
                                             "additionalProperties": _INPUT_VALUES}},
        }),
        "steps": {"type": "array", "minItems": 1, "items": _obj([], {
            "name": {"type": "string"}, "scans": {"type": "integer", "minimum": 1, "maximum": 100000},
            "prescan": {"type": "boolean"},
            "rungs": {"type": "object", "additionalProperties": {"type": "boolean"}},
            "operands": {"type": "object", "additionalProperties": {"type": "object", "additionalProperties": _INPUT_VALUES}},
            "set": {"type": "object", "additionalProperties": {"type": "object", "additionalProperties": _SCALAR}},
            "expect": {"type": "object", "additionalProperties": {"type": "object", "additionalProperties": _SCALAR}},
        })},
    }),
}

#: Names the check and transition expressions may read besides the inputs.
WORLD_NAMES = frozenset(
    {"registered", "path_verified", "distance.magnitude", "move.type", "move.target", "call.done"}
    | {f"handler.{k}" for k in ("eState", "mode", "phy_axis", "pth_axis", "OnPath")}
    | {f"{a}.{k}" for a in ("phy", "pth") for k in (*_AXIS_PROPS, "rotary", "geared", "name")}
)
#: Names a sub-instruction's checks may read besides its operands.
SUB_NAMES = frozenset({f"{a}.{k}" for a in ("axis", "master") for k in (*_AXIS_PROPS, "rotary", "geared", "name")})


# --------------------------------------------------------------------------- IR


@dataclass(frozen=True, slots=True)
class AoiCheck:
    id: str
    code: int
    applies: int | None
    fails: Expr
    source: str
    interpretation: str | None


@dataclass(frozen=True, slots=True)
class Call:
    instruction: str
    axis: str
    master: str | None
    operands: tuple[tuple[str, Expr], ...]


@dataclass(frozen=True, slots=True)
class RecoveryState:
    id: str
    call: Call | None
    error: int | None
    source: str


@dataclass(frozen=True, slots=True)
class RecoveryTransition:
    source_state: str
    target: str
    when: Expr


@dataclass(frozen=True, slots=True)
class SubCheck:
    fails: Expr
    err: int
    source: str


@dataclass(frozen=True, slots=True)
class SubInstruction:
    mnemonic: str
    name: str
    checks: tuple[SubCheck, ...]
    kind: str
    scans: int
    source: str


@dataclass(frozen=True, slots=True)
class AoiSpec:
    id: str
    inputs: tuple[tuple[str, str, object], ...]  # (name, type, default)
    outputs: tuple[tuple[str, str], ...]
    errors: tuple[tuple[int, str], ...]
    checks: tuple[AoiCheck, ...]
    initial: str
    states: tuple[RecoveryState, ...]
    transitions: tuple[RecoveryTransition, ...]
    on_done: tuple[tuple[Expr, str], ...]
    rung_false_clear: tuple[str, ...]
    abort_call: str | None
    prescan_clear: tuple[str, ...]
    prescan_forget: tuple[str, ...]
    instructions: tuple[SubInstruction, ...]

    def state(self, sid: str) -> RecoveryState:
        return next(s for s in self.states if s.id == sid)

    def instruction(self, mnemonic: str) -> SubInstruction:
        return next(i for i in self.instructions if i.mnemonic == mnemonic)

    def input_type(self, name: str) -> str:
        return next(t for n, t, _ in self.inputs if n == name)


def _exprs(f: str, tree: Any, parts: tuple[Any, ...], text: str, known: frozenset[str],
           errors: list[Diagnostic]) -> Expr | None:
    line, col = locate(tree, parts) if hasattr(tree, "lc") else (1, 1)
    try:
        e = parse_expression(text)
    except ExprError as exc:
        errors.append(Diagnostic(f, line, col, node_path(parts), f"bad expression: {exc}"))
        return None
    unknown = check_names(e, known)
    if unknown:
        names = ", ".join(n for n, _ in unknown)
        errors.append(Diagnostic(f, line, col, node_path(parts), f"unknown name(s) {names} in {text!r}"))
        return None
    return e


def _check_interpretations(f: str, tree: Any, errors: list[Diagnostic], root: Path) -> None:
    """Every `interpretation:` the file cites must exist in interpretations.yaml."""
    known: set[str] = set()
    doc = read_yaml(root / "interpretations.yaml", [])
    if doc is not None:
        known = {str(i.get("id")) for i in _plain(doc).get("interpretations", []) if isinstance(i, dict)}
    stack: list[tuple[Any, tuple[Any, ...]]] = [(tree, ())]
    while stack:
        node, parts = stack.pop()
        if isinstance(node, Mapping):
            cited = node.get("interpretation")
            if isinstance(cited, str) and cited not in known:
                line, col = locate(tree, (*parts, "interpretation")) if hasattr(tree, "lc") else (1, 1)
                errors.append(Diagnostic(f, line, col, node_path((*parts, "interpretation")),
                                         f"unknown interpretation {cited!r}; add it to interpretations.yaml"))
            stack.extend((v, (*parts, k)) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, (*parts, i)) for i, v in enumerate(node))


def aoi_files(spec_dir: Path | None = None) -> tuple[list[Path], list[Path]]:
    root = spec_dir or bundled_spec_dir()
    return (sorted((root / "aoi").glob("*.yaml")), sorted((root / "instructions" / "motion").glob("*.yaml")))


@functools.lru_cache(maxsize=1)
def bundled_aoi() -> AoiSpec:
    """The bundled add-on instruction spec, loaded once per process (it is immutable)."""
    return load_aoi()


def load_aoi(spec_dir: Path | str | None = None) -> AoiSpec:
    """Load the add-on instruction and its sub-instructions; raise SpecError with every problem."""
    aoi_paths, sub_paths = aoi_files(Path(spec_dir) if spec_dir else None)
    errors: list[Diagnostic] = []
    subs: list[SubInstruction] = []
    for p in sub_paths:
        f = str(p)
        before = len(errors)
        tree = read_yaml(p, errors)
        if tree is None:
            continue
        errors.extend(schema_diagnostics(f, tree, SUB_SCHEMA, "a sub-instruction file"))
        if len(errors) > before:
            continue
        _check_interpretations(f, tree, errors, Path(spec_dir) if spec_dir else bundled_spec_dir())
        d = _plain(tree)["instruction"]
        checks = []
        for i, c in enumerate(d["checks"]):
            names = SUB_NAMES | {"MoveType", "Speed", "Position", "Position.finite", "Speed.finite"}
            e = _exprs(f, tree, ("instruction", "checks", i, "fails"), c["fails"], names, errors)
            if e is not None:
                checks.append(SubCheck(e, int(c["err"]), c["source"]))
        subs.append(SubInstruction(d["mnemonic"], d["name"], tuple(checks), d["completes"]["kind"],
                                   int(d["completes"].get("scans", 1)), d["source"]))
    if len(aoi_paths) != 1:
        errors.append(Diagnostic(str(bundled_spec_dir() / "aoi"), 1, 1, "", f"expected one add-on instruction file, found {len(aoi_paths)}"))
        raise SpecError(errors)
    p = aoi_paths[0]
    f = str(p)
    before = len(errors)
    tree = read_yaml(p, errors)
    if tree is None:
        raise SpecError(errors)
    errors.extend(schema_diagnostics(f, tree, AOI_SCHEMA, "an add-on instruction file"))
    if len(errors) > before:
        raise SpecError(errors)
    d = _plain(tree)["aoi"]
    inputs = tuple((i["name"], i["type"], i.get("default")) for i in d["inputs"])
    input_names = {n for n, _, _ in inputs}
    known = WORLD_NAMES | input_names | {f"{n}.finite" for n, t, _ in inputs if t == "REAL"}
    codes = {e["code"] for e in d["errors"]}
    checks: list[AoiCheck] = []
    for i, c in enumerate(d["checks"]):
        if c["code"] not in codes:
            errors.append(Diagnostic(f, *locate(tree, ("aoi", "checks", i, "code")), f"aoi.checks[{i}].code", f"code {c['code']} is not in aoi.errors"))
        e = _exprs(f, tree, ("aoi", "checks", i, "fails"), c["fails"], known, errors)
        if e is not None:
            checks.append(AoiCheck(c["id"], c["code"], c.get("applies"), e, c["source"], c.get("interpretation")))
    mnemonics = {s.mnemonic for s in subs}
    states: list[RecoveryState] = []
    for i, s in enumerate(d["recovery"]["states"]):
        call = None
        if "call" in s:
            c = s["call"]
            if c["instruction"] not in mnemonics:
                errors.append(Diagnostic(f, *locate(tree, ("aoi", "recovery", "states", i, "call")), f"aoi.recovery.states[{i}].call",
                                         f"unknown sub-instruction {c['instruction']!r}; known: {', '.join(sorted(mnemonics))}"))
            ops = []
            for k, v in c.get("operands", {}).items():
                e = _exprs(f, tree, ("aoi", "recovery", "states", i, "call", "operands", k), str(v), known, errors)
                if e is not None:
                    ops.append((k, e))
            call = Call(c["instruction"], c["axis"], c.get("master"), tuple(ops))
            if "error" not in s:
                errors.append(Diagnostic(f, *locate(tree, ("aoi", "recovery", "states", i)), f"aoi.recovery.states[{i}]", "a state with a call needs `error`"))
        states.append(RecoveryState(s["id"], call, s.get("error"), s["source"]))
    ids = {s.id for s in states}
    for need in ("idle", "checking", "done", d["recovery"]["initial"]):
        if need not in ids:
            errors.append(Diagnostic(f, 1, 1, "aoi.recovery.states", f"the recovery chart needs a state {need!r}"))
    transitions = []
    for i, t in enumerate(d["recovery"]["transitions"]):
        for k in ("from", "to"):
            if t[k] not in ids:
                errors.append(Diagnostic(f, *locate(tree, ("aoi", "recovery", "transitions", i, k)), f"aoi.recovery.transitions[{i}].{k}", f"unknown state {t[k]!r}"))
        e = _exprs(f, tree, ("aoi", "recovery", "transitions", i, "when"), t["when"], known, errors)
        if e is not None:
            transitions.append(RecoveryTransition(t["from"], t["to"], e))
    on_done = []
    for i, o in enumerate(d["on_done"]):
        e = _exprs(f, tree, ("aoi", "on_done", i, "when"), o["when"], known, errors)
        if e is not None:
            on_done.append((e, o["set"]))
    _check_interpretations(f, tree, errors, Path(spec_dir) if spec_dir else bundled_spec_dir())
    abort = d["rung_false"].get("abort_call")
    if abort is not None and abort not in mnemonics:
        errors.append(Diagnostic(f, 1, 1, "aoi.rung_false.abort_call", f"unknown sub-instruction {abort!r}"))
    if errors:
        raise SpecError(errors)
    return AoiSpec(
        id=d["id"], inputs=inputs, outputs=tuple((o["name"], o["type"]) for o in d["outputs"]),
        errors=tuple((e["code"], e["name"]) for e in d["errors"]), checks=tuple(checks),
        initial=d["recovery"]["initial"], states=tuple(states), transitions=tuple(transitions),
        on_done=tuple(on_done), rung_false_clear=tuple(d["rung_false"]["clear"]), abort_call=abort,
        prescan_clear=tuple(d["prescan"]["clear"]), prescan_forget=tuple(d["prescan"].get("forget", [])),
        instructions=tuple(subs),
    )


# --------------------------------------------------------------------------- world


@dataclass
class Axis:
    name: str
    type: str = "AXIS_CIP_DRIVE"
    position: float = 0.0
    velocity: float = 0.0
    unwind: float = 0.0
    homed: bool = True
    energized: bool = True
    faulted: bool = False
    shutdown: bool = False
    control_mode: str = "position"
    direct_control: bool = False
    home_config_ok: bool = True
    home_position: float = 0.0
    homing: bool = False
    geared: bool = False
    master: str | None = None
    # motion in process (MAM): remaining signed distance and speed
    move_remaining: float = 0.0
    move_speed: float = 0.0
    home_scans_left: int = 0

    @property
    def rotary(self) -> bool:
        return self.unwind > 0

    @property
    def cip_axis_state(self) -> int:
        """A stand-in for the AxisCIP chart's CIPAxisState (Stopped 2, Running 4, Faulted 8, Shutdown 10)."""
        if self.shutdown:
            return 10
        if self.faulted:
            return 8
        return 4 if self.energized else 2

    def env(self, prefix: str) -> dict[str, object]:
        out: dict[str, object] = {f"{prefix}.{k}": getattr(self, k) for k in _AXIS_PROPS}
        out[f"{prefix}.rotary"] = self.rotary
        out[f"{prefix}.geared"] = self.geared
        out[f"{prefix}.name"] = self.name
        return out

    def observe(self) -> dict[str, object]:
        out = {k: getattr(self, k) for k in ("position", "velocity", "homed", "energized", "faulted", "shutdown",
                                             "geared", "homing", "direct_control")}
        out["moving"] = self.velocity != 0
        if self.type == "AXIS_CIP_DRIVE":
            out["CIPAxisState"] = self.cip_axis_state
        return out


@dataclass
class Handler:
    name: str
    id: int = 1
    registered: int = 0
    capacity: int = 10
    eState: int = 7
    mode: str = "physical"
    phy_axis: str = ""
    pth_axis: str = ""
    OnPath: bool = False

    def observe(self) -> dict[str, object]:
        return {"eState": self.eState, "mode": self.mode, "OnPath": self.OnPath, "registered": self.registered}


@dataclass
class PendingCall:
    instruction: SubInstruction
    axis: str
    done: bool = False
    err: int = 0
    aborted: bool = False  # the axis faulted or shut down under it (INT-046)


@dataclass
class Instance:
    name: str
    inputs: dict[str, object]
    outputs: dict[str, object] = field(default_factory=dict)
    state: str = "idle"
    path_verified: bool = False
    registrations: dict[str, int] = field(default_factory=dict)  # handler name -> method id
    call: PendingCall | None = None
    move_type: int = 0
    move_target: float = 0.0

    def observe(self) -> dict[str, object]:
        out = dict(self.outputs)
        out["state"] = self.state
        out["path_verified"] = self.path_verified
        return out


def _finite(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


class World:
    """Device handlers, axes and AOI instances advanced one PLC scan at a time."""

    def __init__(self, spec: AoiSpec, handlers: Sequence[Handler], axes: Sequence[Axis],
                 instances: Sequence[Instance], scan_ms: int = 10) -> None:
        self.spec = spec
        self.handlers = {h.name: h for h in handlers}
        self.axes = {a.name: a for a in axes}
        self.instances = {i.name: i for i in instances}
        self.scan_ms = scan_ms
        self.index = 0
        for inst in self.instances.values():
            for n, _t, default in spec.inputs:
                inst.inputs.setdefault(n, default)
            for n, t in spec.outputs:
                inst.outputs.setdefault(n, False if t == "BOOL" else 0)

    # -- environment -----------------------------------------------------------
    def env(self, inst: Instance) -> dict[str, object]:
        env: dict[str, object] = dict(inst.inputs)
        for n, t, _ in self.spec.inputs:
            if t == "REAL":
                env[f"{n}.finite"] = _finite(inst.inputs.get(n))
        h = self.handlers.get(str(inst.inputs.get("Ref_Handle")))
        env.update({"handler.eState": h.eState if h else 0, "handler.mode": h.mode if h else "none",
                    "handler.phy_axis": h.phy_axis if h else "", "handler.pth_axis": h.pth_axis if h else "",
                    "handler.OnPath": h.OnPath if h else False})
        env["registered"] = h is not None and h.name in inst.registrations
        env["path_verified"] = inst.path_verified
        phy = self.axes[str(inst.inputs["Ref_AxisPhy"])]
        pth = self.axes[str(inst.inputs["Ref_AxisPth"])]
        env.update(phy.env("phy"))
        env.update(pth.env("pth"))
        mt = inst.inputs.get("Cfg_MoveType")
        tol = inst.inputs.get("Cfg_RotaryShortestTOL")
        tol_f = float(tol) if _finite(tol) else 0.0  # type: ignore[arg-type]
        mt_i = int(mt) if isinstance(mt, int) and not isinstance(mt, bool) else -1
        eff = effective_move_type(phy.position, pth.position, phy.unwind, mt_i, tol_f)
        dist = signed_distance(phy.position, pth.position, phy.unwind, eff)
        env["distance.magnitude"] = abs(dist)
        env["move.type"] = eff
        env["move.target"] = unwind(pth.position, phy.unwind)
        env["call.done"] = inst.call is not None and inst.call.done
        return env

    # -- one scan --------------------------------------------------------------
    def scan(self, rungs: Mapping[str, bool] | None = None, prescan: bool = False) -> None:
        self.index += 1
        rungs = rungs or {}
        for inst in self.instances.values():
            self._register(inst)
            if prescan:
                self._rung_false(inst)
                for n in self.spec.prescan_clear:
                    inst.outputs[n] = False if isinstance(inst.outputs[n], bool) else 0
                if "path_verified" in self.spec.prescan_forget:
                    inst.path_verified = False
                inst.state = "idle"
            elif rungs.get(inst.name, False):
                self._rung_true(inst)
            else:
                self._rung_false(inst)
        if not prescan:
            self._motion_update()

    def _register(self, inst: Instance) -> None:
        h = self.handlers.get(str(inst.inputs.get("Ref_Handle")))
        if h is not None and h.name not in inst.registrations and h.registered < h.capacity:
            h.registered += 1
            inst.registrations[h.name] = h.id * 1000 + h.registered
        inst.outputs["Sts_MtdID"] = inst.registrations.get(h.name, 0) if h else 0

    def _rung_false(self, inst: Instance) -> None:
        if inst.call is not None and not inst.call.done and self.spec.abort_call:
            self._issue_stop(inst)
        inst.call = None
        for n in self.spec.rung_false_clear:
            inst.outputs[n] = False
        inst.state = "idle"

    def _issue_stop(self, inst: Instance) -> None:
        """MAS (Stop Type All) on the physical axis: motion, homing and gearing stop."""
        a = self.axes[str(inst.inputs["Ref_AxisPhy"])]
        a.move_remaining = 0.0
        a.velocity = 0.0
        a.homing = False
        a.home_scans_left = 0
        a.geared = False

    def _error(self, inst: Instance, code: int, exerr: int = 0) -> None:
        inst.outputs.update(Sts_ER=True, Sts_ERR=code, Sts_EXERR=exerr, Sts_IP=False, Sts_PC=False)
        inst.state = "error"
        inst.call = None

    def _rung_true(self, inst: Instance) -> None:
        inst.outputs["Sts_EN"] = True
        inst.outputs["Sts_EO"] = True
        if inst.state in ("error", "done"):
            return  # latched until the rung goes false (INT-029)
        if inst.call is not None and inst.call.aborted:
            inst.outputs["Sts_IP"] = False  # nothing in process; no PC, no error (INT-046)
            return
        if inst.state == "idle":
            inst.outputs.update(Sts_ER=False, Sts_ERR=0, Sts_EXERR=0, Sts_PC=False, Sts_IP=False)
            inst.state = self.spec.initial
        env = self.env(inst)
        if inst.state == "checking":
            sync = inst.inputs.get("Cfg_SyncType")
            for c in self.spec.checks:
                if c.applies is not None and c.applies != sync:
                    continue
                if c.fails(env):
                    self._error(inst, c.code)
                    return
            inst.move_type = int(env["move.type"])  # type: ignore[call-overload]
            inst.move_target = float(env["move.target"])  # type: ignore[arg-type]
        for _ in range(len(self.spec.states) + 1):
            nxt = next((t.target for t in self.spec.transitions
                        if t.source_state == inst.state and t.when(env)), None)
            if nxt is None:
                return
            self._enter(inst, nxt)
            if inst.state in ("error", "done"):
                return
            env = self.env(inst)

    def _enter(self, inst: Instance, sid: str) -> None:
        inst.state = sid
        inst.call = None
        st = self.spec.state(sid)
        if sid == "done":
            env = self.env(inst)
            for when, target in self.spec.on_done:
                if when(env):
                    if target == "path_verified":
                        inst.path_verified = True
                    elif target == "handler.OnPath":
                        h = self.handlers.get(str(inst.inputs.get("Ref_Handle")))
                        if h is not None:
                            h.OnPath = True
            inst.outputs.update(Sts_IP=False, Sts_PC=True)
            return
        if st.call is None:
            return
        env = self.env(inst)
        ops = {k: e(env) for k, e in st.call.operands}
        sub = self.spec.instruction(st.call.instruction)
        axis_name = str(inst.inputs["Ref_AxisPhy" if st.call.axis == "phy" else "Ref_AxisPth"])
        axis = self.axes[axis_name]
        senv: dict[str, object] = dict(axis.env("axis"))
        if st.call.master:
            senv.update(self.axes[str(inst.inputs["Ref_AxisPhy" if st.call.master == "phy" else "Ref_AxisPth"])].env("master"))
        else:
            senv.update({k.replace("axis.", "master.", 1): v for k, v in axis.env("axis").items()})
        for k, v in ops.items():
            senv[k] = v
            senv[f"{k}.finite"] = _finite(v)
        for c in sub.checks:
            if c.fails(senv):
                self._error(inst, int(st.error or 0), c.err)
                return
        inst.call = PendingCall(sub, axis_name)
        inst.outputs["Sts_IP"] = True
        if sub.kind == "home":
            axis.homing = True
            axis.home_scans_left = sub.scans
            axis.geared = False
        elif sub.kind == "move":
            axis.geared = False
            axis.move_speed = float(ops["Speed"])  # type: ignore[arg-type]
            axis.move_remaining = signed_distance(axis.position, float(ops["Position"]), axis.unwind,  # type: ignore[arg-type]
                                                  int(ops["MoveType"]))  # type: ignore[call-overload]
            if axis.move_remaining == 0:
                inst.call.done = True
        elif sub.kind == "gear":
            axis.geared = True
            axis.master = str(inst.inputs["Ref_AxisPth"])
            inst.call.done = True  # DN = gearing initiated
        elif sub.kind == "redefine":
            axis.position = unwind(float(ops["Position"]), axis.unwind)  # type: ignore[arg-type]
            inst.call.done = True

    def _motion_update(self) -> None:
        dt = self.scan_ms / 1000.0
        for a in self.axes.values():
            if not a.geared and a.move_remaining == 0 and not a.homing and a.type == "AXIS_VIRTUAL":
                a.position = unwind(a.position + a.velocity * dt, a.unwind)
        stopped: set[str] = set()
        for a in self.axes.values():
            if (a.faulted or a.shutdown) and (a.home_scans_left > 0 or a.move_remaining != 0 or a.geared):
                # the fault or shutdown stops the axis and ends its motion (INT-046)
                if a.home_scans_left > 0:
                    a.homing = False
                    a.home_scans_left = 0
                a.move_remaining = 0.0
                a.velocity = 0.0
                a.geared = False
                stopped.add(a.name)
        for a in self.axes.values():
            if a.homing and a.home_scans_left > 0:  # homing by our MAH; other homing is the scenario's
                a.home_scans_left -= 1
                if a.home_scans_left <= 0:
                    a.homing = False
                    a.homed = True
                    a.position = unwind(a.home_position, a.unwind)
            elif a.move_remaining != 0:
                step = a.move_speed * dt
                if step >= abs(a.move_remaining):
                    a.position = unwind(a.position + a.move_remaining, a.unwind)
                    a.move_remaining = 0.0
                    a.velocity = 0.0
                else:
                    d = math.copysign(step, a.move_remaining)
                    a.position = unwind(a.position + d, a.unwind)
                    a.move_remaining -= d
                    a.velocity = math.copysign(a.move_speed, d)
            elif a.geared and a.master in self.axes:
                m = self.axes[a.master]
                a.position = unwind(m.position, a.unwind)
                a.velocity = m.velocity
        for inst in self.instances.values():
            c = inst.call
            if c is None or c.done:
                continue
            if c.axis in stopped:
                c.aborted = True
                continue
            axis = self.axes[c.axis]
            if c.instruction.kind == "home" and axis.home_scans_left <= 0 and axis.homed:
                c.done = True
            elif c.instruction.kind == "move" and axis.move_remaining == 0:
                c.done = True

    def observe(self) -> dict[str, dict[str, object]]:
        out: dict[str, dict[str, object]] = {}
        for n, h in self.handlers.items():
            out[n] = h.observe()
        for n, a in self.axes.items():
            out[n] = a.observe()
        for n, i in self.instances.items():
            out[n] = i.observe()
        return out


# --------------------------------------------------------------------------- scenarios


@dataclass(frozen=True, slots=True)
class AoiStep:
    index: int
    name: str
    scans: int
    prescan: bool
    rungs: tuple[tuple[str, bool], ...]
    operands: tuple[tuple[str, tuple[tuple[str, object], ...]], ...]
    sets: tuple[tuple[str, tuple[tuple[str, object], ...]], ...]
    expect: tuple[tuple[str, str, object], ...]
    line: int


@dataclass(frozen=True, slots=True)
class AoiScenario:
    file: str
    name: str
    description: str
    sources: tuple[str, ...]
    covers: tuple[str, ...]
    scan_ms: int
    setup: Mapping[str, Any]
    steps: tuple[AoiStep, ...]

    # what a motionchart-scenario/1 reader (e.g. the traceability renderer) looks for:
    # no axis charts and no MOTION_INSTRUCTION tags of the main spec
    @property
    def axes(self) -> tuple[()]:
        return ()

    @property
    def program(self) -> tuple[()]:
        return ()


def _input_problem(spec: AoiSpec, name: str, value: object, refs: Mapping[str, set[str]]) -> str | None:
    t = spec.input_type(name)
    if t == "BOOL":
        return None if isinstance(value, bool) or value in (0, 1) else f"expected true or false, got {value!r}"
    if name == "Cfg_SyncType" and value not in (0, 1):
        return f"expected 0 (path to physical) or 1 (physical to path), got {value!r}"
    if t == "DINT":
        ok = isinstance(value, int) and not isinstance(value, bool) and -2**31 <= value < 2**31
        return None if ok else f"expected a DINT (whole number in 32 bits), got {value!r}"
    if t == "REAL":
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        return None if ok else f"expected a number (.nan and .inf are allowed), got {value!r}"
    known = refs["handle" if t == "handle" else "axis"]
    return None if value in known else f"expected the name of a {t} in the setup ({', '.join(sorted(known))}), got {value!r}"


def load_aoi_scenario(path: Path | str, tree: Any, spec: AoiSpec) -> AoiScenario:
    """Check an AOI scenario (already parsed) against its schema and the AOI spec."""
    name = str(path)
    errors: list[Diagnostic] = list(schema_diagnostics(name, tree, SCENARIO_SCHEMA, "an add-on instruction scenario"))
    if errors:
        raise ScenarioError(errors)
    doc = _plain(tree)

    def err(parts: tuple[Any, ...], message: str) -> None:
        line, col = locate(tree, parts) if hasattr(tree, "lc") else (1, 1)
        errors.append(Diagnostic(name, line, col, node_path(parts), message))

    setup = doc["setup"]
    refs = {"handle": set(setup["handlers"]), "axis": set(setup["axes"])}
    inputs = {n for n, _, _ in spec.inputs}
    for hname, h in setup["handlers"].items():
        for k in ("phy_axis", "pth_axis"):
            if k in h and h[k] not in refs["axis"]:
                err(("setup", "handlers", hname, k), f"unknown axis {h[k]!r}; axes: {', '.join(sorted(refs['axis']))}")
    for iname, ops in setup["aoi"].items():
        for k in ("Ref_AxisPhy", "Ref_AxisPth", "Ref_Handle"):
            if k not in ops:
                err(("setup", "aoi", iname), f"instance {iname} needs {k}")
        for k, v in ops.items():
            if k == "path_verified":
                if not isinstance(v, bool):
                    err(("setup", "aoi", iname, k), "expected true or false")
                continue
            if k not in inputs:
                err(("setup", "aoi", iname, k), f"{spec.id} has no input {k!r}; inputs: {', '.join(sorted(inputs))}")
                continue
            problem = _input_problem(spec, k, v, refs)
            if problem:
                err(("setup", "aoi", iname, k), f"{k}: {problem}")
    objects: dict[str, set[str]] = {}
    for hname in setup["handlers"]:
        objects[hname] = set(Handler(hname).observe())
    for aname, a in setup["axes"].items():
        objects[aname] = set(Axis(aname, type=a["type"]).observe())
    outs = {n for n, _ in spec.outputs} | {"state", "path_verified"}
    for iname in setup["aoi"]:
        objects[iname] = outs
    steps: list[AoiStep] = []
    for i, s in enumerate(doc["steps"]):
        p = ("steps", i)
        for tag in s.get("rungs", {}):
            if tag not in setup["aoi"]:
                err((*p, "rungs", tag), f"unknown add-on instruction instance {tag!r}; instances: {', '.join(setup['aoi'])}")
        for tag, ops in s.get("operands", {}).items():
            if tag not in setup["aoi"]:
                err((*p, "operands", tag), f"unknown add-on instruction instance {tag!r}")
                continue
            for k, v in ops.items():
                if k not in inputs:
                    err((*p, "operands", tag, k), f"{spec.id} has no input {k!r}")
                    continue
                problem = _input_problem(spec, k, v, refs)
                if problem:
                    err((*p, "operands", tag, k), f"{k}: {problem}")
        for obj, fields in s.get("set", {}).items():
            props = _HANDLER_PROPS if obj in setup["handlers"] else _AXIS_PROPS if obj in setup["axes"] else None
            if props is None:
                err((*p, "set", obj), f"unknown handler or axis {obj!r}")
                continue
            for k, v in fields.items():
                if k not in props or k == "type":
                    err((*p, "set", obj, k), f"{obj} has no settable field {k!r}; fields: {', '.join(sorted(set(props) - {'type'}))}")
                elif not jsonschema.Draft202012Validator(props[k]).is_valid(v):
                    err((*p, "set", obj, k), f"{obj}.{k}: {v!r} does not match {json.dumps(props[k], sort_keys=True)}")
        expect = []
        for obj, fields in s.get("expect", {}).items():
            if obj not in objects:
                err((*p, "expect", obj), f"unknown object {obj!r}; objects: {', '.join(sorted(objects))}")
                continue
            for k, v in fields.items():
                if k not in objects[obj]:
                    err((*p, "expect", obj, k), f"{obj} has no observable {k!r}; observables: {', '.join(sorted(objects[obj]))}")
                expect.append((obj, k, v))
        line, _ = locate(tree, p) if hasattr(tree, "lc") else (1, 1)
        steps.append(AoiStep(
            i, str(s.get("name", "")), int(s.get("scans", 1)), bool(s.get("prescan", False)),
            tuple(sorted(s.get("rungs", {}).items())),
            tuple((k, tuple(sorted(v.items()))) for k, v in sorted(s.get("operands", {}).items())),
            tuple((k, tuple(sorted(v.items()))) for k, v in sorted(s.get("set", {}).items())),
            tuple(expect), line))
    if errors:
        raise ScenarioError(errors)
    return AoiScenario(name, doc["name"], str(doc.get("description", "")), tuple(doc.get("sources", [])),
                       tuple(doc.get("covers", [])), int(setup.get("scan_ms", 10)), setup, tuple(steps))


def build_world(spec: AoiSpec, setup: Mapping[str, Any]) -> World:
    handlers = [Handler(n, **{k: v for k, v in h.items()}) for n, h in setup["handlers"].items()]
    axes = []
    for n, a in setup["axes"].items():
        kw = dict(a)
        if a["type"] == "AXIS_VIRTUAL":
            kw.setdefault("control_mode", "position")
        ax = Axis(n, **kw)
        ax.position = unwind(float(ax.position), ax.unwind)
        axes.append(ax)
    instances = []
    for n, ops in setup["aoi"].items():
        ops = dict(ops)
        verified = bool(ops.pop("path_verified", False))
        instances.append(Instance(n, ops, path_verified=verified))
    return World(spec, handlers, axes, instances, scan_ms=int(setup.get("scan_ms", 10)))


def run_aoi_scenario(scenario: AoiScenario, spec: AoiSpec) -> Any:
    """Run the scenario; returns a :class:`statecharts.scenario.ScenarioResult`."""
    from statecharts.scan import ScanRecord
    from statecharts.scenario import Mismatch, ScanRow, ScenarioResult, _same

    world = build_world(spec, scenario.setup)
    before = world.observe()
    rows = []
    mismatches = []
    for step in scenario.steps:
        for inst_name, ops in step.operands:
            world.instances[inst_name].inputs.update(dict(ops))
        for obj, fields in step.sets:
            target: Any = world.handlers.get(obj) or world.axes[obj]
            for k, v in fields:
                setattr(target, k, v)
        rungs = dict(step.rungs)
        for _ in range(step.scans):
            try:
                world.scan(rungs, prescan=step.prescan)
            except (EvalError, ArithmeticError, TypeError, ValueError) as exc:
                raise ScenarioError([Diagnostic(scenario.file, step.line, 1, f"steps[{step.index}]",
                                                f"the add-on instruction spec cannot be evaluated on these values: {exc}")]) from None
            obs = world.observe()
            changes = tuple((o, f, before.get(o, {}).get(f), v) for o, fs in obs.items() for f, v in fs.items()
                            if before.get(o, {}).get(f) != v)
            rows.append(ScanRow(step.index, step.name, ScanRecord(world.index, True, obs), changes))
            before = obs
        for obj, fld, expected in step.expect:
            actual = before[obj][fld]
            if not _same(expected, actual):
                mismatches.append(Mismatch(step.index, step.name, world.index, obj, fld, expected, actual, step.line))
    return ScenarioResult(scenario, tuple(rows), tuple(mismatches))  # type: ignore[arg-type]

