"""The docs site's tests share one build of the site (docs/conf.py) per session.

The build and the browser test need the ``[docs]`` extra (Sphinx, MyST, furo, selenium) and
Debian's ``chromium`` + ``chromium-driver``; without them they skip, saying what is missing,
unless ``SOFTGRASP_DOCS_REQUIRED=1`` (as .ci/run sets), where a missing piece fails the test.
The env-page generation tests need neither.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
REQUIRED = os.environ.get("SOFTGRASP_DOCS_REQUIRED") == "1"

if str(DOCS / "_ext") not in sys.path:
    sys.path.insert(0, str(DOCS / "_ext"))


def need(condition: bool, reason: str) -> None:
    """Skip (or, with SOFTGRASP_DOCS_REQUIRED=1, fail) the test unless ``condition``."""
    if condition:
        return
    if REQUIRED:
        pytest.fail(f"{reason} (SOFTGRASP_DOCS_REQUIRED=1)")
    pytest.skip(reason)


def have_docs_extra() -> bool:
    return all(importlib.util.find_spec(m) is not None for m in ("sphinx", "myst_parser", "furo"))


class Build:
    def __init__(self, outdir: Path, returncode: int, log: str, seconds: float) -> None:
        self.outdir, self.returncode, self.log, self.seconds = outdir, returncode, log, seconds


@pytest.fixture(scope="session")
def built_site(tmp_path_factory) -> Build:
    """The site built as CI builds it: ``sphinx -W --keep-going -b html docs <out>``."""
    need(have_docs_extra(), "the docs build needs the [docs] extra: pip install -e '.[docs]'")
    outdir = tmp_path_factory.mktemp("site") / "html"
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-q", str(DOCS), str(outdir)],
        cwd=ROOT, capture_output=True, text=True, timeout=600)  # fmt: skip
    seconds = time.perf_counter() - start
    print(f"docs build: {seconds:.1f} s")
    return Build(outdir, proc.returncode, proc.stdout + proc.stderr, seconds)
