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


def test_lint_fails_on_a_planted_type_error(pristine: Path, tmp_path: Path) -> None:
    root = planted(pristine, tmp_path, "statecharts/values.py", '\n\ndef planted() -> int:\n    return "not an int"\n')
    done = lint(root)
    assert done.returncode != 0, done.stdout + done.stderr
    assert "statecharts/values.py" in done.stdout and "[return-value]" in done.stdout, done.stdout + done.stderr

