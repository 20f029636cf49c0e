"""Long commands show a status line on a terminal and nothing when their output is not one.

The terminal case runs the command with its standard error on a pseudo-terminal (the
``pty`` module); the other case with both streams on pipes, which must carry exactly
what they carried before (no carriage returns, no status text).
"""

from __future__ import annotations

import io
import os
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from statecharts.progress import Progress

ROOT = Path(__file__).resolve().parent.parent
_SCRIPT = Path(sys.executable).parent / "motionchart"
MOTIONCHART = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-c",
                                                       "import sys, checker.cli; sys.exit(checker.cli.main())"]

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")


def small_scenarios(tmp_path: Path) -> Path:
    folder = tmp_path / "scenarios"
    folder.mkdir(parents=True)
    for name in sorted((ROOT / "scenarios" / "noncip").glob("*.yaml"))[:3]:
        shutil.copy(name, folder / name.name)
    return folder


def run_on_terminal(args: list[str], cwd: Path) -> tuple[int, str, str]:
    """(exit code, stdout, what the terminal on stderr received)."""
    import pty

    master, slave = pty.openpty()
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    proc = subprocess.Popen([*MOTIONCHART, *args], cwd=cwd, stdout=subprocess.PIPE, stderr=slave, env=env)
    os.close(slave)
    chunks: list[bytes] = []

    def drain() -> None:
        while True:
            try:
                data = os.read(master, 4096)
            except OSError:  # the child closed the terminal
                return
            if not data:
                return
            chunks.append(data)

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    out, _ = proc.communicate(timeout=600)
    reader.join(timeout=30)
    os.close(master)
    return proc.returncode, out.decode(), b"".join(chunks).decode(errors="replace")


def run_on_pipes(args: list[str], cwd: Path) -> tuple[int, str, str]:
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    proc = subprocess.run([*MOTIONCHART, *args], cwd=cwd, capture_output=True, text=True, env=env, timeout=600)
    return proc.returncode, proc.stdout, proc.stderr


COMMANDS = {
    "validate": (["validate"], "motionchart validate: loading the spec"),
    "simulate": (["simulate", "--summary", "SCENARIOS"], "motionchart simulate: running "),
    "generate": (["generate", "--check", "-o", "OUT", "--scenarios", "SCENARIOS"],
                 "motionchart generate: running scenario "),
    "docs": (["docs", "-o", "OUT", "--scenarios", "SCENARIOS"], "motionchart docs: "),
}


def _args(template: list[str], tmp_path: Path) -> list[str]:
    scenarios = small_scenarios(tmp_path) if "SCENARIOS" in template else None
    out = tmp_path / "out"
    if "OUT" in template and not out.exists():
        # a copy of generated/ holds the drawn SVGs, so no diagram is redrawn
        shutil.copytree(ROOT / "generated", out)
    return [str(scenarios) if a == "SCENARIOS" else str(out) if a == "OUT" else a for a in template]


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_progress_on_a_terminal_and_silence_on_pipes(command: str, tmp_path: Path) -> None:
    template, expected = COMMANDS[command]
    code_t, out_t, term = run_on_terminal(_args(template, tmp_path / "tty"), ROOT)
    assert expected in term, f"no status line on the terminal: {term!r}"
    assert "\r" in term
    # the same work again, in a folder of its own, with both streams on pipes
    code_p, out_p, err_p = run_on_pipes(_args(template, tmp_path / "pipe"), ROOT)
    out_t, out_p = out_t.replace(str(tmp_path / "tty"), "TMP"), out_p.replace(str(tmp_path / "pipe"), "TMP")
    assert code_p == code_t
    assert "\r" not in err_p and expected not in err_p, f"status text on a pipe: {err_p!r}"
    assert "\r" not in out_t and "\r" not in out_p
    assert out_p == out_t  # the standard output is the same either way


def test_status_line_is_erased_and_silent_when_disabled() -> None:
    buf = io.StringIO()
    p = Progress("motionchart x", stream=buf, enabled=True)
    p.update("step one", 1, 3)
    p.clear()
    assert buf.getvalue().startswith("\rmotionchart x: step one (1/3)") and buf.getvalue().endswith("\r")
    quiet = io.StringIO()
    q = Progress("motionchart x", stream=quiet)  # a StringIO is no terminal
    q.update("step", 1, 2)
    q.close()
    assert quiet.getvalue() == ""
