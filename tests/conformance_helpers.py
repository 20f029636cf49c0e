"""The conformance suite the tests share: every hand-written scenario, a small system and
the vectors-only CIP system of conformance/systems/, built once per test process."""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path
from typing import Any

from conformance.vectors import SYSTEMS_DIR, build_suite, write_suite
from statecharts.loader import load_spec

ROOT = Path(__file__).resolve().parent.parent
SMALL_SYSTEM = """\
format: motionchart-system/1
name: small
description: one servo axis with five state instructions
source: "tests"
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


def build(tmp: Path) -> Any:
    system = tmp / "small.yaml"
    system.write_text(SMALL_SYSTEM, encoding="utf-8")
    return build_suite(load_spec(), scenarios=[ROOT / "scenarios"],
                       systems=[str(system), str(SYSTEMS_DIR / "cip_unassigned.yaml")])


@functools.lru_cache(maxsize=1)
def suite_dir() -> Path:
    tmp = Path(tempfile.mkdtemp(prefix="motionchart-suite-"))
    write_suite(build(tmp), tmp / "vectors")
    return tmp / "vectors"
