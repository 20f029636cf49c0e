"""The examples in README.md and docs/*.md run as tests, so the documentation cannot go stale.

Three kinds of example are checked here (``>>>`` blocks in ``docs/*.md`` are run by
pytest itself, through ``--doctest-glob=*.md`` in ``pyproject.toml``):

* fenced ```` ```yaml ```` blocks whose text starts with
  ``format: motionchart-scenario/1`` are written to a temporary file, loaded with
  :func:`~statecharts.scenario.load_scenario` and run with
  :func:`~statecharts.scenario.run_scenario`; every expectation must hold;
* fenced ```` ```yaml ```` blocks that name a file (see below) and start with
  ``format: motionchart-spec/1`` must load, together with the bundled specification,
  without a diagnostic;
* fenced ```` ```console ```` blocks: each ``$ motionchart ...`` line is run through
  :func:`checker.cli.main` from the repository root, and what it prints (standard
  output and standard error, in order) must equal the lines that follow it up to the
  next ``$`` line, trailing whitespace ignored; ``...`` in the block matches any text,
  as in a doctest with ELLIPSIS; ``$`` lines for other programs (``make``) are not run;
* ``>>>`` blocks in README.md (outside pytest's test paths) run as a doctest here.

A fenced block may name a file in its info string, e.g. ```` ```yaml file=my_scenarios/x.yaml ````.
Console commands then see that file at that relative path: they run in a temporary
directory that holds the named files and a symbolic link to every top-level entry of
the repository, so ``scenarios/...`` and ``spec/...`` resolve exactly as in the
repository root.  A named path must not start with an existing top-level entry (the
repository is never written to).  A named block that does not start with a format line
(for example one that is wrong on purpose and starts with a comment) is only written,
not checked.
"""

from __future__ import annotations

import contextlib
import doctest
import io
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from checker.cli import main
from statecharts import ir
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.scenario import load_scenario, run_scenario

ROOT = Path(__file__).resolve().parents[1]
DOC_FILES = (ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")))
SCENARIO_MARK = "format: motionchart-scenario/1"
SPEC_MARK = "format: motionchart-spec/1"
FENCE = re.compile(r"^(?P<indent> *)(?P<fence>```+|~~~+)(?P<info>[^`\n]*)$")


@dataclass(frozen=True)
class Block:
    file: Path
    line: int  # 1-based line of the opening fence
    lang: str
    text: str
    name: str | None  # the `file=` of the info string, if any

    @property
    def id(self) -> str:
        return f"{self.file.relative_to(ROOT)}:{self.line}"


def fenced_blocks(path: Path) -> list[Block]:
    """Every fenced code block of a Markdown file, with its info-string language."""
    blocks: list[Block] = []
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, indent = m["fence"], len(m["indent"])
        words = m["info"].strip().split()
        lang = (words or [""])[0].lower()
        name = next((w.removeprefix("file=") for w in words[1:] if w.startswith("file=")), None)
        body: list[str] = []
        j = i + 1
        while j < len(lines) and not (lines[j].strip().startswith(fence) and not lines[j].strip().strip(fence[0])):
            body.append(lines[j][indent:] if lines[j][:indent].strip() == "" else lines[j])
            j += 1
        blocks.append(Block(path, i + 1, lang, "\n".join(body) + "\n", name))
        i = j + 1
    return blocks


ALL_BLOCKS = [b for f in DOC_FILES if f.exists() for b in fenced_blocks(f)]
SCENARIO_BLOCKS = [b for b in ALL_BLOCKS if b.lang in ("yaml", "yml") and b.text.lstrip().startswith(SCENARIO_MARK)]
CONSOLE_BLOCKS = [b for b in ALL_BLOCKS if b.lang == "console"]
NAMED_BLOCKS = [b for b in ALL_BLOCKS if b.name]
SPEC_BLOCKS = [b for b in NAMED_BLOCKS if b.text.lstrip().startswith(SPEC_MARK)]


@dataclass(frozen=True)
class Command:
    block: Block
    line: int
    argv: tuple[str, ...]
    expected: str


def motionchart_commands(block: Block) -> list[Command]:
    """The ``$ motionchart ...`` commands of a console block with their expected output."""
    out: list[Command] = []
    current: tuple[int, list[str]] | None = None
    expected: list[str] = []

    def flush() -> None:
        if current is not None and current[1] and current[1][0] == "motionchart":
            out.append(Command(block, current[0], tuple(current[1][1:]), "\n".join(expected)))

    for k, line in enumerate(block.text.splitlines()):
        if line.startswith("$ "):
            flush()
            current = (block.line + 1 + k, shlex.split(line[2:]))
            expected = []
        else:
            expected.append(line)
    flush()
    return out


COMMANDS = [c for b in CONSOLE_BLOCKS for c in motionchart_commands(b)]


def normalise(text: str) -> str:
    lines = [line.rstrip() for line in text.splitlines()]
    while lines and not lines[-1]:
        lines.pop()
    while lines and not lines[0]:
        lines.pop(0)
    return "\n".join(lines) + "\n"


def workspace(tmp_path: Path) -> Path:
    """A directory that looks like the repository root plus the named example files."""
    work = tmp_path / "root"
    work.mkdir()
    for entry in ROOT.iterdir():
        (work / entry.name).symlink_to(entry)
    for block in NAMED_BLOCKS:
        assert block.name is not None
        rel = Path(block.name)
        assert not rel.is_absolute() and ".." not in rel.parts, f"{block.id}: file= must be a relative path"
        assert not (ROOT / rel.parts[0]).exists(), (
            f"{block.id}: file={block.name} would write into the repository; use a new top-level folder")
        (work / rel).parent.mkdir(parents=True, exist_ok=True)
        (work / rel).write_text(block.text, encoding="utf-8")
    return work


def test_named_example_files_are_unique() -> None:
    names = [b.name for b in NAMED_BLOCKS]
    assert len(names) == len(set(names)), names


def test_the_docs_have_examples_of_every_kind() -> None:
    # Guards the extractor: a changed fence style must not turn every test below into none.
    assert (ROOT / "README.md").exists()
    assert len(SCENARIO_BLOCKS) >= 3, [b.id for b in SCENARIO_BLOCKS]
    assert len(COMMANDS) >= 3, [c.block.id for c in COMMANDS]


@pytest.mark.parametrize("block", SCENARIO_BLOCKS, ids=[b.id for b in SCENARIO_BLOCKS])
def test_scenario_example_passes(block: Block, spec: ir.Spec, tmp_path: Path) -> None:
    if block.name:
        # a named scenario sees the other named files (a program it runs) beside it
        path = workspace(tmp_path) / block.name
    else:
        path = tmp_path / f"{block.file.stem}_{block.line}.yaml"
        path.write_text(block.text, encoding="utf-8")
    scenario = load_scenario(path, spec)
    result = run_scenario(scenario, spec)
    assert result.passed, f"{block.id}: " + "; ".join(str(m) for m in result.mismatches)


@pytest.mark.parametrize("block", SPEC_BLOCKS, ids=[b.id for b in SPEC_BLOCKS])
def test_spec_example_loads(block: Block, tmp_path: Path) -> None:
    assert block.name is not None
    path = tmp_path / Path(block.name).name
    path.write_text(block.text, encoding="utf-8")
    load_spec([bundled_spec_dir(), path])


@pytest.mark.parametrize("command", COMMANDS, ids=[f"{c.block.id}:{c.line}" for c in COMMANDS])
def test_console_example_prints_what_the_docs_show(
    command: Command, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.chdir(workspace(tmp_path))
    buffer = io.StringIO()
    # --help, --version and usage errors exit through argparse
    with contextlib.redirect_stdout(buffer), contextlib.redirect_stderr(buffer), contextlib.suppress(SystemExit):
        main(list(command.argv))
    got, want = normalise(buffer.getvalue()), normalise(command.expected)
    checker = doctest.OutputChecker()
    if not checker.check_output(want, got, doctest.ELLIPSIS):
        shown = " ".join(shlex.quote(a) for a in ("motionchart", *command.argv))
        pytest.fail(f"{command.block.file.name}:{command.line}: `{shown}` printed\n{got}\nbut the docs show\n{want}")


LINK = re.compile(r"\[[^\]]*\]\((?P<target>[^)\s]+)\)")


def heading_anchors(path: Path) -> set[str]:
    """GitHub's anchors for the headings of a Markdown file (outside code blocks)."""
    anchors: set[str] = set()
    in_code = False
    for line in path.read_text(encoding="utf-8").splitlines():
        if FENCE.match(line):
            in_code = not in_code
        elif not in_code and line.startswith("#"):
            title = line.lstrip("#").strip().lower()
            anchors.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return anchors


@pytest.mark.parametrize("doc", [f for f in DOC_FILES if f.exists()], ids=lambda f: str(f.relative_to(ROOT)))
def test_relative_links_resolve(doc: Path) -> None:
    text = doc.read_text(encoding="utf-8")
    broken = []
    for m in LINK.finditer(text):
        target = m["target"]
        if "://" in target or target.startswith("mailto:"):
            continue
        file_part, _, anchor = target.partition("#")
        dest = (doc.parent / file_part).resolve() if file_part else doc
        if not dest.exists() or (anchor and dest.suffix == ".md" and anchor not in heading_anchors(dest)):
            broken.append(target)
    assert not broken, f"{doc.name}: broken links {broken}"


README = ROOT / "README.md"

if README.exists() and ">>> " in README.read_text(encoding="utf-8"):

    def test_readme_doctests() -> None:
        # README.md is outside pytest's test paths, so --doctest-glob does not reach it.
        result = doctest.testfile(str(README), module_relative=False, optionflags=doctest.ELLIPSIS)
        assert result.failed == 0
