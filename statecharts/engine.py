"""The engine: IR charts -> python-statemachine ``StateChart`` classes.

Pipeline position: IR -> **engine** -> scan semantics (:mod:`statecharts.scan`).
python-statemachine's SCXML processing model (run-to-completion macrosteps, document
order among enabled transitions, eventless transitions after every event, child
transitions before their ancestors') is the reference semantics; this module only
translates.  Guards and actions are the compiled closures of the IR, bound to one
:class:`AxisInstance`'s variables through a per-chart model class whose methods
python-statemachine resolves by name when the machine is created.

Priorities: transitions of one source state and event are declared in ascending
``priority`` and then spec order, so the library's document-order choice is our
priority rule.

Public API::

    >>> from statecharts.loader import load_spec
    >>> spec = load_spec()
    >>> axis = AxisInstance(spec.chart("AxisNonCIP"), "Axis1")
    >>> sorted(axis.active)
    ['AxisReady', 'Operating']
    >>> axis.send("servo_on"); axis.value
    2
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from statemachine import StateChart
from statemachine.io import create_machine_class_from_definition

from statecharts import ir
from statecharts.expr import Assignment, EvalError

#: Values of the system parameters that axis-chart expressions may read.
DEFAULT_PARAMETERS: dict[str, int] = {"coarse_update_ms": 10, "scan_ms": 10}


#: An event no chart declares: sending it only lets eventless transitions run.
SETTLE_EVENT = "_settle"


#: Most eventless transitions one macrostep (the processing of one event) may take.
MAX_MICROSTEPS = 1000


class EventlessLoopError(EvalError):
    """Eventless transitions kept firing within one macrostep: a cycle the loader could
    not rule out (its guards read variables without a finite domain)."""


class ChartModel:
    """The model object python-statemachine calls back into; holds one axis's variables.

    ``microsteps`` counts the eventless transitions taken since the last event was sent
    (see :data:`MAX_MICROSTEPS`)."""

    env: dict[str, object]
    microsteps: int = 0
    #: while set, eventless guards are false: :meth:`AxisInstance.send` holds them while the
    #: event it sends selects its transitions (see there)
    hold_eventless: bool = False

    def __init__(self, env: dict[str, object]) -> None:
        self.env = env


def _guard_method(guard: Callable[[Mapping[str, object]], object]) -> Callable[..., bool]:
    def method(self: ChartModel, *args: object, **kwargs: object) -> bool:
        return bool(guard(self.env))

    return method


def _eventless_guard_method(
    chart_id: str, t: ir.Transition, guard: Callable[[Mapping[str, object]], object]
) -> Callable[..., bool]:
    def method(self: ChartModel, *args: object, **kwargs: object) -> bool:
        if self.hold_eventless:
            return False
        taken = bool(guard(self.env))
        if taken:
            self.microsteps += 1
            if self.microsteps > MAX_MICROSTEPS:
                raise EventlessLoopError(
                    f"chart {chart_id}: eventless transition {t.id!r} (from {t.source!r}, {t.location}) "
                    f"is still enabled after {MAX_MICROSTEPS} eventless transitions in one macrostep: "
                    "an eventless loop", t.guard.text if t.guard is not None else "")
        return taken

    return method


def _action_method(actions: tuple[Assignment, ...]) -> Callable[..., None]:
    def method(self: ChartModel, *args: object, **kwargs: object) -> None:
        for a in actions:
            a.apply(self.env)

    return method


def ordered_transitions(transitions: Iterable[ir.Transition]) -> list[ir.Transition]:
    """Transitions in the order they are tried: by priority, then in document order."""
    indexed = list(enumerate(transitions))
    return [t for _, t in sorted(indexed, key=lambda it: (it[1].priority, it[0]))]


@functools.cache
def machine_class(chart: ir.Chart) -> tuple[type[StateChart[Any]], type[ChartModel]]:
    """The python-statemachine class for ``chart`` and the model class its names resolve on.

    This is also the documented way to embed a chart in one's own code: instantiate
    ``Model(env)`` with a dict of variables, then ``Machine(model=...)``.
    """
    model_attrs: dict[str, Any] = {}
    by_parent: dict[str | None, list[ir.State]] = {}
    for s in chart.states:
        by_parent.setdefault(s.parent, []).append(s)

    def define(state: ir.State) -> dict[str, Any]:
        d: dict[str, Any] = {"name": state.name, "value": state.id}
        if state.entry:
            model_attrs[f"enter__{state.id}"] = _action_method(state.entry)
            d["enter"] = [f"enter__{state.id}"]
        if state.exit:
            model_attrs[f"exit__{state.id}"] = _action_method(state.exit)
            d["exit"] = [f"exit__{state.id}"]
        if state.kind is ir.StateKind.FINAL:
            d["final"] = True
        if state.kind is ir.StateKind.PARALLEL:
            d["parallel"] = True
        children = [c for c in by_parent.get(state.id, []) if c.kind is not ir.StateKind.HISTORY]
        history = [c for c in by_parent.get(state.id, []) if c.kind is ir.StateKind.HISTORY]
        if children:
            d["states"] = {c.id: define(c) for c in children}
            if state.kind is ir.StateKind.COMPOUND:
                d["states"][state.initial]["initial"] = True
        if history:
            # a history state never visited enters its parent's initial state (SCXML's
            # default history transition)
            d["history"] = {
                h.id: {"type": h.history_type or "shallow", "transitions": [{"target": state.initial}]}
                if state.initial else {"type": h.history_type or "shallow"}
                for h in history
            }
        on: dict[str, list[dict[str, Any]]] = {}
        eventless: list[dict[str, Any]] = []
        for t in ordered_transitions(x for x in chart.transitions if x.source == state.id):
            td: dict[str, Any] = {"target": t.target}
            if t.guard is not None:
                model_attrs[f"guard__{t.id}"] = (
                    _guard_method(t.guard) if t.event is not None else _eventless_guard_method(chart.id, t, t.guard))
                td["cond"] = [f"guard__{t.id}"]
            if t.actions:
                model_attrs[f"action__{t.id}"] = _action_method(t.actions)
                td["on"] = [f"action__{t.id}"]
            if t.event is None:
                eventless.append(td)
            else:
                on.setdefault(t.event, []).append(td)
        if on:
            d["on"] = on
        if eventless:
            d["transitions"] = eventless
        return d

    states: dict[str, Any] = {s.id: define(s) for s in by_parent.get(None, []) if s.kind is not ir.StateKind.HISTORY}
    states[chart.root_initial]["initial"] = True
    model_cls = type(f"{chart.id}Model", (ChartModel,), model_attrs)
    machine = create_machine_class_from_definition(
        chart.id,
        states=states,
        validate_trap_states=False,
        validate_disconnected_states=False,
        validate_final_reachability=False,
    )
    machine.allow_event_without_transition = True
    # an error in a guard or action is a spec error to report, not an event to process
    machine.catch_errors_as_events = False
    return machine, model_cls


def initial_env(chart: ir.Chart, parameters: Mapping[str, object] | None = None) -> dict[str, object]:
    env: dict[str, object] = {v.name: v.initial for v in chart.variables}
    env.update(DEFAULT_PARAMETERS)
    if parameters:
        env.update(parameters)
    return env


class AxisInstance:
    """One axis: a running python-statemachine chart plus its variables."""

    def __init__(
        self,
        chart: ir.Chart,
        name: str,
        *,
        state: str | None = None,
        variables: Mapping[str, object] | None = None,
        parameters: Mapping[str, object] | None = None,
    ) -> None:
        self.chart = chart
        self.name = name
        machine_cls, model_cls = machine_class(chart)
        self.env = initial_env(chart, parameters)
        if variables:
            self.env.update(variables)
        preset = dict(self.env)
        self.model = model_cls(self.env)
        self.machine = machine_cls(model=self.model)
        if state is not None and state not in self.active:
            self._force(state, preset)
        if variables:
            # explicit set-up values win over entry actions of the initial state
            self.env.update(variables)
        # eventless transitions enabled by the set-up are taken before the first scan,
        # whether the axis starts in its initial state or in a named one
        self.send(SETTLE_EVENT)

    def _force(self, state: str, preset: Mapping[str, object]) -> None:
        """Start in ``state``: its configuration is entered and its entry actions run."""
        self.env.clear()
        self.env.update(preset)
        chain = list(reversed(self.chart.ancestors(state)))
        target = self.chart.state(state)
        while target.kind in (ir.StateKind.COMPOUND, ir.StateKind.PARALLEL):
            if target.kind is ir.StateKind.PARALLEL:
                raise ValueError(f"cannot start in parallel state {state!r}; name a leaf state")
            assert target.initial is not None
            target = self.chart.state(target.initial)
            chain.append(target.id)
        self.machine.current_state_value = set(chain) if len(chain) > 1 else chain[0]
        for sid in chain:
            for a in self.chart.state(sid).entry:
                a.apply(self.env)

    @property
    def active(self) -> frozenset[str]:
        return frozenset(str(v) for v in self.machine.configuration_values)

    @property
    def leaf(self) -> ir.State:
        leaves = [s for s in self.chart.leaf_states() if s.id in self.active]
        return leaves[0]

    @property
    def value(self) -> int | None:
        return self.leaf.value

    def send(self, event: str) -> None:
        """One macrostep (docs/semantics.md): the transitions ``event`` enables, then the
        eventless transitions, again and again until none is enabled.

        The variables may have changed since the last macrostep ended (the actions of an
        environment event or of a request are applied just before the event is sent), and
        python-statemachine's processing loop takes the eventless transitions enabled
        then *before* it takes the event.  They are held off while the event selects and
        takes its transitions, and taken after it."""
        self.model.microsteps = 0
        if event == SETTLE_EVENT:
            self.machine.send(event)
            return
        self.model.hold_eventless = True
        try:
            self.machine.send(event)
        finally:
            self.model.hold_eventless = False
        self.machine.send(SETTLE_EVENT)

    def snapshot(self) -> tuple[frozenset[str], tuple[object, ...]]:
        """(active configuration, chart variable values in declaration order)."""
        return self.active, tuple(self.env[v.name] for v in self.chart.variables)

    def restore(self, snap: tuple[frozenset[str], tuple[object, ...]]) -> None:
        """Put the machine in a configuration taken by :meth:`snapshot` (no actions run).

        History memories are not part of the snapshot: restoring is exact for charts
        without history states (the model checker's IR interpreter keeps them)."""
        active, values = snap
        for v, value in zip(self.chart.variables, values):
            self.env[v.name] = value
        self.machine.current_state_value = set(active) if len(active) > 1 else next(iter(active))

    def apply_event_actions(self, event: str) -> None:
        for a in chart_event_actions(self.chart).get(event, ()):
            a.apply(self.env)

    def observe(self) -> dict[str, object]:
        """The axis as the scan table and scenarios see it."""
        out: dict[str, object] = {
            "state": self.leaf.id,
            self.chart.state_attribute: self.value,
        }
        for v in self.chart.variables:
            out[v.name] = self.env[v.name]
        return out

    def expression_env(self) -> dict[str, object]:
        """Variables as instructions see them: ``axis.X`` keys plus ``axis.active``."""
        env: dict[str, object] = {f"axis.{k}": v for k, v in self.env.items()}
        env["axis.active"] = self.active
        env["axis.state"] = self.leaf.id
        env["axis.chart"] = self.chart.id
        env[f"axis.{self.chart.state_attribute}"] = self.value
        return env


@functools.cache
def chart_event_actions(chart: ir.Chart) -> dict[str, tuple[Assignment, ...]]:
    """Environment events change drive-model variables before the chart sees them."""
    return {e.name: e.actions for e in chart.events}
