"""Write the small intersphinx inventories the docs link through (``python make_inventories.py``).

The build machine has no network, so the inventories of Python, NumPy, SciPy and build123d cannot
be fetched at build time. These files list the names occsurf's docstrings refer to, with their
pages on the projects' sites (the URLs of ``conf.intersphinx_mapping``), in Sphinx's inventory
format (version 2: a header, then zlib-compressed ``name domain:role priority uri dispname`` lines).
Add a name here when a docstring starts referring to another one.
"""

from __future__ import annotations

import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent

INVENTORIES: dict[str, tuple[str, str, list[tuple[str, str, str]]]] = {
    "python": ("Python", "3.11", [
        ("float", "py:class", "library/functions.html#float"),
        ("int", "py:class", "library/functions.html#int"),
        ("str", "py:class", "library/stdtypes.html#str"),
        ("bool", "py:class", "library/functions.html#bool"),
        ("list", "py:class", "library/stdtypes.html#list"),
        ("dict", "py:class", "library/stdtypes.html#dict"),
        ("tuple", "py:class", "library/stdtypes.html#tuple"),
        ("pathlib.Path", "py:class", "library/pathlib.html#pathlib.Path"),
        ("concurrent.futures", "py:module", "library/concurrent.futures.html#module-concurrent.futures"),
    ]),
    "numpy": ("NumPy", "2.4", [
        ("numpy.ndarray", "py:class", "reference/generated/numpy.ndarray.html#numpy.ndarray"),
        ("numpy.typing.ArrayLike", "py:data", "reference/typing.html#numpy.typing.ArrayLike"),
        ("numpy.typing.NDArray", "py:data", "reference/typing.html#numpy.typing.NDArray"),
        ("numpy.linspace", "py:function", "reference/generated/numpy.linspace.html#numpy.linspace"),
    ]),
    "scipy": ("SciPy", "1.16", [
        ("scipy.sparse", "py:module", "reference/sparse.html#module-scipy.sparse"),
        ("scipy.sparse.csr_matrix", "py:class", "reference/generated/scipy.sparse.csr_matrix.html#scipy.sparse.csr_matrix"),
        ("scipy.spatial.cKDTree", "py:class", "reference/generated/scipy.spatial.cKDTree.html#scipy.spatial.cKDTree"),
        ("scipy.linalg.expm", "py:function", "reference/generated/scipy.linalg.expm.html#scipy.linalg.expm"),
        ("scipy.linalg.eigh", "py:function", "reference/generated/scipy.linalg.eigh.html#scipy.linalg.eigh"),
        ("scipy.fft.dctn", "py:function", "reference/generated/scipy.fft.dctn.html#scipy.fft.dctn"),
    ]),
    "build123d": ("build123d", "0.12", [
        ("build123d.Compound", "py:class", "direct_api_reference.html#topology.Compound"),
        ("build123d.Edge", "py:class", "direct_api_reference.html#topology.Edge"),
        ("build123d.Face", "py:class", "direct_api_reference.html#topology.Face"),
        ("build123d.Shape", "py:class", "direct_api_reference.html#topology.Shape"),
    ]),
}


def main() -> None:
    for key, (project, version, entries) in INVENTORIES.items():
        body = "".join(f"{name} {role} 1 {uri} -\n" for name, role, uri in entries).encode()
        head = (f"# Sphinx inventory version 2\n# Project: {project}\n# Version: {version}\n"
                "# The remainder of this file is compressed using zlib.\n").encode()
        (HERE / f"{key}.inv").write_bytes(head + zlib.compress(body, 9))


if __name__ == "__main__":
    main()
