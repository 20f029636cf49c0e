"""pytest plugin: a project's scenario files as test items, and its spec as a fixture.

Installed with motionchart (entry point ``pytest11``), active in every pytest run of an
environment that has motionchart; it collects nothing until configured.  In the
project's ``pyproject.toml`` (or ``pytest.ini`` / ``setup.cfg``)::

    [tool.pytest.ini_options]
    motionchart_scenarios = ["scenarios", "acceptance/*.scenario.yaml"]
    motionchart_spec = []            # spec files or folders; empty: the bundled spec

Each entry of ``motionchart_scenarios`` is a folder (every ``*.yaml``, ``*.yml`` and
``*.json`` file under it is a scenario) or a glob pattern, relative to the rootdir; the
files must lie where pytest collects (under the rootdir or the ``testpaths``).  Each
scenario file is one test item: it passes when every expectation holds, and a failure
is reported with the per-scan table, each expectation beside the observed value and
its ``file:line``.  A file that does not load is a failure that lists its located
errors.  ``--motionchart-scenarios PATH`` adds entries from the command line.

The fixture ``motionchart_spec`` gives the loaded spec (the ``motionchart_spec`` ini
option's files, or the bundled spec), loaded once per session.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from statecharts.diagnostics import InputError
from statecharts.ir import Spec

SUFFIXES = (".yaml", ".yml", ".json")
_SPEC_KEY = pytest.StashKey[Spec]()


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini("motionchart_scenarios", type="linelist", default=[],
                  help="folders or glob patterns (relative to the rootdir) of motionchart scenario files to run as tests")
    parser.addini("motionchart_spec", type="linelist", default=[],
                  help="spec files or folders for motionchart scenarios and the motionchart_spec fixture (default: bundled)")
    group = parser.getgroup("motionchart")
    group.addoption("--motionchart-scenarios", action="append", default=[], metavar="PATH",
                    help="a folder or glob pattern of scenario files to run as tests (adds to the ini option)")


def _entries(config: pytest.Config) -> list[str]:
    ini: list[str] = config.getini("motionchart_scenarios")
    cli: list[str] = config.getoption("motionchart_scenarios") or []
    return [e for e in (*ini, *cli) if e.strip()]


def _is_scenario(config: pytest.Config, path: Path) -> bool:
    if path.suffix not in SUFFIXES:
        return False
    root = config.rootpath
    try:
        rel = path.resolve().relative_to(root.resolve()).as_posix()
    except ValueError:
        rel = path.as_posix()
    for entry in _entries(config):
        base = Path(entry) if Path(entry).is_absolute() else root / entry
        if base.is_dir():
            if path.resolve().is_relative_to(base.resolve()):
                return True
        elif fnmatch.fnmatch(rel, entry) or fnmatch.fnmatch(str(path), entry):
            return True
    return False


def project_spec(config: pytest.Config) -> Spec:
    """The spec the configuration names, loaded once per session."""
    spec = config.stash.get(_SPEC_KEY, None)
    if spec is None:
        from statecharts.loader import load_spec

        paths = [str(p if Path(p).is_absolute() else config.rootpath / p) for p in config.getini("motionchart_spec")]
        spec = load_spec(paths or None)
        config.stash[_SPEC_KEY] = spec
    return spec


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    if _is_scenario(parent.config, file_path):
        return ScenarioFile.from_parent(parent, path=file_path)
    return None


@pytest.fixture(scope="session")
def motionchart_spec(pytestconfig: pytest.Config) -> Spec:
    """The loaded spec: the ``motionchart_spec`` ini option's files, or the bundled spec."""
    return project_spec(pytestconfig)


class ScenarioFile(pytest.File):
    """A scenario file: one test item."""

    def collect(self) -> Iterator[pytest.Item]:
        yield ScenarioItem.from_parent(self, name=self.path.name)


class ScenarioFailed(Exception):
    """A scenario ran and some expectation did not hold."""

    def __init__(self, table: str) -> None:
        super().__init__(table)
        self.table = table


class ScenarioItem(pytest.Item):
    """Runs one scenario file; fails with the per-scan table when an expectation does not hold."""

    def runtest(self) -> None:
        from motionchart import scan_table
        from statecharts.scenario import load_scenario, run_scenario

        spec = project_spec(self.config)
        result = run_scenario(load_scenario(self.path, spec), spec)
        if not result.passed:
            located = [m.located(str(self.path)) for m in result.mismatches]
            raise ScenarioFailed(scan_table(result) + "\n".join(located))

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> str:
        exc = excinfo.value
        if isinstance(exc, ScenarioFailed):
            return exc.table
        if isinstance(exc, InputError):
            return "\n".join(str(d) for d in exc.diagnostics)
        return str(super().repr_failure(excinfo))

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, 0, f"scenario {self.path.name}"
