r"""Filling curve networks: Coons patches and Gordon surfaces (course §6-17..6-25).

Three transfinite interpolants, each returned as ONE tensor-product :class:`BSplineSurface` that is
*exactly* the classical formula (not a fit):

* :func:`coons` — the bilinearly blended Coons patch of four boundary curves (course §6-20),

  .. math::

      S = \underbrace{(1-\bar v)\,c_0(u) + \bar v\,c_1(u)}_{\text{ruled in } v}
        + \underbrace{(1-\bar u)\,d_0(v) + \bar u\,d_1(v)}_{\text{ruled in } u}
        - \underbrace{\textstyle\sum (1-\bar u\,|\,\bar u)(1-\bar v\,|\,\bar v) P_{ij}}_{\text{bilinear}}

  with :math:`\bar u, \bar v` the normalised parameters. Each term is a B-spline surface (the
  linear blends are degree-1 B-splines), so after degree elevation and knot refinement to one
  degree ``(max(p, 1), max(q, 1))`` and one pair of knot vectors the three nets simply add.
* :func:`coons_bicubic` — the bicubically blended Coons patch (course §6-21): cubic Hermite
  blending of the boundary curves *and* the cross-boundary derivative curves, minus the bicubic
  Hermite interpolant of the corner data (positions, tangents, twists).
* :func:`gordon` — the Gordon surface of a network of ``m`` u-curves and ``n`` v-curves (course
  §6-22..6-25; W. J. Gordon, "Spline-blended surface interpolation through curve networks",
  J. Math. Mech. 18 (1969)): the Boolean sum :math:`P_1 \oplus P_2 = P_1 + P_2 - P_1 P_2` of the
  spline interpolation projector across v (the loft of the u-curves) and across u (the loft of the
  v-curves); :math:`P_1 P_2` is the tensor-product interpolant of the intersection points.

Exactness
---------
Every step (affine reparametrisation, degree elevation, knot refinement, adding nets) is an exact
operation on B-splines, so the results equal the formulas up to floating-point round-off, and the
boundary rows of a Coons net *are* the boundary curves' poles (the blending terms cancel there
pole for pole). Gordon surfaces interpolate the network to the round-off of the banded
interpolation solves (~1e-13 relative), provided the network is consistent (below).

Rational input
--------------
Coons patches of rational boundaries are built in homogeneous coordinates, which is exact when the
homogeneous corners agree; the weights of each boundary are first scaled by a constant (which
does not change the curve) to make them agree. That is possible unless the product of the
corner-weight ratios around the loop differs from 1; then the boundaries are approximated as
below. Gordon surfaces of rational networks are built in homogeneous coordinates when the
curves meet in homogeneous space too (for instance a network of iso-curves of one NURBS
surface); otherwise, and for :func:`coons_bicubic` (whose derivative data are Cartesian), rational
curves are replaced by polynomial B-spline approximations within ``approx_tol`` (measured on dense
samples, see :func:`polynomial_approximation`), so the result is within that distance of the
rational network.

Modules
-------
The code lives in :mod:`algorithms.coons_patches` (Coons patches, the shared network tolerances
and :func:`polynomial_approximation`) and :mod:`algorithms.gordon_surfaces` (Gordon surfaces and
:func:`network_parameters`); this module re-exports their public names.
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
