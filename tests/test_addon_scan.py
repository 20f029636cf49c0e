"""The add-on instruction as an instruction of the main scan (statecharts/addon.py).

Expected values are written from the documents (SYNC-RM §1.2, §2.3, §4; RM002H p96,
p120 for MAH and MAM) and the scan rules of docs/semantics.md, not read from the spec.
"""

from __future__ import annotations

from pathlib import Path

from statecharts.loader import load_spec
from statecharts.scan import ScanInputs
from statecharts.scenario import build_system, load_scenario, run_scenario

PROJECT = Path(__file__).resolve().parents[1]
SPEC = load_spec()
HOMING = PROJECT / "scenarios" / "aoi" / "homing_then_move.yaml"


def test_homing_then_move_runs_on_the_main_scan() -> None:
    result = run_scenario(load_scenario(HOMING, SPEC), SPEC)
    assert result.passed, "; ".join(map(str, result.mismatches))


def test_the_calls_are_the_main_instruction_charts_on_the_main_axes() -> None:
    system = build_system(load_scenario(HOMING, SPEC), SPEC)
    system.scan(ScanInputs(rungs={"Sync": True}))
    # MAH (RM002H p96) was executed on the physical axis through a MOTION_INSTRUCTION tag
    mah = system.tags["Sync.MAH"]
    assert mah.axis == "Axis_Phy" and mah.instruction.mnemonic == "MAH"
    assert mah.values["DN"] is True and mah.values["IP"] is True
    assert system.axes["Axis_Phy"].env["HomingStatus"] is True
    # the method registered as the third of handler 1: 1003 (SYNC-RM §2.3 Sts_MtdID, §4)
    assert system.observe()["Sync"]["Sts_MtdID"] == 1003


def test_the_instance_is_part_of_the_system_state() -> None:
    system = build_system(load_scenario(HOMING, SPEC), SPEC)
    system.scan(ScanInputs(rungs={"Sync": True}))
    snap = system.snapshot()
    before = {k: dict(v) for k, v in system.observe().items()}
    for _ in range(6):
        system.scan(ScanInputs())
    assert system.observe()["Sync"]["state"] == "moving"
    system.restore(snap)
    assert {k: dict(v) for k, v in system.observe().items()} == before
    assert system.snapshot() == snap


def test_a_step_cannot_rebind_an_axis_parameter(tmp_path: Path) -> None:
    import pytest

    from statecharts.diagnostics import ScenarioError
    text = HOMING.read_text(encoding="utf-8")
    marker = '  - name: "rung true; MAH starts"\n'
    assert marker in text
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace(marker, marker + "    operands: {Sync: {Ref_AxisPhy: Axis_PTH}}\n"), encoding="utf-8")
    with pytest.raises(ScenarioError) as exc:
        load_scenario(bad, SPEC)
    assert f"{bad}:" in str(exc.value) and "Ref_AxisPhy names the axis" in str(exc.value)
