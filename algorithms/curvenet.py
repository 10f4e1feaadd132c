"""Filling curve networks: Coons patches and Gordon surfaces (course §6-17..6-25).

One import point for the curve-net constructions, each returning ONE tensor-product
:class:`BSplineSurface` that is exactly the classical formula (not a fit):

* :func:`coons` (bilinear blend, course §6-20) and :func:`coons_bicubic` (course §6-21), with the
  shared network tolerances and :func:`polynomial_approximation`, live in
  :mod:`algorithms.coons_patches`; its docstring has the formulas, the exactness argument and the
  handling of rational boundaries;
* :func:`gordon` and :func:`network_parameters` (course §6-22..6-25) live in
  :mod:`algorithms.gordon_surfaces`.
"""

from __future__ import annotations

from .coons_patches import (
    APPROXIMATION_TOLERANCE,
    DERIVATIVE_TOLERANCE,
    NETWORK_TOLERANCE,
    coons,
    coons_bicubic,
    polynomial_approximation,
)
from .gordon_surfaces import gordon, network_parameters

__all__ = [
    "NETWORK_TOLERANCE",
    "DERIVATIVE_TOLERANCE",
    "APPROXIMATION_TOLERANCE",
    "coons",
    "coons_bicubic",
    "gordon",
    "network_parameters",
    "polynomial_approximation",
]
