"""The wheel and the one import name ``occsurf`` (issue 18; STYLE.md, Layout).

* The wheel, built from the working tree with the running interpreter, has ``occsurf`` as its only
  top-level package: none of the repository's folders (``algorithms/``, ``bridge/``, ...) lands
  at the top of site-packages.
* Every package folder of the repository is inside it, so the explicit package list in
  pyproject.toml cannot fall behind the folders; the sample files ship as package data.
* Installed alone (``pip install --target``) and run from an unrelated empty directory, the
  package imports from there, the repository's folder names do not import, and the command-line
  entry point of ``entry_points.txt`` inspects the shipped samples.
* ``import occsurf`` is lazy: neither NumPy's users nor OCC load until a name is used.

The build needs the build requirements of pyproject.toml in the running environment (the
``test`` extra lists them: ``setuptools>=68``, ``wheel``); pip checks them.
"""

from __future__ import annotations

import configparser
import json
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

import occsurf

REPO = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
#: {"occsurf.algorithms": "algorithms", ...}: the import name of each mapped repository folder.
PACKAGE_DIR: dict[str, str] = PYPROJECT["tool"]["setuptools"]["package-dir"]
#: Repository folders whose packages must all be in the wheel.
CODE_FOLDERS = ("algorithms", "bridge", "examples")
NOT_AT_TOP = ("algorithms", "bridge", "examples", "tests", "benchmarks", "step_samples")


def _run(cmd: list[str], cwd: Path, env: dict[str, str] | None = None, timeout: float = 300):
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}"
    return proc


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[str, Path]:
    """Copy what the build reads (pyproject's folders, pyproject.toml, the readme) from the working
    tree, build the wheel there without isolation and install it with ``--target``. Built from a
    copy so that the build leaves no ``build/`` or ``*.egg-info`` in the repository."""
    tmp = tmp_path_factory.mktemp("packaging")
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", PYPROJECT["project"]["readme"]):
        shutil.copy2(REPO / name, src / name)
    for folder in sorted(set(PACKAGE_DIR.values())):
        shutil.copytree(REPO / folder, src / folder, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    dist = tmp / "dist"
    _run([sys.executable, "-m", "pip", "wheel", ".", "--no-deps", "--no-build-isolation",
          "--check-build-dependencies", "--disable-pip-version-check", "-w", str(dist)], cwd=src)
    (wheel,) = dist.glob("occsurf-*.whl")
    site = tmp / "site"
    _run([sys.executable, "-m", "pip", "install", "--no-deps", "--disable-pip-version-check",
          "--target", str(site), str(wheel)], cwd=tmp)
    empty = tmp / "empty"
    empty.mkdir()
    return {"wheel": wheel, "site": site, "empty": empty}


def _names(wheel: Path) -> list[str]:
    with zipfile.ZipFile(wheel) as zf:
        return zf.namelist()


def _dist_info_text(wheel: Path, leaf: str) -> str | None:
    with zipfile.ZipFile(wheel) as zf:
        hits = [n for n in zf.namelist() if n.count("/") == 1 and n.endswith(f".dist-info/{leaf}")]
        return zf.read(hits[0]).decode("utf-8") if hits else None


def _repo_packages() -> dict[str, str]:
    """``{dotted name in the wheel: repository folder}`` of every package folder (one with an
    ``__init__.py``) under algorithms/, bridge/ and examples/, mapped as pyproject maps them."""
    folder_to_name = {folder: name for name, folder in PACKAGE_DIR.items()}
    out: dict[str, str] = {}
    for top in CODE_FOLDERS:
        assert top in folder_to_name, f"pyproject's package-dir does not map {top}/"
        for init in sorted((REPO / top).rglob("__init__.py")):
            rel = init.parent.relative_to(REPO / top)
            out[".".join([folder_to_name[top], *rel.parts])] = str(init.parent.relative_to(REPO))
    return out


def test_wheel_has_occsurf_as_its_only_top_level_package(built):
    names = _names(built["wheel"])
    tops = {n.split("/")[0] for n in names}
    dist_info = {t for t in tops if t.endswith(".dist-info")}
    assert len(dist_info) == 1 and tops - dist_info == {"occsurf"}, sorted(tops)
    assert not any(n.split("/")[0] in NOT_AT_TOP for n in names)
    top_level = _dist_info_text(built["wheel"], "top_level.txt")
    if top_level is not None:
        assert top_level.split() == ["occsurf"]
    # The installed tree agrees: nothing beside occsurf/ but its metadata (and bin/ for the script).
    assert {p.name for p in built["site"].iterdir()} - {"bin"} == {"occsurf", *dist_info}


def test_every_package_folder_and_module_of_the_repository_is_in_the_wheel(built):
    names = set(_names(built["wheel"]))
    packages = _repo_packages()
    assert "occsurf.algorithms.kernel" in packages and "occsurf.bridge.cli" in packages  # the scan works
    missing = [f"{folder}/ (as {name})" for name, folder in packages.items()
               if f"{name.replace('.', '/')}/__init__.py" not in names]
    assert not missing, "package folders missing from the wheel (pyproject's package list is behind):\n" + "\n".join(missing)
    # ... and so every module in them.
    folder_to_name = {folder: name for name, folder in PACKAGE_DIR.items()}
    modules = []
    for top in CODE_FOLDERS:
        for path in (REPO / top).rglob("*.py"):
            if (path.parent / "__init__.py").is_file():
                modules.append(f"{folder_to_name[top].replace('.', '/')}/{path.relative_to(REPO / top).as_posix()}")
    assert modules
    assert sorted(set(modules) - names) == []


def test_sample_files_ship_as_package_data(built):
    names = set(_names(built["wheel"]))
    samples = REPO / "step_samples"
    expected = ([p.relative_to(samples).as_posix() for p in samples.glob("*.step")]
                + ["mixed.igs"]
                + [p.relative_to(samples).as_posix() for p in samples.glob("holes/*.step")])
    assert any(e.startswith("holes/") for e in expected) and len(expected) >= 4
    missing = sorted(e for e in expected if f"occsurf/step_samples/{e}" not in names)
    assert not missing, f"sample files missing from the wheel: {missing}"


CHILD = r"""
import importlib, json, sys
site = sys.argv[1]
import occsurf
out = {"file": occsurf.__file__}
for name in ("algorithms", "bridge"):
    try:
        importlib.import_module(name)
    except ModuleNotFoundError:
        out[name] = None
    else:
        out[name] = sys.modules[name].__file__
import occsurf.algorithms, occsurf.bridge.cli
out["subpackages"] = [occsurf.algorithms.__file__, occsurf.bridge.cli.__file__]
json.dump(out, sys.stdout)
"""


def _site_env(site: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(site)
    return env


def test_installed_wheel_imports_from_its_site_and_not_the_folder_names(built):
    site, empty = built["site"], built["empty"]
    proc = _run([sys.executable, "-c", CHILD, str(site)], cwd=empty, env=_site_env(site))
    out = json.loads(proc.stdout)
    assert Path(out["file"]).resolve().is_relative_to(site.resolve()), out["file"]
    for path in out["subpackages"]:
        assert Path(path).resolve().is_relative_to(site.resolve()), path
    assert out["algorithms"] is None and out["bridge"] is None, out


def test_installed_console_script_inspects_the_shipped_samples(built):
    site, empty = built["site"], built["empty"]
    ep = configparser.ConfigParser()
    ep.read_string(_dist_info_text(built["wheel"], "entry_points.txt") or "")
    assert dict(ep["console_scripts"]) == {"occsurf": PYPROJECT["project"]["scripts"]["occsurf"]}
    module, func = ep["console_scripts"]["occsurf"].split(":")
    code = (f"import sys; from {module} import {func} as main; "
            "sys.exit(main(['inspect', '--samples', '3', '--json']))")
    proc = _run([sys.executable, "-c", code], cwd=empty, env=_site_env(site))
    doc = json.loads(proc.stdout)
    shipped = site / "occsurf" / "step_samples"
    paths = [Path(f["path"]) for f in doc["files"]]
    assert all(p.resolve().parent == shipped.resolve() for p in paths), paths
    expected = sorted(p.name for p in (REPO / "step_samples").iterdir() if p.suffix.lower() in {".step", ".stp", ".igs", ".iges"})
    assert sorted(p.name for p in paths) == expected
    assert [f["path"] for f in doc["files"] if f["error"] is not None] == []
    assert doc["samples"] == 3 and sum(f["n_faces"] for f in doc["files"]) > 0


LAZY = r"""
import json, sys
import occsurf
steps = {"import": sorted(m for m in ("OCP", "numpy", "occsurf.algorithms", "occsurf.bridge") if m in sys.modules)}
occsurf.BSplineCurve
steps["BSplineCurve"] = sorted(m for m in ("OCP", "numpy", "occsurf.algorithms", "occsurf.bridge") if m in sys.modules)
read_step = occsurf.read_step
steps["read_step"] = sorted(m for m in ("OCP", "numpy", "occsurf.algorithms", "occsurf.bridge") if m in sys.modules)
read_step(sys.argv[1])
steps["read_step()"] = sorted(m for m in ("OCP", "numpy", "occsurf.algorithms", "occsurf.bridge") if m in sys.modules)
steps["file"] = occsurf.__file__
json.dump(steps, sys.stdout)
"""


def test_import_occsurf_is_lazy():
    sample = REPO / "step_samples" / "loft.step"
    proc = _run([sys.executable, "-c", LAZY, str(sample)], cwd=REPO, timeout=120)
    steps = json.loads(proc.stdout)
    assert Path(steps["file"]).resolve() == Path(occsurf.__file__).resolve()  # the tree under test
    assert steps["import"] == []  # neither OCP nor NumPy nor a subpackage
    assert "occsurf.algorithms" in steps["BSplineCurve"]
    assert "OCP" not in steps["BSplineCurve"] and "occsurf.bridge" not in steps["BSplineCurve"]
    # The bridge's modules import OCC inside their functions: it loads on the first call.
    assert "occsurf.bridge" in steps["read_step"]
    assert "OCP" in steps["read_step()"]


def test_every_name_in_occsurf_all_resolves():
    assert occsurf.__all__ == sorted(set(occsurf.__all__))
    unresolved = [name for name in occsurf.__all__ if getattr(occsurf, name, None) is None]
    assert unresolved == []
    assert set(occsurf.__all__) <= set(dir(occsurf))
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        occsurf.no_such_name  # noqa: B018


def test_wheel_ships_the_py_typed_marker(built):
    """PEP 561: type checkers use the hints of an installed occsurf (one marker covers the subpackages)."""
    assert (REPO / PACKAGE_DIR["occsurf"] / "py.typed").is_file()
    assert "occsurf/py.typed" in set(_names(built["wheel"]))
    assert (built["site"] / "occsurf" / "py.typed").is_file()


#: What a user's type checker is asked: names through the subpackage, the lazy top level and a tolerance.
MYPY_PROBE = """
import occsurf
import occsurf.algorithms
from occsurf.algorithms import tolerances
occsurf.algorithms.BSplineSurface
reveal_type(occsurf.algorithms.BSplineSurface)
reveal_type(occsurf.BSplineSurface)
reveal_type(occsurf.read_step)
reveal_type(tolerances.KNOT_EQUALITY)
reveal_type(tolerances.MAX_ARRAY_BYTES)
"""


@pytest.mark.slow
def test_fresh_install_is_visible_to_mypy(built, tmp_path):
    """Issue 26: ``pip install .`` (the wheel) in a new venv, without system site-packages, and mypy
    run from an empty folder resolves ``occsurf.algorithms.BSplineSurface``, the lazily exported
    top-level names and the tolerance names (served by a module ``__getattr__`` at run time)."""
    # Nothing of this process's PYTHONPATH (tests/conftest.py puts the checkout there for worker
    # processes; an in-tree build leaves occsurf.egg-info in it, which pip would take for an install).
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", str(venv)], cwd=tmp_path, env=env)
    python = venv / "bin" / "python"
    _run([str(python), "-m", "pip", "install", "--no-deps", "--no-index", "--disable-pip-version-check",
          str(built["wheel"])], cwd=tmp_path, env=env)
    assert (venv / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages" / "occsurf").is_dir()
    mypy = [sys.executable, "-m", "mypy", "--python-executable", str(python), "--no-incremental"]
    _run([*mypy, "-c", "import occsurf.algorithms; occsurf.algorithms.BSplineSurface"], cwd=built["empty"], env=env)
    proc = subprocess.run([*mypy, "-c", MYPY_PROBE], cwd=built["empty"], capture_output=True, text=True, timeout=300,
                          env=env)
    revealed = [line.split("Revealed type is ", 1)[1] for line in proc.stdout.splitlines() if "Revealed type is" in line]
    assert len(revealed) == 5, proc.stdout + proc.stderr
    assert all("occsurf.algorithms.kernel.surface.BSplineSurface" in r for r in revealed[:2]), revealed
    assert "occsurf.bridge.exchange" in revealed[2] and "def" in revealed[2], revealed
    assert [r.strip('"').removeprefix("builtins.") for r in revealed[3:]] == ["float", "int"], revealed
    errors = [line for line in proc.stdout.splitlines() if ": error:" in line]
    assert errors == [], proc.stdout


NO_NUMBA = r"""
import json, sys
sys.modules["numba"] = None  # as if numba were not installed: `import numba` raises ImportError
import numpy as np
from occsurf.algorithms import BSplineSurface, tolerances
from occsurf.algorithms import _numba_kernels as nk
rng = np.random.default_rng(3)
s = BSplineSurface((3, 3), ([0.0] * 4 + [0.5] + [1.0] * 4,) * 2, rng.random((5, 5, 3)))
u = rng.random(5000)
with tolerances.override(NUMBA_MIN_POINTS=0):
    values = s.evaluate(u, u[::-1])
json.dump({"numba_loaded": nk.load() is not None, "values": values.tolist()}, sys.stdout)
"""


def test_numba_is_an_optional_extra_with_the_numpy_path_as_fallback():
    deps = " ".join(PYPROJECT["project"]["dependencies"])
    assert "numba" not in deps  # never required
    extras = PYPROJECT["project"]["optional-dependencies"]
    assert any(req.startswith("numba") for req in extras["fast"]), extras["fast"]
    proc = _run([sys.executable, "-c", NO_NUMBA], cwd=REPO, timeout=300)
    out = json.loads(proc.stdout)
    assert out["numba_loaded"] is False
    import numpy as np

    from occsurf.algorithms import BSplineSurface, tolerances

    rng = np.random.default_rng(3)
    s = BSplineSurface((3, 3), ([0.0] * 4 + [0.5] + [1.0] * 4,) * 2, rng.random((5, 5, 3)))
    u = rng.random(5000)
    with tolerances.override(NUMBA_MIN_POINTS=0):  # numba's kernels here when it is installed
        here = s.evaluate(u, u[::-1])
    np.testing.assert_allclose(np.asarray(out["values"]), here, rtol=0, atol=1e-14)
