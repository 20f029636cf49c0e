"""``motionchart check --system aoi``: exhaustive exploration of raM_Opr_SyncPthPhyAx_CD.

What is shown here:

* the bundled AOI system is explored completely, every invariant holds, and every one of
  the 21 codes of 003 §2.4 is produced somewhere in the reachable world (the list of
  codes is written out by hand from the document, not read from spec/);
* seeded mistakes in a copy of the AOI spec are found, with a shortest run, and the
  counterexample file replays the mistake with ``run_aoi_scenario`` (and is refuted by
  the bundled spec);
* a malformed AOI system gets located diagnostics and exit code 1, never a traceback.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from checker import check_cli
from statecharts.aoi import load_aoi, load_aoi_scenario, run_aoi_scenario
from statecharts.loader import bundled_spec_dir, read_yaml

# 003 §2.4, in the document's order of the code list
DOCUMENTED_CODES = [1000, 1001, 1002, 1005, 1006, 1007, 1008, 1010, 1011, 1012, 1013, 1014, 1015, 1016, 1017,
                    1118, 1020, 1022, 1023, 1025, 1027]


def _check(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = check_cli.main(["check", *args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def bundled_report() -> dict[str, object]:
    import argparse
    import io

    from checker import aoi_check

    args = argparse.Namespace(spec=None, quiet=True, json=True, max_states=None, max_seconds=None,
                              counterexamples=None, max_changes=None)
    out = io.StringIO()
    code = aoi_check.run(aoi_check.bundled_aoi_systems()["aoi"], args, out)
    report = json.loads(out.getvalue())
    report["_exit"] = code
    return report


def test_bundled_aoi_system_is_complete_and_every_property_holds(bundled_report: dict[str, object]) -> None:
    assert bundled_report["_exit"] == 0
    assert bundled_report["complete"] is True and bundled_report["error"] is None
    props = bundled_report["properties"]
    assert isinstance(props, list) and len(props) >= 8
    assert all(p["holds"] is True for p in props), [p["name"] for p in props if p["holds"] is not True]
    assert bundled_report["states"] > 1000


def test_bundled_aoi_system_produces_every_documented_code(bundled_report: dict[str, object]) -> None:
    cov = bundled_report["coverage"]
    assert isinstance(cov, dict)
    reached = {int(c) for c in cov["error_codes"]["reached"]}
    assert reached == set(DOCUMENTED_CODES)
    assert cov["goals"]["unreached"] == []
    # recovery states not seen at the end of a scan are each explained
    rs = cov["recovery_states"]
    assert {"moving", "done"} <= set(rs["reached"])
    assert set(rs["unreached"]) == set(rs["explained"])


def _mutated_spec(tmp_path: Path, old: str, new: str) -> Path:
    spec_dir = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), spec_dir, ignore=shutil.ignore_patterns("__pycache__"))
    f = spec_dir / "addons" / "raM_Opr_SyncPthPhyAx_CD.yaml"
    text = f.read_text(encoding="utf-8")
    assert old in text
    f.write_text(text.replace(old, new, 1), encoding="utf-8")
    return spec_dir


def test_a_false_rung_that_keeps_sts_ip_is_found_and_replays(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec_dir = _mutated_spec(tmp_path, "clear: [Sts_EN, Sts_EO, Sts_IP]", "clear: [Sts_EN, Sts_EO]")
    out_dir = tmp_path / "ce"
    code, out, err = _check(["--system", "aoi", "--spec", str(spec_dir), "--counterexamples", str(out_dir),
                             "--json", "-q"], capsys)
    assert code == 1, err
    report = json.loads(out)
    bad = {p["name"]: p for p in report["properties"] if p["holds"] is False}
    assert set(bad) == {"in_process_only_while_enabled"}
    ce = bad["in_process_only_while_enabled"]["counterexample"]
    # shortest: the rung goes true (the move starts, Sts_IP), then false (Sts_IP stays)
    assert ce["moves"] == ["rung true", "rung false"]
    path = Path(ce["scenario"])
    tree = read_yaml(path, [])
    mutated = load_aoi(spec_dir)
    replay = run_aoi_scenario(load_aoi_scenario(path, tree, mutated), mutated)
    assert replay.mismatches == ()
    bundled = load_aoi()
    refuted = run_aoi_scenario(load_aoi_scenario(path, tree, bundled), bundled)
    assert any(m.field == "Sts_IP" for m in refuted.mismatches)


def test_an_undocumented_code_is_found(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec_dir = _mutated_spec(tmp_path, "{id: speed, err: 1017,", "{id: speed, err: 1019,")
    # the error list must know the code for the spec to load
    f = spec_dir / "addons" / "raM_Opr_SyncPthPhyAx_CD.yaml"
    f.write_text(f.read_text(encoding="utf-8").replace(
        "    - {code: 1017, name: Negative speed,", "    - {code: 1019, name: Negative speed,", 1), encoding="utf-8")
    code, out, err = _check(["--system", "aoi", "--spec", str(spec_dir), "--json", "-q"], capsys)
    assert code == 1, err
    bad = [p for p in json.loads(out)["properties"] if p["holds"] is False]
    assert [p["name"] for p in bad] == ["documented_codes_only"]
    # Set_Speed becomes -1 (one input change while the rung is false), then the rung goes true
    assert bad[0]["counterexample"]["moves"] == ["Sync.Set_Speed = -1.0", "rung true"]


def test_text_report_names_counts_and_verdict(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = _check(["--system", "aoi", "-q", "--max-changes", "1"], capsys)
    assert code == 0, err
    assert out.startswith("system aoi (add-on instruction Sync)")
    assert "error_codes: " in out and out.rstrip().endswith("verdict: every property holds")


BAD_SYSTEM = """\
format: motionchart-aoi-system/1
name: broken
source: "MC tests/test_checker_aoi.py"
instance: Sync
setup:
  handlers:
    H1: {id: 1, eState: 7, mode: physical, phy_axis: Phy, pth_axis: Pth}
  axes:
    Phy: {type: AXIS_CIP_DRIVE}
    Pth: {type: AXIS_VIRTUAL}
  aoi:
    Sync: {Ref_AxisPhy: Phy, Ref_AxisPth: Pth, Ref_Handle: H1}
inputs:
  Cfg_Nonsense: [1]
environment:
  Ghost: {eState: [7]}
properties:
  - {id: p, always: "Sync.Sts_ERR >= Sync.NoSuchField", source: "MC tests/test_checker_aoi.py"}
"""


def test_malformed_aoi_system_is_located(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    f = tmp_path / "broken.yaml"
    f.write_text(BAD_SYSTEM, encoding="utf-8")
    code, _out, err = _check(["--system", str(f)], capsys)
    assert code == 1
    assert "Traceback" not in err
    lines = err.splitlines()
    assert any(ln.startswith(f"{f}:14:") and "inputs.Cfg_Nonsense" in ln and "has no input" in ln for ln in lines)
    assert any(ln.startswith(f"{f}:16:") and "unknown handler or axis 'Ghost'" in ln for ln in lines)
    assert any(ln.startswith(f"{f}:18:") and "Sync.NoSuchField" in ln for ln in lines)


def test_options_that_do_not_apply_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _check(["--system", "aoi", "--axes", "2"], capsys)
    assert code == 2 and "--axes" in err
    code, _, err = _check(["--system", "noncip", "--max-changes", "2"], capsys)
    assert code == 2 and "--max-changes" in err
