"""The spline kernel (course ch. 2 and 12): B-spline basis, knots, curves, surfaces, Bézier
form, blossoms, degree raising, rational (homogeneous) forms and exact conics.

Public names: :class:`BSplineCurve`, :class:`BSplineSurface`, :class:`TrimmedSurface` (a surface
with trimming loops of p-curves: a CAD face), :func:`make_compatible`, the conics
(:func:`circle`, :func:`arc`, :func:`ellipse`, :func:`conic_arc`, :func:`conic_from_shoulder`,
:func:`conic_through_point`, :func:`conic_type`); the array-level kernels live in :mod:`.basis`,
:mod:`.knots`, :mod:`.bezier`, :mod:`.blossom`, :mod:`.degree` and :mod:`.rational`. The private
:mod:`._common` holds what the frozen spline values share (``to_dict``/``from_dict``, ``==``,
``transform``; also used by :class:`~occsurf.algorithms.topology.spatch.SPatch`).

A surface method that works along one direction takes the curve method's arguments, then
``direction="u" | "v"`` as a required keyword (see :class:`BSplineSurface`).
"""

from .compat import make_compatible
from .conics import arc, circle, conic_arc, conic_from_shoulder, conic_through_point, conic_type, ellipse
from .curve import BSplineCurve
from .surface import BSplineSurface
from .trimmed import TrimmedSurface

__all__ = [
    "BSplineCurve",
    "BSplineSurface",
    "TrimmedSurface",
    "make_compatible",
    "arc",
    "circle",
    "conic_arc",
    "conic_from_shoulder",
    "conic_through_point",
    "conic_type",
    "ellipse",
]
