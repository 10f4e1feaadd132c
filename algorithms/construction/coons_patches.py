r"""Coons patches (course §6-20, §6-21). The helpers they share with Gordon surfaces
(:mod:`occsurf.algorithms.construction.gordon_surfaces`: argument checks, compatible
tensor-product nets) are in :mod:`occsurf.algorithms.construction._common`, the polynomial
approximation of rational curves both use in
:mod:`occsurf.algorithms.construction.rational_approximation`;
:mod:`occsurf.algorithms.construction` re-exports them all. Tolerances: ``NETWORK_TOLERANCE``, ``DERIVATIVE_TOLERANCE``,
``APPROXIMATION_TOLERANCE`` and ``HOMOGENEOUS_WEIGHT_RTOL`` of :mod:`occsurf.algorithms.tolerances`,
read at call time.

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
samples, see :func:`~occsurf.algorithms.construction.polynomial_approximation`), so the result is within that distance of the
rational network.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.compat import compatible_sets, make_compatible
from ..kernel.curve import BSplineCurve
from ..kernel.degree import elevate_poles
from ..kernel.surface import BSplineSurface
from ._common import Net, check_curve, check_curves, homogeneous_poles, resolve_tolerance, surface_from_net, unify_nets
from .rational_approximation import polynomial_approximation

__all__ = [
    "coons",
    "coons_bicubic",
]

Array = NDArray[np.float64]

_CORNERS = ("(u0, v0)", "(u1, v0)", "(u1, v1)", "(u0, v1)")


# ------------------------------------------------------------------------------------ helpers
def _same_dim(named: dict[str, BSplineCurve]) -> int:
    dims = {k: c.dim for k, c in named.items()}
    if len(set(dims.values())) != 1:
        raise InvalidGeometryError(f"curves: all must have the same dimension, got {dims}")
    return next(iter(dims.values()))


def _with_end_points(c: BSplineCurve, start: Array, end: Array) -> BSplineCurve:
    """A clamped curve with its first and last pole (= its end points) replaced."""
    P = np.array(c.control_points, float)
    P[0], P[-1] = start, end
    return BSplineCurve._trusted(c.degree, c.knots, P, c.weights)


def _bezier(a: float, b: float, p: int) -> Array:
    return np.r_[np.full(p + 1, a), np.full(p + 1, b)]


def _boolean_sum(A: Array, B: Array, C: Array) -> Array:
    """The Coons net ``A + B - C`` of three nets on the same knots, with its boundary rows written.

    ``A`` is the term that interpolates the boundaries ``v = v0, v1`` (its first and last columns
    are their poles), ``B`` the term for ``u = u0, u1`` (first and last rows), ``C`` the corner
    term. Arithmetically the boundary rows of ``A + B - C`` are those poles up to round-off (the
    other two terms agree on them); they are copied from ``A`` and ``B`` so that the patch's
    boundaries are the given curves bit for bit. Shapes ``(n_u, n_v, k)``.
    """
    H = A + B - C
    H[:, 0], H[:, -1] = A[:, 0], A[:, -1]
    H[0, :], H[-1, :] = B[0, :], B[-1, :]
    return H


# ------------------------------------------------------------------------------------ rational
def _scale_loop_weights(cc: list[BSplineCurve]) -> list[BSplineCurve] | None:
    """Scale the weights of compatible rational Coons boundaries so that homogeneous corners agree.

    ``cc`` = bottom, right, top, left (clamped, rational). Returns ``None`` if impossible.
    """
    b, r, t, l = (c.weights for c in cc)
    if b is None or r is None or t is None or l is None:
        raise ValueError("_scale_loop_weights: expected rational boundaries")
    s_b = 1.0
    s_l = b[0] / l[0]
    s_r = b[-1] / r[0]
    s_t = s_l * l[-1] / t[0]
    if abs(s_t * t[-1] - s_r * r[-1]) > tolerances.HOMOGENEOUS_WEIGHT_RTOL * max(s_t * t[-1], s_r * r[-1]):
        return None
    scales = (s_b, s_r, s_t, s_l)
    return [BSplineCurve._trusted(c.degree, c.knots, c.control_points, w * s) for c, w, s in zip(cc, (b, r, t, l), scales)]


# ------------------------------------------------------------------------------------ Coons
#: The corners 00, 10, 11, 01 as (curve, end) index pairs into _check_loop's array of end poles:
#: rows are curve of the first end, its end, curve of the second end, its end.
_CORNER_ENDS = np.array([[0, 0, 2, 2], [0, 1, 1, 0], [3, 1, 1, 3], [0, 0, 1, 1]])


def _check_loop(bottom: BSplineCurve, right: BSplineCurve, top: BSplineCurve, left: BSplineCurve,
                tol: float) -> tuple[Array, bool]:
    """Corner points ``(4, d)`` (means of the two curve ends) in order 00, 10, 11, 01, and whether
    any end moves to them (False: the curves share every corner exactly), or raise. The curves
    must be clamped."""
    # clamped curves: the end points are the end poles (exact, no evaluation); E[k, e] is end e of
    # curve k in the order bottom, right, top, left, and the corners 00, 10, 11, 01 pair them as
    # (bottom 0, left 0), (bottom 1, right 0), (top 1, right 1), (top 0, left 1) (_CORNER_ENDS)
    E = np.stack([c.control_points[:: c.control_points.shape[0] - 1] for c in (bottom, right, top, left)])
    first, second = E[_CORNER_ENDS[0], _CORNER_ENDS[1]], E[_CORNER_ENDS[2], _CORNER_ENDS[3]]
    gaps = np.sqrt(np.square(first - second).sum(axis=1)).tolist()  # np.linalg.norm's values, one call
    if max(gaps) > tol:
        ends = {k: (E[n, 0], E[n, 1]) for n, k in enumerate(("bottom", "right", "top", "left"))}
        pairs = [(("bottom", 0), ("left", 0)), (("bottom", 1), ("right", 0)),
                 (("top", 1), ("right", 1)), (("top", 0), ("left", 1))]
        # Are curves merely reversed or swapped? Try every reversal subset with and without
        # swapping left/right or bottom/top (48 cases of 4 point distances): name the fix.
        order = ("bottom", "right", "top", "left")
        expect = ("expected bottom = S(u, v0) and top = S(u, v1) both running from u0 to u1, "
                  "left = S(u0, v) and right = S(u1, v) both from v0 to v1")
        for swap in (None, ("left", "right"), ("bottom", "top")):
            for mask in range(16):
                if swap is None and mask == 0:
                    continue
                flipped = dict(ends)
                if swap is not None:
                    flipped[swap[0]], flipped[swap[1]] = ends[swap[1]], ends[swap[0]]
                rev = [n for bit, n in enumerate(order) if mask >> bit & 1]
                for n in rev:
                    flipped[n] = flipped[n][::-1]
                g = [float(np.linalg.norm(flipped[a][i] - flipped[b][j])) for (a, i), (b, j) in pairs]
                if max(g) > tol:
                    continue
                fix = ([f"swap {swap[0]} and {swap[1]}"] if swap else []) + [f"pass {n}.reverse()" for n in rev]
                if swap is None and len(rev) == 1:
                    what = f"{rev[0]}: the curve runs the wrong way (reversing it closes the loop)"
                elif swap is None and rev == ["top", "left"]:
                    what = ("top, left: the curves form a head-to-tail loop (OCC's GeomFill_BSplineCurves "
                            "convention), but coons takes the grid orientation")
                elif swap is None:
                    what = f"{', '.join(rev)}: the curves run the wrong way (reversing them closes the loop)"
                else:
                    what = f"{swap[0]}, {swap[1]}: the curves are swapped (exchanging them closes the loop)"
                raise InvalidGeometryError(f"{what}; {expect}: {', '.join(fix)}")
        k = int(np.argmax(gaps))
        (a, i), (b, j) = pairs[k]
        raise InvalidGeometryError(
            f"{a}, {b}: the boundary loop is open at corner {_CORNERS[k]}: the {('start', 'end')[i]} of "
            f"{a} and the {('start', 'end')[j]} of {b} are {gaps[k]:.3g} apart (tol={tol:g})"
        )
    return (first + second) / 2, not np.array_equal(first, second)


def _boundaries(bottom: object, right: object, top: object, left: object, tol: float, rational_ok: bool,
                approx_tol: float) -> dict[str, BSplineCurve]:
    """The four boundaries by name, validated, clamped and corner-snapped (not yet compatible).

    Polynomial approximations within ``approx_tol`` replace rational curves unless
    ``rational_ok``; corner gaps up to ``tol`` are closed by moving the end poles to the corner's
    mean (:func:`_check_loop`).
    """
    cs = {"bottom": check_curve(bottom, "bottom"), "right": check_curve(right, "right"),
          "top": check_curve(top, "top"), "left": check_curve(left, "left")}
    _same_dim(cs)
    if not rational_ok:
        cs = {k: polynomial_approximation(c, approx_tol)[0] for k, c in cs.items()}
    cs = {k: c.clamp() for k, c in cs.items()}
    P, moved = _check_loop(cs["bottom"], cs["right"], cs["top"], cs["left"], tol)
    if not moved:
        return cs  # every corner shared exactly: the curves as they are
    cs["bottom"] = _with_end_points(cs["bottom"], P[0], P[1])
    cs["right"] = _with_end_points(cs["right"], P[1], P[2])
    cs["top"] = _with_end_points(cs["top"], P[3], P[2])
    cs["left"] = _with_end_points(cs["left"], P[0], P[3])
    return cs


def _compatible_loop(bottom: object, right: object, top: object, left: object, tol: float, rational_ok: bool,
                     approx_tol: float) -> tuple[BSplineCurve, BSplineCurve, BSplineCurve, BSplineCurve]:
    """The boundaries ``(bottom, right, top, left)`` of :func:`_boundaries`, made compatible in pairs.

    ``bottom`` and ``top`` share one degree and one knot vector (the u direction of the patch),
    ``left`` and ``right`` another (v), as :func:`occsurf.algorithms.kernel.compat.make_compatible`
    makes them (both pairs in one :func:`~occsurf.algorithms.kernel.compat.compatible_sets` call);
    the loop's corners coincide.
    """
    cs = _boundaries(bottom, right, top, left, tol, rational_ok, approx_tol)
    (pu, U, ((Pb, wb), (Pt, wt))), (pv, V, ((Pl, wl), (Pr, wr))) = compatible_sets(
        [([cs["bottom"], cs["top"]], None), ([cs["left"], cs["right"]], None)])
    return (BSplineCurve._trusted(pu, U, Pb, wb), BSplineCurve._trusted(pv, V, Pr, wr),
            BSplineCurve._trusted(pu, U, Pt, wt), BSplineCurve._trusted(pv, V, Pl, wl))


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
        Largest corner gap accepted (default ``tolerances.NETWORK_TOLERANCE``). Gaps up to ``tol`` are
        closed by moving the two end poles to their mean (each boundary moves by at most half
        the gap).
    approx_tol : float, optional
        Only for rational boundaries whose corner weights cannot be matched (module notes): the
        distance within which they are replaced by polynomial curves
        (:func:`~occsurf.algorithms.construction.polynomial_approximation`; default ``tolerances.APPROXIMATION_TOLERANCE``).

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
    tol = resolve_tolerance(tol, tolerances.NETWORK_TOLERANCE)
    atol = resolve_tolerance(approx_tol, tolerances.APPROXIMATION_TOLERANCE, "approx_tol")
    if blend not in ("linear", "cubic"):
        raise InvalidGeometryError(f"blend: expected 'linear' or 'cubic', got {blend!r}")
    b, r, t, l = _compatible_loop(bottom, right, top, left, tol, True, atol)
    if any(c.is_rational for c in (b, r, t, l)):
        net = _homogeneous_coons_net(b, r, t, l, blend)
        if net is not None:
            return surface_from_net(*net, True, "coons")
        # No exact homogeneous form (corner weights that cannot be matched, or a homogeneous net
        # with non-positive weights, e.g. 120-degree arcs of weight 0.5): polynomial approximations
        # of the boundaries within approx_tol.
        b, r, t, l = _compatible_loop(bottom, right, top, left, tol, False, atol)
    return surface_from_net(*_coons_net(b, r, t, l, blend, False), False, "coons")


def _homogeneous_coons_net(b: BSplineCurve, r: BSplineCurve, t: BSplineCurve, l: BSplineCurve,
                           blend: str) -> Net | None:
    """The exact homogeneous Coons net of a loop with a rational boundary, or ``None`` if there is none.

    Polynomial boundaries get weights 1; the weights of each boundary are then scaled by a constant
    so that the homogeneous corners agree (:func:`_scale_loop_weights`). ``None`` when that is
    impossible or when the homogeneous net has a weight ``<= 0`` (no NURBS form).
    """
    b, r, t, l = [c if c.is_rational else BSplineCurve._trusted(c.degree, c.knots, c.control_points, np.ones(c.n_poles))
                  for c in (b, r, t, l)]
    scaled = _scale_loop_weights([b, r, t, l])
    if scaled is None:
        return None
    sb, sr, st, sl = scaled
    deg, kn, H = _coons_net(sb, sr, st, sl, blend, True)
    return (deg, kn, H) if np.all(H[..., -1] > 0) else None


def _coons_net(b: BSplineCurve, r: BSplineCurve, t: BSplineCurve, l: BSplineCurve, blend: str,
               rational: bool) -> tuple[tuple[int, int], tuple[Array, Array], Array]:
    """Degrees, knots and (homogeneous if ``rational``) net of the Coons patch of compatible pairs
    ``(b, t)`` and ``(l, r)``."""
    k = 1 if blend == "linear" else 3
    (U, Hb, Ht), (Vk, Hl, Hr) = (_elevated_pair(c0, c1, k, rational) for c0, c1 in ((b, t), (l, r)))
    # The three terms written directly on the final knots: each blending function's B-spline
    # coefficients are its blossom at the knots (no Bézier nets to elevate and refine).
    f0u, f1u = _blend_coefficients(U, len(U) - Hb.shape[0] - 1, blend)
    f0v, f1v = _blend_coefficients(Vk, len(Vk) - Hl.shape[0] - 1, blend)
    A = f0v[None, :, None] * Hb[:, None, :] + f1v[None, :, None] * Ht[:, None, :]   # ruled in v
    B = f0u[:, None, None] * Hl[None, :, :] + f1u[:, None, None] * Hr[None, :, :]   # ruled in u
    C = (np.multiply.outer(np.outer(f0u, f0v), Hb[0]) + np.multiply.outer(np.outer(f1u, f0v), Hb[-1])
         + np.multiply.outer(np.outer(f0u, f1v), Ht[0]) + np.multiply.outer(np.outer(f1u, f1v), Ht[-1]))
    deg = (len(U) - Hb.shape[0] - 1, len(Vk) - Hl.shape[0] - 1)
    return deg, (U, Vk), _boolean_sum(A, B, C)


def _elevated_pair(c0: BSplineCurve, c1: BSplineCurve, k: int, rational: bool) -> tuple[Array, Array, Array]:
    """Knots and (homogeneous if ``rational``) poles of two compatible curves, degree raised to at
    least ``k`` (one elevation of the stacked poles: they share the knots)."""
    H0, H1 = homogeneous_poles(c0, rational), homogeneous_poles(c1, rational)
    U = np.asarray(c0.knots, float)
    if c0.degree < k:
        U, H = elevate_poles(U, c0.degree, np.concatenate((H0, H1), axis=-1), k - c0.degree)
        H0, H1 = H[:, : H0.shape[1]], H[:, H0.shape[1]:]
    return U, H0, H1


def _blend_coefficients(knots: Array, degree: int, blend: str) -> tuple[Array, Array]:
    r"""B-spline coefficients ``(f0, f1)``, shape (n,) each, of the Coons blending functions of the
    normalised parameter ``s`` on a clamped knot vector.

    A polynomial's coefficient ``j`` is its degree-``degree`` blossom at the knots ``t_{j+1} ..
    t_{j+degree}`` (course §2-6, §2-10); the blossom of ``s^k`` is ``e_k / C(degree, k)``, ``e_k``
    the elementary symmetric polynomial of the (normalised) arguments. Linear: ``f1 = s`` (the
    Greville abscissae); cubic: ``f1 = 3 s^2 - 2 s^3``; ``f0 = 1 - f1``. Needs ``degree >= 1``,
    resp. ``>= 3``.
    """
    n = knots.shape[0] - degree - 1
    lo, hi = knots[0], knots[-1]
    x = (knots[1 + np.arange(n)[:, None] + np.arange(degree)[None, :]] - lo) / (hi - lo)  # (n, degree)
    if blend == "linear":
        f1 = x.sum(axis=1) / degree  # x.mean(axis=1)'s two steps, without its wrapper
    else:
        e = np.zeros((4, n))
        e[0] = 1.0
        for r in range(degree):            # e_k of the first r+1 arguments (k <= 3): degree steps
            e[1:] = e[1:] + x[:, r] * e[:-1]
        d = degree
        f1 = 3 * e[2] / (d * (d - 1) / 2) - 2 * e[3] / (d * (d - 1) * (d - 2) / 6)
    return 1.0 - f1, f1


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
        (e.g. ``cross_derivatives[0](u0) == left'(v0)``), to ``tolerances.DERIVATIVE_TOLERANCE``.
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
        (:func:`~occsurf.algorithms.construction.polynomial_approximation`; default ``tolerances.APPROXIMATION_TOLERANCE``).

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
    tol = resolve_tolerance(tol, tolerances.NETWORK_TOLERANCE)
    atol = resolve_tolerance(approx_tol, tolerances.APPROXIMATION_TOLERANCE, "approx_tol")
    cs = _boundaries(bottom, right, top, left, tol, False, atol)
    xd = _cross_derivative_curves(cross_derivatives, cs["bottom"].dim, atol)
    _check_bicubic_domains(cs, xd)
    u_side = make_compatible([cs["bottom"], cs["top"], xd[0], xd[2]])   # bottom, top, their S_v
    v_side = make_compatible([cs["left"], cs["right"], xd[3], xd[1]])   # left, right, their S_u
    corners = _corner_data(*u_side, *v_side)
    _check_corner_derivatives(corners)
    W = _corner_twists(twists, corners)
    deg, kn, (A, B, C) = unify_nets(_bicubic_terms(u_side, v_side, corners, W))
    return surface_from_net(deg, kn, _boolean_sum(A, B, C), False, "coons_bicubic")


def _cross_derivative_curves(cross_derivatives: object, dim: int, approx_tol: float) -> list[BSplineCurve]:
    """The 4 cross-derivative curves, checked, polynomial (within ``approx_tol``) and clamped."""
    xd = check_curves(cross_derivatives, "cross_derivatives", 4)
    if len(xd) != 4:
        raise InvalidGeometryError(f"cross_derivatives: expected 4 curves (bottom, right, top, left), got {len(xd)}")
    xd = [polynomial_approximation(c, approx_tol)[0].clamp() for c in xd]
    for k, c in enumerate(xd):
        if c.dim != dim:
            raise InvalidGeometryError(f"cross_derivatives[{k}]: expected dimension {dim}, got {c.dim}")
    return xd


def _check_bicubic_domains(cs: dict[str, BSplineCurve], xd: list[BSplineCurve]) -> None:
    """Bottom, top and their cross derivatives share one u domain; left, right and theirs one v domain.

    Derivatives depend on the parametrisation, so nothing may be reparametrised: the domains must
    agree (to 1e-12 of their length) or :class:`InvalidGeometryError` names the one that differs.
    """
    for a, b2, i, j in (("bottom", "top", 0, 2), ("left", "right", 3, 1)):
        doms = {a: cs[a].domain, b2: cs[b2].domain, f"cross_derivatives[{i}]": xd[i].domain,
                f"cross_derivatives[{j}]": xd[j].domain}
        ref = doms[a]
        for k, dmn in doms.items():
            if not np.allclose(dmn, ref, rtol=0, atol=1e-12 * max(1.0, abs(ref[1] - ref[0]))):
                raise InvalidGeometryError(
                    f"{k}: expected the domain {ref} of {a} (derivatives depend on the parametrisation, so "
                    f"bottom/top and their cross derivatives must share one u domain, left/right one v domain), got {dmn}"
                )


class _CornerData(NamedTuple):
    """What the bicubic Coons data say at the corners ``(u0,v0), (u1,v0), (u1,v1), (u0,v1)``.

    Every field has shape ``(4, d)``, one row per corner in that order.
    """

    #: Positions (from bottom and top).
    points: Array
    #: ``S_u`` from the u-cross-derivative curves (along left and right) ...
    su: Array
    #: ... which must equal the tangents of bottom / top there.
    tangent_u: Array
    #: ``S_v`` from the v-cross-derivative curves (along bottom and top) ...
    sv: Array
    #: ... which must equal the tangents of left / right there.
    tangent_v: Array
    #: The twist ``S_uv`` implied by the u-cross-derivative curves (their v derivative) ...
    twist_u: Array
    #: ... and by the v-cross-derivative curves (their u derivative).
    twist_v: Array


def _corner_data(b: BSplineCurve, t: BSplineCurve, xb: BSplineCurve, xt: BSplineCurve,
                 l: BSplineCurve, r: BSplineCurve, xl: BSplineCurve, xr: BSplineCurve) -> _CornerData:
    """Corner data (:class:`_CornerData`) of the boundaries bottom ``b``, top ``t``, left ``l``,
    right ``r`` and the cross-derivative curves along them (``xb = S_v`` along bottom, ...)."""
    (u0, u1), (v0, v1) = b.domain, l.domain

    def d1(c: BSplineCurve, x: float) -> Array:
        return c.derivatives(x, 1)

    B0, B1 = d1(b, u0), d1(b, u1)
    T0, T1 = d1(t, u0), d1(t, u1)
    L0, L1 = d1(l, v0), d1(l, v1)
    R0, R1 = d1(r, v0), d1(r, v1)
    XB0, XB1, XT0, XT1 = d1(xb, u0), d1(xb, u1), d1(xt, u0), d1(xt, u1)
    XL0, XL1, XR0, XR1 = d1(xl, v0), d1(xl, v1), d1(xr, v0), d1(xr, v1)
    return _CornerData(
        points=np.stack([B0[0], B1[0], T1[0], T0[0]]),
        su=np.stack([XL0[0], XR0[0], XR1[0], XL1[0]]),
        tangent_u=np.stack([B0[1], B1[1], T1[1], T0[1]]),
        sv=np.stack([XB0[0], XB1[0], XT1[0], XT0[0]]),
        tangent_v=np.stack([L0[1], R0[1], R1[1], L1[1]]),
        twist_u=np.stack([XL0[1], XR0[1], XR1[1], XL1[1]]),
        twist_v=np.stack([XB0[1], XB1[1], XT1[1], XT0[1]]),
    )


def _check_corner_derivatives(corners: _CornerData) -> None:
    """At each corner ``S_u`` must be the bottom/top tangent and ``S_v`` the left/right tangent,
    to ``tolerances.DERIVATIVE_TOLERANCE`` relative to ``max(1, |a|, |b|)``; else
    :class:`InvalidGeometryError` names the cross-derivative curve and the corner."""
    names = ("bottom", "right", "top", "left")
    checks = [(corners.su, corners.tangent_u, ("left", "right", "right", "left"), ("bottom", "bottom", "top", "top")),
              (corners.sv, corners.tangent_v, ("bottom", "bottom", "top", "top"), ("left", "right", "right", "left"))]
    for got, want, xnames, bnames in checks:
        for k in range(4):
            scale = max(1.0, float(np.linalg.norm(got[k])), float(np.linalg.norm(want[k])))
            gap = float(np.linalg.norm(got[k] - want[k]))
            if gap > tolerances.DERIVATIVE_TOLERANCE * scale:
                raise InvalidGeometryError(
                    f"cross_derivatives[{names.index(xnames[k])}]: at corner {_CORNERS[k]} the cross derivative "
                    f"along {xnames[k]} must equal the tangent of {bnames[k]} there; they differ by {gap:.3g}"
                )


def _corner_twists(twists: str | ArrayLike, corners: _CornerData) -> Array:
    """The twist vectors ``(4, d)`` at the corners: ``"average"`` of the two the data imply,
    ``"zero"``, or the caller's array (checked: finite, shape ``(4, d)``)."""
    dim = corners.points.shape[1]
    if isinstance(twists, str):
        if twists == "average":
            return (corners.twist_u + corners.twist_v) / 2
        if twists == "zero":
            return np.zeros_like(corners.twist_u)
        raise InvalidGeometryError(
            f"twists: expected 'average', 'zero' or an array of shape (4, {dim}), got {twists!r}"
        )
    W = V.as_finite_array(twists, "twists")
    if W.shape != (4, dim):
        raise InvalidGeometryError(f"twists: expected shape (4, {dim}), got {W.shape}")
    return W


def _hermite_corner_patch(corners: _CornerData, W: Array, hu: float, hv: float) -> Array:
    """Bézier net ``(4, 4, d)`` of the bicubic Hermite interpolant of the corner data: positions,
    ``S_u`` (from the u-cross-derivative curves), ``S_v`` and the twists ``W``; ``hu``, ``hv`` the
    domain lengths. Hermite in u of the Hermite-in-v columns."""
    P, Su, Sv = corners.points, corners.su, corners.sv
    # along v at u0: positions P00, P01, derivatives Sv00, Sv01; at u1: P10, P11, Sv10, Sv11
    col_u0 = _hermite_rows(P[0], P[3], Sv[0], Sv[3], hv)  # (4, d) Bézier in v
    col_u1 = _hermite_rows(P[1], P[2], Sv[1], Sv[2], hv)
    dcol_u0 = _hermite_rows(Su[0], Su[3], W[0], W[3], hv)  # S_u along u0 (Bézier in v)
    dcol_u1 = _hermite_rows(Su[1], Su[2], W[1], W[2], hv)
    return _hermite_rows(col_u0, col_u1, dcol_u0, dcol_u1, hu)


def _bicubic_terms(u_side: Sequence[BSplineCurve], v_side: Sequence[BSplineCurve], corners: _CornerData,
                   W: Array) -> list[Net]:
    """The three terms of the bicubically blended Coons patch, as nets on their own knots.

    ``u_side = (bottom, top, S_v along bottom, S_v along top)`` and ``v_side = (left, right,
    S_u along left, S_u along right)``, each group compatible. Returns ``[L1, L2, T]``: the cubic
    Hermite blend in v of bottom/top and their cross derivatives (it interpolates them at ``v0``,
    ``v1``), the blend in u of left/right, and the bicubic Hermite patch of the corner data.
    """
    b, t, xb, xt = u_side
    l, r, xl, xr = v_side
    (u0, u1), (v0, v1) = b.domain, l.domain
    hu, hv = u1 - u0, v1 - v0
    Pb, Pt, Pxb, Pxt = (np.asarray(c.control_points, float) for c in u_side)
    Pl, Pr, Pxl, Pxr = (np.asarray(c.control_points, float) for c in v_side)
    L1net = _hermite_rows(Pb, Pt, Pxb, Pxt, hv).transpose(1, 0, 2)  # (nu, 4, d)
    L2net = _hermite_rows(Pl, Pr, Pxl, Pxr, hu)  # (4, nv, d)
    k3u, k3v = _bezier(u0, u1, 3), _bezier(v0, v1, 3)
    return [((b.degree, 3), (b.knots, k3v), L1net),
            ((3, l.degree), (k3u, l.knots), L2net),
            ((3, 3), (k3u, k3v), _hermite_corner_patch(corners, W, hu, hv))]
