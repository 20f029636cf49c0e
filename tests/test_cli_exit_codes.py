"""One exit-code convention for every command (docs/getting-started.md, "Exit codes"):
0 success, 1 a finding or an invalid input file, 2 a usage error (the command line
itself: an unknown option, a missing file, an unknown chart or system name, an
output format that cannot be told).

Each command is run in process through ``checker.cli.main`` for each case that applies
to it; the expected codes are the convention's, not read from the implementation.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from checker.cli import main
from statecharts.loader import bundled_spec_dir

ROOT = Path(__file__).resolve().parent.parent


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture()
def broken_spec(tmp_path: Path) -> Path:
    """A copy of the bundled spec with one unresolvable citation."""
    dst = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), dst, ignore=shutil.ignore_patterns("__pycache__", "*.py"))
    mdo = dst / "instructions" / "MDO.yaml"
    mdo.write_text(mdo.read_text(encoding="utf-8").replace('source: "LDH-MDO Operands"', 'source: "my notes"', 1),
                   encoding="utf-8")
    return dst


_SCENARIO = """format: motionchart-scenario/1
name: MSO enables a ready servo axis
setup:
  axes:
    Axis1: {type: AXIS_SERVO}
  program:
    - {tag: mso1, instruction: MSO, axis: Axis1}
steps:
  - rungs: {mso1: true}
    expect:
      Axis1: {state: STATE}
"""


def _scenario(tmp_path: Path, name: str, state: str) -> Path:
    """MSO on a ready servo axis, expecting ``state`` (Servo Control is right: LDH-MSI instruction table)."""
    path = tmp_path / name
    path.write_text(_SCENARIO.replace("STATE", state), encoding="utf-8")
    return path


# --------------------------------------------------------------------------- validate


def test_validate(broken_spec: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _run(["validate"], capsys)[0] == 0
    code, _, err = _run(["validate", str(broken_spec)], capsys)
    assert code == 1 and "unresolvable source 'my notes'" in err
    assert _run(["validate", "--no-such-option"], capsys)[0] == 2
    assert _run(["validate", "no/such/dir"], capsys)[0] == 2


# --------------------------------------------------------------------------- simulate


def test_simulate(tmp_path: Path, broken_spec: Path, capsys: pytest.CaptureFixture[str]) -> None:
    good = _scenario(tmp_path, "good.yaml", "ServoControl")
    assert _run(["simulate", "-q", str(good)], capsys)[0] == 0
    failing = _scenario(tmp_path, "failing.yaml", "AxisReady")
    code, out, _ = _run(["simulate", str(failing)], capsys)
    assert code == 1 and "FAIL" in out  # a finding: the expectation does not hold
    code, _, err = _run(["simulate", "--spec", str(broken_spec), str(good)], capsys)
    assert code == 1 and "unresolvable source" in err  # invalid input
    assert _run(["simulate"], capsys)[0] == 2
    assert _run(["simulate", "no/such/file.yaml"], capsys)[0] == 2


# --------------------------------------------------------------------------- diagram


def test_diagram(tmp_path: Path, broken_spec: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(["diagram", "MSO"], capsys)
    assert code == 0 and out.startswith("digraph")
    code, _, err = _run(["diagram", "MSO", "--spec", str(broken_spec)], capsys)
    assert code == 1 and "unresolvable source" in err
    # usage: an unknown chart, an extension that names no format, a binary format to a terminal
    code, _, err = _run(["diagram", "NoSuchChart"], capsys)
    assert code == 2 and "unknown chart 'NoSuchChart'" in err
    code, _, err = _run(["diagram", "MSO", "-o", str(tmp_path / "x.jpg")], capsys)
    assert code == 2 and "cannot tell the format" in err and not (tmp_path / "x.jpg").exists()
    assert _run(["diagram", "MSO", "--format", "pdf"], capsys)[0] == 2
    assert _run(["diagram", "MSO", "-o", str(tmp_path / "y.pdf"), "--format", "dot"], capsys)[0] == 2
    assert _run(["diagram"], capsys)[0] == 2


def test_diagram_pdf_is_a_real_pdf(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("graphviz") if shutil.which("dot") is None else None
    out = tmp_path / "x.pdf"
    code, _, err = _run(["diagram", "MSO", "-o", str(out)], capsys)
    assert code == 0, err
    assert out.read_bytes().startswith(b"%PDF-")
    svg = tmp_path / "x.svg"
    assert _run(["diagram", "AxisNonCIP", "-o", str(svg)], capsys)[0] == 0
    assert b"<svg" in svg.read_bytes()[:2000]
    dot = tmp_path / "x.gv"
    assert _run(["diagram", "MSO", "-o", str(dot)], capsys)[0] == 0
    assert dot.read_text(encoding="utf-8").startswith("digraph")


# --------------------------------------------------------------------------- docs and generate


def test_docs(tmp_path: Path, broken_spec: Path, capsys: pytest.CaptureFixture[str]) -> None:
    empty = tmp_path / "no_scenarios"
    empty.mkdir()
    code, _, err = _run(["docs", "-o", str(tmp_path / "ref"), "--spec", str(broken_spec),
                         "--scenarios", str(empty)], capsys)
    assert code == 1 and "unresolvable source" in err
    assert _run(["docs"], capsys)[0] == 2  # -o is required
    assert _run(["docs", "-o", str(tmp_path / "ref"), "--spec", "no/such/spec"], capsys)[0] == 2


def test_generate(tmp_path: Path, broken_spec: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # a finding: --check on a copy of generated/ with one file changed
    stale = tmp_path / "generated"
    shutil.copytree(ROOT / "generated", stale)
    (stale / "error-codes.md").write_text("changed by hand\n", encoding="utf-8")
    code, _, err = _run(["generate", "--check", "-o", str(stale)], capsys)
    assert code == 1 and "error-codes.md" in err
    code, _, err = _run(["generate", "-o", str(tmp_path / "g"), "--spec", str(broken_spec)], capsys)
    assert code == 1 and "unresolvable source" in err
    assert _run(["generate", "--no-such-option"], capsys)[0] == 2
    assert _run(["generate", "--scenarios", "no/such/dir"], capsys)[0] == 2
