"""Write docs/sources.md from spec/sources.yaml (run by `make generate`)."""

from __future__ import annotations

import sys
from pathlib import Path

from statecharts.render.sources import docs_page
from statecharts.sources import bundled_registry

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    target = ROOT / "docs" / "sources.md"
    text = docs_page(bundled_registry())
    if target.is_file() and target.read_text(encoding="utf-8") == text:
        return 0
    tmp = target.with_name(target.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(target)
    print(f"wrote {target.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
