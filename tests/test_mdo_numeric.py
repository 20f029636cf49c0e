"""MDO numerics, checked against hand-written functions of 002 (MDO):

* the Drive Output is in volts, or in percent of the Output Limit;
* the Output Limit bounds the Drive Output when MDO executes: beyond it (in volts) or
  beyond 100 % MDO errs (002 .ER for a Drive Output too large, INT-011); the output
  is never beyond +/- Output Limit;
* a Negative Servo Output Polarity inverts it (002: MDO is affected by the Servo
  Output Polarity bit, INT-051);
* the 16-bit DAC gives it in steps of 20 V / 65536, about 305 uV (002), truncated
  toward zero so that it never exceeds the limit (INT-052);
* during the ~500 ms drive-enable delay the output stays at the Output Offset, and DN
  is set when the commanded value is applied (after the delay, at a coarse update);
  the offset is not added to the applied value (002: once the delay is over, the
  Drive Output operand alone sets the output, INT-051);
* lowering the Output Limit below the applied output clamps it (002), at the next
  coarse update (INT-053);
* a Drive Output beyond the Output Limit (or 100 %) is an error (13, EXERR 2); a negative
  Output Limit is refused with 12/3 (INT-054); MDF returns the output to the Output
  Offset (domain-facts §4 MDF).

Every expected value below is computed by the functions of this file, written from the
documents; nothing is read from spec/.
"""

from __future__ import annotations

import math
import sys
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

try:
    import statecharts  # noqa: F401  # only whether the project is installed
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from statecharts.diagnostics import ScenarioError
from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.scan import ScanInputs, System
from statecharts.scenario import load_scenario, run_scenario

SPEC = load_spec()
DELAY_MS = 500  # 002 Description: typically 500 ms between drive enable and the output
DAC_STEP = Fraction(20, 65536)  # 002 Description: 16-bit DAC, 305 uV (a 20 V span)


def dac(volts: float) -> float:
    """The voltage a 16-bit DAC gives for ``volts``: whole steps, truncated toward zero."""
    steps = int(Fraction(volts) / DAC_STEP)  # int() truncates toward zero, exactly
    return float(steps * DAC_STEP)


def documented_output(drive_output: float, units: int, output_limit: float, polarity: str = "Positive") -> float:
    """The analog output 002 describes: volts, or percent of the limit, clamped to the
    limit, inverted by a Negative Servo Output Polarity, in DAC steps."""
    volts = drive_output if units == 0 else drive_output * output_limit / 100.0
    clamped = max(-output_limit, min(output_limit, volts))
    return dac(-clamped if polarity == "Negative" else clamped)


def reclamped(output: float, new_limit: float) -> float:
    """002: an Output Limit reduced below the present output clamps the output to it."""
    if abs(output) <= new_limit:
        return output
    return math.copysign(dac(new_limit), output)


def _system(coarse_ms: int, limit: float, offset: float, drive_output: float, units: int,
            polarity: str = "Positive") -> System:
    params = {"scan_ms": coarse_ms, "coarse_update_ms": coarse_ms}
    axis = AxisInstance(SPEC.chart("AxisNonCIP"), "A", state="AxisReady",
                        variables={"OutputLimit": limit, "OutputOffset": offset, "ServoOutputPolarity": polarity},
                        parameters=params)
    program = [("mdo", "MDO", "A"), ("mdf", "MDF", "A")]
    system = System(SPEC, [axis], program, scan_ms=coarse_ms, coarse_update_ms=coarse_ms)
    system.tags["mdo"].operands.update({"DriveOutput": drive_output, "DriveUnits": units})
    return system


def _applied(system: System) -> dict[str, object]:
    """Raise the MDO rung and scan until its DN (at most 600 scans)."""
    for _ in range(600):
        obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
        if obs["mdo"]["DN"] or obs["mdo"]["ER"]:
            return {"mdo": dict(obs["mdo"]), "A": dict(obs["A"])}
    raise AssertionError("MDO never finished")


@given(
    units=st.sampled_from([0, 1]),
    fraction=st.floats(-1.0, 1.0, allow_nan=False),
    limit=st.floats(0.1, 10.0, allow_nan=False),
    offset=st.floats(-1.0, 1.0, allow_nan=False),
    coarse_ms=st.sampled_from([10, 20, 50, 100, 125, 250, 500]),
)
def test_mdo_output_units_clamp_and_delay(units: int, fraction: float, limit: float, offset: float, coarse_ms: int) -> None:
    drive_output = fraction * (limit if units == 0 else 100.0)
    system = _system(coarse_ms, limit, offset, drive_output, units)
    n = math.ceil(DELAY_MS / coarse_ms)
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["A"]["AxisState"] == 1 and obs["A"]["DriveEnableStatus"] is True
    for _ in range(n - 1):
        assert obs["mdo"]["DN"] is False
        assert obs["A"]["ServoOutput"] == pytest.approx(offset)
        obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["mdo"]["DN"] is (n == 0)
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["mdo"]["DN"] is True and obs["mdo"]["ER"] is False
    assert obs["A"]["ServoOutput"] == pytest.approx(documented_output(drive_output, units, limit), abs=1e-9)
    assert abs(obs["A"]["ServoOutput"]) <= limit + 1e-12


@given(
    units=st.sampled_from([0, 1]),
    drive_output=st.floats(-100.0, 100.0, allow_nan=False),
    limit=st.floats(0.0, 10.0, allow_nan=False),
    offset=st.floats(-2.0, 2.0, allow_nan=False),
    polarity=st.sampled_from(["Positive", "Negative"]),
)
def test_mdo_output_with_polarity_offset_and_dac(units: int, drive_output: float, limit: float, offset: float,
                                                 polarity: str) -> None:
    if units == 0:
        drive_output = drive_output / 100.0 * limit  # within the Output Limit (INT-011)
    system = _system(100, limit, offset, drive_output, units, polarity)
    first = system.scan(ScanInputs(rungs={"mdo": True})).observations
    # during the enable delay: the Output Offset as configured, not inverted (INT-051)
    assert first["A"]["ServoOutput"] == offset
    out = _applied(system)
    assert out["mdo"]["DN"] is True and out["mdo"]["ERR"] == 0
    expected = documented_output(drive_output, units, limit, polarity)
    assert out["A"]["ServoOutput"] == pytest.approx(expected, abs=1e-12)
    # a whole number of DAC steps, never beyond the limit
    steps = Fraction(out["A"]["ServoOutput"]) / DAC_STEP
    assert steps.denominator == 1 and abs(out["A"]["ServoOutput"]) <= limit
    # the other polarity gives exactly the opposite output
    other = _applied(_system(100, limit, offset, drive_output, units,
                             "Positive" if polarity == "Negative" else "Negative"))
    assert other["A"]["ServoOutput"] == -out["A"]["ServoOutput"]


@given(
    drive_output=st.floats(-10.0, 10.0, allow_nan=False),
    new_limit=st.floats(0.0, 10.0, allow_nan=False),
    polarity=st.sampled_from(["Positive", "Negative"]),
)
def test_lowered_output_limit_reclamps_at_the_next_coarse_update(drive_output: float, new_limit: float,
                                                                 polarity: str) -> None:
    system = _system(100, 10.0, 0.0, drive_output, 0, polarity)
    applied = _applied(system)["A"]["ServoOutput"]
    assert applied == pytest.approx(documented_output(drive_output, 0, 10.0, polarity), abs=1e-12)
    system.axes["A"].env["OutputLimit"] = new_limit
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["A"]["ServoOutput"] == pytest.approx(reclamped(applied, new_limit), abs=1e-12)
    assert obs["A"]["AxisState"] == 1 and obs["mdo"]["ER"] is False
    # raising the limit again does not bring the earlier output back (INT-053)
    system.axes["A"].env["OutputLimit"] = 10.0
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["A"]["ServoOutput"] == pytest.approx(reclamped(applied, new_limit), abs=1e-12)


@given(limit=st.one_of(st.floats(-10.0, -1e-9, allow_nan=False), st.just(float("nan"))),
       units=st.sampled_from([0, 1]))
def test_negative_output_limit_is_refused_with_12_3(limit: float, units: int) -> None:
    system = _system(10, limit, 0.0, 5.0, units)
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    # INT-054: Servo Message Failure (12), EXERR 3 Invalid value; the axis is untouched
    assert (obs["mdo"]["ER"], obs["mdo"]["ERR"], obs["mdo"]["EXERR"], obs["mdo"]["DN"]) == (True, 12, 3, False)
    assert obs["A"]["AxisState"] == 0 and obs["A"]["DriveEnableStatus"] is False


def test_zero_output_limit_is_valid_and_holds_zero_volts() -> None:
    system = _system(100, 0.0, 0.0, 50.0, 1)
    out = _applied(system)
    assert out["mdo"]["DN"] is True and out["A"]["ServoOutput"] == 0.0


@given(drive_output=st.floats(-10.0, 10.0, allow_nan=False), offset=st.floats(-2.0, 2.0, allow_nan=False))
def test_mdf_returns_the_output_to_the_output_offset(drive_output: float, offset: float) -> None:
    system = _system(100, 10.0, offset, drive_output, 0)
    _applied(system)
    obs = system.scan(ScanInputs(rungs={"mdo": True, "mdf": True})).observations
    # domain-facts §4 MDF: drive disabled, servo output at the Output Offset
    assert obs["mdf"]["DN"] is True and obs["A"]["AxisState"] == 0
    assert obs["A"]["DriveEnableStatus"] is False and obs["A"]["ServoOutput"] == offset


@given(units=st.sampled_from([0, 1]), excess=st.floats(1.0001, 100.0, allow_nan=False), sign=st.sampled_from([-1, 1]),
       limit=st.floats(0.5, 10.0, allow_nan=False))
def test_mdo_drive_output_too_large_errs(units: int, excess: float, sign: int, limit: float) -> None:
    drive_output = sign * excess * (limit if units == 0 else 100.0)
    system = _system(10, limit, 0.0, drive_output, units)
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert (obs["mdo"]["ER"], obs["mdo"]["ERR"], obs["mdo"]["EXERR"]) == (True, 13, 2)
    assert obs["A"]["AxisState"] == 0


@given(units=st.sampled_from([0, 1]), drive_output=st.floats(-200.0, 200.0, allow_nan=False),
       limit=st.floats(0.0, 10.0, allow_nan=False))
def test_mdo_13_2_exactly_when_the_drive_output_exceeds_the_limit(units: int, drive_output: float, limit: float) -> None:
    # 002 .ER: a Drive Output that is too large; the bound is the Output Limit in volts and
    # 100 % in percent (002 Description, INT-011)
    too_large = abs(drive_output) > (limit if units == 0 else 100.0)
    obs = _system(10, limit, 0.0, drive_output, units).scan(ScanInputs(rungs={"mdo": True})).observations
    assert ((obs["mdo"]["ERR"], obs["mdo"]["EXERR"]) == (13, 2)) is too_large
    assert obs["mdo"]["ER"] is too_large


@given(units=st.integers(2, 1000), drive_output=st.floats(-100.0, 100.0, allow_nan=False))
def test_drive_units_other_than_0_or_1_is_13_3(units: int, drive_output: float) -> None:
    # 002 Operands: 0 Volts, 1 Percent; INT-011: Drive Units is operand 3
    system = _system(10, 10.0, 0.0, drive_output, units)
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert (obs["mdo"]["ER"], obs["mdo"]["ERR"], obs["mdo"]["EXERR"]) == (True, 13, 3)
    assert obs["A"]["AxisState"] == 0


def test_servo_output_polarity_inverts_the_output() -> None:
    assert "ServoOutputPolarity" in {v.name for v in SPEC.chart("AxisNonCIP").variables}
    system = _system(500, 10.0, 0.25, 5.0, 0, "Negative")
    first = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert first["A"]["ServoOutput"] == 0.25
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["mdo"]["DN"] is True and obs["A"]["ServoOutput"] == -5.0


def test_output_is_quantised_to_the_dac_resolution() -> None:
    system = _system(500, 10.0, 0.0, 1.0001, 0)
    system.scan(ScanInputs(rungs={"mdo": True}))
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    step = 20.0 / 65536
    assert obs["A"]["ServoOutput"] == pytest.approx(round(1.0001 / step) * step, abs=1e-12)


def test_lowering_output_limit_later_clamps_the_output() -> None:
    system = _system(500, 10.0, 0.0, 8.0, 0)
    system.scan(ScanInputs(rungs={"mdo": True}))
    system.scan(ScanInputs(rungs={"mdo": True}))
    system.axes["A"].env["OutputLimit"] = 5.0
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["A"]["ServoOutput"] == pytest.approx(5.0)


def test_negative_output_limit_is_refused() -> None:
    system = _system(10, -1.0, 0.0, 5.0, 0)
    obs = system.scan(ScanInputs(rungs={"mdo": True})).observations
    assert obs["mdo"]["ER"] is True


def _scenario(tmp_path: Path, units: str) -> Path:
    p = tmp_path / "units.yaml"
    p.write_text(
        "format: motionchart-scenario/1\nname: bad units\n"
        "setup:\n  axes:\n    A: {type: AXIS_SERVO}\n"
        f"  program:\n    - {{tag: t, instruction: MDO, axis: A, operands: {{DriveOutput: 5.0, DriveUnits: {units}}}}}\n"
        "steps:\n  - rungs: {t: true}\n    expect:\n      t: {ER: true, ERR: 13, EXERR: 3}\n", encoding="utf-8")
    return p


def test_unknown_drive_units_text_is_a_clear_scenario_error(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError) as exc:
        load_scenario(_scenario(tmp_path, "Amps"), SPEC)
    text = str(exc.value)
    assert "DriveUnits" in text and "Volts" in text and "Percent" in text and "Traceback" not in text


def test_drive_units_two_in_a_scenario_is_the_documented_error(tmp_path: Path) -> None:
    result = run_scenario(load_scenario(_scenario(tmp_path, "2"), SPEC), SPEC)
    assert result.passed, result.mismatches
