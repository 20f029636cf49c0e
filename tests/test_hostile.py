"""Hostile and broken inputs: each is a located error, never a traceback, a hang or a pass.

One test (or one parametrised case) per way of breaking an input that was once accepted
silently, hung or ended in a traceback: eventless cycles, runaway expressions, files
that are not regular files, integers beyond the Logix types, duplicate codes, actions
that assign the wrong type, look-alike Unicode names, scenarios that check nothing or
check what can never be observed, property expressions that cannot be evaluated, and
output that cannot be written.  Spec edits go through
:func:`statecharts.loader.load_spec_documents` on the parsed bundled spec (fast); the
command-line cases run ``motionchart`` in process through :func:`checker.cli.main`.
"""

from __future__ import annotations

import copy
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from checker.cli import main
from statecharts.diagnostics import ScenarioError, SpecError
from statecharts.engine import MAX_MICROSTEPS, EventlessLoopError
from statecharts.expr import MAX_SIZE, EvalError, ExprError, parse_assignment, parse_expression
from statecharts.loader import bundled_spec_dir, load_spec_documents, plain_data, read_yaml, spec_files
from statecharts.scenario import load_scenario, load_scenario_document, run_scenario

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "noncip" / "exec_rung_false_clears_en.yaml"


def _bundled_documents() -> dict[str, Any]:
    docs: dict[str, Any] = {}
    for p in spec_files():
        if p.suffix == ".json" or p.parent.name in ("schema", "systems", "properties"):
            continue
        docs[str(p)] = plain_data(read_yaml(p, []))
    return docs


_DOCS = _bundled_documents()


def _doc(docs: dict[str, Any], suffix: str) -> Any:
    return next(v for k, v in docs.items() if k.replace(os.sep, "/").endswith(suffix))


def _edited(edit: Callable[[dict[str, Any]], None]) -> dict[str, Any]:
    docs = copy.deepcopy(_DOCS)
    edit(docs)
    return docs


def _spec_errors(edit: Callable[[dict[str, Any]], None]) -> list[str]:
    with pytest.raises(SpecError) as info:
        load_spec_documents(_edited(edit))
    for d in info.value.diagnostics:
        assert d.file and d.line >= 1
    return [str(d) for d in info.value.diagnostics]


def _noncip(docs: dict[str, Any]) -> dict[str, Any]:
    chart: dict[str, Any] = _doc(docs, "charts/axis_noncip.yaml")["chart"]
    return chart


def _add_transitions(*ts: dict[str, Any]) -> Callable[[dict[str, Any]], None]:
    def edit(docs: dict[str, Any]) -> None:
        _noncip(docs)["transitions"].extend({"source": "MC tests/test_hostile.py", **t} for t in ts)
    return edit


def _add_variable(v: dict[str, Any]) -> Callable[[dict[str, Any]], None]:
    def edit(docs: dict[str, Any]) -> None:
        _noncip(docs)["variables"].append({"source": "MC tests/test_hostile.py", **v})
    return edit


def _both(*edits: Callable[[dict[str, Any]], None]) -> Callable[[dict[str, Any]], None]:
    def edit(docs: dict[str, Any]) -> None:
        for e in edits:
            e(docs)
    return edit


# --------------------------------------------------------------------------- eventless cycles

CYCLES = {
    "two states": _add_transitions(
        {"id": "loop1", "from": "AxisReady", "to": "AxisFaulted", "guard": "True", "priority": -9},
        {"id": "loop2", "from": "AxisFaulted", "to": "AxisReady", "guard": "True", "priority": -9}),
    "self-loop": _add_transitions({"id": "self1", "from": "AxisReady", "to": "AxisReady", "guard": "True",
                                   "priority": -9}),
    "internal toggle": _add_transitions({"id": "toggle", "from": "AxisReady", "guard": "not Moving or Moving",
                                         "actions": ["Moving = not Moving"], "priority": -9}),
    "counter over a finite domain": _both(
        _add_variable({"name": "N", "type": "int", "initial": 0, "range": [0, 9]}),
        _add_transitions({"id": "count", "from": "AxisReady", "guard": "N >= 0", "actions": ["N = (N + 1) % 10"],
                          "priority": -9})),
}


@pytest.mark.parametrize("name", sorted(CYCLES))
def test_an_eventless_cycle_is_a_load_error_naming_it(name: str) -> None:
    errors = _spec_errors(CYCLES[name])
    assert any("eventless cycle" in e and "axis_noncip.yaml" in e for e in errors), errors


def test_a_cycle_that_ends_is_no_error() -> None:
    load_spec_documents(_edited(_both(
        _add_variable({"name": "N", "type": "int", "initial": 0, "range": [0, 10]}),
        _add_transitions({"id": "count", "from": "AxisReady", "guard": "N < 10", "actions": ["N = N + 1"],
                          "priority": -9}))))


def test_an_unbounded_eventless_counter_is_stopped_by_the_engine_bound() -> None:
    spec = load_spec_documents(_edited(_both(
        _add_variable({"name": "N", "type": "int", "initial": 0}),
        _add_transitions({"id": "count", "from": "AxisReady", "guard": "N >= 0", "actions": ["N = N + 1"],
                          "priority": -9}))))
    scenario = load_scenario(SCENARIO, spec)
    with pytest.raises(ScenarioError) as info:
        run_scenario(scenario, spec)
    text = str(info.value)
    assert "AxisNonCIP" in text and "'count'" in text and f"after {MAX_MICROSTEPS}" in text


def test_the_engine_error_is_an_eval_error() -> None:
    assert issubclass(EventlessLoopError, EvalError)


# --------------------------------------------------------------------------- bounded evaluation


@pytest.mark.parametrize("text, env", [
    ("max([0] * n) == 0", {"n": 10**9}),
    ("len_ok == ('ab' * n)", {"len_ok": "", "n": 10**8}),
    ("s + s + s + s == ''", {"s": "a" * (MAX_SIZE // 2)}),
    ("x * x * x * x > 0", {"x": 2**40}),
])
def test_runaway_values_are_refused_naming_the_expression(text: str, env: dict[str, object]) -> None:
    e = parse_expression(text)
    with pytest.raises(EvalError) as info:
        e(env)
    assert text in str(info.value)


def test_a_constant_runaway_value_is_refused_at_load_time() -> None:
    with pytest.raises(ExprError) as info:
        parse_expression("'ab' * 100000 == ''")
    assert "longer than" in str(info.value)


@pytest.mark.parametrize("text", ["𝐒ervoFault", "ＳervoFault and True", "not ﬁrst"])
def test_look_alike_unicode_identifiers_are_refused(text: str) -> None:
    with pytest.raises(ExprError) as info:
        parse_expression(text)
    assert "look-alike" in str(info.value)


def test_a_bold_guard_in_the_spec_is_a_located_error() -> None:
    def edit(docs: dict[str, Any]) -> None:
        _noncip(docs)["transitions"][0]["guard"] = "𝐒ervoFault"
    errors = _spec_errors(edit)
    assert any("look-alike" in e and "transitions[0].guard" in e for e in errors), errors


# --------------------------------------------------------------------------- integers, codes, bits


def test_an_error_code_defined_twice_is_refused() -> None:
    def edit(docs: dict[str, Any]) -> None:
        errors = _doc(docs, "errors.yaml")["errors"]
        errors.append(dict(errors[3]))
    assert any("duplicate error code" in e for e in _spec_errors(edit))


def test_an_error_code_defined_in_two_files_is_refused() -> None:
    def edit(docs: dict[str, Any]) -> None:
        first = dict(_doc(docs, "errors.yaml")["errors"][3])
        docs[str(bundled_spec_dir() / "more_errors.yaml")] = {"format": "motionchart-spec/1", "errors": [first]}
    errors = _spec_errors(edit)
    assert any("more_errors.yaml" in e and "duplicate error code" in e and "first defined at" in e for e in errors)


def test_an_extended_error_defined_twice_is_refused() -> None:
    def edit(docs: dict[str, Any]) -> None:
        ext = _doc(docs, "errors.yaml")["extended_errors"]
        ext.append(dict(ext[0]))
    assert any("duplicate extended error" in e for e in _spec_errors(edit))


@pytest.mark.parametrize("where", ["error code", "state value", "range bound"])
def test_integers_beyond_a_dint_are_refused(where: str) -> None:
    def edit(docs: dict[str, Any]) -> None:
        if where == "error code":
            _doc(docs, "errors.yaml")["errors"][3]["code"] = 2**70
        elif where == "state value":
            _noncip(docs)["states"][1]["value"] = 2**70
        else:
            _noncip(docs)["variables"].append({"name": "Big", "type": "int", "initial": 0, "range": [0, 2**80],
                                               "source": "MC tests/test_hostile.py"})
    assert any("outside the DINT range" in e for e in _spec_errors(edit))


def test_a_tag_bit_collision_is_refused() -> None:
    def edit(docs: dict[str, Any]) -> None:
        members = _doc(docs, "motion_instruction.yaml")["tag_type"]["members"]
        members[1]["bit"] = members[0]["bit"]
    assert any("is already" in e and "bit" in e for e in _spec_errors(edit))


@pytest.mark.parametrize("action, fragment", [
    ("TestTimer = 'abc'", "assigns a string to TestTimer"),
    ("ServoFault = 3", "assigns an integer to ServoFault"),
    ("FaultAction = 'Explode'", "outside its domain"),
    ("TestTimer = 5000", "outside its domain"),
])
def test_an_action_of_the_wrong_type_or_domain_is_refused(action: str, fragment: str) -> None:
    def edit(docs: dict[str, Any]) -> None:
        _noncip(docs)["transitions"][0].setdefault("actions", []).append(action)
    errors = _spec_errors(edit)
    assert any(fragment in e and "transitions[0].actions" in e for e in errors), errors


def test_a_huge_enable_delay_is_refused_at_load_time() -> None:
    def edit(docs: dict[str, Any]) -> None:
        for v in _noncip(docs)["variables"]:
            if v["name"] == "EnableDelayMs":
                v["domain"], v["initial"] = [10**9], 10**9
    assert any("EnableTimer" in e and "outside its domain" in e for e in _spec_errors(edit))


@pytest.mark.parametrize("root", [5, None, [1, 2]])
def test_an_interpretations_file_with_a_wrong_root_is_a_located_error(root: object) -> None:
    def edit(docs: dict[str, Any]) -> None:
        docs[next(k for k in docs if k.endswith("interpretations.yaml"))] = root
    assert any("interpretations.yaml" in e for e in _spec_errors(edit))


def test_an_interpretations_file_with_a_wrong_root_is_one_clear_error_in_validate(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import shutil
    spec = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), spec, ignore=shutil.ignore_patterns("__pycache__", "*.py"))
    for root in ("5", "null", "[1, 2]"):
        (spec / "interpretations.yaml").write_text(root + "\n")
        assert main(["validate", str(spec)]) == 1
        err = capsys.readouterr().err
        assert "interpretations.yaml:1:1" in err and "Traceback" not in err


# --------------------------------------------------------------------------- input files


def _fifo(tmp_path: Path) -> str:
    path = tmp_path / "pipe.yaml"
    os.mkfifo(path)
    return str(path)


def _loop(tmp_path: Path) -> str:
    (tmp_path / "a.yaml").symlink_to(tmp_path / "b.yaml")
    (tmp_path / "b.yaml").symlink_to(tmp_path / "a.yaml")
    return str(tmp_path / "a.yaml")


def _dir(tmp_path: Path) -> str:
    (tmp_path / "dir.yaml").mkdir()
    return str(tmp_path / "dir.yaml")


INPUTS: dict[str, Callable[[Path], str]] = {
    "FIFO": _fifo,
    "/dev/zero": lambda _p: "/dev/zero",
    "symlink loop": _loop,
    "directory named like a YAML file": _dir,
    "empty path": lambda _p: "",
    "over-long name": lambda p: str(p / ("x" * 5000 + ".yaml")),
}


@pytest.mark.skipif(sys.platform == "win32", reason="FIFOs and /dev/zero are POSIX")
@pytest.mark.parametrize("command", ["validate", "simulate"])
@pytest.mark.parametrize("kind", sorted(INPUTS))
def test_unusable_input_files_are_one_clear_message(
        kind: str, command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = INPUTS[kind](tmp_path)
    code = main([command, path])
    err = capsys.readouterr().err
    assert code in (1, 2)
    assert "Traceback" not in err and err.strip()
    assert len(max(err.splitlines(), key=len)) < 1000


@pytest.mark.skipif(sys.platform == "win32", reason="FIFOs are POSIX")
def test_a_fifo_scenario_is_refused_with_what_it_is(tmp_path: Path) -> None:
    from statecharts.loader import load_spec
    with pytest.raises(ScenarioError) as info:
        load_scenario(_fifo(tmp_path), load_spec())
    assert "FIFO" in str(info.value) and ":1:1:" in str(info.value)


# --------------------------------------------------------------------------- scenarios


def _scenario_doc(**steps: Any) -> dict[str, Any]:
    return {
        "format": "motionchart-scenario/1", "name": "hostile",
        "setup": {"axes": {"Axis1": {"type": "AXIS_SERVO"}},
                  "program": [{"tag": "mso1", "instruction": "MSO", "axis": "Axis1"}]},
        "steps": [{"rungs": {"mso1": True}, **steps}],
    }


@pytest.mark.parametrize("expect, fragment", [
    (None, "no step has `expect:`"),
    ({"Axis1": {"state": "ServoCtrl"}}, "did you mean 'ServoControl'"),
    ({"Axis1": {"state": "Operating"}}, "has no state 'Operating'"),
    ({"mso1": {"DN": "yes"}}, "expected true or false"),
    ({"mso1": {"ERR": 2**70}}, "outside the INT range"),
    ({"mso1": {"ERR": float("nan")}}, "NaN"),
    ({"Axis1": {"AxisState": "2"}}, "expected an integer state value"),
])
def test_expectations_that_can_never_hold_are_invalid(spec: Any, expect: Any, fragment: str) -> None:
    doc = _scenario_doc(**({"expect": expect} if expect is not None else {}))
    with pytest.raises(ScenarioError) as info:
        load_scenario_document("hostile.yaml", doc, spec)
    assert fragment in str(info.value)
    assert all(d.file == "hostile.yaml" for d in info.value.diagnostics)


def test_a_json_scenario_with_huge_integers_is_a_located_error(spec: Any, tmp_path: Path) -> None:
    doc = _scenario_doc(expect={"mso1": {"ERR": 2**70}})
    doc["setup"]["program"][0]["operands"] = {}
    path = tmp_path / "big.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, spec)
    assert "big.json" in str(info.value) and "outside the INT range" in str(info.value)


def test_a_json_scenario_with_a_nan_is_a_located_error(spec: Any, tmp_path: Path) -> None:
    path = tmp_path / "nan.json"
    path.write_text(json.dumps(_scenario_doc(expect={"mso1": {"ERR": float("nan")}})))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, spec)
    assert "nan.json:1:1" in str(info.value)


def test_a_nan_operand_is_a_located_error(spec: Any) -> None:
    doc = _scenario_doc(expect={"mdo1": {"EN": True}})
    doc["setup"]["program"] = [{"tag": "mdo1", "instruction": "MDO", "axis": "Axis1",
                                "operands": {"DriveOutput": float("nan")}}]
    doc["steps"][0]["rungs"] = {"mdo1": True}
    with pytest.raises(ScenarioError) as info:
        load_scenario_document("nan.yaml", doc, spec)
    assert "DriveOutput" in str(info.value) and "finite" in str(info.value)


def test_division_by_zero_in_an_action_is_a_located_scenario_error() -> None:
    def edit(docs: dict[str, Any]) -> None:
        for t in _noncip(docs)["transitions"]:
            if t["id"] == "mso":
                t["actions"].append("ServoOutput = 1.0 / (OutputLimit - OutputLimit)")
    spec = load_spec_documents(_edited(edit))
    doc = _scenario_doc(expect={"mso1": {"DN": True}})
    scenario = load_scenario_document("div.yaml", doc, spec)
    with pytest.raises(ScenarioError) as info:
        run_scenario(scenario, spec)
    assert "div.yaml" in str(info.value) and "division by zero" in str(info.value)


def test_a_long_run_keeps_no_rows_when_asked(spec: Any) -> None:
    doc = _scenario_doc(expect={"mso1": {"DN": True}}, scans=2000)
    scenario = load_scenario_document("long.yaml", doc, spec)
    seen: list[int] = []
    result = run_scenario(scenario, spec, on_row=lambda row: seen.append(row.record.index), keep_rows=False)
    assert result.rows == () and result.scans == 2000 and len(seen) == 2000 and result.passed


# --------------------------------------------------------------------------- the checker


def _write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_a_property_naming_an_unknown_state_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    props = _write(tmp_path, "p.yaml", (
        "format: motionchart-properties/1\nproperties:\n  - name: bogus\n    kind: reachable\n    scope: axis\n"
        "    chart: AxisNonCIP\n    goal: \"state == 'ServoCtrl'\"\n    source: test\n"))
    assert main(["check", "-q", "--properties", props]) == 1
    err = capsys.readouterr().err
    assert "p.yaml:7:" in err and "did you mean 'ServoControl'" in err


def test_division_by_zero_in_a_property_is_a_located_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    props = _write(tmp_path, "p.yaml", (
        "format: motionchart-properties/1\nproperties:\n  - name: divzero\n    kind: invariant\n    scope: axis\n"
        "    chart: AxisNonCIP\n    holds: \"1 / (AxisState - AxisState) > 0\"\n    source: test\n"))
    assert main(["check", "-q", "--properties", props]) == 1
    err = capsys.readouterr().err
    assert "p.yaml:3: property divzero" in err and "division by zero" in err and "Traceback" not in err


def test_too_many_axes_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", "--axes", "1000000"]) == 2
    assert "at most" in capsys.readouterr().err


def test_graphml_under_a_file_is_refused_before_the_search(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "afile").write_text("")
    assert main(["check", "-q", "--graphml", str(tmp_path / "afile" / "g.graphml")]) == 2
    assert "is not a directory" in capsys.readouterr().err


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_output_to_a_full_device_is_one_line_and_exit_1(capsys: pytest.CaptureFixture[str]) -> None:
    import subprocess
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "checker", "validate"], stdout=full, stderr=subprocess.PIPE,
                              text=True, timeout=600, check=False)
    assert proc.returncode == 1
    assert "cannot write" in proc.stderr and "Traceback" not in proc.stderr


# --------------------------------------------------------------------------- atomic files


def test_an_atomic_write_leaves_no_temporary_file_when_interrupted(tmp_path: Path) -> None:
    from statecharts.outputs import atomic_path, atomic_write_text
    target = tmp_path / "out.txt"
    atomic_write_text(target, "old")
    with pytest.raises(KeyboardInterrupt), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise KeyboardInterrupt
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_assignments_parse_once_and_are_shared() -> None:
    assert parse_assignment("X = 1") is parse_assignment("X = 1")


def test_an_interrupted_folder_update_leaves_the_previous_folder(tmp_path: Path) -> None:
    from statecharts.outputs import replace_folder
    out = tmp_path / "docs"
    out.mkdir()
    (out / "index.md").write_text("old")

    def fill(folder: Path) -> None:
        (folder / "index.md").write_text("new")
        (folder / "half.md.tmp").write_text("half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        replace_folder(out, fill)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["docs"]
    assert sorted(p.name for p in out.iterdir()) == ["index.md"] and (out / "index.md").read_text() == "old"


def test_a_completed_folder_update_replaces_the_folder_whole(tmp_path: Path) -> None:
    from statecharts.outputs import replace_folder
    out = tmp_path / "docs"
    out.mkdir()
    (out / "index.md").write_text("old")
    (out / "kept.txt").write_text("kept")
    replace_folder(out, lambda folder: (folder / "index.md").write_text("new"))
    assert (out / "index.md").read_text() == "new" and (out / "kept.txt").read_text() == "kept"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["docs"]


def test_docs_into_an_unwritable_place_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "afile").write_text("")
    assert main(["docs", "-o", str(tmp_path / "afile" / "docs")]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_vector_files_go_through_the_safe_reader(tmp_path: Path) -> None:
    from conformance.vectors import load_vector
    big = tmp_path / "big.json"
    big.write_text('{"a": ' + "9" * 5000 + "}")
    for path, fragment in (("/dev/zero", "character device"), (str(big), "JSON error")):
        with pytest.raises(ScenarioError) as info:
            load_vector(path)
        assert fragment in str(info.value) and ":1:1:" in str(info.value)


def test_check_on_an_undecided_eventless_loop_is_a_located_error(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import shutil

    from ruamel.yaml import YAML
    spec = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), spec, ignore=shutil.ignore_patterns("__pycache__", "*.py"))
    chart_file = spec / "charts" / "axis_noncip.yaml"
    yaml = YAML(typ="rt")
    yaml.width = 10**6
    tree = yaml.load(chart_file.read_text())
    tree["chart"]["variables"].append({"name": "N", "type": "int", "initial": 0, "source": "MC tests/test_hostile.py"})
    tree["chart"]["transitions"].append({"id": "count", "from": "AxisReady", "guard": "N >= 0",
                                         "actions": ["N = N + 1"], "priority": -9, "source": "MC tests/test_hostile.py"})
    with chart_file.open("w") as fh:
        yaml.dump(tree, fh)
    assert main(["check", "-q", "--spec", str(spec)]) == 1
    err = capsys.readouterr().err
    assert "eventless" in err and "'count'" in err and "axis_noncip.yaml" in err and "Traceback" not in err
