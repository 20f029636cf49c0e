"""``motionchart export --format promela`` and the SPIN options of ``motionchart check``.

Pipeline position: the CLI layer over :mod:`checker.promela` and :mod:`checker.spin`.
``export`` writes the Promela model of a system; ``check --engine spin`` verifies it
with SPIN and prints the same report as the Python search (text or ``--json``, with an
``engine`` and a ``spin`` entry added).  Exit codes as ``check``: 0 every property holds,
1 a violation (or a user file is wrong, or SPIN failed), 2 usage error, 3 incomplete.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, TextIO

from checker.check_cli import DEFAULT_SYSTEM, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED, positive_int
from statecharts.diagnostics import InputError


def add_check_options(p: argparse.ArgumentParser) -> None:
    """The ``check`` options of the SPIN engine."""
    g = p.add_argument_group("SPIN engine (--engine spin)")
    g.add_argument("--engine", choices=("python", "spin"), default="python",
                   help="python: the built-in breadth-first search (default); spin: export to Promela and run SPIN")
    g.add_argument("--cores", type=positive_int, default=1, metavar="N",
                   help="SPIN: use N cores (breadth-first: -DBFS_PAR; with --dfs: -DNCORE=N)")
    g.add_argument("--dfs", action="store_true",
                   help="SPIN: depth-first search (counterexamples are not the shortest; default breadth-first)")
    g.add_argument("--bitstate", action="store_true",
                   help="SPIN: bitstate hashing (-DBITSTATE): far less memory, coverage not guaranteed")
    g.add_argument("--compress", action="store_true", help="SPIN: state compression (-DCOLLAPSE)")
    g.add_argument("--spin-memory", type=positive_int, default=2048, metavar="MB",
                   help="SPIN: memory limit in megabytes (-DMEMLIM; default 2048)")
    g.add_argument("--spin-hash", type=positive_int, metavar="N", help="SPIN: hash table of 2^N slots (pan -wN)")
    g.add_argument("--spin-depth", type=positive_int, default=10_000_000, metavar="N",
                   help="SPIN: depth limit of a depth-first search (pan -mN; default 10,000,000)")
    g.add_argument("--spin-dir", metavar="DIR",
                   help="SPIN: keep the model, pan and the trails in DIR (default: a temporary directory)")
    g.add_argument("--swarm", type=positive_int, metavar="N",
                   help="SPIN: run a swarm of N randomised bitstate searches (not exhaustive; finds bugs fast)")


def register(subparsers: argparse._SubParsersAction[Any]) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = subparsers.add_parser(
        "export", help="write a system as a model for another tool (Promela for SPIN)",
        description="Write the transition system the checker explores as a Promela model for SPIN: the same "
                    "states, the invariants as asserts, the reachability goals as asserts whose trail is the "
                    "witness. Deterministic output.")
    p.add_argument("--format", choices=("promela",), default="promela", help="output format (default: promela)")
    p.add_argument("--system", default=DEFAULT_SYSTEM, metavar="NAME",
                   help=f"a bundled system name or a system file (default: {DEFAULT_SYSTEM})")
    p.add_argument("--axes", type=positive_int, metavar="N", help="use N axes in every axis group of the system")
    p.add_argument("--properties", action="append", metavar="PATH",
                   help="property files or directories (default: the bundled spec/properties)")
    p.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")
    p.add_argument("--no-symmetry", action="store_true", help="no symmetry reduction (interchangeable axes kept apart)")
    p.add_argument("-o", "--output", metavar="FILE", help="the model file (default: standard output)")
    return p


def dispatch(args: argparse.Namespace) -> int | None:
    if getattr(args, "command", None) != "export":
        return None
    return export(args, sys.stdout)


def _system_path(name: str) -> tuple[Path | None, str | None]:
    from checker.system import bundled_systems
    from statecharts.inputs import path_argument_problem

    systems = bundled_systems()
    if name in systems:
        path = systems[name]
    elif path_argument_problem(name) is None and Path(name).is_file():
        path = Path(name)
    else:
        return None, f"unknown system {name!r}; bundled systems: {', '.join(systems)} (or give a system file)"
    return path, None


def export(args: argparse.Namespace, out: TextIO) -> int:
    from checker.model import Model, ModelError
    from checker.promela import ExportError, build
    from checker.properties import load_properties
    from checker.system import load_system
    from statecharts.inputs import output_path_problem, path_argument_problem, shown_name
    from statecharts.loader import load_spec
    from statecharts.outputs import atomic_write_text

    for opt in ("properties", "spec"):
        for p in getattr(args, opt) or []:
            problem = path_argument_problem(p)
            if problem is not None:
                print(f"motionchart export: {problem}: {shown_name(p)!r}", file=sys.stderr)
                return EXIT_USAGE
    path, why = _system_path(args.system)
    if path is None:
        print(f"motionchart export: {why}", file=sys.stderr)
        return EXIT_USAGE
    if args.output is not None:
        problem = output_path_problem(args.output)
        if problem is not None:
            print(f"motionchart export: -o {shown_name(args.output)!r}: {problem}", file=sys.stderr)
            return EXIT_USAGE
    try:
        spec = load_spec(args.spec)
        sysdef = load_system(path, spec)
        if sysdef.add_ons:
            print(f"motionchart export: {args.system!r} has add-on instruction tags; the Promela export models axes "
                  "and their MOTION_INSTRUCTION tags only", file=sys.stderr)
            return EXIT_USAGE
        if args.axes is not None:
            sysdef = sysdef.scaled(args.axes)
        props = load_properties(spec, args.properties)
        model = Model(spec, sysdef, props, symmetry=False if args.no_symmetry else None)
        pm = build(model, side_tables=None if args.output is not None else False)
    except (InputError, ModelError) as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        return EXIT_VIOLATED
    except ExportError as exc:
        print(f"motionchart export: {exc}", file=sys.stderr)
        return EXIT_VIOLATED
    if args.output is None:
        out.write(pm.text)
    else:
        target = Path(args.output)
        written = [args.output]
        if pm.tables is not None:
            tables = target.with_name(target.stem + "_tables.c")
            atomic_write_text(tables, pm.tables)
            written.append(str(tables))
            atomic_write_text(target, pm.text.replace("TABLES.", target.stem + "_tables."))
        else:
            atomic_write_text(target, pm.text)
        print(f"wrote {' and '.join(written)}: {pm.model.sysdef.name}, {pm.blocks:,} blocks, "
              f"{len(pm.properties)} asserted properties", file=sys.stderr)
    return EXIT_OK


def usage_problem(args: argparse.Namespace) -> str | None:
    """Options that do not go with the engine chosen."""
    if args.engine != "spin":
        spin_only = [f"--{o.replace('_', '-')}" for o in ("dfs", "bitstate", "compress", "spin_dir", "swarm", "spin_hash")
                     if getattr(args, o, None)]
        if args.cores != 1:
            spin_only.append("--cores")
        return f"{', '.join(spin_only)} need(s) --engine spin" if spin_only else None
    bad = [f"--{o.replace('_', '-')}" for o in ("max_states", "graphml") if getattr(args, o, None) is not None]
    return f"{', '.join(bad)} do(es) not apply to --engine spin" if bad else None


def check(model: Any, args: argparse.Namespace, out: TextIO) -> int:
    """``check --engine spin`` on a built model; prints the report, returns the exit code."""
    from checker.promela import ExportError
    from checker.report import build_report, text
    from checker.spin import SpinError, SpinOptions, main_progress, verify

    opts = SpinOptions(search="dfs" if args.dfs else "bfs", cores=args.cores, bitstate=args.bitstate,
                       collapse=args.compress, memory_mb=args.spin_memory, hash_bits=args.spin_hash,
                       max_depth=args.spin_depth, max_seconds=args.max_seconds,
                       workdir=Path(args.spin_dir) if args.spin_dir else None, swarm=args.swarm)
    try:
        run = verify(model, opts, progress=main_progress(args.quiet or args.json))
    except (SpinError, ExportError) as exc:
        print(f"motionchart check: {exc}", file=sys.stderr)
        return EXIT_VIOLATED
    except OSError as exc:
        print(f"motionchart check: {exc.strerror or exc}: {exc.filename or ''}", file=sys.stderr)
        return EXIT_VIOLATED
    report = build_report(run.result, counterexamples=Path(args.counterexamples) if args.counterexamples else None)
    st = run.stats
    spin_info = {
        "states_stored": st.states, "transitions": st.transitions, "depth": st.depth, "errors": st.errors,
        "pan_seconds": st.seconds, "memory_mb": st.memory_mb, "compile_seconds": round(run.compile_seconds, 3),
        "table_seconds": round(run.pm.seconds, 3), "blocks": run.pm.blocks, "flags": run.flags,
        "search": "swarm" if opts.swarm else opts.search, "cores": opts.cores,
        "states_per_second": round(st.states / st.seconds, 1) if st.seconds > 0 else None,
        "swarm_runs": run.swarm_runs, "workdir": str(run.workdir) if opts.workdir else None,
    }
    if args.json:
        d = report.as_dict()
        d["engine"] = "spin"
        d["spin"] = spin_info
        json.dump(d, out, indent=2, sort_keys=True, default=str)
        out.write("\n")
    else:
        body = text(report)
        rate = f", {spin_info['states_per_second']:,} states/s" if spin_info["states_per_second"] else ""
        line = (f"  engine spin ({' '.join(f for f in run.flags if f.startswith('-D'))}): {st.states:,} states stored, "
                f"pan {st.seconds:g} s{rate}, pan compiled in {run.compile_seconds:.1f} s, "
                f"tables {run.pm.seconds:.1f} s ({run.pm.blocks:,} blocks)\n")
        first, rest = body.split("\n", 1)
        second, rest = rest.split("\n", 1)
        out.write(first + "\n" + second + "\n" + line + rest)
    return report.exit_code
