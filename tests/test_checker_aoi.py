"""``motionchart check --system aoi``: raM_Opr_SyncPthPhyAx_CD through the checker's one model and search.

What is shown here:

* the bundled system ``aoi`` (spec/systems/aoi.yaml) is explored completely, every property
  of the add-on instruction (spec/properties/aoi.yaml) holds, and every one of the 21 codes
  of 003 §2.4 is produced somewhere in the reachable world (the list of codes is written out
  by hand from the document, not read from spec/);
* seeded mistakes in a copy of the spec are found with a shortest run, and the
  counterexample scenario replays the mistake on the engine with the copy (and is refuted by
  the bundled spec);
* a malformed add-on instruction system gets located diagnostics and exit code 1, never a
  traceback; options that do not apply are refused.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from checker import check_cli
from checker.system import SystemError_, load_system
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.scenario import load_scenario, run_scenario

# 003 §2.4, in the document's order of the code list
DOCUMENTED_CODES = [1000, 1001, 1002, 1005, 1006, 1007, 1008, 1010, 1011, 1012, 1013, 1014, 1015, 1016, 1017,
                    1118, 1020, 1022, 1023, 1025, 1027]
AOI = "raM_Opr_SyncPthPhyAx_CD"


def _check(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = check_cli.main(["check", *args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def bundled_report() -> dict[str, object]:
    """One complete exploration of the bundled system, its report as ``--json`` prints it."""
    from checker.model import Model
    from checker.properties import load_properties
    from checker.report import build_report, text
    from checker.search import explore
    from checker.system import bundled_systems

    spec = load_spec()
    model = Model(spec, load_system(bundled_systems()["aoi"], spec), load_properties(spec))
    report = build_report(explore(model, progress=False))
    out = report.as_dict()
    out["_exit"] = report.exit_code
    out["_text"] = text(report)
    return out


def test_bundled_aoi_system_is_complete_and_every_property_holds(bundled_report: dict[str, object]) -> None:
    assert bundled_report["_exit"] == 0
    assert bundled_report["complete"] is True
    props = {p["name"]: p for p in bundled_report["properties"]}
    mine = {n: p for n, p in props.items() if n.startswith("aoi_")}
    assert len(mine) >= 14
    assert all(p["holds"] is True for p in props.values()), [n for n, p in props.items() if p["holds"] is not True]
    # the goals were reached with a witness run each
    assert props["aoi_recovers_physical_to_path"]["witness"]["scans"] >= 1
    assert bundled_report["states"] > 1000


def test_bundled_aoi_system_produces_every_documented_code(bundled_report: dict[str, object]) -> None:
    errors = bundled_report["coverage"]["error_codes"]
    reached = {int(item.split(":")[1]) for item in errors["reached"] if item.startswith(AOI + ":")}
    assert reached == set(DOCUMENTED_CODES)
    assert not [i for i in errors["unreached"] if i.startswith(AOI + ":")]


def test_text_report_names_the_add_on_tag_and_the_verdict(bundled_report: dict[str, object]) -> None:
    out = str(bundled_report["_text"])
    assert out.startswith("system aoi: ")
    assert f"add-on instruction tags: Sync ({AOI}); at most 2 change(s) per run" in out
    assert "  error_codes: " in out and out.rstrip().endswith("verdict: every property holds")


def _mutated_spec(tmp_path: Path, old: str, new: str) -> Path:
    spec_dir = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), spec_dir, ignore=shutil.ignore_patterns("__pycache__"))
    f = spec_dir / "addons" / f"{AOI}.yaml"
    text = f.read_text(encoding="utf-8")
    assert old in text
    f.write_text(text.replace(old, new, 1), encoding="utf-8")
    return spec_dir


def _violated(out: str) -> dict[str, dict[str, object]]:
    return {p["name"]: p for p in json.loads(out)["properties"] if p["holds"] is False}


def test_a_false_rung_that_keeps_sts_ip_is_found_and_replays(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec_dir = _mutated_spec(tmp_path, "clear: [Sts_EN, Sts_EO, Sts_IP]", "clear: [Sts_EN, Sts_EO]")
    out_dir = tmp_path / "ce"
    # a violation is a violation in an incomplete search too: the first few thousand states hold it
    code, out, err = _check(["--system", "aoi", "--spec", str(spec_dir), "--counterexamples", str(out_dir),
                             "--json", "-q", "--max-states", "3000"], capsys)
    assert code == 1, err
    bad = _violated(out)
    assert set(bad) == {"aoi_in_process_only_while_enabled"}
    ce = bad["aoi_in_process_only_while_enabled"]["counterexample"]
    # shortest: the rung goes true (the move starts: Sts_IP), then false (Sts_IP stays)
    assert ce["steps"] == ["Sync rung up", "Sync rung down"]
    path = Path(ce["scenario"])
    mutated = load_spec([spec_dir])
    assert run_scenario(load_scenario(path, mutated), mutated).passed
    bundled = load_spec()
    refuted = run_scenario(load_scenario(path, bundled), bundled)
    assert any(m.field == "Sts_IP" for m in refuted.mismatches)


def test_an_undocumented_code_is_found(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec_dir = _mutated_spec(tmp_path, "{id: speed, err: 1017,", "{id: speed, err: 1019,")
    # the error list must know the code for the spec to load
    f = spec_dir / "addons" / f"{AOI}.yaml"
    f.write_text(f.read_text(encoding="utf-8").replace(
        "    - {code: 1017, name: Negative speed,", "    - {code: 1019, name: Negative speed,", 1), encoding="utf-8")
    out_dir = tmp_path / "ce"
    code, out, err = _check(["--system", "aoi", "--spec", str(spec_dir), "--json", "-q", "--max-states", "3000",
                             "--counterexamples", str(out_dir)], capsys)
    assert code == 1, err
    bad = _violated(out)
    assert "aoi_documented_codes_only" in bad
    ce = bad["aoi_documented_codes_only"]["counterexample"]
    # by hand: Set_Speed becomes -1 while the rung is false and the rung goes true in the same scan;
    # every check before the speed check passes in the set-up (003 §1.3.2 row order)
    assert ce["steps"] == ["Sync rung up (Set_Speed=-1.0)"]
    # the scenario writes the input as the step's operands: the copy errs with 1019, the bundled spec with 1017
    path = Path(ce["scenario"])
    mutated = load_spec([spec_dir])
    assert run_scenario(load_scenario(path, mutated), mutated).passed
    bundled = load_spec()
    refuted = run_scenario(load_scenario(path, bundled), bundled)
    assert [(m.field, m.expected, m.actual) for m in refuted.mismatches if m.field == "Sts_ERR"] == [
        ("Sts_ERR", 1019, 1017)]


BAD_SYSTEM = """\
format: motionchart-system/1
name: broken
axes:
  - {name: Phy, type: AXIS_CIP_DRIVE, program: []}
  - {name: Pth, type: AXIS_VIRTUAL, chart: AxisVirtual, program: []}
devices:
  - {name: H1, type: raM_UDT_Dvc_xADH_DataHndl, parameters: {phy_axis: Ghost, colour: 3}}
add_ons:
  - tag: Sync
    instruction: raM_Opr_SyncPthPhyAx_CD
    operands: {Ref_AxisPhy: Phy, Ref_AxisPth: Pth, Ref_Handle: H1, Cfg_Nonsense: 1}
    inputs: {Cfg_SyncType: [0, 1.5], Ref_AxisPhy: [Pth]}
"""


def test_malformed_add_on_system_is_located(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    f = tmp_path / "broken.yaml"
    f.write_text(BAD_SYSTEM, encoding="utf-8")
    code, _out, err = _check(["--system", str(f)], capsys)
    assert code == 1
    assert "Traceback" not in err
    lines = err.splitlines()
    assert any(ln.startswith(f"{f}:7:") and "phy_axis" in ln and "Ghost" in ln for ln in lines), err
    assert any(ln.startswith(f"{f}:7:") and "no parameter 'colour'" in ln for ln in lines), err
    assert any(ln.startswith(f"{f}:11:") and "Cfg_Nonsense" in ln for ln in lines), err
    assert any(ln.startswith(f"{f}:12:") and "Cfg_SyncType" in ln and "1.5" in ln for ln in lines), err
    assert any(ln.startswith(f"{f}:12:") and "no input parameter 'Ref_AxisPhy'" in ln for ln in lines), err
    with pytest.raises(SystemError_):
        load_system(f, load_spec())


def test_options_that_do_not_apply_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _check(["--system", "aoi", "--axes", "2"], capsys)
    assert code == 2 and "--axes" in err
    code, _, err = _check(["--system", "noncip", "--max-changes", "2"], capsys)
    assert code == 2 and "--max-changes" in err
    code, _, err = _check(["--system", "aoi", "--engine", "spin"], capsys)
    assert code == 2 and "--engine spin" in err
    from checker.cli import main
    assert main(["export", "--system", "aoi"]) == 2
    assert "add-on instruction tags" in capsys.readouterr().err


def test_no_change_at_all_still_completes_a_recovery(capsys: pytest.CaptureFixture[str]) -> None:
    """With --max-changes 0 only the first configuration of every group is a start and nothing
    changes: the rung, scans and prescans alone.  By hand (SYNC-RM §1.2, §2.2): SyncType 1 on a
    homed, energized axis 2 units behind the path moves it at 10 units/s (one unit a 100 ms
    scan) and gears it, so the recovery completes; every check passes in the set-up, and after a
    prescan (the path no longer verified) the next execution errs with 1016, the one code
    reached.  A SyncType 0 needs an input change and the Virtual mode an event: those goals and
    the coverage of the codes fail."""
    code, out, _err = _check(["--system", "aoi", "-q", "--max-changes", "0", "--json"], capsys)
    assert code == 1
    doc = json.loads(out)
    assert doc["initial_states"] == 1 and doc["complete"]
    props = {p["name"]: p for p in doc["properties"]}
    assert props["aoi_recovers_physical_to_path"]["holds"] is True
    assert {n for n, p in props.items() if p["holds"] is not True} == {
        "aoi_recovers_path_to_physical", "aoi_virtual_mode_completes", "aoi_every_documented_code_reached"}
    errors = doc["coverage"]["error_codes"]["reached"]
    assert [i for i in errors if i.startswith(AOI + ":")] == [f"{AOI}:1016"]
