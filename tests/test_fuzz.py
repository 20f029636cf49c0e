"""The structural fuzzer of tests/fuzzing.py on a small sample: no input may end in
anything but a located error or success, within the time and memory bounds.

``make deep`` runs the same harness on at least 10,000 mutated specs and 10,000 mutated
scenarios; this sample keeps ``make test`` within its budget.  The harness runs in a
child process so that its address-space cap (1 GiB above its baseline) cannot touch
the test session.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

FUZZER = Path(__file__).with_name("fuzzing.py")


def test_mutated_inputs_give_located_errors_or_success() -> None:
    proc = subprocess.run(
        [sys.executable, str(FUZZER), "--specs", "60", "--scenarios", "60", "--systems", "20", "--properties", "20",
         "--memory-gib", "1"],
        capture_output=True, text=True, timeout=1800, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for kind in ("spec", "scenario", "system", "properties"):
        assert f"{kind}: tried " in proc.stdout
    assert "other exceptions: 0" in proc.stdout
