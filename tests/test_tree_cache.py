"""The on-disk cache of the bundled spec's parsed trees gives the same IR as parsing."""

from __future__ import annotations

from pathlib import Path

import pytest

from statecharts import loader, tree_cache
from statecharts.loader import bundled_spec_dir, load_spec


def fresh_load() -> object:
    loader.forget_trees()  # the in-process memo, so that the disk cache is what is read
    return load_spec()


def test_cached_trees_give_the_same_ir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONCHART_CACHE", "0")
    parsed = fresh_load()
    monkeypatch.setenv("MOTIONCHART_CACHE", "1")
    monkeypatch.setenv("MOTIONCHART_CACHE_DIR", str(tmp_path))
    first = fresh_load()  # fills the cache
    entries = list((tmp_path / tree_cache.SUBDIR).glob("*.json"))
    assert len(entries) == len(list(bundled_spec_dir().rglob("*.yaml")))
    second = fresh_load()  # reads it
    assert repr(parsed) == repr(first) == repr(second)  # locations included


def test_a_damaged_entry_is_a_miss(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONCHART_CACHE_DIR", str(tmp_path))
    raw = (bundled_spec_dir() / "errors.yaml").read_bytes()
    fresh_load()
    assert tree_cache.load(raw) is not None
    for entry in (tmp_path / tree_cache.SUBDIR).glob("*.json"):
        entry.write_text('{"format": "motionchart-tree/1", "tree": [1, 2]}')
    assert tree_cache.load(raw) is None
    assert repr(fresh_load()) == repr(load_spec())


def test_cache_off(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONCHART_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOTIONCHART_CACHE", "0")
    fresh_load()
    assert not (tmp_path / tree_cache.SUBDIR).exists()
