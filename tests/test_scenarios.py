"""Run every scenario under ``scenarios/`` and check what the scenarios cover.

The scenarios are the conformance stories of the non-CIP state instructions: each one
has its expected bits, error codes and axis states written by hand from the source
documents (``sources:`` names them, with the INT-ids where an expectation rests on an
interpretation).  Nothing here reads the spec to decide what is expected; the spec is
only what runs.

Which (instruction, state) pairs and behaviours must be covered is the hand-written
list below, so a scenario that is deleted or renamed without replacement fails here.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

try:
    import statecharts  # noqa: F401  # only whether the project is installed
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from conftest import ScenarioRuns

from statecharts.diagnostics import ScenarioError
from statecharts.scenario import Scenario

SCENARIO_DIR = Path(__file__).resolve().parents[1] / "scenarios"
SCENARIO_FILES = sorted(
    p for p in SCENARIO_DIR.rglob("*") if p.is_file() and p.suffix in (".yaml", ".yml", ".json")
)

#: Scenarios whose documented expectation the spec does not (yet) meet.  Strict: when
#: the spec is fixed the test fails until the entry is removed.
XFAIL: dict[str, str] = {}

INSTRUCTIONS = ("MSO", "MSF", "MASD", "MASR", "MDO", "MDF", "MAFR")
STATES = ("AxisReady", "DirectDriveControl", "ServoControl", "AxisFaulted", "Shutdown")

#: Behaviours besides the instruction x state matrix that some scenario must cover.
REQUIRED_COVERS = (
    # axis types, configuration
    "MSO.type.AXIS_VIRTUAL.err8",
    "MSO.type.AXIS_SERVO_DRIVE.accept",
    "MSO.type.AXIS_GENERIC.accept",
    "MSF.type.AXIS_VIRTUAL.err8",
    "MDO.type.AXIS_SERVO_DRIVE.err8",
    "MDO.type.AXIS_GENERIC.err8",
    "MDO.type.AXIS_VIRTUAL.err8",
    "MDF.type.AXIS_SERVO_DRIVE.err8",
    "MSO.not_configured.err11",
    "MSF.not_configured.err11",
    "MASD.not_configured.err11",
    "MASR.not_configured.err11",
    "MAFR.not_configured.err11",
    "MDO.not_configured.err11",
    "MDF.not_configured.err11",
    "MSO.feedback_only.err8",
    "MDO.feedback_only.err8",
    # precedence
    "MSO.precedence.type_over_shutdown",
    "MDO.precedence.type_over_shutdown",
    "MSO.precedence.not_configured_over_shutdown",
    "MDO.precedence.drive_output_over_shutdown",
    # MDO operands
    "MDO.range.volts_err13_2",
    "MDO.range.percent_err13_2",
    "MDO.units.err13_3",
    "MDO.units.percent_of_output_limit",
    "MDO.drive_output_range.beyond_output_limit",  # INT-011: the Output Limit bounds the Drive Output
    "MDO.drive_output_range.at_output_limit",
    # MDO timing and aborts
    "MDO.timing.enable_delay",
    "MDO.timing.output_offset_during_delay",
    "MDO.timing.enable_delay_slow_coarse_update",
    "MDO.abort.by_MSF",
    "MDO.abort.by_MDF",
    "MDO.abort.by_MASD",
    "MDO.abort.by_fault_disable_drive",
    "MDO.abort.by_fault_shutdown",
    "MDO.loss_of_feedback_procedure",
    # execution table
    "EXEC.prescan.clears_en_dn_er",
    "EXEC.rung_false.clears_en",
    "EXEC.rung_false.en_kept_until_dn",
    "EXEC.rung_held.no_reexecute_after_dn",
    "EXEC.rung_held.no_reexecute_after_er",
    "EXEC.edge.reexecute_clears_er",
    "EXEC.edge.reexecute_clears_dn",
    "EXEC.multiscan.dn_at_coarse_update",
    "EXEC.error_timing.message_error_at_coarse_update",
    "MI.FLAGS.bits",
    # faults
    "FAULT.action.Shutdown",
    "FAULT.action.DisableDrive",
    "FAULT.action.StatusOnly",
    "FAULT.action.StopMotion",
    "FAULT.latched",
    "MAFR.cause_removed",
    "MAFR.cause_present.relatch",
    "MASR.clears_faults.after_shutdown_fault_action",
    # motion
    "MSO.moving.err22",
    "MSF.moving.coast",
)


@pytest.fixture(scope="module")
def loaded(scenario_runs: ScenarioRuns) -> dict[str, Scenario | ScenarioError]:
    """Every scenario file, loaded once per session (conftest); a file that does not load keeps its error."""
    return {p.stem: scenario_runs.loaded[p.resolve()] for p in SCENARIO_FILES}


@pytest.fixture(scope="module")
def scenarios(loaded: dict[str, Scenario | ScenarioError]) -> dict[str, Scenario]:
    errors = {k: v for k, v in loaded.items() if isinstance(v, ScenarioError)}
    assert not errors, "scenarios that do not load:\n" + "\n".join(f"{k}: {v}" for k, v in errors.items())
    return {k: v for k, v in loaded.items() if isinstance(v, Scenario)}


def _params() -> list[object]:
    out = []
    for p in SCENARIO_FILES:
        marks = [pytest.mark.xfail(strict=True, reason=XFAIL[p.stem])] if p.stem in XFAIL else []
        out.append(pytest.param(p, id=p.stem, marks=marks))
    return out


def test_scenario_files_found() -> None:
    assert len(SCENARIO_FILES) >= 35, SCENARIO_FILES
    stems = [p.stem for p in SCENARIO_FILES]
    assert len(stems) == len(set(stems)), "scenario file stems must be unique (they are the test ids)"
    assert set(XFAIL) <= set(stems), f"XFAIL names missing scenarios: {set(XFAIL) - set(stems)}"


@pytest.mark.parametrize("path", _params())
def test_scenario(path: Path, loaded: dict[str, Scenario | ScenarioError], scenario_runs: ScenarioRuns) -> None:
    scenario = loaded[path.stem]
    if isinstance(scenario, ScenarioError):
        pytest.fail(f"{path.name} does not load:\n{scenario}")
    result = scenario_runs.result(path)  # run once per session (conftest)
    assert result.passed, f"{path.name}:\n" + "\n".join(str(m) for m in result.mismatches)


def test_every_scenario_names_sources_and_covers(scenarios: dict[str, Scenario]) -> None:
    missing = [
        name for name, s in scenarios.items()
        if not s.sources or not s.covers or not all(x.strip() for x in (*s.sources, *s.covers))
    ]
    assert not missing, f"scenarios without sources or covers: {missing}"


def test_every_instruction_in_every_state_is_covered(scenarios: dict[str, Scenario]) -> None:
    covers = {c for s in scenarios.values() for c in s.covers}
    missing = [
        f"{ins}.{state}" for ins in INSTRUCTIONS for state in STATES
        if not any(c.startswith(f"{ins}.{state}.") for c in covers)
    ]
    assert not missing, f"instruction x state pairs no scenario covers: {missing}"


def test_required_behaviours_are_covered(scenarios: dict[str, Scenario]) -> None:
    covers = {c for s in scenarios.values() for c in s.covers}
    missing = [c for c in REQUIRED_COVERS if c not in covers]
    assert not missing, f"behaviours no scenario covers: {missing}"


def test_matrix_is_not_only_covered_by_expected_failures(scenarios: dict[str, Scenario]) -> None:
    passing = {c for name, s in scenarios.items() if name not in XFAIL for c in s.covers}
    missing = [
        f"{ins}.{state}" for ins in INSTRUCTIONS for state in STATES
        if not any(c.startswith(f"{ins}.{state}.") for c in passing)
    ]
    assert not missing, f"pairs covered only by expected failures: {missing}"
