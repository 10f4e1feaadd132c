"""The documentation site (issue 33): every public name has an API page, links inside the site
resolve, the course map covers the course's table of contents, and the built pages open in headless
Chromium with something on them.

The site is built by ``.ci/run`` (``sphinx-build -W -b html docs docs/_build/html``, warnings are
errors) before these tests run; where it has not been built they are skipped with that reason.
"""

from __future__ import annotations

import html.parser
import importlib
import json
import re
import sys
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from .browser import chrome, needs_chromium

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
SITE = DOCS / "_build" / "html"
COURSE = ROOT.parent / "shared" / "course" / "C25-course-contents.txt"

needs_site = pytest.mark.skipif(not (SITE / "index.html").is_file(),
                                reason=f"the site is not built ({SITE}): run sphinx-build -W -b html docs docs/_build/html")


def _conf():
    sys.path.insert(0, str(DOCS))
    try:
        return importlib.import_module("conf")
    finally:
        sys.path.remove(str(DOCS))


@needs_site
def test_every_public_name_has_an_api_page():
    conf = _conf()
    generated = SITE / "api" / "generated"
    missing = []
    for module in conf.documented_modules():
        mod = importlib.import_module(module)
        if not (generated / f"{module}.html").is_file():
            missing.append(module)
        for name in getattr(mod, "__all__", ()):
            if name.startswith("_"):
                continue  # a private helper listed in __all__ for `import *` users, not an API
            home = conf.home_of(getattr(mod, name, None), name) or module
            if not (generated / f"{home}.{name}.html").is_file():
                missing.append(f"{module}.{name}")
    for package in ("occsurf.algorithms", "occsurf.bridge"):  # re-exported: a page of the home module
        mod = importlib.import_module(package)
        for name in mod.__all__:
            home = conf.home_of(getattr(mod, name), name) or package
            if not (generated / f"{home}.{name}.html").is_file():
                missing.append(f"{package}.{name}")
    assert not missing, f"{len(missing)} public names without an API page: {missing[:20]}"


class _Links(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"] or "")
        for key in ("href", "src"):
            if a.get(key):
                self.links.append(a[key] or "")


@needs_site
def test_no_broken_links_inside_the_site():
    """A crawl of the built HTML: every relative link and image points to a file of the site, and
    every #anchor to an id on its page."""
    pages: dict[Path, _Links] = {}
    for page in SITE.rglob("*.html"):
        if "_static" in page.parts:
            continue  # the theme's own template fragments
        p = _Links()
        p.feed(page.read_text(encoding="utf-8", errors="replace"))
        pages[page.resolve()] = p
    broken = []
    for page, parsed in pages.items():
        for link in parsed.links:
            u = urlparse(link)
            if u.scheme or link.startswith(("//", "mailto:", "javascript:")):
                continue  # outside the site (intersphinx targets, the source repository)
            target = (page.parent / unquote(u.path)).resolve() if u.path else page
            if not target.exists():
                broken.append(f"{page.relative_to(SITE.resolve())}: {link}")
                continue
            if u.fragment and target.suffix == ".html" and target in pages and u.fragment not in pages[target].ids:
                broken.append(f"{page.relative_to(SITE.resolve())}: {link} (no such anchor)")
    assert not broken, f"{len(broken)} broken links, e.g. {broken[:10]}"


@pytest.mark.skipif(not COURSE.is_file(), reason=f"no course table of contents at {COURSE}")
def test_the_course_map_covers_every_section_of_the_table_of_contents():
    text = (DOCS / "course_map.rst").read_text(encoding="utf-8")
    sections = []
    for line in COURSE.read_text(encoding="utf-8", errors="replace").splitlines():
        m = re.match(r"^(.*\S)\t(\d+-\d+)\s*$", line)
        if m:
            sections.append((re.sub(r"<[^>]+>", "", m.group(1)).strip(), m.group(2)))
    assert len(sections) > 100
    rows = re.findall(r"\* - (.+)\n\s+- (\d+-\d+)\n", text)
    def norm(t: str) -> str:
        return re.sub(r"\s+", " ", t.replace("*", "")).strip()

    titles = {(norm(t), p) for t, p in rows}
    missing = [s for s in sections if (norm(s[0]), s[1]) not in titles]
    assert not missing, f"{len(missing)} sections not on the course map: {missing[:10]}"




@needs_site
@pytest.mark.slow
@needs_chromium
@pytest.mark.parametrize("page", ["index.html", "api/generated/occsurf.algorithms.kernel.BSplineSurface.html",
                                  "auto_gallery/plot_10_figures.html"])
def test_pages_open_in_headless_chromium(page, tmp_path):
    """The front page, the API page of BSplineSurface and a gallery page: loaded from the file system
    with the network cut off, titled, and a screenshot with content (not a blank page)."""
    import numpy as np
    from PIL import Image

    drv = chrome(size=(1280, 1000))
    from selenium.webdriver.common.by import By

    try:
        drv.get((SITE / page).resolve().as_uri())
        assert "occsurf" in drv.title
        assert drv.find_elements(By.TAG_NAME, "h1")
        images = drv.execute_script("return Array.from(document.images).filter(i => i.complete && i.naturalWidth > 0).length")
        if page != "api/generated/occsurf.algorithms.kernel.BSplineSurface.html":
            assert images >= 1  # the pictures load
        shot = tmp_path / "page.png"
        drv.save_screenshot(str(shot))
        grey = np.asarray(Image.open(shot).convert("L"), float)
        assert grey.std() > 20 and (grey < 128).mean() > 0.01  # text and pictures, not a blank page
    finally:
        drv.quit()


def test_the_docs_extra_names_what_the_build_needs():
    import tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]["docs"]
    names = {re.split(r"[<>=\[]", e)[0] for e in extras}
    assert {"sphinx", "pydata-sphinx-theme", "sphinx-gallery"} <= names
    assert json.dumps(sorted(names))  # a plain list of requirement strings


def test_every_name_on_the_course_map_imports():
    """The course map names functions, classes and modules by their import paths: each must exist
    (a renamed function would otherwise leave a dead entry in plain text)."""
    text = (DOCS / "course_map.rst").read_text(encoding="utf-8")
    targets = sorted(set(re.findall(r":(?:func|class|mod|obj|meth|attr|data|exc):`~?([\w.]+)`", text)))
    assert len(targets) > 100
    missing = []
    for t in targets:
        parts = t.split(".")
        for k in range(len(parts), 0, -1):  # the longest importable prefix, then attributes
            try:
                obj = importlib.import_module(".".join(parts[:k]))
            except ImportError:
                continue
            try:
                for attr in parts[k:]:
                    obj = getattr(obj, attr)
            except AttributeError:
                missing.append(t)
            break
        else:
            missing.append(t)
    assert not missing, f"names on the course map that do not exist: {missing}"
