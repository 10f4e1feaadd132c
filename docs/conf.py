"""Sphinx configuration of the occsurf documentation site (``pip install ".[docs]"``, then
``sphinx-build -W -b html docs docs/_build/html``).

The API reference is generated (autosummary, recursive) from the docstrings of every public name:
``api/index.rst`` is written here at each build from the packages themselves, so a new module or
name needs no edit of the docs. The gallery and the tutorials are scripts executed at build time
by sphinx-gallery (their output and pictures are real); the gallery's scripts run the same
functions as ``occsurf demo`` (:mod:`occsurf.examples`), so each picture is written once.
"""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path

HERE = Path(__file__).resolve().parent

project = "occsurf"
author = "the occsurf engineers"
copyright = "2026, the occsurf engineers"  # noqa: A001 - Sphinx's name

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "myst_parser",
]
# The user guide is Markdown (docs/guide/*.md, also read on the repository's page; the README
# links to it): MyST, with GitHub-style tables and headings anchored for links between pages.
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_heading_anchors = 3
templates_path = ["_templates"]
exclude_patterns = ["_build", "gallery", "tutorials", "sg_execution_times.rst", "auto_*/*.ipynb", "**/*.md5", "**/*.codeobj.json", "check",
                    "fill", "fitting", "lighting", "repair", "figures", "_inv"]

# ------------------------------------------------------------------------------------ API reference
autosummary_generate = True
autosummary_ignore_module_all = False  # a module's members are its __all__
autodoc_typehints = "none"  # the NumPy-style docstrings carry the types
autodoc_default_options = {"members": True, "show-inheritance": True}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
# "ndarray, shape (m, 3)": napoleon turns "shape" into a reference that matches many attributes;
# those ambiguities are not errors of the docs.
suppress_warnings = ["ref.python"]

#: The documented modules: every algorithms subpackage (its public names are its __all__), the
#: cross-cutting modules, and every public module of the bridge's rooms (the CLI is documented
#: by its commands, not as an API).
ALGORITHMS = ["kernel", "geometry", "construction", "fitting", "manipulation", "hierarchical", "topology",
              "quality", "lighting"]
BRIDGE_ROOMS = ["conversion", "exchange", "validation", "quality", "modeling", "rendering", "audit"]


def documented_modules() -> list[str]:
    """The modules whose ``__all__`` the API reference covers with a page per name (also used by the
    docs test). The two top-level packages re-export names documented here; their own pages are
    tables of links (:func:`_top_level_table`)."""
    mods = ["occsurf.algorithms.errors", "occsurf.algorithms.tolerances", "occsurf.algorithms.threads"]
    mods += [f"occsurf.algorithms.{s}" for s in ALGORITHMS]
    mods += ["occsurf.bridge.isolation", "occsurf.bridge.messages"]
    for room in BRIDGE_ROOMS:
        pkg = importlib.import_module(f"occsurf.bridge.{room}")
        mods += sorted(f"{pkg.__name__}.{m.name}" for m in pkgutil.iter_modules(pkg.__path__)
                       if not m.name.startswith("_"))
    return mods


def home_of(obj: object, name: str) -> str | None:
    """The documented module whose page documents ``obj`` (exported there as ``name``): the first
    documented module whose ``__all__`` holds the same object under that name, preferring the
    module that defines it."""
    homes = []
    for m in documented_modules():
        mod = importlib.import_module(m)
        if name in getattr(mod, "__all__", ()) and getattr(mod, name, None) is obj:
            homes.append(m)
    defined = getattr(obj, "__module__", None)
    for m in homes:
        if m == defined:
            return m
    return homes[0] if homes else None


def foreign_names() -> set[str]:
    """``module.name`` of the names a documented module re-exports from another documented module:
    left out of its page (one page per object; the templates read this set)."""
    out = set()
    for m in documented_modules():
        mod = importlib.import_module(m)
        for name in getattr(mod, "__all__", ()):
            home = home_of(getattr(mod, name, None), name)
            if home is not None and home != m:
                out.add(f"{m}.{name}")
    return out


def _top_level_table(package: str) -> list[str]:
    mod = importlib.import_module(package)
    rows = [".. list-table::", "   :header-rows: 1", "   :widths: 30 70", "", "   * - name", "     - documented in"]
    own = []
    for name in sorted(getattr(mod, "__all__", ())):
        obj = getattr(mod, name, None)
        home = home_of(obj, name)
        if home is None:  # defined in a private module: documented under the package itself
            own.append(name)
            home = package
        rows += [f"   * - ``{package.rsplit('.', 1)[-1]}.{name}``", f"     - :obj:`{home}.{name}`"]
    rows.append("")
    if own:
        rows += [".. autosummary::", "   :toctree: generated", ""] + [f"   {package}.{n}" for n in own] + [""]
    return rows


def _write_api_index() -> None:
    lines = ["API reference", "=============", "",
             "Every public name of :mod:`occsurf.algorithms` (NumPy/SciPy only) and :mod:`occsurf.bridge`",
             "(the OpenCascade side), generated from their docstrings. Course sections are cited as",
             "``§5-15`` (section) or ``ch. 8`` (chapter); see :doc:`/course_map`.", ""]
    for title, prefix in (("occsurf.algorithms", "occsurf.algorithms"), ("occsurf.bridge", "occsurf.bridge")):
        lines += [title, "-" * len(title), "", ".. autosummary::", "   :toctree: generated", ""]
        lines += [f"   {m}" for m in documented_modules() if m.startswith(prefix)]
        lines += ["", f"The names :mod:`{prefix}` itself exports:", ""] + _top_level_table(prefix)
    (HERE / "api").mkdir(exist_ok=True)
    text = "\n".join(lines) + "\n"
    target = HERE / "api" / "index.rst"
    if not target.exists() or target.read_text() != text:
        target.write_text(text)


def data_members() -> dict[str, list[str]]:
    """Per documented module, the names of its ``__all__`` that are values (constants, presets,
    mapping objects): autosummary's module template lists classes, exceptions and functions only."""
    import inspect

    out: dict[str, list[str]] = {}
    foreign = foreign_names()
    for m in documented_modules():
        mod = importlib.import_module(m)
        names = []
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name, None)
            if name.startswith("_") or f"{m}.{name}" in foreign:
                continue
            if inspect.isclass(obj) or inspect.isfunction(obj) or inspect.isbuiltin(obj) or inspect.ismodule(obj):
                continue
            names.append(name)
        out[m] = names
    return out


_write_api_index()
autosummary_context = {"foreign": sorted(foreign_names()), "data": data_members()}


def _write_cli_page() -> None:
    """``cli.rst``: every command's ``--help``, from the parser itself (never out of date)."""
    from occsurf.bridge.cli import build_parser

    parser = build_parser()
    lines = ["Commands", "========", "",
             "The ``occsurf`` command line: one line per error on stderr (``occsurf: PATH: reason``), exit 0 on",
             "success, 2 for bad input, 1 where a command's gate fails (``check --fail-on``). Every command",
             "that reads a file reads it in a separate process (a crash inside OCC costs that file only).", "",
             ".. code-block:: text", ""]
    lines += ["   " + ln for ln in parser.format_help().splitlines()]
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")  # noqa: SLF001
    for name, p in sub.choices.items():
        lines += ["", f"occsurf {name}", "-" * (8 + len(name)), "", ".. code-block:: text", ""]
        lines += ["   " + ln for ln in p.format_help().replace("usage: ", "usage: ").splitlines()]
    text = "\n".join(lines) + "\n"
    target = HERE / "cli.rst"
    if not target.exists() or target.read_text() != text:
        target.write_text(text)


_write_cli_page()

intersphinx_mapping = {
    "python": ("https://docs.python.org/3", (None, str(HERE / "_inv" / "python.inv"))),
    "numpy": ("https://numpy.org/doc/stable", (None, str(HERE / "_inv" / "numpy.inv"))),
    "scipy": ("https://docs.scipy.org/doc/scipy", (None, str(HERE / "_inv" / "scipy.inv"))),
    "build123d": ("https://build123d.readthedocs.io/en/latest", (None, str(HERE / "_inv" / "build123d.inv"))),
}

# ------------------------------------------------------------------------------------ gallery
sphinx_gallery_conf = {
    "examples_dirs": ["gallery", "tutorials"],
    "gallery_dirs": ["auto_gallery", "auto_tutorials"],
    "filename_pattern": r"/(plot|tutorial)_",
    "ignore_pattern": r"(^|/)_",
    "write_computation_times": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "show_memory": False,
}

# ------------------------------------------------------------------------------------ HTML
html_theme = "pydata_sphinx_theme"
html_title = "occsurf"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
}
html_show_sourcelink = False


# ------------------------------------------------------------------------------------ data docs
def _comment_doc(name: str, obj: object) -> list[str] | None:
    """The ``#:`` comment above the assignment of ``name`` in whichever occsurf module assigns
    this object (a constant re-exported by a package is documented where it is defined)."""
    import sys

    from sphinx.pycode import ModuleAnalyzer

    short = name.rsplit(".", 1)[-1]
    for modname, mod in sorted(sys.modules.items()):
        if not modname.startswith("occsurf.") or getattr(mod, short, None) is not obj:
            continue
        try:
            docs = ModuleAnalyzer.for_module(modname).find_attr_docs()
        except Exception:  # noqa: BLE001 - modules without source (extensions)
            continue
        found = docs.get(("", short))
        if found:
            return list(found)
    return None


def _process_docstring(app: object, what: str, name: str, obj: object, options: object, lines: list[str]) -> None:
    """A value documented without its own ``#:`` comment would show its type's docstring (``dict()
    -> new empty dictionary ...``): take the comment from the module that defines it, or nothing."""
    if what not in ("data", "attribute") or obj is None:
        return
    own = (type(obj).__doc__ or "").strip()
    if lines and own and "\n".join(lines).strip() == own.strip():
        lines[:] = _comment_doc(name, obj) or []
    elif not lines:
        lines[:] = _comment_doc(name, obj) or []


def setup(app: object) -> None:
    app.connect("autodoc-process-docstring", _process_docstring)  # type: ignore[attr-defined]
