"""MRHD on CIP axes: the In Process law, every Hookup Test Status and error found by
hypothesis exploration, and bad operand input.

Written from 000 (MRHD): Hookup Test Status values 0-6, .IP set on the rising rung and
cleared when the test ends, PC and DN set with IP cleared, and the extended errors 1,
12 and 16 under Servo Message Failure (12); the error codes chosen where 000 is silent
are those of INT-049.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, find, given, settings, strategies as st

try:
    import statecharts  # noqa: F401
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from statecharts import ir
from statecharts.diagnostics import ScenarioError
from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scan import EnvironmentEvent, ScanInputs, System
from statecharts.scenario import load_scenario

SPEC = load_spec()
#: a 500 ms coarse update makes the 2 s time-out four updates long
SCAN_MS = COARSE_MS = 500
TAGS = ("mrhd", "msf", "masd", "mafr", "masr", "mso")
ENV = ("test_moved_positive", "test_moved_negative", "marker_detected", "test_no_counts",
       "axis_fault", "safety_fault", "start_inhibit_set", "start_inhibit_cleared", "connection_loss")


def _system(start: str, variables: dict[str, object]) -> System:
    params = {"scan_ms": SCAN_MS, "coarse_update_ms": COARSE_MS}
    base = {"Connected": True, "DCBusUp": True}
    base.update(variables)
    axis = AxisInstance(SPEC.chart("AxisCIP"), "A", state=start, variables=base, parameters=params)
    program = [("mrhd", "MRHD", "A"), ("msf", "MSF", "A"), ("masd", "MASD", "A"), ("mafr", "MAFR", "A"),
               ("masr", "MASR", "A"), ("mso", "MSO", "A")]
    return System(SPEC, [axis], program, scan_ms=SCAN_MS, coarse_update_ms=COARSE_MS)


_STEP = st.one_of(
    st.tuples(st.just("rung"), st.sampled_from(TAGS), st.booleans()),
    st.tuples(st.just("event"), st.sampled_from(ENV), st.just(True)),
    st.tuples(st.just("idle"), st.just(""), st.just(True)),
)
_RUN = st.fixed_dictionaries({
    "start": st.sampled_from(["Stopped", "Stopped", "Running", "Shutdown", "PreCharge"]),
    "test": st.sampled_from([0, 1, 2, 3, 7]),
    "channel": st.sampled_from([1, 2]),
    "motor": st.sampled_from(["PM", "Induction"]),
    "feedback_only": st.sampled_from([False, False, False, True]),
    "steps": st.lists(_STEP, max_size=14),
})


def _run(run: dict[str, object], check_law: bool = False) -> list[dict[str, dict[str, object]]]:
    variables: dict[str, object] = {"HookupTestFeedbackChannel": run["channel"], "MotorType": run["motor"]}
    if run["feedback_only"]:
        variables["AxisConfiguration"] = "FeedbackOnly"
    if run["start"] == "Shutdown":
        variables["ShutdownRequested"] = True
    system = _system(str(run["start"]), variables)
    system.tags["mrhd"].operands.update({"DiagnosticTest": run["test"]})
    rungs = {t: False for t in TAGS}
    seen = []
    for kind, name, value in run["steps"]:  # type: ignore[attr-defined]
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
            # a test in process runs in Starting or Testing with the power structure on
            assert a["HookupTestStatus"] != 1 or (a["state"] in ("Starting", "Testing") and a["PowerStructureEnabled"])
            # PC and DN together; IP never with DN, PC or ER
            assert bool(t["PC"]) == bool(t["DN"]) and not (t["IP"] and (t["DN"] or t["ER"]))
    return seen


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(run=_RUN)
def test_test_status_is_one_exactly_while_in_process(run: dict[str, object]) -> None:
    _run(run, check_law=True)


def _final(run: dict[str, object]) -> tuple[dict[str, object], dict[str, object]]:
    seen = _run(run)
    if not seen:
        return {}, {}
    return seen[-1]["A"], seen[-1]["mrhd"]


@pytest.mark.parametrize("status", range(7))
def test_every_hookup_test_status_is_found_by_exploration(status: int) -> None:
    found = find(_RUN, lambda r: _final(r)[0].get("HookupTestStatus") == status,
                 settings=settings(max_examples=5000, database=None, deadline=None))
    assert _final(found)[0]["HookupTestStatus"] == status


@pytest.mark.parametrize("err, exerr", [(12, 1), (12, 12), (12, 16), (13, 2), (8, 0), (15, 0), (20, 0)])
def test_every_mrhd_error_is_found_by_exploration(err: int, exerr: int) -> None:
    found = find(_RUN, lambda r: (lambda t: t.get("ER") and t.get("ERR") == err and t.get("EXERR") == exerr)(_final(r)[1]),
                 settings=settings(max_examples=5000, database=None, deadline=None))
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
    assert [i.id for i in SPEC.variants("MRHD")] == ["MRHD"]
    assert isinstance(SPEC.instruction("MRHD", "AxisCIP"), ir.Instruction)
