"""Renderers and the ``diagram`` / ``docs`` / ``generate`` commands.

* Snapshot tests pin the exact DOT and Mermaid text of the axis chart, of the MSO
  flowchart and of the every-construct fixture chart (``tests/snapshots/``).  After an
  intended change, rewrite them with
  ``MOTIONCHART_UPDATE_SNAPSHOTS=1 .venv/bin/pytest tests/test_render.py`` and review
  the diff like code.
* Structure tests check what a reader of the diagrams relies on (clusters for compound
  states, split parallel regions, history and initial pseudo-states, values in titles,
  one decision per check in order, each failure ending in its ERR box) without
  restating the spec: expected values below are typed from the documents
  (``shared/reference/domain-facts.md``) or derived from the rendering rules.
* Determinism: the same spec gives the same bytes, with no absolute paths, twice.
* The commands: unknown chart (exit 1, lists the known ones), unwritable output
  (exit 1), usage errors (exit 2), missing Graphviz program (exit 1, says what to
  install), ``generate --check`` (exit 1 listing stale files and ``make generate``).
"""

from __future__ import annotations

import argparse
import contextlib
import doctest
import io
import itertools
import os
import re
from pathlib import Path

import pytest

import statecharts.api
import statecharts.render
from checker import cli, render_cli
from statecharts import ir
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.render import UnknownTarget, graphviz_bin, resolve
from statecharts.render.dot import chart_dot
from statecharts.render.flowchart import build_flowchart, instruction_dot
from statecharts.render.generate import build, svg_stamp
from statecharts.render.mermaid import chart_mermaid, instruction_mermaid
from statecharts.render.reference import interpretation_uses
from statecharts.render.traceability import trace

ROOT = Path(__file__).resolve().parents[1]
SNAPSHOTS = Path(__file__).parent / "snapshots"
FIXTURE = SNAPSHOTS / "demo_every_construct.yaml"
UPDATE = os.environ.get("MOTIONCHART_UPDATE_SNAPSHOTS") == "1"
HAVE_GRAPHVIZ = graphviz_bin.available()


@pytest.fixture(scope="module")
def demo_spec() -> ir.Spec:
    return load_spec([bundled_spec_dir(), FIXTURE])


def run(argv: list[str]) -> tuple[int, str, str]:
    """``motionchart ARGV`` in-process: exit code, stdout, stderr.

    Uses ``checker.cli.main`` once it dispatches these commands; until then the same
    parser with :func:`render_cli.register` added.
    """
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            parser = cli.build_parser()
            sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
            if "diagram" in sub.choices:
                code = cli.main(argv)
            else:
                render_cli.register(sub)
                args = parser.parse_args(argv)
                result = render_cli.dispatch(args)
                code = cli.main(argv) if result is None else result
        except SystemExit as exc:
            code = int(exc.code or 0)
    return code, out.getvalue(), err.getvalue()


def check_snapshot(name: str, text: str) -> None:
    path = SNAPSHOTS / name
    if UPDATE or not path.exists():
        if not UPDATE:
            pytest.fail(f"no snapshot {path.name}; create it with MOTIONCHART_UPDATE_SNAPSHOTS=1")
        path.write_text(text, encoding="utf-8")
        return
    expected = path.read_text(encoding="utf-8")
    assert text == expected, (
        f"{name} changed; if intended, rewrite the snapshots with "
        "MOTIONCHART_UPDATE_SNAPSHOTS=1 .venv/bin/pytest tests/test_render.py and review the diff")


# --------------------------------------------------------------------------- snapshots


def test_snapshot_axis_chart_dot(spec: ir.Spec) -> None:
    check_snapshot("AxisNonCIP.dot", chart_dot(spec.chart("AxisNonCIP")))


def test_snapshot_axis_chart_mermaid(spec: ir.Spec) -> None:
    check_snapshot("AxisNonCIP.mmd", chart_mermaid(spec.chart("AxisNonCIP")))


def test_snapshot_mso_flowchart_dot(spec: ir.Spec) -> None:
    check_snapshot("MSO.flowchart.dot", instruction_dot(spec, spec.instruction("MSO")))


def test_snapshot_mso_flowchart_mermaid(spec: ir.Spec) -> None:
    check_snapshot("MSO.flowchart.mmd", instruction_mermaid(spec, spec.instruction("MSO")))


def test_snapshot_fixture_chart(demo_spec: ir.Spec) -> None:
    chart = demo_spec.chart("DemoEveryConstruct")
    check_snapshot("DemoEveryConstruct.dot", chart_dot(chart))
    check_snapshot("DemoEveryConstruct.mmd", chart_mermaid(chart))


# --------------------------------------------------------------------------- state diagrams


def test_axis_dot_titles_carry_documented_state_values(spec: ir.Spec) -> None:
    dot = chart_dot(spec.chart("AxisNonCIP"))
    # the non-CIP axis states and their values, typed from domain-facts §3a
    for title in ("Axis Ready (0)", "Direct Drive Control (1)", "Servo Control (2)", "Axis Faulted (3)",
                  "Shutdown (4)"):
        assert title in dot
    assert "subgraph cluster_Operating" in dot  # the compound state is a cluster
    assert "compound=true" in dot and "lhead=cluster_Operating" in dot


def test_dot_has_no_addresses_and_no_stray_anchor(spec: ir.Spec) -> None:
    dot = chart_dot(spec.chart("AxisNonCIP"))
    assert not re.search(r"0x[0-9a-f]{6,}|\d{9,}", dot)
    declared = set(re.findall(r"^\s*(\w+) \[", dot, re.M)) - {"graph", "node", "edge"}
    used = set()
    for a, b in re.findall(r"^\s*(\w+) -> (\w+)", dot, re.M):
        used |= {a, b}
    assert used <= declared, f"edges to undeclared nodes: {sorted(used - declared)}"


def test_dot_shows_guards_and_actions_on_edges(spec: ir.Spec) -> None:
    chart = spec.chart("AxisNonCIP")
    dot = chart_dot(chart, labels="full")
    for t in chart.transitions:
        if t.target is not None and t.guard is not None:
            assert t.guard.text.split()[0] in dot
        if t.target is None:  # targetless transitions are listed inside their state
            assert f"/ {t.actions[0].target} =" in dot


def test_label_levels(spec: ir.Spec) -> None:
    chart = spec.chart("AxisNonCIP")
    full, guards, events = (chart_dot(chart, labels=level) for level in ("full", "guards", "events"))
    acts = [a.text for t in chart.transitions if t.target is not None for a in t.actions]
    guarded = [t for t in chart.transitions if t.target is not None and t.guard is not None and t.event]
    assert any(a.split(" = ")[0] + " =" in full for a in acts)
    # guards: event [guard] on the edges, no actions
    assert all(t.guard is not None and t.guard.text.split()[0] in guards for t in guarded)
    assert "/ TestStatus = " not in guards and "/ TestStatus = " in full
    # events: the events alone (the guards of evented transitions are gone)
    assert all(t.event in events for t in guarded)
    assert len(events) < len(guards) < len(full)
    with pytest.raises(ValueError, match="label level"):
        chart_dot(chart, labels="everything")


def test_large_chart_overview_and_parts(spec: ir.Spec) -> None:
    from statecharts.render.views import is_split, leaf_composites, view_names

    cip = spec.chart("AxisCIP")
    assert is_split(cip) and not is_split(spec.chart("AxisNonCIP"))
    parts = {s.id for s in leaf_composites(cip)}
    # the CIP chart's four composites of simple states
    assert parts == {"Connecting", "SelfTest", "Standby", "PowerActive"}
    assert view_names(cip) == ("whole", "overview", "Connecting", "SelfTest", "Standby", "PowerActive")
    ov = chart_dot(cip, part="overview")
    # collapsed: a box per composite, its states listed in it, not drawn as nodes
    for box in parts:
        assert re.search(rf"^\s*{box} \[", ov, re.M)
    assert not re.search(r"^\s*Running \[", ov, re.M) and "Starting, Running, Testing" in ov
    part = chart_dot(cip, part="PowerActive")
    assert "subgraph cluster_PowerActive" in part and re.search(r"^\s*Running \[", part, re.M)
    # the states outside the part are grey stubs, the other composites collapsed
    assert re.search(r"^\s*Standby \[.*dashed", part, re.M) and not re.search(r"^\s*Stopped \[", part, re.M)
    with pytest.raises(KeyError):
        chart_dot(cip, part="Nowhere")


def test_long_flowchart_is_split_in_parts(spec: ir.Spec) -> None:
    from statecharts.render.flowchart import PART_CHECKS, flowchart_part_names

    mds = spec.instruction("MDS")
    names = flowchart_part_names(spec, mds)
    assert len(mds.checks) + len(mds.aborts) > PART_CHECKS and names[0] == "whole" and len(names) >= 3
    seen = []
    for name in names[1:]:
        dot = instruction_dot(spec, mds, part=name)
        seen += [c.id for c in mds.checks if f"check_{c.id} [" in dot]
    assert seen == [c.id for c in mds.checks]  # every check once, in order
    assert "Continued in part 2" in instruction_dot(spec, mds, part="part1")
    assert flowchart_part_names(spec, spec.instruction("MAFR")) == ("whole",)


def test_fixture_dot_draws_every_construct(demo_spec: ir.Spec) -> None:
    dot = chart_dot(demo_spec.chart("DemoEveryConstruct"))
    assert "subgraph cluster_Running" in dot
    # each region of the parallel state is its own dashed cluster inside it
    for region in ("Motor", "Lamp"):
        block = dot[dot.index(f"subgraph cluster_{region}"):]
        assert "rounded,dashed" in block.split("\n", 2)[1]
    assert re.search(r'MotorHist \[label=H\b', dot) and re.search(r'LampHist \[label="H\*"', dot)
    assert "doublecircle" in dot and "Done (9)" in dot
    assert dot.count("__initial [") == 3  # Motor, Lamp and Lit have initial pseudo-states


def test_fixture_mermaid_splits_regions(demo_spec: ir.Spec) -> None:
    mmd = chart_mermaid(demo_spec.chart("DemoEveryConstruct"))
    assert mmd.splitlines()[3] == "stateDiagram-v2"
    assert re.search(r"^\s+--$", mmd, re.M)
    assert 'state "H*" as LampHist' in mmd
    assert "#62;" in mmd or "#60;" in mmd  # comparison signs escaped
    assert "<" not in mmd.replace("<br/>", "")


def test_renderers_are_generic_over_the_ir(demo_spec: ir.Spec) -> None:
    for chart in demo_spec.charts:
        assert chart_dot(chart) == chart_dot(chart)
        assert chart_mermaid(chart).startswith("---\ntitle: ")
    for ins in demo_spec.instructions:
        assert instruction_dot(demo_spec, ins) == instruction_dot(demo_spec, ins)


# --------------------------------------------------------------------------- flowcharts


def test_flowchart_checks_in_documented_order_each_to_its_err_box(spec: ir.Spec) -> None:
    ins = spec.instruction("MSO")
    fc = build_flowchart(spec, ins)
    decisions = [n.id for n in fc.nodes if n.id.startswith("check_")]
    assert decisions == [f"check_{c.id}" for c in ins.checks]
    chain = [e for e in fc.edges if e.source.startswith("check_") and e.target.startswith("check_")]
    assert [(e.source, e.target) for e in chain] == list(itertools.pairwise(decisions))
    assert all(e.label == "no" for e in chain)
    boxes = {n.id: n for n in fc.nodes}
    for c in ins.checks:
        (fail,) = [e for e in fc.edges if e.source == f"check_{c.id}" and e.label == "yes"]
        box = boxes[fail.target]
        assert box.kind == "error"
        assert f"ERR = {c.err}" in box.title[1]
        assert (f"EXERR = {c.exerr}" in box.title[1]) == bool(c.exerr)
    # MSO on a shut-down axis: ERR 12 with EXERR 12, Object Mode conflict (domain-facts §4 MSO)
    assert "ERR = 12, EXERR = 12" in instruction_dot(spec, ins)
    assert "OBJECT_MODE_CONFLICT" in instruction_dot(spec, ins)


def test_flowchart_dot_reads_top_to_bottom(spec: ir.Spec) -> None:
    dot = instruction_dot(spec, spec.instruction("MDO"))
    assert "rankdir=TB" in dot
    positions = [dot.index(f"\tcheck_{c.id} [") for c in spec.instruction("MDO").checks]
    assert positions == sorted(positions)
    assert dot.count("rank=same") == len(spec.instruction("MDO").checks) + len(spec.instruction("MDO").aborts) + 3


# --------------------------------------------------------------------------- Graphviz program


def test_missing_graphviz_is_a_clear_error(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.setattr(graphviz_bin, "_candidate_dirs", lambda: [str(tmp_path)])
    with pytest.raises(graphviz_bin.GraphvizNotFoundError) as info:
        graphviz_bin.find_program()
    assert "dot" in str(info.value) and "graphviz-pure" in str(info.value)
    code, _out, err = run(["diagram", "AxisNonCIP", "--format", "svg", "-o", str(tmp_path / "a.svg")])
    assert code == 1 and "neither `dot`" in err and "Traceback" not in err
    assert not (tmp_path / "a.svg").exists()


def test_graphviz_pure_is_found_in_the_venv_bin(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    fake = tmp_path / "graphviz-pure"
    fake.write_text("#!/bin/sh\nexit 0\n")
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", str(tmp_path / "nothing"))
    monkeypatch.setattr(graphviz_bin, "_candidate_dirs", lambda: [str(tmp_path)])
    assert graphviz_bin.find_program() == str(fake)


@pytest.mark.skipif(not HAVE_GRAPHVIZ, reason="no dot / graphviz-pure installed")
def test_svg_and_png_render(tmp_path: Path) -> None:
    code, _o, err = run(["diagram", "AxisNonCIP", "-o", str(tmp_path / "axis.svg")])
    assert code == 0, err
    assert (tmp_path / "axis.svg").read_text().lstrip().startswith("<?xml")
    code, _o, err = run(["diagram", "MSO", "--format", "png", "-o", str(tmp_path / "mso.png")])
    assert code == 0, err
    assert (tmp_path / "mso.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --------------------------------------------------------------------------- the diagram command


def test_diagram_to_stdout_is_the_dot_text(spec: ir.Spec) -> None:
    code, out, err = run(["diagram", "AxisNonCIP"])
    assert (code, err) == (0, "")
    assert out == chart_dot(spec.chart("AxisNonCIP"))
    code, out, _ = run(["diagram", "mso", "--format", "mermaid"])  # mnemonic, any case
    assert code == 0 and out == instruction_mermaid(spec, spec.instruction("MSO"))


def test_diagram_unknown_chart_lists_known_ones() -> None:
    code, out, err = run(["diagram", "NoSuchChart"])
    assert code == 2 and out == ""  # a usage error, like an unknown system in check
    assert "unknown chart 'NoSuchChart'" in err and "AxisNonCIP" in err and "MSO" in err
    assert "Traceback" not in err


def test_diagram_unwritable_output_is_a_clear_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    code, _out, err = run(["diagram", "AxisNonCIP", "-o", str(blocker / "axis.dot")])
    assert code == 1 and "cannot write" in err and "Traceback" not in err
    code, _out, err = run(["diagram", "AxisNonCIP", "-o", str(tmp_path)])
    assert code == 1 and "is a directory" in err


def test_diagram_usage_errors_exit_2() -> None:
    assert run(["diagram", "AxisNonCIP", "--format", "png"])[0] == 2  # PNG needs -o
    assert run(["diagram", "AxisNonCIP", "--format", "gif"])[0] == 2
    assert run(["diagram"])[0] == 2


def test_diagram_format_follows_the_file_suffix(tmp_path: Path, spec: ir.Spec) -> None:
    code, _o, err = run(["diagram", "AxisNonCIP", "-o", str(tmp_path / "axis.mmd")])
    assert code == 0, err
    assert (tmp_path / "axis.mmd").read_text() == chart_mermaid(spec.chart("AxisNonCIP"))


def test_resolve_refuses_unknown_names(spec: ir.Spec) -> None:
    assert resolve(spec, "msf").id == "MSF"
    with pytest.raises(UnknownTarget):
        resolve(spec, "Axis")


# --------------------------------------------------------------------------- docs and generate


def _no_absolute_paths(root: Path) -> None:
    for p in root.rglob("*"):
        if p.is_file() and p.suffix in (".md", ".dot", ".mmd", ".scxml"):
            text = p.read_text(encoding="utf-8")
            # relative links may climb through them; an absolute path starts after a delimiter
            for absolute in (str(ROOT), str(root), str(Path.home())):
                assert not re.search(rf"(^|[\s(`'\"=]){re.escape(absolute)}", text), (p, absolute)


def _links_resolve(root: Path) -> None:
    for md in root.rglob("*.md"):
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", md.read_text(encoding="utf-8")):
            if "://" in target:
                continue
            assert (md.parent / target).exists(), f"{md.relative_to(root)} links to missing {target}"


def test_generate_twice_is_byte_identical_and_check_passes(tmp_path: Path) -> None:
    out = tmp_path / "generated"
    code, msg, err = run(["generate", "-o", str(out), "--scenarios", str(ROOT / "scenarios")])
    assert code == 0, err
    first = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert {"index.md", "interpretations.md", "error-codes.md", "traceability.md", "README.md"} <= {
        str(p) for p in first}
    assert Path("scxml/AxisNonCIP.scxml") in first and Path("diagrams/AxisNonCIP.mmd") in first
    assert Path("flowcharts/MSO.dot") in first and Path("instructions/MSO.md") in first
    code, msg, err = run(["generate", "-o", str(out), "--scenarios", str(ROOT / "scenarios")])
    assert code == 0 and "0 written" in msg
    second = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert first == second
    _no_absolute_paths(out)
    _links_resolve(out)
    code, msg, err = run(["generate", "-o", str(out), "--check", "--scenarios", str(ROOT / "scenarios")])
    assert code == 0 and "up to date" in msg, err


def test_generate_check_lists_stale_files_and_the_fix(tmp_path: Path) -> None:
    out = tmp_path / "generated"
    assert run(["generate", "-o", str(out), "--scenarios", str(tmp_path / "none")])[0] == 2  # missing dir
    empty = tmp_path / "scenarios"
    empty.mkdir()
    scen = ["--scenarios", str(empty)]  # the traceability matrix is not under test here
    code, _m, err = run(["generate", "-o", str(out), *scen])
    assert code == 0, err
    (out / "charts" / "AxisNonCIP.md").write_text("edited by hand\n")
    (out / "diagrams" / "Removed.dot").write_text("digraph {}\n")
    (out / "index.md").unlink()
    code, _m, err = run(["generate", "-o", str(out), "--check", *scen])
    assert code == 1
    for rel in ("charts/AxisNonCIP.md", "diagrams/Removed.dot", "index.md"):
        assert rel in err
    assert "make generate" in err
    code, msg, _ = run(["generate", "-o", str(out), *scen])
    assert code == 0 and "1 removed" in msg
    assert run(["generate", "-o", str(out), "--check", *scen])[0] == 0


def test_generate_into_a_file_is_an_error(tmp_path: Path) -> None:
    f = tmp_path / "plain"
    f.write_text("x")
    code, _o, err = run(["generate", "-o", str(f)])
    assert code == 1 and "not a directory" in err
    code, _o, err = run(["docs", "-o", str(f / "sub"), "--scenarios", str(tmp_path)])
    assert code == 1 and "Traceback" not in err


def test_docs_writes_the_reference(tmp_path: Path) -> None:
    code, _msg, err = run(["docs", "-o", str(tmp_path / "ref"), "--scenarios", str(ROOT / "scenarios")])
    assert code == 0, err
    ref = tmp_path / "ref"
    mso = (ref / "instructions" / "MSO.md").read_text()
    assert "## Checks, in the order they are evaluated" in mso and "## Error codes" in mso
    assert "## Execution table" in mso and "../flowcharts/MSO.svg" in mso and "```mermaid" in mso
    axis = (ref / "charts" / "AxisNonCIP.md").read_text()
    assert "| 2 |" in axis and "Servo Control" in axis  # state value 2 (domain-facts §3a)
    assert not (ref / "scxml").exists()
    _links_resolve(ref)


def test_svgs_are_reused_while_their_dot_is_unchanged(spec: ir.Spec, tmp_path: Path) -> None:
    calls: list[str] = []

    def fake(src: str) -> bytes:
        calls.append(src)
        return b'<?xml version="1.0"?>\n<svg/>\n'

    files = build(spec, [], tmp_path, render_svg=fake).files
    n = len(calls)
    # one SVG per DOT: every chart and instruction, and the views and parts of the large ones
    assert n == sum(1 for rel in files if rel.endswith(".dot") and "/" in rel) > len(spec.charts) + len(spec.instructions)
    for rel, data in files.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes(data)
    again = build(spec, [], tmp_path, render_svg=fake).files
    assert len(calls) == n and again == files
    assert svg_stamp(chart_dot(spec.chart("AxisNonCIP"))).encode() in files["diagrams/AxisNonCIP.svg"]


# --------------------------------------------------------------------------- traceability


_SHUTDOWN_MSO = """format: motionchart-scenario/1
name: MSO on a shut-down axis
sources: ["RM002H p79 (MSO EXERR)"]
covers: []
setup:
  axes:
    Axis1: {type: AXIS_SERVO, state: Shutdown}
  program:
    - {tag: mso1, instruction: MSO, axis: Axis1}
steps:
  - rungs: {mso1: true}
    expect: {mso1: {ER: true, ERR: 12, EXERR: 12}}
"""


def test_traceability_comes_from_running_the_scenarios(spec: ir.Spec, tmp_path: Path) -> None:
    root = tmp_path / "scenarios"
    root.mkdir()
    (root / "shutdown_mso.yaml").write_text(_SHUTDOWN_MSO)
    (root / "broken.yaml").write_text("format: motionchart-scenario/1\nname: broken\n")
    tr = trace(spec, [root])
    (r,) = tr.runs
    assert r.path == "scenarios/shutdown_mso.yaml" and r.covers == ()
    # MSO on an axis in Shutdown: ER with ERR 12, EXERR 12 (RM002H p79)
    assert ("MSO", 12, 12) in r.errors
    assert ("AxisNonCIP", "Shutdown") in r.states
    assert [p.path for p in tr.problems] == ["scenarios/broken.yaml"]
    assert tr.producing("MSO", 12, 12) == [r] and tr.reaching("AxisNonCIP", "ServoControl") == []


def test_a_traced_scenario_is_run_again_once_its_file_changes(spec: ir.Spec, tmp_path: Path) -> None:
    root = tmp_path / "scenarios"
    root.mkdir()
    f = root / "shutdown_mso.yaml"
    f.write_text(_SHUTDOWN_MSO)
    (first,) = trace(spec, [root]).runs
    assert trace(spec, [root]).runs == (first,) and first.passed
    # a wrong expectation (ERR 13 where RM002H p79 gives 12): the edited file is run again
    f.write_text(_SHUTDOWN_MSO.replace("ERR: 12,", "ERR: 13,"))
    (again,) = trace(spec, [root]).runs
    assert not again.passed and ("MSO", 12, 12) in again.errors


def test_every_interpretation_page_entry_names_its_users(spec: ir.Spec) -> None:
    uses = interpretation_uses(spec)
    cited = {p.interpretation for c in spec.charts for p in
             [c.provenance, *(s.provenance for s in c.states), *(t.provenance for t in c.transitions)]
             if p.interpretation}
    assert cited <= set(uses)
    for interp in spec.interpretations:
        for u in uses.get(interp.id, []):
            assert u.interpretation == interp.id and u.link


# --------------------------------------------------------------------------- documented API


@pytest.mark.parametrize("module", [statecharts.api, statecharts.render])
def test_module_examples_run(module: object) -> None:
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_chart_class_names_known_charts() -> None:
    with pytest.raises(KeyError, match="AxisNonCIP"):
        statecharts.api.chart_class("Nope")


def test_committed_generated_artefacts_are_fresh() -> None:
    """generated/ in the checkout is what the spec and scenarios give now (fix: make generate)."""
    code, msg, err = run(["generate", "-o", str(ROOT / "generated"), "--check", "--scenarios", str(ROOT / "scenarios")])
    assert code == 0, f"generated/ is stale; run `make generate` and commit the result\n{msg}{err}"
