"""Citations outside the spec can be followed too: every ``sources:`` entry of the
scenarios and examples resolves to a document of the sources registry (publication and
page, topic or section), and no page of docs/ cites a working file by its number or the
project's fact list by its section (``001 ...``, ``domain-facts §4``) instead of the
publication."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from ruamel.yaml import YAML

from statecharts import sources

ROOT = Path(__file__).resolve().parent.parent
REGISTRY = sources.bundled_registry()
#: a citation of a working file (``001 instruction table``, ``003 §2.4``) or of the fact list
WORKING_FILE = re.compile(r"(?<![\w.,-])(?<!\d )(00[0-3] (?=§|[A-Za-z.])|domain-facts\b|seeds/)")


#: a top-level ``sources:`` key (found by its line, so that collecting the tests parses no YAML)
TOP_LEVEL_SOURCES = re.compile(r"^sources\s*:", re.MULTILINE)
YAML_FILES = sorted(p for folder in ("scenarios", "examples") for p in (ROOT / folder).rglob("*.yaml"))


def cited_files() -> list[Path]:
    return [p for p in YAML_FILES if TOP_LEVEL_SOURCES.search(p.read_text(encoding="utf-8"))]


FILES = cited_files()


def test_there_are_cited_scenarios() -> None:
    assert len(FILES) >= 100


def test_the_cited_files_are_those_whose_document_has_sources() -> None:
    """The line search of :func:`cited_files` finds exactly the documents with a ``sources`` key."""
    parsed = []
    for path in YAML_FILES:
        doc = YAML(typ="safe").load(path.read_text(encoding="utf-8"))
        if isinstance(doc, dict) and "sources" in doc:
            parsed.append(path)
    assert parsed == FILES


@pytest.mark.parametrize("path", FILES, ids=[str(p.relative_to(ROOT)) for p in FILES])
def test_every_source_of_a_scenario_resolves(path: Path) -> None:
    doc = YAML(typ="safe").load(path.read_text(encoding="utf-8"))
    problems = []
    for entry in doc["sources"]:
        assert not WORKING_FILE.search(str(entry)), f"{path.name}: {entry!r} cites a working file"
        problems += [f"{entry!r}: {p}" for p in sources.source_problems(str(entry), REGISTRY)]
    assert not problems, f"{path.relative_to(ROOT)}: " + "; ".join(problems)


DOCS = sorted([*(ROOT / "docs").rglob("*.md"), ROOT / "README.md", *(ROOT / "examples").rglob("*.md")])


@pytest.mark.parametrize("path", DOCS, ids=[str(p.relative_to(ROOT)) for p in DOCS])
def test_docs_cite_publications_not_working_files(path: Path) -> None:
    bad = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}" for n, line in
           enumerate(path.read_text(encoding="utf-8").splitlines(), start=1) if WORKING_FILE.search(line)]
    assert not bad, "\n".join(bad)


def test_the_pattern_finds_working_file_citations() -> None:
    for text in ("001 instruction table", "003 §2.4 1012", "002 Execution", "domain-facts §1a", "see seeds/"):
        assert WORKING_FILE.search(text), text
    for text in ("LDH-MSI instruction table", "SYNC-RM §2.4 1012", "RM002H p79", "in 2003 it", "ERR 12/001", "28,000 states", "10 000 items"):
        assert not WORKING_FILE.search(text), text
