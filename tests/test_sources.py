"""The sources registry and the citations of the spec.

The expected facts of the registry (publication numbers, revisions) are typed here by
hand from the documents' title pages as cited in the project's research notes; the
refusals are checked on copies of the bundled spec with one citation broken.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from typing import Any

import pytest

from statecharts import sources as S
from statecharts.diagnostics import SpecError
from statecharts.loader import bundled_spec_dir, load_spec, read_yaml
from statecharts.render.sources import citing_elements, docs_page

ROOT = Path(__file__).resolve().parent.parent
SPEC = bundled_spec_dir()


@pytest.fixture()
def spec_copy(tmp_path: Path) -> Path:
    dst = tmp_path / "spec"
    shutil.copytree(SPEC, dst, ignore=shutil.ignore_patterns("__pycache__", "*.py"))
    return dst


def _replace(path: Path, old: str, new: str) -> int:
    text = path.read_text(encoding="utf-8")
    assert old in text, f"{old!r} not in {path}"
    line = text[: text.index(old)].count("\n") + 1
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return line


def _errors(paths: list[Path]) -> list[str]:
    with pytest.raises(SpecError) as exc:
        load_spec(paths)
    return [str(d) for d in exc.value.diagnostics]


def test_registry_holds_the_publications_by_number() -> None:
    reg = S.bundled_registry()
    by = {s.code: s for s in reg.sources}
    assert by["RM002H"].publication == "MOTION-RM002H-EN-P"
    assert by["RM002H"].revision.startswith("H, February 2018")
    assert by["RM003I"].publication == "MOTION-RM003I-EN-P"
    assert by["UM003"].publication == "1784-UM003A-EN-P"
    # the four source topics/manuals are registered under their own codes
    assert {"LDH-MSI", "LDH-MDO", "LDH-MRHD", "SYNC-RM"} <= set(by)
    assert "Motion Run Hookup Diagnostics (MRHD)" in by["LDH-MRHD"].title
    assert "raM_Opr_SyncPthPhyAx_CD" in by["SYNC-RM"].title
    assert by["ICS"].kind == "third-party" and by["IMD"].kind == "third-party"


def _all_citation_texts() -> list[tuple[str, str]]:
    out = []
    for path in sorted(SPEC.rglob("*.yaml")):
        tree = read_yaml(path, [])
        assert tree is not None, path
        out.extend((f"{path.relative_to(SPEC)}", v) for _, v in S.iter_sources(tree) if isinstance(v, str))
    return out


def test_every_bundled_source_resolves() -> None:
    reg = S.bundled_registry()
    texts = _all_citation_texts()
    assert len(texts) > 900
    bad = [(f, t, S.source_problems(t, reg)) for f, t in texts if S.source_problems(t, reg)]
    assert bad == []
    load_spec()


def test_no_citation_names_a_file_a_reader_lacks() -> None:
    """No `000`..`003` file numbers, no research-note section numbers."""
    for f, text in _all_citation_texts():
        for c in S.split_citations(text):
            assert not re.match(r"00[0-3]\b", c), (f, c)
            assert "domain-facts" not in c and "DESIGN" not in c, (f, c)


def _scenario_citations() -> dict[str, set[str]]:
    """Code -> the pages (``p98``) the ``sources:`` lists of scenarios and examples cite."""
    from ruamel.yaml import YAML

    root = Path(__file__).resolve().parent.parent
    out: dict[str, set[str]] = {}
    for folder in ("scenarios", "examples"):
        for path in sorted((root / folder).rglob("*.yaml")):
            doc = YAML(typ="safe").load(path.read_text(encoding="utf-8"))
            for entry in doc.get("sources", []) if isinstance(doc, dict) else []:
                for code, locator in S.citations(str(entry)):
                    out.setdefault(code, set()).update(f"p{n}" for n in S.cited_pages(locator))
    return out


def test_every_registered_page_topic_and_section_is_cited() -> None:
    """By the spec; a document the spec does not cite (the general instructions manual)
    is cited, page for page, by the scenarios and examples."""
    reg = S.bundled_registry()
    uses: dict[str, Any] = dict(citing_elements(SPEC, reg))
    for code, pages in _scenario_citations().items():
        if code not in uses and pages:
            uses[code] = dict.fromkeys(pages)
    for src in reg.sources:
        keys = set(uses.get(src.code, {}))
        assert src.code in uses, f"{src.code} is registered but never cited"
        if src.locator == "pages":
            for a, b in src.pages:
                for page in (a, b):
                    assert f"p{page}" in keys, f"{src.code} p{page} is registered but not cited"
        if src.locator == "topics":
            assert {t for t, _ in src.topics} <= keys, src.code


@pytest.mark.parametrize(("old", "new", "fragment"), [
    ('source: "LDH-MDO Operands"', 'source: "002 Operands"', "'002' is not a registered source"),
    ('source: "LDH-MDO Operands"', 'source: "RM002H p9999"', "page 9999 of RM002H is not among the pages"),
    ('source: "LDH-MDO Operands"', 'source: "RA37 no-such-topic"', "'no-such-topic' is not a listed topic of RA37"),
    ('source: "LDH-MDO Operands"', 'source: "LDH-MDO Nowhere"', "does not begin with one of its sections"),
    ('source: "LDH-MDO Operands"', 'source: "SYNC-RM §9.9"', "§9.9 is not a listed section of SYNC-RM"),
    ('source: "LDH-MDO Operands"', 'source: "LDH-MDO Operands;"', "empty citation"),
    ('source: "LDH-MDO Operands"', 'source: "RM002H"', "RM002H needs a locator"),
])
def test_loader_refuses_an_unresolvable_source(spec_copy: Path, old: str, new: str, fragment: str) -> None:
    path = spec_copy / "instructions" / "MDO.yaml"
    line = _replace(path, old, new)
    errors = _errors([spec_copy])
    hits = [e for e in errors if fragment in e]
    assert len(hits) == 1, errors
    assert hits[0].startswith(f"{path}:{line}:"), hits[0]
    assert "unresolvable source" in hits[0]


def test_unknown_interpretation_cited_in_a_source(spec_copy: Path) -> None:
    path = spec_copy / "instructions" / "MDO.yaml"
    line = _replace(path, 'source: "LDH-MDO Operands"', 'source: "LDH-MDO Operands; INT-999"')
    errors = _errors([spec_copy])
    assert any(e.startswith(f"{path}:{line}:") and "unknown interpretation 'INT-999'" in e for e in errors), errors


def test_evidence_and_model_checker_files_are_checked_too(spec_copy: Path) -> None:
    interp = spec_copy / "interpretations.yaml"
    text = interp.read_text(encoding="utf-8")
    first = re.search(r'evidence: \["([^"]+)"', text)
    assert first is not None
    l1 = _replace(interp, f'evidence: ["{first.group(1)}"', 'evidence: ["seed 002"')
    props = spec_copy / "properties" / "noncip.yaml"
    ptext = props.read_text(encoding="utf-8")
    m = re.search(r'source: "([^"]+)"', ptext)
    assert m is not None
    l2 = _replace(props, m.group(0), 'source: "my notes"')
    errors = _errors([spec_copy])
    assert any(e.startswith(f"{interp}:{l1}:") and "'seed' is not a registered source" in e for e in errors), errors
    assert any(e.startswith(f"{props}:{l2}:") and "'my' is not a registered source" in e for e in errors), errors


def test_add_on_instruction_loader_refuses_too(spec_copy: Path) -> None:
    path = spec_copy / "addons" / "raM_Opr_SyncPthPhyAx_CD.yaml"
    text = path.read_text(encoding="utf-8")
    m = re.search(r'source: "(SYNC-RM [^"]+)"', text)
    assert m is not None
    line = _replace(path, m.group(0), 'source: "003 §2.2"')
    with pytest.raises(SpecError) as exc:
        load_spec([spec_copy])
    msgs = [str(d) for d in exc.value.diagnostics]
    assert any(e.startswith(f"{path}:{line}:") and "'003' is not a registered source" in e for e in msgs), msgs


def test_a_spec_of_ones_own_brings_its_own_registry(tmp_path: Path) -> None:
    own = tmp_path / "mine"
    own.mkdir()
    (own / "sources.yaml").write_text(
        "format: motionchart-sources/1\nsources:\n"
        "  - {code: LAMP-DS, kind: manual, publisher: Acme, publication: ACME-123, title: Lamp data sheet,\n"
        "     revision: '1', about: The lamp., locator: pages, pages: [1-4]}\n", encoding="utf-8")
    lamp = ROOT / "tests" / "snapshots" / "demo_every_construct.yaml"
    target = own / "demo.yaml"
    target.write_text(lamp.read_text(encoding="utf-8").replace(
        "MC tests/snapshots (a rendering fixture)", "LAMP-DS p2", 1), encoding="utf-8")
    spec = load_spec([SPEC, own])  # both registries apply: the bundled codes and LAMP-DS
    assert str(target) in spec.files
    _replace(target, "LAMP-DS p2", "LAMP-DS p7")
    errors = _errors([SPEC, own])
    assert any("page 7 of LAMP-DS" in e for e in errors), errors
    (own / "sources.yaml").write_text((own / "sources.yaml").read_text().replace("LAMP-DS", "RM002H"), encoding="utf-8")
    errors = _errors([SPEC, own])
    assert any("'RM002H' is also defined in" in e for e in errors), errors


def test_malformed_registry_is_located(spec_copy: Path) -> None:
    reg = spec_copy / "sources.yaml"
    line = _replace(reg, "    kind: manual\n", "    kind: pamphlet\n")
    errors = _errors([spec_copy])
    assert any(e.startswith(f"{reg}:{line}:") and "pamphlet" in e for e in errors), errors


def test_docs_sources_page_is_current() -> None:
    page = (ROOT / "docs" / "sources.md").read_text(encoding="utf-8")
    assert page == docs_page(S.bundled_registry()), "docs/sources.md is stale: run make generate"


def test_the_benchmark_model_cites_registered_sources() -> None:
    """`make bench` loads benchmarks/five_state/chart.yaml beside the bundled spec."""
    bench_chart = Path(__file__).resolve().parents[1] / "benchmarks" / "five_state" / "chart.yaml"
    spec = load_spec([bundled_spec_dir(), bench_chart])
    assert any(c.id != "AxisNonCIP" and len(c.states) == 5 for c in spec.charts)
