"""motionchart's Python API: the specification, scenarios, the model checker and the
renderers, from one place.

Everything a user's own code or tests need is exported here (see ``__all__``); the
modules under :mod:`statecharts` and :mod:`checker` are the implementation.  The
examples in ``docs/api.md`` run as tests.

>>> import motionchart
>>> spec = motionchart.bundled_spec()
>>> "AxisNonCIP" in [c.id for c in spec.charts]
True

Hypothesis strategies for property tests are in :mod:`motionchart.strategies`; the
pytest plugin (:mod:`motionchart.pytest_plugin`) collects scenario files as tests; the
Sphinx extension (:mod:`motionchart.sphinx`) draws charts into a user's documentation.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from checker.report import PropertyVerdict, Report
from conformance.runner import RunResult
from conformance.vectors import load_vectors
from statecharts.diagnostics import Diagnostic, InputError, ScenarioError, SpecError
from statecharts.ir import Chart, Instruction, Spec
from statecharts.loader import load_spec as _load_spec
from statecharts.program import Controller, Program, ProgramError
from statecharts.scan import EnvironmentEvent, ScanInputs, ScanRecord, System
from statecharts.scenario import Mismatch, ScanRow, Scenario, ScenarioResult, scan_cell, scenario_files
from statecharts.scenario import load_scenario as _load_scenario
from statecharts.scenario import run_scenario as _run_scenario

__all__ = [
    "Chart",
    "CheckReport",
    "Controller",
    "Diagnostic",
    "EnvironmentEvent",
    "ErrorCodeRow",
    "InputError",
    "Instruction",
    "Mismatch",
    "Program",
    "ProgramError",
    "PropertyVerdict",
    "RunResult",
    "ScanInputs",
    "ScanRecord",
    "ScanRow",
    "Scenario",
    "ScenarioError",
    "ScenarioResult",
    "Spec",
    "SpecError",
    "System",
    "bundled_spec",
    "check",
    "error_codes",
    "load_program",
    "load_scenario",
    "load_spec",
    "load_vectors",
    "render_chart",
    "render_flowchart",
    "run_scenario",
    "run_scenarios",
    "run_vectors",
    "scan_table",
    "scenario_files",
    "write_vectors",
]

#: Formats :func:`render_chart` and :func:`render_flowchart` produce: text (``dot``,
#: ``mermaid``) or an image drawn by Graphviz (``svg`` as text, ``png`` as bytes).
Format = Literal["dot", "mermaid", "svg", "png"]

_BUNDLED: Spec | None = None


# --------------------------------------------------------------------------- the spec


def load_spec(paths: Sequence[Path | str] | None = None) -> Spec:
    """Load, validate and build a specification: the bundled one when ``paths`` is
    ``None``, else the given files and directories (add the bundled directory,
    ``statecharts.loader.bundled_spec_dir()``, to extend it).

    Raises :class:`SpecError` with every problem found, each located (file, line,
    column, node path).
    """
    return _load_spec(paths)


def bundled_spec() -> Spec:
    """The bundled specification, loaded once per process (the IR is immutable)."""
    global _BUNDLED
    if _BUNDLED is None:
        _BUNDLED = _load_spec()
    return _BUNDLED


def _spec(spec: Spec | None) -> Spec:
    return bundled_spec() if spec is None else spec


# --------------------------------------------------------------------------- scenarios


def load_scenario(path: Path | str, spec: Spec | None = None) -> Scenario:
    """Load one scenario file (YAML or JSON) against ``spec`` (default: the bundled one).

    Raises :class:`ScenarioError` with located diagnostics for a malformed scenario.
    """
    return _load_scenario(path, _spec(spec))


def run_scenario(scenario: Scenario | Path | str, spec: Spec | None = None) -> ScenarioResult:
    """Run a scenario (loaded, or a file to load) scan by scan; the result holds every
    scan (:class:`ScanRow`) and every expectation that did not hold (:class:`Mismatch`)."""
    s = _spec(spec)
    loaded = scenario if isinstance(scenario, Scenario) else _load_scenario(scenario, s)
    return _run_scenario(loaded, s)


def run_scenarios(paths: Iterable[Path | str], spec: Spec | None = None) -> list[ScenarioResult]:
    """Run every scenario file under ``paths`` (files, or directories searched for
    ``*.yaml``, ``*.yml`` and ``*.json``), in file order."""
    s = _spec(spec)
    return [run_scenario(f, s) for f in scenario_files(list(paths))]


def scan_table(result: ScenarioResult) -> str:
    """The per-scan table of a run: each scan with what changed, and after each step the
    values it expects beside the values observed (``!=`` marks a mismatch, with the
    file and the line of its step).
    """
    sc = result.scenario
    lines = [f"scenario: {sc.name}  ({sc.file})",
             f"{'scan':>5}  {'step':<28}  {'changes / expected':<28} actual"]
    last_row_of_step: dict[int, int] = {}
    for i, row in enumerate(result.rows):
        last_row_of_step[row.step] = i
    bad = {(m.step, m.target, m.field): m for m in result.mismatches}
    steps = {s.index: s for s in getattr(sc, "steps", ())}
    for i, row in enumerate(result.rows):
        label = f"{row.step + 1}" + (f" {row.step_name}" if row.step_name else "")
        changes = "  ".join(f"{o}.{f}={scan_cell(a)}" for o, f, _b, a in row.changes) or "-"
        cu = "" if row.record.coarse_update else " (no coarse update)"
        lines.append(f"{row.record.index:>5}  {label[:28]:<28}  {changes}{cu}")
        step = steps.get(row.step)
        if step is None or last_row_of_step.get(row.step) != i:
            continue
        for target, fld, expected in step.expect:
            actual = row.record.observations.get(target, {}).get(fld)
            m = bad.get((row.step, target, fld))
            want = f"{target}.{fld}={scan_cell(expected)}"
            if m is None:
                lines.append(f"{'':>5}  {'  expect':<28}  {want:<28} {scan_cell(actual)}")
            else:
                lines.append(f"{'':>5}  {'  expect':<28}  {want:<28} {scan_cell(m.actual)}"
                             f"  != ({sc.file}:{m.line})")
    verdict = "PASS" if result.passed else f"FAIL ({len(result.mismatches)} expectation(s) not met)"
    lines.append(f"{verdict}: {sc.name}, {len(result.rows)} scans")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- the model checker


@dataclass(frozen=True)
class CheckReport:
    """What a :func:`check` found: the verdict, the search's size and each property's verdict."""

    report: Report

    @property
    def verdict(self) -> str:
        """``"holds"`` (every property holds), ``"violated"`` or ``"incomplete"``."""
        return {0: "holds", 1: "violated"}.get(self.report.exit_code, "incomplete")

    @property
    def holds(self) -> bool:
        """Every property holds and the search was complete."""
        return self.report.exit_code == 0

    @property
    def states(self) -> int:
        return self.report.result.states

    @property
    def transitions(self) -> int:
        return self.report.result.transitions

    @property
    def complete(self) -> bool:
        return self.report.result.complete

    @property
    def verdicts(self) -> list[PropertyVerdict]:
        return list(self.report.verdicts)

    @property
    def violated(self) -> list[str]:
        """Names of the properties found violated (each has a shortest counterexample)."""
        return [v.prop.name for v in self.report.verdicts if v.holds is False]

    def text(self) -> str:
        """The report ``motionchart check`` prints."""
        from checker.report import text

        return text(self.report)

    def as_dict(self) -> dict[str, object]:
        """The object ``motionchart check --json`` prints."""
        return self.report.as_dict()


def check(
    system: str | Path = "noncip",
    *,
    spec: Spec | None = None,
    properties: Sequence[Path | str] | None = None,
    axes: int | None = None,
    max_states: int | None = None,
    max_seconds: float | None = None,
    counterexamples: Path | str | None = None,
) -> CheckReport:
    """Model-check a system: a bundled name (``noncip``, ``noncip_pairs``, ``cip``, ``aoi``...) or a
    system file, against the bundled properties or the ``properties`` files.

    ``axes`` sets every axis group's count; ``max_states`` / ``max_seconds`` bound the
    search (its verdict is then ``"incomplete"``); ``counterexamples`` is a directory
    where each violation's shortest run is written as a scenario.  A bad system or
    property file raises :class:`InputError` with located diagnostics.
    """
    from checker.model import Model
    from checker.properties import load_properties
    from checker.report import build_report
    from checker.search import explore
    from checker.system import bundled_systems, load_system

    s = _spec(spec)
    systems = bundled_systems()
    path = systems.get(str(system)) if isinstance(system, str) else None
    if path is None:
        path = Path(system)
        if not path.is_file():
            raise FileNotFoundError(f"unknown system {str(system)!r}; bundled systems: {', '.join(systems)} (or give a system file)")
    sysdef = load_system(path, s)
    if axes is not None:
        sysdef = sysdef.scaled(axes)
    model = Model(s, sysdef, load_properties(s, properties))
    result = explore(model, max_states=max_states, max_seconds=max_seconds, progress=False)
    return CheckReport(build_report(result, counterexamples=Path(counterexamples) if counterexamples else None))


# --------------------------------------------------------------------------- rendering


def _render(dot: str, mermaid: str, fmt: str) -> str | bytes:
    if fmt == "dot":
        return dot
    if fmt == "mermaid":
        return mermaid
    if fmt in ("svg", "png"):
        from statecharts.render.graphviz_bin import render

        data = render(dot, fmt)
        return data.decode("utf-8") if fmt == "svg" else data
    raise ValueError(f"unknown format {fmt!r}; formats: dot, mermaid, svg, png")


def render_chart(chart: str, format: Format = "dot", spec: Spec | None = None) -> str | bytes:
    """A chart's state diagram: Graphviz DOT, Mermaid, SVG (text) or PNG (bytes).

    SVG and PNG need Graphviz's ``dot`` (``make install`` provides it); DOT and Mermaid
    need nothing.  An unknown chart raises ``KeyError`` naming the known ones.
    """
    from statecharts.render import chart_dot, chart_mermaid

    c = _chart(_spec(spec), chart)
    return _render(chart_dot(c), chart_mermaid(c), format)


def render_flowchart(instruction: str, format: Format = "dot", spec: Spec | None = None) -> str | bytes:
    """An instruction's flowchart (its checks in order, each to its error box)."""
    from statecharts.render import instruction_dot, instruction_mermaid

    s = _spec(spec)
    ins = _instruction(s, instruction)
    return _render(instruction_dot(s, ins), instruction_mermaid(s, ins), format)


def _chart(spec: Spec, chart_id: str) -> Chart:
    for c in spec.charts:
        if c.id == chart_id:
            return c
    raise KeyError(f"unknown chart {chart_id!r}; charts: {', '.join(c.id for c in spec.charts)}")


def _instruction(spec: Spec, name: str) -> Instruction:
    for i in spec.instructions:
        if i.id == name:
            return i
    raise KeyError(f"unknown instruction {name!r}; instructions: {', '.join(i.id for i in spec.instructions)}")


# --------------------------------------------------------------------------- error codes


@dataclass(frozen=True)
class ErrorCodeRow:
    """One error code (``exerr`` 0 for a plain code), as documented, with the checks of
    the instruction that produce it (empty: documented, not modelled)."""

    err: int
    exerr: int
    name: str
    meaning: str
    confidence: str
    source: str
    checks: tuple[str, ...] = ()


def error_codes(instruction: str | None = None, spec: Spec | None = None) -> list[ErrorCodeRow]:
    """The error codes of the spec (``instruction=None``), or those one instruction can
    give: the codes its checks and aborts produce and its documented extended codes."""
    s = _spec(spec)
    by_code = {e.code: e for e in s.errors}
    if instruction is None:
        return [ErrorCodeRow(e.code, 0, e.name, e.meaning, e.confidence.value, e.provenance.source) for e in s.errors]
    ins = _instruction(s, instruction)
    checks: dict[tuple[int, int], list[str]] = {}
    for c in (*ins.checks, *ins.aborts):
        checks.setdefault((c.err, c.exerr), []).append(c.id)
    rows: dict[tuple[int, int], ErrorCodeRow] = {}
    for x in s.extended_errors:
        if x.instruction in (ins.id, ins.mnemonic):
            rows[(x.err, x.exerr)] = ErrorCodeRow(x.err, x.exerr, x.name, x.meaning, x.confidence.value,
                                                  x.provenance.source, tuple(checks.get((x.err, x.exerr), ())))
    for (err, exerr), ids in checks.items():
        if (err, exerr) in rows:
            continue
        e = by_code.get(err)
        rows[(err, exerr)] = ErrorCodeRow(err, exerr, e.name if e else "", e.meaning if e else "",
                                          e.confidence.value if e else "", e.provenance.source if e else "", tuple(ids))
    return [rows[k] for k in sorted(rows)]


# --------------------------------------------------------------------------- programs and vectors


def load_program(path: Path | str, spec: Spec | None = None, *, routine: str | None = None,
                 program: str | None = None) -> Program:
    """Read a ladder program: a rung file (ASCII or neutral text) or an L5X export
    (``program`` and ``routine`` choose in an L5X file).  Bind it to axes and scan it
    with :class:`Controller` (docs/programs.md).  Raises :class:`ProgramError` with every
    problem of the file, each located."""
    from statecharts.program import load_program as _load_program

    return _load_program(path, spec=_spec(spec), routine=routine, program=program)


def run_vectors(
    vectors: Sequence[dict[str, object]] | Path | str,
    adapter: str | None = None,
    *,
    spec: Spec | None = None,
    jobs: int = 1,
) -> RunResult:
    """Run conformance vectors (loaded, or a directory written by ``motionchart
    vectors``) against an implementation: ``adapter`` is the command that starts it
    (speaking the JSON Lines protocol of docs/conformance.md), or ``None`` for the
    reference adapter on ``spec`` in this process.  The result has one verdict per
    vector, ``counts()``, ``ok`` and ``summary()``."""
    from conformance.adapter import ReferenceAdapter
    from conformance.runner import InProcessTransport, ProcessTransport, Transport, run

    loaded = load_vectors(vectors) if isinstance(vectors, Path | str) else list(vectors)
    s = _spec(spec)

    def factory() -> Transport:
        if adapter is None:
            return InProcessTransport(ReferenceAdapter(s))
        return ProcessTransport(adapter)

    return run(loaded, factory, jobs=jobs)


def write_vectors(
    directory: Path | str,
    scenarios: Sequence[Path | str] = ("scenarios",),
    systems: Sequence[str | Path] = (),
    *,
    spec: Spec | None = None,
) -> list[Path]:
    """Write a conformance suite to ``directory`` (replaced as a whole): one vector per
    scenario file under ``scenarios``, plus, for each system of ``systems`` (bundled
    names or files), a shortest checker-generated run per transition, error code and
    instruction x state cell (what ``motionchart vectors`` writes).  Returns the files."""
    from conformance.vectors import build_suite, write_suite

    return write_suite(build_suite(_spec(spec), scenarios=list(scenarios), systems=list(systems)), Path(directory))
