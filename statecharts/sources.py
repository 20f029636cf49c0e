"""The sources registry (``spec/sources.yaml``) and the citations that refer to it.

Every ``source:`` in the spec is one or more citations separated by ``;`` (a ``;``
inside parentheses does not separate).  A citation starts with the short code of a
registered document, followed by a locator whose form the entry declares:

- ``pages``: printed page numbers, ``RM002H p79`` or ``RM002H p30-33, p576``; every
  page must lie in the entry's ``pages``;
- ``topics``: online-help topic names, ``RA37 mso, mah``; each must be a listed topic;
- ``sections``: for a topic or manual cited by section, ``LDH-MRHD Test Status`` or
  ``SYNC-RM §2.4 1025``; section numbers (``§2.4``) must each be listed, and a named
  locator must begin with a listed section name;
- ``path``: a repository path, ``MC docs/semantics.md``;
- ``free``: anything after the code (``ICS code 11``).

An interpretation id (``INT-012``, optionally followed by a note) is a citation too.
Text in parentheses after a locator is a note and is not checked.

:func:`source_problems` checks one source text; :func:`tree_source_diagnostics` walks a
parsed YAML tree and reports every unresolvable ``source:`` at its line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from statecharts.diagnostics import Diagnostic, SpecError, locate, node_path

SOURCES_FORMAT = "motionchart-sources/1"
SOURCES_FILE = "sources.yaml"
LOCATOR_KINDS = ("pages", "topics", "sections", "path", "free")
KINDS = ("manual", "online-help", "library-manual", "third-party", "project")

_TEXT = {"type": "string", "minLength": 1}
SOURCES_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "type": "object",
    "additionalProperties": False,
    "required": ["format", "sources"],
    "properties": {
        "format": {"const": SOURCES_FORMAT},
        "sources": {"type": "array", "minItems": 1, "items": {
            "type": "object",
            "additionalProperties": False,
            "required": ["code", "kind", "publisher", "publication", "title", "revision", "about", "locator"],
            "properties": {
                "code": {"type": "string", "pattern": "^[A-Z][A-Za-z0-9]*(-[A-Za-z0-9]+)*$"},
                "kind": {"enum": list(KINDS)},
                "publisher": _TEXT, "publication": _TEXT, "title": _TEXT, "revision": _TEXT, "about": _TEXT,
                "url": _TEXT,
                "locator": {"enum": list(LOCATOR_KINDS)},
                "pages": {"type": "array", "minItems": 1, "items": {
                    "anyOf": [{"type": "integer", "minimum": 1}, {"type": "string", "pattern": "^[0-9]+-[0-9]+$"}]}},
                "topics": {"type": "object", "minProperties": 1, "additionalProperties": _TEXT},
                "sections": {"type": "object", "minProperties": 1, "additionalProperties": _TEXT},
            },
        }},
    },
}

_INTERPRETATION = re.compile(r"INT-\d{3}\b")
_PAGE = re.compile(r"\bp(\d+)(?:-(\d+))?\b")
#: A section number in a locator: ``§4.2`` (group 1: ``4.2``).
SECTION_NUMBER = re.compile(r"§(\d+(?:\.\d+)*)")


@dataclass(frozen=True, slots=True)
class Source:
    """One registered document."""

    code: str
    kind: str
    publisher: str
    publication: str
    title: str
    revision: str
    about: str
    locator: str
    url: str | None = None
    pages: tuple[tuple[int, int], ...] = ()
    topics: tuple[tuple[str, str], ...] = ()
    sections: tuple[tuple[str, str], ...] = ()

    def page_text(self) -> str:
        return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in self.pages)


@dataclass(frozen=True, slots=True)
class Registry:
    sources: tuple[Source, ...]
    path: str

    def get(self, code: str) -> Source | None:
        for s in self.sources:
            if s.code == code:
                return s
        return None

    @property
    def codes(self) -> tuple[str, ...]:
        return tuple(s.code for s in self.sources)


class SourcesError(SpecError):
    """The registry file itself is unreadable or malformed."""


def _pages(items: list[Any]) -> tuple[tuple[int, int], ...]:
    out = []
    for p in items:
        if isinstance(p, int):
            out.append((p, p))
        else:
            a, b = (int(x) for x in str(p).split("-"))
            out.append((min(a, b), max(a, b)))
    return tuple(out)


def load_registry(path: Path | str) -> Registry:
    """Read and check one sources file; raise :class:`SourcesError` with located problems."""
    from statecharts.loader import plain_data as _plain  # the loader imports this module
    from statecharts.loader import read_yaml, schema_diagnostics

    p = Path(path)
    errors: list[Diagnostic] = []
    tree = read_yaml(p, errors, what="sources file")
    if tree is None:
        if not errors:
            errors.append(Diagnostic(str(p), 1, 1, "", f"empty sources file; expected `format: {SOURCES_FORMAT}`"))
        raise SourcesError(errors)
    errors.extend(schema_diagnostics(str(p), tree, SOURCES_SCHEMA, "a sources file"))
    if errors:
        raise SourcesError(errors)
    data = _plain(tree)
    seen: dict[str, int] = {}
    sources = []
    for i, s in enumerate(data["sources"]):
        if s["code"] in seen:
            line, col = locate(tree, ("sources", i, "code"))
            errors.append(Diagnostic(str(p), line, col, node_path(("sources", i, "code")),
                                     f"duplicate source code {s['code']!r} (first at entry {seen[s['code']] + 1})"))
            continue
        seen[s["code"]] = i
        need = {"pages": "pages", "topics": "topics", "sections": "sections"}.get(s["locator"])
        if need and need not in s:
            line, col = locate(tree, ("sources", i))
            errors.append(Diagnostic(str(p), line, col, node_path(("sources", i)),
                                     f"locator {s['locator']!r} needs a `{need}:` list"))
        sources.append(Source(
            code=s["code"], kind=s["kind"], publisher=s["publisher"], publication=s["publication"],
            title=s["title"], revision=s["revision"], about=" ".join(s["about"].split()), locator=s["locator"],
            url=s.get("url"), pages=_pages(s.get("pages", [])), topics=tuple(s.get("topics", {}).items()),
            sections=tuple(s.get("sections", {}).items()),
        ))
    if errors:
        raise SourcesError(errors)
    return Registry(tuple(sources), str(p))


@lru_cache(maxsize=8)
def _cached_registry(path: str, mtime_ns: int) -> Registry:
    return load_registry(path)


def registry_at(path: Path | str) -> Registry:
    """:func:`load_registry`, cached while the file is unchanged."""
    p = Path(path)
    return _cached_registry(str(p), p.stat().st_mtime_ns)


def bundled_registry() -> Registry:
    from statecharts.loader import bundled_spec_dir

    return registry_at(bundled_spec_dir() / SOURCES_FILE)


def split_citations(text: str) -> list[str]:
    """The citations of one source text: split at ``;`` outside parentheses."""
    out: list[str] = []
    depth = 0
    cur: list[str] = []
    for ch in text:
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth = max(0, depth - 1)
        if ch == ";" and depth == 0:
            out.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur).strip())
    return out


def without_notes(text: str) -> str:
    """The locator with its parenthesised notes removed."""
    out, depth = [], 0
    for ch in text:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth = max(0, depth - 1)
        elif depth == 0:
            out.append(ch)
    return "".join(out)


def starts_with_name(locator: str, name: str) -> bool:
    """Whether ``locator`` begins with the section name ``name`` as a whole word (any case)."""
    if not locator.lower().startswith(name.lower()):
        return False
    rest = locator[len(name):]
    return not rest or not (rest[0].isalnum() or rest[0] == "_")


def _in_pages(page: int, ranges: tuple[tuple[int, int], ...]) -> bool:
    return any(a <= page <= b for a, b in ranges)


def citation_problem(citation: str, registry: Registry) -> str | None:
    """Why one citation does not resolve, or None when it does."""
    if not citation:
        return "empty citation (two `;` in a row, or a `;` at the end)"
    if _INTERPRETATION.match(citation):
        return None
    code, _, locator = citation.partition(" ")
    src = registry.get(code)
    if src is None:
        return (f"{code!r} is not a registered source; the codes of {Path(registry.path).name} are: "
                f"{', '.join(registry.codes)} (or cite an interpretation, INT-nnn)")
    loc = locator.strip()
    bare = without_notes(loc).strip()
    if src.locator == "free":
        return None
    if not bare:
        if src.locator == "sections":
            return None  # the whole topic or document
        return f"{code} needs a locator ({src.locator}) after the code, e.g. {_example(src)}"
    if src.locator == "pages":
        found = list(_PAGE.finditer(bare))
        if not found:
            return f"{code} is cited by page: write e.g. {_example(src)}"
        for m in found:
            a = int(m.group(1))
            b = int(m.group(2) or a)
            for page in (a, b):
                if not _in_pages(page, src.pages):
                    return (f"page {page} of {code} is not among the pages the registry lists for it "
                            f"({src.page_text()}); add it to {Path(registry.path).name} if it is really used")
        return None
    if src.locator == "topics":
        topic_names = {t for t, _ in src.topics}
        for word in (w.strip() for w in bare.split(",")):
            if word not in topic_names:
                return f"{word!r} is not a listed topic of {code}; topics: {', '.join(sorted(topic_names))}"
        return None
    if src.locator == "sections":
        names = [n for n, _ in src.sections]
        numbers = SECTION_NUMBER.findall(bare)
        if numbers:
            for n in numbers:
                if f"§{n}" not in names:
                    return f"§{n} is not a listed section of {code}; sections: {', '.join(names)}"
            return None
        if bare.startswith("§"):
            return f"{code}: a section number after § is missing"
        if not any(starts_with_name(bare, n) for n in names if not n.startswith("§")):
            return f"{code} is cited by section: {bare!r} does not begin with one of its sections ({', '.join(names)})"
        return None
    if src.locator == "path":
        if not re.match(r"(spec|docs|scenarios|examples|tests|benchmarks)/\S", bare):
            return f"{code} is cited by repository path (spec/..., docs/...), got {bare!r}"
        return None
    return None


def _example(src: Source) -> str:
    if src.locator == "pages" and src.pages:
        return f"`{src.code} p{src.pages[0][0]}`"
    if src.locator == "topics" and src.topics:
        return f"`{src.code} {src.topics[0][0]}`"
    if src.locator == "sections" and src.sections:
        return f"`{src.code} {src.sections[0][0]}`"
    return f"`{src.code} ...`"


def source_problems(text: str, registry: Registry) -> list[str]:
    """Every reason why a ``source:`` text does not resolve (empty list: it resolves)."""
    if not text.strip():
        return ["empty source; cite a document of the registry (docs/sources.md)"]
    out = []
    for c in split_citations(text):
        problem = citation_problem(c, registry)
        if problem:
            out.append(problem)
    return out


def citations(text: str) -> list[tuple[str, str]]:
    """(code, locator) of each citation of a resolvable source text (interpretations as ``INT``)."""
    out = []
    for c in split_citations(text):
        if _INTERPRETATION.match(c):
            out.append(("INT", c))
        else:
            code, _, loc = c.partition(" ")
            out.append((code, loc.strip()))
    return out


def cited_pages(locator: str) -> list[int]:
    """The page numbers a ``pages`` locator names (ranges expanded)."""
    out: list[int] = []
    for m in _PAGE.finditer(without_notes(locator)):
        a = int(m.group(1))
        b = int(m.group(2) or a)
        out.extend(range(min(a, b), max(a, b) + 1))
    return out


def iter_sources(tree: Any) -> list[tuple[tuple[Any, ...], Any]]:
    """(path, value) of every ``source`` text in a YAML tree, and of every item of an
    interpretation's ``evidence`` list (iterative walk)."""
    out: list[tuple[tuple[Any, ...], Any]] = []
    stack: list[tuple[Any, tuple[Any, ...]]] = [(tree, ())]
    while stack:
        node, parts = stack.pop()
        if isinstance(node, dict):
            for k, v in node.items():
                if k == "source":
                    out.append(((*parts, k), v))
                elif k == "evidence" and isinstance(v, list):
                    out.extend(((*parts, k, i), item) for i, item in enumerate(v))
                else:
                    stack.append((v, (*parts, k)))
        elif isinstance(node, list):
            stack.extend((v, (*parts, i)) for i, v in enumerate(node))
    out.sort(key=lambda x: [str(p) for p in x[0]])
    return out


def interpretation_citations(tree: Any) -> list[tuple[tuple[Any, ...], str]]:
    """(path, INT id) of every interpretation cited inside a ``source:`` text of ``tree``."""
    out: list[tuple[tuple[Any, ...], str]] = []
    for parts, value in iter_sources(tree):
        if isinstance(value, str):
            for c in split_citations(value):
                out.extend((parts, m) for m in _INTERPRETATION.findall(c) if c.startswith("INT-"))
    return out


#: The problems of each source text already checked, per registry (a registry is a frozen
#: value: the same catalog read again finds the same entry).
_PROBLEMS: dict[Registry, dict[str, tuple[str, ...]]] = {}


def tree_source_diagnostics(name: str, tree: Any, registry: Registry) -> list[Diagnostic]:
    """A located diagnostic for every ``source:`` of ``tree`` that does not resolve."""
    out = []
    known = _PROBLEMS.get(registry)
    if known is None:
        if len(_PROBLEMS) >= 8:
            _PROBLEMS.clear()
        known = _PROBLEMS[registry] = {}
    for parts, value in iter_sources(tree):
        if not isinstance(value, str):
            continue  # the file's schema reports a source that is not text
        problems = known.get(value)
        if problems is None:
            problems = known[value] = tuple(source_problems(value, registry))
        for problem in problems:
            line, col = locate(tree, parts)
            out.append(Diagnostic(name, line, col, node_path(parts), f"unresolvable source {value!r}: {problem}"))
    out.sort(key=lambda d: (d.line, d.column))
    return out


def registry_for(paths: list[Path]) -> tuple[Registry | None, list[Diagnostic]]:
    """The registry that governs a set of spec files: every ``sources.yaml`` among them
    (merged; a code defined in two of them is an error), else the bundled one."""
    found = [p for p in paths if p.name == SOURCES_FILE]
    if not found:
        try:
            return bundled_registry(), []
        except (SourcesError, OSError) as exc:
            diags = list(exc.diagnostics) if isinstance(exc, SourcesError) else [
                Diagnostic(SOURCES_FILE, 1, 1, "", f"cannot read the bundled sources registry: {exc}")]
            return None, diags
    merged: list[Source] = []
    where: dict[str, str] = {}
    problems: list[Diagnostic] = []
    for p in found:
        try:
            reg = registry_at(p)
        except SourcesError as exc:
            problems.extend(exc.diagnostics)
            continue
        for src in reg.sources:
            if src.code in where:
                problems.append(Diagnostic(str(p), 1, 1, "", (
                    f"source code {src.code!r} is also defined in {where[src.code]}; codes must be unique")))
                continue
            where[src.code] = str(p)
            merged.append(src)
    if problems:
        return None, problems
    return Registry(tuple(merged), str(found[0])), []
