"""Data fitting (course ch. 7): parametrisation, knot placement, interpolation and least-squares
fitting of curves and gridded surfaces by the Kronecker separation (§7-4, 7-5), lofting,
constrained and smoothed gridded fits (§7-7), scattered data, and adaptive hierarchical fitting
(§7-10).

Modules: :mod:`.interpolation` (parameters, knots, interpolation, least squares, loft),
:mod:`.gridded` (:func:`fit_grid` with smoothing, GCV, constraints, missing cells),
:mod:`.scattered` (:func:`fit_scattered`: point clouds, holes, parameter correction),
:mod:`.adaptive` (:func:`fit_adaptive`: a :class:`~occsurf.algorithms.hierarchical.HierarchicalSurface`
refined only where the data need it), :mod:`.adaptive_scattered` (:func:`fit_adaptive_scattered`:
the same for point clouds), :mod:`._missing` (grids with missing cells: sparse solve and GCV),
:mod:`._common` (sparse collocation, penalties, point projection).

Public names: :func:`parametrize`, :func:`averaged_knots`, :func:`approximation_knots`,
:func:`interpolate_curve`, :func:`fit_curve`, :func:`interpolate_surface`, :func:`fit_surface`,
:func:`loft`, :func:`fit_grid`, :class:`GridFit`, :class:`BoundaryCurve`,
:class:`CrossDerivative`, :class:`FixedPoint`, :class:`TangentPlane`, :class:`Symmetry`,
:func:`fit_scattered`, :class:`ScatteredFit`, :func:`fit_adaptive`, :class:`AdaptiveFit`,
:class:`LevelReport`, :func:`fit_adaptive_scattered`, :class:`ScatteredAdaptiveFit`, :func:`project_points`.
"""

from ._common import project_points
from .adaptive import AdaptiveFit, LevelReport, fit_adaptive
from .adaptive_scattered import ScatteredAdaptiveFit, fit_adaptive_scattered
from .gridded import BoundaryCurve, CrossDerivative, FixedPoint, GridFit, Symmetry, TangentPlane, fit_grid
from .interpolation import (
    approximation_knots,
    averaged_knots,
    fit_curve,
    fit_surface,
    interpolate_curve,
    interpolate_surface,
    loft,
    parametrize,
)
from .scattered import ScatteredFit, fit_scattered

__all__ = [
    "approximation_knots",
    "averaged_knots",
    "fit_curve",
    "fit_surface",
    "interpolate_curve",
    "interpolate_surface",
    "loft",
    "parametrize",
    "fit_grid",
    "GridFit",
    "BoundaryCurve",
    "CrossDerivative",
    "FixedPoint",
    "TangentPlane",
    "Symmetry",
    "fit_scattered",
    "ScatteredFit",
    "fit_adaptive",
    "AdaptiveFit",
    "LevelReport",
    "fit_adaptive_scattered",
    "ScatteredAdaptiveFit",
    "project_points",
]
