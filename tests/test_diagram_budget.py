"""Every bundled diagram fits a page: rendered to PNG at 96 dpi, its long side is at most
2,400 px, or the diagram is split and each of its parts fits.

The diagrams are those of ``generated/`` (the staleness test keeps them equal to what the
spec gives); they are drawn here with the Graphviz ``dot`` program and measured from the
PNG header, independently of the renderer.  A split chart must have an overview; no
diagram may be shrunk to fit (no ``size``/``ratio`` attribute, which would scale its text).
"""

from __future__ import annotations

import re
import struct
import subprocess
from pathlib import Path

import pytest

from statecharts.render import graphviz_bin

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"
BUDGET = 2400  # px, long side, at 96 dpi
DPI = 96

pytestmark = pytest.mark.skipif(not graphviz_bin.available(), reason="no Graphviz program to render PNGs")


def png_size(dot_file: Path) -> tuple[int, int]:
    program = graphviz_bin.find_program()
    proc = subprocess.run([program, "-Tpng", f"-Gdpi={DPI}", str(dot_file)], capture_output=True, timeout=120,
                          check=True)
    png = proc.stdout
    assert png[:8] == b"\x89PNG\r\n\x1a\n", f"{dot_file.name}: not a PNG"
    width, height = struct.unpack(">II", png[16:24])
    return width, height


def groups(folder: str) -> dict[str, list[Path]]:
    """Whole diagram stem -> the DOT files of its parts (``AxisCIP`` -> ``AxisCIP.overview.dot``, ...)."""
    dots = sorted((GENERATED / folder).glob("*.dot"))
    out: dict[str, list[Path]] = {p.stem: [] for p in dots if "." not in p.stem}
    for p in dots:
        if "." in p.stem:
            out[p.stem.split(".", 1)[0]].append(p)
    return out


CASES = [(folder, stem) for folder in ("diagrams", "flowcharts") for stem in groups(folder)]


def test_there_are_diagrams_to_measure() -> None:
    assert len(groups("diagrams")) >= 4 and len(groups("flowcharts")) >= 15


@pytest.mark.parametrize(("folder", "stem"), CASES, ids=[f"{f}/{s}" for f, s in CASES])
def test_diagram_fits_a_page_or_is_split(folder: str, stem: str) -> None:
    whole = GENERATED / folder / f"{stem}.dot"
    parts = groups(folder)[stem]
    for dot in (whole, *parts):
        text = dot.read_text(encoding="utf-8")
        assert not re.search(r"\b(size|ratio)=", text.split("\n", 3)[1]), f"{dot.name} is scaled to fit"
    if not parts:
        w, h = png_size(whole)
        assert max(w, h) <= BUDGET, f"{folder}/{stem}: {w} x {h} px at {DPI} dpi, over {BUDGET} px and not split"
        return
    if folder == "diagrams":
        assert any(p.stem == f"{stem}.overview" for p in parts), f"split chart {stem} has no overview"
    for p in parts:
        w, h = png_size(p)
        assert max(w, h) <= BUDGET, f"{folder}/{p.name}: {w} x {h} px at {DPI} dpi, over {BUDGET} px"
