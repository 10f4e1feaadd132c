"""The import contracts of pyproject.toml (``[tool.importlinter]``, issue 26): they hold, and their lists of
rooms cannot fall behind the folders.

* ``lint-imports`` keeps every contract (``occsurf.algorithms`` is pure, nothing imports the command line,
  only ``occsurf demo`` imports the examples, the rooms of the bridge are layered, the modules they share
  import none of them). import-linter finds
  modules on disk below the package's own folder, and the repository keeps ``occsurf``'s subpackages in
  top-level folders (pyproject's package-dir; a source checkout or an editable install maps them at import,
  which a static scan does not see), so the test scans a tree of links shaped like the installed package:
  ``occsurf/algorithms`` -> ``algorithms/`` and so on.
* ``cli-leaf`` and ``examples-leaf`` list their source rooms one by one (import-linter has no "everything
  but"): every top-level module and package of ``occsurf``, of ``occsurf.bridge`` but the command line,
  must be listed, so a new room is covered the day it is added; likewise every package of the bridge is
  a layer, and every module beside them is a shared one.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
CONTRACTS = {c["id"]: c for c in PYPROJECT["tool"]["importlinter"]["contracts"]}
#: The repository folder of each package (pyproject's package-dir): ``occsurf`` itself, and the code
#: packages below it (``step_samples`` holds data).
PACKAGE_DIR = {name: REPO / folder for name, folder in PYPROJECT["tool"]["setuptools"]["package-dir"].items()}
PACKAGES = ("algorithms", "bridge", "examples")


def _rooms(folder: Path, prefix: str) -> set[str]:
    """The modules and packages directly inside a package folder, as dotted names."""
    out = set()
    for p in folder.iterdir():
        if p.suffix == ".py" and p.name != "__init__.py":
            out.add(f"{prefix}.{p.stem}")
        elif p.is_dir() and (p / "__init__.py").is_file():
            out.add(f"{prefix}.{p.name}")
    return out


def _all_rooms() -> set[str]:
    """``occsurf``'s own modules, its three packages, and every room of ``occsurf.bridge``."""
    top = _rooms(PACKAGE_DIR["occsurf"], "occsurf") | {f"occsurf.{name}" for name in PACKAGES}
    return (top - {"occsurf.bridge"}) | _rooms(PACKAGE_DIR["occsurf.bridge"], "occsurf.bridge")


def test_leaf_contracts_list_every_other_room() -> None:
    rooms = _all_rooms()
    assert {"occsurf.algorithms", "occsurf.bridge.cli", "occsurf.bridge.exchange", "occsurf.bridge.isolation"} <= rooms
    assert set(CONTRACTS["cli-leaf"]["source_modules"]) == rooms - {"occsurf.bridge.cli"}
    assert set(CONTRACTS["examples-leaf"]["source_modules"]) == rooms - {"occsurf.bridge.cli", "occsurf.examples"}


def test_layers_and_shared_modules_name_every_room_of_the_bridge() -> None:
    layered = {name.strip() for layer in CONTRACTS["bridge-layers"]["layers"] for name in layer.split("|")}
    bridge = PACKAGE_DIR["occsurf.bridge"]
    packages = {r for r in _rooms(bridge, "occsurf.bridge") if (bridge / r.rsplit(".", 1)[1]).is_dir()}
    assert layered == packages == set(CONTRACTS["bridge-shared"]["forbidden_modules"])
    assert set(CONTRACTS["bridge-shared"]["source_modules"]) == _rooms(bridge, "occsurf.bridge") - packages


@pytest.fixture(scope="module")
def installed_shape(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding ``occsurf/`` as a wheel lays it out, made of links into this checkout."""
    root = tmp_path_factory.mktemp("layout")
    pkg = root / "occsurf"
    pkg.mkdir()
    for f in PACKAGE_DIR["occsurf"].iterdir():
        if f.suffix == ".py":
            (pkg / f.name).symlink_to(f)
    for name in PACKAGES:
        (pkg / name).symlink_to(PACKAGE_DIR[f"occsurf.{name}"], target_is_directory=True)
    return root


def test_lint_imports_keeps_every_contract(installed_shape: Path) -> None:
    pytest.importorskip("importlinter")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    code = "import sys; from importlinter.cli import lint_imports_command; sys.exit(lint_imports_command())"
    proc = subprocess.run([sys.executable, "-P", "-c", code, "--no-cache", str(REPO / "pyproject.toml")],
                          cwd=installed_shape, env=env, capture_output=True, text=True, timeout=300)
    assert "Analyzed" in proc.stdout and " 0 broken" in proc.stdout, proc.stdout + proc.stderr
    assert proc.returncode == 0, proc.stdout + proc.stderr
    files = int(proc.stdout.split("Analyzed ", 1)[1].split(" files", 1)[0])
    assert files > 150, proc.stdout  # the link tree was scanned, not the checkout's two-file occsurf/
