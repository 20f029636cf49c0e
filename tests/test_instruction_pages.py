"""Every instruction page of ``generated/`` lists every documented code of its instruction.

Independent of the renderer: the expected codes come from the YAML files themselves
(``spec/errors.yaml`` and the instruction files, read with ruamel, not through the IR),
and the pages are read back as Markdown tables.  For MSO the codes are also written out
by hand from the documents (RM002H p78, p79; the third-party table for the generic
numbers), and MRHD's test status values from the MRHD pages (Test Status 0-5 of servo
axes, Hookup Test Status 0-6 of CIP drive axes).
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

import pytest
from ruamel.yaml import YAML

ROOT = Path(__file__).resolve().parent.parent
SPEC = ROOT / "spec"
PAGES = ROOT / "generated" / "instructions"


def load(path: Path) -> Any:
    return YAML(typ="safe").load(path.read_text(encoding="utf-8"))


@functools.cache
def instruction_files() -> dict[str, dict[str, Any]]:
    """Instruction id -> its ``instruction:`` mapping, for every instruction file of the spec."""
    out: dict[str, dict[str, Any]] = {}
    for path in sorted((SPEC / "instructions").rglob("*.yaml")):
        doc = load(path)
        if isinstance(doc, dict) and doc.get("format") == "motionchart-spec/1" and isinstance(doc.get("instruction"), dict):
            ins = doc["instruction"]
            out[ins["id"]] = ins
    return out


#: the ids of the instruction files, found by their lines (collecting the tests parses no YAML)
_ID_LINE = re.compile(r"^instruction:\s*\n(?:[ \t]+.*\n|\s*\n)*?[ \t]+id:\s*([A-Za-z_][\w]*)\s*$", re.MULTILINE)
INSTRUCTION_IDS = sorted(m.group(1) for p in (SPEC / "instructions").rglob("*.yaml")
                         if "format: motionchart-spec/1" in (t := p.read_text(encoding="utf-8"))
                         for m in [_ID_LINE.search(t)] if m)




@functools.cache
def extended_errors() -> list[dict[str, Any]]:
    return list(load(SPEC / "errors.yaml")["extended_errors"])


def test_the_instruction_ids_found_by_line_are_those_of_the_files() -> None:
    assert sorted(instruction_files()) == INSTRUCTION_IDS


def section_table(page: str, heading: str) -> list[dict[str, str]]:
    """The rows of the first Markdown table under ``## heading``, as header -> cell text."""
    lines = page.splitlines()
    start = lines.index(f"## {heading}")
    if "_None._" in lines[start + 1:start + 5]:
        return []  # the page says the section is empty
    rows: list[list[str]] = []
    for line in lines[start + 1:]:
        if line.startswith("## "):
            break
        if line.startswith("|"):
            rows.append([c.strip() for c in line.strip().strip("|").split(" | ")])
        elif rows:
            break
    header, _rule, *body = rows
    assert all(len(r) == len(header) for r in body), f"ragged table under {heading}"
    return [dict(zip(header, r)) for r in body]


def key(err: object, exerr: object) -> tuple[int, int]:
    return int(str(err)), 0 if exerr in (None, "—", 0, "0") else int(str(exerr))


def expected_codes(ins: dict[str, Any]) -> tuple[set[tuple[int, int]], set[tuple[int, int]]]:
    """(every documented code, the codes this instruction's own checks and aborts report)."""
    mnemonic = ins.get("mnemonic", ins["id"])
    modelled = {key(c["err"], c.get("exerr")) for c in [*ins.get("checks", []), *ins.get("aborts", [])]}
    documented = {key(x["err"], x["exerr"]) for x in extended_errors() if x["instruction"] in (mnemonic, ins["id"])}
    return modelled | documented, modelled


def test_every_instruction_has_a_page() -> None:
    assert len(instruction_files()) >= 15
    assert {p.stem for p in PAGES.glob("*.md")} == set(instruction_files()) | {a["id"] for a in addon_files()}


@pytest.mark.parametrize("ins_id", INSTRUCTION_IDS)
def test_page_lists_every_documented_code(ins_id: str) -> None:
    rows = section_table((PAGES / f"{ins_id}.md").read_text(encoding="utf-8"), "Error codes")
    listed = [key(r["ERR"], r["EXERR"]) for r in rows]
    every, modelled = expected_codes(instruction_files()[ins_id])
    assert len(listed) == len(set(listed)), f"{ins_id}: a code is listed twice"
    assert set(listed) == every, f"{ins_id}: missing {sorted(every - set(listed))}, extra {sorted(set(listed) - every)}"
    for r in rows:
        k = key(r["ERR"], r["EXERR"])
        assert r["Modelled"] == ("yes" if k in modelled else "no"), f"{ins_id} {k}: Modelled {r['Modelled']!r}"
        assert r["Meaning"] not in ("", "—") and r["Source"] not in ("", "—") and r["Confidence / interpretation"]
        if k in modelled:
            assert "check [" in r["How the model produces it"] or "abort [" in r["How the model produces it"]
        else:
            assert r["How the model produces it"].startswith(("— (documented, not modelled)", "not by this variant"))


def test_mso_page_has_the_documented_codes_by_hand() -> None:
    rows = section_table((PAGES / "MSO.md").read_text(encoding="utf-8"), "Error codes")
    got = {key(r["ERR"], r["EXERR"]): r["Modelled"] for r in rows}
    # RM002H p78-79: shut down 12/12, enable-input switch 12/15, wrong drive state 12/16 (SERCOS);
    # generic codes 6, 8, 11, 20, 22 of the checks; 12/1 is the CIP variant's (documented for MSO)
    assert got == {(6, 0): "yes", (8, 0): "yes", (11, 0): "yes", (12, 12): "yes", (20, 0): "yes", (22, 0): "yes",
                   (12, 15): "no", (12, 16): "no", (12, 1): "no"}


@pytest.mark.parametrize(("ins_id", "attribute", "values"), [
    ("MRHD", "HookupTestStatus", {0, 1, 2, 3, 4, 5, 6}),
    ("MRHD_SERVO", "TestStatus", {0, 1, 2, 3, 4, 5}),
])
def test_mrhd_pages_list_the_test_status_values(ins_id: str, attribute: str, values: set[int]) -> None:
    rows = section_table((PAGES / f"{ins_id}.md").read_text(encoding="utf-8"), "Status values")
    listed = {int(r["Value"]) for r in rows if r["Attribute"] == f"`{attribute}`"}
    assert listed == values
    for r in rows:
        assert r["Meaning"] not in ("", "—") and r["Source"].startswith("LDH-MRHD")
        assert r["Modelled"] in ("yes", "no")
        if r["Modelled"] == "yes":
            assert r["Set by"] not in ("", "—")


def addon_files() -> list[dict[str, Any]]:
    """The add-on instructions of the spec, wherever the spec keeps them."""
    found = []
    for path in sorted(SPEC.rglob("*.yaml")):
        doc = load(path)
        if isinstance(doc, dict):
            for k in ("aoi", "add_on_instruction"):
                if isinstance(doc.get(k), dict) and "errors" in doc[k]:
                    found.append(doc[k])
    return found


def test_addon_page_lists_every_code() -> None:
    addons = addon_files()
    assert addons
    for aoi in addons:
        page = (PAGES / f"{aoi['id']}.md").read_text(encoding="utf-8")
        rows = section_table(page, "Error codes")
        codes = [int(r["Sts_ERR"].rsplit(">", 1)[-1]) for r in rows]
        assert sorted(codes) == sorted(int(e["code"]) for e in aoi["errors"])
        for r in rows:
            assert r["Name"] not in ("", "—") and r["Source"] not in ("", "—")
