"""The independent implementation of examples/adapters/node/ (JavaScript, written from the
documents) runs against the conformance suite and passes every vector it claims.

"Claims": every vector not skipped by what its `hello` declares and not listed, with a
reason, in its known-failures file.  The known failures are strict: one that passes, or
one that names no vector, fails this test.  Without Node.js (``make install`` installs
it with apt-get when run as root) the test is skipped, and says why.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import conformance_helpers
import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "adapters" / "node"
NODE = shutil.which("node") or shutil.which("nodejs")


@pytest.mark.skipif(NODE is None, reason="no `node` program: install Node.js 18+ (make install does it with apt-get as root)")
def test_the_node_implementation_passes_every_vector_it_claims(tmp_path: Path) -> None:
    suite = conformance_helpers.suite_dir()
    ids = {json.loads(p.read_text("utf-8"))["id"] for p in suite.glob("*.json") if p.name != "manifest.json"}
    # the file is written for the whole bundled suite; keep the entries of vectors this suite has
    known = tmp_path / "known-failures.txt"
    lines = (EXAMPLE / "known-failures.txt").read_text(encoding="utf-8").splitlines()
    known.write_text("\n".join(x for x in lines if x.strip().startswith("#") or not x.strip()
                               or _matches_any(x.split()[0], ids)) + "\n", encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "checker", "conform", "--adapter", f"{NODE} {EXAMPLE / 'noncip.js'}",
                        "--vectors", str(suite), "--known-failures", str(known), "--json"],
                       capture_output=True, text=True, timeout=600, cwd=ROOT)
    doc = json.loads(r.stdout)
    bad = [f"{x['verdict']} {x['id']}: {x['detail']}" for x in doc["results"] if x["verdict"] in ("fail", "error", "timeout", "xpass")]
    assert bad == [] and doc["problems"] == [] and r.returncode == 0, "\n".join(bad + doc["problems"]) + r.stderr
    counts = doc["summary"]
    assert doc["implementation"]["name"] == "noncip.js"
    # it claims the non-CIP vectors: most of them run and pass; CIP and MRHD ones are skipped
    assert counts["pass"] > 100 and counts["skipped"] > 20
    skipped = [x for x in doc["results"] if x["verdict"] == "skipped"]
    assert all("unsupported:" in x["detail"] for x in skipped)


def _matches_any(pattern: str, ids: set[str]) -> bool:
    from fnmatch import fnmatchcase
    return any(fnmatchcase(i, pattern) for i in ids)
