"""The project paraphrases the manuals: no run of 12 or more consecutive words of the
source documents appears in its own text.

Words are compared after lower-casing, with every character other than a letter, a
digit or an underscore taken as a separator (so whitespace, line breaks, punctuation
and YAML or Markdown markup do not matter, and an identifier such as ``Ref_AxisPhy``
is one word).  The source documents are OCR text outside the repository
(``shared/seeds/`` beside or above the checkout, or the folder named by the
environment variable ``MOTIONCHART_SEEDS``); without them the test is skipped with that
reason.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

PROJECT = Path(__file__).resolve().parents[1]
RUN = 12
WORD = re.compile(r"[a-z0-9_]+")
#: what is the project's own text
SCANNED = ("spec", "scenarios", "docs", "generated", "tests", "README.md")


def _seed_dir() -> Path | None:
    env = os.environ.get("MOTIONCHART_SEEDS")
    if env:
        return Path(env)
    for parent in PROJECT.parents:
        candidate = parent / "shared" / "seeds"
        if candidate.is_dir():
            return candidate
    return None


def words(text: str) -> list[str]:
    return WORD.findall(text.lower())


def runs(text_words: list[str], grams: set[tuple[str, ...]], n: int = RUN) -> Iterator[str]:
    """Each maximal run of at least ``n`` words of ``text_words`` whose every ``n``-word
    window is in ``grams``."""
    i = 0
    while i <= len(text_words) - n:
        if tuple(text_words[i:i + n]) in grams:
            j = i + n
            while j < len(text_words) and tuple(text_words[j - n + 1:j + 1]) in grams:
                j += 1
            yield " ".join(text_words[i:j])
            i = j
        else:
            i += 1


def grams_of(text_words: list[str], n: int = RUN) -> set[tuple[str, ...]]:
    return {tuple(text_words[i:i + n]) for i in range(len(text_words) - n + 1)}


def project_files() -> Iterator[Path]:
    for name in SCANNED:
        path = PROJECT / name
        if path.is_file():
            yield path
        elif path.is_dir():
            yield from sorted(p for p in path.rglob("*") if p.is_file() and "__pycache__" not in p.parts)


def test_the_run_finder_on_a_planted_copy() -> None:
    source = words("When the axis has moved far enough, the module sets the test voltage back to zero and disables the drive.")
    grams = grams_of(source)
    planted = words("Our note: the Axis has MOVED far enough, the module sets the test voltage back to zero (done).")
    assert list(runs(planted, grams)) == ["the axis has moved far enough the module sets the test voltage back to zero"]
    assert list(runs(words("the axis has moved far enough the module sets a test voltage back"), grams)) == []


def test_no_run_of_twelve_words_is_shared_with_the_source_documents() -> None:
    seeds = _seed_dir()
    if seeds is None or not seeds.is_dir():
        pytest.skip("source documents not found (shared/seeds/ above the checkout, or MOTIONCHART_SEEDS)")
    grams: set[tuple[str, ...]] = set()
    for seed in sorted(seeds.glob("*.txt")):
        grams |= grams_of(words(seed.read_text(encoding="utf-8", errors="replace")))
    assert grams, f"no seed text under {seeds}"
    copied = []
    for path in project_files():
        try:
            text = path.read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            continue  # binary files (images) hold no prose
        copied += [f"{path.relative_to(PROJECT)}: {run!r}" for run in runs(words(text), grams)]
    assert not copied, "text copied from the manuals (paraphrase it):\n" + "\n".join(copied)
