"""Shared test set-up: hypothesis profiles and the loaded spec.

Profiles (choose with ``HYPOTHESIS_PROFILE=<name>``, default ``dev``):

* ``dev``  – quick local runs (50 examples, no deadline);
* ``ci``   – reproducible CI runs: 100 examples, derandomized, no deadline, the
  reproduction blob printed on failure, no ``too_slow`` health check (the CI machine
  has 2 cores and is shared);
* ``deep`` – long searches before a release (2000 examples, no deadline).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

try:
    import statecharts  # noqa: F401
except ModuleNotFoundError:  # running without the project installed
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from statecharts import ir
from statecharts.loader import load_spec

# No profile has a deadline or a speed-dependent health check: a test fails because
# behaviour is wrong, never because the machine is busy.
_NOT_TIMED = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("dev", max_examples=50, **_NOT_TIMED)
settings.register_profile("ci", max_examples=100, derandomize=True, print_blob=True, **_NOT_TIMED)
settings.register_profile("deep", max_examples=2000, **_NOT_TIMED)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "dev"))


@pytest.fixture(scope="session")
def spec() -> ir.Spec:
    """The bundled specification, loaded once per test session."""
    return load_spec()
