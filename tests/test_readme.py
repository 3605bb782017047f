"""README's code blocks run as written, and README stays a short front door.

Every ```python and ```bash block of README.md (and of PYPI.md, the PyPI page) is executed, each in
a subprocess with a time limit: python blocks in the venv's interpreter from an empty folder (they
must work without a checkout), bash blocks from the repository's root. A block that must not run
here (the setup as CI runs it, a training run, the test suite itself, the docs build) is preceded
by an HTML comment naming why: ``<!-- skip-test: trains for minutes -->``. Such blocks are few and
listed in SKIPPED below, so a new one is a deliberate change of this test.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PYPI = ROOT / "PYPI.md"
MAX_README_LINES = 150
TIMEOUT = 300  # s per block: the first gym.make after a fresh install compiles the solver (~35 s)

# The blocks README does not run, by the reason its marker gives.
SKIPPED = {
    "README.md": {
        "setup, as CI runs it",
        "trains for minutes",
        "the test suite itself",
        "builds the documentation site",
    },
    "PYPI.md": {"installs from PyPI"},
}

_FENCE = re.compile(r"^```(\w*)\s*$")
_SKIP = re.compile(r"^<!--\s*skip-test:\s*(.+?)\s*-->\s*$")


@dataclass(frozen=True)
class Block:
    file: str
    line: int  # 1-based line of the opening fence
    language: str
    code: str
    skip: str | None  # the marker's reason, or None

    @property
    def id(self) -> str:
        return f"{self.file}:{self.line}:{self.language}"


def code_blocks(path: Path) -> list[Block]:
    """The fenced blocks of a Markdown file, each with the skip marker right before it (blank
    lines between the marker and the fence allowed)."""
    blocks: list[Block] = []
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        start, language = i, m.group(1)
        j = i + 1
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        skip = None
        k = start - 1
        while k >= 0 and not lines[k].strip():
            k -= 1
        if k >= 0 and (s := _SKIP.match(lines[k].strip())):
            skip = s.group(1)
        blocks.append(Block(path.name, start + 1, language, "\n".join(lines[start + 1 : j]) + "\n", skip))
        i = j + 1
    return blocks


def _interpreter() -> str:
    venv = ROOT / ".venv" / "bin" / "python"
    return str(venv) if venv.exists() else sys.executable


def _runnable() -> list[Block]:
    out = []
    for path in (README, PYPI):
        if path.exists():
            out += [b for b in code_blocks(path) if b.language in ("python", "bash") and b.skip is None]
    return out


def test_readme_is_short():
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= MAX_README_LINES, f"README.md has {n} lines, at most {MAX_README_LINES}: move detail to docs/"


def test_every_block_is_python_or_bash_and_skips_are_the_named_few():
    for path in (README, PYPI):
        if not path.exists():
            continue
        blocks = code_blocks(path)
        assert blocks, path.name
        for b in blocks:
            assert b.language in ("python", "bash"), f"{b.id}: a code block without a runnable language"
        skips = {b.skip for b in blocks if b.skip is not None}
        assert skips == SKIPPED[path.name], (
            f"{path.name}'s skipped blocks changed: {sorted(skips)}; update SKIPPED if that is meant")


def test_readme_runs_python_and_bash():
    languages = {b.language for b in _runnable() if b.file == "README.md"}
    assert languages == {"python", "bash"}, languages


@pytest.mark.parametrize("block", _runnable(), ids=lambda b: b.id)
def test_code_block_runs(block: Block, tmp_path: Path):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONUNBUFFERED="1")
    if block.language == "python":
        cmd, cwd = [_interpreter(), "-c", block.code], tmp_path  # no checkout needed: run from elsewhere
    else:
        if not (ROOT / ".venv" / "bin" / "python").exists():
            pytest.skip("README's shell blocks use the checkout's .venv (./scripts/setup.sh)")
        cmd, cwd = ["bash", "-euo", "pipefail", "-c", block.code], ROOT
    try:
        result = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{block.id} ran longer than {TIMEOUT} s: make it shorter or mark it skip-test")
    assert result.returncode == 0, f"{block.id} failed:\n{block.code}\n--- stdout\n{result.stdout[-3000:]}\n--- stderr\n{result.stderr[-3000:]}"
