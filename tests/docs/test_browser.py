"""The built site in a real browser: headless Chromium (Debian's ``chromium`` and
``chromium-driver``) driven by Selenium. The home page, one env page and one results page load
with every image drawn, every link into the site resolving, and a screenshot that is not blank.
"""

from __future__ import annotations

import io
import os
import shutil
import time
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from .conftest import need

CHROMIUM = next((p for p in (os.environ.get("CHROMIUM"), shutil.which("chromium"), shutil.which("chromium-browser"))
                 if p), None)  # fmt: skip
CHROMEDRIVER = os.environ.get("CHROMEDRIVER") or shutil.which("chromedriver")
SCREENSHOTS = os.environ.get("SOFTGRASP_DOCS_SCREENSHOTS")
"""A folder to keep the screenshots in (default: the test's temporary folder)."""


@pytest.fixture(scope="module")
def browser():
    need(CHROMIUM is not None and CHROMEDRIVER is not None,
         "the browser test needs Debian's chromium and chromium-driver: apt-get install chromium chromium-driver")
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        need(False, "the browser test needs selenium (the [docs] extra)")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                "--window-size=1280,900", "--allow-file-access-from-files"):  # fmt: skip
        options.add_argument(arg)
    # the driver given: Selenium Manager would otherwise try to download one
    driver = webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=options)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


def _results_page(outdir: Path) -> Path:
    """A results page with figures: the first of docs/results/'s built pages that has an image."""
    pages = sorted((outdir / "results").glob("*.html"))
    with_images = [p for p in pages if "<img" in p.read_text(encoding="utf-8")]
    assert with_images, f"no results page with a figure in {outdir / 'results'}: {[p.name for p in pages]}"
    return with_images[0]


IMAGES_JS = """
return Array.from(document.images).map(img => ({src: img.currentSrc || img.src, complete: img.complete,
    width: img.naturalWidth, height: img.naturalHeight, shown: img.getBoundingClientRect().width}));
"""
LINKS_JS = "return Array.from(document.querySelectorAll('a[href]')).map(a => a.href);"
HAS_ID_JS = "return document.getElementById(arguments[0]) !== null;"


def _check_page(driver, page: Path, outdir: Path, shots: Path) -> dict:
    driver.get(page.as_uri())
    deadline = time.monotonic() + 30
    while driver.execute_script("return document.readyState") != "complete" and time.monotonic() < deadline:
        time.sleep(0.1)
    assert driver.title, f"{page}: no title"
    assert "404" not in driver.title
    # images: each one loaded and decoded (naturalWidth > 0: a broken image has 0)
    images = []
    while time.monotonic() < deadline:
        images = driver.execute_script(IMAGES_JS)
        if all(i["complete"] for i in images):
            break
        time.sleep(0.1)
    broken = [i["src"] for i in images if not (i["complete"] and i["width"] > 0 and i["height"] > 0)]
    assert not broken, f"{page}: broken images {broken}"
    # links: every link into the site is a file of the site, every anchor an id of its page
    for href in driver.execute_script(LINKS_JS):
        parts = urlsplit(href)
        if parts.scheme != "file":
            assert parts.scheme in ("http", "https", "mailto") and (parts.netloc or parts.scheme == "mailto"), href
            continue
        target = Path(unquote(parts.path))
        if target.is_dir():
            target = target / "index.html"
        assert target.is_file(), f"{page}: broken link {href}"
        assert outdir.resolve() in target.resolve().parents, f"{page}: link out of the site {href}"
        if parts.fragment and target.resolve() == page.resolve():
            assert driver.execute_script(HAS_ID_JS, unquote(parts.fragment)), f"{page}: broken anchor {href}"
    # the picture: not blank (a page of one colour has no variance)
    png = driver.get_screenshot_as_png()
    shot = shots / (page.relative_to(outdir).as_posix().replace("/", "_") + ".png")
    shot.write_bytes(png)
    from PIL import Image, ImageStat

    gray = Image.open(io.BytesIO(png)).convert("L")
    variance = ImageStat.Stat(gray).var[0]
    assert variance > 100, f"{page}: the screenshot is (nearly) blank: variance {variance:.1f} ({shot})"
    return {"images": images, "variance": variance, "screenshot": shot}


def test_site_in_headless_chromium(built_site, browser, tmp_path):
    assert built_site.returncode == 0, built_site.log[-6000:]
    outdir = built_site.outdir
    shots = Path(SCREENSHOTS) if SCREENSHOTS else tmp_path
    shots.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()

    home = _check_page(browser, outdir / "index.html", outdir, shots)
    gif = [i for i in home["images"] if i["src"].endswith("grasp.gif")]
    assert gif and gif[0]["shown"] > 100, f"the home page's GIF is not shown: {home['images']}"

    env = _check_page(browser, outdir / "envs" / "lift.html", outdir, shots)
    assert browser.find_element("css selector", "h1").text.startswith("Lift family")
    headings = [h.text.rstrip("#¶ ").strip() for h in browser.find_elements("css selector", "h2")]
    for section in ("Description", "Action Space", "Observation Space", "Rewards", "Episode End", "Arguments"):
        assert section in headings, headings
    assert env["variance"] > 100

    results = _check_page(browser, _results_page(outdir), outdir, shots)
    assert results["images"], "the results page shows no image"
    print(f"browser checks: {time.perf_counter() - start:.1f} s; screenshots in {shots}")
