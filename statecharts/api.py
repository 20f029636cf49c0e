"""Small public API: a chart of the spec as a ready-to-run python-statemachine class.

Pipeline position: IR -> :func:`statecharts.engine.machine_class` -> **api** -> your code.

:func:`chart_class` returns the ``StateChart`` subclass the engine itself runs for a
chart (built once per chart and cached), and :func:`chart_model` a model object holding
the chart's variables, on which the machine's guards and actions are resolved.  Use
them to embed a chart in your own program, to draw it with python-statemachine's own
tools, or to drive it event by event:

>>> from statecharts.api import chart_class, chart_model
>>> Machine = chart_class("AxisNonCIP")
>>> model = chart_model("AxisNonCIP", FaultAction="Shutdown")
>>> sm = Machine(model=model)
>>> sorted(sm.configuration_values)
['AxisReady', 'Operating']
>>> sm.send("servo_on"); sorted(sm.configuration_values)
['Operating', 'ServoControl']
>>> model.env["DriveEnableStatus"]
True

Environment events (``servo_fault`` ...) change drive-model variables before the chart
sees them; apply those with :func:`event_actions` first, as the PLC scan does
(:mod:`statecharts.scan`):

>>> for a in event_actions("AxisNonCIP", "servo_fault"):
...     a.apply(model.env)
>>> sm.send("servo_fault"); sorted(sm.configuration_values)
['Shutdown']

For whole PLC scans (instructions, coarse updates) use :class:`statecharts.scan.System`;
for one axis, :class:`statecharts.engine.AxisInstance`.
"""

from __future__ import annotations

from typing import Any

from statemachine import StateChart

from statecharts import ir
from statecharts.engine import ChartModel, chart_event_actions, initial_env, machine_class
from statecharts.expr import Assignment
from statecharts.loader import load_spec

__all__ = ["chart_class", "chart_model", "event_actions"]

_BUNDLED: ir.Spec | None = None


def _chart(chart_id: str, spec: ir.Spec | None) -> ir.Chart:
    global _BUNDLED
    if spec is None:
        if _BUNDLED is None:
            _BUNDLED = load_spec()
        spec = _BUNDLED
    try:
        return spec.chart(chart_id)
    except KeyError:
        known = ", ".join(c.id for c in spec.charts) or "(none)"
        raise KeyError(f"unknown chart {chart_id!r}; charts: {known}") from None


def chart_class(chart_id: str, spec: ir.Spec | None = None) -> type[StateChart[Any]]:
    """The python-statemachine ``StateChart`` class of chart ``chart_id``.

    ``spec`` defaults to the bundled specification.  Instantiate it with
    ``model=chart_model(chart_id)``: its guards and actions are methods of that model.
    Raises ``KeyError`` naming the known charts for an unknown id.
    """
    machine, _model = machine_class(_chart(chart_id, spec))
    return machine


def chart_model(chart_id: str, spec: ir.Spec | None = None, **variables: object) -> ChartModel:
    """A model for :func:`chart_class`'s machine: the chart's variables at their initial
    values (plus the system parameters), overridden by ``variables``; read them back from
    ``model.env``."""
    chart = _chart(chart_id, spec)
    unknown = sorted(set(variables) - {v.name for v in chart.variables})
    if unknown:
        raise KeyError(f"chart {chart_id} has no variable(s) {', '.join(unknown)}")
    _machine, model_cls = machine_class(chart)
    env = initial_env(chart)
    env.update(variables)
    return model_cls(env)


def event_actions(chart_id: str, event: str, spec: ir.Spec | None = None) -> tuple[Assignment, ...]:
    """The drive-model assignments an environment event makes before the chart sees it."""
    return chart_event_actions(_chart(chart_id, spec)).get(event, ())
