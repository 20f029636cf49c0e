"""`make lint` gates: it fails on a type error and on a lint finding.

Each test copies the linted sources and the tool configuration (``pyproject.toml``,
``Makefile``) into a temporary directory, plants one defect, and runs the Makefile's
``lint-run`` target there with this environment's tools; the failure must name the
planted defect (``make lint`` itself, run by ``.ci/run``, shows that the sources pass).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
#: Top-level entries left out of the copy: not sources, or large.
NOT_COPIED = {".git", ".venv", "generated", ".mypy_cache", ".ruff_cache", ".pytest_cache", ".hypothesis"}

pytestmark = pytest.mark.skipif(
    shutil.which("make") is None or not (BIN / "mypy").exists() or not (BIN / "ruff").exists(),
    reason="make, mypy and ruff are installed by `make install`",
)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("lint") / "src"
    root.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.svg", "*.png")
    for entry in ROOT.iterdir():
        if entry.name in NOT_COPIED or entry.name.endswith(".egg-info"):
            continue
        if entry.is_dir():
            shutil.copytree(entry, root / entry.name, ignore=ignore)
        elif entry.is_file():
            shutil.copy2(entry, root / entry.name)
    # mypy's cache of the unchanged sources, so that each planted copy rechecks only what changed
    subprocess.run([str(BIN / "python"), "-m", "mypy"], cwd=root, capture_output=True, check=False,
                   env={**os.environ, "MYPY_CACHE_DIR": str(root / ".mypy_cache")}, timeout=1800)
    return root


def lint(root: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "MYPY_CACHE_DIR": str(root / ".mypy_cache")}
    return subprocess.run(
        ["make", "--no-print-directory", "-C", str(root), "lint-run", f"BIN={BIN}"],
        capture_output=True, text=True, env=env, timeout=1800, check=False,
    )


def planted(pristine: Path, tmp_path: Path, rel: str, append: str) -> Path:
    root = tmp_path / "src"
    shutil.copytree(pristine, root, symlinks=True)
    with (root / rel).open("a", encoding="utf-8") as f:
        f.write(append)
    return root


def test_lint_fails_on_a_planted_lint_finding(pristine: Path, tmp_path: Path) -> None:
    root = planted(pristine, tmp_path, "checker/report.py", "\n\ndef _planted() -> None:\n    import json\n")
    done = lint(root)
    assert done.returncode != 0, done.stdout + done.stderr
    assert "checker/report.py" in done.stdout and "F401" in done.stdout, done.stdout + done.stderr


def test_lint_fails_on_a_planted_pragma_without_reason_and_private_import(pristine: Path, tmp_path: Path) -> None:
    root = planted(pristine, tmp_path, "checker/report.py",
                   "\n\ndef planted() -> object:\n    from statecharts.scenario import _leaf_visits\n"
                   "    return _leaf_visits  # type: ignore[misc]\n")
    done = lint(root)
    assert done.returncode != 0, done.stdout + done.stderr
    assert "checker/report.py:" in done.stdout, done.stdout + done.stderr
    assert "`from statecharts.scenario import _leaf_visits` uses a private name" in done.stdout, done.stdout
    assert "`type: ignore[misc]` without a reason" in done.stdout, done.stdout


def test_lint_fails_on_a_planted_type_error(pristine: Path, tmp_path: Path) -> None:
    root = planted(pristine, tmp_path, "statecharts/values.py", '\n\ndef planted() -> int:\n    return "not an int"\n')
    done = lint(root)
    assert done.returncode != 0, done.stdout + done.stderr
    assert "statecharts/values.py" in done.stdout and "[return-value]" in done.stdout, done.stdout + done.stderr



# --------------------------------------------------------------------------- the project's own rules

sys.path.insert(0, str(ROOT / "tools"))
import lint_rules  # noqa: E402  # tools/ is not a package: found through sys.path


def test_the_sources_keep_the_project_rules() -> None:
    assert lint_rules.problems(ROOT) == []


@pytest.mark.parametrize(("line", "problem"), [
    ("x = f()  # type: ignore\n", "without error codes"),
    ("x = f()  # type: ignore[arg-type]\n", "without a reason"),
    ("x = f()  # type: ignore[arg-type]  #\n", "without a reason"),
    ("import os  # noqa\n", "without rule codes"),
    ("import os  # noqa: F401\n", "without a reason"),
    ("import os  # noqa: F401 - imported\n", "without a reason"),
    ("x = f()  # type: ignore[misc]  # \n", "without a reason"),
])
def test_a_pragma_without_codes_or_reason_is_a_finding(line: str, problem: str) -> None:
    found = lint_rules.pragma_problems("m.py", "a = 1\n" + line, checked=True)
    assert len(found) == 1 and found[0].startswith("m.py:2: ") and problem in found[0], found


def test_a_pragma_with_its_reason_passes() -> None:
    text = ("x = f()  # type: ignore[arg-type]  # f is untyped upstream\n"
            "import os  # noqa: F401  # re-exported\n"
            "s = '# type: ignore'  # a string is not a comment\n")
    assert lint_rules.pragma_problems("m.py", text, checked=True) == []


def test_a_type_ignore_where_mypy_does_not_look_is_a_finding() -> None:
    found = lint_rules.pragma_problems("tests/t.py", "x = f()  # type: ignore[arg-type]  # a reason\n", checked=False)
    assert found == ["tests/t.py:1: `type: ignore` in a file mypy does not check; remove it"]


@pytest.mark.parametrize(("text", "shown"), [
    ("from statecharts.scenario import _leaf_visits\n", "from statecharts.scenario import _leaf_visits"),
    ("from .scenario import (\n    run_scenario,\n    _leaf_visits,\n)\n", "from .scenario import _leaf_visits"),
    ("from statecharts import loader\nloader._read(1)\n", "loader._read"),
    ("import statecharts.loader as L\nL._read(1)\n", "L._read"),
    ("import checker._private\n", "import checker._private"),
])
def test_a_private_name_of_another_module_is_a_finding(text: str, shown: str) -> None:
    found = lint_rules.private_use_problems("m.py", text)
    assert len(found) == 1 and f"`{shown}`" in found[0], found


def test_public_names_dunders_and_other_libraries_private_types_pass() -> None:
    text = ("from __future__ import annotations\nimport argparse\nfrom statecharts import loader\n"
            "from statecharts.scenario import run_scenario, __doc__\n"
            "def f(s: argparse._SubParsersAction) -> None:\n    self._x = loader.Node\n")
    assert lint_rules.private_use_problems("m.py", text) == []
