"""The Sphinx extension (``motionchart.sphinx``): a tiny documentation project using
its three directives builds with ``-W`` (warnings are errors) and its HTML holds the
drawn diagrams and the error-code table; an unknown chart fails the build with a
located message."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

pytest.importorskip("sphinx", reason="sphinx is a test dependency (make install)")
from sphinx.cmd.build import build_main

from statecharts.render import graphviz_bin

CONF = 'project = "drive docs"\nextensions = ["motionchart.sphinx"]\n'

INDEX = """\
Drive documentation
===================

.. motionchart-chart:: AxisNonCIP
   :caption: Operating states of a non-CIP axis

.. motionchart-flowchart:: MSO

.. motionchart-errors:: MSO
"""


def build(tmp_path: Path, index: str) -> tuple[int, str, Path]:
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(CONF, encoding="utf-8")
    (src / "index.rst").write_text(index, encoding="utf-8")
    out = tmp_path / "html"
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = build_main(["-W", "-q", "-b", "html", "-d", str(tmp_path / "doctrees"), str(src), str(out)])
    return code, err.getvalue(), out


@pytest.mark.skipif(not graphviz_bin.available(), reason="Graphviz draws the diagrams (make install provides it)")
def test_a_project_using_the_directives_builds_with_warnings_as_errors(tmp_path: Path) -> None:
    code, err, out = build(tmp_path, INDEX)
    assert code == 0, err
    html = (out / "index.html").read_text(encoding="utf-8")
    assert html.count("<svg") == 2, "one drawn state diagram and one flowchart"
    # the chart's documented operating states (001) appear in the drawing
    for label in ("Axis Ready", "Servo Control", "Shutdown"):
        assert label in html
    assert "Operating states of a non-CIP axis" in html
    # MSO on a wrong axis type gives ERR 8 (RM002H); the table names it
    assert "WRONG_AXIS_TYPE" in html and "<table" in html


def test_an_unknown_chart_fails_the_build_with_its_location(tmp_path: Path) -> None:
    code, err, _out = build(tmp_path, "Title\n=====\n\n.. motionchart-chart:: NoSuchChart\n")
    assert code != 0
    assert "index.rst:4" in err and "unknown chart 'NoSuchChart'" in err and "AxisNonCIP" in err
