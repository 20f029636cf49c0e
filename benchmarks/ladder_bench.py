"""Ladder interpreter benchmark: scans per second of a 200-rung routine on 3 axes.

Run by ``make bench`` after the checker benchmark (``benchmarks/bench.py`` calls
:func:`ladder_benchmark`), or alone: ``.venv/bin/python benchmarks/ladder_bench.py``.

The routine (written below, 200 rungs in neutral text) mixes contacts, coils, latches,
one-shots, timers, compares, moves and REAL arithmetic, and its last 6 rungs call MSO
and MSF on three AXIS_CIP_DRIVE axes, toggled every 50 scans.  Printed side by side:

* the whole scan with the routine (program step, coarse update of the three axes);
* the program step alone (the routine without the axes' coarse update);
* today's engine with the same six motion instructions as bare instruction calls
  whose rungs are set from outside (no ladder): the reference.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from statecharts.engine import AxisInstance
from statecharts.loader import load_spec
from statecharts.program.ladder import Ladder
from statecharts.program.reader import parse_program_text
from statecharts.scan import ScanInputs, System

AXES = ("X_axis", "Y_axis", "Z_axis")
SCANS = 400
RUNS = 3


def routine(rungs: int = 200) -> str:
    """A routine of ``rungs`` rungs, the last six of them motion instructions on three axes."""
    out = []
    for i in range(rungs - 6):
        k, b = i % 16, i % 32
        out.append([
            f"XIC(In[{b}])XIO(Stop)OTE(Out[{b}]);",
            f"XIC(Out[{b}])TON(T[{k}],100,0);",
            f"XIC(T[{k}].DN)ONS(Os[{k}])ADD(Count,1,Count);",
            "GRT(Count,1000)MOV(0,Count);",
            f"[XIC(A[{b}]),XIC(B[{b}])XIO(C)]OTL(L[{b}]);",
            f"XIC(Reset)OTU(L[{b}]);",
            f"CPT(R[{k}],R[{k}]*0.5+Count);",
            f"EQU(State,{i % 10})MOV({i},Next);",
        ][i % 8])
    for _n, axis in enumerate(AXES):
        out.append(f"XIC(Run)MSO({axis},{axis}_STAT[0]);")
        out.append(f"XIO(Run)MSF({axis},{axis}_STAT[1]);")
    return "\n".join(out) + "\n"


def _axes(spec):
    return [AxisInstance(spec.chart("AxisCIP"), a, state="Stopped", variables={"Connected": True, "DCBusUp": True})
            for a in AXES]


def _inputs(k: int) -> dict[str, bool]:
    return {"Run": (k // 50) % 2 == 0, f"In[{(k % 4) * 8}]": k % 3 == 0}


def ladder_benchmark() -> None:
    spec = load_spec()
    program = parse_program_text("bench.txt", routine(), spec=spec, form="neutral")
    rungs = sum(len(r.rungs) for r in program.routines)

    def full() -> float:
        system = System(spec, _axes(spec), [], ladder=Ladder(program))
        system.ladder.prescan()
        t = time.perf_counter()
        for k in range(SCANS):
            system.advance(ScanInputs(writes=_inputs(k)))
        return SCANS / (time.perf_counter() - t)

    def program_only() -> float:
        system = System(spec, _axes(spec), [], ladder=Ladder(program))
        ladder = system.ladder
        assert ladder is not None
        ladder.prescan()
        t = time.perf_counter()
        for k in range(SCANS):
            for path, value in _inputs(k).items():
                ladder.write(path, value)
            ladder.scan()
        return SCANS / (time.perf_counter() - t)

    def bare() -> float:
        calls = [(f"{a}_STAT[{n}]", m, a) for a in AXES for n, m in ((0, "MSO"), (1, "MSF"))]
        system = System(spec, _axes(spec), calls)
        t = time.perf_counter()
        for k in range(SCANS):
            run = (k // 50) % 2 == 0
            system.advance(ScanInputs(rungs={name: (run if name.endswith("[0]") else not run) for name, _, _ in calls}))
        return SCANS / (time.perf_counter() - t)

    rates = {name: statistics.median(f() for _ in range(RUNS))
             for name, f in (("full", full), ("program", program_only), ("bare", bare))}
    print()
    print(f"ladder interpreter: {rungs}-rung routine, {len(AXES)} AXIS_CIP_DRIVE axes, {SCANS} scans (median of {RUNS} runs)")
    print(f"{'what':<58} {'scans/s':>9}")
    print(f"{'scan with the routine (program step + coarse update)':<58} {rates['full']:>9,.0f}")
    print(f"{'program step alone (the 200 rungs)':<58} {rates['program']:>9,.0f}")
    print(f"{'reference: engine, the 6 motion instructions as bare calls':<58} {rates['bare']:>9,.0f}")
    print(f"routine/bare scans-per-second ratio: {rates['full'] / rates['bare']:.2f}")


if __name__ == "__main__":
    ladder_benchmark()
