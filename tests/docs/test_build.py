"""The site builds with warnings as errors, and its links and images resolve."""

from __future__ import annotations

from .conftest import DOCS


def test_site_builds_without_warnings(built_site):
    assert built_site.returncode == 0, built_site.log[-6000:]
    assert "WARNING" not in built_site.log, built_site.log[-6000:]
    for page in ("index.html", "api.html", "changelog.html", "envs/index.html", "envs/lift.html"):
        assert (built_site.outdir / page).is_file(), page


def test_links_and_images_of_the_built_site_resolve(built_site):
    """docs/_ext/sitecheck.py's check (which the build also runs as warnings), on its own."""
    from sitecheck import check_site

    assert built_site.returncode == 0, built_site.log[-6000:]
    assert check_site(built_site.outdir) == []


def test_the_check_finds_a_broken_link_image_and_anchor(tmp_path):
    """The link check itself: a broken relative link, a missing image, a missing anchor and a
    malformed external link are each reported; good ones are not."""
    from sitecheck import check_site

    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "b.html").write_text('<h1 id="there">b</h1>')
    (tmp_path / "pic.png").write_bytes(b"\x89PNG")
    (tmp_path / "a.html").write_text(
        '<a href="sub/b.html#there">ok</a> <a href="#top" id="top">ok</a> <img src="pic.png">'
        '<a href="https://example.org/x">ok</a>'
        '<a href="sub/c.html">broken</a> <img src="gone.png"> <a href="sub/b.html#nowhere">anchor</a>'
        '<a href="https:/missing-host">bad</a>')  # fmt: skip
    problems = check_site(tmp_path)
    assert len(problems) == 4, problems
    assert any("sub/c.html" in p for p in problems) and any("gone.png" in p for p in problems)
    assert any("nowhere" in p for p in problems) and any("missing-host" in p for p in problems)


def test_the_changelog_page_includes_the_changelog():
    assert "{include} ../CHANGELOG.md" in (DOCS / "changelog.md").read_text()
