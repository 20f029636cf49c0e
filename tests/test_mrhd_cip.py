"""MRHD on CIP axes: the In Process law, every Hookup Test Status and error found by
hypothesis exploration, and bad operand input.

Written from 000 (MRHD): Hookup Test Status values 0-6, .IP set on the rising rung and
cleared when the test ends, PC and DN set with IP cleared, and the extended errors 1,
12 and 16 under Servo Message Failure (12); the error codes chosen where 000 is silent
are those of INT-049, and those of an axis that cannot run a test at all (inhibited,
ungrouped, without a drive, still initializing or waiting for its motion group) are
those of INT-042 and INT-060.  Every status value, every error and every precondition
failure must be produced both by a hand-written scenario under ``scenarios/mrhd/`` and
by hypothesis exploration.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import Phase, find, given, settings
from hypothesis import strategies as st

try:
    import statecharts  # noqa: F401  # only whether the project is installed
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from conftest import ScenarioRuns, sampled

from statecharts import ir
from statecharts.diagnostics import ScenarioError
from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scan import EnvironmentEvent, ScanInputs, System
from statecharts.scenario import load_scenario, scenario_files

SPEC = load_spec()
#: a 500 ms coarse update makes the 2 s time-out four updates long
SCAN_MS = COARSE_MS = 500
TAGS = ("mrhd", "msf", "masd", "mafr", "masr", "mso")
ENV = ("test_moved_positive", "test_moved_negative", "marker_detected", "test_no_counts",
       "axis_fault", "safety_fault", "start_inhibit_set", "start_inhibit_cleared", "connection_loss")
#: The wider exploration adds the drive's Shutdown fault action and the events that let
#: an axis that is not yet operational move on.
ENV_WIDE = (*ENV, "shutdown_fault_action", "group_synchronized", "uninhibit", "group_assigned",
            "device_associated", "connection_established", "dc_bus_up")
MRHD_DIR = Path(__file__).resolve().parents[1] / "scenarios" / "mrhd"
#: Exploration looks for one example; shrinking it would only cost time.
FIND_SETTINGS = settings(max_examples=5000, database=None, phases=[Phase.explicit, Phase.generate])

#: What a start state of the wider exploration needs besides a connection and a DC bus
#: to stay in that state.
START_VARIABLES: dict[str, dict[str, object]] = {
    "Shutdown": {"ShutdownRequested": True},
    "PreCharge": {"DCBusUp": False},
    "AxisInhibited": {"Inhibited": True, "Connected": False},
    "NotGrouped": {"Grouped": False, "Connected": False},
    "NoDevice": {"DeviceAssociated": False, "Connected": False},
    "Initializing": {"Connected": False},
    "WaitingForGroup": {"GroupSynchronized": False},
    "Faulted": {"MajorFault": True, "PhysicalAxisFault": True},
    "Aborting": {"MajorFault": True, "PhysicalAxisFault": True, "StoppingUpdates": 2, "Timer": 2},
    "StartInhibited": {"StartInhibit": True},
    "Testing": {"TestRequested": True},
}


def _system(start: str, variables: dict[str, object]) -> System:
    params = {"scan_ms": SCAN_MS, "coarse_update_ms": COARSE_MS}
    base = {"Connected": True, "DCBusUp": True}
    base.update(variables)
    axis = AxisInstance(SPEC.chart("AxisCIP"), "A", state=start, variables=base, parameters=params)
    program = [("mrhd", "MRHD", "A"), ("msf", "MSF", "A"), ("masd", "MASD", "A"), ("mafr", "MAFR", "A"),
               ("masr", "MASR", "A"), ("mso", "MSO", "A")]
    return System(SPEC, [axis], program, scan_ms=SCAN_MS, coarse_update_ms=COARSE_MS)


_IDLE = st.tuples(st.just("idle"), st.just(""), st.just(True))
_STEP = st.one_of(
    st.tuples(st.just("rung"), st.sampled_from(TAGS), st.booleans()),
    st.tuples(st.just("event"), st.sampled_from(ENV), st.just(True)),
    _IDLE, _IDLE,
)
_STEP_WIDE = st.one_of(
    st.tuples(st.just("rung"), st.sampled_from(TAGS), st.booleans()),
    st.tuples(st.just("event"), st.sampled_from(ENV_WIDE), st.just(True)),
    _IDLE, _IDLE,
)
#: Every state an MRHD can meet, each set up so that it holds (START_VARIABLES).
_RUN_WIDE = st.fixed_dictionaries({
    "wide": st.just(True),
    "start": st.sampled_from(["Stopped", "Running", "Shutdown", "PreCharge", "AxisInhibited", "NotGrouped",
                              "NoDevice", "Initializing", "WaitingForGroup", "Faulted", "Aborting",
                              "StartInhibited", "Testing"]),
    "test": st.sampled_from([0, 1, 2, 3, 7]),
    "channel": st.sampled_from([1, 2]),
    "motor": st.sampled_from(["PM", "Induction"]),
    "feedback_only": st.sampled_from([False, False, False, True]),
    "pre_event": st.sampled_from([None, None, *ENV_WIDE]),
    "lead": st.booleans(),
    "steps": st.lists(_STEP_WIDE, max_size=10),
})
_RUN = st.fixed_dictionaries({
    "start": st.sampled_from(["Stopped", "Stopped", "Running", "Shutdown", "PreCharge"]),
    "test": st.sampled_from([0, 1, 2, 3, 7]),
    "channel": st.sampled_from([1, 2]),
    "motor": st.sampled_from(["PM", "Induction"]),
    "feedback_only": st.sampled_from([False, False, False, True]),
    "lead": st.booleans(),
    "steps": st.lists(_STEP, max_size=14),
})


def _run(run: dict[str, object], check_law: bool = False) -> list[dict[str, dict[str, object]]]:
    variables: dict[str, object] = {"HookupTestFeedbackChannel": run["channel"], "MotorType": run["motor"]}
    if run["feedback_only"]:
        variables["AxisConfiguration"] = "FeedbackOnly"
    if run.get("wide"):
        variables.update(START_VARIABLES.get(str(run["start"]), {}))
    elif run["start"] == "Shutdown":
        variables["ShutdownRequested"] = True
    system = _system(str(run["start"]), variables)
    system.tags["mrhd"].operands.update({"DiagnosticTest": run["test"]})
    rungs = dict.fromkeys(TAGS, False)
    seen = []
    # a run may start with one environment event, then the MRHD rung going true, so that
    # the exploration meets the interesting cases often enough
    lead = [("event", run["pre_event"], True)] if run.get("pre_event") else []
    lead += [("rung", "mrhd", True)] if run.get("lead") else []
    for kind, name, value in [*lead, *run["steps"]]:
        events: tuple[EnvironmentEvent, ...] = ()
        if kind == "rung":
            rungs[name] = value
        elif kind == "event":
            events = (EnvironmentEvent("A", name),)
        record = system.scan(ScanInputs(rungs=dict(rungs), events=events))
        obs = {k: dict(v) for k, v in record.observations.items()}
        seen.append(obs)
        if check_law:
            a, t = obs["A"], obs["mrhd"]
            # Hookup Test Status is 1 exactly while the test is in process (IP)
            assert (a["HookupTestStatus"] == 1) == bool(t["IP"]), obs
            assert 0 <= a["HookupTestStatus"] <= 6
            # 001 Testing: a Run Test service that needs the power structure runs through
            # Starting and Testing with it on (the motor/encoder and commutation tests);
            # 000: the encoder and marker tests make no motion and only watch the
            # feedback, on a servo axis in Stopped or a feedback-only one (INT-073)
            if a["HookupTestStatus"] == 1:
                if run["test"] in (0, 3):
                    assert a["state"] in ("Starting", "Testing") and a["PowerStructureEnabled"], obs
                else:
                    assert a["state"] == ("Running" if run["feedback_only"] else "Stopped"), obs
                    assert not a["PowerStructureEnabled"] and not a["DriveEnableStatus"], obs
            # PC and DN together; IP never with DN, PC or ER
            assert bool(t["PC"]) == bool(t["DN"]) and not (t["IP"] and (t["DN"] or t["ER"]))
    return seen


@given(run=st.one_of(_RUN, _RUN_WIDE))
def test_test_status_is_one_exactly_while_in_process(run: dict[str, object]) -> None:
    _run(run, check_law=True)


def _final(run: dict[str, object]) -> tuple[dict[str, object], dict[str, object]]:
    seen = _run(run)
    if not seen:
        return {}, {}
    return seen[-1]["A"], seen[-1]["mrhd"]


@pytest.mark.parametrize("status", sampled(range(7), fast={0, 1, 2, 3, 4}))
def test_every_hookup_test_status_is_found_by_exploration(status: int) -> None:
    found = find(_RUN, lambda r: _final(r)[0].get("HookupTestStatus") == status,
                 settings=FIND_SETTINGS)
    assert _final(found)[0]["HookupTestStatus"] == status


@pytest.mark.parametrize("err, exerr", [(12, 1), (12, 12), (12, 16), (13, 2), (8, 0), (15, 0), (20, 0)])
def test_every_mrhd_error_is_found_by_exploration(err: int, exerr: int) -> None:
    found = find(_RUN, lambda r: (lambda t: t.get("ER") and t.get("ERR") == err and t.get("EXERR") == exerr)(_final(r)[1]),
                 settings=FIND_SETTINGS)
    assert _final(found)[1]["ERR"] == err


#: Each precondition failure as (axis state when MRHD executes, ERR, EXERR), written from
#: 000 (Test Status paragraph, extended errors 12 and 16, Diagnostic Test 0-3,
#: commutation only for a PM motor) and INT-049, INT-042, INT-060.
PRECONDITION_FAILURES = {
    ("Running", 12, 16): "not Stopped (Device in wrong state)",
    ("PreCharge", 12, 16): "not Stopped (Device in wrong state)",
    ("Shutdown", 12, 12): "Shutdown (Object Mode conflict)",
    ("Stopped", 13, 2): "Diagnostic Test outside 0-3 (third operand)",
    ("Stopped", 8, 0): "commutation test on an induction motor",
    ("Running", 8, 0): "motor/encoder or commutation test on a feedback-only axis",
    ("Faulted", 20, 0): "faulted",
    ("Aborting", 20, 0): "aborting a major fault",
    ("Stopped", 20, 0): "safety fault latched",
    ("AxisInhibited", 53, 0): "inhibited",
    ("NotGrouped", 11, 0): "no motion group",
    ("NoDevice", 11, 0): "no drive",
    ("Initializing", 82, 0): "waiting for its connection",
    ("WaitingForGroup", 82, 0): "waiting for its motion group",
}


def _scenario_outcomes(runs: ScenarioRuns) -> tuple[set[int], set[tuple[int, int]], set[tuple[str, int, int]]]:
    """Hookup Test Status values, MRHD (ERR, EXERR) pairs, and (axis state, ERR, EXERR)
    when an MRHD tag's ER rises, over every scenario under scenarios/mrhd/ (run once per
    session, conftest)."""
    statuses: set[int] = set()
    errors: set[tuple[int, int]] = set()
    refusals: set[tuple[str, int, int]] = set()
    for path in scenario_files([MRHD_DIR]):
        result = runs.result(path)
        scenario = result.scenario
        assert result.passed, f"{path.name}: " + "; ".join(str(m) for m in result.mismatches)
        axis_of = {p.tag: p.axis for p in scenario.program if p.instruction == "MRHD"}
        er_before = dict.fromkeys(axis_of, False)
        for row in result.rows:
            obs = row.record.observations
            for a in scenario.axes:
                if a.chart == "AxisCIP":
                    statuses.add(int(obs[a.name]["HookupTestStatus"]))
            for tag, axis in axis_of.items():
                t = obs[tag]
                if t["ER"]:
                    errors.add((int(t["ERR"]), int(t["EXERR"])))
                    if not er_before[tag]:
                        refusals.add((str(obs[axis]["state"]), int(t["ERR"]), int(t["EXERR"])))
                er_before[tag] = bool(t["ER"])
    return statuses, errors, refusals


def test_scenarios_produce_every_status_error_and_precondition_failure(scenario_runs: ScenarioRuns) -> None:
    statuses, errors, refusals = _scenario_outcomes(scenario_runs)
    assert set(range(7)) <= statuses, f"Hookup Test Status values no scenario shows: {set(range(7)) - statuses}"
    # 000: extended errors 1, 12, 16 under Servo Message Failure (12); INT-049: 15 for a failed test
    wanted = {(12, 1), (12, 12), (12, 16), (15, 0)}
    assert wanted <= errors, f"MRHD errors no scenario produces: {wanted - errors}"
    missing = {k: v for k, v in PRECONDITION_FAILURES.items() if k not in refusals}
    assert not missing, f"precondition failures no scenario produces: {missing}"


@pytest.mark.parametrize("state, err, exerr", sampled(sorted(PRECONDITION_FAILURES), fast={
    ("Running", 12, 16), ("PreCharge", 12, 16), ("Faulted", 20, 0), ("Aborting", 20, 0), ("AxisInhibited", 53, 0),
    ("NoDevice", 11, 0), ("WaitingForGroup", 82, 0)}), ids=lambda v: str(v))
def test_every_precondition_failure_is_found_by_exploration(state: str, err: int, exerr: int) -> None:
    def refused_there(r: dict[str, object]) -> bool:
        seen = _run(r)
        for before, after in zip([None, *seen], seen):
            t, was = after["mrhd"], (before or {}).get("mrhd", {"ER": False})
            if t["ER"] and not was["ER"] and (t["ERR"], t["EXERR"]) == (err, exerr) and after["A"]["state"] == state:
                return True
        return False

    found = find(_RUN_WIDE, refused_there, settings=FIND_SETTINGS)
    assert refused_there(found)


@pytest.mark.parametrize("err", sampled([53, 11, 82], fast={11, 82}))
def test_errors_of_an_axis_not_yet_operational_are_found_by_exploration(err: int) -> None:
    found = find(_RUN_WIDE, lambda r: (lambda t: t.get("ER") and t.get("ERR") == err)(_final(r)[1]),
                 settings=FIND_SETTINGS)
    assert _final(found)[1]["ERR"] == err


def test_unknown_diagnostic_test_text_is_a_clear_scenario_error(tmp_path: Path) -> None:
    p = tmp_path / "bad.yaml"
    p.write_text(
        "format: motionchart-scenario/1\nname: bad\nsources: [x]\ncovers: [x]\n"
        "setup:\n  axes:\n    A: {type: AXIS_CIP_DRIVE, state: Stopped}\n"
        "  program:\n    - {tag: t, instruction: MRHD, axis: A, operands: {DiagnosticTest: hookup}}\n"
        "steps:\n  - rungs: {t: true}\n", encoding="utf-8")
    with pytest.raises(ScenarioError) as exc:
        load_scenario(p, SPEC)
    text = str(exc.value)
    assert "DiagnosticTest" in text and "motor_encoder" in text and "commutation" in text


def test_mrhd_variants() -> None:
    # The CIP variant is MRHD; a servo-axis variant (MRHD_SERVO, added for AxisNonCIP by
    # the servo work) may exist beside it, but no other variant may claim the CIP chart.
    ids = [i.id for i in SPEC.variants("MRHD")]
    assert ids[0] == "MRHD"
    cip = SPEC.instruction("MRHD", "AxisCIP")
    assert isinstance(cip, ir.Instruction) and cip.id == "MRHD"
    assert [i.id for i in SPEC.variants("MRHD") if "AxisCIP" in i.charts] == ["MRHD"]
