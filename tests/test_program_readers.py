"""The program readers: three forms of one routine give one program; bad programs give located errors."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from checker.cli import main
from statecharts.loader import load_spec
from statecharts.program.ir import AXIS_UNTYPED
from statecharts.program.reader import ProgramError, load_program
from statecharts.scenario import load_scenario, run_scenario

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "programs"
LOCATED = re.compile(r"^[^:]+:\d+:\d+: rung \d+: instruction \d+: ")


@pytest.fixture(scope="module")
def spec():
    return load_spec()


def test_the_three_forms_load_to_the_same_program(spec) -> None:
    ascii_ = load_program(EXAMPLES / "state_machine.rll", spec=spec)
    neutral = load_program(EXAMPLES / "state_machine.txt", spec=spec)
    l5x = load_program(EXAMPLES / "state_machine.L5X", spec=spec)
    assert (ascii_.form, neutral.form, l5x.form) == ("ascii", "neutral", "l5x")
    assert ascii_.routines == neutral.routines == l5x.routines
    assert ascii_.main == neutral.main == l5x.main == "MainRoutine"
    assert ascii_.tags == neutral.tags
    # the rung files declare no tags: every one is inferred, with the type and size the L5X declares;
    # only the axis type is the scenario's to give
    declared = {(t.name, t.data_type, t.dimensions, t.initial) for t in l5x.tags}
    inferred = {(t.name, t.data_type, t.dimensions, t.initial) for t in ascii_.tags}
    assert declared - inferred == {("Axis1", "AXIS_CIP_DRIVE", (), ())}
    assert inferred - declared == {("Axis1", AXIS_UNTYPED, (), ())}


def test_the_three_forms_run_to_the_same_observations(spec) -> None:
    tables = []
    for name in ("state_machine_ascii.yaml", "state_machine_neutral.yaml", "state_machine_l5x.yaml"):
        result = run_scenario(load_scenario(EXAMPLES / name, spec), spec)
        assert result.passed, [str(m) for m in result.mismatches]
        tables.append([(r.record.index, r.changes) for r in result.rows])
    assert tables[0] == tables[1] == tables[2]
    assert len(tables[0]) == 21


def _errors(tmp_path: Path, name: str, text: str | bytes, spec) -> list[str]:
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    with pytest.raises(ProgramError) as info:
        load_program(path, spec=spec)
    return [str(d) for d in info.value.diagnostics]


def test_unknown_mnemonic_and_wrong_operand_count(tmp_path: Path, spec) -> None:
    errors = _errors(tmp_path, "p.txt", "XIC(A)FOO(B)OTE(C);\nXIC(A,B)OTE(C);\nXIC(A)MAM(X,Y,1,2,3,4,5,6,7,8,9);\n", spec)
    assert len(errors) == 3  # every problem of the file in one pass
    assert all(LOCATED.match(e) for e in errors)
    assert errors[0].startswith(f"{tmp_path}/p.txt:1:7: rung 0: instruction 2: unknown instruction 'FOO'; supported: ")
    assert "XIC takes 1 operand(s), found 2" in errors[1] and ":2:1: rung 1: instruction 1:" in errors[1]
    assert "motion instruction MAM is not modelled yet" in errors[2]
    ascii_errors = _errors(tmp_path, "p.rll", "XIC A OTE\nXIC A FAL X\n", spec)
    assert ":1:7: rung 0: instruction 2: OTE takes 1 operand(s), found 0: the rung ends" in ascii_errors[0]
    assert "Logix instruction FAL is not supported" in ascii_errors[1]


def test_unbalanced_and_deeply_nested_branches(tmp_path: Path, spec) -> None:
    errors = _errors(tmp_path, "p.rll", "XIC A BST XIC B NXB XIC C OTE D\nXIC A BND OTE B\n", spec)
    assert "1:7: rung 0: unbalanced branch" in errors[0]
    assert "2:7: rung 1: a branch ends (BND or ']') that was never started" in errors[1]
    deep = "[" * 5000 + "XIC(A)" + "]" * 5000 + "OTE(B);"
    errors = _errors(tmp_path, "deep.txt", deep, spec)
    assert errors == [f"{tmp_path}/deep.txt:1:33: rung 0: branches nested deeper than 32 levels"]


def test_l5x_undefined_tag_and_st_routine(tmp_path: Path, spec) -> None:
    text = (EXAMPLES / "state_machine.L5X").read_text(encoding="utf-8")
    bad = text.replace("XIC(START_PB)", "XIC(START_BUTTON)").replace(
        "</Routines>", '<Routine Name="Calc" Type="ST"><STContent><Line Number="0"><![CDATA[x := 1;]]></Line></STContent></Routine>\n</Routines>')
    errors = _errors(tmp_path, "p.L5X", bad, spec)
    assert any("routine 'Calc' is a Structured Text (ST) routine; only ladder (RLL) routines can be run" in e for e in errors)
    bad = text.replace("XIC(START_PB)", "XIC(START_BUTTON)")
    errors = _errors(tmp_path, "p.L5X", bad, spec)
    line = next(n for n, ln in enumerate(bad.splitlines(), start=1) if "START_BUTTON" in ln)
    col = bad.splitlines()[line - 1].index("XIC(START_BUTTON)") + 1
    assert errors == [f"{tmp_path}/p.L5X:{line}:{col}: rung 0: instruction 2: undefined tag 'START_BUTTON': it is "
                      f"declared neither in the controller's tags nor in program 'MainProgram'"]


def test_xml_bomb_is_refused(tmp_path: Path, spec) -> None:
    bomb = ('<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n'
            + "".join(f' <!ENTITY lol{i} "{("&lol%s;" % (i - 1 if i > 1 else "")) * 10}">\n' for i in range(1, 10))
            + ']>\n<RSLogix5000Content>&lol9;</RSLogix5000Content>\n')
    errors = _errors(tmp_path, "bomb.L5X", bomb, spec)
    assert len(errors) == 1 and errors[0].startswith(f"{tmp_path}/bomb.L5X:2:1: the L5X file declares a DTD")
    errors = _errors(tmp_path, "broken.L5X", "<RSLogix5000Content><Controller></RSLogix5000Content>", spec)
    assert "not well-formed XML" in errors[0]


def test_ten_megabyte_file_is_refused(tmp_path: Path, spec) -> None:
    errors = _errors(tmp_path, "big.rll", b"XIC A OTE B\n" * 900_000, spec)
    assert errors == [f"{tmp_path}/big.rll:1:1: program is larger than 5000000 bytes (10800000 bytes)"]


def test_not_utf8_and_not_a_regular_file(tmp_path: Path, spec) -> None:
    errors = _errors(tmp_path, "bin.rll", b"XIC A\nOTE \xff\n", spec)
    assert errors[0].startswith(f"{tmp_path}/bin.rll:2:5: program is not UTF-8 text")
    (tmp_path / "dir.rll").mkdir()
    with pytest.raises(ProgramError, match="it is a directory, not a regular file"):
        load_program(tmp_path / "dir.rll", spec=spec)
    fifo = tmp_path / "fifo.rll"
    os.mkfifo(fifo)
    with pytest.raises(ProgramError, match="FIFO"):
        load_program(fifo, spec=spec)


def test_inference_conflicts_are_located(tmp_path: Path, spec) -> None:
    errors = _errors(tmp_path, "p.txt", "XIC(A)MOV(1,A);\nXIC(T.DN)OTE(B);\n", spec)
    assert "tag 'A' is used both as a BOOL" in errors[0]
    assert ":2:1: rung 1: instruction 1: cannot infer the data type of 'T'" in errors[1]


def test_validate_prints_a_summary(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(EXAMPLES / "fault_recovery.L5X")]) == 0
    out = capsys.readouterr().out
    assert "program MainProgram" in out and "axes: X_axis (AXIS_CIP_DRIVE)" in out
    assert "instructions: EQU x1, MAFR x3, MOV x2, MSF x3, NEQ x1, ONS x1, OTE x1, XIC x11" in out


def test_validate_reports_a_bad_program(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "p.rll").write_text("XIC A MAH X Y\n", encoding="utf-8")
    assert main(["validate", str(tmp_path / "p.rll")]) == 1
    err = capsys.readouterr().err
    assert "rung 0: instruction 2: motion instruction MAH is not modelled yet" in err


def test_l5x_alias_tags_and_unmodelled_types(tmp_path: Path, spec) -> None:
    text = (EXAMPLES / "state_machine.L5X").read_text(encoding="utf-8")
    aliased = text.replace("<Tags>\n", '<Tags>\n<Tag Name="Start" TagType="Alias" AliasFor="START_PB"></Tag>\n'
                           '<Tag Name="Ons0" TagType="Alias" AliasFor="Ons[0]"></Tag>\n'
                           '<Tag Name="In1" TagType="Alias" AliasFor="Local:1:I.Data.0"></Tag>\n'
                           '<Tag Name="Recipe" TagType="Base" DataType="UDT_Recipe"></Tag>\n', 1)
    aliased = aliased.replace("XIC(START_PB)", "XIC(Start)").replace("ONS(Ons[0])", "ONS(Ons0)")
    (tmp_path / "a.L5X").write_text(aliased, encoding="utf-8")
    program = load_program(tmp_path / "a.L5X", spec=spec)
    # an alias stands for the tag it names: the routine is the one without aliases
    assert program.routines == load_program(EXAMPLES / "state_machine.L5X", spec=spec).routines
    assert "tag In1, an alias for Local:1:I.Data.0 (module I/O data is not modelled), is not modelled" in program.warnings[0]
    errors = _errors(tmp_path, "b.L5X", aliased.replace("OTL(Fault_Lamp)", "OTL(In1)").replace("MOV(10,State)", "MOV(10,Recipe)"), spec)
    assert any("tag 'In1' is an alias for Local:1:I.Data.0 (module I/O data is not modelled)" in e for e in errors)
    assert any("tag 'Recipe' is a UDT_Recipe; the modelled data types are" in e for e in errors)


def test_validate_json(capsys: pytest.CaptureFixture[str]) -> None:
    import json
    assert main(["validate", "--json", str(EXAMPLES / "state_machine.txt")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["valid"] is True
    summary = doc["programs"][0]
    assert (summary["form"], summary["rungs"], summary["axes"]) == ("neutral", 9, {"Axis1": "AXIS"})
    assert summary["motion_instructions"] == ["MSF", "MSO"] and summary["unsupported"] == []
