"""Run the scenarios and record what each one exercises: states reached, codes produced.

Pipeline position: IR + scenario files -> :mod:`statecharts.scenario` (load, run) ->
**traceability** -> the traceability matrix of the reference docs.

What a scenario exercises is read from its *run*, not from its ``covers:`` list: every
scan's observations give each axis's active leaf state (its ancestors are active too)
and each tag's ``ER`` / ``ERR`` / ``EXERR`` / ``DN``.  ``covers:`` and ``sources:`` are
kept to be shown beside the observed facts.  An add-on instruction tag of the program
is read the same way from its ``Sts_`` members: the recovery-chart states observed, the
``Sts_ERR`` / ``Sts_EXERR`` seen with ``Sts_ER`` set, and ``Sts_PC``; its calls' tags
(``Sync.MAM``) count as the instructions they run.  A scenario that cannot be loaded or
crashes is reported, never raised: generated docs must not depend on every scenario
being valid.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from statecharts import ir
from statecharts.diagnostics import InputError
from statecharts.scenario import Scenario, load_scenario, run_scenario, scenario_files
from statecharts.values import as_int


@dataclass(frozen=True, slots=True, order=True)
class ScenarioRun:
    """One scenario run and what it exercised."""

    path: str  # as shown in the docs: "scenarios/noncip/mso_enable.yaml"
    name: str
    passed: bool
    scans: int
    covers: tuple[str, ...]
    sources: tuple[str, ...]
    states: frozenset[tuple[str, str]]  # (chart id, state id) observed active
    errors: frozenset[tuple[str, int, int]]  # (instruction, ERR, EXERR) observed with ER set
    done: frozenset[str]  # instructions observed with DN set
    aoi_states: frozenset[str] = frozenset()  # recovery-chart states of an add-on instruction instance
    aoi_errors: frozenset[tuple[int, int]] = frozenset()  # (Sts_ERR, Sts_EXERR) observed with Sts_ER set
    aoi_done: bool = False  # some add-on instruction instance observed with Sts_PC set


@dataclass(frozen=True, slots=True, order=True)
class ScenarioProblem:
    path: str
    message: str


@dataclass(frozen=True, slots=True)
class Traceability:
    runs: tuple[ScenarioRun, ...]
    problems: tuple[ScenarioProblem, ...]
    root: str | None  # the scenario directory as shown, or None when there was none
    link_base: str = ""  # from the output directory to the scenario paths' base ("../")

    def reaching(self, chart: str, state: str) -> list[ScenarioRun]:
        return [r for r in self.runs if (chart, state) in r.states]

    def producing(self, instruction: str, err: int, exerr: int) -> list[ScenarioRun]:
        return [r for r in self.runs if (instruction, err, exerr) in r.errors]

    def completing(self, instruction: str) -> list[ScenarioRun]:
        return [r for r in self.runs if instruction in r.done]

    def aoi_producing(self, code: int, exerr: int | None = None) -> list[ScenarioRun]:
        """Add-on instruction scenarios that observed ``Sts_ERR = code`` (and ``exerr`` if given)."""
        return [r for r in self.runs if any(e == code and (exerr is None or x == exerr) for e, x in r.aoi_errors)]

    def aoi_reaching(self, state: str) -> list[ScenarioRun]:
        return [r for r in self.runs if state in r.aoi_states]

    def aoi_completing(self) -> list[ScenarioRun]:
        return [r for r in self.runs if r.aoi_done]


def display_path(path: Path, root: Path) -> str:
    """``path`` relative to the parent of the scenario root (never absolute)."""
    p = path.resolve()
    base = root.resolve().parent
    try:
        return p.relative_to(base).as_posix()
    except ValueError:
        return p.name


#: What each scenario run exercised, kept for this process: a second ``generate`` (or
#: ``docs``) over the same spec object and unchanged scenario files reuses the runs.  Only
#: scenarios read from one file are kept (a ladder scenario also reads its program file).
_RUNS: dict[tuple[int, str, str, str], tuple[ir.Spec, ScenarioRun]] = {}


def _memo_key(spec: ir.Spec, f: Path, shown: str, scenario: object) -> tuple[int, str, str, str] | None:
    if type(scenario) is not Scenario:
        return None
    try:
        if not f.is_file():
            return None
        digest = hashlib.sha256(f.read_bytes()).hexdigest()
    except OSError:
        return None
    return (id(spec), str(f.resolve()), digest, shown)


def trace(spec: ir.Spec, roots: Sequence[Path | str],
          progress: Callable[[str, int | None, int | None], None] | None = None) -> Traceability:
    """Load and run every scenario under ``roots``; collect what each exercised.

    ``progress(what, done, total)`` is called before each scenario runs."""
    runs: list[ScenarioRun] = []
    problems: list[ScenarioProblem] = []
    existing = [Path(r) for r in roots if Path(r).exists()]
    if not existing:
        return Traceability((), (), None)
    todo = [(root, f) for root in existing for f in scenario_files([root])]
    for n, (root, f) in enumerate(todo):
        shown = display_path(f, root)
        if progress is not None:
            progress(f"running scenario {shown}", n, len(todo))
        try:
            scenario = load_scenario(f, spec)
        except InputError as exc:
            first = exc.diagnostics[0] if exc.diagnostics else None
            where = f"line {first.line}: {first.message}" if first else str(exc)
            more = f" (and {len(exc.diagnostics) - 1} more)" if len(exc.diagnostics) > 1 else ""
            problems.append(ScenarioProblem(shown, f"does not load: {where}{more}"))
            continue
        key = _memo_key(spec, f, shown, scenario)
        kept = _RUNS.get(key) if key is not None else None
        if kept is not None and kept[0] is spec:
            runs.append(kept[1])
            continue
        try:
            result = run_scenario(scenario, spec)
        except Exception as exc:
            problems.append(ScenarioProblem(shown, f"crashed: {type(exc).__name__}: {exc}"))
            continue
        charts = {a.name: spec.chart(a.chart) for a in scenario.axes}
        add_ons = {a.id for a in spec.add_ons}
        instr = {p.tag: p.instruction for p in scenario.program if p.instruction not in add_ons}
        instances = {p.tag for p in scenario.program if p.instruction in add_ons}
        if result.rows:  # the MOTION_INSTRUCTION tags of an instance's calls: ``Sync.MAM``
            instr.update({obj: obj.split(".", 1)[1].split("_")[0] for obj in result.rows[0].record.observations
                          if "." in obj and obj.split(".", 1)[0] in instances})
        states: set[tuple[str, str]] = set()
        errors: set[tuple[str, int, int]] = set()
        done: set[str] = set()
        aoi_states: set[str] = set()
        aoi_errors: set[tuple[int, int]] = set()
        aoi_done = False
        for row in result.rows:
            for obj, fields in row.record.observations.items():
                if obj in instances:
                    if isinstance(fields.get("state"), str):
                        aoi_states.add(str(fields["state"]))
                    if fields.get("Sts_ER"):
                        aoi_errors.add((as_int(fields.get("Sts_ERR", 0)), as_int(fields.get("Sts_EXERR", 0))))
                    aoi_done = aoi_done or bool(fields.get("Sts_PC"))
                elif obj in charts:
                    chart = charts[obj]
                    leaf = fields.get("state")
                    if isinstance(leaf, str):
                        states.update((chart.id, s) for s in chart.ancestors(leaf))
                elif obj in instr:
                    if fields.get("ER"):
                        errors.add((instr[obj], as_int(fields.get("ERR", 0)), as_int(fields.get("EXERR", 0))))
                    if fields.get("DN"):
                        done.add(instr[obj])
        run = ScenarioRun(
            path=shown, name=scenario.name, passed=result.passed, scans=len(result.rows),
            covers=scenario.covers, sources=scenario.sources, states=frozenset(states),
            errors=frozenset(errors), done=frozenset(done), aoi_states=frozenset(aoi_states),
            aoi_errors=frozenset(aoi_errors), aoi_done=aoi_done,
        )
        if key is not None:
            _RUNS[key] = (spec, run)
        runs.append(run)
    shown_root = ", ".join(sorted(Path(r).resolve().name for r in existing))
    return Traceability(tuple(sorted(runs)), tuple(sorted(problems)), shown_root)
