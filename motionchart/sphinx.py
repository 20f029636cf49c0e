"""Sphinx extension: diagrams and tables from the motionchart spec in a user's own docs.

Add ``"motionchart.sphinx"`` to ``extensions`` in ``conf.py``; then, in reStructuredText
(or MyST with the ``{eval-rst}`` block)::

    .. motionchart-chart:: AxisNonCIP

    .. motionchart-flowchart:: MSO

    .. motionchart-errors:: MSO

``motionchart-chart`` draws a chart's state diagram, ``motionchart-flowchart`` an
instruction's flowchart (its checks in order, each to its error box), both as inline
SVG drawn by Graphviz in HTML output (left out of LaTeX, text, man and Texinfo
output); ``motionchart-errors`` is a table of the error codes an instruction can give
(no argument: every error code of the spec).  Options: ``:caption:`` (a caption under a
diagram), ``:class:`` (CSS classes).

The spec is the bundled one, or the files and folders in the configuration value
``motionchart_spec`` (a list of paths relative to the source directory).  An unknown chart or
instruction, a spec that does not load or a missing Graphviz is a located Sphinx error
(so ``-W`` builds fail), never a traceback.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective

from statecharts.diagnostics import InputError
from statecharts.ir import Spec

__all__ = ["setup"]

_SPECS: dict[tuple[str, ...], Spec] = {}


def _spec(directive: SphinxDirective) -> Spec:
    from statecharts.loader import load_spec

    src = Path(directive.env.srcdir)
    paths = tuple(str(src / p) for p in directive.config.motionchart_spec)
    if paths not in _SPECS:
        _SPECS[paths] = load_spec(list(paths) or None)
    return _SPECS[paths]


class _SpecDirective(SphinxDirective):
    required_arguments = 1
    optional_arguments = 0
    option_spec: ClassVar[dict[str, Any]] = {"caption": directives.unchanged, "class": directives.class_option}

    def problem(self, message: str) -> list[nodes.Node]:
        return [self.state.document.reporter.error(f"{self.name}: {message}", line=self.lineno)]

    def spec_or_problem(self) -> Spec | list[nodes.Node]:
        try:
            return _spec(self)
        except InputError as exc:
            return self.problem("the spec does not load:\n" + "\n".join(str(d) for d in exc.diagnostics))

    def diagram(self, dot: str, alt: str) -> list[nodes.Node]:
        from statecharts.render.graphviz_bin import RenderError, render

        try:
            svg = render(dot, "svg").decode("utf-8")
        except RenderError as exc:
            return self.problem(f"cannot draw {alt}: {exc}")
        body = diagram(dot=dot, svg=svg[svg.find("<svg"):], alt=alt,
                       classes=["motionchart-diagram", *self.options.get("class", [])])
        caption = self.options.get("caption")
        if not caption:
            return [body]
        figure = nodes.figure("", body, classes=["motionchart-figure"])
        figure += nodes.caption(caption, caption)
        return [figure]


class diagram(nodes.General, nodes.Element):
    """A drawn diagram: inline SVG in HTML, its DOT text as a literal block elsewhere."""


def _visit_html(self: Any, node: diagram) -> None:
    classes = " ".join(node["classes"])
    self.body.append(f'<div class="{classes}" role="img" aria-label="{self.attval(node["alt"])}">{node["svg"]}</div>')
    raise nodes.SkipNode


def _visit_text_like(self: Any, node: diagram) -> None:
    raise nodes.SkipNode


class ChartDirective(_SpecDirective):
    """``.. motionchart-chart:: CHART`` -- a chart's state diagram."""

    def run(self) -> list[nodes.Node]:
        from statecharts.render import chart_dot

        spec = self.spec_or_problem()
        if isinstance(spec, list):
            return spec
        name = self.arguments[0]
        chart = next((c for c in spec.charts if c.id == name), None)
        if chart is None:
            return self.problem(f"unknown chart {name!r}; charts: {', '.join(c.id for c in spec.charts)}")
        return self.diagram(chart_dot(chart), f"state diagram of {chart.id}")


class FlowchartDirective(_SpecDirective):
    """``.. motionchart-flowchart:: INSTRUCTION`` -- an instruction's flowchart."""

    def run(self) -> list[nodes.Node]:
        from statecharts.render import instruction_dot

        spec = self.spec_or_problem()
        if isinstance(spec, list):
            return spec
        name = self.arguments[0]
        ins = next((i for i in spec.instructions if i.id == name), None)
        if ins is None:
            return self.problem(f"unknown instruction {name!r}; instructions: {', '.join(i.id for i in spec.instructions)}")
        return self.diagram(instruction_dot(spec, ins), f"flowchart of {ins.id}")


class ErrorsDirective(_SpecDirective):
    """``.. motionchart-errors:: [INSTRUCTION]`` -- a table of error codes."""

    required_arguments = 0
    optional_arguments = 1

    def run(self) -> list[nodes.Node]:
        from motionchart import error_codes

        spec = self.spec_or_problem()
        if isinstance(spec, list):
            return spec
        name = self.arguments[0] if self.arguments else None
        if name is not None and name not in {i.id for i in spec.instructions}:
            return self.problem(f"unknown instruction {name!r}; instructions: {', '.join(i.id for i in spec.instructions)}")
        rows = error_codes(name, spec)
        header = ["ERR", "EXERR", "Name", "Meaning", "Checks"] if name else ["ERR", "Name", "Meaning", "Confidence"]
        body = [[str(r.err), str(r.exerr), r.name, r.meaning, ", ".join(r.checks) or "(documented, not modelled)"]
                if name else [str(r.err), r.name, r.meaning, r.confidence] for r in rows]
        return [_table(header, body, ["motionchart-errors", *self.options.get("class", [])], self.options.get("caption"))]


def _table(header: list[str], rows: list[list[str]], classes: list[str], caption: str | None) -> nodes.table:
    table = nodes.table(classes=classes)
    if caption:
        table += nodes.title(caption, caption)
    group = nodes.tgroup(cols=len(header))
    table += group
    for _ in header:
        group += nodes.colspec(colwidth=1)

    def row(cells: list[str]) -> nodes.row:
        r = nodes.row()
        for text in cells:
            r += nodes.entry("", nodes.paragraph(text, text))
        return r

    thead = nodes.thead()
    thead += row(header)
    group += thead
    tbody = nodes.tbody()
    for cells in rows:
        tbody += row(cells)
    group += tbody
    return table


def setup(app: Sphinx) -> dict[str, Any]:
    """Register the directives and the ``motionchart_spec`` configuration value."""
    app.add_config_value("motionchart_spec", [], "env", [list])
    skip = (_visit_text_like, None)
    app.add_node(diagram, html=(_visit_html, None), latex=skip, text=skip, man=skip, texinfo=skip)
    app.add_directive("motionchart-chart", ChartDirective)
    app.add_directive("motionchart-flowchart", FlowchartDirective)
    app.add_directive("motionchart-errors", ErrorsDirective)
    from importlib.metadata import version

    return {"version": version("motionchart"), "parallel_read_safe": True, "parallel_write_safe": True}
