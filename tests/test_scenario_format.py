"""The scenario-format rules for writing expectations from the manuals (docs/scenarios.md,
"Writing expectations from the manuals"): tolerances, ``not:``, ``within:``,
``passes_through:``, ``set:``, the drive values a set-up state implies and preset tag
bits.  Each rule is shown to pass where the documents say it should, to fail where they
say otherwise, and to refuse a malformed use with a located message.

Also: the keys the scenario loader reads are exactly those of
``spec/schema/scenario.schema.json``.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest

from statecharts import expectations
from statecharts.diagnostics import ScenarioError
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.scenario import load_scenario, run_scenario

SPEC = load_spec()
HEAD = "format: motionchart-scenario/1\nname: t\n"
#: one step of a 16-bit DAC over 20 V (002: about 305 uV)
DAC_STEP = 20.0 / 65536


def _write(tmp_path: Path, body: str) -> Path:
    p = tmp_path / "s.yaml"
    p.write_text(HEAD + textwrap.dedent(body), encoding="utf-8")
    return p


def _run(tmp_path: Path, body: str) -> list[str]:
    result = run_scenario(load_scenario(_write(tmp_path, body), SPEC), SPEC)
    return [str(m) for m in result.mismatches]


def _errors(tmp_path: Path, body: str) -> str:
    with pytest.raises(ScenarioError) as exc:
        load_scenario(_write(tmp_path, body), SPEC)
    text = str(exc.value)
    assert "Traceback" not in text
    return text


MDO_4V = """
setup:
  scan_ms: 100
  axes:
    A: {type: AXIS_SERVO}
  program:
    - {tag: mdo, instruction: MDO, axis: A, operands: {DriveOutput: 4.0, DriveUnits: Volts}}
steps:
  - rungs: {mdo: true}
    scans: 6
    expect:
      mdo: {DN: true}
      A: {ServoOutput: %s}
"""


# ------------------------------------------------------------------------ tolerances

def test_named_dac_step_is_the_16_bit_step_of_20_volts() -> None:
    assert expectations.NAMED_TOLERANCES["dac_step"] == pytest.approx(DAC_STEP)
    assert 305e-6 < DAC_STEP < 306e-6  # 002: 305 uV


@pytest.mark.parametrize("expected, passes", [
    ("{approx: 4.0, within: dac_step}", True),       # 4 V is output as the DAC step below it
    ("{approx: 4.0, within: 0.0004}", True),
    ("{approx: 4.0, within: 0.00001}", False),       # tighter than one DAC step
    ("{approx: 4.001, within: 0.0004}", False),
    ("4.0", False),                                   # a plain value is compared to 1e-9
])
def test_tolerance_on_the_mdo_output(tmp_path: Path, expected: str, passes: bool) -> None:
    failures = _run(tmp_path, MDO_4V % expected)
    assert (failures == []) is passes, failures


def test_tolerance_errors_are_located(tmp_path: Path) -> None:
    text = _errors(tmp_path, """
        setup:
          axes:
            A: {type: AXIS_SERVO}
          program:
            - {tag: mso, instruction: MSO, axis: A}
        steps:
          - rungs: {mso: true}
            expect:
              mso: {DN: {approx: 1, within: 0.1}}
              A: {ServoOutput: {approx: 1.0, within: half_a_step}, OutputLimit: {approx: 1.0, within: -1}}
        """)
    assert "mso.DN: `approx:` applies to numbers only" in text
    assert "unknown tolerance 'half_a_step'; named tolerances: dac_step" in text
    assert "at least 0" in text
    assert "s.yaml:12:" in text  # file and line of the offending value


# ------------------------------------------------------------------------ not:

def test_not_matches_anything_but_the_value(tmp_path: Path) -> None:
    body = """
        setup:
          axes:
            A: {type: AXIS_SERVO, state: Shutdown}
          program:
            - {tag: mso, instruction: MSO, axis: A}
        steps:
          - rungs: {mso: true}
            expect:
              mso: {ER: true, ERR: {not: %s}}
        """
    # MSO on a shut-down axis: Servo Message Failure (12) with EXERR 12, Object Mode
    # conflict (domain-facts §4 MSO, RM002H-p79)
    assert _run(tmp_path, body % "0") == []
    failures = _run(tmp_path, body % "12")
    assert len(failures) == 1 and "mso.ERR expected not 12, got 12" in failures[0]


def test_not_refuses_a_structured_value(tmp_path: Path) -> None:
    text = _errors(tmp_path, """
        setup:
          axes:
            A: {type: AXIS_SERVO}
        steps:
          - expect:
              A: {AxisState: {not: 0, approx: 1}}
        """)
    assert "steps[0].expect.A" in text and "s.yaml:9:" in text  # located at the object holding it


# ------------------------------------------------------------------------ within:

WITHIN = """
setup:
  axes:
    A: {type: AXIS_CIP_DRIVE, state: Stopped}
  program:
    - {tag: mso, instruction: MSO, axis: A}
steps:
  - rungs: {mso: true}
    within: %d
    expect:
      mso: {DN: true}
  - expect:
      mso: {DN: true}
"""


def test_within_ends_the_step_when_the_expectations_hold(tmp_path: Path) -> None:
    # 001: Stopped, Enable -> Starting -> (conditions met) Running; DN when Running
    result = run_scenario(load_scenario(_write(tmp_path, WITHIN % 50), SPEC), SPEC)
    assert result.passed
    first_step = [r for r in result.rows if r.step == 0]
    assert 1 < len(first_step) < 50  # the step stopped early, after more than one scan
    assert result.rows[len(first_step) - 1].record.observations["mso"]["DN"] is True


def test_within_fails_when_the_expectations_never_hold_in_time(tmp_path: Path) -> None:
    failures = _run(tmp_path, WITHIN % 1)
    assert failures and "scan 0: mso.DN expected true, got false" in failures[0]


def test_within_and_scans_together_are_refused(tmp_path: Path) -> None:
    text = _errors(tmp_path, """
        setup:
          axes:
            A: {type: AXIS_SERVO}
        steps:
          - within: 3
            scans: 3
            expect:
              A: {AxisState: 0}
          - within: 3
        """)
    assert "either `scans:`" in text and "needs expectations to wait for" in text


# ------------------------------------------------------------------------ passes_through:

PASSES = """
setup:
  axes:
    A: {type: AXIS_CIP_DRIVE, state: Running}
  program:
    - {tag: msf, instruction: MSF, axis: A}
steps:
  - rungs: {msf: true}
    scans: 4
    expect:
      A: {passes_through: %s}
"""


@pytest.mark.parametrize("states, passes", [
    ("[Stopping, Stopped]", True),            # 001 Stopping: Disable in Running, then Stopped
    ("[Running, Stopping, Stopped]", True),   # the state at the start counts
    ("[PowerActive, Standby]", True),         # compound states may be named
    ("[Stopped, Stopping]", False),           # order matters
    ("[Aborting]", False),                    # a Disable does not abort
])
def test_passes_through(tmp_path: Path, states: str, passes: bool) -> None:
    failures = _run(tmp_path, PASSES % states)
    assert (failures == []) is passes, failures


def test_passes_through_sees_a_state_left_within_one_coarse_update(tmp_path: Path) -> None:
    # A Shutdown Reset from Shutdown goes to Pre-Charge, and with the DC bus kept up on
    # to Stopped (001 Shutdown): Pre-Charge never ends a scan here
    body = """
        setup:
          axes:
            A: {type: AXIS_CIP_DRIVE, state: Shutdown}
          program:
            - {tag: masr, instruction: MASR, axis: A}
        steps:
          - rungs: {masr: true}
            expect:
              A: {state: Stopped, passes_through: [Shutdown, PreCharge, Stopped]}
        """
    result = run_scenario(load_scenario(_write(tmp_path, body), SPEC), SPEC)
    assert result.passed, result.mismatches
    assert all(r.record.observations["A"]["state"] != "PreCharge" for r in result.rows)


def test_passes_through_names_only_states_of_the_chart(tmp_path: Path) -> None:
    text = _errors(tmp_path, PASSES % "[Stoping]")
    assert "chart AxisCIP has no state 'Stoping'" in text
    text = _errors(tmp_path, PASSES % "[]")
    assert "passes_through" in text


# ------------------------------------------------------------------------ set:

def test_set_writes_an_attribute_as_ssv_does(tmp_path: Path) -> None:
    # 002: an Output Limit reduced below the present output clamps the Servo Output
    body = """
        setup:
          scan_ms: 100
          axes:
            A: {type: AXIS_SERVO}
          program:
            - {tag: mdo, instruction: MDO, axis: A, operands: {DriveOutput: 4.0, DriveUnits: Volts}}
            - {tag: mdf, instruction: MDF, axis: A}
        steps:
          - rungs: {mdo: true}
            scans: 6
          - set: {A: {OutputLimit: 2.5, OutputOffset: 0.25}}
            expect:
              A: {OutputLimit: 2.5, ServoOutput: {approx: 2.5, within: dac_step}}
          - name: MDF returns the output to the Output Offset the program wrote (001 MDF)
            rungs: {mdf: true}
            expect:
              A: {AxisState: 0, ServoOutput: 0.25}
        """
    assert _run(tmp_path, body) == []


def test_set_refuses_what_a_program_cannot_write(tmp_path: Path) -> None:
    text = _errors(tmp_path, """
        setup:
          axes:
            A: {type: AXIS_SERVO}
        steps:
          - set: {A: {ServoOutput: 1.0, OutputLimit: high, Nope: 1}, B: {OutputLimit: 1.0}}
        """)
    assert "chart AxisNonCIP has no writable attribute 'ServoOutput'; a program may write: " in text
    assert "OutputLimit" in text and "FaultAction" in text
    assert "OutputLimit: expected a number, got 'high'" in text
    assert "no variable 'Nope'" in text
    assert "unknown axis 'B'" in text


def test_writable_attributes_are_configuration_not_status() -> None:
    for chart in SPEC.charts:
        for v in chart.variables:
            if v.writable:
                assert not v.name.endswith("Status"), (chart.id, v.name)


# ------------------------------------------------------------------------ implied set-up values

@pytest.mark.parametrize("state, implied", [
    # 001 Stopped: main power applied, DC bus at operational level; connected (Initializing done)
    ("Stopped", {"Connected": True, "DCBusUp": True}),
    ("Running", {"Connected": True, "DCBusUp": True}),
    # 001 Shutdown: left only by a Shutdown Reset
    ("Shutdown", {"ShutdownRequested": True}),
    # 001 Faulted: faults are latched conditions
    ("Faulted", {"MajorFault": True}),
    ("StartInhibited", {"StartInhibit": True}),
])
def test_a_cip_setup_state_brings_its_drive_values(tmp_path: Path, state: str, implied: dict[str, bool]) -> None:
    expect = ", ".join(f"{k}: {'true' if v else 'false'}" for k, v in implied.items())
    body = f"""
        setup:
          axes:
            A: {{type: AXIS_CIP_DRIVE, state: {state}}}
        steps:
          - expect:
              A: {{state: {state}, {expect}}}
        """
    assert _run(tmp_path, body) == []


def test_given_variables_win_over_implied_ones(tmp_path: Path) -> None:
    body = """
        setup:
          axes:
            A: {type: AXIS_CIP_DRIVE, state: Faulted, variables: {Connected: false, ModuleFault: true}}
        steps:
          - expect:
              A: {state: Faulted, Connected: false, MajorFault: true}
        """
    assert _run(tmp_path, body) == []


def test_noncip_axis_faulted_setup_has_its_fault_latched(tmp_path: Path) -> None:
    # 001 Axis Faulted: a servo fault is present; MAFR clears it (domain-facts §4 MAFR)
    body = """
        setup:
          axes:
            A: {type: AXIS_SERVO, state: AxisFaulted}
          program:
            - {tag: mafr, instruction: MAFR, axis: A}
        steps:
          - expect:
              A: {ServoFault: true, AxisState: 3}
          - rungs: {mafr: true}
            expect:
              A: {ServoFault: false, AxisState: 0}
        """
    assert _run(tmp_path, body) == []


def test_an_axis_chooses_its_chart_when_several_model_its_type(tmp_path: Path) -> None:
    # INT-065: a virtual axis of the virtual axis chart is always under (virtual) servo
    # control; RA37 mas lists AXIS_VIRTUAL among the axis types of MAS
    body = """
        setup:
          axes:
            V: {type: AXIS_VIRTUAL, chart: AxisVirtual}
          program:
            - {tag: mas, instruction: MAS, axis: V}
        steps:
          - expect:
              V: {state: ServoControl, AxisState: 2, ServoActionStatus: true}
          - rungs: {mas: true}
            expect:
              mas: {EN: true, DN: true, ER: false}
        """
    assert _run(tmp_path, body) == []


def test_a_chart_that_does_not_model_the_axis_type_is_refused(tmp_path: Path) -> None:
    text = _errors(tmp_path, """
        setup:
          axes:
            V: {type: AXIS_VIRTUAL, chart: AxisCIP}
        steps:
          - expect:
              V: {AxisState: 2}
        """)
    assert "s.yaml:6:36: setup.axes.V.chart" in text
    assert "chart 'AxisCIP' does not model axis type 'AXIS_VIRTUAL'; expected one of: AxisNonCIP, AxisVirtual" in text


# ------------------------------------------------------------------------ preset tag bits

def test_preset_bits_meet_the_execution_table(tmp_path: Path) -> None:
    # domain-facts §4 generic execution table: rung true with EN set does nothing; rung
    # false clears EN only when DN or ER is set
    body = """
        setup:
          axes:
            A: {type: AXIS_SERVO}
          program:
            - {tag: held, instruction: MSO, axis: A, preset: {EN: true}}
            - {tag: done, instruction: MSF, axis: A, preset: {EN: true, DN: true, ERR: 0}}
        steps:
          - rungs: {held: true}
            expect:
              held: {EN: true, DN: false, FLAGS: -2147483648}
              done: {EN: false, DN: true}
              A: {state: AxisReady}
          - rungs: {held: false}
            expect:
              held: {EN: true}
        """
    assert _run(tmp_path, body) == []


def test_preset_refuses_unknown_members_and_wrong_types(tmp_path: Path) -> None:
    text = _errors(tmp_path, """
        setup:
          axes:
            A: {type: AXIS_SERVO}
          program:
            - {tag: t, instruction: MSO, axis: A, preset: {EN: 1, ERR: true, Done: true}}
        steps:
          - expect:
              t: {EN: false}
        """)
    assert "EN is a BOOL: expected true or false, got 1" in text
    assert "ERR is an integer member" in text
    assert "'Done' is not a MOTION_INSTRUCTION member" in text


# ------------------------------------------------------------------------ schema and loader agree

SCENARIO_SCHEMA = json.loads((bundled_spec_dir() / "schema" / "scenario.schema.json").read_text(encoding="utf-8"))

#: the keys each node of the scenario format has, as the loader reads them
LOADER_KEYS = {
    "": {"format", "name", "description", "sources", "covers", "setup", "steps"},
    # tags and prescan: set-up of a ladder program (statecharts/program/scenario.py)
    "/properties/setup": {"scan_ms", "coarse_update_ms", "axes", "devices", "program", "tags", "prescan"},
    "/properties/setup/properties/axes/additionalProperties": {"type", "chart", "state", "variables"},
    "/properties/setup/properties/devices/additionalProperties": {"type", "chart", "state", "variables", "parameters",
                                                                  "events"},
    "/properties/setup/properties/program/oneOf/0/items": {"tag", "instruction", "axis", "master", "operands", "preset"},
    # tags and always: steps of a scenario with a ladder program
    "/properties/steps/items": {"name", "prescan", "scans", "within", "rungs", "operands", "events", "expect", "set",
                                "tags", "always"},
    "/properties/steps/items/properties/events/items": {"axis", "event"},
}


def _node(pointer: str) -> dict[str, object]:
    node: object = SCENARIO_SCHEMA
    for part in filter(None, pointer.split("/")):
        node = node[int(part)] if isinstance(node, list) else node[part]
    assert isinstance(node, dict)
    return node


@pytest.mark.parametrize("pointer", sorted(LOADER_KEYS))
def test_scenario_schema_and_loader_agree(pointer: str) -> None:
    props = _node(pointer)["properties"]
    assert isinstance(props, dict)
    assert set(props) == LOADER_KEYS[pointer]


def test_expectation_forms_in_the_schema_are_those_the_loader_parses() -> None:
    per_object = _node("/properties/steps/items/properties/expect/additionalProperties/oneOf/0")
    forms = per_object["additionalProperties"]
    assert isinstance(forms, dict)
    objects = [f for f in forms["oneOf"] if f.get("type") == "object"]
    assert {frozenset(f["properties"]) for f in objects} == {expectations.APPROX_KEYS, expectations.NOT_KEYS}


# ------------------------------------------------------------------------ the same rules with a ladder program

def test_the_rules_hold_in_a_scenario_with_a_ladder_program(tmp_path: Path) -> None:
    program = Path(__file__).resolve().parents[1] / "examples" / "programs" / "fault_recovery.L5X"
    body = f"""
        setup:
          program: {program}
          axes:
            X_axis: {{type: AXIS_CIP_DRIVE, state: Running}}
            Y_axis: {{type: AXIS_CIP_DRIVE, state: Running}}
            Z_axis: {{type: AXIS_CIP_DRIVE, state: Running}}
          tags: {{STATE: 1, NEXTSTATE: 1}}
        steps:
          - tags: {{NEXTSTATE: 9}}
            expect: {{STATE: 9}}
          - name: MSF on every axis, then MAFR once each is stopped (001 Stopping, then Stopped)
            within: 10
            expect:
              X_AXIS_STAT[1]: {{DN: true, ERR: {{not: 20}}}}
              X_axis: {{passes_through: [Running, Stopping, Stopped]}}
              Y_axis: {{CIPAxisState: {{approx: 2, within: 0}}}}
        """
    assert _run(tmp_path, body) == []
    failures = _run(tmp_path, body.replace("within: 10", "within: 1"))
    assert failures and "within" not in failures[0]  # the step ended after one scan, with its values
