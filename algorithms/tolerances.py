"""Tolerances and kernel limits, as documented module constants.

Every tolerance that an algorithm uses by default lives here, so that it is written once and can
be changed for a block of code with :func:`override`::

    from . import tolerances
    with tolerances.override(KNOT_REMOVAL=1e-6):
        c2 = c.remove_knot(0.5)

Functions also take an explicit ``tol=`` keyword, which wins over the module value.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = ["MAX_DEGREE", "KNOT_EQUALITY", "PARAMETER", "KNOT_REMOVAL", "WEIGHT_SUM", "MAX_CONDITION", "override"]

#: Highest degree accepted, the same as OpenCascade's ``Geom_BSplineCurve::MaxDegree()`` so that
#: every spline we build can be handed to OCC.
MAX_DEGREE: int = 25

#: Two knots closer than this (relative to the knot range) are treated as one knot when counting
#: multiplicities, inserting, or converting to OCC's distinct knots + multiplicities.
KNOT_EQUALITY: float = 1e-12

#: How far (relative to the domain length) a parameter may lie outside the domain and still be
#: snapped onto it rather than rejected. Covers round-off in callers' arithmetic.
PARAMETER: float = 1e-10

#: Default geometric tolerance for knot removal: the largest allowed movement of any control point
#: of the refined representation (which bounds the movement of the curve by the convex-hull
#: property). Absolute, in model units.
KNOT_REMOVAL: float = 1e-9

#: Tolerance on weights that must sum to one (affine combinations).
WEIGHT_SUM: float = 1e-12

#: A frame basis (or any matrix that must be inverted, e.g. of an affine or projective map) whose
#: 2-norm condition number exceeds this is treated as singular: its inverse would lose more than
#: ~12 of 16 significant digits.
MAX_CONDITION: float = 1e12

_NAMES = ("KNOT_EQUALITY", "PARAMETER", "KNOT_REMOVAL", "WEIGHT_SUM", "MAX_CONDITION")


@contextlib.contextmanager
def override(**values: float) -> Iterator[None]:
    """Temporarily replace module tolerances, e.g. ``override(KNOT_REMOVAL=1e-6)``.

    Parameters
    ----------
    **values : float
        New values keyed by constant name. ``MAX_DEGREE`` is a kernel limit and cannot be changed.

    Raises
    ------
    KeyError
        If a name is not an overridable tolerance of this module.
    """
    g = globals()
    for name in values:
        if name not in _NAMES:
            raise KeyError(f"override: {name!r} is not a tolerance; known: {', '.join(_NAMES)}")
    old = {name: g[name] for name in values}
    g.update({k: float(v) for k, v in values.items()})
    try:
        yield
    finally:
        g.update(old)
