"""``motionchart vectors``, ``conform``, ``adapter`` and ``mutate``: the conformance commands.

Pipeline position: the CLI layer over :mod:`conformance.vectors`, :mod:`conformance.runner`,
:mod:`conformance.adapter` and :mod:`conformance.mutation`.  :func:`register` adds the
subcommands to the ``motionchart`` parser; :func:`dispatch` runs them.

Exit codes: ``vectors`` 0 written, 1 a scenario or the spec is wrong; ``conform`` 0 when
nothing unexpected happened (every vector passed, was skipped or is a listed known
failure), 1 otherwise; ``mutate --score`` 0 when the score reaches ``--min-score``;
2 usage errors everywhere.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any, TextIO

from statecharts.cli_args import EXIT_FINDING as EXIT_FAIL
from statecharts.cli_args import EXIT_OK, EXIT_USAGE, input_error, positive_int
from statecharts.cli_args import positive_seconds as _seconds
from statecharts.diagnostics import InputError

COMMANDS = ("vectors", "conform", "adapter", "mutate")


def register(sub: argparse._SubParsersAction[Any]) -> None:
    v = sub.add_parser("vectors", help="write the conformance suite: one JSON vector per case, and a manifest",
                       description="Export every hand-written scenario and a shortest checker-generated run for "
                                   "each transition, error code, instruction x state cell and check boundary as "
                                   "self-contained JSON vectors (docs/conformance.md).")
    v.add_argument("-o", "--output", required=True, metavar="DIR", help="directory to write (replaced as a whole)")
    v.add_argument("--scenarios", action="append", metavar="DIR", help="scenario directories (default: scenarios)")
    v.add_argument("--system", action="append", metavar="NAME",
                   help="bundled system names or system files to generate from (default: those "
                        "conformance/systems/suite.yaml lists)")
    v.add_argument("--no-generated", action="store_true", help="export the scenarios only")
    v.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")
    v.add_argument("--quiet", "-q", action="store_true", help="no progress lines")

    c = sub.add_parser("conform", help="run the conformance vectors against an implementation's adapter",
                       description="Drive an adapter (a program speaking the JSON Lines protocol of "
                                   "docs/conformance.md) through every vector; print a verdict per vector.")
    c.add_argument("--adapter", required=True, metavar="CMD", help="the adapter command line, e.g. \"motionchart adapter\"")
    c.add_argument("--vectors", metavar="DIR", help="a suite written by `motionchart vectors` (default: the "
                                                    "bundled suite, generated once into the user cache)")
    c.add_argument("--only", action="append", metavar="PATTERN",
                   help="run only vectors whose id contains PATTERN (or matches it as a glob); repeatable")
    c.add_argument("--known-failures", metavar="FILE", help="`VECTOR-ID REASON` lines: expected failures (strict)")
    c.add_argument("--junit", metavar="FILE", help="also write JUnit XML")
    c.add_argument("--json", action="store_true", help="print one JSON object instead of the verdict lines")
    c.add_argument("-j", "--jobs", type=positive_int, default=1, metavar="N", help="run N adapters in parallel")
    c.add_argument("--timeout", type=_seconds, default=10.0, metavar="S", help="per-message time-out (default 10 s)")
    c.add_argument("--vector-timeout", type=_seconds, default=120.0, metavar="S",
                   help="per-vector time-out (default 120 s)")
    c.add_argument("--startup-timeout", type=_seconds, default=60.0, metavar="S",
                   help="time the adapter has to answer hello after it starts (default 60 s)")
    c.add_argument("--max-line", type=positive_int, default=4 * 1024 * 1024, metavar="BYTES",
                   help="longest answer line accepted (default 4 MiB)")
    c.add_argument("--quiet", "-q", action="store_true", help="print only what is not a pass, and the summary")

    a = sub.add_parser("adapter", help="serve the project's engine over the conformance protocol on stdin/stdout")
    a.add_argument("--spec", action="append", metavar="PATH", help="spec files or directories (default: bundled)")
    a.add_argument("--mutant", metavar="ID", help="serve this mutant of the spec (ids as `mutate --score --json` lists them)")

    m = sub.add_parser("mutate", help="mutation score of the conformance suite",
                       description="Build mutants of the spec (dropped guards, swapped targets, changed codes and "
                                   "EXERRs, reordered checks, off-by-one timers, flipped bits), serve each through "
                                   "the reference adapter and report the fraction the vectors kill.")
    m.add_argument("--score", action="store_true", help="compute and print the mutation score")
    m.add_argument("--vectors", metavar="DIR", help="the suite (default: the bundled suite, as for conform)")
    m.add_argument("--sample", type=positive_int, metavar="N", help="only N mutants, spread over the kinds")
    m.add_argument("--subprocess", type=int, default=3, metavar="N",
                   help="also serve N mutants through a `motionchart adapter` child process (default 3)")
    m.add_argument("--min-score", type=float, default=0.95, metavar="F", help="exit 1 below this score (default 0.95)")
    m.add_argument("--json", action="store_true", help="print one JSON object")
    m.add_argument("--quiet", "-q", action="store_true", help="no progress lines")


def dispatch(args: argparse.Namespace) -> int | None:
    cmd = getattr(args, "command", None)
    if cmd not in COMMANDS:
        return None
    if cmd == "vectors":
        return _vectors(args, sys.stdout)
    if cmd == "conform":
        return _conform(args, sys.stdout)
    if cmd == "adapter":
        return _adapter(args)
    return _mutate(args, sys.stdout)


def _progress(quiet: bool) -> Any:
    if quiet:
        return None
    return lambda msg: print(f"vectors: {msg}", file=sys.stderr, flush=True)


def _missing(paths: list[str] | None) -> list[str]:
    return [p if p else repr(p) for p in (paths or []) if not p or not Path(p).exists()]


def _vectors(args: argparse.Namespace, out: TextIO) -> int:
    from conformance import vectors as vec
    from statecharts.loader import load_spec
    missing = _missing((args.scenarios or []) + (args.spec or []))
    if missing:
        print(f"motionchart vectors: no such file or directory: {', '.join(missing)}", file=sys.stderr)
        return EXIT_USAGE
    scenarios = args.scenarios or (["scenarios"] if Path("scenarios").is_dir() else [])
    systems = [] if args.no_generated else (args.system or list(vec.DEFAULT_SYSTEMS))
    try:
        spec = load_spec(args.spec)
        from checker.system import bundled_systems
        known = bundled_systems()
        bad = [s for s in systems if s not in known and not Path(s).is_file()]
        if bad:
            print(f"motionchart vectors: unknown system {', '.join(map(repr, bad))}; bundled systems: "
                  f"{', '.join(n for n in known if n not in ('aoi',))}", file=sys.stderr)
            return EXIT_USAGE
        suite = vec.build_suite(spec, scenarios=scenarios, systems=systems, progress=_progress(args.quiet))
        vec.write_suite(suite, Path(args.output))
    except InputError as exc:
        return input_error(exc)
    except OSError as exc:
        print(f"motionchart vectors: cannot write {args.output}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_FAIL
    cov = vec.manifest(suite)["coverage"]
    kinds: dict[str, int] = {}
    for v in suite.vectors:
        kinds[v["kind"]] = kinds.get(v["kind"], 0) + 1
    out.write(f"wrote {len(suite.vectors)} vectors ({kinds.get('scenario', 0)} from scenarios, "
              f"{kinds.get('generated', 0)} generated) and manifest.json to {args.output}\n")
    reasons: dict[str, int] = {}
    for x in suite.left_out:
        reasons[x["reason"]] = reasons.get(x["reason"], 0) + 1
    for reason, n in reasons.items():
        out.write(f"left out: {n} scenario(s): {reason}\n")
    out.write("coverage of the suite:\n")
    out.write(vec.coverage_text(cov))
    return EXIT_OK


def default_suite_dir(quiet: bool = False) -> Path:
    """The bundled suite, generated once per spec, scenario and code content into the user cache."""
    from conformance import vectors as vec
    from statecharts.loader import bundled_spec_dir, load_spec
    roots = [bundled_spec_dir()] + ([Path("scenarios")] if Path("scenarios").is_dir() else [])
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "motionchart"

    def build() -> vec.Suite:
        if not quiet:
            print(f"conform: generating the bundled suite into {cache} (once; a minute or two)", file=sys.stderr)
        return vec.build_suite(load_spec(), scenarios=list(roots[1:]), progress=_progress(quiet))

    return vec.cached_suite(cache, roots, build)


def _conform(args: argparse.Namespace, out: TextIO) -> int:
    from conformance import runner
    from conformance.vectors import load_vectors
    paths = [p for p in (args.vectors, args.known_failures) if p is not None]
    missing = _missing(paths)
    if missing:
        print(f"motionchart conform: no such file or directory: {', '.join(missing)}", file=sys.stderr)
        return EXIT_USAGE
    try:
        directory = Path(args.vectors) if args.vectors else default_suite_dir(args.quiet or args.json)
        vectors = load_vectors(directory)
        known = runner.load_known_failures(Path(args.known_failures)) if args.known_failures else []
    except InputError as exc:
        return input_error(exc)
    if not vectors:
        print(f"motionchart conform: no vectors in {directory}", file=sys.stderr)
        return EXIT_USAGE
    chosen = runner.select(vectors, args.only or [])
    if not chosen:
        print(f"motionchart conform: no vector matches {', '.join(args.only)}", file=sys.stderr)
        return EXIT_USAGE

    def factory() -> runner.Transport:
        return runner.ProcessTransport(args.adapter, max_line=args.max_line)

    def show(v: runner.Verdict) -> None:
        if args.json or (args.quiet and v.verdict in ("pass", "skipped", "xfail")):
            return
        out.write(v.line() + "\n")
        out.flush()

    result = runner.run(chosen, factory, jobs=args.jobs, known=known, message_timeout=args.timeout,
                        vector_timeout=args.vector_timeout, startup_timeout=args.startup_timeout, on_verdict=show, all_ids=[v["id"] for v in vectors])
    # verdict lines came in completion order; the summary and the files follow the suite's order
    if args.junit:
        try:
            Path(args.junit).write_bytes(runner.junit_xml(result, chosen))
        except OSError as exc:
            print(f"motionchart conform: cannot write {args.junit}: {exc.strerror or exc}", file=sys.stderr)
            return EXIT_FAIL
    if args.json:
        doc = result.as_dict()
        doc["adapter"] = args.adapter
        doc["vectors"] = str(directory)
        json.dump(doc, out, indent=2, sort_keys=True, default=str)
        out.write("\n")
    else:
        for p in result.problems:
            out.write(f"ERROR {p}\n")
        impl = result.implementation
        who = f"{impl.get('name', '?')} {impl.get('version', '')}".strip() if impl else args.adapter
        out.write(f"{result.summary()} ({who})\n")
    return EXIT_OK if result.ok else EXIT_FAIL


def _adapter(args: argparse.Namespace) -> int:
    from conformance.adapter import serve
    from statecharts.loader import load_spec
    try:
        spec = load_spec(args.spec)
    except InputError as exc:
        return input_error(exc)
    if args.mutant:
        from conformance.mutation import find
        try:
            spec = find(spec, args.mutant).build(spec)
        except KeyError:
            print(f"motionchart adapter: no mutant {args.mutant!r}", file=sys.stderr)
            return EXIT_USAGE
    return serve(spec)


def _mutate(args: argparse.Namespace, out: TextIO) -> int:
    if not args.score:
        print("motionchart mutate: nothing to do; give --score", file=sys.stderr)
        return EXIT_USAGE
    from conformance import mutation
    from conformance.vectors import load_vectors
    from statecharts.loader import load_spec
    if args.vectors and _missing([args.vectors]):
        print(f"motionchart mutate: no such file or directory: {args.vectors}", file=sys.stderr)
        return EXIT_USAGE
    try:
        directory = Path(args.vectors) if args.vectors else default_suite_dir(args.quiet or args.json)
        vectors = load_vectors(directory)
        spec = load_spec()
    except InputError as exc:
        return input_error(exc)
    progress = None if (args.quiet or args.json) else (lambda msg: print(f"mutate: {msg}", file=sys.stderr, flush=True))
    explained: dict[str, dict[str, str]] = {}
    manifest = directory / "manifest.json" if directory.is_dir() else None
    if manifest is not None and manifest.is_file():
        try:
            coverage = json.loads(manifest.read_text(encoding="utf-8"))["coverage"]
            explained = {k: dict(coverage[k]["explained"]) for k in ("orders", "refusals") if k in coverage}
        except (ValueError, KeyError, TypeError, AttributeError):
            explained = {}
    try:
        score = mutation.score(spec, vectors, sample=args.sample, subprocess_sample=args.subprocess, progress=progress,
                               explained_orders=explained.get("orders", {}),
                               explained_refusals=explained.get("refusals", {}))
    except mutation.BaselineError as exc:
        print(f"motionchart mutate: {exc}", file=sys.stderr)
        return EXIT_FAIL
    if args.json:
        json.dump(score.as_dict(), out, indent=2, sort_keys=True, default=str)
        out.write("\n")
    else:
        out.write(score.text())
    return EXIT_OK if score.score >= args.min_score else EXIT_FAIL
