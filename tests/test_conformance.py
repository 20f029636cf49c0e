"""The conformance suite: vectors, the protocol, the reference adapter and the runner.

The bundled suite (tests/conformance_helpers.py) is generated once per content and shared
by the test workers; a second, small suite of one servo-axis system is quick enough to
build twice.  The reference adapter runs a sample of the bundled suite that covers every
item the suite covers; ``make deep`` runs all of it, in process and through
``motionchart adapter``, and ``make bench`` prints the mutation score of the whole suite.  Runner robustness is shown against
``tests/adapters/oracle_adapter.py``, an implementation that answers with the vectors'
own expectations and misbehaves on request.
"""

from __future__ import annotations

import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import conformance_helpers
import jsonschema
import pytest

from conformance import runner
from conformance.adapter import ReferenceAdapter
from conformance.schemas import MANIFEST_SCHEMA, MESSAGES, VECTOR_SCHEMA
from conformance.vectors import load_vectors, write_suite
from statecharts.diagnostics import ScenarioError
from statecharts.loader import load_spec
from statecharts.scenario import load_scenario

ROOT = Path(__file__).resolve().parent.parent
ORACLE = Path(__file__).resolve().parent / "adapters" / "oracle_adapter.py"
SCENARIOS = ["noncip/mso_enable.yaml", "noncip/mso_axis_moving.yaml", "noncip/mdo_enable_delay.yaml",
             "noncip/exec_prescan.yaml", "noncip/masr_shutdown.yaml", "noncip/fault_action_shutdown.yaml",
             "cip/cip_power_up_and_enable.yaml", "mrhd/mrhd_servo_preconditions.yaml"]


@pytest.fixture(scope="module")
def spec() -> Any:
    return load_spec()


@pytest.fixture(scope="module")
def suite_dir() -> Path:
    return conformance_helpers.suite_dir()


@pytest.fixture(scope="module")
def vectors(suite_dir: Path) -> list[dict[str, Any]]:
    return load_vectors(suite_dir)


@pytest.fixture(scope="module")
def few_dir(suite_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The vectors the runner's tests drive (six scenarios and one generated vector),
    copied from the bundled suite: each `conform` child then reads seven files, not all."""
    d = tmp_path_factory.mktemp("few") / "vectors"
    d.mkdir()
    for vid in [*SIX, "noncip-error-MSO.11"]:
        (d / f"{vid}.json").write_bytes((suite_dir / f"{vid}.json").read_bytes())
    return d


@pytest.fixture(scope="module")
def small_dir() -> Path:
    return conformance_helpers.small_suite_dir()


@pytest.fixture(scope="module")
def small_vectors(small_dir: Path) -> list[dict[str, Any]]:
    return load_vectors(small_dir)


def representative(vectors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Vectors that together cover every item the whole suite covers (greedy set cover,
    the one with most new items first, ties to the shorter and then the smaller id), plus
    one vector per axis family and instruction set not yet in."""
    items = {id(v): {(k, i) for k, xs in v["covers"].items() for i in xs} for v in vectors}
    left = set().union(*items.values())
    chosen: list[dict[str, Any]] = []
    while left:
        best = max(vectors, key=lambda v: (len(items[id(v)] & left), -len(v["scans"]), [-ord(c) for c in v["id"]]))
        chosen.append(best)
        left -= items[id(best)]
    kinds = {(tuple(v["requires"]["axis_families"]), tuple(v["requires"]["instructions"])) for v in chosen}
    for v in sorted(vectors, key=lambda v: (len(v["scans"]), v["id"])):
        key = (tuple(v["requires"]["axis_families"]), tuple(v["requires"]["instructions"]))
        if key not in kinds:
            kinds.add(key)
            chosen.append(v)
    return sorted(chosen, key=lambda v: v["id"])


# --------------------------------------------------------------------------- the vectors


def test_every_vector_and_the_manifest_match_their_schemas(suite_dir: Path, vectors: list[dict[str, Any]]) -> None:
    """Every vector file loaded (``load_vectors`` checks each against ``vector.schema.json``:
    the test below shows it refusing one that does not match) and the manifest lists them."""
    manifest = json.loads((suite_dir / "manifest.json").read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator(MANIFEST_SCHEMA).validate(manifest)
    files = sorted(p.name for p in suite_dir.glob("*.json") if p.name != "manifest.json")
    assert len(files) > 20 and len(vectors) == len(files) == manifest["count"]
    assert sorted(f"{v['id']}.json" for v in vectors) == files == sorted(m["file"] for m in manifest["vectors"])


def test_a_vector_that_does_not_match_the_schema_is_refused_located(vectors: list[dict[str, Any]], tmp_path: Path) -> None:
    doc = json.loads(json.dumps(vectors[0]))
    jsonschema.Draft202012Validator(VECTOR_SCHEMA).validate(doc)
    del doc["scans"][0]["expect"]
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    with pytest.raises(ScenarioError) as info:
        load_vectors(path)
    text = str(info.value)
    assert "expect" in text and f"{path}:" in text and "Traceback" not in text


def _same_files(a: Path, b: Path) -> None:
    first = {p.name: p.read_bytes() for p in a.iterdir()}
    second = {p.name: p.read_bytes() for p in b.iterdir()}
    assert first.keys() == second.keys()
    assert [n for n in first if first[n] != second[n]] == []


def test_output_is_byte_identical(small_dir: Path, tmp_path: Path) -> None:
    again = tmp_path / "again"
    write_suite(conformance_helpers.build_small(tmp_path), again)
    _same_files(small_dir, again)


@pytest.mark.deep
def test_the_bundled_suite_is_byte_identical(suite_dir: Path, tmp_path: Path) -> None:
    from conformance.vectors import build_suite
    again = tmp_path / "again"
    write_suite(build_suite(load_spec(), scenarios=[ROOT / "scenarios"]), again)
    _same_files(suite_dir, again)


def test_the_add_on_instruction_scenarios_are_left_out_with_the_reason(suite_dir: Path) -> None:
    manifest = json.loads((suite_dir / "manifest.json").read_text(encoding="utf-8"))
    left = {x["file"]: x["reason"] for x in manifest["left_out"]}
    aoi = sorted(p.relative_to(ROOT / "scenarios").as_posix() for p in (ROOT / "scenarios" / "aoi").glob("*.yaml"))
    assert aoi and sorted(f for f in left if f.startswith("aoi/")) == aoi
    assert all("calls an add-on instruction" in left[f] for f in aoi)
    assert not any(v["origin"].startswith("scenarios/aoi/") for v in (json.loads(p.read_text("utf-8"))
                                                                      for p in suite_dir.glob("scenario-*.json")))


def test_a_scenario_vector_carries_the_hand_written_expectations(spec: Any, vectors: list[dict[str, Any]]) -> None:
    """Every expectation of the scenario file is in the vector, at the scan that ends its step."""
    by_origin = {v.get("origin"): v for v in vectors}
    for rel in SCENARIOS:
        scenario = load_scenario(ROOT / "scenarios" / rel, spec)
        v = by_origin[f"scenarios/{rel}"]
        scan = -1
        for step in scenario.steps:
            scan += step.scans
            for obj, fld, value in step.expect:
                got = v["scans"][scan]["expect"][obj][fld]
                assert (got == value and type(got) is type(value)) or (
                    isinstance(value, (int, float)) and not isinstance(value, bool) and abs(got - value) < 1e-9), (rel, scan, obj, fld)


def test_the_mso_enable_vector_says_what_the_manual_says(vectors: list[dict[str, Any]]) -> None:
    """Written from RM002H-p78/79 by hand: MSO on a ready servo axis is done within the
    scan of the coarse update, with servo action and drive enable on, Servo Control
    (AxisState 2); EN stays until the rung goes false."""
    v = next(v for v in vectors if v.get("origin") == "scenarios/noncip/mso_enable.yaml")
    assert v["requires"]["axis_families"] == ["AxisNonCIP"] and "MSO" in v["requires"]["instructions"]
    first = next(s for s in v["scans"] if any(s["inputs"]["rungs"].values()))
    tag = next(t for t, on in first["inputs"]["rungs"].items() if on)
    assert first["expect"][tag]["EN"] is True and first["index"] > 0
    assert v["scans"][0]["expect"][tag]["EN"] is False
    done = next(s for s in v["scans"] if s["expect"][tag]["DN"])
    axis = v["setup"]["axes"][0]["name"]
    assert done["expect"][axis]["state"] == "ServoControl" and done["expect"][axis]["AxisState"] == 2
    assert done["expect"][axis]["ServoActionStatus"] is True and done["expect"][axis]["DriveEnableStatus"] is True


def test_generated_vectors_cover_what_the_checker_reaches(spec: Any, small_vectors: list[dict[str, Any]],
                                                         tmp_path: Path) -> None:
    """Every transition, error code, cell and check the search of the small system reaches
    is covered by a generated vector, and each generated run is a shortest one: no
    vector of that system is longer than the search's depth + 1."""
    from checker import search
    from checker.model import Model
    from checker.properties import load_properties
    from checker.system import load_system
    system = conformance_helpers.small_system(tmp_path)
    model = Model(spec, load_system(system, spec), load_properties(spec))
    result = search.explore(model, progress=False)
    gen = [v for v in small_vectors if v["kind"] == "generated" and v["id"].startswith("small-")]
    covered: dict[str, set[str]] = {k: set() for k in ("transitions", "error_codes", "cells", "checks")}
    for v in gen:
        for k in covered:
            covered[k].update(v["covers"][k])
        assert len(v["scans"]) <= result.depth + 1
    cov = result.coverage
    assert {f"{c}:{t}" for c, t in cov.fired} <= covered["transitions"]
    assert {f"{m}@{s}" for m, s in cov.executed} <= covered["cells"]
    assert {f"{m}.{c}" for m, c in cov.checks} <= covered["checks"]
    cip_only = ("MSO_CIP", "MSF_CIP", "MDS", "MRHD", "MAFR_CIP", "MASD_CIP", "MASR_CIP")
    assert len(cov.errors) == len({e for e in covered["error_codes"] if not e.startswith(cip_only)})


def test_a_generated_error_vector_ends_with_the_documented_code(small_vectors: list[dict[str, Any]]) -> None:
    """MSO on an unconfigured axis: ERR 11 Axis Not Configured (domain-facts §1a)."""
    v = next(v for v in small_vectors if v["id"] == "small-error-MSO.11")
    last = v["scans"][-1]["expect"]
    assert last["Axis_MSO"]["ER"] is True and last["Axis_MSO"]["ERR"] == 11
    assert v["setup"]["axes"][0]["variables"]["Configured"] is False


def test_bad_vector_files_get_located_errors(tmp_path: Path, vectors: list[dict[str, Any]]) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "motionchart-vector/1",\n "id": 3}', encoding="utf-8")
    with pytest.raises(ScenarioError) as exc:
        load_vectors(bad)
    text = str(exc.value)
    assert "bad.json:" in text and "id" in text
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": ', encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"broken.json:1:12: JSON syntax error"):
        load_vectors(broken)
    wrong_tag = dict(vectors[0])
    wrong_tag["scans"] = [dict(vectors[0]["scans"][0], inputs={"rungs": {"nosuchtag": True}})]
    p = tmp_path / "tag.json"
    p.write_text(json.dumps(wrong_tag), encoding="utf-8")
    with pytest.raises(ScenarioError, match="unknown tag 'nosuchtag'"):
        load_vectors(p)


# --------------------------------------------------------------------------- the protocol and the reference adapter


def test_the_reference_adapter_passes_a_representative_sample_in_process(spec: Any, vectors: list[dict[str, Any]]) -> None:
    sample = representative(vectors)
    assert 20 < len(sample) < len(vectors)
    result = runner.run(sample, lambda: runner.InProcessTransport(ReferenceAdapter(spec)))
    assert [v.line() for v in result.verdicts if v.verdict != "pass"] == []
    assert result.ok


@pytest.mark.deep
def test_the_reference_adapter_passes_every_vector_in_process(spec: Any, vectors: list[dict[str, Any]]) -> None:
    result = runner.run(vectors, lambda: runner.InProcessTransport(ReferenceAdapter(spec)))
    assert [v.line() for v in result.verdicts if v.verdict != "pass"] == []
    assert result.ok


def test_the_checker_interpreter_passes_the_sample_too(spec: Any, vectors: list[dict[str, Any]]) -> None:
    """The mutants are served on the checker's interpreter: on the unmutated spec it must
    agree with the engine, or a kill would say nothing (``mutate --score`` checks every
    vector so before it scores)."""
    from conformance import mutation
    mutation.baseline(spec, representative(vectors))


def test_an_event_is_taken_before_the_eventless_transitions_its_actions_enable(spec: Any) -> None:
    """docs/semantics.md: sending an event takes the transitions it enables, then the
    eventless ones.  A power cycle of a running CIP axis drops the DC bus (an action of
    the event) and goes to Initializing; the bus-down fault (eventless, from the power
    structure's states) has no time to act first: the axis never passes through Aborting,
    whose entry would load its stopping time."""
    from checker.compile import FastAxis
    from conformance.session import Session
    setup = {"scan_ms": 10, "coarse_update_ms": 10, "program": [], "axes": [{
        "name": "A", "type": "AXIS_CIP_DRIVE", "family": "AxisCIP", "state": "Running",
        "variables": {"Connected": True, "DCBusUp": True, "PowerStructureEnabled": True, "DriveEnableStatus": True,
                      "ServoActionStatus": True, "TrackingCommand": True}}]}
    for backend in (None, FastAxis):
        s = Session(spec, setup) if backend is None else Session(spec, setup, backend=backend)
        obs = s.scan({"rungs": {}, "events": [{"axis": "A", "event": "power_cycle"}]})["A"]
        assert (obs["state"], obs["Timer"], obs["MajorFault"]) == ("Initializing", 0, False), backend


def test_a_vector_event_that_is_a_request_is_refused(spec: Any) -> None:
    """docs/conformance.md: a scan's events are environment (and drive) events; a request
    such as shutdown comes from an instruction (MASD), so the adapter answers an error."""
    adapter = ReferenceAdapter(spec)
    setup = {"scan_ms": 10, "coarse_update_ms": 10, "program": [],
             "axes": [{"name": "V", "type": "AXIS_VIRTUAL", "family": "AxisVirtual"}]}
    assert adapter.handle({"type": "reset", "vector": "v", "setup": setup})["type"] == "ready"
    answer = adapter.handle({"type": "scan", "index": 0, "inputs": {"events": [{"axis": "V", "event": "shutdown"}]}})
    assert answer["type"] == "error"
    assert "chart AxisVirtual has a request event, not an environment or drive event, 'shutdown'" in answer["message"]
    answer = adapter.handle({"type": "scan", "index": 0, "inputs": {"events": [{"axis": "V", "event": "nonsense"}]}})
    assert "chart AxisVirtual has no event 'nonsense'" in answer["message"]


def test_the_reference_adapter_answers_match_the_message_schemas(spec: Any, vectors: list[dict[str, Any]]) -> None:
    a = ReferenceAdapter(spec)
    hello = a.handle({"type": "hello", "protocol": "motionchart-conformance/1"})
    jsonschema.validate(hello, MESSAGES["hello-reply"])
    v = vectors[0]
    jsonschema.validate({"type": "reset", "vector": v["id"], "setup": v["setup"]}, MESSAGES["reset"])
    jsonschema.validate(a.handle({"type": "reset", "vector": v["id"], "setup": v["setup"]}), MESSAGES["ready"])
    msg = {"type": "scan", "index": 0, "inputs": v["scans"][0]["inputs"]}
    jsonschema.validate(msg, MESSAGES["scan"])
    jsonschema.validate(a.handle(msg), MESSAGES["observations"])
    err = a.handle({"type": "reset", "vector": "x", "setup": {"axes": [{"name": "A", "type": "AXIS_NOPE"}]}})
    jsonschema.validate(err, MESSAGES["error"])
    assert "AXIS_NOPE" in err["message"]
    assert a.handle({"type": "frobnicate"})["type"] == "error"
    assert a.handle({"type": "bye"}) is None


def _conform(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "checker", "conform", *args], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT)


def test_conform_against_motionchart_adapter_passes_and_writes_junit(suite_dir: Path, tmp_path: Path) -> None:
    junit = tmp_path / "junit.xml"
    only = ["scenario-noncip-mso_*", "noncip-error-MSO.*"]
    r = _conform("--adapter", f"{sys.executable} -m checker adapter", "--vectors", str(suite_dir),
                 "--junit", str(junit), "-j", "2", *[x for o in only for x in ("--only", o)])
    assert r.returncode == 0, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    assert lines[-1].startswith("vectors: ") and " 0 failed, 0 errors, 0 timed out" in lines[-1]
    assert all(x.startswith("PASS ") for x in lines[:-1]) and len(lines) > 8
    suite = ET.parse(junit).getroot().find("testsuite")
    assert suite is not None and suite.get("failures") == "0" and suite.get("errors") == "0"
    assert int(suite.get("tests", "0")) == len(lines) - 1


# --------------------------------------------------------------------------- robustness


def _oracle(few_dir: Path, mode: str) -> str:
    return f"{sys.executable} {ORACLE} {few_dir} {mode}"


SIX = ["scenario-noncip-mso_enable", "scenario-noncip-mso_axis_moving", "scenario-noncip-exec_prescan",
       "scenario-noncip-masr_shutdown", "scenario-noncip-fault_action_shutdown", "scenario-noncip-flags_word"]


def _six(few_dir: Path, mode: str, *extra: str,
         only: Sequence[str] = SIX) -> tuple[subprocess.CompletedProcess[str], dict[str, Any]]:
    args = ["--adapter", _oracle(few_dir, mode), "--vectors", str(few_dir), "--json", "--timeout", "2",
            *[x for o in only for x in ("--only", o)], *extra]
    r = _conform(*args, timeout=240)
    doc = json.loads(r.stdout)
    return r, doc


def _verdicts(doc: dict[str, Any]) -> dict[str, str]:
    return {x["id"]: x["verdict"] for x in doc["results"]}


def test_a_well_behaved_implementation_passes(few_dir: Path) -> None:
    r, doc = _six(few_dir, "good")
    assert r.returncode == 0 and set(_verdicts(doc).values()) == {"pass"} and len(doc["results"]) == 6


def test_an_adapter_that_exits_at_the_third_vector_is_restarted(few_dir: Path) -> None:
    r, doc = _six(few_dir, "exit3")
    v = _verdicts(doc)
    assert r.returncode == 1 and len(v) == 6
    # the third vector of each adapter's life ends it; the restarted one does the same
    assert [x["verdict"] for x in doc["results"]] == ["pass", "pass", "error", "pass", "pass", "error"]
    bad = next(x for x in doc["results"] if x["verdict"] == "error")
    assert "exited with status 3" in bad["detail"] and "exiting on purpose" in bad["detail"]
    assert doc["summary"]["error"] == 2 and doc["summary"]["pass"] == 4


def test_an_adapter_that_sleeps_forever_times_out_and_the_rest_runs(few_dir: Path) -> None:
    r, doc = _six(few_dir, "sleep")
    v = _verdicts(doc)
    assert r.returncode == 1 and len(v) == 6
    # the second vector of each adapter's life hangs; each time it is killed and restarted
    assert [x["verdict"] for x in doc["results"]] == ["pass", "timeout"] * 3
    bad = next(x for x in doc["results"] if x["verdict"] == "timeout")
    assert "no answer to scan within 2 s" in bad["detail"] and bad["scan"] == 0


def test_an_adapter_that_prints_garbage_is_an_error(few_dir: Path) -> None:
    r, doc = _six(few_dir, "garbage")
    assert r.returncode == 1 and [x["verdict"] for x in doc["results"]] == ["pass", "error"] * 3
    bad = next(x for x in doc["results"] if x["verdict"] == "error")
    assert "not JSON" in bad["detail"] and "this is not JSON" in bad["detail"]


def test_an_adapter_that_floods_its_output_is_cut_off(few_dir: Path) -> None:
    r, doc = _six(few_dir, "flood", "--max-line", "1000000")
    assert r.returncode == 1 and [x["verdict"] for x in doc["results"]] == ["pass", "error"] * 3
    bad = next(x for x in doc["results"] if x["verdict"] == "error")
    assert "longer than 1,000,000 bytes" in bad["detail"]


def test_a_slow_adapter_within_the_time_outs_passes(few_dir: Path) -> None:
    # one vector: every answer of the adapter comes 0.2 s late, within the 2 s time-out
    r, doc = _six(few_dir, "slow", only=["noncip-error-MSO.11"])
    assert r.returncode == 0 and _verdicts(doc) == {"noncip-error-MSO.11": "pass"}


def test_a_vector_time_out_bounds_a_slow_adapter(few_dir: Path) -> None:
    _r, doc = _six(few_dir, "slow", "--vector-timeout", "1")
    v = _verdicts(doc)
    assert "timeout" in v.values() and len(v) == 6
    assert any("longer than 1 s" in x["detail"] for x in doc["results"] if x["verdict"] == "timeout")


def test_an_adapter_that_never_answers_hello_ends_with_an_error_per_vector(few_dir: Path) -> None:
    r, doc = _six(few_dir, "silent", "--startup-timeout", "1")
    assert r.returncode == 1 and set(_verdicts(doc).values()) == {"error"} and len(doc["results"]) == 6
    assert "did not answer hello" in doc["results"][0]["detail"]


def test_a_wrong_answer_is_a_failure_naming_scan_field_expected_and_actual(few_dir: Path) -> None:
    r, doc = _six(few_dir, "wrong")
    fails = [x for x in doc["results"] if x["verdict"] == "fail"]
    assert r.returncode == 1 and len(fails) >= 5
    assert {x["verdict"] for x in doc["results"]} <= {"fail", "pass"}
    f = fails[0]
    assert f["scan"] == 1 and f["field"] == "DN" and f["expected"] is (not f["actual"])
    assert "scan 1" in f["detail"] and f"{f['object']}.DN expected" in f["detail"]


def test_an_adapter_error_answer_is_an_error_verdict(few_dir: Path) -> None:
    _r, doc = _six(few_dir, "error")
    assert set(_verdicts(doc).values()) == {"error"}
    assert "this set-up is not supported" in doc["results"][0]["detail"]


# --------------------------------------------------------------------------- known failures, skips


def test_known_failures_are_strict(few_dir: Path, tmp_path: Path) -> None:
    known = tmp_path / "known.txt"
    known.write_text("# wrong on purpose\nscenario-noncip-mso_* the adapter inverts DN\n"
                     "scenario-noncip-masr_shutdown also inverted\n", encoding="utf-8")
    _r, plain = _six(few_dir, "wrong")
    base = _verdicts(plain)
    listed = {"scenario-noncip-mso_enable", "scenario-noncip-mso_axis_moving", "scenario-noncip-masr_shutdown"}
    r, doc = _six(few_dir, "wrong", "--known-failures", str(known))
    v = _verdicts(doc)
    want = {i: ({"fail": "xfail", "pass": "xpass"}[base[i]] if i in listed else base[i]) for i in SIX}
    assert v == want and "xfail" in v.values()
    assert r.returncode == (0 if set(v.values()) <= {"pass", "xfail"} else 1)
    r, doc = _six(few_dir, "good", "--known-failures", str(known))
    assert r.returncode == 1 and _verdicts(doc)["scenario-noncip-mso_enable"] == "xpass"
    stale = tmp_path / "stale.txt"
    stale.write_text("no-such-vector because\n", encoding="utf-8")
    r, doc = _six(few_dir, "good", "--known-failures", str(stale))
    assert r.returncode == 1 and "names no vector" in doc["problems"][0]
    broken = tmp_path / "broken.txt"
    broken.write_text("\nscenario-noncip-mso_enable\n", encoding="utf-8")
    r = _conform("--adapter", _oracle(few_dir, "good"), "--vectors", str(few_dir), "--known-failures", str(broken))
    assert r.returncode == 1 and f"{broken}:2:1: expected `VECTOR-ID REASON`" in r.stderr and "Traceback" not in r.stderr


def test_unsupported_families_are_skipped_not_run(spec: Any, vectors: list[dict[str, Any]]) -> None:
    class NonCipOnly(ReferenceAdapter):
        def supports(self) -> dict[str, Any]:
            return {"axis_families": ["AxisNonCIP"], "instructions": ["MSO", "MSF", "MASD", "MASR", "MAFR", "MDO", "MDF"],
                    "observables": {"tag": ["EN", "DN", "ER", "ERR"], "AxisNonCIP": ["state"]}}

    ids = {"scenario-cip-cip_power_up_and_enable", "scenario-mrhd-mrhd_servo_preconditions", "scenario-noncip-mso_enable"}
    result = runner.run([v for v in vectors if v["id"] in ids], lambda: runner.InProcessTransport(NonCipOnly(spec)))
    by = {v.id: v for v in result.verdicts}
    cip = by["scenario-cip-cip_power_up_and_enable"]
    assert cip.verdict == "skipped" and "unsupported: axis family AxisCIP" in cip.detail
    mrhd = by["scenario-mrhd-mrhd_servo_preconditions"]
    assert mrhd.verdict == "skipped" and "instruction MRHD" in mrhd.detail
    assert by["scenario-noncip-mso_enable"].verdict == "pass"
    assert result.ok


def test_conform_usage_errors(few_dir: Path) -> None:
    r = _conform("--adapter", "x", "--vectors", "/no/such/dir")
    assert r.returncode == 2 and "no such file or directory" in r.stderr
    r = _conform("--adapter", _oracle(few_dir, "good"), "--vectors", str(few_dir), "--only", "zzz-none")
    assert r.returncode == 2 and "no vector matches" in r.stderr
    r = _conform("--adapter", "/no/such/program", "--vectors", str(few_dir), "--only", "noncip-error-MSO.11")
    assert r.returncode == 1 and "cannot be started" in r.stdout and "Traceback" not in r.stderr


# --------------------------------------------------------------------------- mutation score (a sample; the full score is make bench)


def test_mutants_are_many_deterministic_and_of_every_kind(spec: Any) -> None:
    from conformance.mutation import mutants
    ms = mutants(spec, charts=["AxisNonCIP", "AxisCIP"])
    assert len(ms) >= 200
    assert len({m.id for m in ms}) == len(ms)
    assert {m.kind for m in ms} == {"drop_guard", "swap_target", "error_code", "exerr", "reorder", "timer", "flip_bit"}
    assert [m.id for m in ms] == [m.id for m in mutants(spec, charts=["AxisNonCIP", "AxisCIP"])]


def test_a_sample_of_mutants_is_killed_by_the_vectors(spec: Any, vectors: list[dict[str, Any]]) -> None:
    """Hand-picked faults the suite must notice: MSO's Axis In Motion code changed, the
    MDO enable delay counted without its guard, the delay one coarse update longer, Servo
    Action Status left off in Servo Control."""
    from conformance import mutation
    ms = {m.id: m for m in mutation.mutants(spec, charts=["AxisNonCIP"], instructions=["MSO", "MDO", "MSF"])}
    picks = ["err MSO.in_motion 22->23", "drop_guard AxisNonCIP:enable_delay"]
    picks += [i for i in ms if i.startswith("timer AxisNonCIP:") and "EnableTimer" in i and i.endswith("+1")][:1]
    picks += [i for i in ms if i.startswith("flip AxisNonCIP:") and "servoactionstatus = true" in i.lower()][:1]
    assert len(picks) == 4, sorted(ms)[:20]
    for mid in picks:
        r = mutation.try_mutant(ms[mid], spec, vectors, mutation.in_process)
        assert r.killed, mid


def test_a_reorder_of_checks_that_never_fail_together_is_equivalent(spec: Any, suite_dir: Path) -> None:
    """MSO's Shutdown and Axis Faulted checks test two different states of the axis: no
    state makes both fail, so their order cannot be seen (the generator's search says so)."""
    from conformance import mutation
    explained = json.loads((suite_dir / "manifest.json").read_text("utf-8"))["coverage"]["orders"]["explained"]
    m = mutation.find(spec, "reorder MSO.shutdown<->faulted")
    why = mutation.order_equivalence(spec, m, explained)
    assert why.startswith("the two checks never fail together") and "'Shutdown' in axis.active" in why
    assert mutation.order_equivalence(spec, mutation.find(spec, "err MSO.in_motion 22->23"), explained) == ""


def test_a_mutant_is_killed_through_the_adapter_child_process_too(spec: Any, vectors: list[dict[str, Any]]) -> None:
    from conformance import mutation
    from conformance.runner import ProcessTransport
    m = mutation.find(spec, "err MSO.in_motion 22->23")
    first = mutation.try_mutant(m, spec, vectors, mutation.in_process)
    assert first.killed
    cmd = f"{sys.executable} -m checker adapter --mutant 'err MSO.in_motion 22->23'"
    again = mutation.try_mutant(m, spec, [v for v in vectors if v["id"] == first.by], lambda _s: ProcessTransport(cmd))
    assert again.killed and again.by == first.by and "ERR expected 22, got 23" in again.detail


def test_every_listed_equivalent_mutant_exists_and_has_a_reason(spec: Any) -> None:
    from conformance import mutation
    eq = mutation.load_equivalents()
    ids = {m.id for m in mutation.mutants(spec)}
    assert [k for k in eq if k not in ids] == []
    assert all(len(reason) > 20 for reason in eq.values())
