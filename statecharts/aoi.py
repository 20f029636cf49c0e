"""The raM_Opr_SyncPthPhyAx_CD add-on instruction: world model and runner.

Pipeline position: ``spec/addons/*.yaml`` (an ``add_on_instruction:`` section of the spec
language, built by :mod:`statecharts.addon_loader` into :class:`statecharts.ir.AddOnInstruction`)
and ``spec/instructions/motion/*.yaml`` (the motion instructions as the recovery calls
them) -> **this module** -> :class:`World` (device handlers on the DeviceHandler chart, a
physical axis on AxisCIP and a path axis on AxisVirtual, run by the engine through the
add-on instruction's `world:` facts, the motion planner's numbers, AOI instances, one
PLC scan at a time) -> scenarios (run by ``motionchart simulate`` through
:mod:`statecharts.scenario`).

Per scan and per AOI instance, in program order: registration with the handler named by
Ref_Handle (if not yet registered); then the prescan routine, the rung-false routine, or
the rung-true logic (a new execution runs the ordered checks, then the recovery chart's
states issue sub-instruction calls); then the motion update advances the axes and the
calls in process.  See docs/aoi.md, INT-021..INT-030, INT-046 and INT-065..INT-070.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, cast

import jsonschema

from statecharts import ir
from statecharts.addon_loader import SubInstruction, build_sub_instructions, undefined_calls
from statecharts.diagnostics import Diagnostic, ScenarioError, SpecError, locate, node_path
from statecharts.expr import EvalError
from statecharts.loader import bundled_spec_dir, load_spec, plain_data, read_yaml, schema_diagnostics
from statecharts.rotary import effective_move_type, signed_distance, unwind
from statecharts.values import as_float, as_int

SCENARIO_FORMAT = "motionchart-aoi-scenario/1"
_SCHEMA_DIR = bundled_spec_dir() / "schema"


@functools.cache
def _schema(name: str) -> dict[str, Any]:
    return cast("dict[str, Any]", json.loads((_SCHEMA_DIR / name).read_text(encoding="utf-8")))


_SETUP = _schema("aoi-scenario.schema.json")["properties"]["setup"]["properties"]
_CHART_SETUP_FIELDS = ("state", "variables", "events")
#: A scenario's axis and handler fields and their JSON Schemas.
_AXIS_PROPS: dict[str, Any] = {k: v for k, v in _SETUP["axes"]["additionalProperties"]["properties"].items()
                               if k not in _CHART_SETUP_FIELDS}
_HANDLER_PROPS: dict[str, Any] = {k: v for k, v in _SETUP["handlers"]["additionalProperties"]["properties"].items()
                                  if k not in _CHART_SETUP_FIELDS}
@dataclass(frozen=True)
class AoiSpec:
    """The add-on instruction of a loaded spec, with the motion instructions its recovery calls."""

    add_on: ir.AddOnInstruction
    instructions: tuple[SubInstruction, ...]
    main: ir.Spec = field(compare=False, repr=False)
    #: the spec directory the charts of the world come from (None: the bundled spec)
    spec_dir: str | None = field(default=None, compare=False)

    @property
    def id(self) -> str:
        return self.add_on.id

    @property
    def inputs(self) -> tuple[tuple[str, str, object], ...]:
        return tuple((p.name, p.type, p.default) for p in self.add_on.parameters)

    @property
    def outputs(self) -> tuple[tuple[str, str], ...]:
        return tuple((m.name, m.type) for m in self.add_on.status)

    @property
    def errors(self) -> tuple[tuple[int, str], ...]:
        return tuple((e.code, e.name) for e in self.add_on.errors)

    def binding(self, kind: str) -> ir.WorldObject:
        return self.add_on.world.object(kind)

    def instruction(self, mnemonic: str) -> SubInstruction:
        return next(i for i in self.instructions if i.mnemonic == mnemonic)

    def input_type(self, name: str) -> str:
        return self.add_on.parameter(name).type


def load_motion_calls(spec_dir: Path | None = None) -> tuple[SubInstruction, ...]:
    """The motion instructions as the recovery calls them (spec/instructions/motion/),
    checked as :func:`statecharts.loader.load_spec` checks them; SpecError with every problem."""
    root = spec_dir or bundled_spec_dir()
    errors: list[Diagnostic] = []
    documents: list[tuple[str, Any]] = []
    for p in sorted((root / "instructions" / "motion").glob("*.yaml")):
        tree = read_yaml(p, errors)
        if tree is not None:
            documents.append((str(p), tree))
    subs = build_sub_instructions(documents, errors)
    if errors:
        raise SpecError(errors)
    return subs


def load_aoi(spec_dir: Path | str | None = None) -> AoiSpec:
    """The add-on instruction of the spec in ``spec_dir`` (the bundled one by default); SpecError with every problem."""
    root = Path(spec_dir) if spec_dir else None
    main = load_spec([root]) if root else load_spec()  # the motion instructions of a directory included
    subs = load_motion_calls(root if root is None or root.is_dir() else None)
    if not main.add_ons:
        raise SpecError([Diagnostic(str(root or bundled_spec_dir()), 1, 1, "", "the spec defines no add_on_instruction")])
    add_on = main.add_ons[0]
    problems = undefined_calls([add_on], subs)
    if problems:
        raise SpecError(problems)
    return AoiSpec(add_on, subs, main, None if spec_dir is None else str(spec_dir))


_FOR_SPEC: dict[int, tuple[ir.Spec, AoiSpec]] = {}


def for_spec(spec: ir.Spec) -> AoiSpec:
    """The add-on instruction of a loaded spec, with the motion calls of the directory it came from."""
    hit = _FOR_SPEC.get(id(spec))
    if hit is not None and hit[0] is spec:
        return hit[1]
    bundled = bundled_aoi()
    if spec is bundled.main:
        return bundled
    if not spec.add_ons:
        raise SpecError([Diagnostic(spec.files[0] if spec.files else "spec", 1, 1, "",
                                    "the spec defines no add_on_instruction")])
    root = Path(spec.add_ons[0].location.file).parent.parent
    subs = load_motion_calls(root) if (root / "instructions" / "motion").is_dir() else bundled.instructions
    out = AoiSpec(spec.add_ons[0], subs, spec, str(root))
    _FOR_SPEC.clear()
    _FOR_SPEC[id(spec)] = (spec, out)
    return out


@functools.lru_cache(maxsize=1)
def bundled_aoi() -> AoiSpec:
    """The bundled add-on instruction spec, loaded once per process (it is immutable)."""
    return load_aoi()


# --------------------------------------------------------------------------- world

Snap = tuple[frozenset[str], tuple[object, ...]]


class ChartRunner:
    """Runs one chart of the main spec for every world object of that chart.

    A world object keeps its chart's configuration as a snapshot of the engine
    (:meth:`statecharts.engine.AxisInstance.snapshot`: active states, variable values).
    To fire an event the runner restores that snapshot into an engine
    :class:`~statecharts.engine.AxisInstance` of the chart, lets the engine run the
    event (its actions first for environment events, then python-statemachine's
    macrostep) and takes the snapshot again.  The engine is deterministic and the
    charts have no history states (the loader refuses them), so a snapshot and an
    event determine the next snapshot: results are memoised, which makes building
    thousands of worlds and exploring them affordable.
    """

    MEMO_LIMIT = 100_000

    def __init__(self, chart: Any, parameters: Mapping[str, int]) -> None:
        self.chart = chart
        self.parameters = dict(parameters)
        self.index = {v.name: i for i, v in enumerate(chart.variables)}
        self.events = frozenset(e.name for e in chart.events)
        self._leaves = tuple((st.id, st.value) for st in chart.leaf_states())
        self._inst: Any = None
        self._memo: dict[tuple[object, ...], Snap] = {}
        self._facts: dict[tuple[int, Snap], dict[str, object]] = {}

    def _engine(self) -> Any:
        from statecharts.engine import AxisInstance
        if self._inst is None:
            self._inst = AxisInstance(self.chart, self.chart.id, parameters=self.parameters)
        return self._inst

    def _remember(self, key: tuple[object, ...], snap: Snap) -> Snap:
        if len(self._memo) >= self.MEMO_LIMIT:
            self._memo.clear()
        self._memo[key] = snap
        return snap

    def initial(self, state: str | None, variables: Mapping[str, object]) -> Snap:
        """The snapshot of a fresh instance: in ``state`` (or the chart's initial state) with ``variables``."""
        from statecharts.engine import AxisInstance
        key = ("initial", state, tuple(sorted(variables.items())))
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        inst = AxisInstance(self.chart, self.chart.id, state=state, variables=variables, parameters=self.parameters)
        return self._remember(key, inst.snapshot())

    def send(self, snap: Snap, event: str) -> Snap:
        key = (snap, event)
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        inst = self._engine()
        inst.restore(snap)
        inst.apply_event_actions(event)
        inst.send(event)
        return self._remember(key, inst.snapshot())

    def assign(self, snap: Snap, name: str, value: object) -> Snap:
        """Give one variable a value, then let the eventless transitions it enables run."""
        from statecharts.engine import SETTLE_EVENT
        values = list(snap[1])
        values[self.index[name]] = value
        return self.send((snap[0], tuple(values)), SETTLE_EVENT)

    def leaf(self, active: frozenset[str]) -> tuple[str, int | None]:
        return next((sid, value) for sid, value in self._leaves if sid in active)

    def facts(self, binding: ir.WorldObject, snap: Snap) -> dict[str, object]:
        """Every fact of ``binding`` on the configuration ``snap``."""
        key = (id(binding), snap)
        hit = self._facts.get(key)
        if hit is not None:
            return hit
        env: dict[str, object] = {v.name: snap[1][i] for i, v in enumerate(self.chart.variables)}
        env["active"] = snap[0]
        env["state"] = self.leaf(snap[0])[0]
        out = {fb.name: (fb.when(env) if fb.when is not None else env[str(fb.variable)])
               for fb in binding.facts}  # the loader gives every fact a `when` or a `variable`
        if len(self._facts) >= self.MEMO_LIMIT:
            self._facts.clear()
        self._facts[key] = out
        return out


_RUNNERS: dict[tuple[int, tuple[tuple[str, int], ...]], ChartRunner] = {}


def chart_runner(chart: Any, scan_ms: int) -> ChartRunner:
    """The runner of ``chart`` for a world with scan (and coarse-update) period ``scan_ms``."""
    params = (("coarse_update_ms", scan_ms), ("scan_ms", scan_ms))
    key = (id(chart), params)
    runner = _RUNNERS.get(key)
    if runner is None or runner.chart is not chart:
        runner = _RUNNERS[key] = ChartRunner(chart, dict(params))
    return runner


class ChartObject:
    """A world object run by a chart: its binding, its runner and its current snapshot."""

    #: facts kept by the object itself when its binding does not read them from the chart
    PLAIN: ClassVar[dict[str, object]] = {}

    def __init__(self, name: str, binding: ir.WorldObject, runner: ChartRunner, snap: Snap) -> None:
        self.name = name
        self.binding = binding
        self.runner = runner
        self.snap = snap
        self.plain: dict[str, object] = {k: v for k, v in self.PLAIN.items() if binding.fact(k) is None}

    # -- the chart ------------------------------------------------------------------
    @property
    def chart_state(self) -> str:
        """The active leaf state (the first region's, for a chart with parallel regions)."""
        return self.runner.leaf(self.snap[0])[0]

    @property
    def chart_value(self) -> int | None:
        return self.runner.leaf(self.snap[0])[1]

    @property
    def active(self) -> frozenset[str]:
        return self.snap[0]

    def variable(self, name: str) -> object:
        return self.snap[1][self.runner.index[name]]

    def fire(self, event: str) -> None:
        """Send one event of the chart (environment actions first, as the main engine does)."""
        if event not in self.runner.events:
            raise ValueError(f"chart {self.runner.chart.id} has no event {event!r}; "
                             f"events: {', '.join(sorted(self.runner.events))}")
        self.snap = self.runner.send(self.snap, event)
        self._after_chart()

    def _after_chart(self) -> None:
        """Hook: the planner obeys what the chart did."""

    # -- facts ------------------------------------------------------------------------
    def fact(self, name: str) -> object:
        if name in self.plain:
            return self.plain[name]
        return self.runner.facts(self.binding, self.snap)[name]

    def set_fact(self, name: str, value: object) -> None:
        """Give a fact a value the way the binding says: fire its events or assign its variable.

        Nothing happens when the fact already has the value; the chart may refuse an
        event (an Enable on a Faulted axis is ignored), and then the fact keeps its value.
        """
        if name in self.plain:
            self.plain[name] = value
            return
        fb = self.binding.fact(name)
        if fb is None:
            raise KeyError(f"{self.name} has no fact {name!r}")
        if self.fact(name) == value:
            return
        if fb.variable is not None:
            self.snap = self.runner.assign(self.snap, fb.variable, value)
            self._after_chart()
            return
        for fs in fb.set:
            v, events = fs.value, fs.fire
            if v == value and type(v) is type(value):
                for e in events:
                    self.fire(e)
                return
        raise ValueError(f"{self.name}.{name} is read from chart {self.binding.chart} and cannot be set to {value!r}")


class Axis(ChartObject):
    """An axis: its chart (AxisCIP or AxisVirtual) and the motion planner's numbers.

    Positions, velocities, the move, homing and gearing in process, and configuration
    (unwind, control mode, home position, ...) are the planner's; the state-like facts
    (faulted, shut down, energized, ...) come from the chart through the binding.
    """

    PLAIN: ClassVar[dict[str, object]] = {"homed": True, "homing": False, "direct_control": False}

    def __init__(self, name: str, type: str, binding: ir.WorldObject, runner: ChartRunner, snap: Snap) -> None:
        super().__init__(name, binding, runner, snap)
        self.type = type
        self.position = 0.0
        self._velocity = 0.0
        self.unwind = 0.0
        self.control_mode = "position"
        self.home_config_ok = True
        self.home_position = 0.0
        self.geared = False
        self.master: str | None = None
        # motion in process (MAM): remaining signed distance and speed; homing by MAH
        self.move_remaining = 0.0
        self.move_speed = 0.0
        self.home_scans_left = 0

    PLANNER = ("position", "_velocity", "unwind", "control_mode", "home_config_ok", "home_position", "geared",
               "master", "move_remaining", "move_speed", "home_scans_left")

    # -- facts as attributes (what the checks, the calls and World.set use) ------------
    faulted = property(lambda self: self.fact("faulted"), lambda self, v: self.set_fact("faulted", v))
    shutdown = property(lambda self: self.fact("shutdown"), lambda self, v: self.set_fact("shutdown", v))
    energized = property(lambda self: self.fact("energized"), lambda self, v: self.set_fact("energized", v))
    homed = property(lambda self: self.fact("homed"), lambda self, v: self.set_fact("homed", v))
    homing = property(lambda self: self.fact("homing"), lambda self, v: self.set_fact("homing", v))
    direct_control = property(lambda self: self.fact("direct_control"),
                              lambda self, v: self.set_fact("direct_control", v))

    @property
    def tracking(self) -> bool:
        """The axis follows the planner (the motion in process advances)."""
        return bool(self.fact("tracking"))

    @property
    def can_move(self) -> bool:
        """A motion in process may go on: not faulted, not shut down, tracking or about to (INT-068)."""
        return not self.faulted and not self.shutdown and bool(self.tracking or self.fact("starting"))

    @property
    def velocity(self) -> float:
        return self._velocity

    @velocity.setter
    def velocity(self, value: float) -> None:
        self._velocity = value
        if self.binding.fact("moving") is not None:
            self.set_fact("moving", value != 0)
            if not self.fact("moving"):
                self._velocity = 0.0  # the chart refused the motion (faulted, shut down)

    def _after_chart(self) -> None:
        if self.binding.fact("moving") is not None and not self.fact("moving"):
            self._velocity = 0.0  # a fault, shutdown or stop of the chart ended the motion

    @property
    def rotary(self) -> bool:
        return self.unwind > 0

    def clock(self) -> None:
        """The motion update (coarse update) reaches the chart: its clock events."""
        for e in self.binding.on_scan:
            self.fire(e)

    def stop_motion(self) -> None:
        """Motion, homing and gearing in process end (MAS Stop All, or a fault / shutdown)."""
        self.move_remaining = 0.0
        self.home_scans_left = 0
        self.geared = False
        for e in self.binding.stop:
            self.fire(e)
        if "homing" in self.plain:
            self.plain["homing"] = False
        self.velocity = 0.0

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
        out["state"] = self.chart_state
        out[self.runner.chart.state_attribute] = self.chart_value
        return out

    def snapshot(self) -> tuple[object, ...]:
        return (self.snap, tuple(getattr(self, k) for k in self.PLANNER), tuple(sorted(self.plain.items())))

    def restore(self, snap: tuple[object, ...]) -> None:
        chart, planner, plain = cast("tuple[tuple[frozenset[str], tuple[object, ...]], tuple[object, ...], tuple[tuple[str, object], ...]]", snap)
        self.snap = chart
        for k, v in zip(self.PLANNER, planner):
            setattr(self, k, v)
        self.plain = dict(plain)


class Handler(ChartObject):
    """A device handler: its DeviceHandler chart plus its id and associated axes (configuration)."""

    def __init__(self, name: str, binding: ir.WorldObject, runner: ChartRunner, snap: Snap, *, id: int = 1,
                 phy_axis: str = "", pth_axis: str = "") -> None:
        super().__init__(name, binding, runner, snap)
        self.id = id
        self.phy_axis = phy_axis
        self.pth_axis = pth_axis

    eState = property(lambda self: self.fact("eState"), lambda self, v: self.set_fact("eState", v))
    mode = property(lambda self: self.fact("mode"), lambda self, v: self.set_fact("mode", v))
    OnPath = property(lambda self: self.fact("OnPath"), lambda self, v: self.set_fact("OnPath", v))
    registered = property(lambda self: self.fact("registered"), lambda self, v: self.set_fact("registered", v))
    capacity = property(lambda self: self.fact("capacity"), lambda self, v: self.set_fact("capacity", v))

    def register(self) -> int:
        """A method registers (the binding's `register` events); its order, or 0 when the registry is full."""
        before = self.registered
        for e in self.binding.register:
            self.fire(e)
        after = self.registered
        return as_int(after) if after != before else 0

    def observe(self) -> dict[str, object]:
        out = {"eState": self.eState, "mode": self.mode, "OnPath": self.OnPath, "registered": self.registered,
               "capacity": self.capacity}
        if self.binding.fact("running") is not None:
            out["running"] = self.fact("running")
        return out

    def snapshot(self) -> tuple[object, ...]:
        return (self.snap, self.id, self.phy_axis, self.pth_axis)

    def restore(self, snap: tuple[object, ...]) -> None:
        self.snap, self.id, self.phy_axis, self.pth_axis = cast("tuple[tuple[frozenset[str], tuple[object, ...]], int, str, str]", snap)


@dataclass
class PendingCall:
    instruction: SubInstruction
    axis: str
    done: bool = False
    err: int = 0
    aborted: bool = False  # the axis faulted, shut down or lost its power under it (INT-046, INT-068)


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


#: The order in which one `set:` applies its fields: resets before enables (MASR, MAFR, then MSO).
SET_ORDER = ("shutdown", "faulted", "energized")
#: Fields of a handler that are configuration of the instance, not chart facts.
HANDLER_CONFIG = ("id", "phy_axis", "pth_axis")
#: Axis fields that are the planner's numbers and configuration.
AXIS_PLANNER_FIELDS = ("position", "velocity", "unwind", "control_mode", "home_config_ok", "home_position")


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

    # -- state access (scenarios, the model checker) -----------------------------
    def _object(self, obj: str) -> Handler | Axis:
        target = self.handlers.get(obj) or self.axes.get(obj)
        if target is None:
            raise KeyError(f"unknown handler or axis {obj!r}")
        return target

    def set(self, obj: str, field: str, value: object) -> None:
        """What a scenario step's ``set:`` does to one handler or axis field (INT-069).

        A chart fact fires the chart events its binding names (``faulted: true`` on an
        AXIS_CIP_DRIVE is an axis fault, ``energized: true`` an Enable, ...) or assigns
        its variable; planner fields and handler configuration are assigned.  Nothing
        happens when the fact already has the value.
        """
        target = self._object(obj)
        if isinstance(target, Handler):
            if field not in _HANDLER_PROPS:
                raise KeyError(f"handler {obj} has no field {field!r}; fields: {', '.join(sorted(_HANDLER_PROPS))}")
        elif field not in _AXIS_PROPS or field == "type":
            raise KeyError(f"axis {obj} has no settable field {field!r}")
        setattr(target, field, value)

    def fire(self, obj: str, event: str) -> None:
        """Send one event to the chart of a handler or an axis (a step's ``events:``)."""
        self._object(obj).fire(event)

    def snapshot(self) -> tuple[object, ...]:
        """The whole mutable world state as a hashable, deterministic value (scan index excluded)."""
        def call(c: PendingCall | None) -> object:
            return None if c is None else (c.instruction.mnemonic, c.axis, c.done, c.err, c.aborted)

        return (
            tuple((n, h.snapshot()) for n, h in self.handlers.items()),
            tuple((n, a.snapshot()) for n, a in self.axes.items()),
            tuple((n, tuple(sorted(i.inputs.items())), tuple(sorted(i.outputs.items())), i.state,
                   i.path_verified, tuple(sorted(i.registrations.items())), call(i.call), i.move_type, i.move_target)
                  for n, i in self.instances.items()),
        )

    def restore(self, snap: tuple[object, ...]) -> None:
        """Put the world back into the state :meth:`snapshot` returned (the scan index is kept)."""
        hs, axs, insts = cast("tuple[tuple[tuple[str, Any], ...], tuple[tuple[str, Any], ...], tuple[tuple[Any, ...], ...]]", snap)
        for n, s in hs:
            self.handlers[n].restore(s)
        for n, s in axs:
            self.axes[n].restore(s)
        for n, inputs, outputs, state, verified, regs, call, mt, target in insts:
            i = self.instances[n]
            i.inputs = dict(inputs)
            i.outputs = dict(outputs)
            i.state = state
            i.path_verified = verified
            i.registrations = dict(regs)
            i.call = None if call is None else PendingCall(self.spec.instruction(call[0]), call[1], call[2], call[3], call[4])
            i.move_type = mt
            i.move_target = target

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
        tol_f = as_float(tol) if _finite(tol) else 0.0
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
                for n in self.spec.add_on.prescan.clear:
                    inst.outputs[n] = False if isinstance(inst.outputs[n], bool) else 0
                if "path_verified" in self.spec.add_on.prescan.forget:
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
        if h is not None and h.name not in inst.registrations:
            order = h.register()
            if order:
                inst.registrations[h.name] = h.id * 1000 + order
        inst.outputs["Sts_MtdID"] = inst.registrations.get(h.name, 0) if h else 0

    def _rung_false(self, inst: Instance) -> None:
        if inst.call is not None and not inst.call.done and self.spec.add_on.rung_false.abort_call:
            self._issue_stop(inst)
        inst.call = None
        for n in self.spec.add_on.rung_false.clear:
            inst.outputs[n] = False
        inst.state = "idle"

    def _issue_stop(self, inst: Instance) -> None:
        """MAS (Stop Type All) on the physical axis: motion, homing and gearing stop."""
        self.axes[str(inst.inputs["Ref_AxisPhy"])].stop_motion()

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
            inst.state = self.spec.add_on.recovery.initial
        env = self.env(inst)
        if inst.state == "checking":
            for c in self.spec.add_on.checks:
                if c.fails_when(env):
                    self._error(inst, c.err)
                    return
            inst.move_type = as_int(env["move.type"])
            inst.move_target = as_float(env["move.target"])
        for _ in range(len(self.spec.add_on.recovery.states) + 1):
            nxt = next((t.target for t in self.spec.add_on.recovery.transitions
                        if t.source == inst.state and t.when(env)), None)
            if nxt is None:
                return
            self._enter(inst, nxt)
            if inst.state in ("error", "done"):
                return
            env = self.env(inst)

    def _enter(self, inst: Instance, sid: str) -> None:
        inst.state = sid
        inst.call = None
        st = self.spec.add_on.recovery.state(sid)
        if sid == "done":
            env = self.env(inst)
            for od in self.spec.add_on.on_done:
                if od.when(env):
                    target = od.set
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
            axis.move_speed = as_float(ops["Speed"])
            axis.move_remaining = signed_distance(axis.position, as_float(ops["Position"]), axis.unwind,
                                                  as_int(ops["MoveType"]))
            if axis.move_remaining == 0:
                inst.call.done = True
        elif sub.kind == "gear":
            axis.geared = True
            axis.master = str(inst.inputs["Ref_AxisPth"])
            inst.call.done = True  # DN = gearing initiated
        elif sub.kind == "redefine":
            axis.position = unwind(as_float(ops["Position"]), axis.unwind)
            inst.call.done = True

    def _motion_update(self) -> None:
        """The motion task's update at the end of the scan (the coarse update, INT-068):
        the charts' clocks first, then the planner advances what the charts allow."""
        dt = self.scan_ms / 1000.0
        for a in self.axes.values():
            a.clock()
        for a in self.axes.values():
            if not a.geared and a.move_remaining == 0 and not a.homing and a.type == "AXIS_VIRTUAL":
                a.position = unwind(a.position + a.velocity * dt, a.unwind)
        stopped: set[str] = set()
        for a in self.axes.values():
            if (a.home_scans_left > 0 or a.move_remaining != 0 or a.geared) and not a.can_move:
                # a fault, a shutdown or the loss of power stops the axis and ends its
                # motion (INT-046, INT-068)
                a.stop_motion()
                stopped.add(a.name)
        for a in self.axes.values():
            if not a.tracking:
                continue  # Starting: the motion in process waits for Running
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
            if ((c.instruction.kind == "home" and axis.home_scans_left <= 0 and axis.homed)
                    or (c.instruction.kind == "move" and axis.move_remaining == 0)):
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
    events: tuple[tuple[str, tuple[str, ...]], ...] = ()


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


def _set_rank(item: tuple[str, object]) -> tuple[int, str]:
    """Fields of one `set:` apply resets first, then enables (SET_ORDER), then the rest by name."""
    return (SET_ORDER.index(item[0]) if item[0] in SET_ORDER else len(SET_ORDER), item[0])


def _check_chart_setup(parts: tuple[Any, ...], entry: Mapping[str, Any], binding: ir.WorldObject, chart: Any,
                       err: Any) -> None:
    """`state:`, `variables:` and `events:` of a set-up entry name things of its chart; fields the
    chart decides alone keep their defaults."""
    states = {st.id: st for st in chart.states}
    if "state" in entry:
        sid = entry["state"]
        if sid not in states:
            err((*parts, "state"), f"chart {chart.id} has no state {sid!r}; states: {', '.join(sorted(states))}")
        elif any(states[a].kind.value == "parallel" for a in chart.ancestors(sid)) or states[sid].kind.value == "parallel":
            err((*parts, "state"), f"chart {chart.id} has parallel regions: it cannot be started in {sid!r}; "
                                   "use `events:` (or the fields) instead")
        chosen = {n for r in binding.setup.rules
                  for n in (*r.when.names, *(m for _name, e in r.variables for m in e.names))}
        flags = sorted(chosen & set(entry))
        if flags:
            err((*parts, "state"), f"give either `state:` or the field(s) {', '.join(flags)}, which choose the state")
    variables = {v.name: v for v in chart.variables}
    for k, v in entry.get("variables", {}).items():
        if k not in variables:
            err((*parts, "variables", k), f"chart {chart.id} has no variable {k!r}")
        elif variables[k].domain is not None and v not in variables[k].domain:
            err((*parts, "variables", k), f"{v!r} is not in the domain of {k}: {list(variables[k].domain)!r}")
    events = {e.name for e in chart.events}
    for j, ev in enumerate(entry.get("events", [])):
        if ev not in events:
            err((*parts, "events", j), f"chart {chart.id} has no event {ev!r}; events: {', '.join(sorted(events))}")
    used = {n for _name, e in binding.setup.variables for n in e.names} | set(binding.setup.then_set)
    for r in binding.setup.rules:
        used |= set(r.when.names) | {n for _name, e in r.variables for n in e.names}
    defaults = HANDLER_DEFAULTS if binding.kind == "handler" else AXIS_DEFAULTS
    for fb in binding.facts:
        if fb.name in entry and fb.name not in used and fb.variable is None and entry[fb.name] != defaults.get(fb.name):
            err((*parts, fb.name), f"{fb.name} of a {binding.kind} is read from chart {chart.id} and cannot be "
                                   f"{entry[fb.name]!r} at set-up")


def _oversized_integers(name: str, tree: Any) -> list[Diagnostic]:
    """Integers no Logix tag holds (beyond LINT) and no REAL can stand for: refused, located
    (NaN and infinities stay allowed: they are inputs the add-on instruction checks)."""
    out: list[Diagnostic] = []
    stack: list[tuple[Any, tuple[Any, ...]]] = [(tree, ())]
    while stack:
        node, parts = stack.pop()
        if isinstance(node, Mapping):
            stack.extend((v, (*parts, k)) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, (*parts, i)) for i, v in enumerate(node))
        elif isinstance(node, int) and not isinstance(node, bool) and not -(2**63) <= node < 2**63:
            line, col = locate(tree, parts)
            out.append(Diagnostic(name, line, col, node_path(parts), "integer beyond 64 bits (the LINT range)"))
    return out


def load_aoi_scenario(path: Path | str, tree: Any, spec: AoiSpec) -> AoiScenario:
    """Check an AOI scenario (already parsed) against its schema and the AOI spec."""
    name = str(path)
    errors: list[Diagnostic] = list(schema_diagnostics(name, tree, _schema("aoi-scenario.schema.json"), "an add-on instruction scenario"))
    errors.extend(_oversized_integers(name, tree))
    if errors:
        raise ScenarioError(errors)
    doc = plain_data(tree)

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
    charts = {c.id: c for c in spec.main.charts}
    objects: dict[str, set[str]] = {}
    bindings: dict[str, ir.WorldObject] = {}
    for hname, h in setup["handlers"].items():
        bindings[hname] = b = spec.binding("handler")
        objects[hname] = {"eState", "mode", "OnPath", "registered", "capacity"} | (
            {"running"} if b.fact("running") else set())
        _check_chart_setup(("setup", "handlers", hname), h, b, charts[b.chart], err)
    for aname, a in setup["axes"].items():
        bindings[aname] = b = spec.binding(a["type"])
        objects[aname] = {"position", "velocity", "homed", "energized", "faulted", "shutdown", "geared", "homing",
                          "direct_control", "moving", "state", charts[b.chart].state_attribute}
        _check_chart_setup(("setup", "axes", aname), a, b, charts[b.chart], err)
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
                else:
                    fb = bindings[obj].fact(k)
                    if fb is not None and fb.variable is None and not fb.set:
                        err((*p, "set", obj, k), f"{obj}.{k} is read from chart {bindings[obj].chart} and cannot be set "
                                                 f"(a {bindings[obj].kind} has no event for it)")
        for obj, names in s.get("events", {}).items():
            if obj not in bindings:
                err((*p, "events", obj), f"unknown handler or axis {obj!r}")
                continue
            chart = charts[bindings[obj].chart]
            known_events = {e.name for e in chart.events}
            for j, ev in enumerate(names):
                if ev not in known_events:
                    err((*p, "events", obj, j), f"chart {chart.id} of {obj} has no event {ev!r}; events: {', '.join(sorted(known_events))}")
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
            tuple((k, tuple(sorted(v.items(), key=_set_rank))) for k, v in sorted(s.get("set", {}).items())),
            tuple(expect), line,
            tuple((k, tuple(v)) for k, v in sorted(s.get("events", {}).items()))))
    if errors:
        raise ScenarioError(errors)
    return AoiScenario(name, doc["name"], str(doc.get("description", "")), tuple(doc.get("sources", [])),
                       tuple(doc.get("covers", [])), int(setup.get("scan_ms", 10)), setup, tuple(steps))


#: The values of a scenario's axis and handler fields when the set-up does not give them.
AXIS_DEFAULTS: dict[str, object] = {
    "position": 0.0, "velocity": 0.0, "unwind": 0.0, "homed": True, "energized": True, "faulted": False,
    "shutdown": False, "control_mode": "position", "direct_control": False, "home_config_ok": True,
    "home_position": 0.0, "homing": False,
}
HANDLER_DEFAULTS: dict[str, object] = {
    "id": 1, "registered": 0, "capacity": 10, "eState": 7, "mode": "physical", "phy_axis": "", "pth_axis": "",
    "OnPath": False,
}
#: Set-up keys that are not fields: the chart's state, variables and events (docs/aoi.md).
CHART_SETUP_KEYS = ("state", "variables", "events")


def _initial_snap(binding: ir.WorldObject, runner: ChartRunner, fields: Mapping[str, object],
                  entry: Mapping[str, Any]) -> Snap:
    """The chart's first configuration: the binding's set-up rules, or an explicit `state:`."""
    variables = {name: e(fields) for name, e in binding.setup.variables}
    state = None
    if "state" in entry:
        state = str(entry["state"])
    else:
        for r in binding.setup.rules:
            if r.when(fields):
                state = r.state
                variables.update({name: e(fields) for name, e in r.variables})
                break
    variables.update(entry.get("variables", {}))
    return runner.initial(state, variables)


def build_world(spec: AoiSpec, setup: Mapping[str, Any]) -> World:
    """The world of a set-up (the `setup:` of a scenario): every object on its chart (INT-069)."""
    charts = {c.id: c for c in spec.main.charts}
    scan_ms = int(setup.get("scan_ms", 10))
    handlers = []
    hb = spec.binding("handler")
    hrun = chart_runner(charts[hb.chart], scan_ms)
    for n, h in setup["handlers"].items():
        fields = {**HANDLER_DEFAULTS, **{k: v for k, v in h.items() if k not in CHART_SETUP_KEYS}}
        obj = Handler(n, hb, hrun, _initial_snap(hb, hrun, fields, h), id=as_int(fields["id"]),
                      phy_axis=str(fields["phy_axis"]), pth_axis=str(fields["pth_axis"]))
        for name in hb.setup.then_set:
            obj.set_fact(name, fields[name])
        for e in h.get("events", []):
            obj.fire(e)
        handlers.append(obj)
    axes = []
    for n, a in setup["axes"].items():
        b = spec.binding(a["type"])
        run = chart_runner(charts[b.chart], scan_ms)
        fields = {**AXIS_DEFAULTS, **{k: v for k, v in a.items() if k not in CHART_SETUP_KEYS}}
        ax = Axis(n, a["type"], b, run, _initial_snap(b, run, fields, a))
        for name in b.setup.then_set:
            ax.set_fact(name, fields[name])
        for k in ("homed", "homing", "direct_control"):
            if k in ax.plain:
                ax.plain[k] = fields[k]
        ax.unwind = as_float(fields["unwind"])
        ax.position = unwind(as_float(fields["position"]), ax.unwind)
        ax.control_mode = str(fields["control_mode"])
        ax.home_config_ok = bool(fields["home_config_ok"])
        ax.home_position = as_float(fields["home_position"])
        for e in a.get("events", []):
            ax.fire(e)
        ax.velocity = as_float(fields["velocity"])
        axes.append(ax)
    instances = []
    for n, ops in setup["aoi"].items():
        ops = dict(ops)
        verified = bool(ops.pop("path_verified", False))
        instances.append(Instance(n, ops, path_verified=verified))
    return World(spec, handlers, axes, instances, scan_ms=scan_ms)


def run_aoi_scenario(scenario: AoiScenario, spec: AoiSpec) -> Any:
    """Run the scenario; returns a :class:`statecharts.scenario.ScenarioResult`."""
    from statecharts.scan import ScanRecord
    from statecharts.scenario import Mismatch, ScanRow, ScenarioResult, same_value

    world = build_world(spec, scenario.setup)
    before = world.observe()
    rows = []
    mismatches = []
    for step in scenario.steps:
        for inst_name, ops in step.operands:
            world.instances[inst_name].inputs.update(dict(ops))
        for obj, fields in step.sets:
            for k, v in fields:
                world.set(obj, k, v)
        for obj, events in step.events:
            for e in events:
                world.fire(obj, e)
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
            if not same_value(expected, actual):
                mismatches.append(Mismatch(step.index, step.name, world.index, obj, fld, expected, actual, step.line))
    return ScenarioResult(scenario, tuple(rows), tuple(mismatches))  # type: ignore[arg-type]  # callers read only fields both scenarios have

