"""Program scenarios: the three-axis fault-recovery routine on CIP axes, and the scenario keys of programs."""

from __future__ import annotations

from pathlib import Path

import pytest

from checker.cli import main
from statecharts.diagnostics import ScenarioError
from statecharts.loader import load_spec
from statecharts.scenario import load_scenario, run_scenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "programs"


@pytest.fixture(scope="module")
def spec():
    return load_spec()


def test_all_axes_running_reach_state_1_in_four_scans(spec) -> None:
    # The count, by hand from docs/programs.md: scan k (first in state 9) executes the MSFs, whose
    # requests take the Running axes to Stopping at that scan's coarse update (001 Running, Disable);
    # Stopping lasts one coarse update (INT-035, StoppingUpdates 1), so the MSFs are DN after scan k+1;
    # scan k+2 reads MSF.DN and executes the MAFRs, done in that coarse update (INT-017); scan k+3 reads
    # every MAFR.DN and moves 1 to NEXTSTATE and STATE.
    result = run_scenario(load_scenario(EXAMPLES / "fault_recovery_all_running.yaml", spec), spec)
    assert result.passed, [str(m) for m in result.mismatches]
    first_in_9 = next(r.record.index for r in result.rows if r.record.observations["STATE9_IND"][""])
    reached = next(r.record.index for r in result.rows if r.record.observations["NEXTSTATE"][""] == 1
                   and r.record.index > first_in_9)
    assert reached - first_in_9 == 3  # NEXTSTATE = 1 in the fourth scan in state 9


def test_one_axis_in_shutdown_never_reaches_state_1(spec) -> None:
    scenario = load_scenario(EXAMPLES / "fault_recovery_one_shutdown.yaml", spec)
    result = run_scenario(scenario, spec)
    assert result.passed, [str(m) for m in result.mismatches]
    assert len(result.rows) == 503
    assert all(r.record.observations["NEXTSTATE"][""] == 9 for r in result.rows[1:])
    # the scenario says so: its `always` fails if the routine leaves state 9
    step = scenario.steps[-1]
    assert ("NEXTSTATE", "", 9) in step.always


def test_simulate_prints_program_tags(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", str(EXAMPLES / "fault_recovery_all_running.yaml")]) == 0
    out = capsys.readouterr().out
    assert "    1  2 the sequence asks for stat  NEXTSTATE=9  STATE=9\n" in out
    assert "    5  6 every MAFR done, next stat  NEXTSTATE=1  STATE=1\n" in out
    assert "X_AXIS_STAT[0].DN=1" in out


def _write(tmp_path: Path, text: str) -> Path:
    (tmp_path / "p.rll").write_text("XIC START OTE RUN\nXIC RUN MSO Ax1 mso1\n", encoding="utf-8")
    path = tmp_path / "s.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_program_scenario_errors_are_located(tmp_path: Path, spec) -> None:
    path = _write(tmp_path, """format: motionchart-scenario/1
name: bad
setup:
  program: p.rll
  axes:
    Other: {type: AXIS_SERVO}
  tags: {NOPE: 1, RUN: 3}
steps:
  - rungs: {mso1: true}
    expect: {RUN: true, GHOST: 1, mso1: {XX: 1}}
""")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, spec)
    text = "\n".join(str(d) for d in info.value.diagnostics)
    assert "the program uses axis 'Ax1'; give it in setup.axes" in text
    assert "cannot write 'NOPE'" in text
    assert "RUN is a BOOL: expected true or false, got 3" in text
    assert "the program decides the rungs and operands" in text
    assert "'GHOST' is not a program tag, motion tag or axis" in text


def test_program_scenario_runs_a_rung_file(tmp_path: Path, spec) -> None:
    path = _write(tmp_path, """format: motionchart-scenario/1
name: start
setup:
  program: p.rll
  axes:
    Ax1: {type: AXIS_SERVO}
steps:
  - tags: {START: true}
    expect: {RUN: true, mso1: {EN: true, DN: true}, Ax1: {state: ServoControl}}
""")
    result = run_scenario(load_scenario(path, spec), spec)
    assert result.passed, [str(m) for m in result.mismatches]
