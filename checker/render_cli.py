"""The ``diagram``, ``docs`` and ``generate`` commands of ``motionchart``.

Pipeline position: CLI layer over :mod:`statecharts.render`.  :func:`register` adds the
three sub-commands to the main parser's sub-parsers; :func:`dispatch` runs one and
returns its exit code (``None`` for a command that is not one of these).

* ``motionchart diagram CHART [--format dot|svg|png|pdf|mermaid] [-o FILE] [--labels events|guards|full]
  [--part NAME] [--spec PATH]``: a chart's state diagram, or, for an instruction mnemonic (``MSO``), its
  flowchart (``--part overview`` or a composite state's id for a large chart, ``part1`` ... for a long
  flowchart);
  for an add-on instruction, ``<ID>`` draws its flowchart and ``<ID>_recovery`` its
  recovery chart.
  The format defaults to the output file's suffix (``.dot``/``.gv``, ``.svg``, ``.png``,
  ``.mmd``), else ``dot``.  Without ``-o`` the text goes to standard output; PNG needs
  ``-o``.
* ``motionchart docs -o DIR [--scenarios DIR] [--spec PATH]``: the Markdown reference
  with its diagrams.
* ``motionchart generate [-o DIR] [--check] [--scenarios DIR] [--spec PATH]``: every
  artefact into ``generated/``; ``--check`` regenerates into a temporary directory,
  lists what differs and exits 1 (fix: ``make generate``).

Exit codes: 0 success, 1 bad input (unknown chart, spec error, unwritable output, no
Graphviz program for an image, stale ``generated/``), 2 usage.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

from statecharts.diagnostics import InputError
from statecharts.inputs import output_path_problem, path_argument_problem, shown_name
from statecharts.outputs import replace_folder
from statecharts.progress import Progress

COMMANDS = ("diagram", "docs", "generate")
FORMATS = ("dot", "svg", "png", "pdf", "mermaid")
#: Output formats by file extension (``-o x.pdf``); any other extension needs ``--format``.
SUFFIX_FORMATS = {".dot": "dot", ".gv": "dot", ".svg": "svg", ".png": "png", ".pdf": "pdf", ".mmd": "mermaid",
                  ".mermaid": "mermaid"}
#: Formats Graphviz draws (binary ones need ``-o FILE``).
DRAWN = ("svg", "png", "pdf")
BINARY = ("png", "pdf")
EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


def register(subparsers: Any) -> None:
    """Add ``diagram``, ``docs`` and ``generate`` to an argparse sub-parsers object."""
    d = subparsers.add_parser(
        "diagram", help="draw a chart's state diagram or an instruction's flowchart",
        description="Draw a chart's state diagram, or the flowchart of an instruction (CHART = mnemonic, e.g. MSO).")
    d.add_argument("chart", metavar="CHART",
                   help="chart id (e.g. AxisNonCIP), instruction mnemonic (e.g. MSO), add-on instruction id "
                        "(its flowchart) or <id>_recovery (its recovery chart)")
    d.add_argument("--format", "-f", choices=FORMATS,
                   help="output format (default: from -o's extension: .dot .gv .svg .png .pdf .mmd .mermaid; "
                        "else dot)")
    d.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of standard output")
    d.add_argument("--labels", choices=("events", "guards", "full"), default=None,
                   help="how much text edges carry: events (triggers only), guards (event [guard], the default), "
                        "full (with actions)")
    d.add_argument("--part", metavar="NAME", default="whole",
                   help="a large chart's overview or one composite state (e.g. --part overview, --part Standby), "
                        "or part1, part2 ... of a long flowchart (default: whole)")
    d.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")

    r = subparsers.add_parser(
        "docs", help="write the Markdown reference (charts, instructions, codes, traceability)",
        description="Write the Markdown reference with its diagrams into DIR.")
    r.add_argument("-o", "--output", metavar="DIR", required=True, help="output directory")
    r.add_argument("--scenarios", action="append", metavar="DIR",
                   help="scenario directories run for the traceability matrix (default: scenarios)")
    r.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")

    g = subparsers.add_parser(
        "generate", help="write every generated artefact (diagrams, docs, SCXML) into generated/",
        description="Write diagrams (.dot, .mmd, .svg), flowcharts, the reference docs and SCXML into DIR.")
    g.add_argument("-o", "--output", metavar="DIR", default="generated", help="output directory (default: generated)")
    g.add_argument("--check", action="store_true",
                   help="regenerate into a temporary directory and exit 1 if DIR differs")
    g.add_argument("--scenarios", action="append", metavar="DIR",
                   help="scenario directories run for the traceability matrix (default: scenarios)")
    g.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")


def dispatch(args: argparse.Namespace) -> int | None:
    """Run the command in ``args`` if it is one of ours; its exit code, else ``None``."""
    command = getattr(args, "command", None)
    if command not in COMMANDS:
        return None
    from statecharts.render.graphviz_bin import RenderError
    from statecharts.render.scxml import ScxmlUnsupported

    prog = f"motionchart {command}"
    try:
        missing = [shown_name(p) for p in (args.spec or []) if path_argument_problem(p) is not None]
        if missing:
            return _fail(prog, f"no such file or directory: {', '.join(missing)}", EXIT_USAGE)
        if command == "diagram":
            return _diagram(args, prog)
        if command == "docs":
            return _docs(args, prog)
        return _generate(args, prog)
    except InputError as exc:
        for diag in exc.diagnostics:
            print(diag, file=sys.stderr)
        return EXIT_FAIL
    except (RenderError, ScxmlUnsupported) as exc:
        return _fail(prog, str(exc))
    except BrokenPipeError:
        # the reader went away (``| head``): say nothing more, not even at exit
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_FAIL


def _fail(prog: str, message: str, code: int = EXIT_FAIL) -> int:
    print(f"{prog}: error: {message}", file=sys.stderr)
    return code


def _os_message(exc: OSError) -> str:
    where = exc.filename if exc.filename else ""
    return f"cannot write {where}: {exc.strerror or exc}" if where else f"cannot write: {exc.strerror or exc}"


def output_format(given: str | None, output: str | None) -> tuple[str, str | None]:
    """(format, problem): ``--format`` if given, else the output file's extension, else DOT.

    An extension that names no format is refused rather than guessed (``-o x.jpg``), and
    a ``--format`` that contradicts a known extension too (``-o x.pdf --format dot``)."""
    suffix = Path(output).suffix.lower() if output else ""
    from_suffix = SUFFIX_FORMATS.get(suffix)
    if given is not None:
        fmt = given
        if from_suffix is not None and from_suffix != given:
            return fmt, f"--format {given} contradicts the extension of {output!r} ({from_suffix}); drop one of them"
    elif output and suffix and from_suffix is None:
        known = " ".join(sorted(SUFFIX_FORMATS))
        return "dot", (f"cannot tell the format from the extension {suffix!r} of {output!r}; use one of {known} "
                       f"or give --format {{{','.join(FORMATS)}}}")
    else:
        fmt = from_suffix or "dot"
    if fmt in BINARY and not output:
        return fmt, f"{fmt.upper()} is binary: give an output file with -o FILE.{fmt}"
    return fmt, None


def _diagram(args: argparse.Namespace, prog: str) -> int:
    from statecharts import ir
    from statecharts.loader import load_spec
    from statecharts.render import UnknownTarget, chart_dot, chart_mermaid, instruction_dot, instruction_mermaid, resolve

    fmt, problem = output_format(args.format, args.output)
    if problem:
        return _fail(prog, problem, EXIT_USAGE)
    spec = load_spec(args.spec)
    try:
        target = resolve(spec, args.chart)
    except UnknownTarget as exc:
        return _fail(prog, str(exc), EXIT_USAGE)
    from statecharts.render.dot import DEFAULT_LABELS
    from statecharts.render.flowchart import flowchart_part_names
    from statecharts.render.views import view_names

    recovery = isinstance(target, ir.Chart) and target.id not in {c.id for c in spec.charts}
    labels = args.labels or ("full" if recovery else DEFAULT_LABELS)  # an add-on's recovery: draw its calls
    part = args.part
    names = view_names(target) if isinstance(target, ir.Chart) else flowchart_part_names(spec, target)
    if isinstance(target, ir.Chart):
        from statecharts.render.views import leaf_composites
        names = (*names, *(s.id for s in leaf_composites(target) if s.id not in names))
    folded = [n for n in names if n.casefold() == part.casefold()]
    if not folded:
        return _fail(prog, f"{target.id} has no part {part!r}; parts: {', '.join(names)}", EXIT_USAGE)
    part = folded[0]
    if fmt == "mermaid" and (part != "whole" or args.labels not in (None, "full")):
        return _fail(prog, "the Mermaid text is of the whole diagram with full labels; drop --part/--labels",
                     EXIT_USAGE)
    if isinstance(target, ir.Chart):
        text = chart_mermaid(target) if fmt == "mermaid" else chart_dot(target, labels=labels, part=part)
    else:
        text = (instruction_mermaid(spec, target) if fmt == "mermaid"
                else instruction_dot(spec, target, labels=labels, part=part))
    return _emit(args, prog, fmt, text)


def _emit(args: argparse.Namespace, prog: str, fmt: str, text: str) -> int:
    from statecharts.render.graphviz_bin import render

    data: bytes = render(text, fmt) if fmt in DRAWN else text.encode("utf-8")
    if not args.output:
        sys.stdout.write(data.decode("utf-8"))  # text formats only: PNG and PDF need -o
        sys.stdout.flush()
        return EXIT_OK
    out = Path(args.output)
    if out.is_dir():
        return _fail(prog, f"{out} is a directory; give a file name")
    try:
        out.write_bytes(data)
    except OSError as exc:
        return _fail(prog, _os_message(exc))
    return EXIT_OK


def _scenario_roots(args: argparse.Namespace) -> list[str]:
    return list(args.scenarios) if args.scenarios else ["scenarios"]


def _check_out_dir(out: Path, prog: str) -> int | None:
    if out.exists() and not out.is_dir():
        return _fail(prog, f"{out} exists and is not a directory")
    problem = output_path_problem(str(out), directory=True)
    if problem is not None:  # found before the work, not after it
        return _fail(prog, f"cannot write {shown_name(out)}: {problem}")
    return None


def _check_inputs(args: argparse.Namespace, prog: str) -> int | None:
    """The exit code when the output directory or a scenario directory is unusable."""
    bad = _check_out_dir(Path(args.output), prog)
    if bad is not None:
        return bad
    missing = [shown_name(s) for s in (args.scenarios or []) if path_argument_problem(s) is not None]
    if missing:
        return _fail(prog, f"no such scenario directory: {', '.join(missing)}", EXIT_USAGE)
    return None


def _docs(args: argparse.Namespace, prog: str) -> int:
    from statecharts.loader import load_spec
    from statecharts.render.generate import build, write

    out = Path(args.output)
    bad = _check_inputs(args, prog)
    if bad is not None:
        return bad
    with Progress(prog) as progress:
        progress.update("loading the spec")
        spec = load_spec(args.spec)
        artefacts = build(spec, _scenario_roots(args), out, scxml=False, readme=False,
                          progress=progress.update)
        progress.update(f"writing {len(artefacts.files)} files")
        try:
            report = replace_folder(out, lambda folder: write(folder, artefacts.files, prune=False))
        except OSError as exc:
            progress.close()
            return _fail(prog, _os_message(exc))
    print(f"{out}: {len(artefacts.files)} files ({len(report.written)} written, {report.unchanged} unchanged); "
          f"start at {out / 'index.md'}")
    return EXIT_OK


def _generate(args: argparse.Namespace, prog: str) -> int:
    from statecharts.loader import load_spec
    from statecharts.render.generate import FIX_COMMAND, build, stale_files, write

    out = Path(args.output)
    bad = _check_inputs(args, prog)
    if bad is not None:
        return bad
    with Progress(prog) as progress:
        progress.update("loading the spec")
        spec = load_spec(args.spec)
        if args.check:
            artefacts = build(spec, _scenario_roots(args), out, missing_renderer="skip",
                              progress=progress.update)
            progress.update("comparing")
            with tempfile.TemporaryDirectory(prefix="motionchart-generate-") as tmp:
                write(tmp, artefacts.files, prune=False)
                stale = stale_files(out, tmp)
            progress.close()
            if not stale:
                print(f"{out}: up to date ({len(artefacts.files)} files)")
                return EXIT_OK
            print(f"{out} is out of date; {len(stale)} file(s) differ from what the spec generates:", file=sys.stderr)
            for rel in stale:
                note = " (no Graphviz program here to redraw it)" if rel in artefacts.unrendered else ""
                print(f"  {out.as_posix().rstrip('/')}/{rel}{note}", file=sys.stderr)
            print(f"run `{FIX_COMMAND}` (or `motionchart generate`) to update it", file=sys.stderr)
            return EXIT_FAIL
        artefacts = build(spec, _scenario_roots(args), out, progress=progress.update)
        progress.update(f"writing {len(artefacts.files)} files")
        try:
            report = replace_folder(out, lambda folder: write(folder, artefacts.files, prune=True))
        except OSError as exc:
            progress.close()
            return _fail(prog, _os_message(exc))
        progress.close()
        print(f"{out}: {len(artefacts.files)} files ({len(report.written)} written, {report.unchanged} unchanged, "
              f"{len(report.removed)} removed)")
        return EXIT_OK
