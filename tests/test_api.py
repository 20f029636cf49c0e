"""The public API (``motionchart``): one place exports every stable name, and bad
arguments get clear errors naming what is known.  The examples in docs/api.md are the
behavioural tests (they run as doctests)."""

from __future__ import annotations

from pathlib import Path

import pytest

import motionchart
from motionchart import strategies

ROOT = Path(__file__).resolve().parents[1]


def test_every_exported_name_exists_and_is_documented() -> None:
    assert len(motionchart.__all__) == len(set(motionchart.__all__))
    api_doc = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    for name in motionchart.__all__:
        obj = getattr(motionchart, name)
        assert obj.__doc__, f"motionchart.{name} has no docstring"
        if callable(obj) and not isinstance(obj, type) and not name.startswith("_"):
            assert f"{name}(" in api_doc or f"`{name}`" in api_doc, f"docs/api.md does not show motionchart.{name}"
    for name in strategies.__all__:
        assert getattr(strategies, name).__doc__ or name.isupper(), f"strategies.{name} has no docstring"


def test_unknown_names_are_clear_errors() -> None:
    with pytest.raises(KeyError, match=r"unknown chart 'NoChart'; charts: .*AxisNonCIP"):
        motionchart.render_chart("NoChart")
    with pytest.raises(KeyError, match=r"unknown instruction 'NOPE'; instructions: .*MSO"):
        motionchart.render_flowchart("NOPE")
    with pytest.raises(KeyError, match="unknown instruction 'NOPE'"):
        motionchart.error_codes("NOPE")
    with pytest.raises(ValueError, match="unknown format 'gif'"):
        motionchart.render_chart("AxisNonCIP", "gif")  # a wrong format on purpose
    with pytest.raises(FileNotFoundError, match=r"unknown system 'nosuch'; bundled systems: .*noncip"):
        motionchart.check("nosuch")


def test_error_codes_of_mso_are_the_documented_ones() -> None:
    # RM002H MSO error codes, typed in by hand: 6 servo on already / direct drive,
    # 8 wrong axis type, 11 not configured, 12 servo message failure, 20 faulted, 22 in motion
    codes = {r.err for r in motionchart.error_codes("MSO")}
    assert {6, 8, 11, 12, 20, 22} <= codes
    plain = {r.err for r in motionchart.error_codes()}
    assert {6, 8, 11, 12, 13, 20, 22} <= plain


def test_bundled_spec_is_loaded_once() -> None:
    assert motionchart.bundled_spec() is motionchart.bundled_spec()
