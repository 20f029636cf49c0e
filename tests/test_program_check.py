"""The program checker: whole-controller properties of a ladder program on its axes.

The expected verdicts are worked out by hand from the routines and the documented
instruction behaviour (docs/programs.md): an MSF on a shut-down axis errs with ERR 12 /
EXERR 12 (domain-facts §1b), its DN never comes, the MAFR of that axis never executes and
the one-shot never retries; so the recovery hangs exactly from the starts in which some
axis is in Shutdown, 64 - 3**3 = 37 of the 64.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from checker.cli import main
from checker.program_check import load_program_system, run_system, scenario_document, write_scenario
from checker.program_model import AxisSetup, ProgramModel, ProgramModelError, Start
from checker.program_search import ProgramProperty, parse_property_text
from statecharts.loader import load_spec
from statecharts.program.environment import CIP_STARTS
from statecharts.program.reader import parse_program_text
from statecharts.program.strategies import PROGRAM_INPUTS, programs
from statecharts.scenario import load_scenario, run_scenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "programs"
SPEC = load_spec()
AXES = ("X_axis", "Y_axis", "Z_axis")


@pytest.fixture(scope="module")
def recovery():
    system = load_program_system(EXAMPLES / "fault_recovery.check.yaml", SPEC)
    return system, run_system(system, SPEC)


def test_recovery_hangs_exactly_from_the_starts_with_an_axis_in_shutdown(recovery) -> None:
    _system, report = recovery
    hang = next(v for v in report.verdicts if v.prop.kind == "always_reachable")
    assert hang.holds is False
    labels = {report.graph.starts[i].label for i in hang.hanging_starts}
    expected = {", ".join(f"{a}={s}" for a, s in zip(AXES, combo))
                for combo in itertools.product(CIP_STARTS, repeat=3) if "Shutdown" in combo}
    assert len(report.graph.starts) == 64
    assert labels == expected and len(labels) == 37
    fair = next(v for v in report.verdicts if v.prop.kind == "eventually")
    assert fair.holds is False and {report.graph.starts[i].label for i in fair.hanging_starts} == expected
    # the trap: state 9 for ever, the shut-down axis's MSF erred with 12/12, its MAFR never ran
    m, g = report.model, report.graph
    for u in hang.trap:
        values = m.describe(g.states[u])
        assert values["NEXTSTATE"] == 9 and values["STATE"] == 9
        down = [a for a in AXES if values[f"{a}.state"] == "Shutdown"]
        assert down
        for a in down:
            tag = f"{a[0]}_AXIS_STAT"
            assert (values[f"{tag}[0].ER"], values[f"{tag}[0].ERR"], values[f"{tag}[0].EXERR"]) == (True, 12, 12)
            assert values[f"{tag}[1].EN"] is False
    # coverage: MSF can end in 12/12 here
    errors = {(e["instruction"], e["ERR"], e["EXERR"]) for e in report.coverage()["motion_errors"]}
    assert errors == {("MSF", 12, 12)}


def test_recovery_counterexample_replays_as_a_program_scenario(recovery, tmp_path: Path) -> None:
    system, report = recovery
    for v in report.verdicts:
        assert v.holds is False
        doc = scenario_document(report.model, system, report.graph, v, tmp_path)
        out = tmp_path / f"{v.prop.kind}.yaml"
        write_scenario(doc, out)
        result = run_scenario(load_scenario(out, SPEC), SPEC)
        assert result.passed, [str(x) for x in result.mismatches]
        if v.prop.kind == "always_reachable":
            always = doc["steps"][-1]["always"]
            assert always["NEXTSTATE"] == 9 and always["Z_AXIS_STAT[0].ER"] is True
            assert always["Z_axis"] == {"state": "Shutdown"}


def test_fixed_recovery_never_hangs() -> None:
    system = load_program_system(EXAMPLES / "fault_recovery_fixed.check.yaml", SPEC)
    report = run_system(system, SPEC, extra=[parse_property_text("deadlock: STATE == 1 and NEXTSTATE == 1")])
    assert report.graph.complete and len(report.graph.starts) == 64
    assert [(v.prop.kind, v.holds) for v in report.verdicts] == [
        ("always_reachable", True), ("eventually", True), ("deadlock", True)]
    assert report.exit_code == 0


def test_cli_reports_the_hang_and_writes_replayable_counterexamples(tmp_path: Path, capsys) -> None:
    code = main(["check", "--system", "fault_recovery", "--counterexamples", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 1
    assert "from 37 of 64 start(s)" in out and "MSF(" in out and "erred: ERR 12, EXERR 12" in out
    assert main(["simulate", "-q", *sorted(str(p) for p in tmp_path.glob("*.yaml"))]) == 0
    capsys.readouterr()
    assert main(["check", "--system", "fault_recovery", "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["states"] == 220 and doc["complete"] and doc["properties"][0]["holds"] is False
    assert len(doc["properties"][0]["hanging_starts"]) == 37


def test_cli_program_with_a_property(capsys) -> None:
    code = main(["check", "--program", str(EXAMPLES / "fault_recovery_fixed.txt"),
                 "--property", "always_reachable: NEXTSTATE == 1"])
    # a rung file's axes are AXIS_CIP_DRIVE starting in each preset; NEXTSTATE starts at 0 and state 9
    # is never entered: the goal is never reachable
    assert code == 1
    assert "VIOLATED" in capsys.readouterr().out


def test_bad_property_and_system_are_located_errors(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.check.yaml"
    bad.write_text("format: motionchart-program-system/1\nprogram: %s\naxes:\n  W_axis: {type: AXIS_CIP_DRIVE}\n"
                   "properties:\n  - {kind: sometimes, expr: 'A'}\n" % (EXAMPLES / "fault_recovery.L5X"))
    assert main(["check", "--system", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "bad.check.yaml:4:" in err and "W_axis is not an axis" in err
    assert "kind: one of" in err
    assert main(["check", "--system", "fault_recovery", "--property", "invariant: NOSUCH == 1"]) == 1
    assert "NOSUCH" in capsys.readouterr().err
    assert main(["check", "--system", "fault_recovery", "--property", "sometimes: A"]) == 2


# --------------------------------------------------------------------------- the one semantics rule


def _starts(draw: st.DrawFn, axes: tuple[str, ...]) -> Start:
    chosen = [draw(st.sampled_from(sorted(CIP_STARTS))) for _ in axes]
    return Start(",".join(chosen), tuple(AxisSetup(a, "AXIS_CIP_DRIVE", CIP_STARTS[s]["state"],
                                                   tuple(CIP_STARTS[s]["variables"].items()))
                                         for a, s in zip(axes, chosen)))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=programs(max_rungs=7), data=st.data())
def test_the_compiled_scan_is_the_engine_scan(text: str, data: st.DataObject) -> None:
    """Random programs and input/event sequences: every engine scan is the checker's successor
    under the same choice (so every engine run maps onto a path of the checker)."""
    _same_scans(text, data)


@pytest.mark.deep
@settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=programs(max_rungs=14), data=st.data())
def test_the_compiled_scan_is_the_engine_scan_deep(text: str, data: st.DataObject) -> None:
    _same_scans(text, data)


def _same_scans(text: str, data: st.DataObject) -> None:
    program = parse_program_text("random.txt", text, spec=SPEC, form="neutral")
    axes = tuple(t.name for t in program.axes())
    names = {t.name for t in program.tags}
    inputs = [i for i in PROGRAM_INPUTS if i in names]
    events = {a: ["axis_fault", "shutdown_fault_action"] for a in axes}
    model = ProgramModel(SPEC, program, axis_types=dict.fromkeys(axes, "AXIS_CIP_DRIVE"), inputs=inputs,
                         events=events, max_events=3)
    start = _starts(data.draw, axes)
    engine = model.engine(start)
    state = model.initial(start)
    assert state[1:] == model.encode(engine.system)[1:]
    for _scan in range(data.draw(st.integers(1, 12))):
        choice = data.draw(st.integers(0, model.nchoices - 1))
        outs = dict(model.successors(state)[0])
        if choice not in outs:  # an event beyond the budget
            continue
        ch = model.choice(choice)
        engine.scan(events=(ch.event,) if ch.event else (), **dict(ch.writes))
        state = outs[choice]
        assert state[1:] == model.encode(engine.system)[1:], (text, choice)


def test_unsupported_instructions_are_located_errors() -> None:
    program = parse_program_text("p.txt", "XIC(A)DIV(B,2,C);\n", spec=SPEC, form="neutral")
    with pytest.raises(ProgramModelError) as exc:
        ProgramModel(SPEC, program, axis_types={})
    assert "p.txt:1:" in str(exc.value) and "DIV is not modelled by the program checker" in str(exc.value)


def test_property_texts() -> None:
    p = parse_property_text("leads_to: STATE == 9 -> NEXTSTATE == 1 within 50 scans")
    assert (p.kind, p.expr, p.goal, p.within) == ("leads_to", "STATE == 9", "NEXTSTATE == 1", 50)
    assert parse_property_text("deadlock").kind == "deadlock"
    assert parse_property_text("invariant: X_AXIS_STAT[1].DN or not STATE9_IND") == ProgramProperty(
        "invariant: X_AXIS_STAT[1].DN or not STATE9_IND", "invariant", "X_AXIS_STAT[1].DN or not STATE9_IND")


# --------------------------------------------------------------------------- the interlock and seeded faults

CELL = (EXAMPLES / "three_axis_cell.txt").read_text(encoding="utf-8")


def _cell_report(tmp_path: Path, text: str):
    (tmp_path / "cell.txt").write_text(text, encoding="utf-8")
    doc = (EXAMPLES / "interlock.check.yaml").read_text(encoding="utf-8").replace(
        "program: three_axis_cell.txt", "program: cell.txt")
    (tmp_path / "cell.check.yaml").write_text(doc, encoding="utf-8")
    system = load_program_system(tmp_path / "cell.check.yaml", SPEC)
    return system, run_system(system, SPEC)


def _verdicts(report) -> dict[str, bool | None]:
    return {v.prop.name: v.holds for v in report.verdicts}


def test_the_cell_keeps_its_interlock(tmp_path: Path) -> None:
    _system, report = _cell_report(tmp_path, CELL)
    assert report.graph.complete
    assert set(_verdicts(report).values()) == {True}


@pytest.mark.parametrize(("fault", "old", "new", "broken"), [
    ("drop a contact", "XIC(X_MSO.DN)EQU(X_axis.CIPAxisState,4)MSO", "XIC(X_MSO.DN)MSO",
     "Y only after X, Z only after Y"),
    ("swap an output", "[XIC(STOP_PB),XIO(ENABLE_SW)]OTU(RUN)", "[XIC(STOP_PB),XIO(ENABLE_SW)]OTL(RUN)", "stop wins"),
    ("remove a one-shot", "XIC(START_PB)ONS(START_ONS)OTE(START_PULSE)", "XIC(START_PB)OTE(START_PULSE)",
     "the start pulse lasts one scan"),
])
def test_seeded_faults_are_found_by_the_property_they_break(tmp_path: Path, fault: str, old: str, new: str,
                                                            broken: str) -> None:
    assert old in CELL
    system, report = _cell_report(tmp_path, CELL.replace(old, new))
    verdicts = _verdicts(report)
    assert verdicts[broken] is False, fault
    assert all(v for name, v in verdicts.items() if name != broken), (fault, verdicts)
    v = next(v for v in report.verdicts if v.prop.name == broken)
    doc = scenario_document(report.model, system, report.graph, v, tmp_path)
    write_scenario(doc, tmp_path / "ce.yaml")
    result = run_scenario(load_scenario(tmp_path / "ce.yaml", SPEC), SPEC)
    assert result.passed, [str(x) for x in result.mismatches]


def test_the_dropped_interlock_has_a_shortest_counterexample_of_four_scans(tmp_path: Path) -> None:
    # By hand: the ONS storage is set by the prescan, so START must be released in scan 1 and pressed
    # in scan 2 (RUN, X's MSO executes: X Starting); X's MSO is DN at the end of scan 3 at the
    # earliest, and for X not to be Running at the end of scan 4 its MSF must be given in scan 3
    # (RUN dropped: STOP or the enable switch), START released; in scan 4 START again: Y's MSO reads
    # X_MSO.DN (still set) and executes while X is stopping: Y Starting, X not Running.  Nothing
    # shorter exists, since Y's MSO can read X_MSO.DN in scan 4 at the earliest.
    _system, report = _cell_report(tmp_path, CELL.replace("XIC(X_MSO.DN)EQU(X_axis.CIPAxisState,4)MSO",
                                                          "XIC(X_MSO.DN)MSO"))
    v = next(v for v in report.verdicts if v.prop.name == "Y only after X, Z only after Y")
    assert len(v.path) - 1 == 4
    last = report.model.describe(report.graph.states[v.path[-1]])
    assert last["Y_axis.state"] == "Starting" and last["X_axis.state"] != "Running"


def test_the_committed_hang_scenario_is_what_the_checker_writes(recovery, tmp_path: Path) -> None:
    system, report = recovery
    v = next(v for v in report.verdicts if v.prop.kind == "always_reachable")
    doc = scenario_document(report.model, system, report.graph, v, EXAMPLES)
    doc["sources"] = [s.replace(system.file, "examples/programs/fault_recovery.check.yaml") for s in doc["sources"]]
    write_scenario(doc, tmp_path / "hang.yaml")
    assert (tmp_path / "hang.yaml").read_text(encoding="utf-8") == \
        (EXAMPLES / "fault_recovery_hang.yaml").read_text(encoding="utf-8")


def test_integer_domains_computed_and_declared(tmp_path: Path) -> None:
    (tmp_path / "count.txt").write_text(
        "XIC(PART)ONS(PART_ONS)CTU(PARTS,3,0);\nXIC(PARTS.DN)XIC(ACK)RES(PARTS);\n"
        "XIC(ACK)TON(T1,25,0);\nXIC(PART)MOV(7,CODE);\nXIC(ACK)MOV(CODE,LAST);\n", encoding="utf-8")
    (tmp_path / "count.check.yaml").write_text(
        "format: motionchart-program-system/1\nprogram: count.txt\ndomains: {PARTS.ACC: [0, 4]}\n"
        "properties:\n  - {name: reset, kind: always_reachable, expr: 'PARTS.ACC == 0'}\n", encoding="utf-8")
    system = load_program_system(tmp_path / "count.check.yaml", SPEC)
    report = run_system(system, SPEC)
    domains = report.domains()
    # by hand: a 25 ms timer counted in 10 ms scans takes 0, 10, 20, 30; CODE is 0 or 7 and LAST copies it
    assert "T1.ACC: {0, 10, 20, 30} (counted in scans of 10 ms up to the preset 25)" in domains
    assert "CODE: {0, 7}" in domains and "LAST: {0, 7}" in domains
    assert "PARTS.ACC: declared 0..4 (CTU in rung 0)" in domains
    # five presses without ACK take the counter to 5: the declared domain is left, the search stops there
    v = next(v for v in report.verdicts if v.prop.name == "domain of PARTS.ACC")
    assert v.holds is False and report.model.describe(report.graph.states[v.path[-1]])["PARTS.ACC"] == 5
    assert not report.graph.complete and report.exit_code == 1


@pytest.fixture(scope="module")
def cell_graph():
    from checker.program_search import explore
    system = load_program_system(EXAMPLES / "three_axis_cell.check.yaml", SPEC)
    model = system.model(SPEC)
    start = system.starts()[0]
    return model, explore(model, [start]), start


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.fixed_dictionaries({n: st.booleans() for n in ("START_PB", "STOP_PB", "RESET_PB",
                                                                               "ENABLE_SW")}),
                          st.sampled_from([None, "X_axis", "Y_axis", "Z_axis"])), min_size=1, max_size=15))
def test_every_engine_run_is_a_path_of_the_explored_graph(cell_graph, run) -> None:
    """The engine (python-statemachine axes) driven by random button presses and axis faults: after
    every scan its state is a state of the complete exploration, reached by an edge of the graph."""
    model, graph, start = cell_graph
    assert graph.complete
    engine = model.engine(start)
    u = graph.index[model.initial(start)]
    events = 0
    for writes, fault in run:
        event = (fault, "axis_fault") if fault is not None and events < model.max_events else None
        events += event is not None
        engine.scan(events=(event,) if event else (), **writes)
        s = (events, *model.encode(engine.system)[1:])
        v = graph.index[s]
        assert v in graph.succ[u]
        u = v
