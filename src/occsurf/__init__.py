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
``examples/`` and ``step_samples/``, and this file lives in ``src/occsurf/``; ``pyproject.toml``
maps them below ``occsurf`` (``[tool.setuptools.package-dir]``). A source checkout is used through
the README's install (``pip install .``, or ``pip install -e .`` while developing): the installed
package, editable or not, is what tests, type checkers and IDEs see, so ``occsurf.algorithms`` is the
same module for all of them.

Type checkers see the lazy names through the ``if TYPE_CHECKING:`` imports below (the same names
:data:`__all__` lists); at run time they are imported on first use by :func:`_lazy.lazy_exports`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._lazy import lazy_exports

__version__ = "0.1.0"

if TYPE_CHECKING:  # the names of _ALGORITHMS and _BRIDGE, for type checkers and IDEs
    from .algorithms import (
        AffineMap,
        BSplineCurve,
        BSplineSurface,
        Curvature,
        ExchangeError,
        Frame,
        HierarchicalCurve,
        HierarchicalSurface,
        HoleSide,
        InvalidGeometryError,
        KernelError,
        Mesh,
        Normal,
        OccsurfError,
        ParameterError,
        Point,
        Position,
        SPatch,
        Tangent,
        ToleranceError,
        TrimmedSurface,
        Vector,
        arc,
        circle,
        constrain,
        coons,
        coons_bicubic,
        curve_frenet,
        drag_point,
        drag_surface_point,
        ellipse,
        extrude,
        fill_hole,
        fit_curve,
        fit_surface,
        generalized_bicubic,
        generalized_biquadratic,
        gordon,
        interpolate_curve,
        interpolate_surface,
        loft,
        make_compatible,
        revolve,
        ruled,
        surface_curvatures,
        sweep,
    )
    from .bridge import (
        ImportedModel,
        curve_deviation,
        from_occ,
        read_iges,
        read_step,
        surface_deviation,
        to_edge,
        to_face,
        to_occ,
        write_iges,
        write_step,
    )

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
