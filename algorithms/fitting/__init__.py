"""Data fitting (course ch. 7): parametrisation, knot placement, interpolation and least-squares
fitting of curves and gridded surfaces by the Kronecker separation (§7-4, 7-5), and lofting.

Public names: :func:`parametrize`, :func:`averaged_knots`, :func:`approximation_knots`,
:func:`interpolate_curve`, :func:`fit_curve`, :func:`interpolate_surface`, :func:`fit_surface`,
:func:`loft`.
"""

from .interpolation import approximation_knots, averaged_knots, fit_curve, fit_surface, interpolate_curve, interpolate_surface, loft, parametrize

__all__ = [
    "approximation_knots",
    "averaged_knots",
    "fit_curve",
    "fit_surface",
    "interpolate_curve",
    "interpolate_surface",
    "loft",
    "parametrize",
]
