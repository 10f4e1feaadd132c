"""Names served lazily at run time are visible to type checkers (issue 26; STYLE.md, Layout).

A package that serves names through a module ``__getattr__`` (``occsurf``, ``occsurf.bridge`` and
its lazy rooms) imports the same names under ``if TYPE_CHECKING:``, and
:mod:`occsurf.algorithms.tolerances` declares every tolerance as a typed module attribute. These
tests read the sources, so a name added to one list and not the other fails here rather than
silently vanishing from mypy and go-to-definition.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

from occsurf.algorithms import tolerances

LAZY_PACKAGES = ["occsurf", "occsurf.algorithms", "occsurf.bridge", "occsurf.bridge.quality", "occsurf.bridge.audit"]


def _tree(module_name: str) -> ast.Module:
    module = importlib.import_module(module_name)
    return ast.parse(Path(module.__file__).read_text(encoding="utf-8"))


def _type_checking_names(tree: ast.Module) -> set[str]:
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            for stmt in ast.walk(node):
                if isinstance(stmt, ast.ImportFrom | ast.Import):
                    names.update(a.asname or a.name.split(".")[0] for a in stmt.names)
    return names


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_lazy_names_are_imported_for_type_checkers(package):
    tree = _tree(package)
    served = set(importlib.import_module(package).__all__) - _eager_names(tree)
    missing = served - _type_checking_names(tree)
    assert missing == set(), f"{package}: served lazily but not imported under TYPE_CHECKING: {sorted(missing)}"


def _eager_names(tree: ast.Module) -> set[str]:
    """Names bound at module level outside ``if TYPE_CHECKING:`` (plain imports, defs, assignments)."""
    out: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.Import | ast.ImportFrom):
            out.update(a.asname or a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.FunctionDef | ast.ClassDef):
            out.add(node.name)
        elif isinstance(node, ast.Assign):
            out.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return out


def test_every_tolerance_is_a_typed_module_attribute():
    tree = _tree("occsurf.algorithms.tolerances")
    declared = {node.target.id: ast.unparse(node.annotation) for node in tree.body
                if isinstance(node, ast.AnnAssign) and node.value is None and isinstance(node.target, ast.Name)}
    expected = {name: type(value).__name__ for name, value in tolerances.defaults().items()}
    assert declared == expected


def test_declared_tolerances_still_read_the_current_context():
    """The annotations create no attribute: reads go through ``__getattr__`` and see overrides."""
    assert "KNOT_EQUALITY" not in vars(tolerances)
    before = tolerances.KNOT_EQUALITY
    with tolerances.override(KNOT_EQUALITY=before * 2):
        assert tolerances.KNOT_EQUALITY == before * 2
    assert tolerances.KNOT_EQUALITY == before


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_every_lazily_served_name_resolves(package):
    """Each name in ``__all__`` imports (``occsurf.bridge.quality.occ_gap`` pointed at a module that
    does not define it, and raised AttributeError, until the TYPE_CHECKING imports made mypy look)."""
    module = importlib.import_module(package)
    unresolved = []
    for name in module.__all__:
        try:
            getattr(module, name)
        except AttributeError:
            unresolved.append(name)
    assert unresolved == []
