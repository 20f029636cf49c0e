"""Shared test set-up: hypothesis profiles and the loaded spec.

The hypothesis profile is chosen here and nowhere else; ``make test``, ``.ci/run`` and
a plain ``pytest`` all run ``ci`` unless ``HYPOTHESIS_PROFILE`` names another one:

* ``ci`` (default) – 100 examples per test, derandomized (every run tries the same
  examples, so a failure reproduces), the reproduction blob printed on failure;
* ``dev`` – quick local runs while editing (50 examples, random);
* ``deep`` – long searches before a release (2000 examples), used by ``make deep``.

No profile has a deadline or a speed-dependent health check: a test fails because
behaviour is wrong, never because the machine is busy.  Tests leave ``deadline`` and
the ``too_slow`` health check to the profile.
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

DEFAULT_PROFILE = "ci"
_NOT_TIMED = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("ci", max_examples=100, derandomize=True, print_blob=True, **_NOT_TIMED)
settings.register_profile("dev", max_examples=50, **_NOT_TIMED)
settings.register_profile("deep", max_examples=2000, **_NOT_TIMED)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or DEFAULT_PROFILE)


def pytest_report_header(config: pytest.Config) -> str:
    return f"hypothesis profile: {settings.get_current_profile_name()}"


@pytest.fixture(scope="session")
def spec() -> ir.Spec:
    """The bundled specification, loaded once per test session."""
    return load_spec()
