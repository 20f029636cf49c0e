"""Model-checker benchmark: states per second and wall time, side by side with a reference.

Run with ``make bench`` (or ``.venv/bin/python benchmarks/bench.py``); no arguments.

1. Every bundled system (``spec/systems/*.yaml``) is checked once with the bundled
   properties: states, transitions, wall and CPU seconds, states per second (of
   each), and the bytes each stored state takes (visited set, packed states, BFS list,
   parent, choice and depth columns).  The machine may be shared: CPU seconds are
   what one core spent, wall seconds include waiting for it.
2. The scaled model: N interchangeable five-state axes (``benchmarks/five_state/``:
   the documented five-state model of ``shared/reference/tooling-notes.md`` §5 written
   as a chart, without the cross-axis interlock, which a per-axis chart cannot state),
   N = 1, 3, 6, 9, 12.  The checker explores it through the whole pipeline (the
   compiled core of ``checker/core.py``, its pieces computed on first use by the scan
   semantics and the IR interpreter, symmetry reduction, packed visited set); the
   reference is a minimal breadth-first search over tuples written by hand below from
   the five-state model, with the same symmetry reduction (sorted tuples) and the same
   count of transitions (distinct successors, the stutter step included).  Both must
   find the same numbers of states and transitions.  Each figure is the median of
   several runs.

The last line is ``checker/reference states-per-second ratio: X.XX``, the median of the
ratios over the scaled sizes.
"""

from __future__ import annotations

import gc
import statistics
import sys
import time
from collections import deque
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from checker.coverage import table as coverage_table
from checker.model import Model
from checker.properties import load_properties
from checker.search import explore, stored_bytes
from checker.system import bundled_systems, load_system
from statecharts.loader import bundled_spec_dir, load_spec

SIZES = (1, 3, 6, 9, 12)
RUNS = 5
FIVE_STATE = Path(__file__).resolve().parent / "five_state"

# --------------------------------------------------------------------------- the reference

READY, DDC, SERVO, FAULTED, SHUTDOWN = range(5)
# MSO, MSF, MDO, MDF, MASD (from every state but Shutdown), MASR, MAFR, fault
MOVES = {
    READY: (SERVO, DDC, SHUTDOWN, FAULTED),
    DDC: (READY, SHUTDOWN, FAULTED),
    SERVO: (READY, SHUTDOWN, FAULTED),
    FAULTED: (SHUTDOWN, READY),
    SHUTDOWN: (READY,),
}


def reference_bfs(n: int) -> tuple[int, int]:
    """(states, transitions) of N five-state axes, axes interchangeable (sorted tuples)."""
    init = (READY,) * n
    parent: dict[tuple[int, ...], tuple[int, ...] | None] = {init: None}
    queue = deque([init])
    transitions = 0
    while queue:
        s = queue.popleft()
        succ = {s}  # a scan in which nothing changes
        for i, local in enumerate(s):
            for tgt in MOVES[local]:
                succ.add(tuple(sorted((*s[:i], tgt, *s[i + 1:]))))
        transitions += len(succ)
        for t in succ:
            if t not in parent:
                parent[t] = s
                queue.append(t)
    return len(parent), transitions


# --------------------------------------------------------------------------- runs


def timed(fn):
    """(result, CPU seconds of this process): the machine is shared, wall time is noisy."""
    t0 = time.process_time()
    out = fn()
    return out, time.process_time() - t0


def main() -> int:
    spec = load_spec()
    props = load_properties(spec)
    print("bundled systems (bundled properties, one run each)")
    print(f"{'system':<14} {'states':>9} {'transitions':>12} {'depth':>6} {'wall s':>7} {'cpu s':>7} "
          f"{'states/s':>9} {'st/cpu-s':>9} {'B/state':>8}  verdict")
    r = None
    for name, path in bundled_systems().items():
        # the previous system's result (its tables, millions of objects) is freed and
        # collected here, not inside the next system's timing
        r = None
        gc.collect()
        model = Model(spec, load_system(path, spec), props)
        c0 = time.process_time()
        r = explore(model, progress=False, max_seconds=240)
        cpu = time.process_time() - c0
        bad = sorted(r.violations)
        verdict = "complete" if r.complete else f"INCOMPLETE ({r.stop_reason})"
        if bad:
            verdict += f", violated: {', '.join(bad)}"
        per_state = stored_bytes(r) / max(r.states, 1)
        print(f"{name:<14} {r.states:>9,} {r.transitions:>12,} {r.depth:>6} {r.seconds:>7.2f} {cpu:>7.2f} "
              f"{r.states_per_second:>9,.0f} {r.states / max(cpu, 1e-9):>9,.0f} {per_state:>8.0f}  {verdict}")
        for what in ("states", "transitions", "error_codes", "cells"):
            t = coverage_table(r, what)
            print(f"{'':<14} coverage {what}: {len(t.reached)}/{t.total}")

    bench_spec = load_spec([bundled_spec_dir(), FIVE_STATE / "chart.yaml"])
    base = load_system(FIVE_STATE / "system.yaml", bench_spec)
    print()
    print(f"scaled five-state model, N non-CIP axes (median of {RUNS} runs, CPU seconds; each checker run "
          "starts from empty tables)")
    print(f"{'N':>3} {'states':>7} {'transitions':>12} {'checker s':>10} {'checker st/s':>13} "
          f"{'reference s':>12} {'reference st/s':>15} {'ratio':>6}")
    ratios = []
    for n in SIZES:
        sysdef = base.scaled(n)
        checker_times = []
        result = None
        for _ in range(RUNS):
            model = Model(bench_spec, sysdef, ())
            result, seconds = timed(lambda model=model: explore(model, progress=False))
            checker_times.append(seconds)
        ref_times = []
        ref = (0, 0)
        for _ in range(RUNS):
            ref, seconds = timed(lambda n=n: reference_bfs(n))
            ref_times.append(seconds)
        assert result is not None
        if (result.states, result.transitions) != ref:
            print(f"MISMATCH at N={n}: checker {result.states}/{result.transitions}, reference {ref[0]}/{ref[1]}")
            return 1
        c_s = statistics.median(checker_times)
        r_s = statistics.median(ref_times)
        c_rate = result.states / c_s
        r_rate = ref[0] / r_s
        ratios.append(c_rate / r_rate)
        print(f"{n:>3} {result.states:>7,} {result.transitions:>12,} {c_s:>10.4f} {c_rate:>13,.0f} "
              f"{r_s:>12.5f} {r_rate:>15,.0f} {c_rate / r_rate:>6.3f}")
    print("state and transition counts of checker and reference agree at every N")
    print(f"checker/reference states-per-second ratio: {statistics.median(ratios):.2f}")
    return 0


if __name__ == "__main__":
    code = main()
    # the ladder interpreter's figures, a separate section (benchmarks/ladder_bench.py)
    from benchmarks.ladder_bench import ladder_benchmark
    ladder_benchmark()
    # the program checker's figures (benchmarks/program_bench.py)
    from benchmarks.program_bench import program_benchmark
    program_benchmark()
    raise SystemExit(code)
