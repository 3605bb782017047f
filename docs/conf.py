"""Sphinx configuration of the documentation site (Sphinx + MyST Markdown, the furo theme).

Build (warnings are errors):

    .venv/bin/python -m sphinx -W --keep-going -b html docs docs/_build/html

docs/envs/ is generated at build time from the code (docs/_ext/envpages.py); docs/_ext/sitecheck.py
checks, after the build, that every relative link and image of the built HTML resolves.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(ROOT))  # the package from the checkout (the docs extra does not install it)

import softgrasp_env  # noqa: E402

project = "softgrasp"
author = "softgrasp maintainers"
copyright = "softgrasp maintainers"
release = softgrasp_env.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.viewcode",
    "envpages",
    "sitecheck",
]

source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "_ext",
    # the results page before it is split into docs/results/ (its content moves there)
    "RESULTS.md",
    "**/.pytest_cache",
]

# Pages the toctrees name that other people write: until each lands, the home page's toctree
# leaves it out (docs/_ext/sitecheck.py; any other missing entry is still a warning, so an error).
pending_pages = {"getting-started", "fingers", "tactile", "training", "results/index"}

myst_enable_extensions = ["colon_fence", "deflist", "dollarmath"]
myst_heading_anchors = 3  # [text](page.md#a-heading) resolves, and a wrong anchor is a warning
suppress_warnings: list[str] = []

autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"
autodoc_preserve_defaults = True
# gymnasium.Env's docstrings (step, reset, ...) are its API, documented by gymnasium; ours are on the
# env pages
autodoc_inherit_docstrings = False

html_theme = "furo"
html_title = f"softgrasp {release}"
html_static_path: list[str] = []
