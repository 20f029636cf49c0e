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


def test_a_copy_of_the_spec_is_read_from_the_cache_and_a_changed_file_is_parsed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import shutil

    monkeypatch.setenv("MOTIONCHART_CACHE_DIR", str(tmp_path / "cache"))
    expected = repr(fresh_load())  # fills the cache from the bundled spec
    copy = tmp_path / "spec"
    shutil.copytree(bundled_spec_dir(), copy, ignore=shutil.ignore_patterns("__pycache__", "*.py", "schema", "*.json"))
    errors_yaml = copy / "errors.yaml"
    errors_yaml.write_text(errors_yaml.read_text() + "\n# a user's note\n")
    parsed: list[str] = []
    real = loader.parse_yaml_bytes

    def spy(name: str, raw: bytes, errors: list[loader.Diagnostic], *, what: str = "file") -> object:
        parsed.append(name)
        return real(name, raw, errors, what=what)

    monkeypatch.setattr(loader, "parse_yaml_bytes", spy)
    loader.forget_trees()
    stored = set((tmp_path / "cache" / tree_cache.SUBDIR).glob("*.json"))
    spec = load_spec([copy])
    # the unchanged copies came from the cache (sources.yaml may not be in it: the bundled
    # registry read earlier in this process is memoised apart, so fresh_load may not store it)
    names = [Path(n).name for n in parsed]
    assert "errors.yaml" in names and set(names) <= {"errors.yaml", "sources.yaml"}
    assert repr(spec).replace(str(copy), "<spec>") == expected.replace(str(bundled_spec_dir()), "<spec>")
    assert set((tmp_path / "cache" / tree_cache.SUBDIR).glob("*.json")) == stored  # a user's file is not stored


def test_only_a_document_found_valid_is_remembered(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONCHART_CACHE_DIR", str(tmp_path))
    schema = {"type": "object", "properties": {"a": {"type": "integer"}}, "additionalProperties": False}
    good, bad = {"a": 1}, {"a": "one"}
    assert loader.schema_diagnostics("good.yaml", good, schema, "file") == []
    assert len(list((tmp_path / tree_cache.VALID_SUBDIR).iterdir())) == 1
    loader.forget_trees()  # the in-process memos: the marker on disk is what is read
    assert loader.schema_diagnostics("good.yaml", good, schema, "file") == []
    for _ in range(2):
        found = loader.schema_diagnostics("bad.yaml", bad, schema, "file")
        assert [d.message for d in found] == [found[0].message] and "integer" in found[0].message
    assert len(list((tmp_path / tree_cache.VALID_SUBDIR).iterdir())) == 1
    monkeypatch.setenv("MOTIONCHART_CACHE", "0")
    assert not tree_cache.known_valid("{}", "{}")
