"""The pytest plugin (``motionchart.pytest_plugin``, entry point ``pytest11``), run on a
user's project in a temporary directory outside the repository with ``pytester``.

The project has its own scenario files (one passing, one with a wrong expectation
planted on purpose), a ``pyproject.toml`` that names the scenario folder, and a
hypothesis property test that uses the public strategies and the ``motionchart_spec``
fixture.  The expected values in the scenarios are written by hand from the documents
(MSO on a ready servo axis: EN, DN set, ServoControl; RM002H, 001).
"""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

PYPROJECT = """\
[tool.pytest.ini_options]
motionchart_scenarios = ["scenarios"]
"""

GOOD = """\
format: motionchart-scenario/1
name: MSO enables a ready servo axis
setup:
  axes:
    Axis1: {type: AXIS_SERVO}
  program:
    - {tag: mso1, instruction: MSO, axis: Axis1}
steps:
  - name: power-up
    expect:
      mso1: {EN: false, DN: false, ER: false}
      Axis1: {state: AxisReady}
  - name: rung goes true
    rungs: {mso1: true}
    expect:
      mso1: {EN: true, DN: true, ER: false, ERR: 0}
      Axis1: {state: ServoControl}
"""

# line 10 expects the axis to stay in Axis Ready after MSO: wrong on purpose
WRONG = """\
format: motionchart-scenario/1
name: a wrong expectation
setup:
  axes:
    Axis1: {type: AXIS_SERVO}
  program:
    - {tag: mso1, instruction: MSO, axis: Axis1}
steps:
  - name: rung goes true
    rungs: {mso1: true}
    expect:
      mso1: {DN: true}
      Axis1: {state: AxisReady}
"""

PROPERTY_TEST = """\
from hypothesis import given, settings

import motionchart
from motionchart import strategies as mst

SPEC = motionchart.bundled_spec()
CHART = SPEC.chart("AxisNonCIP")


def test_the_fixture_gives_the_spec(motionchart_spec):
    assert "AxisNonCIP" in [c.id for c in motionchart_spec.charts]


@settings(max_examples=15, database=None, deadline=None)
@given(mst.scenarios(SPEC, CHART, ["MSO", "MSF", "MAFR"]))
def test_er_always_comes_with_an_error_code(scenario):
    # RM002H: when ER is set, ERR holds the error code (never 0)
    result = motionchart.run_scenario(scenario, SPEC)
    for row in result.rows:
        for tag in ("MSO_Ctrl", "MSF_Ctrl", "MAFR_Ctrl"):
            bits = row.record.observations[tag]
            assert not bits["ER"] or bits["ERR"] != 0
"""


@pytest.fixture
def project(pytester: pytest.Pytester) -> pytest.Pytester:
    assert not pytester.path.resolve().is_relative_to(ROOT), "the user project must lie outside the repository"
    pytester.makefile(".toml", pyproject=PYPROJECT)
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "mso_good.yaml").write_text(GOOD, encoding="utf-8")
    pytester.makepyfile(test_properties=PROPERTY_TEST)
    return pytester


def test_scenarios_and_a_property_test_pass(project: pytest.Pytester) -> None:
    result = project.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=3)
    result.stdout.fnmatch_lines(["*mso_good.yaml*"])


def test_a_wrong_expectation_fails_with_the_per_scan_table(project: pytest.Pytester) -> None:
    (project.path / "scenarios" / "wrong.yaml").write_text(WRONG, encoding="utf-8")
    result = project.runpytest("-p", "no:cacheprovider", "-rf")
    result.assert_outcomes(passed=3, failed=1)
    result.stdout.fnmatch_lines([
        "*scenario: a wrong expectation*",
        "* scan  step * changes / expected * actual*",
        "*    0  1 rung goes true*mso1.EN=1*",
        "*expect*mso1.DN=1 * 1",
        "*expect*Axis1.state=AxisReady * ServoControl  != (*wrong.yaml:9)",
        "FAIL (1 expectation(s) not met): a wrong expectation, 1 scans",
        "*wrong.yaml:9: step 1 (rung goes true), scan 0: Axis1.state expected 'AxisReady', got 'ServoControl'",
    ])
    assert "Traceback" not in result.stdout.str()


def test_a_scenario_that_does_not_load_is_a_located_failure(project: pytest.Pytester) -> None:
    (project.path / "scenarios" / "broken.yaml").write_text(GOOD.replace("instruction: MSO", "instruction: NOPE"),
                                                            encoding="utf-8")
    result = project.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=3, failed=1)
    result.stdout.fnmatch_lines(["*broken.yaml:7:32: setup.program[[]0[]].instruction: unknown instruction *NOPE*"])
    assert "Traceback" not in result.stdout.str()


def test_nothing_is_collected_unless_configured(pytester: pytest.Pytester) -> None:
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "mso_good.yaml").write_text(GOOD, encoding="utf-8")
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes()
    result = pytester.runpytest("-p", "no:cacheprovider", "--motionchart-scenarios", "scenarios/*.yaml")
    result.assert_outcomes(passed=1)
