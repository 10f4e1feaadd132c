"""The boundary (STYLE.md): ``occsurf.algorithms`` imports the standard library, NumPy and SciPy
only, never ``occsurf.bridge`` nor ``occsurf.examples``; and the modules of ``occsurf.algorithms``
and ``occsurf.bridge`` import one another without cycles.

Each of the two import rules is checked twice, independently: every module imports in a fresh
interpreter in which OCP, cadquery, build123d, ``occsurf.bridge`` and ``occsurf.examples`` cannot
be imported (and none of them is even attempted), and a static read of every file's import
statements (relative ones resolved). Then the import graph of ``occsurf.algorithms`` and
``occsurf.bridge``, read statically, must have no cycle.
"""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

import occsurf.algorithms as algorithms
import occsurf.bridge as bridge

PACKAGE_DIR = Path(algorithms.__file__).resolve().parent
REPO = PACKAGE_DIR.parent
FORBIDDEN = ("OCP", "OCC", "cadquery", "build123d")
#: Packages of occsurf that algorithms must not import: the dependency runs the other way.
FORBIDDEN_OCCSURF = ("occsurf.bridge", "occsurf.examples")
ALLOWED_THIRD_PARTY = {"numpy", "scipy"}

# Runs in the child. The finder goes first on sys.meta_path, before anything imports algorithms,
# and records every attempt, so a lazy or guarded `try: import OCP` is caught too.
CHILD = r"""
import importlib, json, pkgutil, sys

FORBIDDEN = {forbidden!r}
FORBIDDEN_OCCSURF = {forbidden_occsurf!r}
attempts = []

def blocked(name):
    return name.split(".")[0] in FORBIDDEN or any(name == p or name.startswith(p + ".") for p in FORBIDDEN_OCCSURF)

class Block:
    def find_spec(self, name, path=None, target=None):
        if blocked(name):
            attempts.append(name)
            raise ImportError(f"{{name}} is blocked by test_boundary")
        return None

sys.meta_path.insert(0, Block())
for name in sorted(FORBIDDEN) + sorted(FORBIDDEN_OCCSURF):
    try:
        importlib.import_module(name)
    except ImportError:
        pass
    else:
        raise SystemExit(f"the blocker failed: {{name}} imported")
del attempts[:]

import occsurf.algorithms as algorithms
modules = ["occsurf.algorithms"]
for info in pkgutil.walk_packages(algorithms.__path__, "occsurf.algorithms."):
    importlib.import_module(info.name)
    modules.append(info.name)
print(json.dumps({{
    "file": algorithms.__file__,
    "modules": modules,
    "attempts": attempts,
    "loaded": sorted(m for m in sys.modules if blocked(m)),
}}))
"""


def _module_names() -> set[str]:
    return set(_modules({"occsurf.algorithms": PACKAGE_DIR}))


@pytest.fixture(scope="module")
def blocked_import_report() -> dict:
    """Every module of occsurf.algorithms imported in a child with OCC, bridge and examples blocked."""
    code = CHILD.format(forbidden=set(FORBIDDEN), forbidden_occsurf=set(FORBIDDEN_OCCSURF))
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert Path(report["file"]).resolve().parent == PACKAGE_DIR  # the package under test
    assert set(report["modules"]) == _module_names()
    return report


def _is_occ(name: str) -> bool:
    return name.split(".")[0] in FORBIDDEN


def test_every_module_imports_without_the_occ_stack(blocked_import_report):
    attempts = [a for a in blocked_import_report["attempts"] if _is_occ(a)]
    assert attempts == [], f"algorithms tried to import {attempts}"
    assert [m for m in blocked_import_report["loaded"] if _is_occ(m)] == []


def test_every_module_imports_without_bridge_or_examples(blocked_import_report):
    attempts = [a for a in blocked_import_report["attempts"] if not _is_occ(a)]
    assert attempts == [], f"algorithms tried to import {attempts} (bridge and examples build on algorithms, not the reverse)"
    assert [m for m in blocked_import_report["loaded"] if not _is_occ(m)] == []


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
    allowed = set(sys.stdlib_module_names) | ALLOWED_THIRD_PARTY | {"occsurf"}
    alternatives = "|".join(FORBIDDEN)
    dynamic = re.compile(rf"""(import_module|__import__|find_spec)\s*\(\s*f?["']({alternatives})\b""")
    word = re.compile(rf"^\s*(import|from)\s+({alternatives})\b", re.MULTILINE)
    problems = []
    for lineno, root, guarded in _imported_roots(ast.parse(text, filename=str(path))):
        if root in FORBIDDEN:
            problems.append(f"{path}:{lineno}: imports {root} (the OCC stack belongs in bridge/)")
        elif root not in allowed and not guarded:
            problems.append(f"{path}:{lineno}: imports {root} unconditionally (only NumPy/SciPy are dependencies)")
    # A plain-text grep as well: catches imports hidden in strings handed to exec/importlib.
    for m in list(dynamic.finditer(text)) + list(word.finditer(text)):
        problems.append(f"{path}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0).strip()}")
    return problems


def test_static_imports_no_occ_stack_and_only_numpy_scipy_as_hard_dependencies():
    """No file of algorithms/ imports OCP/OCC/cadquery/build123d, even guarded or lazily; any
    third-party import other than NumPy/SciPy must be optional (inside ``try ... except
    ImportError``), so that the package imports with NumPy and SciPy alone."""
    files = sorted(PACKAGE_DIR.rglob("*.py"))
    assert files, "no sources found"
    problems = [msg for path in files for msg in _problems(path.relative_to(REPO), path.read_text(encoding="utf-8"))]
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


# ------------------------------------------------------------- rule 2: algorithms never imports bridge
@dataclass(frozen=True)
class ImportRef:
    """One import statement as Python executes it in a given module."""

    line: int
    #: The module named, a relative name resolved: ``a.b`` of ``import a.b`` and ``from a.b import c``.
    module: str
    #: The names imported by ``from ... import``; ``()`` for ``import``.
    names: tuple[str, ...]
    #: ``"module"`` (runs when the module is imported, class bodies included), ``"function"`` (runs
    #: when a function is called) or ``"type-checking"`` (under ``if TYPE_CHECKING:``, never runs).
    context: str


def _resolve(module: str, is_package: bool, level: int, name: str | None) -> str:
    """The absolute module of ``from <level dots><name> import ...`` written in ``module``."""
    if level == 0:
        return name or ""
    package = module.split(".") if is_package else module.split(".")[:-1]
    if level - 1 >= len(package):
        raise ValueError(f"{module}: relative import of level {level} leaves the top-level package")
    return ".".join(package[: len(package) - (level - 1)] + ([name] if name else []))


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _import_refs(tree: ast.AST, module: str, is_package: bool) -> list[ImportRef]:
    """Every import statement of ``module`` (a package's ``__init__`` when ``is_package``), at any
    depth, relative ones resolved, with the context in which it runs."""
    out: list[ImportRef] = []

    def visit(node: ast.AST, context: str) -> None:
        if isinstance(node, ast.Import):
            out.extend(ImportRef(node.lineno, a.name, (), context) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            target = _resolve(module, is_package, node.level, node.module)
            out.append(ImportRef(node.lineno, target, tuple(a.name for a in node.names), context))
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.body:
                visit(child, "type-checking")
            for child in node.orelse:
                visit(child, context)
            return
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)) and context == "module":
            context = "function"
        for child in ast.iter_child_nodes(node):
            visit(child, context)

    visit(tree, "module")
    return out


def _named(ref: ImportRef) -> list[str]:
    """The module named by ``ref`` and, for ``from m import x``, ``m.x`` (which may be a module)."""
    return [ref.module, *(f"{ref.module}.{n}" for n in ref.names if n != "*")]


def _in_forbidden_occsurf(name: str) -> bool:
    return any(name == p or name.startswith(p + ".") for p in FORBIDDEN_OCCSURF)


def _occsurf_problems(path: Path, text: str, module: str, is_package: bool) -> list[str]:
    """Imports of occsurf.bridge / occsurf.examples by ``module``: absolute or relative, at module
    level, in a function, guarded or under TYPE_CHECKING alike; and by name in a string."""
    problems = []
    for ref in _import_refs(ast.parse(text, filename=str(path)), module, is_package):
        hit = next((n for n in _named(ref) if _in_forbidden_occsurf(n)), None)
        if hit is not None:
            problems.append(f"{path}:{ref.line}: imports {hit} ({ref.context} level; bridge and examples "
                            "build on algorithms, not the reverse)")
    names = "|".join(re.escape(p) for p in FORBIDDEN_OCCSURF)
    dynamic = re.compile(rf"""(import_module|__import__|find_spec)\s*\(\s*f?["']({names})\b""")
    for m in dynamic.finditer(text):
        problems.append(f"{path}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0).strip()}")
    return problems


def _modules(roots: dict[str, Path]) -> dict[str, tuple[Path, bool]]:
    """``{dotted name: (file, is a package)}`` of every module below each ``{package: folder}``."""
    out: dict[str, tuple[Path, bool]] = {}
    for package, folder in roots.items():
        for path in sorted(folder.rglob("*.py")):
            if "__pycache__" in path.parts:
                continue
            parts = [package, *path.relative_to(folder).with_suffix("").parts]
            is_package = parts[-1] == "__init__"
            out[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return out


def test_static_no_module_of_algorithms_imports_bridge_or_examples():
    modules = _modules({"occsurf.algorithms": PACKAGE_DIR})
    assert len(modules) > 10, "no sources found"
    problems = [msg for name, (path, is_package) in sorted(modules.items())
                for msg in _occsurf_problems(path.relative_to(REPO), path.read_text(encoding="utf-8"),
                                             name, is_package)]
    assert not problems, "\n".join(problems)


def test_static_check_detects_imports_of_bridge_and_examples():
    # Relative imports are resolved against the module (and against the package itself in an
    # __init__); function-level, guarded and TYPE_CHECKING imports count; lookalikes do not.
    src = (
        "from ..kernel.curve import BSplineCurve\n"                  # 1: fine
        "from ... import bridge\n"                                    # 2: occsurf.bridge
        "def f():\n    from ...bridge.exchange import read_step\n"   # 4: function level
        "try:\n    import occsurf.examples.demo\nexcept ImportError:\n    pass\n"  # 6: guarded
        "if TYPE_CHECKING:\n    from occsurf.bridge import to_occ\n"  # 10: typing only
        "from .bridgework import x\n"                                 # 11: fine (a lookalike)
        "from occsurf import algorithms\n"                            # 12: fine
        "m = importlib.import_module('occsurf.bridge.cli')\n"         # 13: by name
    )
    found = _occsurf_problems(Path("x.py"), src, "occsurf.algorithms.geometry.x", False)
    assert [m.split(":")[1] for m in found] == ["2", "4", "6", "10", "13"], found
    assert "imports occsurf.bridge (module level" in found[0]
    assert "imports occsurf.bridge.exchange (function level" in found[1]
    assert "imports occsurf.examples.demo (module level" in found[2]
    assert "(type-checking level" in found[3]
    # In a package's __init__, one dot is the package itself.
    assert _resolve("occsurf.algorithms", True, 1, "kernel") == "occsurf.algorithms.kernel"
    assert _resolve("occsurf.algorithms.kernel.curve", False, 1, None) == "occsurf.algorithms.kernel"
    assert _occsurf_problems(Path("__init__.py"), "from ..bridge import to_occ\n", "occsurf.algorithms", True)
    with pytest.raises(ValueError, match="leaves the top-level package"):
        _resolve("occsurf.algorithms", True, 3, None)


# --------------------------------------------------------------------- no import cycles
#: The packages whose modules form the import graph.
GRAPH_ROOTS = {"occsurf.algorithms": PACKAGE_DIR, "occsurf.bridge": Path(bridge.__file__).resolve().parent}


def _ancestors(module: str) -> set[str]:
    parts = module.split(".")
    return {".".join(parts[:k]) for k in range(1, len(parts))}


def import_graph(roots: dict[str, Path]) -> dict[str, dict[str, list[tuple[int, str]]]]:
    """``{module: {imported module: [(line, context), ...]}}`` over the modules below ``roots``,
    read statically (edges to modules outside them are left out).

    An import statement makes an edge to the module it names and, for ``from m import x``, to
    ``m.x`` when that is a module. Left out: imports under ``if TYPE_CHECKING:`` (never run), and
    the importer's own parent packages (always imported before it, so they close no new cycle).
    """
    modules = _modules(roots)
    graph: dict[str, dict[str, list[tuple[int, str]]]] = {m: {} for m in modules}
    for module, (path, is_package) in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        skip = _ancestors(module) | {module}
        for ref in _import_refs(tree, module, is_package):
            if ref.context == "type-checking":
                continue
            for target in dict.fromkeys(_named(ref)):
                if target in modules and target not in skip:
                    graph[module].setdefault(target, []).append((ref.line, ref.context))
    return graph


def find_cycles(graph: dict[str, dict[str, object]] | dict[str, set[str]]) -> list[list[str]]:
    """One shortest cycle ``[a, b, ..., a]`` per strongly connected component that has a cycle
    (Tarjan's algorithm), through the component's smallest node; sorted by that node."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[set[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            components.append(component)

    for v in sorted(graph):
        if v not in index:
            connect(v)
    cycles = []
    for component in components:
        start = min(component)
        if len(component) == 1 and start not in graph.get(start, ()):
            continue
        # Breadth-first from start inside the component, back to start.
        parent: dict[str, str] = {}
        queue, seen, end = [start], {start}, None
        while queue and end is None:
            nxt = []
            for v in queue:
                for w in sorted(graph.get(v, ())):
                    if w == start:
                        end = v
                        break
                    if w in component and w not in seen:
                        seen.add(w)
                        parent[w] = v
                        nxt.append(w)
                if end is not None:
                    break
            queue = nxt
        path = [end]
        while path[-1] != start:
            path.append(parent[path[-1]])
        cycles.append([*reversed(path), start])
    return sorted(cycles)


def _describe(cycle: list[str], graph: dict[str, dict[str, list[tuple[int, str]]]]) -> str:
    steps = [f"  {a}\n    -> {b}  ({', '.join(f'{ctx} level, line {line}' for line, ctx in graph[a][b])})"
             for a, b in zip(cycle, cycle[1:])]
    return "\n".join(steps)


@pytest.mark.slow
def test_no_import_cycles_in_algorithms_and_bridge():
    """Module-level and function-level imports alike: a function-level import that closes a cycle
    is a cycle postponed, not removed."""
    graph = import_graph(GRAPH_ROOTS)
    assert "occsurf.algorithms.kernel.curve" in graph and "occsurf.bridge.cli" in graph  # the scan works
    assert any(graph.values()), "no edges found"
    cycles = find_cycles(graph)
    assert not cycles, f"{len(cycles)} import cycle(s):\n" + "\n\n".join(_describe(c, graph) for c in cycles)


def test_cycle_finder_on_a_small_graph():
    graph = {
        "a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(),     # a -> b -> c -> a, d hangs off it
        "e": {"e"},                                               # a self-import
        "f": {"g"}, "g": {"f", "h"}, "h": {"g"},                  # one component, two cycles through g
        "i": {"j"}, "j": {"k"}, "k": set(),                       # acyclic
    }
    assert find_cycles(graph) == [["a", "b", "c", "a"], ["e", "e"], ["f", "g", "f"]]
    assert find_cycles({"x": {"y"}, "y": {"z"}, "z": set()}) == []
    assert find_cycles({}) == []


def test_import_graph_edges_resolve_relative_imports_and_record_the_context(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .sub import a\n")
    (pkg / "sub" / "__init__.py").write_text("from . import a\nfrom .a import f\n")
    (pkg / "sub" / "a.py").write_text(
        "from .. import helpers\n"          # line 1: pkg.helpers, a module
        "from . import b\n"                 # line 2: pkg.sub.b
        "import numpy\n"                    # outside the graph
        "if TYPE_CHECKING:\n    from ..helpers import T\n"  # never runs: no edge
        "def f():\n    from .b import g\n")  # line 7: function level
    (pkg / "sub" / "b.py").write_text("class C:\n    from . import a\n")  # class body: module level
    (pkg / "helpers.py").write_text("")
    graph = import_graph({"pkg": pkg})
    assert graph["pkg"] == {"pkg.sub": [(1, "module")], "pkg.sub.a": [(1, "module")]}
    assert graph["pkg.sub"] == {"pkg.sub.a": [(1, "module"), (2, "module")]}  # not pkg.sub itself
    assert graph["pkg.sub.a"] == {"pkg.helpers": [(1, "module")], "pkg.sub.b": [(2, "module"), (7, "function")]}
    assert graph["pkg.sub.b"] == {"pkg.sub.a": [(2, "module")]}
    assert find_cycles(graph) == [["pkg.sub.a", "pkg.sub.b", "pkg.sub.a"]]
    assert "function level, line 7" in _describe(["pkg.sub.a", "pkg.sub.b", "pkg.sub.a"], graph)
