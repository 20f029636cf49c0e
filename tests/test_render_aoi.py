"""The add-on instruction's generated artefacts: reference page, flowchart, recovery chart.

They come from the common renderers, fed with the IR (``spec.add_ons``).  Expected values
are typed in from the documents, not read from the spec: the order of the 17 ordered
checks is the one of 003 §1.3.2 as docs/aoi.md resolves it (1017 placed after 1016 and
the last rows 1025, 1002, 1118: INT-022, INT-026), the 21 codes are those of 003 §2.4,
the axis data types of the references those of 003 §2.2 (so MAH, MAM and MAG run on the
CIP drive axis and MRP on the virtual path axis), and the preconditions of the calls are
the ``.ERR`` codes of docs/aoi.md ("The recovery chart").  The tests check that the spec
agrees with them and that the artefacts show them: in the page's tables, one flowchart
decision per check in that order, each failing to a box with its code, a recovery chart
with every state and transition, DOT that is the same on every run and that Graphviz
accepts, and the artefacts written by ``generate`` / ``docs`` and drawn by ``diagram``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import re
from pathlib import Path

import pytest

from checker import cli
from statecharts import ir
from statecharts.loader import load_spec
from statecharts.render import graphviz_bin, instruction_dot, instruction_mermaid
from statecharts.render.addon import recovery_chart
from statecharts.render.dot import chart_dot
from statecharts.render.flowchart import build_flowchart, split_flowchart
from statecharts.render.generate import build
from statecharts.render.mermaid import chart_mermaid
from statecharts.render.reference import add_on_page
from statecharts.render.traceability import trace

ROOT = Path(__file__).resolve().parents[1]
AOI_ID = "raM_Opr_SyncPthPhyAx_CD"
HAVE_GRAPHVIZ = graphviz_bin.available()

#: 003 §1.3.2, top to bottom, as docs/aoi.md orders it (INT-026 places 1017 after 1016 and
#: gives the last rows 1025, 1002, 1118; INT-022 reads the energized row's code as 1118).
CHECK_ORDER = [1000, 1001, 1005, 1006, 1007, 1008, 1010, 1011, 1012, 1013, 1014, 1015, 1016, 1017, 1025, 1002, 1118]
#: The checks that only apply to a physical-to-path recovery (docs/aoi.md: "SyncType 1").
SYNC1_ONLY = {1012, 1013, 1014, 1015, 1016, 1017}
#: 003 §2.4: every code the instruction reports (the ordered checks' and the four call errors).
ALL_CODES = sorted([*CHECK_ORDER, 1020, 1022, 1023, 1027])
#: docs/aoi.md "The recovery chart": the instruction each calling state issues and its code.
CALL_CODES = {"MAH": 1020, "MAM": 1022, "MAG": 1023, "MRP": 1027}
#: 003 §2.2: Ref_AxisPhy is an AXIS_CIP_DRIVE, Ref_AxisPth an AXIS_VIRTUAL; the recovery homes,
#: moves and gears the physical axis and redefines the path axis (003 §1.1, §1.2).
CALLED_VARIANTS = {"MAH": "MAH_CIP", "MAM": "MAM_CIP", "MAG": "MAG_CIP", "MRP": "MRP_VIRTUAL"}
#: docs/aoi.md: the preconditions of each call, as .ERR codes; the variant called checks them (in its own order).
CALL_ERRS = {"MAH": [87, 41], "MAM": [87, 17, 13], "MAG": [87, 16], "MRP": [16, 13]}


@pytest.fixture(scope="module")
def spec() -> ir.Spec:
    return load_spec()


@pytest.fixture(scope="module")
def aoi(spec: ir.Spec) -> ir.AddOnInstruction:
    return spec.add_on(AOI_ID)


@pytest.fixture(scope="module")
def page(spec: ir.Spec, aoi: ir.AddOnInstruction) -> str:
    return add_on_page(spec, aoi, trace(spec, []))


def section(page: str, title: str) -> str:
    """The text of ``## title`` (or ``### title``) up to the next heading of the same or a higher level."""
    m = re.search(rf"^(#+) {re.escape(title)}\n", page, re.M)
    assert m, title
    level = len(m.group(1))
    rest = page[m.end():]
    end = re.search(rf"^#{{1,{level}}} ", rest, re.M)
    return rest[: end.start()] if end else rest


def table_rows(text: str) -> list[dict[str, str]]:
    """The first Markdown table of ``text`` as header -> cell."""
    rows = [[c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]] for line in text.splitlines()
            if line.startswith("| ")]
    header, *body = rows
    assert all(len(r) == len(header) for r in body)
    return [dict(zip(header, r)) for r in body]


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main(argv)
    return code, out.getvalue(), err.getvalue()


# --------------------------------------------------------------------------- the spec agrees with the documents


def test_spec_check_order_is_the_documented_order(aoi: ir.AddOnInstruction) -> None:
    assert [c.err for c in aoi.checks] == CHECK_ORDER
    # a check restricted to SyncType 1 says so first: "Cfg_SyncType == 1 and (...)"
    assert {c.err for c in aoi.checks if c.fails_when.text.startswith("Cfg_SyncType == 1 and (")} == SYNC1_ONLY
    assert all("Cfg_SyncType" not in c.fails_when.text for c in aoi.checks if c.err not in SYNC1_ONLY)
    assert sorted(e.code for e in aoi.errors) == ALL_CODES


# --------------------------------------------------------------------------- reference page


def test_check_table_lists_the_codes_in_the_documented_order(page: str) -> None:
    rows = table_rows(section(page, "Checks, in the order they are evaluated"))
    assert [r["#"] for r in rows] == [str(n) for n in range(1, len(CHECK_ORDER) + 1)]
    assert [int(r["Sts_ERR"]) for r in rows] == CHECK_ORDER
    by_code = {int(r["Sts_ERR"]): r for r in rows}
    for code, r in by_code.items():
        assert r["Fails when"].startswith("`Cfg_SyncType == 1 and (") == (code in SYNC1_ONLY), r
        assert r["Source"].startswith("SYNC-RM") and r["Error"] not in ("", "—")
        assert f"{AOI_ID}.yaml:" in r["Defined at"]
    # the interpretations the documents' gaps needed
    assert "INT-022" in by_code[1118]["Interpretation / confidence"]
    assert "INT-026" in by_code[1017]["Interpretation / confidence"]
    assert "INT-026" in by_code[1002]["Interpretation / confidence"]


def test_codes_table_lists_every_documented_code_with_its_source(page: str) -> None:
    rows = table_rows(section(page, "Error codes"))
    listed = [int(r["Sts_ERR"].rsplit(">", 1)[-1]) for r in rows]
    assert listed == ALL_CODES
    by_code = dict(zip(listed, rows))
    for code, r in by_code.items():
        assert r["Source"] == f"SYNC-RM §2.4 {code}" or r["Source"].startswith(f"SYNC-RM §2.4 {code},"), r
        assert r["Name"] not in ("", "—") and r["Modelled"] == "yes", r
    for code in CHECK_ORDER:
        assert by_code[code]["How the model produces it"].startswith("check ["), code
    for mnemonic, code in CALL_CODES.items():  # the four call errors come from the calling state
        assert f"when its {mnemonic} call errs" in by_code[code]["How the model produces it"]


def test_page_lists_parameters_status_and_local_tags(page: str) -> None:
    params = {r["Parameter"].split("`")[1]: r for r in table_rows(section(page, "Parameters"))}
    # 003 §2.2, in Logix order: the three references and six configuration inputs
    assert list(params) == ["Ref_AxisPhy", "Ref_AxisPth", "Ref_Handle", "Cfg_SyncType", "Cfg_AllowHome",
                            "Cfg_TravelLIM", "Cfg_RotaryShortestTOL", "Cfg_MoveType", "Set_Speed"]
    assert params["Ref_AxisPhy"]["Data type"] == "AXIS_CIP_DRIVE" and params["Set_Speed"]["Type"] == "REAL"
    assert params["Ref_AxisPth"]["Usage"] == "InOut" and params["Cfg_AllowHome"]["Default"] == "false"
    status = [r["Member"].strip("`") for r in table_rows(section(page, "Status tag"))]
    assert {"Sts_ER", "Sts_ERR", "Sts_EXERR", "Sts_IP", "Sts_PC"} <= set(status)
    assert [r["Variable"] for r in table_rows(section(page, "Local tags"))] == ["`path_verified`"]
    routines = {r["Routine"]: r for r in table_rows(section(page, "Rung false and prescan"))}
    assert "MAS" in routines["rung false"]["Also"] and "path_verified" in routines["prescan"]["Also"]


def test_page_shows_completion_and_the_objects_it_reads_with_their_sources(page: str) -> None:
    # SYNC-RM §1.2 note: a path-to-physical sync (SyncType 0) verifies the path's integrity
    # (what 1016 checks); §1.3.1: Sts.OnPath of the handler is set on completion
    done = {r["Sets"].strip("`"): r for r in table_rows(section(page, "Completion"))}
    assert list(done) == ["path_verified", "handler.OnPath"]
    assert "Cfg_SyncType == 0" in done["path_verified"]["When"] and done["handler.OnPath"]["When"] == "always"
    assert done["path_verified"]["Source"].startswith("SYNC-RM §1.2") and "§1.3.1" in done["handler.OnPath"]["Source"]
    # 003 §2.2: the physical axis is an AXIS_CIP_DRIVE, the path axis an AXIS_VIRTUAL, and the handle
    world = section(page, "The world it runs in")
    split = world.index("| Object | Fact |")
    objects = {r["Object"].strip("`"): r for r in table_rows(world[:split])}
    assert list(objects) == ["AXIS_CIP_DRIVE", "AXIS_VIRTUAL", "handler"]
    assert objects["AXIS_CIP_DRIVE"]["Chart"] == "[AxisCIP](../charts/AxisCIP.md)"
    assert all(r["Source"].startswith("SYNC-RM §") for r in objects.values())
    facts = table_rows(world[split:])
    assert {"faulted", "shutdown", "energized"} <= {r["Fact"].strip("`") for r in facts if r["Object"] == "`AXIS_VIRTUAL`"}
    assert all(r["Source"] not in ("", "—") for r in facts)


def test_links_into_the_page_name_its_anchors(tmp_path: Path, spec: ir.Spec) -> None:
    """Every ``instructions/<AOI>.md#fragment`` link of the reference (the users of each
    interpretation) lands on an anchor or a heading of the page."""
    fake = lambda src: b'<?xml version="1.0"?>\n<svg/>\n'  # noqa: E731  # no Graphviz needed here
    files = build(spec, [], tmp_path, render_svg=fake).files
    page = files[f"instructions/{AOI_ID}.md"].decode()
    anchors = set(re.findall(r'<a id="([^"]+)"></a>', page)) | {
        re.sub(r"[^a-z0-9 _-]", "", h.lower()).replace(" ", "-") for h in re.findall(r"^#+ (.+)$", page, re.M)}
    links = {m for text in files.values() if text.lstrip().startswith(b"<!--")
             for m in re.findall(rf"instructions/{AOI_ID}\.md#([^)\s]+)\)", text.decode())}
    assert {"transition-t1", "state-virtual_done", "check-energized", "the-world-it-runs-in"} <= links
    assert links <= anchors, links - anchors


def test_calls_link_to_the_variant_for_the_axis_data_type(spec: ir.Spec, page: str) -> None:
    rows = table_rows(section(page, "Motion instructions it calls"))
    got = {r["Call"].strip("`").split("(")[0].split("_")[0]: r for r in rows}
    assert set(got) == set(CALLED_VARIANTS)
    for mnemonic, variant in CALLED_VARIANTS.items():
        r = got[mnemonic]
        assert r["Instruction page"] == f"[{variant}]({variant}.md)"
        assert r[f"{AOI_ID} code if it errs"].startswith(f"[{CALL_CODES[mnemonic]}]")
        # the preconditions docs/aoi.md gives the call are checks of the variant called
        assert set(CALL_ERRS[mnemonic]) <= {c.err for c in spec.instruction(variant).checks}, variant
        assert (ROOT / "generated" / "instructions" / f"{variant}.md").is_file()


def test_page_is_deterministic_and_has_no_absolute_path(spec: ir.Spec, page: str) -> None:
    again = load_spec()
    assert add_on_page(again, again.add_on(AOI_ID), trace(again, [])) == page
    assert str(ROOT) not in page and str(Path.home()) not in page


# --------------------------------------------------------------------------- flowchart


def test_flowchart_has_one_decision_per_check_in_order(spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    fc = build_flowchart(spec, aoi)
    nodes = {n.id: n for n in fc.nodes}
    checks = [n for n in fc.nodes if n.id.startswith("check_")]
    assert all(n.kind == "decision" for n in checks) and len(checks) == len(CHECK_ORDER)
    for n, (node, code) in enumerate(zip(checks, CHECK_ORDER), start=1):
        assert node.title[0].startswith(f"{n}. ")
        (yes,) = [e for e in fc.edges if e.source == node.id and e.label == "yes"]
        assert nodes[yes.target].kind == "error" and f"Sts_ERR = {code}" in nodes[yes.target].title
        assert " ".join(node.detail).startswith("Cfg_SyncType == 1 and (") == (code in SYNC1_ONLY)
    # the "no" branches chain the checks top to bottom, then to the recovery
    chain = [e.target for e in fc.edges if e.label == "no" and e.source.startswith("check_")]
    assert chain == [n.id for n in checks[1:]] + ["recovery"]
    dot = instruction_dot(spec, aoi)
    positions = [dot.index(f"\t{n.id} [") for n in checks]
    assert positions == sorted(positions)
    # drawn in parts that each fit a page, every check in exactly one part
    parts = split_flowchart(fc)
    assert len(parts) >= 2
    assert sorted(n.id for _name, part in parts for n in part.nodes if n.id.startswith("check_")) == sorted(
        n.id for n in checks)


def test_flowchart_ends_where_the_recovery_chart_takes_over(spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    fc = build_flowchart(spec, aoi)
    (last,) = [e for e in fc.edges if e.target == "recovery"]
    assert last.source == f"check_{aoi.checks[-1].id}" and last.label == "no"
    assert [n.kind for n in fc.nodes if n.id == "recovery"] == ["done"]
    assert f"{AOI_ID}_recovery" in " ".join(fc.note)
    assert "flowchart TD" in instruction_mermaid(spec, aoi)


def test_flowchart_and_page_name_the_status_tag_the_instruction_has(spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    """The error boxes, the code columns and the recovery's actions name the members of the
    instruction's own status tag: renamed there, renamed everywhere."""
    def out(name: str) -> str:
        return name.replace("Sts_", "Out_", 1)

    other = dataclasses.replace(
        aoi, status=tuple(dataclasses.replace(m, name=out(m.name)) for m in aoi.status),
        rung_false=dataclasses.replace(aoi.rung_false, clear=tuple(map(out, aoi.rung_false.clear))),
        prescan=dataclasses.replace(aoi.prescan, clear=tuple(map(out, aoi.prescan.clear))))
    boxes = [n for n in build_flowchart(spec, other).nodes if n.kind == "error"]
    assert boxes[0].title[:2] == ("Out_ER set", f"Out_ERR = {CHECK_ORDER[0]}")
    assert not any("Sts_" in line for n in boxes for line in n.title)
    page = add_on_page(spec, other, trace(spec, []))
    assert "Out_ERR" in table_rows(section(page, "Checks, in the order they are evaluated"))[0]
    mmd = chart_mermaid(recovery_chart(spec, other, ordered=True))
    assert f"Out_ERR = {CALL_CODES['MAH']}" in mmd and "Out_EXERR = MAH.ERR" in mmd and "Sts_" not in mmd


# --------------------------------------------------------------------------- recovery chart


def test_recovery_chart_shows_every_state_transition_and_error_exit(spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    chart = recovery_chart(spec, aoi, ordered=True)
    dot, mmd = chart_dot(chart, labels="full"), chart_mermaid(chart)
    spec_states = [s.id for s in aoi.recovery.states]
    for sid in spec_states:
        assert f"\t{sid} [" in dot or f"cluster_{sid}" in dot
        assert f'as {sid}' in mmd
    for t in aoi.recovery.transitions:
        assert re.search(rf"\t{t.source} -> {t.target} \[|\t{t.target} -> {t.source} \[", dot), (t.source, t.target)
        assert f"{t.source} --> {t.target}" in mmd
    # a false rung leaves the whole execution; every calling state errs with its code
    assert "rung_false" in dot and "executing --> idle : rung_false" in mmd
    for mnemonic, code in CALL_CODES.items():
        assert f"Sts_ERR = {code}" in mmd and f"Sts_EXERR = {mnemonic}.ERR" in mmd
    # the calls are in the state boxes, with the variant for the axis
    for variant in CALLED_VARIANTS.values():
        assert f"entry / {variant}(" in dot
    # 003 §1.3.2: out of `checking`, Virtual mode first, then SyncType 0 (redefine), SyncType 1 (home if
    # needed, then move), in this try order
    branches = re.findall(r"checking --> (\w+) : \[(\d): ", mmd)
    assert branches == [("virtual_done", "1"), ("redefine", "2"), ("homing", "3"), ("moving", "4")]


def test_dot_is_deterministic(spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    other = load_spec()
    b = other.add_on(AOI_ID)
    assert instruction_dot(spec, aoi) == instruction_dot(other, b)
    assert chart_dot(recovery_chart(spec, aoi), labels="full") == chart_dot(recovery_chart(other, b), labels="full")
    for text in (instruction_dot(spec, aoi), chart_dot(recovery_chart(spec, aoi))):
        assert not re.search(r"0x[0-9a-f]{6,}", text) and str(ROOT) not in text


@pytest.mark.skipif(not HAVE_GRAPHVIZ, reason="no Graphviz program (dot / graphviz-pure) here")
def test_dot_parses_with_graphviz(spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    for text in (instruction_dot(spec, aoi), chart_dot(recovery_chart(spec, aoi, ordered=True), labels="full")):
        assert b"<svg" in graphviz_bin.render(text, "svg")


# --------------------------------------------------------------------------- generate, docs and diagram


def test_build_writes_the_aoi_artefacts(tmp_path: Path, spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    fake = lambda src: b'<?xml version="1.0"?>\n<svg/>\n'  # noqa: E731  # no Graphviz needed here
    files = build(spec, [], tmp_path, render_svg=fake).files
    for name in (f"instructions/{AOI_ID}.md", f"flowcharts/{AOI_ID}.dot", f"flowcharts/{AOI_ID}.mmd",
                 f"flowcharts/{AOI_ID}.svg", f"flowcharts/{AOI_ID}.part1.dot", f"diagrams/{AOI_ID}_recovery.dot",
                 f"diagrams/{AOI_ID}_recovery.mmd", f"diagrams/{AOI_ID}_recovery.svg"):
        assert name in files, name
    assert files[f"flowcharts/{AOI_ID}.dot"].decode() == instruction_dot(spec, aoi)
    index = files["index.md"].decode()
    assert f"[{AOI_ID}](instructions/{AOI_ID}.md)" in index and f"[recovery chart](diagrams/{AOI_ID}_recovery.svg)" in index
    interps = files["interpretations.md"].decode()
    assert f"](instructions/{AOI_ID}.md#check-energized)" in interps  # INT-022's user
    assert f"](instructions/{AOI_ID}.md#the-world-it-runs-in)" in interps  # INT-068's users
    codes = section(files["error-codes.md"].decode(), "Codes of add-on instructions")  # 003 §2.4: all 21
    assert re.findall(rf"\[(\d+)\]\(instructions/{AOI_ID}\.md#code-\1\)", codes) == [str(c) for c in ALL_CODES]
    assert not any(name.startswith("aoi/") for name in files)


def test_traceability_matrix_lists_the_add_on_states_codes_and_completion(tmp_path: Path, spec: ir.Spec) -> None:
    fake = lambda src: b'<?xml version="1.0"?>\n<svg/>\n'  # noqa: E731  # no Graphviz needed here
    matrix = build(spec, [], tmp_path, render_svg=fake).files["traceability.md"].decode()
    page = f"instructions/{AOI_ID}.md"
    codes = [r for r in table_rows(section(matrix, "Error codes")) if r["Instruction"] == f"[{AOI_ID}]({page})"]
    assert [int(r["ERR / EXERR"].split("]")[0][1:]) for r in codes] == ALL_CODES  # 003 §2.4
    for r in codes:
        assert r["ERR / EXERR"].endswith(f"({page}#code-{r['ERR / EXERR'].split(']')[0][1:]})")
    by_code = {int(r["ERR / EXERR"].split("]")[0][1:]): r["Spec elements (checks)"] for r in codes}
    for mnemonic, code in CALL_CODES.items():  # docs/aoi.md: the calling state reports the call's error
        assert f"when its {mnemonic} call errs" in by_code[code]
    states = [r["State"] for r in table_rows(section(matrix, "States")) if r["Chart"].startswith(f"[{AOI_ID}_recovery]")]
    assert states == [f"[{s.id}]({page}#state-{s.id})" for s in spec.add_on(AOI_ID).recovery.states]
    done = [r for r in table_rows(section(matrix, "Completion (DN)")) if r["Instruction"] == f"[{AOI_ID}]({page})"]
    assert len(done) == 1 and "Sts_PC" in done[0]["Spec element"]


def test_docs_command_writes_the_aoi_page(tmp_path: Path) -> None:
    out = tmp_path / "ref"
    code, _msg, err = run(["docs", "-o", str(out), "--scenarios", str(ROOT / "scenarios")])
    assert code == 0, err
    page = (out / "instructions" / f"{AOI_ID}.md").read_text(encoding="utf-8")
    assert "## Checks, in the order they are evaluated" in page and "## Recovery chart" in page
    assert f"../flowcharts/{AOI_ID}.svg" in page and f"../diagrams/{AOI_ID}_recovery.svg" in page
    codes = section(page, "Error codes")
    row = next(line for line in codes.splitlines() if '"code-1118"' in line)
    assert "scenarios/aoi/err_1118_not_energized.yaml)" in row  # a scenario producing 1118
    for md in out.rglob("*.md"):  # every relative link of the reference resolves
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", md.read_text(encoding="utf-8")):
            if "://" not in target:
                assert (md.parent / target).exists(), f"{md.relative_to(out)} links to missing {target}"


def test_diagram_command_draws_the_aoi(spec: ir.Spec, aoi: ir.AddOnInstruction) -> None:
    code, out, err = run(["diagram", AOI_ID])
    assert (code, err) == (0, "") and out == instruction_dot(spec, aoi)
    code, out, err = run(["diagram", AOI_ID, "--part", "part2"])
    assert (code, err) == (0, "") and out == instruction_dot(spec, aoi, part="part2")
    code, out, err = run(["diagram", AOI_ID.lower() + "_RECOVERY", "--format", "mermaid"])  # any case
    assert (code, err) == (0, "") and out == chart_mermaid(recovery_chart(spec, aoi, ordered=True))
    code, out, err = run(["diagram", AOI_ID + "_recovery"])  # as generated/ draws it: with the calls
    assert (code, err) == (0, "") and out == chart_dot(recovery_chart(spec, aoi, ordered=True), labels="full")
    code, out, err = run(["diagram", "NoSuchThing"])
    assert code == 2 and out == "" and f"add-on instructions: {AOI_ID}, {AOI_ID}_recovery" in err


def test_committed_pages_of_the_move_instructions_are_linked_from_the_index() -> None:
    """MAH, MAM, MAJ, MAS, MAG and MRP on CIP and virtual axes: page, flowchart and codes table."""
    index = (ROOT / "generated" / "index.md").read_text(encoding="utf-8")
    for mnemonic in ("MAH", "MAM", "MAJ", "MAS", "MAG", "MRP"):
        for family in ("CIP", "VIRTUAL"):
            v = f"{mnemonic}_{family}"
            assert f"[{v}](instructions/{v}.md)" in index and f"[svg](flowcharts/{v}.svg)" in index, v
            page = (ROOT / "generated" / "instructions" / f"{v}.md").read_text(encoding="utf-8")
            assert "## Error codes" in page and f"../flowcharts/{v}.svg" in page, v
            assert all((ROOT / "generated" / "flowcharts" / f"{v}.{ext}").is_file() for ext in ("dot", "mmd", "svg"))
