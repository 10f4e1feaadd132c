"""The boundary: ``algorithms`` imports the standard library, NumPy and SciPy only (STYLE.md).

Two independent checks: every module imports in a fresh interpreter in which OCP, cadquery and
build123d cannot be imported (and none of them is even attempted), and a static read of every
file's import statements.
"""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

import occsurf.algorithms as algorithms

PACKAGE_DIR = Path(algorithms.__file__).resolve().parent
REPO = PACKAGE_DIR.parent
FORBIDDEN = ("OCP", "OCC", "cadquery", "build123d")
ALLOWED_THIRD_PARTY = {"numpy", "scipy"}

# Runs in the child. The finder goes first on sys.meta_path, before anything imports algorithms,
# and records every attempt, so a lazy or guarded `try: import OCP` is caught too.
CHILD = r"""
import importlib, json, pkgutil, sys

FORBIDDEN = {forbidden!r}
attempts = []

class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in FORBIDDEN:
            attempts.append(name)
            raise ImportError(f"{{name}} is blocked by test_boundary")
        return None

sys.meta_path.insert(0, Block())
for name in FORBIDDEN:
    try:
        importlib.import_module(name)
    except ImportError:
        pass
    else:
        raise SystemExit(f"the blocker failed: {{name}} imported")
del attempts[:]

import occsurf.algorithms as algorithms
modules = ["algorithms"]
for info in pkgutil.walk_packages(algorithms.__path__, "algorithms."):
    importlib.import_module(info.name)
    modules.append(info.name)
print(json.dumps({{
    "file": algorithms.__file__,
    "modules": modules,
    "attempts": attempts,
    "loaded": sorted(m for m in sys.modules if m.split(".")[0] in FORBIDDEN),
}}))
"""


def _module_names() -> set[str]:
    out = set()
    for path in PACKAGE_DIR.rglob("*.py"):
        rel = path.relative_to(PACKAGE_DIR).with_suffix("")
        parts = ["algorithms", *rel.parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out.add(".".join(parts))
    return out


def test_every_module_imports_without_the_occ_stack():
    code = CHILD.format(forbidden=set(FORBIDDEN))
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert Path(report["file"]).resolve().parent == PACKAGE_DIR  # the package under test
    assert set(report["modules"]) == _module_names()
    assert report["attempts"] == [], f"algorithms tried to import {report['attempts']}"
    assert report["loaded"] == []


_GUARDS = {"ImportError", "ModuleNotFoundError", "Exception", "BaseException"}


def _imported_roots(tree: ast.AST) -> list[tuple[int, str, bool]]:
    """``(line, top-level module, guarded)`` of every absolute import, at any depth; ``guarded``
    when it sits in the body of a ``try`` whose handlers catch ImportError (an optional import)."""
    out: list[tuple[int, str, bool]] = []

    def catches_import_error(node: ast.Try) -> bool:
        for h in node.handlers:
            types = h.type.elts if isinstance(h.type, ast.Tuple) else [h.type]
            if h.type is None or any(isinstance(t, ast.Name) and t.id in _GUARDS for t in types):
                return True
        return False

    def visit(node: ast.AST, guarded: bool) -> None:
        if isinstance(node, ast.Import):
            out.extend((node.lineno, a.name.split(".")[0], guarded) for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.append((node.lineno, node.module.split(".")[0], guarded))
        if isinstance(node, ast.Try):
            g = guarded or catches_import_error(node)
            for child in node.body:
                visit(child, g)
            for child in node.handlers + node.orelse + node.finalbody:
                visit(child, guarded)
        else:
            for child in ast.iter_child_nodes(node):
                visit(child, guarded)

    visit(tree, False)
    return out


def _problems(path: Path, text: str) -> list[str]:
    allowed = set(sys.stdlib_module_names) | ALLOWED_THIRD_PARTY | {"algorithms"}
    dynamic = re.compile(r"""(import_module|__import__|find_spec)\s*\(\s*f?["'](%s)\b""" % "|".join(FORBIDDEN))
    word = re.compile(r"^\s*(import|from)\s+(%s)\b" % "|".join(FORBIDDEN), re.MULTILINE)
    problems = []
    for lineno, root, guarded in _imported_roots(ast.parse(text, filename=str(path))):
        if root in FORBIDDEN:
            problems.append(f"{path.name}:{lineno}: imports {root} (the OCC stack belongs in bridge/)")
        elif root not in allowed and not guarded:
            problems.append(f"{path.name}:{lineno}: imports {root} unconditionally (only NumPy/SciPy are dependencies)")
    # A plain-text grep as well: catches imports hidden in strings handed to exec/importlib.
    for m in list(dynamic.finditer(text)) + list(word.finditer(text)):
        problems.append(f"{path.name}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0).strip()}")
    return problems


def test_static_imports_no_occ_stack_and_only_numpy_scipy_as_hard_dependencies():
    """No file of algorithms/ imports OCP/OCC/cadquery/build123d, even guarded or lazily; any
    third-party import other than NumPy/SciPy must be optional (inside ``try ... except
    ImportError``), so that the package imports with NumPy and SciPy alone."""
    files = sorted(PACKAGE_DIR.rglob("*.py"))
    assert files, "no sources found"
    problems = [msg for path in files for msg in _problems(path, path.read_text(encoding="utf-8"))]
    assert not problems, "\n".join(problems)


def test_static_check_detects_forbidden_and_unguarded_imports():
    # The checker itself can fail: OCP is seen inside a function and even when guarded; an
    # unguarded third-party import is flagged, a guarded one is not.
    src = (
        "import numpy\n"
        "def f():\n    from OCP.Geom import Geom_BSplineCurve\n"
        "try:\n    import numba\nexcept ImportError:\n    numba = None\n"
        "try:\n    import cadquery\nexcept Exception:\n    pass\n"
        "import pandas\n"
        "x = importlib.import_module('build123d')\n"
    )
    assert [(r, g) for _, r, g in _imported_roots(ast.parse(src))] == [
        ("numpy", False), ("OCP", False), ("numba", True), ("cadquery", True), ("pandas", False)]
    found = _problems(Path("x.py"), src)
    assert any("imports OCP" in m for m in found) and any("imports cadquery" in m for m in found)
    assert any("imports pandas unconditionally" in m for m in found)
    assert any("import_module('build123d" in m for m in found)
    assert not any("numba" in m for m in found)
