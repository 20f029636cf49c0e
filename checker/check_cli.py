"""``motionchart check``: explore a system exhaustively and report verdicts, coverage, statistics.

Pipeline position: the CLI layer over :mod:`checker.system`, :mod:`checker.model`,
:mod:`checker.search` and :mod:`checker.report`.  :func:`register` adds the subcommand to
the ``motionchart`` parser; :func:`dispatch` runs it.  Exit codes: 0 every property
holds, 1 a property is violated (or a user file is wrong), 2 usage error, 3 the search
was incomplete (state or time limit) and nothing was violated.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TextIO

from statecharts.cli_args import EXIT_FINDING, input_error, positive_seconds
from statecharts.cli_args import EXIT_OK as EXIT_OK  # re-exported for the other checker commands
from statecharts.cli_args import EXIT_USAGE as EXIT_USAGE
from statecharts.cli_args import positive_int as positive_int
from statecharts.diagnostics import InputError

if TYPE_CHECKING:  # the checker modules are imported when a check runs, not when the CLI starts
    from checker.properties import Property
    from statecharts import ir

EXIT_VIOLATED = EXIT_FINDING
EXIT_INCOMPLETE = 3
DEFAULT_SYSTEM = "noncip"


#: shared with the other subcommands (statecharts.cli_args)
_positive_float = positive_seconds


#: Most axes ``--axes`` may put in a group (each axis multiplies the state space).
MAX_AXES = 64


def _axis_count(text: str) -> int:
    value = positive_int(text)
    if value > MAX_AXES:
        raise argparse.ArgumentTypeError(f"at most {MAX_AXES} axes per group, got {value}")
    return value


def register(subparsers: argparse._SubParsersAction[Any]) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = subparsers.add_parser(
        "check", help="model-check a system: properties, counterexamples, coverage",
        description="Explore every reachable state of a system (spec/systems/*.yaml) and check the "
                    "properties (spec/properties/*.yaml). Exit 0: all hold; 1: a violation; 3: incomplete.")
    p.add_argument("--system", default=DEFAULT_SYSTEM, metavar="NAME",
                   help=f"a bundled system name or a system file (default: {DEFAULT_SYSTEM}; --list-systems lists them)")
    p.add_argument("--list-systems", action="store_true", help="list the bundled systems and exit")
    p.add_argument("--axes", type=_axis_count, metavar="N", help="use N axes in every axis group of the system")
    p.add_argument("--max-changes", type=_non_negative_int, metavar="N",
                   help="systems that count their changes (add-on instruction systems): allow N environment events "
                        "and input changes per run (default: the system's)")
    p.add_argument("--max-states", type=positive_int, metavar="N", help="stop (incomplete) after N states")
    p.add_argument("--max-seconds", type=_positive_float, metavar="S", help="stop (incomplete) after S seconds")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--counterexamples", metavar="DIR", help="write each counterexample as a scenario file in DIR")
    p.add_argument("--graphml", metavar="FILE", help="write the state graph as GraphML (networkx)")
    p.add_argument("--properties", action="append", metavar="PATH",
                   help="property files or directories (default: the bundled spec/properties)")
    p.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")
    p.add_argument("--no-symmetry", action="store_true", help="explore without symmetry reduction")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    p.add_argument("--program", metavar="FILE",
                   help="check a ladder program (.rll, .txt, .L5X) on its axes from every start "
                        "(docs/program-checking.md); a program system file is given with --system")
    p.add_argument("--property", action="append", metavar="KIND:TEXT",
                   help="program systems: a property, e.g. 'invariant: not (A and B)', "
                        "'always_reachable: NEXTSTATE == 1', 'leads_to: STATE == 9 -> NEXTSTATE == 1 within 50'")
    p.add_argument("--max-events", type=_non_negative_int, metavar="N",
                   help="program systems: at most N environment events per run (default: the system's)")
    p.add_argument("--max-scans", type=positive_int, metavar="N",
                   help="program systems: explore runs up to N scans (default: the system's, else unbounded)")
    from checker import spin_cli
    spin_cli.add_check_options(p)
    return p


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number of at least 0, got {text!r}")
    return value


def dispatch(args: argparse.Namespace) -> int | None:
    """Run ``check`` if it is the command; None for any other command."""
    if getattr(args, "command", None) != "check":
        return None
    return run(args, sys.stdout)


def run(args: argparse.Namespace, out: TextIO) -> int:
    from checker.compile import DivergenceError
    from checker.model import Model, ModelError
    from checker.properties import load_properties
    from checker.report import build_report, text
    from checker.search import explore
    from checker.system import bundled_systems, load_system
    from statecharts.expr import EvalError
    from statecharts.inputs import output_path_problem, path_argument_problem, shown_name
    from statecharts.loader import load_spec

    for opt in ("properties", "spec"):
        for p in getattr(args, opt) or []:
            problem = path_argument_problem(p)
            if problem is not None:
                print(f"motionchart check: {problem}: {shown_name(p)!r}", file=sys.stderr)
                return EXIT_USAGE
    from checker.program_check import bundled_program_systems, is_program_system
    systems = {**bundled_systems(), **bundled_program_systems()}
    program_only = ("axes", "graphml", "properties", "max_changes")
    if getattr(args, "program", None):
        from checker import program_check
        if path_argument_problem(args.program) is not None or not Path(args.program).is_file():
            print(f"motionchart check: --program: no such file {shown_name(args.program)!r}", file=sys.stderr)
            return EXIT_USAGE
        unsupported = [f"--{o.replace('_', '-')}" for o in program_only if getattr(args, o, None)]
        if unsupported or args.system != DEFAULT_SYSTEM:
            print(f"motionchart check: {', '.join(unsupported) or '--system'} cannot be combined with --program",
                  file=sys.stderr)
            return EXIT_USAGE
        return program_check.run(args, None, out)
    if args.list_systems:
        for name, path in systems.items():
            out.write(f"{name}\t{path}\n")
        return EXIT_OK
    if args.system in systems:
        system_path = systems[args.system]
    elif path_argument_problem(args.system) is None and Path(args.system).is_file():
        system_path = Path(args.system)
    else:
        print(f"motionchart check: unknown system {args.system!r}; bundled systems: {', '.join(systems)} "
              "(or give a system file)", file=sys.stderr)
        return EXIT_USAGE
    from checker import spin_cli
    problem = spin_cli.usage_problem(args)
    if problem is not None:
        print(f"motionchart check: {problem}", file=sys.stderr)
        return EXIT_USAGE
    if is_program_system(system_path) and args.engine == "spin":
        print(f"motionchart check: --engine spin does not apply to the program system {args.system!r}",
              file=sys.stderr)
        return EXIT_USAGE
    if is_program_system(system_path):
        from checker import program_check
        unsupported = [f"--{o.replace('_', '-')}" for o in program_only if getattr(args, o, None)] + (
            ["--no-symmetry"] if args.no_symmetry else [])
        if unsupported:
            print(f"motionchart check: {', '.join(unsupported)} do(es) not apply to the program system "
                  f"{args.system!r}", file=sys.stderr)
            return EXIT_USAGE
        return program_check.run(args, system_path, out)
    for opt in ("property", "max_events", "max_scans"):
        if getattr(args, opt, None) is not None:
            print(f"motionchart check: --{opt.replace('_', '-')} applies to program systems only, "
                  f"not {args.system!r}", file=sys.stderr)
            return EXIT_USAGE
    try:
        spec = load_spec(args.spec)
        sysdef = load_system(system_path, spec)
        if args.max_changes is not None:
            if not sysdef.add_ons and sysdef.max_changes is None:
                print(f"motionchart check: --max-changes applies to systems that count their changes (max_changes:, "
                      f"add-on instruction systems), not {args.system!r}", file=sys.stderr)
                return EXIT_USAGE
            sysdef = dataclasses.replace(sysdef, max_changes=args.max_changes)
        if sysdef.add_ons and (args.engine == "spin" or args.axes is not None):
            print(f"motionchart check: {'--engine spin' if args.engine == 'spin' else '--axes'} does not apply to the "
                  f"add-on instruction system {args.system!r}", file=sys.stderr)
            return EXIT_USAGE
        if args.axes is not None:
            sysdef = sysdef.scaled(args.axes)
        props = load_properties(spec, args.properties)
        model = Model(spec, sysdef, props, symmetry=False if args.no_symmetry else None)
    except (InputError, ModelError) as exc:
        return input_error(exc)
    except (EvalError, DivergenceError, ArithmeticError, RecursionError) as exc:
        _cannot_explore(exc, props if "props" in locals() else (), spec if "spec" in locals() else None)
        return EXIT_VIOLATED
    progress = False if (args.quiet or args.json) else None
    for opt, path in (("--graphml", args.graphml), ("--counterexamples", args.counterexamples)):
        problem = output_path_problem(path, directory=opt == "--counterexamples") if path is not None else None
        if problem is not None:
            print(f"motionchart check: {opt} {shown_name(path)!r}: {problem}", file=sys.stderr)
            return EXIT_USAGE
    if args.engine == "spin":
        return spin_cli.check(model, args, out)
    try:
        result = explore(model, max_states=args.max_states, max_seconds=args.max_seconds,
                         keep_graph=args.graphml is not None, progress=progress)
    except (EvalError, DivergenceError, ArithmeticError, RecursionError) as exc:
        _cannot_explore(exc, props, spec)
        return EXIT_VIOLATED
    try:
        report = build_report(result, counterexamples=Path(args.counterexamples) if args.counterexamples else None,
                              graphml=Path(args.graphml) if args.graphml else None)
    except OSError as exc:
        print(f"motionchart check: cannot write {shown_name(exc.filename or '')}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_VIOLATED
    if args.json:
        json.dump(report.as_dict(), out, indent=2, sort_keys=True, default=str)
        out.write("\n")
    else:
        out.write(text(report))
    return report.exit_code


def _cannot_explore(exc: BaseException, props: Iterable[Property], spec: ir.Spec | None) -> None:
    where = _expression_site(props, spec, getattr(exc, "text", ""))
    print(f"{where or 'motionchart check: '}the system cannot be explored: {exc}", file=sys.stderr)


def _expression_site(props: Iterable[Property], spec: ir.Spec | None, text: str) -> str:
    """``file:line: `` of the property or chart element whose expression is ``text``."""
    if not text:
        return ""
    for p in props:
        for key in ("where", "holds", "goal", "trigger", "response", "unless"):
            e = getattr(p, key, None)
            if e is not None and e.text == text:
                return f"{p.file}:{p.line}: property {p.name}: "
    for c in spec.charts if spec is not None else ():
        for t in c.transitions:
            texts = [t.guard.text] if t.guard is not None else []
            texts += [a.value.text for a in t.actions] + [a.text for a in t.actions]
            if text in texts:
                return f"{t.location.file}:{t.location.line}:{t.location.column}: transition {t.id}: "
    return ""


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry (``python -m checker.check_cli``), for use before the main CLI wires ``check``."""
    class _P(argparse.ArgumentParser):
        def error(self, message: str) -> NoReturn:
            self.print_usage(sys.stderr)
            print(f"{self.prog}: error: {message}", file=sys.stderr)
            raise SystemExit(EXIT_USAGE)

    parser = _P(prog="motionchart")
    sub = parser.add_subparsers(dest="command", parser_class=_P)
    register(sub)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    code = dispatch(args)
    return EXIT_USAGE if code is None else code


if __name__ == "__main__":
    raise SystemExit(main())
