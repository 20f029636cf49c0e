"""The ``motionchart`` command line (also ``python -m checker``).

Pipeline position: the outermost layer; it calls the loader, the scenario runner and
(later) the checker and renderers, and turns their results into text, JSON and exit
codes.  Exit codes: 0 success, 1 a user file is wrong or an expectation failed,
2 usage error.  A user error is printed as ``file:line:col: node-path: message`` lines,
never as a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.metadata
import io
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TextIO

from checker import check_cli, render_cli, spin_cli
from conformance import cli as conformance_cli
from statecharts.diagnostics import Diagnostic, InputError
from statecharts.inputs import path_argument_problem, shown_name

if TYPE_CHECKING:  # the loader and the engine are imported by the commands that need them
    from statecharts.scenario import ScenarioResult

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)


def _version() -> str:
    """The installed distribution's version (pyproject.toml is the one place it is written)."""
    try:
        return importlib.metadata.version("motionchart")
    except importlib.metadata.PackageNotFoundError:  # running from a checkout that is not installed
        return "0+unknown"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="motionchart", description="Executable, checkable specification of Logix motion behaviour.")
    parser.add_argument("--version", action="version", version=f"motionchart {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    v = sub.add_parser("validate", help="check spec files (default: the bundled spec), or ladder program files")
    v.add_argument("paths", nargs="*", metavar="PATH",
                   help="spec files or directories; or program files (.rll/.txt rung text, .L5X exports)")
    v.add_argument("--json", action="store_true", help="print one JSON object")

    s = sub.add_parser("simulate", help="run scenarios on the engine and check their expectations")
    s.add_argument("scenarios", nargs="+", metavar="SCENARIO", help="scenario files or directories")
    s.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.add_argument("--quiet", "-q", action="store_true", help="print only the summary line of each scenario")
    s.add_argument("--summary", action="store_true", help="print only failed scenarios and the closing count")

    check_cli.register(sub)
    spin_cli.register(sub)
    render_cli.register(sub)
    conformance_cli.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code (also for ``--version``/``--help``/usage errors)."""
    _tolerant_streams()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse exits for --version, --help and usage errors
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        code = _run_command(args)
        sys.stdout.flush()
        return code
    except InputError as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        return EXIT_FAIL
    except BrokenPipeError:
        # the reader went away (``| head``): say nothing more, not even at exit
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except KeyboardInterrupt:
        print("motionchart: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:
        # output that cannot be written (a full disk, /dev/full, a path under a file)
        target = f" {shown_name(exc.filename)}" if getattr(exc, "filename", None) else " the output"
        print(f"motionchart {args.command}: cannot write{target}: {exc.strerror or exc}", file=sys.stderr)
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_FAIL


def _run_command(args: argparse.Namespace) -> int:
    if args.command == "validate":
        return _validate(args, sys.stdout)
    if args.command == "simulate":
        return _simulate(args, sys.stdout)
    for extension in (check_cli, spin_cli, render_cli, conformance_cli):
        code: int | None = extension.dispatch(args)
        if code is not None:
            return code
    return EXIT_USAGE


def _tolerant_streams() -> None:
    """Spec text can hold any character; never fail printing it on a narrow console encoding."""
    for stream in (sys.stdout, sys.stderr):
        if isinstance(stream, io.TextIOWrapper):
            with contextlib.suppress(ValueError, OSError):
                stream.reconfigure(errors="backslashreplace")


def _missing(paths: Sequence[str]) -> list[str]:
    # an empty argument would name the current directory and load everything under it
    out = []
    for p in paths:
        problem = path_argument_problem(p)
        if problem is None:
            continue
        name = repr(p) if not p else shown_name(p)
        out.append(name if problem == "no such file or directory" else f"{name} ({problem})")
    return out


def _validate(args: argparse.Namespace, out: TextIO) -> int:
    """Load the whole spec, its add-on instructions included, as every command loads it;
    every problem is reported."""
    from statecharts.loader import load_spec

    missing = _missing(args.paths)
    if missing:
        print(f"motionchart validate: no such file or directory: {', '.join(missing)}", file=sys.stderr)
        return EXIT_USAGE
    if args.paths and all(_is_program_file(p) for p in args.paths):
        return _validate_programs(args, out)
    from statecharts.progress import Progress

    problems: list[Diagnostic] = []
    spec = None
    progress = Progress("motionchart validate")
    progress.update("loading the spec")
    try:
        spec = load_spec(args.paths or None)
    except InputError as exc:
        problems.extend(exc.diagnostics)
    progress.close()
    if problems or spec is None:
        if args.json:
            json.dump({"valid": False, "errors": [str(d) for d in problems],
                       "diagnostics": [d.as_dict() for d in problems]}, out, indent=2, sort_keys=True)
            out.write("\n")
        for d in problems:
            print(d, file=sys.stderr)
        print(f"{len(problems)} error(s)", file=sys.stderr)
        return EXIT_FAIL
    add_ons = [_add_on_summary(a) for a in spec.add_ons]
    summary: dict[str, object] = {
        "valid": True,
        "files": len(spec.files),
        "charts": [c.id for c in spec.charts],
        "states": sum(len(c.states) for c in spec.charts),
        "transitions": sum(len(c.transitions) for c in spec.charts),
        "instructions": [i.id for i in spec.instructions],
        "checks": sum(len(i.checks) for i in spec.instructions),
        "error_codes": len(spec.errors),
        "interpretations": len(spec.interpretations),
        "add_on_instructions": add_ons,
    }
    if args.json:
        json.dump(summary, out, indent=2, sort_keys=True)
        out.write("\n")
    else:
        line = (
            f"spec OK: {summary['files']} files, {len(spec.charts)} chart(s) "
            f"({summary['states']} states, {summary['transitions']} transitions), "
            f"{len(spec.instructions)} instructions ({summary['checks']} checks), "
            f"{summary['error_codes']} error codes, {summary['interpretations']} interpretations"
        )
        for a in add_ons:
            line += (f", add-on instruction {a['id']} ({a['checks']} checks, {a['error_codes']} codes, "
                     f"{a['recovery_states']} recovery states, {a['recovery_transitions']} transitions; "
                     f"calls {', '.join(a['calls'])})")  # type: ignore[arg-type]  # a list of mnemonics
        out.write(line + "\n")
    return EXIT_OK


def _add_on_summary(a: Any) -> dict[str, object]:
    """What ``validate`` says of one add-on instruction (``a``: an ``ir.AddOnInstruction``)."""
    from statecharts.loader import bundled_spec_dir

    calls = sorted({s.call.instruction for s in a.recovery.states if s.call} | {a.rung_false.abort_call} - {None})
    root = bundled_spec_dir()
    file = Path(a.location.file)
    shown = f"spec/{file.relative_to(root).as_posix()}" if file.is_relative_to(root) else file.name
    return {"id": a.id, "file": shown, "checks": len(a.checks), "error_codes": len(a.errors),
            "recovery_states": len(a.recovery.states), "recovery_transitions": len(a.recovery.transitions),
            "calls": calls}


def _is_program_file(path: str) -> bool:
    from statecharts.program.reader import RUNG_SUFFIXES
    return Path(path).is_file() and Path(path).suffix.lower() in (*RUNG_SUFFIXES, ".l5x")


def _validate_programs(args: argparse.Namespace, out: TextIO) -> int:
    from statecharts.loader import load_spec

    """``validate PROGRAM...``: read each program and print what it holds (docs/programs.md)."""
    from statecharts.program.reader import load_program, probe_compile, summary

    spec = load_spec()
    results: list[dict[str, object]] = []
    problems: list[Diagnostic] = []
    for path in args.paths:
        try:
            program = load_program(path, spec=spec)
            probe_compile(program, spec)
        except InputError as exc:
            problems.extend(exc.diagnostics)
            continue
        results.append(summary(program))
    if args.json:
        json.dump({"valid": not problems, "programs": results, "errors": [str(d) for d in problems],
                   "diagnostics": [d.as_dict() for d in problems]}, out, indent=2, sort_keys=True)
        out.write("\n")
    else:
        for r in results:
            routines = r["routines"]
            assert isinstance(routines, dict)
            out.write(f"program {r['program']} ({r['file']}, {r['form']}): {len(routines)} routine(s), "
                      f"{r['rungs']} rungs, {r['tags']} tags\n")
            out.write("  routines: " + ", ".join(f"{n} ({k} rungs{', main' if n == r['main_routine'] else ''})"
                                                 for n, k in routines.items()) + "\n")
            axes = r["axes"]
            assert isinstance(axes, dict)
            if axes:
                out.write("  axes: " + ", ".join(f"{n} ({t})" for n, t in axes.items()) + "\n")
            used = r["instructions"]
            assert isinstance(used, dict)
            out.write("  instructions: " + ", ".join(f"{m} x{k}" for m, k in used.items()) + "\n")
            warnings = r["warnings"]
            assert isinstance(warnings, list)
            for w in warnings:
                out.write(f"  note: {w}\n")
    for d in problems:
        print(d, file=sys.stderr)
    if problems:
        print(f"{len(problems)} error(s)", file=sys.stderr)
    return EXIT_FAIL if problems else EXIT_OK


def _print_table(result: ScenarioResult, out: TextIO) -> None:
    _print_header(result.scenario, out)
    for row in result.rows:
        _print_row(row, out)


def _print_header(scenario: Any, out: TextIO) -> None:
    out.write(f"scenario: {scenario.name}  ({scenario.file})\n")
    out.write(f"{'scan':>5}  {'step':<28}  changes\n")


def _print_row(row: Any, out: TextIO) -> None:
    from statecharts.scenario import scan_cell, scan_label

    label = f"{row.step + 1}" + (f" {row.step_name}" if row.step_name else "")
    changes = "  ".join(f"{scan_label(o, f)}={scan_cell(a)}" for o, f, _b, a in row.changes) or "-"
    cu = "" if row.record.coarse_update else " (no coarse update)"
    out.write(f"{row.record.index:>5}  {label[:28]:<28}  {changes}{cu}\n")


def _result_json(result: ScenarioResult) -> dict[str, object]:
    from statecharts.scenario import scan_label

    return {
        "scenario": result.scenario.name,
        "file": result.scenario.file,
        "passed": result.passed,
        "scans": [
            {
                "scan": r.record.index,
                "step": r.step + 1,
                "coarse_update": r.record.coarse_update,
                "changes": {scan_label(o, f): a for o, f, _b, a in r.changes},
            }
            for r in result.rows
        ],
        "failures": [
            {"step": m.step + 1, "step_name": m.step_name, "scan": m.scan, "line": m.line, "object": m.target,
             "field": m.field, "expected": m.expected, "actual": m.actual}
            for m in result.mismatches
        ],
    }


def _simulate(args: argparse.Namespace, out: TextIO) -> int:
    from statecharts.loader import load_spec
    from statecharts.scenario import load_scenario, run_scenario, scenario_files

    missing = _missing(args.scenarios + (args.spec or []))
    if missing:
        print(f"motionchart simulate: no such file or directory: {', '.join(missing)}", file=sys.stderr)
        return EXIT_USAGE
    files = scenario_files(args.scenarios)
    if not files:
        print(f"motionchart simulate: no scenario files (*.yaml, *.yml, *.json) found in "
              f"{', '.join(shown_name(p) for p in args.scenarios)}", file=sys.stderr)
        return EXIT_USAGE
    try:
        spec = load_spec(args.spec)
    except InputError as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        print(f"{len(exc.diagnostics)} error(s) in the spec", file=sys.stderr)
        if args.json:
            json.dump({"results": [], "input_errors": [str(d) for d in exc.diagnostics], "passed": 0, "failed": 0},
                      out, indent=2, sort_keys=True)
            out.write("\n")
        return EXIT_FAIL
    results: list[ScenarioResult] = []
    input_errors: list[str] = []
    from statecharts.progress import Progress

    streaming = not (args.json or args.quiet or args.summary)
    # the streamed tables show the work as it goes; the other modes get a status line
    progress = Progress("motionchart simulate", enabled=False if streaming else None)
    for n, f in enumerate(files):
        progress.update(f"running {shown_name(f)}", n, len(files))
        try:
            scenario = load_scenario(f, spec)
            if streaming:
                _print_header(scenario, out)
            # the table is printed as the scans run; only --json needs the rows afterwards
            result = run_scenario(scenario, spec, on_row=(lambda row: _print_row(row, out)) if streaming else None,
                                  keep_rows=bool(args.json))
        except InputError as exc:
            progress.clear()
            input_errors.extend(str(d) for d in exc.diagnostics)
            for d in exc.diagnostics:
                print(d, file=sys.stderr)
            continue
        results.append(result)
        if args.summary and result.passed:
            continue
        progress.clear()
        if not args.json:
            verdict = "PASS" if result.passed else "FAIL"
            out.write(f"{verdict} {scenario.name} ({result.scans} scans)\n")
            for m in result.mismatches:
                out.write(f"  {m.located(scenario.file)}\n")
            if not (args.quiet or args.summary):
                out.write("\n")
    progress.close()
    failed = [r for r in results if not r.passed]
    if args.json:
        json.dump({"results": [_result_json(r) for r in results], "input_errors": input_errors,
                   "passed": len(results) - len(failed), "failed": len(failed)}, out, indent=2, sort_keys=True, default=str)
        out.write("\n")
    elif len(files) > 1 or input_errors or args.summary:
        out.write(f"scenarios: {len(results) - len(failed)} passed, {len(failed)} failed, "
                  f"{len(files) - len(results)} invalid\n")
    return EXIT_FAIL if failed or input_errors else EXIT_OK
