"""``motionchart check``: exit codes, ``--json`` shape, counterexample files, GraphML, limits, bad input.

The command is exercised through :func:`checker.check_cli.main` (the stand-alone entry
that builds the same sub-parser the ``motionchart`` CLI registers).  The bundled system
is checked once per session (a few seconds); the rest use small systems.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from checker import check_cli
from statecharts import ir
from statecharts.loader import load_spec
from statecharts.scenario import load_scenario, run_scenario

SMALL_SYSTEM = """\
format: motionchart-system/1
name: tiny
scan_ms: 10
coarse_update_ms: 10
axes:
  - name: Axis
    type: AXIS_SERVO
    program: [MSO, MASD, MASR]
environment: [servo_fault, fault_cleared]
prescan: false
max_live_calls: 1
abstraction:
  collapse: [ServoOutput, DriveOutputCommand]
"""

# a property the chart breaks on purpose: MSO is not always refused in Shutdown... in
# Axis Faulted it is refused with 20, so "MSO never errs" is false, reached in 2 scans
FALSE_PROPERTY = """\
format: motionchart-properties/1
properties:
  - name: mso_never_errs
    kind: invariant
    scope: tag
    instruction: MSO
    holds: "not ER"
    source: "MC tests/test_checker_cli.py (deliberately false)"
"""


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = check_cli.main(["check", *args])
    out, err = capsys.readouterr()
    return code, out, err


def _check_json(args: list[str]) -> dict[str, object]:
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = check_cli.main(["check", "--json", *args])
    data: dict[str, object] = json.loads(buf.getvalue())
    data["_exit"] = code
    return data


@pytest.fixture(scope="module")
def bundled_json() -> dict[str, object]:
    return _check_json([])


def test_bundled_system_every_property_holds(bundled_json: dict[str, object]) -> None:
    d = bundled_json
    assert d["_exit"] == 0 and d["complete"] is True and d["verdict"] == "holds"
    for key in ("states", "transitions", "seconds", "states_per_second", "depth", "peak_memory_mb"):
        assert key in d
    props = d["properties"]
    assert isinstance(props, list) and props
    for p in props:
        assert {"name", "holds", "counterexample"} <= set(p)
        assert p["holds"] is True, p


def test_bundled_coverage_is_reported_and_unreached_codes_are_explained(bundled_json: dict[str, object]) -> None:
    cov = bundled_json["coverage"]
    assert isinstance(cov, dict)
    codes = cov["error_codes"]
    # written by hand from the documents: MSO 12/12 Object Mode conflict (RM002H-p79),
    # MDO 13/2 Drive Output out of range (002, INT-011), MDO 12/1 (000, INT-013)
    for item in ("MSO:12/12", "MDO:13/2", "MDO:12/1", "MSO:22"):
        assert item in codes["reached"]
    assert set(codes["unreached"]) <= set(codes["explained"])
    assert {"MSO:12/15", "MSO:12/16"} <= set(codes["unreached"])  # SERCOS-only catalog entries
    for what in ("states", "transitions"):
        assert cov[what]["total"] >= cov[what]["reached"] > 0


def _graph_round_trip(data: dict[str, object], graphml: Path) -> None:
    import networkx as nx

    g = data["graph"]
    assert isinstance(g, dict)
    assert g["nodes"] == data["states"] and g["dead_ends"] == 0
    loaded = nx.read_graphml(graphml)
    assert loaded.number_of_nodes() == data["states"]


def test_graph_analyses_and_graphml(tmp_path: Path) -> None:
    system = tmp_path / "tiny.yaml"
    system.write_text(SMALL_SYSTEM, encoding="utf-8")
    graphml = tmp_path / "tiny.graphml"
    data = _check_json(["--system", str(system), "--graphml", str(graphml)])
    assert data["complete"] is True  # (its coverage property fails: a tiny program)
    _graph_round_trip(data, graphml)


@pytest.mark.deep
def test_bundled_graph_analyses(tmp_path: Path) -> None:
    """The bundled system's state graph (about 80,000 states, a 32 MB GraphML file) has no
    dead end and reads back whole."""
    graphml = tmp_path / "noncip.graphml"
    _graph_round_trip(_check_json(["--graphml", str(graphml)]), graphml)


def test_violation_exits_1_with_a_replayable_counterexample(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    system = tmp_path / "tiny.yaml"
    system.write_text(SMALL_SYSTEM, encoding="utf-8")
    props = tmp_path / "props.yaml"
    props.write_text(FALSE_PROPERTY, encoding="utf-8")
    code, out, _ = _run(["--system", str(system), "--properties", str(props), "--json",
                         "--counterexamples", str(tmp_path / "cex")], capsys)
    assert code == 1
    d = json.loads(out)
    (p,) = d["properties"]
    assert p["holds"] is False and p["counterexample"]["scans"] == 2
    path = Path(p["counterexample"]["scenario"])
    spec = load_spec()
    assert run_scenario(load_scenario(path, spec), spec).passed
    code, out, _ = _run(["--system", str(system), "--properties", str(props)], capsys)
    assert code == 1 and "VIOLATED mso_never_errs" in out and "counterexample for mso_never_errs" in out


def test_state_limit_gives_incomplete(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(["--max-states", "50", "--json"], capsys)
    d = json.loads(out)
    assert code == 3 and d["complete"] is False and "state limit" in d["stop_reason"]
    assert any(p["holds"] is None for p in d["properties"])


def test_time_limit_gives_incomplete(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(["--system", "noncip_pairs", "--max-seconds", "0.3", "-q"], capsys)
    assert code == 3 and "INCOMPLETE" in out


def test_axes_scales_the_system(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    system = tmp_path / "tiny.yaml"
    system.write_text(SMALL_SYSTEM, encoding="utf-8")
    code1, out1, _ = _run(["--system", str(system), "--json"], capsys)
    code2, out2, _ = _run(["--system", str(system), "--axes", "2", "--json"], capsys)
    one, two = json.loads(out1), json.loads(out2)
    assert code2 == code1 and two["axes"] == 2 and two["symmetric_axis_groups"] == [["Axis1", "Axis2"]]
    n = one["states"]
    # interchangeable axes: unordered pairs of one-axis states (times the shared clock phase, here 1)
    assert two["states"] <= n * (n + 1) // 2
    _code3, out3, _ = _run(["--system", str(system), "--axes", "2", "--no-symmetry", "--json"], capsys)
    assert json.loads(out3)["states"] > two["states"]


def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _run(["--system", "no_such_system"], capsys)
    assert code == 2 and "unknown system" in err
    assert _run(["--axes", "0"], capsys)[0] == 2
    assert _run(["--max-seconds", "soon"], capsys)[0] == 2


def test_bad_property_file_is_located(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(FALSE_PROPERTY.replace('"not ER"', '"not ER and __import__"'), encoding="utf-8")
    code, _, err = _run(["--properties", str(bad)], capsys)
    assert code == 1 and f"{bad}:" in err and "holds" in err
    bad.write_text(FALSE_PROPERTY.replace('"not ER"', '"not ERROR"'), encoding="utf-8")
    code, _, err = _run(["--properties", str(bad)], capsys)
    assert code == 1 and "unknown name 'ERROR'" in err and ":7:" in err


def test_bad_system_file_is_located(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(SMALL_SYSTEM.replace("[MSO, MASD, MASR]", "[MSO, MXYZ]"), encoding="utf-8")
    code, _, err = _run(["--system", str(bad)], capsys)
    assert code == 1 and "unknown instruction 'MXYZ'" in err and f"{bad}:" in err


def test_a_system_chooses_the_chart_of_a_type_several_charts_model(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    from checker.system import load_system
    virtual = SMALL_SYSTEM.replace("type: AXIS_SERVO\n    program: [MSO, MASD, MASR]",
                                   "type: AXIS_VIRTUAL\n    chart: AxisVirtual\n    program: [MAM_VIRTUAL]")
    virtual = virtual.replace("[servo_fault, fault_cleared]", "[axis_fault]").replace(
        "[ServoOutput, DriveOutputCommand]", "[ActualPosition]")
    good = tmp_path / "virtual.yaml"
    good.write_text(virtual, encoding="utf-8")
    sysdef = load_system(good, load_spec())
    assert [(g.axis_type, g.chart) for g in sysdef.groups] == [("AXIS_VIRTUAL", "AxisVirtual")]
    # without `chart:` the type keeps its first chart, on which MAM_VIRTUAL is not defined
    plain = tmp_path / "plain.yaml"
    plain.write_text(virtual.replace("    chart: AxisVirtual\n", ""), encoding="utf-8")
    code, _, err = _run(["--system", str(plain)], capsys)
    assert code == 1 and "MAM_VIRTUAL is not defined for chart AxisNonCIP" in err
    # a chart that does not model the type is an error at the `chart:` line
    bad = tmp_path / "bad.yaml"
    bad.write_text(virtual.replace("chart: AxisVirtual", "chart: AxisCIP"), encoding="utf-8")
    code, _, err = _run(["--system", str(bad)], capsys)
    assert code == 1 and f"{bad}:8:" in err and "chart 'AxisCIP' does not model axis type 'AXIS_VIRTUAL'" in err
    assert "expected one of: AxisNonCIP, AxisVirtual" in err


def test_list_systems(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(["--list-systems"], capsys)
    assert code == 0 and "noncip" in out and "noncip_pairs" in out


GEARED_SYSTEM = """\
format: motionchart-system/1
name: geared
axes:
  - name: Slave
    type: AXIS_VIRTUAL
    chart: AxisVirtual
    state: ServoControl
    program: [MAG_VIRTUAL]
    masters: {MAG_VIRTUAL: Master}
  - name: Master
    type: AXIS_VIRTUAL
    chart: AxisVirtual
    state: ServoControl
    program: [MAH_VIRTUAL]
environment: [home_complete]
prescan: false
max_live_calls: 1
abstraction:
  collapse: [ActualPosition, CommandVelocity, GearRatio, HomePosition]
"""

#: a mistake in the master binding of GEARED_SYSTEM -> (old text, new text, the line's
#: marker, what the message says)
BAD_BINDINGS = {
    "unknown-axis": ("{MAG_VIRTUAL: Master}", "{MAG_VIRTUAL: Zmaster}", "Zmaster", "unknown axis 'Zmaster'"),
    "own-group": ("{MAG_VIRTUAL: Master}", "{MAG_VIRTUAL: Slave}", "masters:",
                  "the master axis of MAG_VIRTUAL is an axis of its own group 'Slave'"),
    "missing": ("    masters: {MAG_VIRTUAL: Master}\n", "", "program: [MAG_VIRTUAL]",
                "MAG_VIRTUAL needs its MasterAxis operand bound to another axis of the system"),
    "not-in-program": ("program: [MAG_VIRTUAL]", "program: [MAH_VIRTUAL]", "masters:",
                       "MAG_VIRTUAL is not in the program of axis group 'Slave'"),
    "no-master-operand": ("program: [MAG_VIRTUAL]\n    masters: {MAG_VIRTUAL: Master}",
                          "program: [MAG_VIRTUAL, MAH_VIRTUAL]\n    masters: {MAG_VIRTUAL: Master, MAH_VIRTUAL: Master}",
                          "MAH_VIRTUAL: Master", "MAH_VIRTUAL has no master-axis operand"),
}


@pytest.mark.parametrize("case", sorted(BAD_BINDINGS))
def test_a_bad_master_binding_is_located(tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str) -> None:
    old, new, marker, message = BAD_BINDINGS[case]
    assert old in GEARED_SYSTEM
    text = GEARED_SYSTEM.replace(old, new)
    bad = tmp_path / "bad.yaml"
    bad.write_text(text, encoding="utf-8")
    line = next(i for i, t in enumerate(text.splitlines(), 1) if marker in t)
    code, _, err = _run(["--system", str(bad)], capsys)
    assert code == 1 and f"{bad}:{line}:" in err and message in err, err
    assert "Traceback" not in err


def test_a_slave_errs_while_its_master_homes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """MAG on the slave while the master axis homes: Home In Process (ERR 16; IMD, MAG
    ERR 16 while the master homes); the check reads the bound master, not the slave."""
    from checker.model import Model
    from checker.search import explore

    good = tmp_path / "geared.yaml"
    good.write_text(GEARED_SYSTEM, encoding="utf-8")
    spec = load_spec()
    from checker.system import load_system
    sysdef = load_system(good, spec)
    assert sysdef.masters() == {"Slave_MAG_VIRTUAL": "Master"}
    result = explore(Model(spec, sysdef), progress=False)
    assert result.complete
    assert ("MAG_VIRTUAL", 16, 0) in result.coverage.errors
    assert ("MAG_VIRTUAL", "master_homing") in result.coverage.checks
    # the slave itself never homes here (it has no MAH): its own homing check never fails
    assert ("MAG_VIRTUAL", "homing") not in result.coverage.checks
    code, out, _ = _run(["--system", str(good)], capsys)
    assert code == 0, out


@pytest.mark.parametrize("name", ["noncip", "motion"])
def test_a_change_bound_offers_no_event_once_spent(spec: ir.Spec, name: str) -> None:
    """``max_changes: 0`` on a bundled system: no environment event is ever offered (alone or
    with a drive event; the drive model's own events are no changes), and only the first
    configuration of each group is a start (a configuration other than the first is a
    change made before the first scan)."""
    import dataclasses

    from checker.model import Model
    from checker.search import explore
    from checker.system import bundled_systems, load_system

    sysdef = dataclasses.replace(load_system(bundled_systems()[name], spec), max_changes=0)
    model = Model(spec, sysdef, ())
    assert model.assignments == [tuple(0 for _ in model.axes)]
    result = explore(model, progress=False, max_states=2000)
    taken = [model.choices[result.via[i]] for i in range(result.states) if result.parent[i] >= 0]
    environment = {e.name for c in model.charts.values() for e in c.events if e.kind == "environment"}
    assert not [c.label() for c in taken for e in c.inputs.events if e.event in environment]
    assert {"raise", "drop"} <= {c.kind for c in taken}
