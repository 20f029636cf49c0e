"""The conformance suites the tests share, each generated once per content.

* :func:`suite_dir`: the bundled suite, exactly what ``motionchart vectors`` writes (every
  hand-written scenario and the generated vectors of the systems of
  ``conformance/systems/suite.yaml``).  It is built once into the temporary directory,
  under a name derived from the spec, the scenarios and the code, so that the test
  workers of one run and later runs on the same content share it.
* :func:`small_suite_dir`: the generated vectors of one small servo-axis system only,
  quick to build again (the byte-identity test builds it twice).
"""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path
from typing import Any

from conformance.vectors import build_suite, cached_suite
from statecharts.loader import bundled_spec_dir, load_spec

ROOT = Path(__file__).resolve().parent.parent
CACHE = Path(tempfile.gettempdir()) / "motionchart-test-vectors"
SMALL_SYSTEM = """\
format: motionchart-system/1
name: small
description: one servo axis with five state instructions
source: "MC tests/conformance_helpers.py"
scan_ms: 10
coarse_update_ms: 20
axes:
  - name: Axis
    type: AXIS_SERVO
    program: [MSO, MSF, MASD, MASR, MAFR]
    configurations:
      - {name: servo}
      - {name: unconfigured, variables: {Configured: false}}
environment: [servo_fault, fault_cleared, motion_started, motion_stopped]
max_live_calls: 1
abstraction:
  collapse: [ServoOutput, DriveOutputCommand, TestStatus, TestDirectionForward]
"""


def small_system(tmp: Path) -> Path:
    system = tmp / "small.yaml"
    system.write_text(SMALL_SYSTEM, encoding="utf-8")
    return system


def build_small(tmp: Path) -> Any:
    return build_suite(load_spec(), scenarios=[], systems=[str(small_system(tmp))])


@functools.lru_cache(maxsize=1)
def suite_dir() -> Path:
    roots = [bundled_spec_dir(), ROOT / "scenarios"]
    return cached_suite(CACHE, roots, lambda: build_suite(load_spec(), scenarios=[ROOT / "scenarios"]))


@functools.lru_cache(maxsize=1)
def small_suite_dir() -> Path:
    tmp = Path(tempfile.mkdtemp(prefix="motionchart-small-suite-"))
    from conformance.vectors import write_suite
    write_suite(build_small(tmp), tmp / "vectors")
    return tmp / "vectors"
