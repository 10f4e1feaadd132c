"""Polynomial B-spline approximation of rational curves (course §6-20 .. §6-25), for the
constructions whose formulas need polynomial data: the bicubic Coons patch (Cartesian derivative
data, :mod:`~occsurf.algorithms.construction.coons_patches`), Coons loops and Gordon networks whose
homogeneous corners cannot be made to agree
(:mod:`~occsurf.algorithms.construction.gordon_surfaces`). Tolerance: ``APPROXIMATION_TOLERANCE``
of :mod:`occsurf.algorithms.tolerances`, read at call time.
"""

from __future__ import annotations

import numpy as np

from .. import _validate as V
from .. import tolerances
from ..errors import ToleranceError
from ..fitting.interpolation import interpolate_values
from ..kernel.basis import greville
from ..kernel.curve import BSplineCurve
from ._common import check_curve, resolve_tolerance

__all__ = ["polynomial_approximation"]


def polynomial_approximation(curve: BSplineCurve, tol: float | None = None, *,
                             max_subdivisions: int = 256) -> tuple[BSplineCurve, float]:
    """A polynomial B-spline within ``tol`` of a rational curve, with the measured error.

    Degree ``max(p, 3)``; knots: the curve's own (multiplicities raised with the degree, so the
    continuity at each knot is kept) with every span cut into ``k`` equal pieces, ``k = 2, 4, 8,
    ...``; the spline interpolating the curve at the Greville abscissae of those knots (which
    satisfy the Schoenberg–Whitney condition). Stops once the largest distance over 16 samples
    per span is at most ``tol``. The end points are interpolated exactly (they are Greville
    abscissae of clamped knots), so Coons corners and network ends stay put.

    Parameters
    ----------
    curve : BSplineCurve
        Returned unchanged (error 0.0) if it is not rational.
    tol : float, optional
        Default ``tolerances.APPROXIMATION_TOLERANCE``.
    max_subdivisions : int
        Largest ``k`` tried. A step whose work arrays would exceed ``tolerances.MAX_ARRAY_BYTES``
        is refused before it is made (InvalidGeometryError).

    Returns
    -------
    (BSplineCurve, float)
        The approximation (same domain, degree ``max(curve.degree, 3)``) and its measured error.

    Raises
    ------
    ToleranceError
        ``tol`` is not reached with ``max_subdivisions``.
    """
    c = check_curve(curve, "curve")
    tol = resolve_tolerance(tol, tolerances.APPROXIMATION_TOLERANCE)
    cap = V.check_times(max_subdivisions, "max_subdivisions")
    if not c.is_rational:
        return c, 0.0
    c = c.clamp()
    p = max(c.degree, 3)
    vals, mult = np.unique(c.knots, return_counts=True)
    mult = np.minimum(mult + (p - c.degree), p + 1)  # keeps the curve's continuity at its knots
    k = 2
    err = np.inf
    while k <= cap:
        # per piece: knots, Greville sites, homogeneous values, the banded system (2p + 1) and 16
        # samples of both curves; refused before the step that would pass MAX_ARRAY_BYTES
        V.check_size(((vals.size - 1) * k, 4 + c.dim + 2 * p + 1 + 16 * 2 * (c.dim + 1)),
                     f"polynomial_approximation with max_subdivisions={cap}: {k} pieces per span of {vals.size - 1}")
        f = np.linspace(0.0, 1.0, k + 1)[1:-1]
        extra = (vals[:-1, None] + f * np.diff(vals)[:, None]).ravel()
        kn = np.sort(np.r_[np.repeat(vals, mult), extra])
        x = greville(kn, p)  # Schoenberg-Whitney holds at the Greville abscissae
        approx = BSplineCurve._trusted(p, kn, interpolate_values(x, c.evaluate(x), p, kn))
        s = np.linspace(0.0, 1.0, 17)[:-1]
        br = np.unique(kn)
        y = np.r_[(br[:-1, None] + s * np.diff(br)[:, None]).ravel(), br[-1]]
        err = float(np.max(np.linalg.norm(approx.evaluate(y) - c.evaluate(y), axis=-1)))
        if err <= tol:
            return approx, err
        k *= 2
    raise ToleranceError(
        f"polynomial_approximation: could not approximate the rational curve within tol={tol:g} "
        f"(error {err:.3g} with {k // 2} pieces per span)"
    )
