"""Site checks of the docs build, a Sphinx extension:

- toctree entries named in conf.py's ``PENDING_PAGES`` (pages other people are writing) are left
  out while their source does not exist, with an info line; any other missing entry stays a
  warning (an error under -W);
- the env classes' docstrings (the env cards, Markdown with tables) are not parsed as reST by
  autodoc: the API page shows their first paragraph and links to their generated env page;
- after an HTML build, every relative link and image of the built pages must resolve to a file of
  the site, and every ``#anchor`` to an id in its page; external links are checked for syntax only
  (the build has no internet, so Sphinx's linkcheck builder cannot run). Each failure is a warning,
  so ``-W`` fails the build. :func:`check_site` is the same check for a test.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

try:  # the check itself (check_site) is plain Python; only the build's hooks log through Sphinx
    from sphinx.util import logging
except ImportError:  # tests of check_site run without the [docs] extra
    import logging
logger = logging.getLogger(__name__)

ENV_CARDS = {"softgrasp_env.env.SoftGraspEnv": "envs/lift", "softgrasp_env.env.SoftGraspGoalEnv": "envs/goal"}
"""The classes whose docstrings are env cards, and the generated page of each."""


# --- pending toctree entries ------------------------------------------------------------------------


def _drop_pending(app, docname: str, source: list[str]) -> None:
    pending = set(getattr(app.config, "pending_pages", ()) or ())
    if not pending or "{toctree}" not in source[0]:
        return
    srcdir = Path(app.srcdir)
    base = Path(docname).parent

    def missing(entry: str) -> bool:
        name = (base / entry).as_posix() if not entry.startswith("/") else entry.lstrip("/")
        if name not in pending:
            return False
        return not any((srcdir / (name + suffix)).exists() for suffix in app.config.source_suffix)

    out, in_tree = [], False
    for line in source[0].splitlines(keepends=True):
        stripped = line.strip()
        if stripped.startswith("```{toctree}"):
            in_tree = True
        elif in_tree and stripped.startswith("```"):
            in_tree = False
        elif in_tree and stripped and not stripped.startswith(":") and missing(stripped):
            logger.info(f"[sitecheck] {docname}: toctree entry {stripped!r} left out: not written yet")
            continue
        out.append(line)
    source[0] = "".join(out)


# --- the env cards in the API reference -------------------------------------------------------------


def _card_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    if what != "class" or name not in ENV_CARDS:
        return
    first = []
    for line in lines:
        if not line.strip():
            break
        first.append(line)
    lines[:] = [*first, "", f"The env card: :doc:`/{ENV_CARDS[name]}`.", ""]


def _indented_blocks(app, what, name, obj, options, lines: list[str]) -> None:
    """A docstring's indented block after a line ending in one colon (a recipe, a code sample),
    which reST would take as an unexpected indentation, is shown as a literal block (``::``)."""
    for k, line in enumerate(lines[:-2]):
        if not line.rstrip().endswith(":") or line.rstrip().endswith("::") or lines[k + 1].strip():
            continue
        nxt = next((m for m in range(k + 1, len(lines)) if lines[m].strip()), None)
        indent = len(line) - len(line.lstrip())
        if nxt is not None and len(lines[nxt]) - len(lines[nxt].lstrip()) > indent and not lines[nxt].lstrip().startswith(("-", "*", "..")):
            lines[k] = line.rstrip() + ":"


# --- links and images of the built site -------------------------------------------------------------


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.refs: list[tuple[str, str]] = []  # (tag.attr, url)

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if attrs.get("id"):
            self.ids.add(attrs["id"])
        if tag == "a" and attrs.get("name"):
            self.ids.add(attrs["name"])
        if tag in ("a", "link") and attrs.get("href") is not None:
            self.refs.append((f"{tag}.href", attrs["href"]))
        if tag in ("img", "script", "source") and attrs.get("src"):
            self.refs.append((f"{tag}.src", attrs["src"]))


_URL_OK = re.compile(r"^[^\s<>\"]+$")


def check_site(outdir: Path) -> list[str]:
    """Every broken relative link, image or anchor of the HTML site in ``outdir``, and every
    external link that is not a well-formed http(s) / mailto URL, as messages (empty: all good)."""
    outdir = Path(outdir)
    pages: dict[Path, _Page] = {}
    for path in sorted(outdir.rglob("*.html")):
        parser = _Page()
        parser.feed(path.read_text(encoding="utf-8", errors="replace"))
        pages[path.resolve()] = parser
    problems = []
    for path, page in pages.items():
        rel = path.relative_to(outdir.resolve())
        for what, url in page.refs:
            parts = urlsplit(url)
            if parts.scheme in ("http", "https"):
                if not parts.netloc or not _URL_OK.match(url):
                    problems.append(f"{rel}: malformed external link {url!r} ({what})")
                continue
            if parts.scheme in ("mailto", "data"):
                continue
            if parts.scheme or parts.netloc:
                problems.append(f"{rel}: unexpected link {url!r} ({what})")
                continue
            target = path if not parts.path else (path.parent / unquote(parts.path)).resolve()
            if parts.path.endswith("/") or target.is_dir():
                target = target / "index.html"
            if not target.is_file():
                problems.append(f"{rel}: broken link {url!r} ({what}): no {target}")
                continue
            fragment = unquote(parts.fragment)
            if fragment and target.suffix == ".html" and target in pages and fragment not in pages[target].ids:
                problems.append(f"{rel}: broken anchor {url!r} ({what}): no id {fragment!r} in {target.name}")
    return problems


def _build_finished(app, exception) -> None:
    if exception is not None or app.builder.format != "html":
        return
    for problem in check_site(Path(app.outdir)):
        logger.warning(f"[sitecheck] {problem}", type="sitecheck")


def setup(app):
    app.add_config_value("pending_pages", set(), "env")
    app.connect("source-read", _drop_pending)
    app.connect("autodoc-process-docstring", _card_docstring)
    app.connect("autodoc-process-docstring", _indented_blocks)
    app.connect("build-finished", _build_finished)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
