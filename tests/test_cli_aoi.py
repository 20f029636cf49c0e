"""``motionchart validate`` loads the whole spec, the add-on instruction (``spec/addons/``) included.

What is checked: the one summary line and the add-on instruction's counts in it (17 ordered checks and 21 codes
are typed in from 003 §1.3.2 / §2.4 and docs/aoi.md, not read from the spec); the
``--json`` record; and that a broken add-on instruction or sub-instruction file in a
copy of the spec gives located ``file:line:col: path: message`` lines on standard
error, the error count, exit 1, nothing on standard output and no traceback, also
through the installed console script and for ``generate`` and ``diagram``; and that a
copy validate refuses (a duplicated check id, a broken motion instruction file) is refused
by every command that loads a spec, at the same place.  The line
of each diagnostic is found by a marker unique to the change.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from checker.cli import main
from statecharts.loader import bundled_spec_dir, load_spec

DIAGNOSTIC = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (?P<rest>.*)$")
AOI_ID = "raM_Opr_SyncPthPhyAx_CD"
ROOT = Path(__file__).resolve().parents[1]
#: 003 §1.3.2 has 17 rows with a code once 1017 is placed (docs/aoi.md); §2.4 lists 21 codes.
DOCUMENTED_CHECKS = 17
DOCUMENTED_CODES = 21
#: MAH, MAM, MAG, MRP and MAS (docs/aoi.md, "the recovery chart").
DOCUMENTED_SUBS = 5
MOTIONCHART = Path(sys.executable).with_name("motionchart")


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def diagnostics(err: str) -> list[re.Match[str]]:
    return [m for m in (DIAGNOSTIC.match(line) for line in err.splitlines()) if m is not None]


def line_of(path: Path, marker: str) -> int:
    lines = [i for i, t in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if marker in t]
    assert len(lines) == 1, lines
    return lines[0]


@pytest.fixture
def spec_copy(tmp_path: Path) -> Path:
    d = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), d, ignore=shutil.ignore_patterns("__pycache__", "*.py", "schema"))
    return d


def aoi_file(spec_dir: Path) -> Path:
    (path,) = sorted((spec_dir / "addons").glob("*.yaml"))
    return path


def edit(path: Path, old: str, new: str) -> Path:
    text = path.read_text(encoding="utf-8")
    assert text.count(old) == 1, old
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


def assert_located(rc: int, out: str, err: str, file: Path, line: int, *words: str) -> None:
    assert rc == 1 and out == "", (out, err)
    assert "Traceback" not in err
    found = diagnostics(err)
    assert found, err
    hits = [m for m in found if m["file"] == str(file) and int(m["line"]) == line]
    assert hits, f"no diagnostic at {file}:{line} in\n{err}"
    for w in words:
        assert any(w in m["rest"] for m in hits), (w, err)
    assert err.rstrip().endswith(f"{len(found)} error(s)")


# --------------------------------------------------------------------------- the summary


def test_validate_prints_one_summary_with_the_add_on_instruction(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = run(capsys, "validate")
    assert (rc, err) == (0, "")
    (line,) = out.splitlines()
    assert line.startswith("spec OK: ")
    (add_on,) = load_spec().add_ons
    calls = {s.call.instruction for s in add_on.recovery.states if s.call} | {add_on.rung_false.abort_call}
    assert (len(add_on.checks), len(add_on.errors), len(calls)) == (DOCUMENTED_CHECKS, DOCUMENTED_CODES, DOCUMENTED_SUBS)
    rec = add_on.recovery
    assert line.endswith(f", add-on instruction {AOI_ID} ({DOCUMENTED_CHECKS} checks, {DOCUMENTED_CODES} codes, "
                         f"{len(rec.states)} recovery states, {len(rec.transitions)} transitions; "
                         "calls MAG, MAH, MAM, MAS, MRP)")


def test_validate_directory_loads_its_own_add_on_instruction(capsys: pytest.CaptureFixture[str],
                                                             spec_copy: Path) -> None:
    # one check fewer in the copy: the count printed is the copy's, not the bundled one's
    edit(aoi_file(spec_copy), "    - {id: speed, err: 1017,", "    - {id: speed_gone, err: 1017,")
    text = aoi_file(spec_copy).read_text(encoding="utf-8")
    kept = [line for line in text.splitlines() if "{id: speed_gone," not in line]
    aoi_file(spec_copy).write_text("\n".join(kept) + "\n", encoding="utf-8")
    rc, out, err = run(capsys, "validate", str(spec_copy))
    assert (rc, err) == (0, "")
    assert f"add-on instruction {AOI_ID} ({DOCUMENTED_CHECKS - 1} checks, {DOCUMENTED_CODES} codes" in out


def test_validate_json_lists_the_add_on_instruction(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = run(capsys, "validate", "--json")
    assert rc == 0
    doc = json.loads(out)
    (aoi,) = doc["add_on_instructions"]
    assert aoi["id"] == AOI_ID and aoi["file"] == "spec/addons/raM_Opr_SyncPthPhyAx_CD.yaml"
    assert (aoi["checks"], aoi["error_codes"]) == (DOCUMENTED_CHECKS, DOCUMENTED_CODES)
    assert aoi["calls"] == ["MAG", "MAH", "MAM", "MAS", "MRP"]


def test_a_spec_file_alone_has_no_add_on_instruction(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # a file (not a directory) names no addons/ folder: only the main loader speaks
    f = tmp_path / "one.yaml"
    f.write_text("format: motionchart-spec/1\n", encoding="utf-8")
    rc, out, err = run(capsys, "validate", str(f))
    assert rc == 1 and out == "" and "add-on" not in err and "Traceback" not in err


# --------------------------------------------------------------------------- broken add-on instruction files


def test_malformed_aoi_yaml_is_a_located_error(capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    path = edit(aoi_file(spec_copy), "  execution: {mode: level,", "  execution: {mode: level: zz_mark,")
    rc, out, err = run(capsys, "validate", str(spec_copy))
    assert_located(rc, out, err, path, line_of(path, "zz_mark"), "YAML syntax error")
    assert len(diagnostics(err)) == 1  # one loader: one report


@pytest.mark.parametrize(("old", "new", "marker", "words"), [
    ("  execution: {mode: level,", "  zz_unknown: 1\n  execution: {mode: level,", "zz_unknown",
     ("add_on_instruction", "zz_unknown")),
    ('fails_when: "handler.eState != 7"', 'fails_when: "handler.eState !=== 7"', "!===",
     ("add_on_instruction.checks[1].fails_when", "!==")),
    ('fails_when: "handler.eState != 7"', 'fails_when: "hndlr_zz.eState != 7"', "hndlr_zz",
     ("add_on_instruction.checks[1].fails_when", "unknown variable")),
    ("{id: handler_running, err: 1001,", "{id: handler_running, err: 9901,", "9901",
     ("add_on_instruction.checks[1].err", "9901")),
    ("{from: homing, to: moving,", "{from: homing_zz, to: moving,", "homing_zz",
     ("add_on_instruction.recovery.transitions[4].from", "unknown state")),
    ("call: {instruction: MAH, axis: phy}", "call: {instruction: MZZ, axis: phy}", "MZZ",
     ("add_on_instruction.recovery.states[4].call.instruction", "unknown instruction")),
    # a repeated check id is refused by the loader itself (anchors and diagram nodes need it unique)
    ("{id: handler_running, err: 1001,", "{id: registered, err: 1001,", "{id: registered, err: 1001,",
     ("add_on_instruction.checks[1].id", "duplicate check 'registered'")),
])
def test_bad_aoi_content_is_a_located_error(capsys: pytest.CaptureFixture[str], spec_copy: Path, old: str,
                                            new: str, marker: str, words: tuple[str, ...]) -> None:
    path = edit(aoi_file(spec_copy), old, new)
    rc, out, err = run(capsys, "validate", str(spec_copy))
    assert_located(rc, out, err, path, line_of(path, marker), *words)


def test_bad_aoi_json_output(capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    path = edit(aoi_file(spec_copy), "  execution: {mode: level,", "  zz_unknown: 1\n  execution: {mode: level,")
    rc, out, _ = run(capsys, "validate", "--json", str(spec_copy))
    assert rc == 1
    doc = json.loads(out)
    assert doc["valid"] is False
    (d,) = doc["diagnostics"]
    assert (d["file"], d["line"]) == (str(path), line_of(path, "zz_unknown"))


def test_empty_aoi_file_is_reported(capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    path = aoi_file(spec_copy)
    path.write_text("", encoding="utf-8")
    rc, out, err = run(capsys, "validate", str(spec_copy))
    assert_located(rc, out, err, path, 1, "empty")


def test_a_spec_without_the_add_on_instruction_is_refused_by_commands_that_need_it(
        capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    aoi_file(spec_copy).rename(spec_copy / "addons" / "moved.txt")
    rc, out, err = run(capsys, "validate", str(spec_copy))
    # what only the add-on instruction cited is now cited by nothing: a located error
    assert rc == 1 and out == "" and "interpretation INT-023 is not used by any spec element" in err
    rc, out, err = run(capsys, "diagram", AOI_ID, "--spec", str(spec_copy))
    assert rc != 0 and out == "" and "Traceback" not in err
    assert str(bundled_spec_dir()) not in err


def test_bad_sub_instruction_is_a_located_error(capsys: pytest.CaptureFixture[str], spec_copy: Path) -> None:
    # the MAM the recovery calls on the CIP axis is the main spec's
    path = edit(spec_copy / "instructions" / "cip" / "MAM.yaml", "err: 17,", "err: -17,")
    rc, out, err = run(capsys, "validate", str(spec_copy))
    assert_located(rc, out, err, path, line_of(path, "err: -17,"), "instruction.checks[10].err")


def test_aoi_and_main_spec_errors_are_reported_together(capsys: pytest.CaptureFixture[str],
                                                        spec_copy: Path) -> None:
    aoi = edit(aoi_file(spec_copy), "  execution: {mode: level,", "  zz_unknown: 1\n  execution: {mode: level,")
    main_file = sorted((spec_copy / "instructions").glob("*.yaml"))[0]
    edit(main_file, "\ninstruction:\n", "\ninstruction:\n  zz_bogus: 1\n")
    rc, out, err = run(capsys, "validate", str(spec_copy))
    assert rc == 1 and out == ""
    files = {m["file"] for m in diagnostics(err)}
    assert {str(aoi), str(main_file)} <= files
    assert err.rstrip().endswith("2 error(s)")


def test_generate_and_diagram_report_a_broken_aoi(capsys: pytest.CaptureFixture[str], spec_copy: Path,
                                                  tmp_path: Path) -> None:
    path = edit(aoi_file(spec_copy), 'fails_when: "handler.eState != 7"', 'fails_when: "hndlr_zz.eState != 7"')
    line = line_of(path, "hndlr_zz")
    rc, out, err = run(capsys, "generate", "-o", str(tmp_path / "gen"), "--spec", str(spec_copy),
                       "--scenarios", str(tmp_path))
    assert rc == 1 and "Traceback" not in err and f"{path}:{line}:" in err
    rc, out, err = run(capsys, "diagram", AOI_ID, "--spec", str(spec_copy))
    assert rc == 1 and out == "" and f"{path}:{line}:" in err
    # the add-on instruction is part of the spec: a spec validate rejects, every command rejects
    rc, out, err = run(capsys, "diagram", "AxisNonCIP", "--spec", str(spec_copy))
    assert rc == 1 and out == "" and f"{path}:{line}:" in err


# --------------------------------------------------------------------------- one validation for every command

#: Every command that loads a spec, with the arguments that make it load ``--spec COPY``
#: (``{spec}``: the copy, ``{tmp}``: a scratch directory); each must refuse what validate refuses.
COMMANDS = {
    "validate": ("validate", "{spec}"),
    "simulate_aoi": ("simulate", "-q", str(ROOT / "scenarios" / "aoi" / "err_1017_negative_speed.yaml"), "--spec", "{spec}"),
    "simulate_axis": ("simulate", "-q", str(ROOT / "scenarios" / "noncip" / "exec_prescan.yaml"), "--spec", "{spec}"),
    "check": ("check", "--spec", "{spec}"),
    "check_aoi": ("check", "--system", "aoi", "--spec", "{spec}"),
    "export": ("export", "--spec", "{spec}", "-o", "{tmp}/model.pml"),
    "generate": ("generate", "-o", "{tmp}/gen", "--spec", "{spec}", "--scenarios", "{tmp}"),
    "docs": ("docs", "-o", "{tmp}/docs", "--spec", "{spec}", "--scenarios", "{tmp}"),
    "diagram_aoi": ("diagram", AOI_ID, "--spec", "{spec}"),
    "diagram_chart": ("diagram", "AxisNonCIP", "--spec", "{spec}"),
    "vectors": ("vectors", "-o", "{tmp}/vectors", "--spec", "{spec}", "--quiet"),
}

#: Copies validate refuses: (file under the spec, text, replacement, marker on the line reported, words).
BREAKS = {
    # two checks with one id (the diagram's nodes and the reference's anchors need them unique)
    "duplicate_check_id": ("addons/raM_Opr_SyncPthPhyAx_CD.yaml", "{id: handler_running, err: 1001,",
                           "{id: registered, err: 1001,", "{id: registered, err: 1001,",
                           ("add_on_instruction.checks[1].id", "duplicate check 'registered'")),
    # a motion instruction the recovery calls, with an error code below 1
    "sub_instruction_code": ("instructions/cip/MAM.yaml", "err: 17,", "err: -17,", "err: -17,",
                             ("instruction.checks[10].err",)),
    # a check of a motion instruction reading a name an axis does not offer
    "sub_instruction_name": ("instructions/cip/MAM.yaml", '"axis.DirectControlStatus"', '"axis.zz_control"',
                             "axis.zz_control", ("instruction.checks[6].fails_when", "axis.zz_control")),
}


#: The breaks of a motion instruction file are tried on the commands that read no add-on
#: instruction; the duplicated check id on all.
CASES = [(c, "duplicate_check_id") for c in sorted(COMMANDS)] + [
    (c, b) for b in ("sub_instruction_code", "sub_instruction_name")
    for c in ("validate", "check", "export", "docs", "diagram_chart", "simulate_axis")]


@pytest.mark.parametrize(("command", "broken"), CASES)
def test_a_spec_validate_refuses_is_refused_by_every_command(capsys: pytest.CaptureFixture[str], spec_copy: Path,
                                                              tmp_path: Path, command: str, broken: str) -> None:
    rel, old, new, marker, words = BREAKS[broken]
    path = edit(spec_copy / rel, old, new)
    line = line_of(path, marker)
    argv = [a.format(spec=spec_copy, tmp=tmp_path) for a in COMMANDS[command]]
    rc, out, err = run(capsys, *argv)
    assert rc == 1, (rc, out, err)
    assert "Traceback" not in out + err
    hits = [m for m in diagnostics(err) if m["file"] == str(path) and int(m["line"]) == line]
    assert hits, f"no diagnostic at {path}:{line} in\n{err}"
    for w in words:
        assert any(w in m["rest"] for m in hits), (w, err)
    assert "PASS" not in out and "spec OK" not in out
    assert not (tmp_path / "gen").exists() and not (tmp_path / "vectors").exists()


def test_an_add_on_call_of_a_missing_motion_instruction_is_refused(capsys: pytest.CaptureFixture[str],
                                                                   spec_copy: Path) -> None:
    (spec_copy / "instructions" / "cip" / "MAH.yaml").unlink()  # MAH of the CIP axis, which the recovery calls
    path = aoi_file(spec_copy)
    for argv in (("validate", str(spec_copy)), ("diagram", "AxisCIP", "--spec", str(spec_copy))):
        rc, out, err = run(capsys, *argv)
        assert rc == 1 and out == "" and "Traceback" not in err
        assert f"{path}:{line_of(path, 'call: {instruction: MAH, axis: phy}')}:" in err
        assert "MAH has no variant for chart AxisCIP" in err


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST", "COV_"))}
    env.update(extra)
    return env


@pytest.mark.skipif(not MOTIONCHART.exists(), reason="console script not installed next to this python")
def test_console_script_reports_a_broken_aoi_without_traceback(spec_copy: Path, tmp_path: Path) -> None:
    path = edit(aoi_file(spec_copy), "  execution: {mode: level,", "  zz_unknown§: 1\n  execution: {mode: level,")
    proc = subprocess.run([str(MOTIONCHART), "validate", str(spec_copy)], capture_output=True, text=True,
                          env=_env(PYTHONIOENCODING="ascii"), timeout=120, cwd=tmp_path)
    assert proc.returncode == 1 and proc.stdout == ""
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"{path}:{line_of(path, 'zz_unknown')}:")
    assert proc.stderr.rstrip().endswith("1 error(s)")


def test_simulate_runs_the_add_on_instruction_of_the_spec_copy(capsys: pytest.CaptureFixture[str],
                                                               spec_copy: Path) -> None:
    scenario = ROOT / "scenarios" / "aoi" / "err_1017_negative_speed.yaml"
    rc, out, err = run(capsys, "simulate", "-q", str(scenario), "--spec", str(spec_copy))
    assert rc == 0, (out, err)
    # the copy reports another code for a negative speed: the scenario that expects 1017 now fails
    edit(aoi_file(spec_copy), "{id: speed, err: 1017,", "{id: speed, err: 1013,")
    rc, out, err = run(capsys, "simulate", "-q", str(scenario), "--spec", str(spec_copy))
    assert rc == 1 and "Sts_ERR expected 1017, got 1013" in out + err, (out, err)
    # a copy the loader refuses is refused here too, with its place
    path = edit(aoi_file(spec_copy), 'fails_when: "handler.eState != 7"', 'fails_when: "hndlr_zz.eState != 7"')
    rc, out, err = run(capsys, "simulate", "-q", str(scenario), "--spec", str(spec_copy))
    assert rc == 1 and f"{path}:{line_of(path, 'hndlr_zz')}:" in err and "Traceback" not in err


def test_simulate_runs_the_motion_instructions_of_the_spec_copy(capsys: pytest.CaptureFixture[str],
                                                                spec_copy: Path) -> None:
    # RM002H p255: a zero MAM speed is ERR 13 (Parameter Out Of Range), which the add-on
    # instruction reports as 1022 with that code in Sts_EXERR (003 §2.4)
    scenario = ROOT / "scenarios" / "aoi" / "err_1022_mam_zero_speed.yaml"
    rc, out, err = run(capsys, "simulate", "-q", str(scenario), "--spec", str(spec_copy))
    assert rc == 0, (out, err)
    # the copy's MAM (the main instruction chart the recovery calls) takes a zero speed
    edit(spec_copy / "instructions" / "cip" / "MAM.yaml", "not (op.Speed > 0.0 and", "not (op.Speed >= 0.0 and")
    rc, out, err = run(capsys, "simulate", "-q", str(scenario), "--spec", str(spec_copy))
    assert rc == 1 and "Sync.Sts_ER expected true, got false" in out + err, (out, err)
