"""Renderers: the IR as diagrams, flowcharts, Markdown reference pages and SCXML.

Pipeline position: ``spec`` -> :mod:`statecharts.loader` -> IR -> **render** ->
``generated/`` (through ``motionchart diagram | docs | generate``).

One module per output, each generic over the IR (nothing here names a chart, a state or
an instruction of the bundled spec):

* :mod:`~statecharts.render.labels` -- the wording all renderers share;
* :mod:`~statecharts.render.dot` -- chart state diagrams as Graphviz DOT;
* :mod:`~statecharts.render.flowchart` -- flowcharts of ordered checks (model and DOT): an
  instruction's, and an add-on instruction's up to where its recovery chart takes over;
* :mod:`~statecharts.render.mermaid` -- both as Mermaid text;
* :mod:`~statecharts.render.graphviz_bin` -- finds ``dot`` / ``graphviz-pure`` and
  draws SVG or PNG;
* :mod:`~statecharts.render.scxml` -- charts as W3C SCXML;
* :mod:`~statecharts.render.traceability` -- runs the scenarios to see what they exercise;
* :mod:`~statecharts.render.reference` -- the Markdown reference: pages of charts, of
  instructions and of add-on instructions, built from the same sections;
* :mod:`~statecharts.render.addon` -- an add-on instruction's recovery as a chart, so that
  the chart renderers draw and table it;
* :mod:`~statecharts.render.generate` -- every artefact as bytes, written or checked.

>>> from statecharts.loader import load_spec
>>> spec = load_spec()
>>> chart = spec.chart("AxisNonCIP")
>>> chart_dot(chart) == chart_dot(chart)  # same spec, same bytes
True
>>> chart_mermaid(chart).splitlines()[3]
'stateDiagram-v2'
"""

from __future__ import annotations

from statecharts import ir
from statecharts.render.addon import RECOVERY_SUFFIX, recovery_chart
from statecharts.render.dot import chart_dot
from statecharts.render.flowchart import build_flowchart, flowchart_dot, instruction_dot
from statecharts.render.mermaid import chart_mermaid, flowchart_mermaid, instruction_mermaid
from statecharts.render.scxml import ScxmlUnsupported, chart_scxml

__all__ = [
    "ScxmlUnsupported",
    "UnknownTarget",
    "build_flowchart",
    "chart_dot",
    "chart_mermaid",
    "chart_scxml",
    "flowchart_dot",
    "flowchart_mermaid",
    "instruction_dot",
    "instruction_mermaid",
    "resolve",
]


class UnknownTarget(KeyError):
    """A name that is neither a chart nor an instruction of the spec."""

    def __init__(self, name: str, spec: ir.Spec) -> None:
        self.name = name
        self.charts = tuple(c.id for c in spec.charts)
        self.instructions = tuple(i.id for i in spec.instructions)
        self.add_ons = tuple(n for a in spec.add_ons for n in (a.id, a.id + RECOVERY_SUFFIX))
        super().__init__(name)

    def __str__(self) -> str:
        return (f"unknown chart {self.name!r}; charts: {', '.join(self.charts) or '(none)'}; "
                f"instructions: {', '.join(self.instructions) or '(none)'}"
                + (f"; add-on instructions: {', '.join(self.add_ons)}" if self.add_ons else ""))


def resolve(spec: ir.Spec, name: str) -> ir.Chart | ir.Instruction | ir.AddOnInstruction:
    """The chart, instruction or add-on instruction called ``name``, or the recovery chart
    of an add-on instruction for ``<id>_recovery`` (exact id first, then ignoring case)."""
    targets: list[tuple[str, ir.Chart | ir.Instruction | ir.AddOnInstruction]] = [
        *((c.id, c) for c in spec.charts), *((i.id, i) for i in spec.instructions),
        *((a.id, a) for a in spec.add_ons), *((a.id + RECOVERY_SUFFIX, recovery_chart(spec, a, ordered=True)) for a in spec.add_ons)]
    for key, target in targets:
        if key == name:
            return target
    matches = [t for key, t in targets if key.casefold() == name.casefold()]
    if len(matches) == 1:
        return matches[0]
    raise UnknownTarget(name, spec)
