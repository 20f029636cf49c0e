"""SPIN against the Python checker: states per second, and the largest N each handles in 60 s.

Run by ``make bench`` (or ``.venv/bin/python benchmarks/spin_bench.py``); no arguments.

Three engines explore the same transition system (symmetry reduction off on both sides,
so that the product of the axes is what is searched): the Python search
(:func:`checker.search.explore`), SPIN on one core (``-DBFS``) and SPIN on two cores
(``-DBFS_PAR``, ``pan -u2``), both on the model of :mod:`checker.promela`.

1. the five-state model (``benchmarks/five_state/``) at N = 9 and the largest bundled
   system (``noncip_pairs``): states (the engines must agree), wall seconds of the search,
   CPU seconds, states per wall second and per CPU second; for SPIN also the seconds
   spent computing the per-axis tables and compiling ``pan``;
2. the largest N of the five-state model each engine explores completely within 60 s of
   wall time, end to end (for SPIN: tables, ``spin -a``, the C compiler and ``pan``),
   searching upwards from N = 9 (downwards if N = 9 does not fit); a run is stopped at
   60 s.

The machine may be shared: the load average is printed; CPU seconds are what the
engine's processes spent, wall seconds include waiting for a core.
"""

from __future__ import annotations

import os
import resource
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from checker import spin
from checker.model import Model
from checker.promela import PromelaModel, build
from checker.properties import load_properties
from checker.search import explore
from checker.system import SystemDef, bundled_systems, load_system
from statecharts import ir
from statecharts.loader import bundled_spec_dir, load_spec

FIVE = ROOT / "benchmarks" / "five_state"
LIMIT = 60.0
ENGINES = ("python", "spin-1", "spin-2")


def _cpu() -> float:
    me = resource.getrusage(resource.RUSAGE_SELF)
    return me.ru_utime + me.ru_stime


_BUILT: dict[str, PromelaModel] = {}


def run(engine: str, spec: ir.Spec, sd: SystemDef, props: Any, limit: float | None) -> dict[str, Any]:
    """One exploration; wall and CPU seconds, states, completeness.  The two SPIN engines
    share the tables of a model (computed by the first, its seconds reported by both)."""
    model = Model(spec, sd, props, symmetry=False)
    if engine == "python":
        c0 = _cpu()
        r = explore(model, progress=False, max_seconds=limit)
        return {"states": r.states, "wall": r.seconds, "cpu": _cpu() - c0, "complete": r.complete,
                "total": r.seconds}
    cores = 2 if engine == "spin-2" else 1
    t0 = time.perf_counter()
    opts = spin.SpinOptions(cores=cores, memory_mb=6144, max_seconds=limit)
    key = f"{sd.name}/{len(model.axes)}"
    built = _BUILT.get(key)
    reused = built.seconds if built is not None else 0.0  # counted as if computed again
    try:
        if built is None:
            built = _BUILT[key] = build(model)
        sr = spin.verify(model, opts, pm=built)
    except spin.SpinError:  # stopped by the time limit
        total = time.perf_counter() - t0
        return {"states": 0, "wall": total, "cpu": 0.0, "complete": False, "total": total, "tables": 0.0, "compile": 0.0}
    total = time.perf_counter() - t0 + reused
    st = sr.stats
    return {"states": st.states, "wall": st.seconds, "cpu": st.cpu_seconds, "complete": st.complete,
            "total": total, "tables": sr.pm.seconds, "compile": sr.compile_seconds}


def _row(name: str, engine: str, r: dict[str, Any]) -> str:
    rate = r["states"] / r["wall"] if r["wall"] > 0 else float("nan")
    crate = r["states"] / r["cpu"] if r["cpu"] > 0 else float("nan")
    if engine == "spin-2":  # the parallel workers' CPU time is not all reported to this process
        return (f"{name:<16} {engine:<8} {r['states']:>10,} {r['wall']:>8.2f} {'n/a':>8} {rate:>11,.0f} {'n/a':>11} "
                f"{r['total']:>8.1f}  tables {r['tables']:.1f} s, compile {r['compile']:.1f} s"
                + ("" if r["complete"] else "  INCOMPLETE"))
    extra = f"  tables {r['tables']:.1f} s, compile {r['compile']:.1f} s" if "tables" in r else ""
    done = "" if r["complete"] else "  INCOMPLETE"
    return (f"{name:<16} {engine:<8} {r['states']:>10,} {r['wall']:>8.2f} {r['cpu']:>8.2f} {rate:>11,.0f} "
            f"{crate:>11,.0f} {r['total']:>8.1f}{extra}{done}")


def main() -> int:
    if spin.missing_tools() is not None:
        print(f"SPIN benchmark skipped: {spin.missing_tools()}")
        return 0
    load = os.getloadavg()
    print()
    print(f"SPIN and the Python checker, symmetry off (load average {load[0]:.1f} {load[1]:.1f} {load[2]:.1f} "
          f"on {os.cpu_count()} cores)")
    print(f"{'model':<16} {'engine':<8} {'states':>10} {'wall s':>8} {'cpu s':>8} {'states/s':>11} "
          f"{'st/cpu-s':>11} {'total s':>8}")
    five_spec = load_spec([bundled_spec_dir(), FIVE / "chart.yaml"])
    five = load_system(FIVE / "system.yaml", five_spec)
    at: dict[tuple[str, int], dict[str, Any]] = {}
    status = 0
    for engine in ENGINES:
        r = run(engine, five_spec, five.scaled(9), (), None)
        at[(engine, 9)] = r
        print(_row("five-state N=9", engine, r), flush=True)
    if len({at[(e, 9)]["states"] for e in ENGINES}) != 1:
        print("MISMATCH: the engines found different numbers of states")
        status = 1
    spec = load_spec()
    props = load_properties(spec)
    largest = "noncip_pairs"
    sd = load_system(bundled_systems()[largest], spec)
    counts = set()
    for engine in ENGINES:
        r = run(engine, spec, sd, props, None)
        counts.add(r["states"])
        print(_row(largest, engine, r), flush=True)
    if len(counts) != 1:
        print("MISMATCH: the engines found different numbers of states")
        status = 1
    print()
    print(f"largest N of the five-state model explored completely within {LIMIT:g} s of wall time "
          "(SPIN: tables, compile and search)")
    for engine in ENGINES:
        def fits(n: int, engine: str = engine) -> bool:
            r = at.get((engine, n))
            if r is None:
                r = run(engine, five_spec, five.scaled(n), (), LIMIT)
                at[(engine, n)] = r
            return bool(r["complete"] and r["total"] <= LIMIT)

        n = 9
        if fits(n):
            while fits(n + 1):
                n += 1
        else:
            while n > 1 and not fits(n - 1):
                n -= 1
            n -= 1
        r = at.get((engine, n))
        detail = f" ({r['states']:,} states in {r['total']:.1f} s)" if r is not None else ""
        print(f"  {engine:<8} N = {n}{detail}", flush=True)
    return status


if __name__ == "__main__":
    raise SystemExit(main())
