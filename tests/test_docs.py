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
import os
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


# Start tags and their attributes as html.parser reads them (quoted values may hold ">"), with the
# content of <script> and <style> elements (CDATA to the parser) and comments left out.
_SKIPPED = re.compile(r"<!--.*?-->|(<(script|style)\b[^>]*>).*?(</\2\s*>)", re.S | re.I)
_START_TAG = re.compile(r"""<[a-zA-Z][^\s/>]*((?:\s+[^\s"'>/=]+(?:\s*=\s*(?:"[^"]*"|'[^']*'|[^\s"'>]+))?)*)\s*/?>""")
_ATTRIBUTE = re.compile(r"""([^\s"'>/=]+)(?:\s*=\s*(?:"([^"]*)"|'([^']*)'|([^\s"'>]+)))?""")


def _links_and_ids(text: str) -> tuple[list[str], set[str]]:
    """The ``href`` and ``src`` values of a page's start tags, in order, and its ``id`` values: what
    an ``html.parser.HTMLParser`` collecting them in ``handle_starttag`` finds (the names lowered,
    the values unescaped, the last of a repeated attribute, empty values left out), 5x faster:
    on the 790 pages of the site of 2026-12-07 the same lists and sets page for page, 8 s against
    ~40 s (the parser read every character of 117 MB of pages, the sidebar's ~750 links on each).
    Written for Sphinx's well-formed output: a tag without spaces between its attributes, ``<``
    inside a quoted value or tags inside CDATA sections and processing instructions are read
    differently from the parser (a review's 42 hand-made cases: 19 differ), none of which Sphinx
    writes."""
    links: list[str] = []
    ids: set[str] = set()
    body = _SKIPPED.sub(lambda m: (m.group(1) or "") + (m.group(3) or ""), text)
    for tag in _START_TAG.finditer(body):
        attrs = tag.group(1)
        if not attrs:
            continue
        a: dict[str, str | None] = {}
        for x in _ATTRIBUTE.finditer(attrs):
            value = next((v for v in x.group(2, 3, 4) if v is not None), None)
            a[x.group(1).lower()] = None if value is None else html.unescape(value)
        if a.get("id"):
            ids.add(a["id"] or "")
        links += [a[key] or "" for key in ("href", "src") if a.get(key)]
    return links, ids


class _Collect(html.parser.HTMLParser):
    """The reference :func:`_links_and_ids` is tested against: the parser's own start tags."""

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


def test_links_and_ids_are_those_html_parser_finds():
    """Quoting, entities, repeated and empty attributes, self-closing and upper-case tags, and tags
    inside scripts, styles and comments (which are not tags to the parser)."""
    page = (
        '<html><head><script src="a.js"></script><script>var s = "<a href=\'no.html\'>";</script>'
        "<style>a[href='x.html'] { }</style><link rel=stylesheet href=style.css></head>"
        '<body id="top"><!-- <a href="commented.html"> --><A HREF="Up.html#T" id=\'x&amp;y\'>a</A>'
        '<a href="one.html" href="two.html">b</a><a href="">empty</a><img src="p.png" alt="1 > 0"/>'
        '<div data-href="not-a-link.html" title=\'say "hi"\' id="">c</div>'
        '<a href="q.html?a=1&amp;b=2#frag">d</a><p id=z class="k">e</p></body></html>')
    ref = _Collect()
    ref.feed(page)
    assert _links_and_ids(page) == (ref.links, ref.ids)
    assert ref.links == ["a.js", "style.css", "Up.html#T", "two.html", "p.png", "q.html?a=1&b=2#frag"]
    assert ref.ids == {"top", "x&y", "z"}


def _broken_links(site: Path) -> list[str]:
    """Relative links and images of the site's pages that point to no file of it, and #anchors to
    no id on their page. Paths are joined and normalised as strings and looked up in the site's
    listing (a built site has no symbolic links for ``Path.resolve`` to follow: it took 5.4
    million ``lstat`` calls for the 590 000 links of 2026-12-07's site, 82 s of the crawl with
    the parsing)."""
    site = site.resolve()
    pages: dict[str, tuple[list[str], set[str]]] = {}
    for page in site.rglob("*.html"):
        if "_static" in page.parts:
            continue  # the theme's own template fragments
        pages[str(page)] = _links_and_ids(page.read_text(encoding="utf-8", errors="replace"))
    listed = {str(p) for p in site.rglob("*")} | {str(site)}
    parsed: dict[str, tuple[str, str, bool]] = {}  # link -> (path, fragment, outside the site)
    joined: dict[tuple[str, str], str] = {}
    broken = []
    for page, (links, _) in pages.items():
        folder = os.path.dirname(page)
        for link in links:
            if link not in parsed:
                u = urlparse(link)
                parsed[link] = (unquote(u.path), u.fragment,
                                bool(u.scheme) or link.startswith(("//", "mailto:", "javascript:")))
            path, fragment, outside = parsed[link]
            if outside:
                continue  # outside the site (intersphinx targets, the source repository)
            if not path:
                target = page
            elif (target := joined.get((folder, path))) is None:  # a folder's pages share their sidebar
                target = joined[folder, path] = os.path.normpath(os.path.join(folder, path))
            if target not in listed and not os.path.exists(target):
                broken.append(f"{os.path.relpath(page, site)}: {link}")
                continue
            if fragment and target.endswith(".html") and target in pages and fragment not in pages[target][1]:
                broken.append(f"{os.path.relpath(page, site)}: {link} (no such anchor)")
    return broken


def test_the_crawl_finds_broken_links_and_anchors(tmp_path: Path) -> None:
    (tmp_path / "api").mkdir()
    (tmp_path / "img.png").write_bytes(b"")
    (tmp_path / "index.html").write_text(
        '<a href="api/page.html#here">ok</a><a href="api/page.html#gone">anchor</a><img src="img.png">'
        '<a href="missing.html">file</a><a href="https://example.org/x.html">outside</a><a href="#top" id="top">self</a>'
        '<a href="api/">folder</a><a href="api/../img.png">dots</a><a href="api/page%20two.html">quoted</a>')
    (tmp_path / "api" / "page.html").write_text('<h1 id="here">h</h1><a href="../index.html#nowhere">back</a>')
    (tmp_path / "api" / "page two.html").write_text("<p>two</p>")
    assert sorted(_broken_links(tmp_path)) == ["api/page.html: ../index.html#nowhere (no such anchor)",
                                               "index.html: api/page.html#gone (no such anchor)",
                                               "index.html: missing.html"]


@needs_site
def test_no_broken_links_inside_the_site():
    """A crawl of the built HTML: every relative link and image points to a file of the site, and
    every #anchor to an id on its page."""
    broken = _broken_links(SITE)
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
