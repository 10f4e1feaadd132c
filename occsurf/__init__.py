"""occsurf: the spline-surface algorithms of the SIGGRAPH '91 course C25 (Bartels, DeRose, Forsey,
Warn) in NumPy/SciPy, bridged both ways to OpenCascade NURBS.

* :mod:`occsurf.algorithms` — pure NumPy/SciPy, one subpackage per family of course chapters;
* :mod:`occsurf.bridge` — the only code that touches OCC (OCP, cadquery, build123d): exact
  conversion, STEP/IGES, validation against OCC, rendering and the ``occsurf`` command line;
* :mod:`occsurf.examples` — the gallery that ``occsurf demo`` runs;
* ``occsurf/step_samples/`` — the sample files ``occsurf inspect`` reads by default.

The main user-facing names are available here and are imported on first use, so ``import occsurf``
loads neither NumPy's users nor OpenCascade until a name is asked for::

    import occsurf
    c = occsurf.circle([0, 0, 0], 2.0)           # loads occsurf.algorithms
    occsurf.write_step("c.step", [c])            # loads OCC now

Layout: in the repository the subpackages are the top-level folders ``algorithms/``, ``bridge/``,
``examples/`` and ``step_samples/``; ``pyproject.toml`` maps them below ``occsurf`` in a wheel. When
this file is imported from a source checkout (not installed, or the repository root is the current
directory), the repository root is added to this package's ``__path__`` so that the same dotted
names resolve to those folders.
"""

from __future__ import annotations

from pathlib import Path

from ._lazy import lazy_exports

__version__ = "0.1.0"

_here = Path(__file__).resolve().parent
if not (_here / "algorithms").is_dir() and (_here.parent / "algorithms" / "__init__.py").is_file():
    __path__.append(str(_here.parent))  # source checkout: occsurf.algorithms is ../algorithms

_ALGORITHMS = (
    "BSplineCurve", "BSplineSurface", "TrimmedSurface", "circle", "arc", "ellipse", "make_compatible",
    "Point", "Vector", "Normal", "Frame", "AffineMap", "surface_curvatures", "curve_frenet",
    "extrude", "ruled", "revolve", "sweep", "coons", "coons_bicubic", "gordon",
    "interpolate_curve", "interpolate_surface", "fit_curve", "fit_surface", "loft",
    "constrain", "drag_point", "drag_surface_point", "Position", "Tangent", "Curvature",
    "HierarchicalSurface", "HierarchicalCurve",
    "SPatch", "fill_hole", "HoleSide", "Mesh", "generalized_biquadratic", "generalized_bicubic",
    "OccsurfError", "InvalidGeometryError", "ParameterError", "ToleranceError", "KernelError",
    "ExchangeError",
)
_BRIDGE = (
    "to_occ", "from_occ", "to_face", "to_edge", "read_step", "write_step", "read_iges",
    "write_iges", "ImportedModel", "surface_deviation", "curve_deviation",
)
_EXPORTS = {**{n: "occsurf.algorithms" for n in _ALGORITHMS}, **{n: "occsurf.bridge" for n in _BRIDGE}}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
