"""The add-on instruction's generated artefacts: reference page, flowchart, recovery chart.

Expected values are typed in from the documents, not read from the spec: the order of
the 17 ordered checks is the one of 003 §1.3.2 as docs/aoi.md resolves it (1017 placed
after 1016 and the last rows 1025, 1002, 1118: INT-022, INT-026), the 21 codes are those
of 003 §2.4, and the sub-instructions' preconditions and ``.ERR`` codes are the table of
docs/aoi.md ("The recovery chart").  The tests then check that the spec agrees with
them and that the artefacts show them: in the page's tables, one flowchart decision per
check in that order, each failing to a box with its code, DOT text that is the same on
every run and that Graphviz accepts, and the artefacts written by ``generate`` / ``docs``
and drawn by ``diagram``.
"""

from __future__ import annotations

import contextlib
import io
import re
import shutil
from pathlib import Path

import pytest

from checker import cli
from statecharts.aoi import bundled_aoi
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.render import graphviz_bin
from statecharts.render.aoi import (
    AoiDocument,
    aoi_flowchart_dot,
    aoi_flowchart_mermaid,
    aoi_page,
    aoi_spec_dirs,
    build_aoi_flowchart,
    load_aoi_document,
    recovery_dot,
    recovery_mermaid,
)
from statecharts.render.generate import build
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
#: docs/aoi.md "The recovery chart": the state calling each instruction and its code.
CALL_CODES = {"MAH": 1020, "MAM": 1022, "MAG": 1023, "MRP": 1027}
#: docs/aoi.md: each sub-instruction's preconditions in order, as .ERR codes.
SUB_ERRS = {"MAH": [87, 41], "MAM": [87, 17, 13], "MAG": [87, 16], "MRP": [16, 13], "MAS": []}


@pytest.fixture(scope="module")
def doc() -> AoiDocument:
    return load_aoi_document()


@pytest.fixture(scope="module")
def page(doc: AoiDocument) -> str:
    spec = load_spec()
    return aoi_page(doc, trace(spec, [ROOT / "scenarios"]), {e.code: e.name for e in spec.errors})


def section(page: str, title: str) -> str:
    """The text of ``## title`` (or ``### title``) up to the next heading of the same or a higher level."""
    m = re.search(rf"^(#+) {re.escape(title)}\n", page, re.M)
    assert m, title
    level = len(m.group(1))
    rest = page[m.end():]
    end = re.search(rf"^#{{1,{level}}} ", rest, re.M)
    return rest[: end.start()] if end else rest


def table_rows(text: str) -> list[list[str]]:
    rows = [line for line in text.splitlines() if line.startswith("| ")]
    return [[c.strip() for c in re.split(r"(?<!\\)\|", r)[1:-1]] for r in rows[1:]]  # without the header


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main(argv)
    return code, out.getvalue(), err.getvalue()


# --------------------------------------------------------------------------- the spec agrees with the documents


def test_spec_check_order_is_the_documented_order() -> None:
    aoi = bundled_aoi()
    checks = aoi.add_on.checks
    assert [c.err for c in checks] == CHECK_ORDER
    # a check restricted to SyncType 1 says so first: "Cfg_SyncType == 1 and (...)"
    assert {c.err for c in checks if c.fails_when.text.startswith("Cfg_SyncType == 1 and (")} == SYNC1_ONLY
    assert all("Cfg_SyncType" not in c.fails_when.text for c in checks if c.err not in SYNC1_ONLY)
    assert sorted(code for code, _ in aoi.errors) == ALL_CODES


# --------------------------------------------------------------------------- reference page


def test_check_table_lists_the_codes_in_spec_and_documented_order(doc: AoiDocument, page: str) -> None:
    rows = table_rows(section(page, "Checks, in the order they run"))
    assert [r[0] for r in rows] == [str(n) for n in range(1, len(CHECK_ORDER) + 1)]
    codes = [int(re.match(r"\[(\d+)\]", r[2]).group(1)) for r in rows]
    assert codes == [c.err for c in bundled_aoi().add_on.checks]
    assert codes == CHECK_ORDER
    for r, code in zip(rows, codes):
        assert r[3].startswith("`Cfg_SyncType == 1 and (") == (code in SYNC1_ONLY), r
        assert r[5] and r[5] != "—"  # the source
        assert "raM_Opr_SyncPthPhyAx_CD.yaml:" in r[7]  # defined at
    # the interpretation links the documents name
    by_code = dict(zip(codes, rows))
    assert "INT-022" in by_code[1118][6] and "INT-026" in by_code[1017][6] and "INT-026" in by_code[1002][6]


def test_every_error_code_appears_in_the_page(doc: AoiDocument, page: str) -> None:
    rows = table_rows(section(page, "Error codes"))
    listed = [int(re.search(r"</a>(\d+)$", r[0]).group(1)) for r in rows]
    assert listed == ALL_CODES == sorted(e.code for e in doc.errors)
    for r in rows:
        assert r[1] and r[2] != "— (reported by nothing)" and r[3] != "—", r
    for code in ALL_CODES:
        assert str(code) in page
    # the four call errors are reported by the state calling the instruction
    by_code = dict(zip(listed, rows))
    for mnemonic, code in CALL_CODES.items():
        assert f"({mnemonic} fails)" in by_code[code][2]


def test_page_lists_inputs_outputs_and_recovery(doc: AoiDocument, page: str) -> None:
    inputs = {r[0].strip("`"): r for r in table_rows(section(page, "Inputs"))}
    # 003 §2.2 and docs/aoi.md: the three references and six configuration inputs
    assert list(inputs) == ["Ref_AxisPhy", "Ref_AxisPth", "Ref_Handle", "Cfg_SyncType", "Cfg_AllowHome",
                            "Cfg_TravelLIM", "Cfg_RotaryShortestTOL", "Cfg_MoveType", "Set_Speed"]
    assert inputs["Ref_AxisPhy"][2] == "`AXIS_CIP_DRIVE`" and inputs["Set_Speed"][1] == "REAL"
    outputs = [r[0].strip("`") for r in table_rows(section(page, "Outputs (status members)"))]
    assert {"Sts_ER", "Sts_ERR", "Sts_EXERR", "Sts_IP", "Sts_PC"} <= set(outputs)
    states = [re.search(r"`(\w+)`", r[0]).group(1) for r in table_rows(section(page, "States"))]
    assert states == [s.state.id for s in doc.states]
    transitions = table_rows(section(page, "Transitions"))
    assert [(r[1].strip("`"), r[2].strip("`")) for r in transitions] == [(t.source, t.target) for t in doc.transitions]
    assert "rung false (EnableIn false)" in page and "| prescan |" in page and "## Completion" in page


def test_page_lists_sub_instructions_with_ordered_err_codes(page: str) -> None:
    subs = section(page, "Sub-instructions")
    for mnemonic, errs in SUB_ERRS.items():
        m = re.search(rf"^### {mnemonic}: ", subs, re.M)
        assert m, mnemonic
        block = section(subs[m.start():], subs[m.start():].splitlines()[0].lstrip("# "))
        rows = table_rows(block)
        assert [int(re.match(r"\[?(\d+)", r[2]).group(1)) for r in rows] == errs, mnemonic
        assert [r[0] for r in rows] == [str(n) for n in range(1, len(errs) + 1)]
    # names from the main spec's error catalog, linked to it
    assert "[87](../error-codes.md#err-87)" in subs


def test_page_is_deterministic_and_has_no_absolute_path(doc: AoiDocument, page: str) -> None:
    spec = load_spec()
    again = aoi_page(load_aoi_document(), trace(spec, [ROOT / "scenarios"]), {e.code: e.name for e in spec.errors})
    assert page == again
    assert str(ROOT) not in page and str(Path.home()) not in page


# --------------------------------------------------------------------------- flowchart


def test_flowchart_has_one_decision_per_check_in_order(doc: AoiDocument) -> None:
    fc = build_aoi_flowchart(doc)
    checks = [n for n in fc.nodes if n.id.startswith("check_")]
    assert all(n.kind == "decision" for n in checks)
    assert [n.id for n in checks] == [f"check_{c.id}" for c in doc.checks]
    assert len(checks) == len(CHECK_ORDER)
    nodes = {n.id: n for n in fc.nodes}
    for n, (node, code) in enumerate(zip(checks, CHECK_ORDER), start=1):
        assert node.title[0].startswith(f"{n}. ")
        (yes,) = [e for e in fc.edges if e.source == node.id and e.label == "yes"]
        assert nodes[yes.target].kind == "error" and f"Sts_ERR = {code}" in nodes[yes.target].title
        assert " ".join(node.detail).startswith("Cfg_SyncType == 1 and (") == (code in SYNC1_ONLY)
    # the "no" branches chain the checks top to bottom
    chain = [e.target for e in fc.edges if e.label == "no" and e.source.startswith("check_")]
    assert chain == [n.id for n in checks[1:]] + ["recovery"]
    # in the DOT text the decisions come in the same order
    dot = aoi_flowchart_dot(doc)
    positions = [dot.index(f"\t{n.id} [") for n in checks]
    assert positions == sorted(positions)


def test_flowchart_ends_in_the_recovery_branch(doc: AoiDocument) -> None:
    fc = build_aoi_flowchart(doc)
    nodes = {n.id: n for n in fc.nodes}
    routes = [n for n in fc.nodes if n.id.startswith("route_")]
    assert routes and all(n.kind == "decision" for n in routes)
    assert [e.target for e in fc.edges if e.source == "recovery"] == [routes[0].id]
    # every call state fails to its code; done sets Sts_PC
    for mnemonic, code in CALL_CODES.items():
        (state,) = [n for n in fc.nodes if n.kind == "process" and n.title[0].split(": ")[-1].startswith(mnemonic)]
        (fail,) = [e for e in fc.edges if e.source == state.id and nodes[e.target].kind == "error"]
        assert f"Sts_ERR = {code}" in nodes[fail.target].title
    assert nodes["state_done"].kind == "done" and "Sts_PC" in nodes["state_done"].title[0]
    assert "flowchart TD" in aoi_flowchart_mermaid(doc)


# --------------------------------------------------------------------------- determinism and Graphviz


def test_dot_is_deterministic(doc: AoiDocument) -> None:
    other = load_aoi_document()
    assert aoi_flowchart_dot(doc) == aoi_flowchart_dot(doc) == aoi_flowchart_dot(other)
    assert recovery_dot(doc) == recovery_dot(doc) == recovery_dot(other)
    assert recovery_mermaid(doc) == recovery_mermaid(other)
    assert aoi_flowchart_mermaid(doc) == aoi_flowchart_mermaid(other)
    for text in (aoi_flowchart_dot(doc), recovery_dot(doc)):
        assert not re.search(r"0x[0-9a-f]{6,}", text)  # no memory addresses
        assert str(ROOT) not in text


@pytest.mark.skipif(not HAVE_GRAPHVIZ, reason="no Graphviz program (dot / graphviz-pure) here")
def test_dot_parses_with_graphviz(doc: AoiDocument) -> None:
    for text in (aoi_flowchart_dot(doc), recovery_dot(doc)):
        svg = graphviz_bin.render(text, "svg")
        assert b"<svg" in svg


def test_recovery_chart_shows_every_state_and_transition(doc: AoiDocument) -> None:
    dot = recovery_dot(doc)
    mmd = recovery_mermaid(doc)
    for s in doc.states:
        assert f"\t{s.state.id} [" in dot
        assert f'state "{s.state.id}" as s_{s.state.id}' in mmd
    for t in doc.transitions:
        assert f"\t{t.source} -> {t.target} [" in dot
        assert f"s_{t.source} --> s_{t.target} : " in mmd
    for mnemonic, code in CALL_CODES.items():
        assert f"[{mnemonic} fails] / Sts_ERR = {code}" in mmd
    assert "stateDiagram-v2" in mmd


# --------------------------------------------------------------------------- generate, docs and diagram


def test_build_writes_the_aoi_artefacts(tmp_path: Path, doc: AoiDocument) -> None:
    spec = load_spec()
    fake = lambda src: b'<?xml version="1.0"?>\n<svg/>\n'  # noqa: E731  # no Graphviz needed here
    files = build(spec, [], tmp_path, render_svg=fake, aoi=[doc]).files
    for name in (f"aoi/{AOI_ID}.md", f"flowcharts/{AOI_ID}.dot", f"flowcharts/{AOI_ID}.mmd",
                 f"flowcharts/{AOI_ID}.svg", f"diagrams/{AOI_ID}_recovery.dot",
                 f"diagrams/{AOI_ID}_recovery.mmd", f"diagrams/{AOI_ID}_recovery.svg"):
        assert name in files, name
    assert files[f"flowcharts/{AOI_ID}.dot"].decode() == aoi_flowchart_dot(doc)
    index = files["index.md"].decode()
    assert f"[{AOI_ID}](aoi/{AOI_ID}.md)" in index and "## Add-on instructions" in index
    interps = files["interpretations.md"].decode()
    assert f"](aoi/{AOI_ID}.md#check-energized)" in interps  # INT-022's user
    # without the add-on instruction nothing of it is written
    plain = build(spec, [], tmp_path, render_svg=fake).files
    assert not any(AOI_ID in name for name in plain)


def test_docs_command_writes_the_aoi_page(tmp_path: Path) -> None:
    out = tmp_path / "ref"
    code, _msg, err = run(["docs", "-o", str(out), "--scenarios", str(ROOT / "scenarios")])
    assert code == 0, err
    page = (out / "aoi" / f"{AOI_ID}.md").read_text(encoding="utf-8")
    assert "## Checks, in the order they run" in page and "## Recovery chart" in page
    assert f"../flowcharts/{AOI_ID}.svg" in page and f"../diagrams/{AOI_ID}_recovery.svg" in page
    assert "scenarios/aoi/err_1118_not_energized.yaml)" in page  # a scenario producing 1118
    for md in out.rglob("*.md"):  # every relative link of the reference resolves
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", md.read_text(encoding="utf-8")):
            if "://" not in target:
                assert (md.parent / target).exists(), f"{md.relative_to(out)} links to missing {target}"


def test_diagram_command_draws_the_aoi(doc: AoiDocument) -> None:
    code, out, err = run(["diagram", AOI_ID])
    assert (code, err) == (0, "") and out == aoi_flowchart_dot(doc)
    code, out, err = run(["diagram", AOI_ID.lower() + "_RECOVERY", "--format", "mermaid"])  # any case
    assert (code, err) == (0, "") and out == recovery_mermaid(doc)
    code, out, err = run(["diagram", "NoSuchThing"])
    assert code == 2 and out == "" and f"add-on instructions: {AOI_ID}, {AOI_ID}_recovery" in err


@pytest.mark.skipif(not HAVE_GRAPHVIZ, reason="no Graphviz program (dot / graphviz-pure) here")
def test_diagram_command_svg(tmp_path: Path) -> None:
    code, _out, err = run(["diagram", AOI_ID, "-o", str(tmp_path / "aoi.svg")])
    assert code == 0, err
    assert b"<svg" in (tmp_path / "aoi.svg").read_bytes()


def test_spec_dirs_follow_the_spec_arguments(tmp_path: Path) -> None:
    assert aoi_spec_dirs(None) == [bundled_spec_dir()]
    copy = tmp_path / "myspec"
    shutil.copytree(bundled_spec_dir(), copy, ignore=shutil.ignore_patterns("__pycache__", "*.py", "schema"))
    assert aoi_spec_dirs([copy, copy / "charts"]) == [copy]
    doc = load_aoi_document(copy)
    assert doc.file == "myspec/addons/raM_Opr_SyncPthPhyAx_CD.yaml"  # never absolute
    assert all(s.file.startswith("myspec/instructions/motion/") for s in doc.subs)
