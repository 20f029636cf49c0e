"""Renderers: the IR as diagrams, flowcharts, Markdown reference pages and SCXML.

Pipeline position: ``spec`` -> :mod:`statecharts.loader` -> IR -> **render** ->
``generated/`` (through ``motionchart diagram | docs | generate``).

One module per output, each generic over the IR (nothing here names a chart, a state or
an instruction of the bundled spec):

* :mod:`~statecharts.render.labels` -- the wording all renderers share;
* :mod:`~statecharts.render.dot` -- chart state diagrams as Graphviz DOT;
* :mod:`~statecharts.render.flowchart` -- instruction flowcharts (model and DOT);
* :mod:`~statecharts.render.mermaid` -- both as Mermaid text;
* :mod:`~statecharts.render.graphviz_bin` -- finds ``dot`` / ``graphviz-pure`` and
  draws SVG or PNG;
* :mod:`~statecharts.render.scxml` -- charts as W3C SCXML;
* :mod:`~statecharts.render.traceability` -- runs the scenarios to see what they exercise;
* :mod:`~statecharts.render.reference` -- the Markdown reference;
* :mod:`~statecharts.render.aoi` -- the add-on instructions of ``spec/addons/`` (their own
  loader, :mod:`statecharts.aoi`): reference page, flowchart, recovery-chart diagram;
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
        super().__init__(name)

    def __str__(self) -> str:
        return (f"unknown chart {self.name!r}; charts: {', '.join(self.charts) or '(none)'}; "
                f"instructions: {', '.join(self.instructions) or '(none)'}")


def resolve(spec: ir.Spec, name: str) -> ir.Chart | ir.Instruction:
    """The chart or instruction called ``name`` (exact id first, then ignoring case)."""
    for c in spec.charts:
        if c.id == name:
            return c
    for i in spec.instructions:
        if i.id == name:
            return i
    folded = name.casefold()
    matches: list[ir.Chart | ir.Instruction] = [c for c in spec.charts if c.id.casefold() == folded]
    matches += [i for i in spec.instructions if i.id.casefold() == folded]
    if len(matches) == 1:
        return matches[0]
    raise UnknownTarget(name, spec)
