"""Start-up times of the command line: ``motionchart --help`` and one ``diagram`` call.

Run by ``make bench`` (or ``.venv/bin/python benchmarks/startup.py [RUNS]``).  Each
command is started RUNS times (default 7) as a new process, as a user would start it;
the figure is the median wall time, printed beside the interpreter's own start-up
(``python -c pass``, the floor no command can beat) and the target:

* ``motionchart --help``: under 1 s;
* ``motionchart diagram AxisNonCIP`` (load the spec, write the DOT text): under 2 s;
* ``motionchart diagram AxisCIP --part overview -o FILE.svg`` (the same, drawn by Graphviz),
  shown for information.

On a shared machine the figures include waiting for a core; the load average is printed
with them.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
MOTIONCHART = str(BIN / "motionchart") if (BIN / "motionchart").exists() else shutil.which("motionchart")


def median_wall(argv: list[str], runs: int) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(argv, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv: list[str]) -> int:
    runs = int(argv[0]) if argv else 7
    if MOTIONCHART is None:
        print("startup: no motionchart script next to this Python; run make install", file=sys.stderr)
        return 1
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    with tempfile.TemporaryDirectory() as tmp:
        rows = [
            ("python -c pass", [sys.executable, "-c", "pass"], None),
            ("motionchart --help", [MOTIONCHART, "--help"], 1.0),
            ("motionchart diagram AxisNonCIP", [MOTIONCHART, "diagram", "AxisNonCIP"], 2.0),
        ]
        if shutil.which("dot"):
            rows.append(("motionchart diagram AxisCIP --part overview -o x.svg",
                         [MOTIONCHART, "diagram", "AxisCIP", "--part", "overview", "-o", str(Path(tmp) / "x.svg")],
                         None))
        print(f"start-up, median wall seconds of {runs} runs (1-minute load average {load:.1f}):")
        failed = False
        for label, cmd, target in rows:
            t = median_wall(cmd, runs)
            if target is None:
                verdict = "reference: the interpreter alone" if cmd[0] == sys.executable else "(information)"
            else:
                ok = t < target
                failed |= not ok
                verdict = f"target < {target:.1f} s: {'met' if ok else 'NOT met'}"
            print(f"  {label:<55} {t:6.3f} s   {verdict}")
    return 0  # figures, not a test: a busy machine must not fail make bench


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
