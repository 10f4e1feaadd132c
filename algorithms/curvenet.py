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
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _validate as V
from .compat import common_knots, make_compatible, missing_knots
from .degree import elevate_poles
from .knots import merge_knots, refine_poles, snap_knots
from .curve import BSplineCurve
from .errors import InvalidGeometryError, ToleranceError
from .basis import greville
from .fitting import averaged_knots, interpolate_values
from .rational import from_homogeneous, to_homogeneous
from .surface import BSplineSurface

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

Array = NDArray[np.float64]

#: Largest gap allowed between curves that should meet (Coons corners, Gordon intersections),
#: absolute, in model units (OCC's ``Precision::Confusion()``). Gaps up to it are closed (Coons:
#: the curves' end poles move to the corner's mean; Gordon: the intersection point is the mean);
#: larger ones raise :class:`InvalidGeometryError`.
NETWORK_TOLERANCE: float = 1e-7

#: Bicubic Coons corner compatibility: a cross-boundary derivative at a corner must equal the
#: tangent of the adjacent boundary there to this tolerance, relative to the larger of the two
#: vectors' lengths (and 1).
DERIVATIVE_TOLERANCE: float = 1e-7

#: Default largest distance between a rational curve and the polynomial B-spline that replaces it
#: where an exact homogeneous construction is impossible (absolute, model units).
APPROXIMATION_TOLERANCE: float = 1e-6

#: Closest-point search between two curves: samples per non-empty knot span (at least 16 per
#: curve) for the starting guess, then Gauss-Newton iterations.
_SAMPLES_PER_SPAN = 8
_NEWTON_STEPS = 40
#: Starting pairs refined per curve pair (the closest sample pairs), so that a nearby local
#: minimum of the distance does not hide the intersection.
_STARTS = 8

#: Relative agreement demanded of homogeneous corner / intersection weights.
_WEIGHT_RTOL = 1e-12

_CORNERS = ("(u0, v0)", "(u1, v0)", "(u1, v1)", "(u0, v1)")


# ------------------------------------------------------------------------------------ helpers
def _tol(tol: float | None, default: float, name: str = "tol") -> float:
    if tol is None:
        return default
    t = float(tol)
    if not np.isfinite(t) or t < 0:
        raise InvalidGeometryError(f"{name}: expected a finite value >= 0, got {tol!r}")
    return t


def _curve(c: object, name: str) -> BSplineCurve:
    if not isinstance(c, BSplineCurve):
        raise InvalidGeometryError(f"{name}: expected a BSplineCurve, got {type(c).__name__}")
    return c


def _curves(items: object, name: str, minimum: int = 2) -> list[BSplineCurve]:
    try:
        out = list(items)  # type: ignore[call-overload]
    except TypeError as err:
        raise InvalidGeometryError(f"{name}: expected a sequence of BSplineCurve, got {type(items).__name__}") from err
    if len(out) < minimum:
        raise InvalidGeometryError(f"{name}: expected at least {minimum} curves, got {len(out)}")
    return [_curve(c, f"{name}[{i}]") for i, c in enumerate(out)]


def _same_dim(named: dict[str, BSplineCurve]) -> int:
    dims = {k: c.dim for k, c in named.items()}
    if len(set(dims.values())) != 1:
        raise InvalidGeometryError(f"curves: all must have the same dimension, got {dims}")
    return next(iter(dims.values()))


def _hnet(c: BSplineCurve, rational: bool) -> Array:
    """Poles of a (compatible) curve, homogeneous ``(n, d+1)`` if ``rational``."""
    if not rational:
        return np.asarray(c.control_points, float)
    w = np.ones(c.n_poles) if c.weights is None else c.weights
    return to_homogeneous(np.asarray(c.control_points, float), w)


def _with_end_points(c: BSplineCurve, start: Array, end: Array) -> BSplineCurve:
    """A clamped curve with its first and last pole (= its end points) replaced."""
    P = np.array(c.control_points, float)
    P[0], P[-1] = start, end
    return BSplineCurve._trusted(c.degree, c.knots, P, c.weights)


def _unify(nets: list[tuple[tuple[int, int], tuple[Array, Array], Array]]) -> tuple[tuple[int, int], tuple[Array, Array], list[Array]]:
    """Bring tensor-product nets to one pair of degrees and knot vectors (exact operations).

    Each item is ``((p, q), (U, V), H)`` with ``H`` of shape ``(n_u, n_v, k)`` (homogeneous
    coordinates for rational nets: the kernels are linear, so no weight is ever divided by);
    all are clamped on one domain. Per direction: degree elevation, then knot refinement to the
    union of the knot vectors, as :func:`make_compatible` does for curves.
    """
    items = [(list(d), list(kn), np.asarray(H, float)) for d, kn, H in nets]
    for ax in (0, 1):
        top = max(d[ax] for d, _, _ in items)
        elevated = []
        for d, kn, H in items:
            if d[ax] < top:
                kn = list(kn)
                kn[ax], Hx = elevate_poles(kn[ax], d[ax], np.moveaxis(H, ax, 0), top - d[ax])
                H = np.moveaxis(Hx, 0, ax)
                d = list(d)
                d[ax] = top
            elevated.append((d, kn, H))
        items = elevated
        T = common_knots([kn[ax] for _, kn, _ in items])
        lo, hi = float(T[0]), float(T[-1])
        T[: top + 1], T[-(top + 1):] = lo, hi
        out = []
        for d, kn, H in items:
            missing = missing_knots(kn[ax], T)
            if missing.size:
                tau = merge_knots(kn[ax], snap_knots(kn[ax], missing))
                H = np.moveaxis(refine_poles(kn[ax], top, np.moveaxis(H, ax, 0), tau), 0, ax)
            kn = list(kn)
            kn[ax] = T
            out.append((d, kn, H))
        items = out
    d, kn, _ = items[0]
    return (d[0], d[1]), (kn[0], kn[1]), [np.ascontiguousarray(H) for _, _, H in items]


def _surface(deg: tuple[int, int], kn: tuple[Array, Array], H: Array, rational: bool, what: str) -> BSplineSurface:
    if not rational:
        return BSplineSurface._trusted(deg, kn, np.ascontiguousarray(H))
    if np.any(H[..., -1] <= 0):
        raise InvalidGeometryError(
            f"{what}: the homogeneous construction gives non-positive weights "
            f"(min {float(H[..., -1].min()):.3g}); rescale the curves' weights"
        )
    P, w = from_homogeneous(np.ascontiguousarray(H))
    return BSplineSurface._trusted(deg, kn, P, w)


def _bezier(a: float, b: float, p: int) -> Array:
    return np.r_[np.full(p + 1, a), np.full(p + 1, b)]


# ------------------------------------------------------------------------------------ rational
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
        Default :data:`APPROXIMATION_TOLERANCE`.
    max_subdivisions : int
        Largest ``k`` tried.

    Returns
    -------
    (BSplineCurve, float)
        The approximation (same domain, degree ``max(curve.degree, 3)``) and its measured error.

    Raises
    ------
    ToleranceError
        ``tol`` is not reached with ``max_subdivisions``.
    """
    c = _curve(curve, "curve")
    tol = _tol(tol, APPROXIMATION_TOLERANCE)
    if not c.is_rational:
        return c, 0.0
    c = c.clamp()
    p = max(c.degree, 3)
    vals, mult = np.unique(c.knots, return_counts=True)
    mult = np.minimum(mult + (p - c.degree), p + 1)  # keeps the curve's continuity at its knots
    k = 2
    err = np.inf
    while k <= max_subdivisions:
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
        f"(error {err:.3g} with {max_subdivisions} pieces per span)"
    )


def _scale_loop_weights(cc: list[BSplineCurve]) -> list[BSplineCurve] | None:
    """Scale the weights of compatible rational Coons boundaries so that homogeneous corners agree.

    ``cc`` = bottom, right, top, left (clamped, rational). Returns ``None`` if impossible.
    """
    b, r, t, l = (c.weights for c in cc)
    s_b = 1.0
    s_l = b[0] / l[0]
    s_r = b[-1] / r[0]
    s_t = s_l * l[-1] / t[0]
    if abs(s_t * t[-1] - s_r * r[-1]) > _WEIGHT_RTOL * max(s_t * t[-1], s_r * r[-1]):
        return None
    scales = (s_b, s_r, s_t, s_l)
    return [BSplineCurve._trusted(c.degree, c.knots, c.control_points, c.weights * s) for c, s in zip(cc, scales)]


# ------------------------------------------------------------------------------------ Coons
def _check_loop(bottom: BSplineCurve, right: BSplineCurve, top: BSplineCurve, left: BSplineCurve,
                tol: float) -> Array:
    """Corner points ``(4, d)`` (means of the two curve ends) in order 00, 10, 11, 01, or raise."""
    ends = {k: (c.evaluate(c.domain[0]), c.evaluate(c.domain[1]))
            for k, c in (("bottom", bottom), ("right", right), ("top", top), ("left", left))}
    pairs = [(("bottom", 0), ("left", 0)), (("bottom", 1), ("right", 0)),
             (("top", 1), ("right", 1)), (("top", 0), ("left", 1))]
    gaps = [float(np.linalg.norm(ends[a][i] - ends[b][j])) for (a, i), (b, j) in pairs]
    if max(gaps) > tol:
        # Is one curve simply reversed? Reversing it must close all of its corners.
        for name in ends:
            flipped = dict(ends)
            flipped[name] = ends[name][::-1]
            g = [float(np.linalg.norm(flipped[a][i] - flipped[b][j])) for (a, i), (b, j) in pairs]
            if max(g) <= tol:
                raise InvalidGeometryError(
                    f"{name}: the curve runs the wrong way (reversing it closes the loop); expected "
                    "bottom = S(u, v0) and top = S(u, v1) both running from u0 to u1, left = S(u0, v) "
                    f"and right = S(u1, v) both from v0 to v1: pass {name}.reverse()"
                )
        k = int(np.argmax(gaps))
        (a, i), (b, j) = pairs[k]
        raise InvalidGeometryError(
            f"{a}, {b}: the boundary loop is open at corner {_CORNERS[k]}: the {('start', 'end')[i]} of "
            f"{a} and the {('start', 'end')[j]} of {b} are {gaps[k]:.3g} apart (tol={tol:g})"
        )
    return np.stack([(ends[a][i] + ends[b][j]) / 2 for (a, i), (b, j) in pairs])


def _boundaries(bottom, right, top, left, tol, rational_ok: bool, approx_tol: float):
    """Validated, corner-snapped, compatible boundary pairs ``(bottom, top)``, ``(left, right)``."""
    cs = {"bottom": _curve(bottom, "bottom"), "right": _curve(right, "right"),
          "top": _curve(top, "top"), "left": _curve(left, "left")}
    _same_dim(cs)
    if not rational_ok:
        cs = {k: polynomial_approximation(c, approx_tol)[0] for k, c in cs.items()}
    cs = {k: c.clamp() for k, c in cs.items()}
    P = _check_loop(cs["bottom"], cs["right"], cs["top"], cs["left"], tol)
    cs["bottom"] = _with_end_points(cs["bottom"], P[0], P[1])
    cs["right"] = _with_end_points(cs["right"], P[1], P[2])
    cs["top"] = _with_end_points(cs["top"], P[3], P[2])
    cs["left"] = _with_end_points(cs["left"], P[0], P[3])
    return cs


def coons(bottom: BSplineCurve, right: BSplineCurve, top: BSplineCurve, left: BSplineCurve, *,
          blend: str = "linear", tol: float | None = None, approx_tol: float | None = None) -> BSplineSurface:
    r"""Bilinearly blended Coons patch of four boundary curves (course §6-20), exactly.

    Orientation (the grid order, not a loop)::

        left = S(u0, v)  ^   top = S(u, v1)  ->   ^  right = S(u1, v)
                         |   bottom = S(u, v0) -> |

    ``bottom`` and ``top`` both run from ``u0`` to ``u1``; ``left`` and ``right`` both from ``v0``
    to ``v1``. (OCC's ``GeomFill_BSplineCurves`` takes a loop instead: its third and fourth curves
    are ``top`` and ``left`` reversed.)

    Parameters
    ----------
    bottom, right, top, left : BSplineCurve
        Same dimension; any degrees, knots, clamping; rational allowed (see the module notes).
        The u domain is the common domain of ``bottom`` and ``top`` if they share one, else
        ``[0, 1]`` (both mapped affinely); likewise v from ``left`` and ``right``.
    blend : {"linear", "cubic"}
        Blending functions: ``(1 - t, t)``, the bilinearly blended patch of course §6-20
        (default), or the cubic Hermite pair ``(1 - 3t² + 2t³, 3t² - 2t³)``, which gives the
        bicubically blended patch with zero cross-boundary derivatives and twists (degree at
        least 3): the patch OCC's ``GeomFill_Coons`` builds from Bézier boundaries.
    tol : float, optional
        Largest corner gap accepted (default :data:`NETWORK_TOLERANCE`). Gaps up to ``tol`` are
        closed by moving the two end poles to their mean (each boundary moves by at most half
        the gap).
    approx_tol : float, optional
        Only for rational boundaries whose corner weights cannot be matched (module notes): the
        distance within which they are replaced by polynomial curves
        (:func:`polynomial_approximation`; default :data:`APPROXIMATION_TOLERANCE`).

    Returns
    -------
    BSplineSurface
        Degree ``(max(p_b, p_t, 1), max(q_l, q_r, 1))``, knots the union of the boundaries' knots.
        ``S(u, v0) == bottom(u)`` etc. to round-off: the net's boundary rows are the (compatible)
        boundary poles. Rational iff a boundary is.

    Raises
    ------
    InvalidGeometryError
        Not curves, mixed dimensions, a curve running the wrong way (the message names it), a
        corner gap above ``tol`` (the message names the corner, both curves and the gap).
    ToleranceError
        Rational boundaries that need approximating and cannot be approximated within
        ``approx_tol``.

    Notes
    -----
    The three terms are B-spline surfaces: the ruled surface in v (net rows ``c_0``, ``c_1``,
    degree 1 in v), the ruled surface in u, and the bilinear patch of the corners. Degree
    elevation of a linear function to degree ``q`` with knots ``V`` gives poles at the Greville
    abscissae, so the result is the *discrete* Coons formula applied to the boundary polygons
    with Greville-abscissa blending weights: ``P_ij = (1-η_j) c0_i + η_j c1_i + (1-ξ_i) d0_j +
    ξ_i d1_j - bilinear(ξ_i, η_j)``. OCC's ``GeomFill_Coons`` blends the pole arrays with its own
    weights: the cubic Hermite functions ``F = 1 - 3t² + 2t³``, ``G = 1 - F``, degree-elevated
    to the number of poles minus 1 and indexed by pole number. For Bézier boundaries of degree
    >= 3 that is exactly ``blend="cubic"``; for multi-span boundaries it is not a Coons formula
    (the blending follows pole indices, not parameters), and the surfaces differ inside.
    """
    tol = _tol(tol, NETWORK_TOLERANCE)
    atol = _tol(approx_tol, APPROXIMATION_TOLERANCE, "approx_tol")
    if blend not in ("linear", "cubic"):
        raise InvalidGeometryError(f"blend: expected 'linear' or 'cubic', got {blend!r}")
    cs = _boundaries(bottom, right, top, left, tol, True, atol)
    b, t = make_compatible([cs["bottom"], cs["top"]])
    l, r = make_compatible([cs["left"], cs["right"]])
    rational = any(c.is_rational for c in (b, t, l, r))
    if rational:
        b, r, t, l = [c if c.is_rational else BSplineCurve._trusted(c.degree, c.knots, c.control_points, np.ones(c.n_poles))
                      for c in (b, r, t, l)]
        scaled = _scale_loop_weights([b, r, t, l])
        if scaled is None:
            # No exact homogeneous form: polynomial approximations within approx_tol.
            cs = _boundaries(bottom, right, top, left, tol, False, atol)
            b, t = make_compatible([cs["bottom"], cs["top"]])
            l, r = make_compatible([cs["left"], cs["right"]])
            rational = False
        else:
            b, r, t, l = scaled
    (u0, u1), (v0, v1) = b.domain, l.domain
    Hb, Ht, Hl, Hr = (_hnet(c, rational) for c in (b, t, l, r))
    # Blending functions as Bézier coefficients: linear (1-t, t) or cubic Hermite (1-3t²+2t³, 3t²-2t³).
    f0 = np.array([1.0, 0.0]) if blend == "linear" else np.array([1.0, 1.0, 0.0, 0.0])
    f1 = f0[::-1]
    k = f0.shape[0] - 1
    ku, kv = _bezier(u0, u1, k), _bezier(v0, v1, k)
    ruled_v = ((b.degree, k), (b.knots, kv), np.einsum("j,ik->ijk", f0, Hb) + np.einsum("j,ik->ijk", f1, Ht))
    ruled_u = ((k, l.degree), (ku, l.knots), np.einsum("i,jk->ijk", f0, Hl) + np.einsum("i,jk->ijk", f1, Hr))
    corners = (np.einsum("i,j,k->ijk", f0, f0, Hb[0]) + np.einsum("i,j,k->ijk", f1, f0, Hb[-1])
               + np.einsum("i,j,k->ijk", f0, f1, Ht[0]) + np.einsum("i,j,k->ijk", f1, f1, Ht[-1]))
    bilinear = ((k, k), (ku, kv), corners)
    deg, kn, (A, B, C) = _unify([ruled_v, ruled_u, bilinear])
    H = A + B - C
    # The boundary rows of A + B - C are the boundary poles up to round-off (B and C agree on
    # them); write the compatible boundary poles themselves so the boundaries are bit-faithful.
    H[:, 0], H[:, -1] = A[:, 0], A[:, -1]
    H[0, :], H[-1, :] = B[0, :], B[-1, :]
    return _surface(deg, kn, H, rational, "coons")


def _hermite_rows(c0: Array, c1: Array, d0: Array, d1: Array, h: float) -> Array:
    """Cubic Bézier rows of ``c0 H0 + c1 H1 + d0 H2 + d1 H3`` (Hermite data at both ends)."""
    return np.stack([c0, c0 + d0 * (h / 3), c1 - d1 * (h / 3), c1])


def coons_bicubic(bottom: BSplineCurve, right: BSplineCurve, top: BSplineCurve, left: BSplineCurve, *,
                  cross_derivatives: Sequence[BSplineCurve],
                  twists: str | ArrayLike = "average",
                  tol: float | None = None,
                  approx_tol: float | None = None) -> BSplineSurface:
    r"""Bicubically blended Coons patch (course §6-21): boundaries plus cross-boundary derivatives.

    .. math::

        S = \sum_k c_k(u) H_k(v) + \sum_k d_k(v) H_k(u) - \sum_{k,l} T_{kl} H_k(u) H_l(v)

    with the cubic Hermite functions ``H_0..H_3`` (value at each end, derivative at each end) on
    the domain, ``c = (bottom, top, ∂S/∂v along bottom, ∂S/∂v along top)``, ``d = (left, right,
    ∂S/∂u along left, ∂S/∂u along right)`` and ``T`` the corner data: points, first partials
    (taken from the cross-derivative curves) and twists ``∂²S/∂u∂v``.

    Parameters
    ----------
    bottom, right, top, left : BSplineCurve
        As in :func:`coons` (grid orientation), except that bottom and top must share one u domain
        and left and right one v domain (derivatives depend on the parametrisation, so nothing is
        reparametrised).
    cross_derivatives : sequence of 4 BSplineCurve
        ``(∂S/∂v (u, v0), ∂S/∂u (u1, v), ∂S/∂v (u, v1), ∂S/∂u (u0, v))``, in the order of the
        boundaries: the first and third are functions of u on the u domain, the others of v.
        At each corner the cross derivative of one boundary must equal the tangent of the other
        (e.g. ``cross_derivatives[0](u0) == left'(v0)``), to :data:`DERIVATIVE_TOLERANCE`.
    twists : "average", "zero" or array_like, shape (4, d)
        Twist vectors ``∂²S/∂u∂v`` at the corners ``(u0,v0), (u1,v0), (u1,v1), (u0,v1)``.
        ``"average"`` (default) uses the mean of the two twists the data imply at each corner
        (the u-derivative of the v-cross-derivative curve and the v-derivative of the u one):
        when they agree (compatible data, e.g. taken from one surface) the patch reproduces every
        boundary and every cross derivative exactly; when they do not, no bicubic Coons patch can,
        and each cross derivative is then off by at most half the twist mismatch times
        ``max |H_2| = 4/27`` of the domain length. ``"zero"`` gives zero twists (the classical
        choice, which makes the cross derivatives inexact unless the data twists vanish).
    tol : float, optional
        Corner gap tolerance, as in :func:`coons`.
    approx_tol : float, optional
        Rational curves are replaced by polynomial approximations within this distance
        (:func:`polynomial_approximation`; default :data:`APPROXIMATION_TOLERANCE`).

    Returns
    -------
    BSplineSurface
        Polynomial, degree ``(max(p, 3), max(q, 3))``.

    Raises
    ------
    InvalidGeometryError
        As :func:`coons`; domains that differ; a cross-derivative curve inconsistent with the
        adjacent boundary's tangent at a corner; bad ``twists``.
    """
    tol = _tol(tol, NETWORK_TOLERANCE)
    atol = _tol(approx_tol, APPROXIMATION_TOLERANCE, "approx_tol")
    cs = _boundaries(bottom, right, top, left, tol, False, atol)
    xd = _curves(cross_derivatives, "cross_derivatives", 4)
    if len(xd) != 4:
        raise InvalidGeometryError(f"cross_derivatives: expected 4 curves (bottom, right, top, left), got {len(xd)}")
    names = ("bottom", "right", "top", "left")
    xd = [polynomial_approximation(c, atol)[0].clamp() for c in xd]
    dim = cs["bottom"].dim
    for k, c in enumerate(xd):
        if c.dim != dim:
            raise InvalidGeometryError(f"cross_derivatives[{k}]: expected dimension {dim}, got {c.dim}")
    for group in (("bottom", "top", 0, 2), ("left", "right", 3, 1)):
        a, b2, i, j = group
        doms = {a: cs[a].domain, b2: cs[b2].domain, f"cross_derivatives[{i}]": xd[i].domain,
                f"cross_derivatives[{j}]": xd[j].domain}
        ref = doms[a]
        for k, dmn in doms.items():
            if not np.allclose(dmn, ref, rtol=0, atol=1e-12 * max(1.0, abs(ref[1] - ref[0]))):
                raise InvalidGeometryError(
                    f"{k}: expected the domain {ref} of {a} (derivatives depend on the parametrisation, so "
                    f"bottom/top and their cross derivatives must share one u domain, left/right one v domain), got {dmn}"
                )
    b, t, xb, xt = make_compatible([cs["bottom"], cs["top"], xd[0], xd[2]])
    l, r, xl, xr = make_compatible([cs["left"], cs["right"], xd[3], xd[1]])
    (u0, u1), (v0, v1) = b.domain, l.domain
    hu, hv = u1 - u0, v1 - v0

    # Corner data, order 00, 10, 11, 01: position, S_u, S_v, and the two twist estimates.
    def d1(c: BSplineCurve, x: float) -> Array:
        return c.derivatives(x, 1)

    B0, B1 = d1(b, u0), d1(b, u1)
    T0, T1 = d1(t, u0), d1(t, u1)
    L0, L1 = d1(l, v0), d1(l, v1)
    R0, R1 = d1(r, v0), d1(r, v1)
    XB0, XB1, XT0, XT1 = d1(xb, u0), d1(xb, u1), d1(xt, u0), d1(xt, u1)
    XL0, XL1, XR0, XR1 = d1(xl, v0), d1(xl, v1), d1(xr, v0), d1(xr, v1)
    P = np.stack([B0[0], B1[0], T1[0], T0[0]])
    Su = np.stack([XL0[0], XR0[0], XR1[0], XL1[0]])  # from the u-cross-derivative curves
    Sv = np.stack([XB0[0], XB1[0], XT1[0], XT0[0]])  # from the v-cross-derivative curves
    # Compatibility: Su must be the bottom/top tangent, Sv the left/right tangent.
    checks = [(Su, np.stack([B0[1], B1[1], T1[1], T0[1]]), ("left", "right", "right", "left"), ("bottom", "bottom", "top", "top")),
              (Sv, np.stack([L0[1], R0[1], R1[1], L1[1]]), ("bottom", "bottom", "top", "top"), ("left", "right", "right", "left"))]
    for got, want, xnames, bnames in checks:
        for k in range(4):
            scale = max(1.0, float(np.linalg.norm(got[k])), float(np.linalg.norm(want[k])))
            gap = float(np.linalg.norm(got[k] - want[k]))
            if gap > DERIVATIVE_TOLERANCE * scale:
                raise InvalidGeometryError(
                    f"cross_derivatives[{names.index(xnames[k])}]: at corner {_CORNERS[k]} the cross derivative "
                    f"along {xnames[k]} must equal the tangent of {bnames[k]} there; they differ by {gap:.3g}"
                )
    tw_v = np.stack([XB0[1], XB1[1], XT1[1], XT0[1]])  # d/du of dS/dv curves
    tw_u = np.stack([XL0[1], XR0[1], XR1[1], XL1[1]])  # d/dv of dS/du curves
    if isinstance(twists, str):
        if twists == "average":
            W = (tw_u + tw_v) / 2
        elif twists == "zero":
            W = np.zeros_like(tw_u)
        else:
            raise InvalidGeometryError(f"twists: expected 'average', 'zero' or an array of shape (4, {dim}), got {twists!r}")
    else:
        W = V.as_finite_array(twists, "twists")
        if W.shape != (4, dim):
            raise InvalidGeometryError(f"twists: expected shape (4, {dim}), got {W.shape}")

    Pb, Pt, Pxb, Pxt = (np.asarray(c.control_points, float) for c in (b, t, xb, xt))
    Pl, Pr, Pxl, Pxr = (np.asarray(c.control_points, float) for c in (l, r, xl, xr))
    L1net = _hermite_rows(Pb, Pt, Pxb, Pxt, hv).transpose(1, 0, 2)  # (nu, 4, d)
    L2net = _hermite_rows(Pl, Pr, Pxl, Pxr, hu)  # (4, nv, d)
    # Bicubic Hermite corner patch: Hermite in u of the Hermite-in-v rows.
    # along v at u0: positions P00, P01, derivatives Sv00, Sv01; at u1: P10, P11, Sv10, Sv11
    col_u0 = _hermite_rows(P[0], P[3], Sv[0], Sv[3], hv)  # (4, d) Bézier in v
    col_u1 = _hermite_rows(P[1], P[2], Sv[1], Sv[2], hv)
    dcol_u0 = _hermite_rows(Su[0], Su[3], W[0], W[3], hv)  # S_u along u0 (Bézier in v)
    dcol_u1 = _hermite_rows(Su[1], Su[2], W[1], W[2], hv)
    Tnet = _hermite_rows(col_u0, col_u1, dcol_u0, dcol_u1, hu)  # (4, 4, d)
    k3u, k3v = _bezier(u0, u1, 3), _bezier(v0, v1, 3)
    deg, kn, (A, B, C) = _unify([((b.degree, 3), (b.knots, k3v), L1net),
                                 ((3, l.degree), (k3u, l.knots), L2net),
                                 ((3, 3), (k3u, k3v), Tnet)])
    H = A + B - C
    H[:, 0], H[:, -1] = A[:, 0], A[:, -1]
    H[0, :], H[-1, :] = B[0, :], B[-1, :]
    return _surface(deg, kn, H, False, "coons_bicubic")


# ------------------------------------------------------------------------------------ Gordon
def _samples(c: BSplineCurve) -> Array:
    br = np.unique(c.knots[c.degree: c.n_poles + 1])
    k = max(_SAMPLES_PER_SPAN, -(-16 // (br.shape[0] - 1)))
    f = np.linspace(0.0, 1.0, k + 1)[:-1]
    return np.r_[(br[:-1, None] + f * np.diff(br)[:, None]).ravel(), br[-1]]


def network_parameters(u_curves: Sequence[BSplineCurve], v_curves: Sequence[BSplineCurve]) -> tuple[Array, Array, Array]:
    """Closest-point parameters of every u-curve / v-curve pair.

    For each pair ``(i, j)`` the parameters ``(s, t)`` minimising ``|u_curves[i](s) -
    v_curves[j](t)|``: a grid search over samples of both curves, then Gauss-Newton (vectorised
    over all pairs; loops run over curves, not points). With several local minima (closed
    curves, curves crossing twice) the sampled global minimum is refined.

    Returns
    -------
    s : ndarray, shape (m, n)
        Parameter on ``u_curves[i]`` (a u value).
    t : ndarray, shape (m, n)
        Parameter on ``v_curves[j]`` (a v value).
    dist : ndarray, shape (m, n)
        The distances at ``(s, t)``.
    """
    A = _curves(u_curves, "u_curves", 1)
    B = _curves(v_curves, "v_curves", 1)
    m, n = len(A), len(B)
    sa = [_samples(a) for a in A]
    sb = [_samples(b) for b in B]
    pa = [a.evaluate(x) for a, x in zip(A, sa)]
    pb = [b.evaluate(x) for b, x in zip(B, sb)]
    K = _STARTS
    s = np.empty((m, n, K))
    t = np.empty((m, n, K))
    for i in range(m):
        for j in range(n):
            d2 = np.sum((pa[i][:, None, :] - pb[j][None, :, :]) ** 2, axis=-1).ravel()
            best = np.argsort(d2, kind="stable")[:K]
            best = np.r_[best, np.full(K - best.shape[0], best[0])]
            k, l = np.unravel_index(best, (sa[i].shape[0], sb[j].shape[0]))
            s[i, j], t[i, j] = sa[i][k], sb[j][l]
    for _ in range(_NEWTON_STEPS):
        Da = np.stack([a.derivatives(s[i], 1) for i, a in enumerate(A)])  # (m, n, K, 2, d)
        Db = np.stack([b.derivatives(t[:, j], 1) for j, b in enumerate(B)], axis=1)
        F = Da[..., 0, :] - Db[..., 0, :]
        J = np.stack([Da[..., 1, :], -Db[..., 1, :]], axis=-1)  # (m, n, K, d, 2)
        JtJ = np.einsum("...ka,...kb->...ab", J, J)
        g = np.einsum("...ka,...k->...a", J, F)
        reg = (1e-14 * np.trace(JtJ, axis1=-2, axis2=-1) + 1e-300)[..., None, None] * np.eye(2)
        step = np.linalg.solve(JtJ + reg, g[..., None])[..., 0]
        s_new = np.stack([np.clip(s[i] - step[i, ..., 0], *a.domain) for i, a in enumerate(A)])
        t_new = np.stack([np.clip(t[:, j] - step[:, j, ..., 1], *b.domain) for j, b in enumerate(B)], axis=1)
        done = np.array_equal(s_new, s) and np.array_equal(t_new, t)
        s, t = s_new, t_new
        if done:
            break
    pa_ = np.stack([a.evaluate(s[i]) for i, a in enumerate(A)])
    pb_ = np.stack([b.evaluate(t[:, j]) for j, b in enumerate(B)], axis=1)
    dist = np.linalg.norm(pa_ - pb_, axis=-1)  # (m, n, K)
    k = np.argmin(dist, axis=-1)[..., None]
    take = lambda x: np.take_along_axis(x, k, axis=-1)[..., 0]  # noqa: E731
    return take(s), take(t), take(dist)


def _increasing(x: Array, name: str, what: str) -> None:
    if np.any(np.diff(x) <= 0):
        raise InvalidGeometryError(
            f"{name}: expected strictly increasing parameters ({what}), got {np.array2string(x, precision=6)}"
        )


def _cross_knots(params: Array, degree: int, domain: tuple[float, float]) -> Array:
    kn = averaged_knots(params, degree)
    kn[: degree + 1], kn[-(degree + 1):] = domain
    return kn


def gordon(u_curves: Sequence[BSplineCurve], v_curves: Sequence[BSplineCurve], *,
           u_params: ArrayLike | None = None, v_params: ArrayLike | None = None,
           degree: tuple[int, int] = (3, 3),
           cross_knots: tuple[ArrayLike | None, ArrayLike | None] = (None, None),
           tol: float | None = None, approx_tol: float | None = None) -> BSplineSurface:
    r"""Gordon surface through a network of u- and v-curves (course §6-22..6-25), exactly.

    The Boolean sum ``P1 + P2 - P12`` where ``P1`` interpolates the u-curves across v, ``P2`` the
    v-curves across u, and ``P12`` the intersection points in both directions, with the same
    spline interpolation operators (degree and knots) across u in ``P2`` and ``P12`` and across
    v in ``P1`` and ``P12``. The three are made compatible (degree elevation, knot refinement)
    and their nets added: one :class:`BSplineSurface` equal to the Boolean sum.

    Parameters
    ----------
    u_curves : sequence of m >= 2 BSplineCurve
        ``u_curves[i](u) = S(u, v_params[i])``, ordered by increasing v; made compatible (their
        common u domain if they share one, else ``[0, 1]``).
    v_curves : sequence of n >= 2 BSplineCurve
        ``v_curves[j](v) = S(u_params[j], v)``, ordered by increasing u; likewise in v.
    u_params : array_like, shape (n,), optional
        The u value of each v-curve, strictly increasing, inside the u-curves' domain. Default:
        computed (:func:`network_parameters`): the parameter where the u-curves cross v-curve j,
        which must be the same on every u-curve (to ``tol`` in space).
    v_params : array_like, shape (m,), optional
        The v value of each u-curve, likewise.
    degree : (int, int)
        Degrees of the interpolation across u (between v-curves) and across v; each lowered to
        the number of curves minus 1.
    cross_knots : (array_like or None, array_like or None)
        Knot vectors of those interpolations (length ``n + degree[0] + 1``, resp. ``m + degree[1]
        + 1``, clamped to the curves' domains). Default: averaging of the parameters (The NURBS
        Book eq. 9.8) with the ends moved to the domain ends.
    tol : float, optional
        Largest distance between ``u_curves[i](u_params[j])`` and ``v_curves[j](v_params[i])``
        (default :data:`NETWORK_TOLERANCE`). The intersection point used is their mean: the
        surface then reproduces each curve up to the interpolant of half the gaps.
    approx_tol : float, optional
        For rational networks that do not meet in homogeneous coordinates: distance within which
        rational curves are replaced by polynomial ones (default :data:`APPROXIMATION_TOLERANCE`).

    Returns
    -------
    BSplineSurface
        ``S(u, v_params[i]) == u_curves[i](u)`` and ``S(u_params[j], v) == v_curves[j](v)`` over
        the whole domains (to ~1e-13 relative on consistent networks). Degree ``(max(p_u,
        degree[0]), max(q_v, degree[1]))``.

    Raises
    ------
    InvalidGeometryError
        Fewer than 2 curves in a family, mixed dimensions, parameters not increasing or outside
        the domain, a u-curve and a v-curve that do not meet within ``tol`` (the message names
        both and the gap), or a network that is not consistent: the crossings of v-curve j lie at
        different u on different u-curves (Gordon surfaces need one parameter per curve).

    Notes
    -----
    **Reproduction.** ``I - P1 ⊕ P2 = (I - P1)(I - P2)``, so a surface ``F`` whose iso-curves
    form the network is reproduced whenever one projector reproduces it: e.g. ``P1 F = F`` when
    F's v spline space (degree, knots) is contained in the interpolation space across v and the
    Schoenberg–Whitney condition holds: pass ``cross_knots=(None, F.knots[1])`` and ``v_params``
    = F's v Greville abscissae, or take F polynomial in v (one v span) of degree <= ``degree[1]``
    with at least ``degree[1] + 1`` u-curves.
    """
    tol = _tol(tol, NETWORK_TOLERANCE)
    atol = _tol(approx_tol, APPROXIMATION_TOLERANCE, "approx_tol")
    A = _curves(u_curves, "u_curves")
    B = _curves(v_curves, "v_curves")
    dims = {c.dim for c in A + B}
    if len(dims) != 1:
        raise InvalidGeometryError(f"u_curves, v_curves: all curves must have one dimension, got {sorted(dims)}")
    if not isinstance(degree, (tuple, list)) or len(degree) != 2:
        raise InvalidGeometryError(f"degree: expected a pair (across u, across v), got {degree!r}")
    pu = min(V.as_degree(degree[0], "degree[0]"), len(B) - 1)
    qv = min(V.as_degree(degree[1], "degree[1]"), len(A) - 1)
    A = make_compatible(A)
    B = make_compatible(B)
    rational = A[0].is_rational or B[0].is_rational
    for attempt in ("exact", "approximate"):
        if attempt == "approximate":
            fa = [polynomial_approximation(c, atol) for c in A]
            fb = [polynomial_approximation(c, atol) for c in B]
            A = make_compatible([c for c, _ in fa])
            B = make_compatible([c for c, _ in fb])
            rational = False
            # the approximations move each curve by their measured error: allow for it at the crossings
            tol += max(e for _, e in fa) + max(e for _, e in fb)
        m, n = len(A), len(B)
        udom, vdom = A[0].domain, B[0].domain
        up, vp = _network_params(A, B, u_params, v_params, udom, vdom, tol)
        Pa = np.stack([a.evaluate(up) for a in A])  # (m, n, d): u_curves[i](u_j)
        Pb = np.stack([b.evaluate(vp) for b in B], axis=1)  # (m, n, d): v_curves[j](v_i)
        gap = np.linalg.norm(Pa - Pb, axis=-1)
        if gap.max() > tol:
            i, j = np.unravel_index(int(np.argmax(gap)), gap.shape)
            raise InvalidGeometryError(
                f"u_curves[{i}], v_curves[{j}]: the network is not consistent: u_curves[{i}](u_params[{j}]="
                f"{up[j]:.9g}) and v_curves[{j}](v_params[{i}]={vp[i]:.9g}) are {gap[i, j]:.3g} apart (tol={tol:g}); "
                "a Gordon surface needs every u-curve to cross v-curve j at the same u (and every v-curve "
                "to cross u-curve i at the same v): reparametrise the curves or pass consistent u_params/v_params"
            )
        if rational:
            Ha = np.stack([_hnet_eval(a, up) for a in A])
            Hb = np.stack([_hnet_eval(b, vp) for b in B], axis=1)
            if not np.all(np.abs(Ha[..., -1] - Hb[..., -1]) <= _WEIGHT_RTOL * 1e3 * np.maximum(Ha[..., -1], Hb[..., -1])):
                continue  # the curves do not meet in homogeneous space: approximate
        Ku = _cross_or_default(cross_knots[0], up, pu, udom, "cross_knots[0]")
        Kv = _cross_or_default(cross_knots[1], vp, qv, vdom, "cross_knots[1]")
        if rational:
            Q = (Ha + Hb) / 2
            Ra = np.stack([_hnet(a, True) for a in A])  # (m, nu, k)
            Rb = np.stack([_hnet(b, True) for b in B])  # (n, nv, k)
        else:
            Q = (Pa + Pb) / 2
            Ra = np.stack([np.asarray(a.control_points, float) for a in A])
            Rb = np.stack([np.asarray(b.control_points, float) for b in B])
        X1 = interpolate_values(vp, Ra, qv, Kv).transpose(1, 0, 2)  # (nu, m, k): across v
        X2 = interpolate_values(up, Rb, pu, Ku)  # (n, nv, k): across u
        X12 = interpolate_values(up, interpolate_values(vp, Q, qv, Kv).transpose(1, 0, 2), pu, Ku)  # (n, m, k)
        deg, kn, (S1, S2, S12) = _unify([((A[0].degree, qv), (A[0].knots, Kv), X1),
                                          ((pu, B[0].degree), (Ku, B[0].knots), X2),
                                          ((pu, qv), (Ku, Kv), X12)])
        H = S1 + S2 - S12
        if not rational or np.all(H[..., -1] > 0):
            break
        # the homogeneous Boolean sum has non-positive weights: no exact NURBS form; approximate
    return _surface(deg, kn, H, rational, "gordon")


def _hnet_eval(c: BSplineCurve, x: Array) -> Array:
    """Homogeneous values ``(w C, w)`` of a rational curve at ``x``."""
    w = np.ones(c.n_poles) if c.weights is None else c.weights
    H = BSplineCurve._trusted(c.degree, c.knots, to_homogeneous(np.asarray(c.control_points, float), w))
    return H.evaluate(x)


def _cross_or_default(kn: ArrayLike | None, params: Array, p: int, domain: tuple[float, float], name: str) -> Array:
    if kn is None:
        return _cross_knots(params, p, domain)
    t = V.check_knots(kn, p, params.shape[0], name)
    if not np.allclose([t[0], t[-1]], domain, rtol=0, atol=1e-12 * max(1.0, domain[1] - domain[0])) or \
            np.any(t[: p + 1] != t[0]) or np.any(t[-(p + 1):] != t[-1]):
        raise InvalidGeometryError(f"{name}: expected a clamped knot vector on the domain {domain}, got [{t[0]!r} .. {t[-1]!r}]")
    t = t.copy()
    t[: p + 1], t[-(p + 1):] = domain
    return t


def _network_params(A: list[BSplineCurve], B: list[BSplineCurve], u_params, v_params,
                    udom: tuple[float, float], vdom: tuple[float, float], tol: float) -> tuple[Array, Array]:
    m, n = len(A), len(B)
    given = []
    for x, count, dom, name, what in ((u_params, n, udom, "u_params", "one per v-curve, in order of increasing u"),
                                      (v_params, m, vdom, "v_params", "one per u-curve, in order of increasing v")):
        if x is None:
            given.append(None)
            continue
        a = V.as_finite_array(x, name, ndim=1)
        if a.shape[0] != count:
            raise InvalidGeometryError(f"{name}: expected {count} values ({what}), got {a.shape[0]}")
        a = V.check_parameters(a, *dom, name=name)
        _increasing(a, name, what)
        given.append(a)
    up, vp = given
    if up is None or vp is None:
        s, t, dist = network_parameters(A, B)
        if dist.max() > tol:
            i, j = np.unravel_index(int(np.argmax(dist)), dist.shape)
            raise InvalidGeometryError(
                f"u_curves[{i}], v_curves[{j}]: the curves do not meet: closest distance {dist[i, j]:.3g} "
                f"at u={s[i, j]:.9g}, v={t[i, j]:.9g} (tol={tol:g})"
            )
        if up is None:
            up = np.median(s, axis=0)
            _increasing(up, "v_curves", "the u values where the v-curves cross the u-curves; order the v-curves by increasing u")
        if vp is None:
            vp = np.median(t, axis=1)
            _increasing(vp, "u_curves", "the v values where the u-curves cross the v-curves; order the u-curves by increasing v")
    return up, vp
