"""One exit-code convention for every command (docs/getting-started.md, "Exit codes"):
0 success, 1 a finding or an invalid input file, 2 a usage error (the command line
itself: an unknown option, a missing file, an unknown chart or system name, an
output format that cannot be told).

Each command is run in process through ``checker.cli.main`` for each case that applies
to it; the expected codes are the convention's, not read from the implementation.
"""

from __future__ import annotations

import shutil
import sys
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
    empty = tmp_path / "no-scenarios"  # the traceability matrix (every scenario run) is not under test here
    empty.mkdir()
    code, _, err = _run(["generate", "--check", "-o", str(stale), "--scenarios", str(empty)], capsys)
    assert code == 1 and "error-codes.md" in err
    code, _, err = _run(["generate", "-o", str(tmp_path / "g"), "--spec", str(broken_spec)], capsys)
    assert code == 1 and "unresolvable source" in err
    assert _run(["generate", "--no-such-option"], capsys)[0] == 2
    assert _run(["generate", "--scenarios", "no/such/dir"], capsys)[0] == 2


# --------------------------------------------------------------------------- check and export

_SMALL_SYSTEM = """\
format: motionchart-system/1
name: tiny
scan_ms: 10
coarse_update_ms: 10
axes:
  - name: Axis
    type: AXIS_SERVO
    program: [MSO, MASD, MASR]
environment: [servo_fault, fault_cleared]
prescan: false
max_live_calls: 1
abstraction:
  collapse: [ServoOutput, DriveOutputCommand]
"""

# false on purpose: on a faulted axis MSO is refused with ERR 20 (ICS code 20)
_FALSE_PROPERTY = """\
format: motionchart-properties/1
properties:
  - name: mso_never_errs
    kind: invariant
    scope: tag
    instruction: MSO
    holds: "not ER"
    source: "MC tests/test_cli_exit_codes.py (deliberately false)"
"""


# holds in the model: an MSO tag never has DN and ER set together
_TRUE_PROPERTY = _FALSE_PROPERTY.replace("mso_never_errs", "mso_not_done_and_errored").replace(
    '"not ER"', '"not (DN and ER)"').replace("deliberately false", "holds")


@pytest.fixture()
def tiny_system(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(_SMALL_SYSTEM, encoding="utf-8")
    return path


def test_check(tmp_path: Path, tiny_system: Path, capsys: pytest.CaptureFixture[str]) -> None:
    holds = tmp_path / "true.yaml"
    holds.write_text(_TRUE_PROPERTY, encoding="utf-8")
    code, out, err = _run(["check", "--system", str(tiny_system), "--properties", str(holds), "-q"], capsys)
    assert code == 0, out + err
    props = tmp_path / "false.yaml"
    props.write_text(_FALSE_PROPERTY, encoding="utf-8")
    code, out, _ = _run(["check", "--system", str(tiny_system), "--properties", str(props), "-q"], capsys)
    assert code == 1 and "VIOLATED mso_never_errs" in out  # a finding
    bad = tmp_path / "bad.yaml"
    bad.write_text(_SMALL_SYSTEM.replace("[MSO, MASD, MASR]", "[MSO, MXYZ]"), encoding="utf-8")
    code, _, err = _run(["check", "--system", str(bad), "-q"], capsys)
    assert code == 1 and f"{bad}:" in err  # invalid input, located
    assert _run(["check", "--system", "no_such_system"], capsys)[0] == 2
    assert _run(["check", "--axes", "0"], capsys)[0] == 2
    assert _run(["check", "--max-states", "20", "--system", str(tiny_system), "--properties", str(holds), "-q"],
                capsys)[0] == 3


def test_export(tmp_path: Path, tiny_system: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "tiny.pml"
    code, _, err = _run(["export", "--system", str(tiny_system), "-o", str(out)], capsys)
    assert code == 0, err
    assert out.stat().st_size > 0
    # export reports no findings (it writes a model); invalid input and usage errors:
    bad = tmp_path / "bad.yaml"
    bad.write_text(_SMALL_SYSTEM.replace("[MSO, MASD, MASR]", "[MSO, MXYZ]"), encoding="utf-8")
    code, _, err = _run(["export", "--system", str(bad), "-o", str(tmp_path / "bad.pml")], capsys)
    assert code == 1 and f"{bad}:" in err
    assert _run(["export", "--format", "nusmv"], capsys)[0] == 2
    assert _run(["export", "--system", "no_such_system"], capsys)[0] == 2


# --------------------------------------------------------------------------- conformance commands

ADAPTER = f"{sys.executable} -m checker adapter"


@pytest.fixture()
def one_vector(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    """A suite of one vector: the MSO scenario above (no checker-generated vectors)."""
    scenarios = tmp_path / "scenarios"
    scenarios.mkdir()
    _scenario(scenarios, "good.yaml", "ServoControl")
    out = tmp_path / "vectors"
    code, _, err = _run(["vectors", "-o", str(out), "--scenarios", str(scenarios), "--no-generated", "-q"], capsys)
    assert code == 0, err
    return out


def test_vectors(tmp_path: Path, one_vector: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert (one_vector / "manifest.json").is_file()
    bad = tmp_path / "bad_scenarios"
    bad.mkdir()
    (bad / "broken.yaml").write_text(_SCENARIO.replace("instruction: MSO", "instruction: MXYZ"), encoding="utf-8")
    code, _, err = _run(["vectors", "-o", str(tmp_path / "v2"), "--scenarios", str(bad), "--no-generated", "-q"],
                        capsys)
    assert code == 1 and "broken.yaml" in err  # invalid input
    assert _run(["vectors"], capsys)[0] == 2  # -o is required
    assert _run(["vectors", "-o", str(tmp_path / "v3"), "--system", "no_such_system"], capsys)[0] == 2
    assert _run(["vectors", "-o", str(tmp_path / "v4"), "--scenarios", "no/such/dir"], capsys)[0] == 2


_INEXACT_SYSTEM = """\
format: motionchart-system/1
name: home_stop
description: a virtual axis homing, stopped with the Home stop type
source: "MC tests/test_cli_exit_codes.py"
scan_ms: 10
coarse_update_ms: 10
axes:
  - name: Axis
    type: AXIS_VIRTUAL
    chart: AxisVirtual
    state: ServoControl
    program: [MAH_VIRTUAL, MAS_VIRTUAL]
    configurations:
      - {name: linear}
operands:
  MAS_VIRTUAL: {StopType: [4]}
environment: [home_complete, stopping_complete]
max_live_calls: 2
abstraction:
  collapse: [ActualPosition, CommandVelocity, MoveCommand, MoveSpeed, MoveRemaining, MovePlanned, MoveType,
             JogVelocity, GearRatio, StopDecel, RedefinePosition, RedefineType, HomePosition, PositionUnwind]
"""


def test_vectors_of_a_system_whose_abstraction_is_not_exact(tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    """The search reaches the homing stop (mas_home) with the planner collapsed; the engine,
    replaying the run, does not: a located error on the system file, not a traceback."""
    system = tmp_path / "home_stop.yaml"
    system.write_text(_INEXACT_SYSTEM, encoding="utf-8")
    (tmp_path / "none").mkdir()
    code, _, err = _run(["vectors", "-q", "-o", str(tmp_path / "v"), "--scenarios", str(tmp_path / "none"),
                         "--system", str(system)], capsys)
    assert code == 1 and "Traceback" not in err
    assert f"{system}:1:1: abstraction:" in err and "mas_home" in err and "not exact" in err


def test_conform(tmp_path: Path, one_vector: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _run(["conform", "--adapter", ADAPTER, "--vectors", str(one_vector), "-q"], capsys)[0] == 0
    # a finding: the vector expects another state than the implementation reaches
    wrong = tmp_path / "wrong"
    shutil.copytree(one_vector, wrong)
    vector = wrong / "scenario-good.json"
    vector.write_text(vector.read_text(encoding="utf-8").replace('"AxisState": 2', '"AxisState": 0'),
                      encoding="utf-8")
    assert _run(["conform", "--adapter", ADAPTER, "--vectors", str(wrong), "-q"], capsys)[0] == 1
    broken = tmp_path / "broken"
    shutil.copytree(one_vector, broken)
    (broken / "scenario-good.json").write_text("{not json", encoding="utf-8")
    code, _, err = _run(["conform", "--adapter", ADAPTER, "--vectors", str(broken), "-q"], capsys)
    assert code == 1 and "scenario-good.json" in err  # invalid input
    assert _run(["conform", "--vectors", str(one_vector)], capsys)[0] == 2  # --adapter is required
    assert _run(["conform", "--adapter", ADAPTER, "--vectors", "no/such/dir"], capsys)[0] == 2


def test_adapter(broken_spec: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import io

    hello = '{"type":"hello","protocol":"motionchart-conformance/1"}\n'
    monkeypatch.setattr(sys, "stdin", io.StringIO(hello + '{"type":"bye"}\n'))
    code, out, _ = _run(["adapter"], capsys)
    assert code == 0 and '"type": "hello"' in out.replace('"type":"hello"', '"type": "hello"')
    # a message that is not JSON is answered in band (the protocol's error message); the
    # adapter keeps serving, so it is no exit code of its own
    monkeypatch.setattr(sys, "stdin", io.StringIO("not json\n"))
    code, out, _ = _run(["adapter"], capsys)
    assert code == 0 and '"error"' in out
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    code, _, err = _run(["adapter", "--spec", str(broken_spec)], capsys)
    assert code == 1 and "unresolvable source" in err
    assert _run(["adapter", "--mutant", "no-such-mutant"], capsys)[0] == 2
    assert _run(["adapter", "--no-such-option"], capsys)[0] == 2


def test_mutate(tmp_path: Path, one_vector: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _out, err = _run(["mutate", "--score", "--vectors", str(one_vector), "--sample", "3", "--min-score", "0",
                           "--quiet"], capsys)
    assert code == 0, err
    # a finding: one vector cannot kill every mutant, so a required score of 1 is not met
    code, _, _ = _run(["mutate", "--score", "--vectors", str(one_vector), "--sample", "3", "--min-score", "1",
                       "--quiet"], capsys)
    assert code == 1
    broken = tmp_path / "broken"
    shutil.copytree(one_vector, broken)
    (broken / "scenario-good.json").write_text("{not json", encoding="utf-8")
    assert _run(["mutate", "--score", "--vectors", str(broken), "--quiet"], capsys)[0] == 1
    assert _run(["mutate"], capsys)[0] == 2  # nothing to do without --score
    assert _run(["mutate", "--score", "--vectors", "no/such/dir"], capsys)[0] == 2
