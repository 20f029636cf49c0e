"""Shared test set-up: hypothesis profiles and the loaded spec.

The hypothesis profile is chosen here and nowhere else; ``make test``, ``.ci/run`` and
a plain ``pytest`` all run ``ci`` unless ``HYPOTHESIS_PROFILE`` names another one:

* ``ci`` (default) – 100 examples per test, derandomized (every run tries the same
  examples, so a failure reproduces), the reproduction blob printed on failure, no
  example database (nothing written into the checkout; parallel workers share nothing);
* ``dev`` – quick local runs while editing (50 examples, random);
* ``deep`` – long searches before a release (2000 examples), used by ``make deep``.

No profile has a deadline or a speed-dependent health check: a test fails because
behaviour is wrong, never because the machine is busy.  Tests leave ``deadline`` and
the ``too_slow`` health check to the profile.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Container, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, settings

try:
    import statecharts  # noqa: F401  # only whether the project is installed
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from statecharts import engine, ir
from statecharts.diagnostics import ScenarioError
from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scenario import Scenario, ScenarioResult, load_scenario, run_scenario, scenario_files

pytest_plugins = ["pytester"]

DEFAULT_PROFILE = "ci"
_NOT_TIMED = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow]}
settings.register_profile("ci", max_examples=100, derandomize=True, print_blob=True, database=None, **_NOT_TIMED)
settings.register_profile("dev", max_examples=50, **_NOT_TIMED)
settings.register_profile("deep", max_examples=2000, **_NOT_TIMED)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or DEFAULT_PROFILE)


#: Test files that share one expensive thing, each group given to one worker by ``make
#: test``'s file-by-file distribution (``--dist loadfile``): the session's scenario runs
#: (the ``scenario_runs`` fixture, about ten seconds) run once, not once per worker, and
#: the bundled conformance suite (about 45 s to generate when its content changed) is
#: built by the worker that uses it, instead of one worker waiting for the other's build.
SHARED_UNITS = {
    **dict.fromkeys(("test_aoi.py", "test_cip_chart.py", "test_mrhd_cip.py", "test_scenarios.py"), "scenario runs"),
    **dict.fromkeys(("test_conformance.py", "test_conformance_node.py"), "conformance suite"),
}


#: The longest units of work (about a minute down to a quarter of one each, on the quiet
#: machine), longest first: collected first, they are handed out first, and the short
#: files fill the end of both workers' queues (with ``--no-loadscope-reorder``, which keeps
#: the collection order; xdist would order by the number of tests).
LONGEST_FIRST = ("conformance suite", "scenario runs", "test_loader_errors.py", "test_checker_compile.py",
                 "test_exact_codes.py", "test_checker_aoi.py", "test_spin.py", "test_lint.py",
                 "test_mrhd_servo.py", "test_checker_soundness.py", "test_scxml.py", "test_checker_core.py",
                 "test_render.py", "test_cli_aoi.py")


def unit_of(nodeid: str) -> str:
    """The unit of work of a test: its file, or the group of :data:`SHARED_UNITS` it is in."""
    file = nodeid.split("::", 1)[0]
    return SHARED_UNITS.get(Path(file).name, file)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    rank = {u: i for i, u in enumerate(LONGEST_FIRST)}

    def key(item: pytest.Item) -> int:
        unit = unit_of(item.nodeid)
        return rank.get(unit, rank.get(Path(unit).name, len(rank)))

    items.sort(key=key)  # stable: within a unit, and among the others, the collection order


def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """``--dist loadfile``, with each group of :data:`SHARED_UNITS` as one unit of work."""
    if config.getoption("dist", None) != "loadfile":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class _FileScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return unit_of(nodeid)

    return _FileScheduling(config, log)


def pytest_report_header(config: pytest.Config) -> str:
    return f"hypothesis profile: {settings.get_current_profile_name()}"


# With pytest-xdist (``-n``) the workers collect and deselect, and the summary line leaves
# the deselected count out: each worker reports it, and the summary names it again.
_DESELECTED: list[int] = []


def pytest_deselected(items: Sequence[pytest.Item]) -> None:
    _DESELECTED.append(len(items))


def pytest_sessionfinish(session: pytest.Session) -> None:
    workeroutput = getattr(session.config, "workeroutput", None)
    if workeroutput is not None:
        workeroutput["deselected"] = sum(_DESELECTED)


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node: Any, error: object) -> None:
    _DESELECTED.append(-int(getattr(node, "workeroutput", {}).get("deselected", 0)))


def pytest_terminal_summary(terminalreporter: Any, config: pytest.Config) -> None:
    reported = [-n for n in _DESELECTED if n < 0]
    if reported and max(reported):
        terminalreporter.write_line(f"{max(reported)} deselected (`make deep` runs those marked deep)")


def examples(fast: int, deep: int | None = None) -> int:
    """The number of examples of a long property test: ``fast`` under ``make test``'s
    profile (``ci``; at most the profile's count under ``dev``), ``deep`` (else the
    profile's own count) under ``make deep``'s profile."""
    profile = settings.get_current_profile_name()
    current = settings().max_examples
    if profile == "deep":
        return deep if deep is not None else current
    return min(fast, current)


def sampled(values: Iterable[Any], fast: Container[Any]) -> list[Any]:
    """Parameters of a long exploration: those in ``fast`` run in ``make test`` (the fast
    sample), the others only in ``make deep`` (marked ``deep``, deselected by default)."""
    out = []
    for v in values:
        args = v if isinstance(v, tuple) else (v,)
        out.append(pytest.param(*args, marks=() if v in fast else (pytest.mark.deep,)))
    return out


@pytest.fixture(scope="session")
def bundled_spec() -> ir.Spec:
    """The bundled specification, loaded once per test session."""
    return load_spec()


@pytest.fixture(scope="session")
def spec(bundled_spec: ir.Spec) -> ir.Spec:
    """The bundled specification (a test module may override this name)."""
    return bundled_spec


# --------------------------------------------------------------------------- scenarios, run once

SCENARIO_ROOT = Path(__file__).resolve().parents[1] / "scenarios"

#: Charts whose transitions are recorded while the scenarios run (tests/test_cip_chart.py).
RECORDED_CHARTS = ("AxisCIP",)


@dataclass
class ScenarioRuns:
    """Every scenario file under ``scenarios/``, loaded and run once per test session.

    ``outcome`` maps a file to its :class:`ScenarioResult`, or to the
    :class:`ScenarioError` raised while loading or running it; ``taken`` names, per
    recorded chart and transition id, the scenario files whose scans took it (not the
    set-up of their axes).
    """

    files: list[Path]
    outcome: dict[Path, ScenarioResult | ScenarioError] = field(default_factory=dict)
    loaded: dict[Path, Scenario | ScenarioError] = field(default_factory=dict)
    taken: dict[str, dict[str, set[Path]]] = field(default_factory=dict)

    def result(self, path: Path) -> ScenarioResult:
        """The result of ``path``; a file that did not load or run fails the calling test."""
        got = self.outcome[path.resolve()]
        if isinstance(got, ScenarioError):
            pytest.fail(f"{path.name} does not load or run:\n{got}")
        return got

    def under(self, *dirs: Path) -> list[Path]:
        roots = [d.resolve() for d in dirs]
        return [p for p in self.files if any(p.is_relative_to(r) for r in roots)]


class _TakenRecorder:
    """A python-statemachine listener naming the chart transitions taken.

    The engine declares each chart transition with its guard ``guard__<id>`` and its
    actions ``action__<id>``; a transition with neither is known by its source, event
    and target, which must be unique in its chart."""

    def __init__(self, chart: str, keys: dict[tuple[object, ...], str], taken: dict[str, set[Path]]) -> None:
        self.chart = chart
        self.keys = keys
        self.armed = False
        self.taken = taken
        self.current: Path | None = None

    def on_transition(self, event: object, source: object, target: object, transition: Any) -> None:
        if not self.armed or source is None or self.current is None or str(event) == "__initial__":
            return
        conds = [str(c) for c in transition.cond]
        ons = [str(c) for c in transition.on]
        guard = next((c[len("guard__"):] for c in conds if c.startswith("guard__")), None)
        action = next((c[len("action__"):] for c in ons if c.startswith("action__")), None)
        if guard is not None:
            tid: str | None = guard
        elif action is not None:
            tid = action
        else:
            tid = self.keys.get((getattr(source, "id", None), str(event) if event else None,
                                 getattr(target, "id", None) if target else None))
        if tid is not None:
            self.taken.setdefault(tid, set()).add(self.current)


@pytest.fixture(scope="session")
def scenario_runs(bundled_spec: ir.Spec) -> ScenarioRuns:
    """Load and run every bundled scenario once for the whole test session, recording the
    transitions of :data:`RECORDED_CHARTS` that each run takes during its scans."""
    runs = ScenarioRuns(sorted(p.resolve() for p in scenario_files([SCENARIO_ROOT])))
    recorders: dict[str, _TakenRecorder] = {}
    for cid in RECORDED_CHARTS:
        keys: dict[tuple[object, ...], str] = {}
        for t in bundled_spec.chart(cid).transitions:
            if t.guard is None and not t.actions:
                key = (t.source, t.event, t.target)
                assert key not in keys, f"{cid}: {t.id} and {keys[key]} cannot be told apart"
                keys[key] = t.id
        recorders[cid] = _TakenRecorder(cid, keys, runs.taken.setdefault(cid, {}))
    original_class = engine.machine_class
    original_init = AxisInstance.__init__

    def machine_class(c: ir.Chart) -> Any:
        machine, model = original_class(c)
        recorder = recorders.get(c.id)
        if recorder is None:
            return machine, model
        return (lambda *a, **kw: machine(*a, listeners=[recorder], **kw)), model

    def init(self: AxisInstance, *a: Any, **kw: Any) -> None:
        for r in recorders.values():
            r.armed = False
        original_init(self, *a, **kw)
        for r in recorders.values():
            r.armed = True

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(engine, "machine_class", machine_class)
        mp.setattr(AxisInstance, "__init__", init)
        for path in runs.files:
            for r in recorders.values():
                r.current = path
            try:
                scenario = load_scenario(path, bundled_spec)
            except ScenarioError as exc:
                runs.loaded[path] = runs.outcome[path] = exc
                continue
            runs.loaded[path] = scenario
            try:
                runs.outcome[path] = run_scenario(scenario, bundled_spec)
            except ScenarioError as exc:
                runs.outcome[path] = exc
        for r in recorders.values():
            r.current = None
    return runs


# --------------------------------------------------------------------------- generation, traced once


@pytest.fixture(scope="session", autouse=True)
def _scenarios_traced_once_per_content() -> Iterator[None]:
    """Generation (``generate``, ``docs``) runs every scenario to see what it exercises;
    within the session, one spec and one set of scenario files (by content) are traced
    once and the result reused."""
    from statecharts.render import generate, traceability

    original = traceability.trace
    memo: dict[object, traceability.Traceability] = {}

    def trace(spec: ir.Spec, roots: Sequence[Path | str],
              progress: Callable[[str, int | None, int | None], None] | None = None) -> traceability.Traceability:
        files = scenario_files([r for r in roots if Path(r).exists()])
        key = (spec, tuple(str(r) for r in roots), tuple((str(f), f.read_bytes()) for f in files))
        if key not in memo:
            memo[key] = original(spec, roots, progress)
        return memo[key]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(generate, "trace", trace)
        yield
