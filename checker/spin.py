"""``motionchart check --engine spin``: the Promela model of a system verified by SPIN.

Pipeline position: :mod:`checker.promela` (the model) -> **checker.spin** (``spin -a``, the C
compiler, ``pan``, its statistics and trails) -> :mod:`checker.report` (the same report as
the Python search: verdicts, counterexample scenarios, coverage).

How a run goes:

1. the model is written to a work directory (``--spin-dir``, else a temporary one);
2. ``spin -a model.pml`` writes ``pan.c``; it is compiled with ``-O2 -DSAFETY -DNOREDUCE``
   (one process: partial-order reduction has nothing to reduce), ``-DBFS`` for the
   default breadth-first search (shortest counterexamples), ``-DNCORE=N`` for a
   multi-core depth-first search, ``-DBFS_PAR`` for a multi-core breadth-first search,
   ``-DBITSTATE`` (bitstate hashing: states are not stored, only hashed into a bit
   array, so coverage is partial) or ``-DCOLLAPSE`` (state compression) on request,
   and ``-DMEMLIM`` (megabytes);
3. ``pan -c0 -e`` runs to the end, writing a trail for each property decided (each
   property fails its assert once per run);
4. each trail is replayed by ``pan -S -r`` (the replay prints one ``MC`` line per scan: the
   input taken), the run is rebuilt on the compiled core and replayed on the concrete
   system exactly as a Python counterexample is (:func:`checker.counterexample.replay`),
   so a counterexample is a scenario file that ``motionchart simulate`` checks on the
   engine.

``--swarm N`` runs SPIN's swarm recipe: N differently seeded bitstate searches with
randomised transition order (``-DBITSTATE -DT_RAND -DP_RAND``, ``-RS<seed>``), each with its
own hash function, run side by side on the cores available; a configuration file for
SPIN's ``swarm`` tool is written next to the model for runs across machines.  A swarm is
not exhaustive: what it finds is real, a property it does not break is "unknown".
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from array import array
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from checker.model import Model
from checker.promela import PromelaModel, build
from checker.search import Coverage, SearchResult, Witness

#: the compiler flags of every build (one process, safety properties only)
BASE_FLAGS = ("-O2", "-w", "-DSAFETY", "-DNOREDUCE", "-DNOFAIR", "-DNOBOUNDCHECK")


class SpinError(RuntimeError):
    """SPIN, the C compiler or ``pan`` failed (the message says which and why)."""


def tools() -> tuple[str | None, str | None]:
    """(spin, C compiler) found on PATH; None for a missing one."""
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    return shutil.which("spin"), cc


def missing_tools() -> str | None:
    """Why the SPIN engine cannot run here, or None."""
    spin, cc = tools()
    missing = [name for name, path in (("spin", spin), ("a C compiler (cc)", cc)) if path is None]
    if not missing:
        return None
    return (f"{' and '.join(missing)} not found; install Debian's packages with `make deps-spin` "
            "(as root) or `apt-get install spin gcc`")


@dataclass
class SpinOptions:
    search: str = "bfs"  # "bfs" | "dfs"
    cores: int = 1
    bitstate: bool = False
    collapse: bool = False
    memory_mb: int = 2048
    hash_bits: int | None = None
    max_depth: int = 10_000_000
    max_seconds: float | None = None
    workdir: Path | None = None
    swarm: int | None = None

    def flags(self) -> list[str]:
        out = list(BASE_FLAGS)
        if self.swarm:
            pass  # a swarm member is a depth-first search of its own
        elif self.cores > 1 and self.search == "bfs":
            out.append("-DBFS_PAR")
        elif self.search == "bfs":
            out.append("-DBFS")
        if self.cores > 1 and self.search == "dfs" and not self.swarm:
            out.append(f"-DNCORE={self.cores}")
        if self.bitstate or self.swarm:
            out.append("-DBITSTATE")
        if self.swarm:
            out += ["-DT_RAND", "-DP_RAND"]
        if self.collapse:
            out.append("-DCOLLAPSE")
        out.append(f"-DMEMLIM={self.memory_mb}")
        return out


@dataclass
class PanStats:
    states: int = 0
    transitions: int = 0
    depth: int = 0
    errors: int = 0
    seconds: float = 0.0
    #: CPU seconds of pan and its worker processes (user + system)
    cpu_seconds: float = 0.0
    memory_mb: float = 0.0
    complete: bool = True
    stop_reason: str | None = None
    #: (property bit, trail file) in the order pan reported them
    trails: list[tuple[int, Path]] = field(default_factory=list)
    output: str = ""


_STORED = re.compile(r"^\s*(\d+) states, stored", re.M)
_TRANS = re.compile(r"^\s*(\d+) transitions \(= ", re.M)
_DEPTH = re.compile(r"depth reached (\d+)")
_ERRORS = re.compile(r"errors: (\d+)")
_ELAPSED = re.compile(r"elapsed time ([0-9.e+]+) seconds")
_MEMORY = re.compile(r"^\s*([0-9.]+)\s+total actual memory usage", re.M)
_ASSERT = re.compile(r"pan:\d+: assertion violated \(viol ?!= ?(\d+)\)")
_WROTE = re.compile(r"pan: wrote (\S+\.trail)")


def parse_pan(text: str, workdir: Path) -> PanStats:
    """The statistics and trails of a ``pan`` run's output (single- or multi-core)."""
    st = PanStats(output=text)
    stored = [int(x) for x in _STORED.findall(text)]
    st.states = stored[-1] if stored else 0
    trans = [int(x) for x in _TRANS.findall(text)]
    st.transitions = trans[-1] if trans else 0
    depths = [int(x) for x in _DEPTH.findall(text)]
    st.depth = max(depths) if depths else 0
    errs = [int(x) for x in _ERRORS.findall(text)]
    st.errors = max(errs) if errs else 0
    el = _ELAPSED.findall(text)
    st.seconds = max(float(x) for x in el) if el else 0.0
    mem = _MEMORY.findall(text)
    st.memory_mb = float(mem[-1]) if mem else 0.0
    pending: list[int] = []
    for line in text.splitlines():
        m = _ASSERT.search(line)
        if m:
            pending.append(int(m.group(1)) - 1)
            continue
        m = _WROTE.search(line)
        if m and pending:
            st.trails.append((pending.pop(0), workdir / Path(m.group(1)).name))
    if "max search depth too small" in text:
        st.complete, st.stop_reason = False, "SPIN's search depth limit was reached (raise --spin-depth)"
    if re.search(r"out of memory|reached -DMEMLIM bound|memory limit", text, re.I):
        st.complete, st.stop_reason = False, "SPIN ran out of memory (raise --spin-memory or use --bitstate)"
    if "Search not completed" in text and st.complete:
        st.complete, st.stop_reason = False, "SPIN did not complete the search"
    return st


def _kill_group(p: subprocess.Popen[str], reap: bool = True) -> None:
    """Stop ``p`` and every process of its group (its session), then reap ``p``."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(p.pid, signal.SIGKILL)
    if reap:
        with contextlib.suppress(subprocess.TimeoutExpired, ValueError, OSError):
            p.communicate(timeout=5)


def run_tool(cmd: list[str], cwd: Path, what: str, timeout: float | None = None) -> str:
    """Run ``cmd`` in ``cwd`` and return its output; ``SpinError`` (naming ``what``) when it
    cannot start, fails (except ``pan``, whose exit status its output explains) or outlasts
    ``timeout`` seconds."""
    # its own process group: pan's parallel search (-u N) forks workers, and a time-out
    # must stop them all, not only the process that was started
    try:
        p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)
    except OSError as exc:
        raise SpinError(f"{what}: cannot run {cmd[0]}: {exc.strerror or exc}") from exc
    try:
        stdout, stderr = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        _kill_group(p)
        raise SpinError(f"{what} did not finish within {timeout:g} s") from exc
    except BaseException:
        _kill_group(p)
        raise
    _kill_group(p, reap=False)  # workers left behind by a finished search
    out = (stdout or "") + (stderr or "")
    if p.returncode != 0 and what != "pan":
        tail = "\n".join(out.strip().splitlines()[-12:])
        raise SpinError(f"{what} failed (exit {p.returncode}):\n{tail}")
    return out


def hash_bits_for(pm: PromelaModel) -> int:
    """A hash table size (2^N slots) for the product of the classes' block counts."""
    estimate = 1.0
    for ci in pm.class_of:
        estimate *= max(len(pm.classes[ci].blocks), 1) * max(pm.core.spu, 1)
        if estimate > 2**40:
            break
    return max(18, min(27, math.ceil(math.log2(max(estimate, 2))) + 1))


@dataclass
class SpinRun:
    pm: PromelaModel
    stats: PanStats
    result: SearchResult
    options: SpinOptions
    workdir: Path
    compile_seconds: float
    flags: list[str]
    swarm_runs: int = 0


def compile_pan(pm: PromelaModel, workdir: Path, opts: SpinOptions, extra_flags: list[str] | None = None
                ) -> tuple[Path, list[str], float]:
    """Write ``model.pml``, run ``spin -a`` and compile ``pan``; (pan, flags, seconds)."""
    spin, cc = tools()
    if spin is None or cc is None:
        raise SpinError(missing_tools() or "SPIN is missing")
    t0 = time.perf_counter()
    (workdir / "model.pml").write_text(pm.text.replace("TABLES.", "model_tables."), encoding="ascii")
    objects: list[str] = []
    if pm.tables is not None:
        (workdir / "model_tables.c").write_text(pm.tables, encoding="ascii")
        run_tool([cc, "-c", "-O0", "-w", "-o", "model_tables.o", "model_tables.c"], workdir, "the C compiler (tables)")
        objects.append("model_tables.o")
    run_tool([spin, "-a", "model.pml"], workdir, "spin -a")
    flags = opts.flags() + (extra_flags or [])
    vector = 16 + 6 * pm.core.naxes + len(pm.model.slots)
    if vector > 900:
        flags.append(f"-DVECTORSZ={vector + 128}")
    run_tool([cc, *flags, "-o", "pan", "pan.c", *objects], workdir, "the C compiler")
    return workdir / "pan", flags, time.perf_counter() - t0


def run_pan(pan: Path, workdir: Path, opts: SpinOptions, pm: PromelaModel, extra: list[str] | None = None) -> PanStats:
    args = [str(pan), "-c0", "-e", "-n"]
    if opts.bitstate or opts.swarm:
        args.append(f"-w{opts.hash_bits or 30}")
    else:
        args.append(f"-w{opts.hash_bits or hash_bits_for(pm)}")
    if opts.search == "dfs":
        args.append(f"-m{opts.max_depth}")
    if opts.cores > 1 and opts.search == "bfs":
        args.append(f"-u{opts.cores}")
    if opts.max_seconds is not None:
        args.append(f"-Q{max(1, math.ceil(opts.max_seconds / 60))}")
    args += extra or []
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = run_tool(args, workdir, "pan", timeout=None if opts.max_seconds is None else opts.max_seconds + 30)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    st = parse_pan(out, workdir)
    st.cpu_seconds = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if re.search(r"elapsed time|pan: rate", out) is None and st.states == 0:
        tail = "\n".join(out.strip().splitlines()[-12:])
        raise SpinError(f"pan did not report a result:\n{tail}")
    if opts.bitstate or opts.swarm:
        st.complete = False
        st.stop_reason = st.stop_reason or ("bitstate hashing: states are hashed, not stored, so some may be missed"
                                            if not opts.swarm else "a swarm of bitstate searches is not exhaustive")
    if opts.max_seconds is not None and "time limit" in out.lower():
        st.complete, st.stop_reason = False, f"time limit of {opts.max_seconds:g} s reached"
    return st


def replay_trail(pan: Path, workdir: Path, trail: Path) -> list[tuple[str, int, int]]:
    """The inputs of a trail: ("initial", j, 0), ("step", axis, local), ("prescan", 0, 0)."""
    out = run_tool([str(pan), "-S", "-r", trail.name], workdir, "pan -r")
    steps: list[tuple[str, int, int]] = []
    for line in out.splitlines():
        parts = line.split()
        if len(parts) < 2 or parts[0] != "MC":
            continue
        if parts[1] == "initial":
            steps.append(("initial", int(parts[2]), 0))
        elif parts[1] == "step":
            steps.append(("step", int(parts[2]), int(parts[3])))
        elif parts[1] == "prescan":
            steps.append(("prescan", 0, 0))
    return steps


def _result(pm: PromelaModel, st: PanStats, runs: list[tuple[int, list[tuple[str, int, int]]]],
            seconds: float) -> SearchResult:
    """A :class:`SearchResult` holding the initial states and each trail's run as a chain of
    parent links, so that :func:`checker.report.build_report` replays and reports it."""
    from checker.search import CoreCodec

    core = pm.core
    model = pm.model
    codec = CoreCodec(core)
    codec.set_format("I")
    encoded: list[bytes] = []
    parent = array("i")
    via = array("i")
    depth_of = array("H")
    initial_assignment: dict[int, int] = {}
    violations: dict[str, Witness] = {}
    reached: dict[str, Witness] = {}
    deadlocks: list[int] = []

    def add(state: tuple[int, ...], par: int, choice: int, depth: int) -> int:
        encoded.append(struct.pack(f"<{core.width}I", *state))
        parent.append(par)
        via.append(choice)
        depth_of.append(min(depth, 65535))
        return len(encoded) - 1

    initial_index: list[int] = []
    for vec, a_index in pm.initials:
        sid = add(pm.core_state(0, vec), -1, a_index, 0)
        initial_assignment[sid] = a_index
        initial_index.append(sid)
    # properties decided in an initial state (the model checks them before its search)
    for a_index, (_state, bad, good) in enumerate(core.initial_states()):
        for p in bad:
            violations.setdefault(p.name, Witness(p.name, -1, a_index, 0))
        for p in good:
            reached.setdefault(p.name, Witness(p.name, -1, a_index, 0))
    dead_props = [p for p in pm.properties if p.kind == "deadlock_free"]
    if dead_props and pm.dead(0, pm.initials[0][0]):
        deadlocks.append(initial_index[0])
        dead_props = []
    for bit, steps in runs:
        prop = pm.properties[bit]
        if prop.kind == "deadlock_free" and deadlocks:
            continue
        if prop.name in violations or prop.name in reached:
            continue
        starts = [i for i, (kind, _a, _k) in enumerate(steps) if kind == "initial"]
        first = steps[starts[-1]][1] if starts else 0
        tail = steps[starts[-1] + 1:] if starts else steps
        vec, _a_index = pm.initials[first]
        phase, blocks = 0, list(vec)
        node = initial_index[first]
        depth = 0
        choice = -1
        for n, (kind, axis, local) in enumerate(tail):
            if kind == "prescan":
                assert core.prescan_index >= 0
                choice = core.prescan_index
                nphase, nblocks, _bad, _good = pm.step(phase, blocks, -1, 0, prescan=True)
            elif axis < 0:
                choice = core.nothing_index
                nphase, nblocks, _bad, _good = pm.step(phase, blocks, -1, 0)
            else:
                choice = pm.alphabet[axis][local]
                nphase, nblocks, _bad, _good = pm.step(phase, blocks, axis, local)
            depth += 1
            if n == len(tail) - 1 and prop.kind != "deadlock_free":
                break  # the last step is the one that decides the property
            node = add(pm.core_state(nphase, nblocks), node, choice, depth)
            phase, blocks = nphase, nblocks
        if prop.kind == "deadlock_free":
            deadlocks.append(node)
        elif prop.kind == "reachable":
            reached[prop.name] = Witness(prop.name, node, choice, depth)
        else:
            violations[prop.name] = Witness(prop.name, node, choice, depth)
    cov = core.cov
    coverage = Coverage(set(cov.configs), set(cov.fired), set(cov.executed), set(cov.errors), set(cov.values),
                        set(cov.checks))
    import resource

    return SearchResult(
        model=model, states=st.states, transitions=st.transitions, depth=st.depth, seconds=seconds,
        complete=st.complete, stop_reason=st.stop_reason, violations=violations, reached=reached,
        deadlocks=deadlocks, coverage=coverage,
        peak_rss_kb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, codec=codec, encoded=encoded,
        parent=parent, via=via, depth_of=depth_of, edges=None, initial_assignment=initial_assignment, core=core)


def verify(model: Model, opts: SpinOptions, *, progress: Callable[[str], None] | None = None,
           pm: PromelaModel | None = None) -> SpinRun:
    """Verify ``model`` with SPIN; the run's statistics and a report-ready result.  ``pm``
    is a model already built from ``model`` (its tables are then not computed again)."""
    problem = missing_tools()
    if problem is not None:
        raise SpinError(problem)
    t0 = time.perf_counter()
    say = progress or (lambda _m: None)
    if pm is None:
        say("computing the per-axis tables")
        pm = build(model)
    if opts.workdir is not None:
        workdir = opts.workdir
        workdir.mkdir(parents=True, exist_ok=True)
        for old in workdir.glob("model.pml*.trail"):
            old.unlink()
        cleanup = None
    else:
        cleanup = tempfile.TemporaryDirectory(prefix="motionchart-spin-")
        workdir = Path(cleanup.name)
    try:
        say(f"compiling pan ({pm.blocks:,} blocks)")
        pan, flags, csec = compile_pan(pm, workdir, opts)
        runs_done = 0
        if opts.swarm:
            st = _swarm(pan, workdir, opts, pm, say)
            runs_done = opts.swarm
        else:
            say("running pan")
            st = run_pan(pan, workdir, opts, pm)
        if opts.cores > 1 and not opts.swarm and st.trails:
            # multi-core trails are not reliable (parallel breadth-first) or stop the
            # search at the first error (multi-core depth-first): the counterexamples come
            # from a single-core breadth-first run, which ends once as many properties
            # are decided as the multi-core run decided
            say("rebuilding the counterexamples with a single-core breadth-first search")
            sub = workdir / "trails"
            sub.mkdir(exist_ok=True)
            for old in sub.glob("*.trail"):
                old.unlink()
            single = SpinOptions(search="bfs", memory_mb=opts.memory_mb, hash_bits=opts.hash_bits,
                                 collapse=opts.collapse, max_seconds=opts.max_seconds)
            decided = len({bit for bit, _t in st.trails})
            stop = decided if opts.search == "bfs" else 0
            pan, flags2, csec2 = compile_pan(pm, sub, single, extra_flags=[f"-DMC_STOP_AFTER={stop}"])
            csec += csec2
            again = run_pan(pan, sub, single, pm)
            if opts.search == "dfs":  # the multi-core depth-first search stopped early
                st = again
                flags = [*flags, "(counterexamples and verdicts: " + " ".join(flags2) + ")"]
            else:
                st.trails = again.trails
            workdir = sub
        runs: list[tuple[int, list[tuple[str, int, int]]]] = []
        best: dict[int, list[tuple[str, int, int]]] = {}
        for bit, trail in st.trails:
            if not trail.exists():
                continue
            steps = replay_trail(pan, workdir, trail)
            if bit not in best or len(steps) < len(best[bit]):
                best[bit] = steps
        runs = sorted(best.items())
        result = _result(pm, st, runs, time.perf_counter() - t0)
        return SpinRun(pm, st, result, opts, workdir, csec, flags, runs_done)
    finally:
        if cleanup is not None:
            cleanup.cleanup()


def swarm_config(pm: PromelaModel, opts: SpinOptions) -> str:
    """A configuration file for SPIN's ``swarm`` tool (``swarm -F swarm.lib``)."""
    minutes = max(1, math.ceil((opts.max_seconds or 600) / 60))
    return "\n".join([
        f"# swarm configuration for system {pm.model.sysdef.name}: run `swarm -F swarm.lib`, then the script it writes",
        "ranges",
        "k 1 4",
        "w 20 32",
        "limits",
        "depth 10000000",
        f"cpus {max(opts.cores, 1)}",
        f"memory {opts.memory_mb}M",
        f"time {minutes}m",
        "vector 512",
        "speed 250000",
        "file model.pml",
        "compilation options",
        "-O2 -DSAFETY -DNOREDUCE -DBITSTATE -DT_RAND -DP_RAND",
        "runtime options",
        "-c0 -e",
        "spin options",
        "-a",
        "",
    ])


def _swarm(pan: Path, workdir: Path, opts: SpinOptions, pm: PromelaModel, say: Callable[[str], None]) -> PanStats:
    """SPIN's swarm recipe: differently seeded, randomised bitstate searches side by side."""
    (workdir / "swarm.lib").write_text(swarm_config(pm, opts), encoding="ascii")
    n = opts.swarm or 1
    jobs = max(1, opts.cores)
    total = PanStats(complete=False, stop_reason="a swarm of bitstate searches is not exhaustive")
    pending = list(range(n))
    running: list[tuple[int, subprocess.Popen[str], Path]] = []
    outputs: list[str] = []
    while pending or running:
        while pending and len(running) < jobs:
            k = pending.pop(0)
            sub = workdir / f"swarm{k}"
            sub.mkdir(exist_ok=True)
            for old in sub.glob("*.trail"):
                old.unlink()
            shutil.copy(pan, sub / "pan")
            shutil.copy(workdir / "model.pml", sub / "model.pml")
            args = [str(sub / "pan"), "-c0", "-e", "-n", f"-RS{1000 + 7919 * k}", f"-h{k % 100}",
                    f"-w{opts.hash_bits or (22 + k % 6)}", f"-k{1 + k % 3}", f"-m{opts.max_depth}"]
            if opts.max_seconds is not None:
                args.append(f"-Q{max(1, math.ceil(opts.max_seconds / 60))}")
            say(f"swarm run {k + 1} of {n}")
            proc = subprocess.Popen(args, cwd=sub, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            running.append((k, proc, sub))
        k, proc, sub = running.pop(0)
        out, _ = proc.communicate()
        outputs.append(out)
        st = parse_pan(out, sub)
        total.states = max(total.states, st.states)
        total.transitions += st.transitions
        total.depth = max(total.depth, st.depth)
        total.errors += st.errors
        total.seconds += st.seconds
        total.memory_mb = max(total.memory_mb, st.memory_mb)
        for bit, trail in st.trails:
            # replay needs the trail next to the model pan was built from
            dest = workdir / f"model.pml{len(total.trails) + 1}.swarm.trail"
            if trail.exists():
                shutil.copy(trail, dest)
                total.trails.append((bit, dest))
    total.output = "\n".join(outputs)
    return total


def main_progress(quiet: bool) -> Callable[[str], None]:
    def say(message: str) -> None:
        if not quiet:
            print(f"spin: {message}", file=sys.stderr, flush=True)
    return say
