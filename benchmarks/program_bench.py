"""Program checker benchmark: a three-axis routine explored completely, states per second.

Run by ``make bench`` after the checker and ladder benchmarks (``benchmarks/bench.py`` calls
:func:`program_benchmark`), or alone: ``.venv/bin/python benchmarks/program_bench.py``.

The system is ``examples/programs/three_axis_cell.check.yaml``: the 12-rung routine of
``three_axis_cell.txt`` on three AXIS_CIP_DRIVE axes, four free BOOL inputs (any of them
may change at every scan: 16 input combinations per scan), an ``axis_fault`` on any axis
at any scan, at most two per run, and its three properties.  Each run starts from a fresh
model (empty piece tables and a newly generated successor function), so the figures
include compiling the program and computing every piece; the verdicts are checked too.
Printed: states, transitions, controller states (states without the inputs' last
values, whose successors are computed once), wall and CPU seconds, and states per
CPU-second (the machine may be shared), the median of several runs.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from checker.program_check import load_program_system, run_system
from statecharts.loader import load_spec

SYSTEM = ROOT / "examples" / "programs" / "three_axis_cell.check.yaml"
RUNS = 3
TARGET = 20_000


def program_benchmark() -> float:
    spec = load_spec()
    print()
    print("program checker: three_axis_cell (12 rungs, 3 axes, 4 free inputs, up to 2 axis faults per run)")
    rates, walls, cpus = [], [], []
    report = None
    for _ in range(RUNS):
        system = load_program_system(SYSTEM, spec)
        w0, c0 = time.perf_counter(), time.process_time()
        report = run_system(system, spec)
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
        rates.append(len(report.graph.states) / cpus[-1])
    assert report is not None
    g = report.graph
    verdicts = ", ".join(f"{v.prop.name}: {'holds' if v.holds else 'VIOLATED'}" for v in report.verdicts)
    print(f"  {'states':>8} {'transitions':>12} {'ctrl states':>12} {'wall s':>7} {'CPU s':>6} {'states/CPU-s':>13}")
    print(f"  {len(g.states):>8,} {g.transitions:>12,} {g.controller_states:>12,} {statistics.median(walls):>7.2f} "
          f"{statistics.median(cpus):>6.2f} {statistics.median(rates):>13,.0f}")
    print(f"  explored completely: {g.complete}; {verdicts}")
    rate = statistics.median(rates)
    print(f"program checker states per CPU-second: {rate:,.0f} (target {TARGET:,}: "
          f"{'met' if rate >= TARGET else 'NOT met'})")
    return rate


if __name__ == "__main__":
    program_benchmark()
