"""An add-on instruction as an instruction of the main scan (Level execution).

Pipeline position: :class:`statecharts.ir.AddOnInstruction` (``spec/addons/*.yaml``,
built by :mod:`statecharts.addon_loader`) -> **this module** -> :class:`statecharts.scan.System`,
which scans an :class:`AddOnInstance` in program order like a MOTION_INSTRUCTION tag.

Everything the instance does is read from the IR: the ordered checks, the recovery
chart, ``on_done``, ``rung_false`` and ``prescan``.  The motion instructions its recovery
states call are the main spec's instruction charts (MAH, MAM, MAG, MRP, MAS), run as
the instance's own MOTION_INSTRUCTION tags (:class:`statecharts.scan.TagInstance`) on the
main axes, so motion comes from the drive model (:mod:`statecharts.drive`).  The facts the
checks read (``phy.faulted``, ``handler.mode``...) are the ``world:`` facts of the add-on
instruction, evaluated over the chart instances its InOut parameters name.  The rules
are written out in docs/semantics.md ("Add-on instructions: Level execution").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, cast

from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.rotary import effective_move_type, signed_distance, unwind

if TYPE_CHECKING:
    from statecharts.scan import System, TagInstance

#: The recovery states an instance is in between executions and at their ends.
IDLE, ERROR, DONE = "idle", "error", "done"


def _finite(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _number(value: object) -> float:
    return float(value) if isinstance(value, (int, float)) else math.nan


class AddOnInstance:
    """One tag of an add-on instruction in the program: its parameters, status, local
    tags, recovery state and the MOTION_INSTRUCTION tags of the calls it makes."""

    def __init__(self, name: str, add_on: ir.AddOnInstruction, system: System,
                 operands: Mapping[str, object]) -> None:
        from statecharts.scan import TagInstance

        self.name = name
        self.add_on = add_on
        self.system = system
        self.inputs: dict[str, object] = {p.name: p.default for p in add_on.parameters}
        self.inputs.update(operands)
        self.status: dict[str, object] = {m.name: False if m.type == "BOOL" else 0 for m in add_on.status}
        self.locals: dict[str, object] = {v.name: v.initial for v in add_on.local_tags}
        self.state = IDLE
        #: handler name -> the method id its registration gave
        self.method_ids: dict[str, int] = {}
        self.rung = False
        #: recovery state id -> the name of the tag of its call; (axis alias) -> the abort call's tag
        self.call_tags: dict[str, str] = {}
        self.abort_tags: dict[str, str] = {}
        sites: dict[tuple[str, str, str | None], str] = {}
        calls = [(s.id, s.call.instruction, s.call.axis, s.call.master) for s in add_on.recovery.states if s.call]
        abort = add_on.rung_false.abort_call
        if abort:
            calls += [("", abort, alias, None) for alias in dict.fromkeys(c[2] for c in calls)]
        for sid, mnemonic, alias, master in calls:
            key = (mnemonic, alias, master)
            if key not in sites:
                same = sum(1 for k in sites if k[0] == mnemonic)
                sites[key] = tag = f"{name}.{mnemonic}" + (f"_{same + 1}" if same else "")
                axis = self.axis_name(alias)
                ins = system.variant(mnemonic, axis)
                system.tags[tag] = TagInstance(tag, ins, system.spec.tag_type, axis,
                                               self.axis_name(master) if master else None)
            if sid:
                self.call_tags[sid] = sites[key]
            else:
                self.abort_tags[alias] = sites[key]

    # -- the objects the parameters name --------------------------------------------

    def axis_name(self, alias: str) -> str:
        return str(self.inputs[self.add_on.parameter(alias).name])

    def _handler(self) -> AxisInstance | None:
        par = next((p for p in self.add_on.parameters if p.type == "handle"), None)
        return self.system.axes.get(str(self.inputs[par.name])) if par else None

    def _binding(self, obj: AxisInstance) -> ir.WorldObject | None:
        return next((o for o in self.add_on.world.objects if o.chart == obj.chart.id), None)

    def facts(self, obj: AxisInstance) -> dict[str, object]:
        """The ``world:`` facts of one chart instance (its variables, ``active``, ``state``)
        and its chart parameters."""
        env: dict[str, object] = dict(obj.env)
        env["active"] = obj.active
        env["state"] = obj.leaf.id
        out: dict[str, object] = {cp.name: obj.env.get(cp.name, cp.default) for cp in obj.chart.parameters}
        binding = self._binding(obj)
        for fb in binding.facts if binding else ():
            out[fb.name] = fb.when(env) if fb.when is not None else env[str(fb.variable)]
        out["name"] = obj.name
        return out

    def _fire(self, obj: AxisInstance, fact: str, value: object) -> None:
        """Give a fact a value the way the binding says: send its events."""
        binding = self._binding(obj)
        fb = binding.fact(fact) if binding else None
        for fs in fb.set if fb else ():
            if fs.value == value:
                for event in fs.fire:
                    obj.apply_event_actions(event)
                    obj.send(event)

    def env(self) -> dict[str, object]:
        """What the checks, transitions and call operands read (docs/aoi.md)."""
        env: dict[str, object] = dict(self.inputs)
        env.update(self.locals)
        for p in self.add_on.parameters:
            if p.type == "REAL":
                env[f"{p.name}.finite"] = _finite(self.inputs.get(p.name))
            if p.alias is not None:
                obj = self.system.axes.get(str(self.inputs.get(p.name)))
                if obj is not None:
                    env.update({f"{p.alias}.{k}": v for k, v in self.facts(obj).items()})
        handler = self._handler()
        env["registered"] = handler is not None and handler.name in self.method_ids
        phy_p, pth_p = _number(env.get("phy.position")), _number(env.get("pth.position"))
        u = _number(env.get("phy.unwind"))
        u = u if math.isfinite(u) else 0.0
        mt, tol = self.inputs.get("Cfg_MoveType"), self.inputs.get("Cfg_RotaryShortestTOL")
        mt_i = int(mt) if isinstance(mt, int) and not isinstance(mt, bool) else -1
        eff = effective_move_type(phy_p, pth_p, u, mt_i, _number(tol) if _finite(tol) else 0.0)
        env["distance.magnitude"] = abs(signed_distance(phy_p, pth_p, u, eff))
        env["move.type"] = eff
        env["move.target"] = unwind(pth_p, u)
        tag = self.call()
        env["call.done"] = tag is not None and self.done(tag)
        return env

    # -- the call in process ----------------------------------------------------------

    def call(self) -> TagInstance | None:
        """The tag of the current recovery state's call, if it has one."""
        name = self.call_tags.get(self.state)
        return self.system.tags[name] if name else None

    @staticmethod
    def done(tag: TagInstance) -> bool:
        """The call has done its work: PC for an instruction whose process completes, else DN."""
        process = tag.instruction.process
        member = "PC" if process is not None and process.complete_when is not None else "DN"
        return bool(tag.values[member])

    def _ended(self, tag: TagInstance) -> bool:
        """The call's process ended without completing (a fault, a shutdown, a stop: INT-046)."""
        return bool(tag.values["DN"]) and not tag.values["IP"] and not self.done(tag)

    def _issue(self, tag: TagInstance, operands: Mapping[str, object]) -> None:
        """The call's rung goes true: the instruction executes (its rung-false row first,
        so that a finished earlier execution leaves EN)."""
        tag.operands.update({o.name: o.default for o in tag.instruction.operands if o.name in tag.operands})
        tag.operands.update(operands)
        self.system.motion_row(tag, "rung_false")
        self.system.motion_row(tag, "rung_true")

    # -- one scan -------------------------------------------------------------------

    def scan(self, condition: str) -> None:
        """One scan of the instance with its rung-condition-in (``rung_true`` / ``rung_false``)
        or on a prescan pass (``prescan``)."""
        self._register()
        if condition == "rung_true":
            self._rung_true()
        else:
            self._rung_false()
        if condition == "prescan":
            rule = self.add_on.prescan
            for n in rule.clear:
                self.status[n] = False if isinstance(self.status[n], bool) else 0
            for v in self.add_on.local_tags:
                if v.name in rule.forget:
                    self.locals[v.name] = v.initial
        current = self.call_tags.get(self.state) if condition == "rung_true" else None
        for tag in dict.fromkeys((*self.call_tags.values(), *self.abort_tags.values())):
            if tag != current:
                self.system.motion_row(self.system.tags[tag], "rung_false")

    def _register(self) -> None:
        """Registration with the handler Ref_Handle names, once (INT-021): Sts_MtdID."""
        handler = self._handler()
        binding = self._binding(handler) if handler is not None else None
        if handler is not None and binding is not None and handler.name not in self.method_ids:
            before = self.facts(handler).get("registered")
            for event in binding.register:
                handler.apply_event_actions(event)
                handler.send(event)
            facts = self.facts(handler)
            if facts.get("registered") != before:
                self.method_ids[handler.name] = int(cast("int", facts["id"])) * 1000 + int(cast("int", facts["registered"]))
        if "Sts_MtdID" in self.status:
            self.status["Sts_MtdID"] = self.method_ids.get(handler.name, 0) if handler is not None else 0

    def _rung_false(self) -> None:
        """The rung-false routine (INT-029): a call still in process is stopped with the
        abort call on its axis; the status bits of the rule are cleared."""
        rule = self.add_on.rung_false
        tag = self.call()
        if (tag is not None and rule.abort_call and tag.instruction.process is not None
                and not self.done(tag) and not tag.values["ER"]):
            alias = next(s.call.axis for s in self.add_on.recovery.states if s.id == self.state and s.call)
            self._issue(self.system.tags[self.abort_tags[alias]], {})
        for n in rule.clear:
            self.status[n] = False
        self.state = IDLE

    def _error(self, code: int, exerr: int = 0) -> None:
        self.status.update(Sts_ER=True, Sts_ERR=code, Sts_EXERR=exerr, Sts_IP=False, Sts_PC=False)
        self.state = ERROR

    def _rung_true(self) -> None:
        self.status["Sts_EN"] = True
        self.status["Sts_EO"] = True
        if self.state in (ERROR, DONE):
            return  # latched until the rung goes false (INT-029)
        tag = self.call()
        if tag is not None and tag.values["ER"]:
            self._error(int(self.add_on.recovery.state(self.state).error or 0), int(cast("int", tag.values["ERR"])))
            return
        if tag is not None and self._ended(tag):
            self.status["Sts_IP"] = False  # nothing in process; no PC, no error (INT-046)
            return
        if self.state == IDLE:
            self.status.update(Sts_ER=False, Sts_ERR=0, Sts_EXERR=0, Sts_PC=False, Sts_IP=False)
            self.state = self.add_on.recovery.initial
        env = self.env()
        if self.state == self.add_on.recovery.initial:
            for c in self.add_on.checks:
                if c.fails_when(env):
                    self._error(c.err)
                    return
        for _ in range(len(self.add_on.recovery.states)):
            nxt = next((t.target for t in self.add_on.recovery.transitions
                        if t.source == self.state and t.when(env)), None)
            if nxt is None:
                return
            self._enter(nxt, env)
            if self.state in (ERROR, DONE):
                return
            env = self.env()

    def _enter(self, sid: str, env: Mapping[str, object]) -> None:
        self.state = sid
        if sid == DONE:
            for od in self.add_on.on_done:
                if od.when(env):
                    alias, _, fact = od.set.rpartition(".")
                    obj = self.system.axes.get(self.axis_name(alias)) if alias else None
                    if obj is not None:
                        self._fire(obj, fact, True)
                    else:
                        self.locals[fact] = True
            self.status.update(Sts_IP=False, Sts_PC=True)
            return
        st = self.add_on.recovery.state(sid)
        tag = self.call()
        if st.call is None or tag is None:
            return
        self._issue(tag, {k: e(env) for k, e in st.call.operands})
        if tag.values["ER"]:
            self._error(int(st.error or 0), int(cast("int", tag.values["ERR"])))
            return
        self.status["Sts_IP"] = True

    # -- state and observation ---------------------------------------------------------

    def snapshot(self) -> tuple[object, ...]:
        return (tuple(self.inputs.values()), tuple(self.status.values()), tuple(self.locals.values()), self.state,
                tuple(sorted(self.method_ids.items())), self.rung)

    def restore(self, snap: tuple[object, ...]) -> None:
        inputs, status, local, self.state, ids, self.rung = cast("tuple[Any, Any, Any, str, Any, bool]", snap)
        self.inputs.update(zip(self.inputs, inputs))
        self.status.update(zip(self.status, status))
        self.locals.update(zip(self.locals, local))
        self.method_ids = dict(ids)

    def observe(self) -> dict[str, object]:
        return {**self.status, "state": self.state, **self.locals}

    def preset(self, values: Mapping[str, object]) -> None:
        """Status members and local tags set before the first scan (a scenario's ``preset:``)."""
        for k, v in values.items():
            (self.status if k in self.status else self.locals)[k] = v


# --------------------------------------------------------------------------- scenario checks

def check_operands(add_on: ir.AddOnInstruction, given: Mapping[str, object], charts: Mapping[str, ir.Chart],
                   parts: tuple[Any, ...], err: Any) -> dict[str, object]:
    """The operands of a program entry (or a step) for ``add_on``; each problem goes to
    ``err(parts, message)``.  ``charts`` maps the set-up's axes and devices to their charts."""
    out: dict[str, object] = {}
    params = {p.name: p for p in add_on.parameters}
    for name, value in given.items():
        par = params.get(name)
        if par is None:
            err((*parts, name), f"{add_on.id} has no parameter {name!r}; parameters: {', '.join(params)}")
            continue
        problem = None
        if par.type == "BOOL" and not isinstance(value, bool):
            problem = f"expected true or false, got {value!r}"
        elif par.type == "DINT" and (isinstance(value, bool) or not isinstance(value, int) or not -2**31 <= value < 2**31):
            problem = f"expected a DINT (whole number in 32 bits), got {value!r}"
        elif par.type == "REAL" and (isinstance(value, bool) or not isinstance(value, (int, float))):
            problem = f"expected a number (.nan and .inf are allowed), got {value!r}"
        elif par.type in ("axis", "handle"):
            fits = sorted(n for n, c in charts.items() if par.data_type in c.axis_types)
            if value not in fits:
                problem = f"expected the name of a {par.data_type} of the set-up ({', '.join(fits) or 'none'}), got {value!r}"
        if problem:
            err((*parts, name), f"{name}: {problem}")
        else:
            out[name] = value
    return out


def check_preset(add_on: ir.AddOnInstruction, given: Mapping[str, object], parts: tuple[Any, ...],
                 err: Any) -> dict[str, object]:
    """``preset:`` of an add-on instruction entry: status members and local tags."""
    out: dict[str, object] = {}
    for name, value in given.items():
        problem = observable_problem(add_on, name, value)
        if problem or name == "state":
            err((*parts, name), f"{name}: {problem or 'the recovery state cannot be preset'}")
        else:
            out[name] = value
    return out


def observable_problem(add_on: ir.AddOnInstruction, name: str, value: object) -> str | None:
    """Why ``value`` can never be observed in ``name`` of an instance of ``add_on``, or None."""
    types = {m.name: m.type for m in add_on.status}
    types.update({v.name: "BOOL" if v.type == "bool" else "DINT" for v in add_on.local_tags})
    if name == "state":
        states = [s.id for s in add_on.recovery.states] + [ERROR]
        return None if value in states else f"expected one of the recovery states {', '.join(states)}, got {value!r}"
    if name not in types:
        return f"{add_on.id} has no observable {name!r}; expected one of: {', '.join([*types, 'state'])}"
    if types[name] == "BOOL":
        return None if isinstance(value, bool) else f"expected true or false, got {value!r}"
    return None if isinstance(value, int) and not isinstance(value, bool) else f"expected an integer, got {value!r}"
