"""The ``motionchart`` command line: every flag, exit codes, and bad scenarios.

Exit codes (checker/cli.py): 0 success, 1 a user file is wrong or an expectation
failed, 2 usage error.  Most tests call :func:`checker.cli.main` in-process with
``capsys``; a few run the installed console script (and ``python -m checker``) in a
subprocess to prove that no traceback reaches stderr.

Scenario errors are built from one small hand-written scenario (MSO on a ready servo
axis; the expected bits and AxisState 2 = Servo Control are typed in from
domain-facts §2/§3a, not read from the spec) by replacing one line; the line of each
diagnostic is found by a marker unique to the change.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from checker.cli import main
from statecharts.diagnostics import ScenarioError
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.scenario import load_scenario, run_scenario

SPEC = load_spec()
CHART = SPEC.chart_for_axis_type("AXIS_SERVO")
BOOL_VARIABLE = next(v.name for v in CHART.variables if v.type == "bool")
TEXT_OPERAND = next(o.name for o in SPEC.instruction("MDO").operands if o.text_values)
PROJECT = Path(__file__).resolve().parents[1]
DIAGNOSTIC = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (?P<rest>.*)$")

BASE = """\
format: motionchart-scenario/1
name: MSO enables a ready servo axis (CLI test)
sources: ["domain-facts §4 MSO (RM002H-p78)"]
setup:
  axes:
    Axis1: {type: AXIS_SERVO}
  program:
    - {tag: mso1, instruction: MSO, axis: Axis1}
    - {tag: mdo1, instruction: MDO, axis: Axis1}
steps:
  - name: rung goes true
    rungs: {mso1: true}
    expect:
      mso1: {EN: true, DN: true, ER: false, ERR: 0}
      Axis1: {AxisState: 2}
  - name: rung false clears EN
    rungs: {mso1: false}
    expect:
      mso1: {EN: false, DN: true}
"""


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def diagnostics(err: str) -> list[re.Match[str]]:
    found = [DIAGNOSTIC.match(line) for line in err.splitlines()]
    return [m for m in found if m is not None]


def write(tmp_path: Path, text: str, name: str = "scenario.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def line_of(path: Path, marker: str) -> int:
    lines = [i for i, t in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if marker in t]
    assert len(lines) == 1, lines
    return lines[0]


def variant(old: str, new: str) -> str:
    assert BASE.count(old) == 1, old
    return BASE.replace(old, new)


@pytest.fixture
def spec_copy(tmp_path: Path) -> Path:
    d = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), d, ignore=shutil.ignore_patterns("__pycache__", "*.py", "schema"))
    return d


def break_spec(spec_dir: Path) -> Path:
    """Give the first instruction file an unknown key; return that file."""
    path = sorted((spec_dir / "instructions").glob("*.yaml"))[0]
    text = path.read_text(encoding="utf-8")
    assert "\ninstruction:\n" in text
    path.write_text(text.replace("\ninstruction:\n", "\ninstruction:\n  zz_bogus§: 1\n", 1), encoding="utf-8")
    return path


# --------------------------------------------------------------------------- top level


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = run(capsys, "--version")
    assert rc == 0
    assert re.fullmatch(r"motionchart \d+\.\d+\.\d+\S*\n", out)


def test_help(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = run(capsys, "--help")
    assert rc == 0 and "validate" in out and "simulate" in out


def test_no_command_prints_help_and_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = run(capsys)
    assert rc == 2
    assert out == ""
    assert "usage: motionchart" in err and "validate" in err and "simulate" in err


def test_unknown_command(capsys: pytest.CaptureFixture[str]) -> None:
    rc, _, err = run(capsys, "frobnicate")
    assert rc == 2
    assert "invalid choice: 'frobnicate'" in err


def test_unknown_flag(capsys: pytest.CaptureFixture[str]) -> None:
    rc, _, err = run(capsys, "validate", "--frob")
    assert rc == 2 and "unrecognized arguments: --frob" in err


def test_simulate_needs_a_scenario(capsys: pytest.CaptureFixture[str]) -> None:
    rc, _, err = run(capsys, "simulate")
    assert rc == 2 and "SCENARIO" in err


# --------------------------------------------------------------------------- validate


def test_validate_bundled(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = run(capsys, "validate")
    assert (rc, err) == (0, "")
    assert out.startswith("spec OK: ")
    assert f"{len(SPEC.files)} files" in out and f"{len(SPEC.instructions)} instructions" in out


def test_validate_json(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = run(capsys, "validate", "--json")
    assert rc == 0
    doc = json.loads(out)
    assert doc["valid"] is True
    assert doc["instructions"] == [i.id for i in SPEC.instructions]
    assert doc["charts"] == [c.id for c in SPEC.charts]
    assert doc["files"] == len(SPEC.files)


def test_validate_directory(capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    rc, out, _ = run(capsys, "validate", str(spec_copy))
    assert rc == 0 and out.startswith("spec OK: ")


def test_validate_broken_spec(capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    broken = break_spec(spec_copy)
    rc, out, err = run(capsys, "validate", str(spec_copy))
    assert rc == 1 and out == ""
    found = diagnostics(err)
    assert len(found) == 1
    assert found[0]["file"] == str(broken) and int(found[0]["line"]) == line_of(broken, "zz_bogus")
    assert "instruction.zz_bogus§: unknown key" in found[0]["rest"]
    assert err.rstrip().endswith("1 error(s)")


def test_validate_broken_spec_json(capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    broken = break_spec(spec_copy)
    rc, out, _ = run(capsys, "validate", "--json", str(spec_copy))
    assert rc == 1
    doc = json.loads(out)
    assert doc["valid"] is False
    [d] = doc["diagnostics"]
    assert d["file"] == str(broken) and d["line"] == line_of(broken, "zz_bogus")
    assert d["path"] == "instruction.zz_bogus§" and "expected one of" in d["message"]
    assert doc["errors"] == [f"{broken}:{d['line']}:{d['column']}: {d['path']}: {d['message']}"]


@pytest.mark.parametrize("path", ["no/such/spec", ""])
def test_validate_missing_path(capsys: pytest.CaptureFixture[str], path: str) -> None:
    rc, out, err = run(capsys, "validate", path)
    assert rc == 2 and out == ""
    assert "no such file or directory" in err


def test_validate_directory_without_spec_files(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    rc, _, err = run(capsys, "validate", str(tmp_path))
    assert rc == 1 and "no spec files" in err


# --------------------------------------------------------------------------- simulate


def test_simulate_pass(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = write(tmp_path, BASE)
    rc, out, err = run(capsys, "simulate", str(path))
    assert (rc, err) == (0, "")
    assert "scan  step" in out  # the per-scan table
    assert "mso1.EN=1" in out
    assert "PASS MSO enables a ready servo axis (CLI test) (2 scans)" in out


def test_simulate_quiet(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = write(tmp_path, BASE)
    for flag in ("--quiet", "-q"):
        rc, out, _ = run(capsys, "simulate", flag, str(path))
        assert rc == 0
        assert out == "PASS MSO enables a ready servo axis (CLI test) (2 scans)\n"


def test_simulate_summary_prints_failures_and_the_count(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    good = write(tmp_path, BASE, "a_good.yaml")
    rc, out, _ = run(capsys, "simulate", "--summary", str(good))
    assert (rc, out) == (0, "scenarios: 1 passed, 0 failed, 0 invalid\n")
    bad = write(tmp_path, variant("mso1: {EN: false, DN: true}", "mso1: {EN: false, DN: false}"), "b_bad.yaml")
    rc, out, _ = run(capsys, "simulate", "--summary", str(good), str(bad))
    assert rc == 1
    lines = out.splitlines()
    assert lines[0].startswith("FAIL ") and "mso1.DN expected false, got true" in lines[1]
    assert lines[-1] == "scenarios: 1 passed, 1 failed, 0 invalid"


def test_simulate_json(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    good = write(tmp_path, BASE, "a_good.yaml")
    bad = write(tmp_path, variant("mso1: {EN: false, DN: true}", "mso1: {EN: false, DN: false}"), "b_bad.yaml")
    rc, out, _ = run(capsys, "simulate", "--json", str(good), str(bad))
    assert rc == 1
    doc = json.loads(out)
    assert {"results", "passed", "failed", "input_errors"} <= set(doc)
    assert (doc["passed"], doc["failed"], doc["input_errors"]) == (1, 1, [])
    assert [r["passed"] for r in doc["results"]] == [True, False]
    [failure] = doc["results"][1]["failures"]
    assert failure["step"] == 2 and failure["object"] == "mso1" and failure["field"] == "DN"
    assert failure["expected"] is False and failure["actual"] is True
    assert failure["line"] == line_of(bad, "rung false clears EN")
    assert doc["results"][0]["scans"][0]["changes"]["mso1.EN"] is True


def test_simulate_failing_expectation_names_step_and_field(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = write(tmp_path, variant("mso1: {EN: true, DN: true, ER: false, ERR: 0}", "mso1: {EN: true, DN: false}"))
    rc, out, _ = run(capsys, "simulate", "--quiet", str(path))
    assert rc == 1
    assert out.startswith("FAIL ")
    assert f"{path}:{line_of(path, 'rung goes true')}: step 1 (rung goes true), scan 0: mso1.DN expected false, got true" in out


def test_simulate_directory_and_summary(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    write(tmp_path, BASE, "one.yaml")
    write(tmp_path, BASE.replace("name: MSO", "name: again MSO"), "two.json.yaml")
    write(tmp_path, "format: [\n", "three.yaml")
    rc, out, err = run(capsys, "simulate", "-q", str(tmp_path))
    assert rc == 1
    assert out.rstrip().endswith("scenarios: 2 passed, 0 failed, 1 invalid")
    assert f"{tmp_path / 'three.yaml'}:2:1: YAML syntax error" in err


def test_simulate_with_spec_directory(capsys: pytest.CaptureFixture[str], tmp_path: Path, spec_copy: Path) -> None:
    path = write(tmp_path, BASE)
    rc, out, _ = run(capsys, "simulate", "-q", "--spec", str(spec_copy), str(path))
    assert rc == 0 and out.startswith("PASS")
    broken = break_spec(spec_copy)
    rc, out, err = run(capsys, "simulate", "-q", "--spec", str(spec_copy), str(path))
    assert rc == 1 and out == ""
    assert [m["file"] for m in diagnostics(err)] == [str(broken)]
    rc, out, _ = run(capsys, "simulate", "--json", "--spec", str(spec_copy), str(path))
    assert rc == 1 and json.loads(out)["input_errors"]


def test_simulate_spec_directory_changes_the_outcome(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                      spec_copy: Path) -> None:
    """--spec really replaces the bundled spec: the copy's MSO refuses every axis."""
    mso = spec_copy / "instructions" / "MSO.yaml"
    text = mso.read_text(encoding="utf-8")
    mso.write_text(re.sub(r'fails_when: "[^"]*", err: 8,', 'fails_when: "True", err: 8,', text, count=1), encoding="utf-8")
    path = write(tmp_path, BASE)
    assert run(capsys, "simulate", "-q", str(path))[0] == 0
    rc, out, _ = run(capsys, "simulate", "-q", "--spec", str(spec_copy), str(path))
    assert rc == 1 and "mso1.ER expected false, got true" in out


@pytest.mark.parametrize("args", [["missing.yaml"], ["--spec", "no/such/dir", "SCENARIO"]])
def test_simulate_missing_file(capsys: pytest.CaptureFixture[str], tmp_path: Path, args: list[str]) -> None:
    args = [str(write(tmp_path, BASE)) if a == "SCENARIO" else str(tmp_path / a) if a == "missing.yaml" else a
            for a in args]
    rc, out, err = run(capsys, "simulate", *args)
    assert rc == 2 and out == ""
    assert "no such file or directory" in err


def test_simulate_directory_without_scenarios(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    rc, _, err = run(capsys, "simulate", str(tmp_path))
    assert rc == 2 and "no scenario files" in err


# --------------------------------------------------------------------------- bad scenarios

BAD_SCENARIOS = {
    "yaml-syntax": ("    rungs: {mso1: true}", "    rungs: {mso1: true\n    zz_after: 1", "zz_after", "YAML syntax error"),
    "schema-unknown-key": ("    rungs: {mso1: true}", "    rungs: {mso1: true}\n    zz_key: 1", "zz_key",
                           "unknown key 'zz_key'; expected one of:"),
    "schema-wrong-type": ("    rungs: {mso1: true}", "    rungs: {mso1: zz_yes}", "zz_yes", "expected true or false"),
    "unknown-axis-type": ("{type: AXIS_SERVO}", "{type: ZZ_AXIS}", "ZZ_AXIS", "unknown axis type 'ZZ_AXIS'"),
    "unknown-state": ("{type: AXIS_SERVO}", "{type: AXIS_SERVO, state: ZzState}", "ZzState", "has no state 'ZzState'"),
    "unknown-variable": ("{type: AXIS_SERVO}", "{type: AXIS_SERVO, variables: {ZzVar: 1}}", "ZzVar",
                         "has no variable 'ZzVar'"),
    "variable-wrong-type": ("{type: AXIS_SERVO}", f"{{type: AXIS_SERVO, variables: {{{BOOL_VARIABLE}: zz_text}}}}",
                            "zz_text", "expected true or false"),
    "unknown-tag": ("    rungs: {mso1: true}", "    rungs: {zz_tag: true}", "zz_tag", "unknown tag 'zz_tag'"),
    "unknown-instruction": ("instruction: MDO", "instruction: ZZI", "ZZI", "unknown instruction 'ZZI'"),
    "unknown-operand": ("    rungs: {mso1: true}", "    rungs: {mso1: true}\n    operands: {mdo1: {ZzOperand: 1}}",
                        "ZzOperand", "has no operand 'ZzOperand'"),
    "operand-text": ("    rungs: {mso1: true}",
                     f"    rungs: {{mso1: true}}\n    operands: {{mdo1: {{{TEXT_OPERAND}: zz_units}}}}",
                     "zz_units", "expected a number or one of:"),
    "unknown-event": ("    rungs: {mso1: true}", "    rungs: {mso1: true}\n    events: [{axis: Axis1, event: zz_event}]",
                      "zz_event", "'zz_event' is not an environment event"),
    "unknown-expected-field": ("      Axis1: {AxisState: 2}", "      Axis1: {AxisState: 2, ZzField: 1}", "ZzField",
                               "Axis1 has no observable 'ZzField'; expected one of:"),
    "unknown-expected-target": ("      Axis1: {AxisState: 2}", "      zz_target: {AxisState: 2}", "zz_target",
                                "unknown tag or axis 'zz_target'"),
}


@pytest.mark.parametrize("case", sorted(BAD_SCENARIOS))
def test_bad_scenario(capsys: pytest.CaptureFixture[str], tmp_path: Path, case: str) -> None:
    old, new, marker, message = BAD_SCENARIOS[case]
    path = write(tmp_path, variant(old, new))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, SPEC)
    [d] = info.value.diagnostics
    assert (d.file, d.line) == (str(path), line_of(path, marker)), str(d)
    assert message in d.message, str(d)
    rc, _out, err = run(capsys, "simulate", str(path))
    assert rc == 1
    assert err.splitlines()[0] == str(d)
    assert "Traceback" not in err


def test_scenario_missing_setup(tmp_path: Path) -> None:
    start, end = BASE.index("setup:"), BASE.index("steps:")
    path = write(tmp_path, BASE[:start] + BASE[end:])
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, SPEC)
    [d] = info.value.diagnostics
    assert d.line == 1 and "missing required key 'setup'" in d.message


def test_scenario_errors_come_in_one_pass(tmp_path: Path) -> None:
    text = variant("{type: AXIS_SERVO}", "{type: AXIS_SERVO, state: ZzState}")
    text = text.replace("    rungs: {mso1: true}", "    rungs: {zz_tag: true}")
    text = text.replace("      Axis1: {AxisState: 2}", "      Axis1: {AxisState: 2, ZzField: 1}")
    path = write(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, SPEC)
    lines = [d.line for d in info.value.diagnostics]
    assert lines == [line_of(path, "ZzState"), line_of(path, "zz_tag"), line_of(path, "ZzField")]


def test_json_scenario(tmp_path: Path) -> None:
    """JSON scenarios run too, and their semantic errors still carry line numbers."""
    from ruamel.yaml import YAML

    doc = YAML(typ="safe").load(BASE)
    path = write(tmp_path, json.dumps(doc, indent=2, ensure_ascii=False), "scenario.json")
    assert run_scenario(load_scenario(path, SPEC), SPEC).passed
    doc["setup"]["axes"]["Axis1"]["type"] = "ZZ_AXIS"
    path.write_text(json.dumps(doc, indent=2), encoding="utf-8")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, SPEC)
    [d] = info.value.diagnostics
    assert d.line == line_of(path, "ZZ_AXIS") and "unknown axis type" in d.message


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [('{"format": "motionchart-scenario/1",\n "name": }\n', 2, "JSON syntax error"),
     ("[" * 5000 + "]" * 5000, 1, "nesting"),
     ("", 1, "JSON syntax error")],
    ids=["syntax", "deep", "empty"],
)
def test_bad_json_scenario(tmp_path: Path, text: str, line: int, message: str) -> None:
    path = write(tmp_path, text, "scenario.json")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, SPEC)
    [d] = info.value.diagnostics
    assert d.line == line and message in d.message, str(d)


def test_scenario_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_bytes(BASE.encode("utf-8").replace(b"name: MSO", b"name: \xff MSO"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, SPEC)
    assert info.value.diagnostics[0].line == 2 and "not UTF-8" in info.value.diagnostics[0].message


def test_scenario_alias_bomb(tmp_path: Path) -> None:
    bomb = "x0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"x{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]\n" for i in range(1, 9))
    path = write(tmp_path, BASE + bomb)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, SPEC)
    assert "YAML nodes" in info.value.diagnostics[0].message


# --------------------------------------------------------------------------- subprocesses

MOTIONCHART = Path(sys.executable).with_name("motionchart")


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST", "COV_"))}
    env.update(extra)
    return env


@pytest.mark.skipif(not MOTIONCHART.exists(), reason="console script not installed next to this python")
def test_console_script_reports_without_traceback(tmp_path: Path, spec_copy: Path) -> None:
    """Bad spec and bad scenario through the real console script, on an ASCII-only
    console: located lines, exit 1, no traceback (the key holds a non-ASCII character)."""
    broken = break_spec(spec_copy)
    bad = write(tmp_path, variant("{type: AXIS_SERVO}", "{type: ZZ_AXIS§}"))
    env = _env(PYTHONIOENCODING="ascii")
    proc = subprocess.run([str(MOTIONCHART), "validate", str(spec_copy)], capture_output=True, text=True,
                          env=env, timeout=60, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"{broken}:{line_of(broken, 'zz_bogus')}:")
    proc = subprocess.run([str(MOTIONCHART), "simulate", str(bad)], capture_output=True, text=True,
                          env=env, timeout=60, cwd=tmp_path)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"{bad}:{line_of(bad, 'ZZ_AXIS')}:")
    assert "unknown axis type 'ZZ_AXIS\\xa7'" in proc.stderr


def test_python_dash_m_checker_validate(tmp_path: Path) -> None:
    env = _env(PYTHONPATH=os.pathsep.join(filter(None, [str(PROJECT), os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, "-m", "checker", "validate"], capture_output=True, text=True,
                          env=env, timeout=60, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("spec OK: ") and proc.stderr == ""
    proc = subprocess.run([sys.executable, "-m", "checker", "validate", "no/such/path"], capture_output=True,
                          text=True, env=env, timeout=60, cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


# --------------------------------------------------------------------------- fuzz

_SCENARIO_STRINGS = sorted(
    {"Axis1", "mso1", "mdo1", "MSO", "MDO", "EN", "DN", "ER", "ERR", "AxisState", "state", "AXIS_SERVO",
     "AXIS_VIRTUAL", "", "zz", "true", "1e400", "[", "{", "&a [*a]", "*a", "!!binary aGk=", "- x", "? [a]\n: b"}
    | {s.id for s in CHART.states} | {v.name for v in CHART.variables} | {e.name for e in CHART.events}
    | {o.name for i in SPEC.instructions for o in i.operands}
)


@st.composite
def _damaged_scenarios(draw: st.DrawFn) -> str:
    lines = BASE.splitlines(keepends=True)
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(lines) - 1))
        op = draw(st.sampled_from(["delete", "duplicate", "swap", "scalar", "indent", "word"]))
        if op == "delete" and len(lines) > 1:
            del lines[i]
        elif op == "duplicate":
            lines.insert(i, lines[i])
        elif op == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif op == "scalar":
            words = re.findall(r"[\w.§-]+", lines[i])
            if words:
                old = draw(st.sampled_from(words))
                new = draw(st.one_of(st.sampled_from(_SCENARIO_STRINGS), st.text(max_size=8),
                                     st.integers().map(str), st.floats().map(str)))
                lines[i] = lines[i].replace(old, new, 1)
        elif op == "indent":
            lines[i] = "  " + lines[i] if draw(st.booleans()) else lines[i][2:]
        elif op == "word":
            key = draw(st.sampled_from(["scans", "prescan", "events", "operands", "state", "variables", "expect"]))
            value = draw(st.sampled_from(["3", "true", "[]", "{}", "[{axis: Axis1, event: zz}]", "{mdo1: {zz: 1}}",
                                          "{Axis1: {state: AxisReady}}", "AxisReady", "{OKContact: 5}"]))
            lines.insert(i, " " * draw(st.sampled_from([0, 2, 4, 6])) + f"{key}: {value}\n")
    return "".join(lines)


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture])  # tmp_path is reused on purpose: each example overwrites one file
@given(text=_damaged_scenarios(), suffix=st.sampled_from([".yaml", ".json"]))
def test_fuzz_damaged_scenario_raises_only_scenario_error(tmp_path: Path, text: str, suffix: str) -> None:
    path = tmp_path / f"fuzz{suffix}"
    if suffix == ".json":
        from ruamel.yaml import YAML

        with contextlib.suppress(Exception):
            text = json.dumps(YAML(typ="safe").load(text), default=str)
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        result = run_scenario(load_scenario(path, SPEC), SPEC)
    except ScenarioError as exc:
        assert exc.diagnostics and all(d.file == str(path) and d.line >= 1 for d in exc.diagnostics)
    else:
        assert len(result.rows) == sum(s.scans for s in result.scenario.steps)
