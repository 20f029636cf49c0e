"""Every generated artefact as bytes, written to a directory or compared with one.

Pipeline position: IR + scenarios -> renderers -> **generate** -> ``generated/``
(``motionchart generate``, ``motionchart docs``, ``make generate``).

Layout of the output directory::

    README.md, index.md, interpretations.md, error-codes.md, traceability.md, sources.md
    charts/<chart>.md           instructions/<MNEMONIC>.md
    diagrams/<chart>.{dot,mmd,svg}
    flowcharts/<MNEMONIC>.{dot,mmd,svg}
    scxml/<chart>.scxml         (``generate`` only)
    diagrams/<AOI>_recovery.{dot,mmd,svg}   an add-on instruction's recovery chart (its
                                page and flowchart are with the instructions')

The bytes depend only on the spec and the scenarios: sorted or spec-ordered content,
relative paths, no dates.  SVG is the one artefact made by an external program; each
SVG carries the SHA-256 of the DOT it was drawn from (an XML comment), and an SVG whose
DOT has not changed is reused as it is.  So regenerating never churns SVGs, a different
Graphviz build on another machine does not make them "stale", and ``--check`` works on
a machine without ``dot`` as long as no diagram changed.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from statecharts import ir
from statecharts.diagnostics import Diagnostic, SpecError
from statecharts.render import sources as sources_render
from statecharts.render import views
from statecharts.render.addon import RECOVERY_SUFFIX, recovery_chart
from statecharts.render.dot import chart_dot
from statecharts.render.flowchart import flowchart_part_names, instruction_dot
from statecharts.render.graphviz_bin import GraphvizNotFoundError, render
from statecharts.render.labels import spec_path
from statecharts.render.mermaid import chart_mermaid, instruction_mermaid
from statecharts.render.reference import GENERATED_NOTE, reference_pages
from statecharts.render.scxml import chart_scxml
from statecharts.render.traceability import Traceability, trace

#: Sub-directories whose whole content the generator owns (stale files there are removed).
MANAGED_DIRS = ("charts", "instructions", "diagrams", "flowcharts", "scxml")
#: Top-level files the generator owns.
TOP_FILES = ("README.md", "index.md", "interpretations.md", "error-codes.md", "traceability.md", "sources.md")
#: The command that brings ``generated/`` up to date.
FIX_COMMAND = "make generate"
_STAMP = "<!-- motionchart: drawn from DOT with sha256 {} -->"


@dataclass(frozen=True, slots=True)
class Artefacts:
    files: dict[str, bytes]  # path relative to the output directory -> content
    unrendered: tuple[str, ...]  # SVGs that could not be drawn (no Graphviz program)


def svg_stamp(dot_text: str) -> str:
    return _STAMP.format(hashlib.sha256(dot_text.encode("utf-8")).hexdigest())


def stamped_svg(dot_text: str, svg: bytes) -> bytes:
    """Insert the DOT hash after the XML declaration of a rendered SVG."""
    stamp = svg_stamp(dot_text).encode("utf-8")
    head, sep, rest = svg.partition(b"\n")
    if head.startswith(b"<?xml"):
        return head + sep + stamp + b"\n" + rest
    return stamp + b"\n" + svg


def _readme() -> str:
    return "\n".join([
        GENERATED_NOTE, "", "# generated/", "",
        "Artefacts produced from `spec/` by `motionchart generate` (`make generate`). Never edit them by hand: "
        "change the spec, regenerate, commit both. `motionchart generate --check` fails when this directory "
        "is out of date.", "",
        "- [index.md](index.md): the reference (charts, instructions, interpretations, error codes, traceability)",
        "- [sources.md](sources.md): every document the spec cites, with the elements citing each page or section",
        "- `diagrams/`: state diagrams as Graphviz DOT, Mermaid and SVG",
        "- `flowcharts/`: instruction flowcharts as Graphviz DOT, Mermaid and SVG (also those of the "
        "add-on instructions, whose recovery charts are `diagrams/<id>_recovery.*`)",
        "- `charts/`, `instructions/`: one reference page per chart, instruction and add-on instruction",
        "- `scxml/`: each chart as W3C SCXML (loads with `statemachine.io.load(path, format=\"scxml\")`)", "",
    ])


def spec_root(spec: ir.Spec) -> Path | None:
    """The top directory of the spec that holds a ``sources.yaml`` (None: no such directory)."""
    best: Path | None = None
    for f in spec.files:
        for d in Path(f).resolve().parents:
            if (d / sources_render.S.SOURCES_FILE).is_file() and (best is None or len(d.parts) < len(best.parts)):
                best = d
    return best


def sources_page(spec: ir.Spec) -> str | None:
    """generated/sources.md for the spec's own registry, or None when it has none."""
    root = spec_root(spec)
    if root is None:
        return None
    return sources_render.generated_page(sources_render.S.registry_at(root / sources_render.S.SOURCES_FILE), root)


def link_base(out_dir: Path, scenario_roots: Sequence[Path | str]) -> str:
    """Relative path from ``out_dir`` to the directory scenario paths are shown from."""
    for root in scenario_roots:
        r = Path(root)
        if r.exists():
            rel = os.path.relpath(r.resolve().parent, Path(out_dir).resolve())
            rel = Path(rel).as_posix()
            return "" if rel == "." else rel.rstrip("/") + "/"
    return ""


def build(
    spec: ir.Spec,
    scenario_roots: Sequence[Path | str],
    out_dir: Path | str,
    *,
    scxml: bool = True,
    readme: bool = True,
    render_svg: Callable[[str], bytes] | None = None,
    missing_renderer: str = "raise",
    progress: Callable[[str, int | None, int | None], None] | None = None,
) -> Artefacts:
    """Everything for ``out_dir`` (used for relative links and as the SVG cache).

    ``missing_renderer`` says what to do when an SVG must be drawn and no Graphviz
    program is installed: ``"raise"`` (GraphvizNotFoundError) or ``"skip"`` (leave it
    out and list it in ``Artefacts.unrendered``).
    """
    out = Path(out_dir)
    tr: Traceability = trace(spec, scenario_roots, progress)
    if progress is not None:
        progress("writing the reference pages", None, None)
    tr = replace(tr, link_base=link_base(out, scenario_roots))
    text: dict[str, str] = {}
    dots: dict[str, str] = {}
    for c in spec.charts:
        for name in views.view_names(c):
            dots[f"diagrams/{views.stem(c, name)}"] = chart_dot(c, part=name)
        text[f"diagrams/{c.id}.mmd"] = chart_mermaid(c)
        if scxml:
            text[f"scxml/{c.id}.scxml"] = chart_scxml(c, source=spec_path(spec, c.location.file))
    instructions: list[ir.Instruction | ir.AddOnInstruction] = [*spec.instructions, *spec.add_ons]
    for i in instructions:
        for name in flowchart_part_names(spec, i):
            dots[f"flowcharts/{i.id}" + ("" if name == "whole" else f".{name}")] = instruction_dot(spec, i, part=name)
        text[f"flowcharts/{i.id}.mmd"] = instruction_mermaid(spec, i)
    for a in spec.add_ons:
        if a.id + RECOVERY_SUFFIX in {c.id for c in spec.charts}:
            raise SpecError([Diagnostic(a.location.file, a.location.line, 1, "add_on_instruction.id",
                                        f"its recovery chart would overwrite the diagram of chart {a.id}{RECOVERY_SUFFIX}")])
        dots[f"diagrams/{a.id}{RECOVERY_SUFFIX}"] = chart_dot(recovery_chart(spec, a, ordered=True), labels="full")
        text[f"diagrams/{a.id}{RECOVERY_SUFFIX}.mmd"] = chart_mermaid(recovery_chart(spec, a, ordered=True))
    for stem, dot in dots.items():
        text[f"{stem}.dot"] = dot
    text.update(reference_pages(spec, tr, scxml=scxml))
    if readme:
        text["README.md"] = _readme()
        page = sources_page(spec)
        if page is not None:
            text["sources.md"] = page
    files = {k: v.encode("utf-8") for k, v in text.items()}
    unrendered: list[str] = []
    draw = render_svg or (lambda src: render(src, "svg"))
    for n, (stem, dot) in enumerate(sorted(dots.items())):
        name = f"{stem}.svg"
        cached = out / name
        stamp = svg_stamp(dot).encode("utf-8")
        try:
            old = cached.read_bytes() if cached.is_file() else None
        except OSError:
            old = None
        if old is not None and stamp in old[:400]:
            files[name] = old
            continue
        if progress is not None:
            progress(f"drawing {name}", n, len(dots))
        try:
            files[name] = stamped_svg(dot, draw(dot))
        except GraphvizNotFoundError:
            if missing_renderer != "skip":
                raise
            unrendered.append(name)
    return Artefacts(dict(sorted(files.items())), tuple(unrendered))


def managed(path: str) -> bool:
    return path in TOP_FILES or path.split("/", 1)[0] in MANAGED_DIRS


def existing_managed(out_dir: Path) -> set[str]:
    found: set[str] = set()
    if not out_dir.is_dir():
        return found
    for name in TOP_FILES:
        if (out_dir / name).is_file():
            found.add(name)
    for d in MANAGED_DIRS:
        root = out_dir / d
        if root.is_dir():
            found.update(p.relative_to(out_dir).as_posix() for p in root.rglob("*") if p.is_file())
    return found


@dataclass(frozen=True, slots=True)
class WriteReport:
    written: tuple[str, ...]  # created or changed
    unchanged: int
    removed: tuple[str, ...]


def write(out_dir: Path | str, files: dict[str, bytes], *, prune: bool) -> WriteReport:
    """Write ``files`` under ``out_dir`` (only those whose bytes differ); with ``prune``,
    delete managed files that are no longer produced."""
    out = Path(out_dir)
    written: list[str] = []
    unchanged = 0
    for rel, data in files.items():
        target = out / rel
        try:
            if target.is_file() and target.read_bytes() == data:
                unchanged += 1
                continue
        except OSError:
            pass
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name(target.name + ".tmp")
        tmp.write_bytes(data)
        os.replace(tmp, target)
        written.append(rel)
    removed: list[str] = []
    if prune:
        for rel in sorted(existing_managed(out) - set(files)):
            (out / rel).unlink()
            removed.append(rel)
        for d in MANAGED_DIRS:
            root = out / d
            if root.is_dir():
                for sub in sorted((p for p in root.rglob("*") if p.is_dir()), reverse=True):
                    if not any(sub.iterdir()):
                        sub.rmdir()
                if not any(root.iterdir()):
                    root.rmdir()
    return WriteReport(tuple(written), unchanged, tuple(removed))


def stale_files(out_dir: Path | str, fresh_dir: Path | str) -> list[str]:
    """Managed files that differ between ``out_dir`` and a fresh generation in ``fresh_dir``."""
    out, fresh = Path(out_dir), Path(fresh_dir)
    names = existing_managed(out) | existing_managed(fresh)
    stale = []
    for rel in sorted(names):
        a, b = out / rel, fresh / rel
        if not a.is_file() or not b.is_file() or a.read_bytes() != b.read_bytes():
            stale.append(rel)
    return stale

