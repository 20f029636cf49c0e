"""Program systems: what the environment may do besides free inputs and events, and coverage by table.

Each expectation is worked out by hand from the little programs below and the scan rules of
docs/semantics.md (inputs are written before the scan, rungs run in order, a prescan pass
clears every OTE output, RM003I "Prescan"); the shortest runs are counted scan by scan in the
comments.  The coverage of the three-axis recovery follows from docs/programs.md: an MSF on a
shut-down axis errs with ERR 12 (domain-facts §1b), an MSF on a running axis passes through
Stopping to Stopped, an MAFR takes a faulted axis to Stopped.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from checker.cli import main
from checker.program_check import load_program_system, run_system, scenario_document, write_scenario
from statecharts.diagnostics import InputError
from statecharts.loader import load_spec
from statecharts.scenario import load_scenario, run_scenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "programs"
SPEC = load_spec()
HEAD = "format: motionchart-program-system/1\n"


def _system(tmp_path: Path, program: str, body: str):
    (tmp_path / "p.txt").write_text(program, encoding="utf-8")
    f = tmp_path / "p.check.yaml"
    f.write_text(HEAD + "program: p.txt\n" + body, encoding="utf-8")
    return load_program_system(f, SPEC)


def _verdict(report, name: str):
    return next(v for v in report.verdicts if v.prop.name == name)


def _replays(report, system, verdict, tmp_path: Path) -> dict:
    doc = scenario_document(report.model, system, report.graph, verdict, tmp_path)
    out = tmp_path / "ce.yaml"
    write_scenario(doc, out)
    result = run_scenario(load_scenario(out, SPEC), SPEC)
    assert result.passed, [str(x) for x in result.mismatches]
    return doc


# rung 0 compares this scan's RECIPE with the last scan's (PREV) while GO was set in the last scan
# (WAS_GO); rung 1 remembers RECIPE, rung 2 remembers GO.
RECIPE_PROGRAM = ("XIC(WAS_GO)NEQ(RECIPE,PREV)OTL(CHANGED_WHILE_GO);\nMOV(RECIPE,PREV);\n"
                  "XIC(GO)OTE(WAS_GO);\nXIC(SEEN2)EQU(RECIPE,1)OTL(BACK);\nEQU(RECIPE,2)OTL(SEEN2);\n"
                  "XIC(GO)MSO(X_axis,X_MSO);\n")
# a scenario (the counterexamples) has at least one axis
AXIS = "axes:\n  X_axis: {type: AXIS_CIP_DRIVE, starts: [Stopped]}\n"
RECIPE_PROPS = ("properties:\n  - {name: steady while GO, kind: invariant, expr: not CHANGED_WHILE_GO,\n"
                "     source: 'MC tests/test_program_check_environment.py'}\n"
                "  - {name: never back, kind: invariant, expr: not BACK}\n")


def test_an_input_that_changes_only_while_a_condition_holds(tmp_path: Path) -> None:
    free = _system(tmp_path, RECIPE_PROGRAM, AXIS + "tags: {RECIPE: 1, PREV: 1}\ninputs: {GO: BOOL, RECIPE: [1, 2]}\n"
                   + RECIPE_PROPS)
    report = run_system(free, SPEC)
    v = _verdict(report, "steady while GO")
    # by hand: scan 1 GO (WAS_GO set), scan 2 RECIPE 2 while WAS_GO: two scans, none shorter (WAS_GO is
    # clear before scan 1)
    assert v.holds is False and len(v.path) - 1 == 2
    assert v.prop.source == "MC tests/test_program_check_environment.py"
    _replays(report, free, v, tmp_path)
    guarded = _system(tmp_path, RECIPE_PROGRAM, AXIS + "tags: {RECIPE: 1, PREV: 1}\n"
                      "inputs: {GO: BOOL, RECIPE: {values: [1, 2], while: not GO}}\n" + RECIPE_PROPS)
    report = run_system(guarded, SPEC)
    assert report.graph.complete and _verdict(report, "steady while GO").holds is True
    # it still changes while GO is clear: 1 -> 2 -> 1 in two scans
    assert _verdict(report, "never back").holds is False


@pytest.mark.parametrize(("budget", "holds"), [(1, True), (2, False)])
def test_counted_input_changes_spend_the_runs_budget(tmp_path: Path, budget: int, holds: bool) -> None:
    system = _system(tmp_path, RECIPE_PROGRAM, AXIS + f"tags: {{RECIPE: 1, PREV: 1}}\nmax_events: {budget}\n"
                     "inputs: {GO: BOOL, RECIPE: {values: [1, 2], counted: true}}\n" + RECIPE_PROPS)
    report = run_system(system, SPEC)
    assert report.graph.complete
    v = _verdict(report, "never back")
    # BACK needs RECIPE 1 -> 2 -> 1: two changes; GO is free and costs nothing
    assert v.holds is holds
    if not holds:
        assert len(v.path) - 1 == 2
        assert report.model.getter("events")(report.graph.states[v.path[-1]]) == 2
        _replays(report, system, v, tmp_path)


def test_a_prescan_at_any_scan(tmp_path: Path) -> None:
    body = AXIS + "inputs: {A: BOOL}\nproperties:\n  - {name: B follows A, kind: invariant, expr: B == A}\n"
    program = "XIC(A)OTE(B);\nXIC(A)MSO(X_axis,X_MSO);\n"
    system = _system(tmp_path, program, body)
    assert run_system(system, SPEC).verdicts[0].holds is True
    system = _system(tmp_path, program, "prescan: true\n" + body)
    report = run_system(system, SPEC)
    v = report.verdicts[0]
    # by hand: scan 1 with A (B set), then a prescan pass: the OTE is cleared, A is as it was
    assert v.holds is False and len(v.path) - 1 == 2
    assert report.model.choice(report.graph.via[v.path[-1]]).prescan
    doc = _replays(report, system, v, tmp_path)
    assert doc["steps"][1]["prescan"] is True
    assert "^ a prescan pass" in report.text()  # the engine replays the path the report shows


def test_a_writable_chart_variable_set_by_the_environment(tmp_path: Path) -> None:
    axes = "axes:\n  X_axis: {type: AXIS_CIP_DRIVE, starts: [Stopped], set: {FlyingStartEnable: [true]}}\n"
    props = "properties:\n  - {name: no flying start, kind: invariant, expr: not X_axis.FlyingStartEnable}\n"
    program = "XIC(GO)MSO(X_axis,X_MSO);\n"
    system = _system(tmp_path, program, axes + "inputs: {GO: BOOL}\n" + props)
    assert run_system(system, SPEC).verdicts[0].holds is True  # max_events 0: no set
    system = _system(tmp_path, program, axes + "inputs: {GO: BOOL}\nmax_events: 1\n" + props)
    report = run_system(system, SPEC)
    v = report.verdicts[0]
    assert v.holds is False and len(v.path) - 1 == 1
    assert report.model.choice(report.graph.via[v.path[-1]]).set == ("X_axis", "FlyingStartEnable", True)
    doc = _replays(report, system, v, tmp_path)
    assert doc["steps"][0]["set"] == {"X_axis": {"FlyingStartEnable": True}}
    assert "^ X_axis.FlyingStartEnable set to True before the scan" in report.text()


def test_bad_environment_entries_are_located(tmp_path: Path) -> None:
    body = ("axes:\n  X_axis: {type: AXIS_CIP_DRIVE, set: {CIPAxisState: [1], FlyingStartEnable: [3]}}\n"
            "inputs: {GO: {values: BOOL, whilst: GO}}\nprescan: sometimes\nunreached: {X_MSO 99: no such code}\n"
            "properties:\n  - {name: p, kind: invariant, expr: GO, interpretation: INT-999}\n")
    with pytest.raises(InputError) as info:
        _system(tmp_path, "XIC(GO)MSO(X_axis,X_MSO);\n", body)
    text = "\n".join(str(d) for d in info.value.diagnostics)
    assert "p.check.yaml:4:" in text and "'CIPAxisState' is not a writable variable" in text
    assert "FlyingStartEnable: expected true or false" in text
    assert "p.check.yaml:5:" in text and "unknown key 'whilst'" in text
    assert "p.check.yaml:6:" in text and "prescan: true" in text
    assert "p.check.yaml:7:" in text and "'X_MSO 99' is not a coverage item" in text
    assert "INT-999 is not an interpretation" in text


def test_coverage_tables_of_the_recovery(tmp_path: Path) -> None:
    src = (EXAMPLES / "fault_recovery.check.yaml").read_text(encoding="utf-8")
    f = tmp_path / "r.check.yaml"
    f.write_text(src.replace("program: fault_recovery.L5X", f"program: {EXAMPLES / 'fault_recovery.L5X'}")
                 + "unreached:\n  X_axis Starting: no MSO in the recovery\n", encoding="utf-8")
    report = run_system(load_program_system(f, SPEC), SPEC)
    cov = report.coverage()
    codes = cov["error_codes"]
    # every MSF can end with 12 (a shut-down axis), nothing else; no MAFR errs
    assert set(codes["reached"]) == {"X_AXIS_STAT[0] 12", "Y_AXIS_STAT[0] 12", "Z_AXIS_STAT[0] 12"}
    assert "X_AXIS_STAT[1] 11" in codes["unreached"]
    states = cov["states"]
    assert {s.split()[1] for s in states["reached"] if s.startswith("X_axis ")} == {
        "Running", "Stopping", "Stopped", "Faulted", "Shutdown"}
    assert states["explained"] == {"X_axis Starting": "no MSO in the recovery"}
    text = report.text()
    assert "error codes of X_AXIS_STAT[0] (MSF): 1/" in text
    assert "Starting (explained)" in text


def test_cli_json_has_the_tables(capsys: pytest.CaptureFixture[str]) -> None:
    import json
    assert main(["check", "--system", "interlock", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["coverage"]["error_codes"]["reached"] == []  # no fault: no MSO or MSF errs
    assert "X_axis Running" in doc["coverage"]["states"]["reached"]
