"""Hole sides described by a curve and the neighbour's tangent planes (course §8-3, trimmed neighbours).

:func:`~occsurf.algorithms.topology.nsided.fill_hole` needs, per side, the boundary curve ``B`` and
a cross-boundary field ``X`` spanning the neighbour's tangent plane with ``B'``. When the side is an
iso-line of an untrimmed neighbour, :func:`~occsurf.algorithms.topology.nsided.side_from_surface`
gives ``X`` exactly. A real model's hole edge is a trimming curve: its p-curve is not an iso-line,
and the neighbour's cross derivative along it is no spline of low degree. This module builds the
side from what any source offers (a STEP model, a build123d face, our own surfaces): the boundary
curve and the neighbour's unit normals ``N`` at sample parameters. Then

.. math::

    X(s) \\approx B'(s) \\times N(s)

(tangent to the neighbour, across the boundary, pointing to the right of the curve seen from the
side ``N`` points to: into the neighbour when the loop runs counter-clockwise about ``N``) is fitted
by a cubic B-spline in the least-squares sense, the curve's own knots first, and the spans where the
tangent plane ``span(B', X)`` misses ``N`` by more than the angle tolerance are bisected until it is
met (or the samples no longer support another knot; what was achieved is returned). The boundary
curve is kept exactly, so the fill's G0 to the edge curve stays exact; its G1 to the neighbour is the
achieved fitting angle (the fill is G1 to the fitted field by construction).

:func:`corner_normals` and :func:`blend_normals` treat sides without a G1 condition (sharp edges of
the original model: only G0 is asked) and corners where the neighbours do not share a tangent plane
(the fill's plane at a corner is spanned by the two side tangents; a neighbour whose plane differs
there cannot be met at the corner by any surface; the normal field is turned into the corner plane
over a short span, and the G1 error left there is reported per edge). Where such a corner lies
between a side asking G1 and one asking only G0 (a crease of the original model ending at a
smooth joint), :func:`turn_end_tangent` first turns the G0 side's end tangent into the G1
neighbour's plane, moving that side near the corner by less than its G0 tolerance: G0 asks
position only, and the corner's G1 bound (the tangent's angle out of the plane) drops to zero.

References
----------
Course C25 §8-3. J. Peters, "Joining smooth patches around a vertex to form a C^k surface" (1992)
on transversal fields; The NURBS Book, 2nd ed., §9.4 (least-squares curve fitting).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.banded_lstsq import spline_lstsq
from ..kernel.curve import BSplineCurve
from .nsided import HoleSide

__all__ = ["SideFit", "side_from_normals", "fit_boundary", "corner_normals", "blend_normals", "plane_angle",
           "turn_end_tangent"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SideFit:
    """A side fitted by :func:`side_from_normals`.

    Attributes
    ----------
    side : HoleSide
        The exact curve and the fitted cross field (homogeneous 4-D for a rational curve).
    angle : float
        Largest angle (degrees) at the samples between ``span(B', X)`` and the neighbour's plane.
    spans : int
        Number of knot spans of the fitted field.
    converged : bool
        Whether ``angle <= angle_tol``.
    """

    side: HoleSide
    angle: float
    spans: int
    converged: bool


def _unit(v: Array) -> Array:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def plane_angle(normals: Array, tangents: Array, cross: Array) -> Array:
    """Angle (degrees, sign-free) between planes with ``normals`` (m, 3) and ``span(tangents, cross)``."""
    m, n = _unit(np.cross(tangents, cross)), _unit(normals)
    c = np.abs(np.einsum("mi,mi->m", n, m))
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(n, m), axis=-1), c))  # accurate near 0


def _cartesian_tangent(curve: BSplineCurve, s: Array) -> tuple[Array, Array]:
    """Points and Cartesian first derivatives (m, 3) of a possibly rational curve."""
    D = curve.derivatives(s, 1)
    return D[:, 0], D[:, 1]


def _weights_at(curve: BSplineCurve, s: Array) -> Array:
    if not curve.is_rational:
        return np.ones_like(s)
    H = BSplineCurve._trusted(curve.degree, curve.knots, curve.homogeneous_points)
    return H.evaluate(s)[:, 3]


def _check_inputs(curve: BSplineCurve, params: ArrayLike, normals: ArrayLike) -> tuple[Array, Array]:
    if not isinstance(curve, BSplineCurve) or curve.dim != 3:
        raise InvalidGeometryError(f"curve: expected a 3-D BSplineCurve, got {type(curve).__name__}"
                                   + (f" of dimension {curve.dim}" if isinstance(curve, BSplineCurve) else ""))
    s = np.asarray(params, float).ravel()
    N = np.asarray(normals, float)
    if N.ndim != 2 or N.shape != (s.shape[0], 3):
        raise InvalidGeometryError(f"normals: expected shape ({s.shape[0]}, 3) (one per parameter), got {N.shape}")
    if s.shape[0] < 8 or not (np.all(np.isfinite(s)) and np.all(np.isfinite(N))):
        raise InvalidGeometryError(f"params/normals: expected at least 8 finite samples, got {s.shape[0]}")
    lo, hi = curve.domain
    tol = 1e-9 * (hi - lo)
    if s.min() < lo - tol or s.max() > hi + tol:
        raise InvalidGeometryError(f"params: expected values in the curve's domain [{lo:.6g}, {hi:.6g}], got "
                                   f"[{s.min():.6g}, {s.max():.6g}]")
    if np.any(np.linalg.norm(N, axis=1) < 1e-12):
        raise InvalidGeometryError("normals: a normal is zero (the neighbour is degenerate there)")
    order = np.argsort(s)
    return np.clip(s[order], lo, hi), _unit(N[order])


def _lsq(knots: Array, degree: int, s: Array, Y: Array, w: Array) -> Array:
    """Weighted least squares by band accumulation (:func:`~occsurf.algorithms.kernel.banded_lstsq.spline_lstsq`:
    the dense ``lstsq`` it replaced took 0.2-0.4 s a fit for the 16 000 samples of a linkrods side)."""
    return spline_lstsq(knots, degree, s, Y, w)


def _sampled_knots(inner: Array, s: Array, lo: float, hi: float, least: int = 2) -> Array:
    """The knots of ``inner`` kept greedily from ``lo`` so that every span holds at least ``least``
    samples ``s``: the field's least squares has full rank (Schoenberg-Whitney). A side curve's
    knots can be far denser than the samples (lens face 2: 60 spans of 1/256 for 96 samples, 8
    spans empty, rank 58 of 63): ``lstsq``'s minimum-norm field then sagged between the samples,
    2.66 deg off the neighbour where it was 0.003 deg at every sample."""
    kept, last = [], lo
    for k in inner:
        if np.count_nonzero((s >= last) & (s < k)) >= least:
            kept.append(k)
            last = k
    while kept and np.count_nonzero((s >= kept[-1]) & (s <= hi)) < least:
        kept.pop()
    return np.asarray(kept, float)


def side_from_normals(curve: BSplineCurve, params: ArrayLike, normals: ArrayLike, *,
                      angle_tol: float | None = None, max_spans: int | None = None) -> SideFit:
    """A hole side from its boundary curve and the neighbour's normals at sample parameters.

    Parameters
    ----------
    curve : BSplineCurve
        The boundary (3-D, polynomial or rational), oriented along the hole's loop. Kept exactly.
    params : array_like, shape (m,)
        Parameters on ``curve`` of the samples (m >= 8, dense near the ends where the neighbour's
        plane turns fastest; their order does not matter).
    normals : array_like, shape (m, 3)
        The neighbour's normal there (any length), oriented so that ``B' x N`` points into the
        neighbour (away from the hole).
    angle_tol : float, optional
        Target angle (degrees) between the fitted tangent plane and the neighbour's; default
        ``tolerances.FILL_FIT_ANGLE``.
    max_spans : int, optional
        Most knot spans of the field; default ``tolerances.FILL_FIT_MAX_SPANS``.

    Returns
    -------
    SideFit
        The side, the achieved angle at the samples, the span count and whether ``angle_tol`` was met.

    Notes
    -----
    Weighted least squares (the two end samples weigh 1e4: the corner data of the fill come from
    the ends), cubic field (or the curve's degree if higher), simple knots (C2: the curve's, less
    those that would leave a span with fewer than two samples, :func:`_sampled_knots`); each round bisects
    every span holding a sample whose angle exceeds ``angle_tol`` while the span still holds at
    least 4 samples. For a rational curve the field is the homogeneous ``(w X, 0)``, whose Cartesian
    cross derivative is ``X``.
    """
    tol = tolerances.FILL_FIT_ANGLE if angle_tol is None else float(angle_tol)
    cap = tolerances.FILL_FIT_MAX_SPANS if max_spans is None else int(max_spans)
    s, N = _check_inputs(curve, params, normals)
    _, T = _cartesian_tangent(curve, s)
    target = np.cross(T, N)  # |B'|-scaled, across the boundary, into the neighbour
    if curve.is_rational:
        target = np.c_[target * _weights_at(curve, s)[:, None], np.zeros(s.shape[0])]
    lo, hi = curve.domain
    p = max(3, curve.degree)
    inner = _sampled_knots(np.unique(curve.knots[(curve.knots > lo) & (curve.knots < hi)]), s, lo, hi)
    w = np.ones_like(s)
    w[[0, -1]] = 1e4
    while True:
        knots = np.r_[np.full(p + 1, lo), inner, np.full(p + 1, hi)]
        coef = _lsq(knots, p, s, target, w)
        X = BSplineCurve(p, knots, coef)
        Xc = X.evaluate(s)[:, :3]
        ang = plane_angle(N, T, Xc)
        worst = float(ang.max())
        breaks = np.r_[lo, inner, hi]
        if worst <= tol or len(breaks) - 1 >= cap:
            break
        span = np.clip(np.searchsorted(breaks, s, side="right") - 1, 0, len(breaks) - 2)
        counts = np.bincount(span, minlength=len(breaks) - 1)
        bad = np.unique(span[ang > tol])
        bad = bad[counts[bad] >= 2 * (p + 1)]
        if bad.size == 0:
            break
        inner = np.unique(np.r_[inner, 0.5 * (breaks[bad] + breaks[bad + 1])])
    return SideFit(HoleSide(curve, X), worst, len(breaks) - 1, worst <= tol)


def corner_normals(t_in: ArrayLike, t_out: ArrayLike, reference: ArrayLike) -> Array:
    """The fill's normal at each hole corner: ``t_in x t_out``, signed like ``reference``.

    Parameters
    ----------
    t_in, t_out : array_like, shape (n, 3)
        Tangent of the side ending at the corner and of the side starting there.
    reference : array_like, shape (n, 3)
        A normal of the neighbours there (its sign is kept; its direction is used where the two
        tangents are parallel, a flat corner).

    Returns
    -------
    ndarray, shape (n, 3)
        Unit normals.
    """
    a, b, r = (np.atleast_2d(np.asarray(x, float)) for x in (t_in, t_out, reference))
    c = np.cross(a, b)
    flat = np.linalg.norm(c, axis=1) <= 1e-9 * np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
    c = np.where(flat[:, None], r, c)
    c = np.where((np.einsum("ij,ij->i", c, r) < 0)[:, None], -c, c)
    return _unit(c)


def smoothstep(x: ArrayLike) -> Array:
    """The C2 smoothstep ``x^3 (10 - 15 x + 6 x^2)`` of ``x`` clipped to [0, 1] (0 and 1 with vanishing
    first and second derivatives at both ends): the blend of :func:`blend_normals` and of refill's
    corner pinning (``refill_traces._pin_end``)."""
    t = np.clip(np.asarray(x, float), 0.0, 1.0)
    return t ** 3 * (10 - 15 * t + 6 * t * t)


def blend_normals(s: ArrayLike, normals: ArrayLike, start: ArrayLike, end: ArrayLike, span: float) -> Array:
    """Turn a normal field into given end normals over a fraction ``span`` of the side.

    The rotation ``R0`` taking the field's first normal ``N(0)`` into ``start`` (about
    ``N(0) x start``, by their angle ``theta0``) is applied to the field with the fraction ``b0`` of
    its angle, and likewise ``R1`` (``N(1)`` into ``end``) with ``b1``:

    .. math::

        N'(s) = R_1(b_1\\,\\theta_1)\\,R_0(b_0\\,\\theta_0)\\,N(s), \\qquad
        b_0 = h(1 - s / \\mathrm{span}), \\quad b_1 = h(1 - (1 - s) / \\mathrm{span}),

    ``h`` the C2 smoothstep clipped to [0, 1]; ``s`` on [0, 1]. The field keeps its own turning
    (a curved neighbour's normal turns along the side) and moves by at most ``theta0`` (``theta1``):
    the corner's incompatibility, nothing more. Where the field already ends in ``start``/``end``
    nothing changes.

    Parameters
    ----------
    s : array_like, shape (m,)
        Sample parameters on [0, 1], increasing (``normals[0]``/``normals[-1]`` are the ends).
    normals : array_like, shape (m, 3)
    start, end : array_like, shape (3,)
        Sign-free: taken with the sign of the field's end normal.
    span : float
        In (0, 0.5].

    Returns
    -------
    ndarray, shape (m, 3)
        Unit normals.

    Notes
    -----
    Blending the field with the constant end normal instead (``(1 - b) N(s) + b start``) moves it
    by up to its own turn over the span: 0.92 deg on the bearing's face 172 for a 0.02 deg corner.
    """
    if not 0.0 < span <= 0.5:
        raise InvalidGeometryError(f"span: expected a number in (0, 0.5], got {span!r}")
    s = np.asarray(s, float)
    N = _unit(np.asarray(normals, float))

    def turn(V: Array, a: Array, b: Array, frac: Array) -> Array:
        """Rotate the rows of ``V`` about ``a x b`` by ``frac`` of the angle from ``a`` to ``b``."""
        k = np.cross(a, b)
        sin, cos = np.linalg.norm(k), float(a @ b)
        if sin <= 1e-300:
            return V
        k, phi = k / sin, frac * np.arctan2(sin, cos)
        c, sn = np.cos(phi)[:, None], np.sin(phi)[:, None]
        return V * c + np.cross(k, V) * sn + np.outer(V @ k, k) * (1 - c)  # Rodrigues

    st, en = _unit(np.asarray(start, float)), _unit(np.asarray(end, float))
    st = np.where((N[0] @ st) < 0, -st, st)
    en = np.where((N[-1] @ en) < 0, -en, en)
    out = turn(N, N[0], st, smoothstep(1 - s / span))
    return _unit(turn(out, N[-1], en, smoothstep(1 - (1 - s) / span)))


def fit_boundary(params: ArrayLike, points: ArrayLike, tol: float, *, max_spans: int | None = None
                 ) -> tuple[BSplineCurve, float]:
    """A cubic B-spline through ordered boundary samples, refined until within ``tol``.

    Used where several edges meeting tangentially (a flat corner) become one side of the hole:
    their chain is one smooth curve geometrically but not one spline (knots of full multiplicity,
    different weights). Least squares on the given parameters (ends interpolated: weight 1e4), every
    span holding a sample farther than ``tol`` bisected while it holds at least 8 samples. The end
    poles are then set to the end samples, so the curve starts and ends exactly there.

    Parameters
    ----------
    params : array_like, shape (m,)
        Increasing parameters of the samples (e.g. arc length).
    points : array_like, shape (m, 3)
    tol : float
        Largest distance (model units) at the samples.
    max_spans : int, optional
        Default ``tolerances.FILL_FIT_MAX_SPANS``.

    Returns
    -------
    (BSplineCurve, float)
        The curve on ``[params[0], params[-1]]`` and the largest distance at the samples.
    """
    s = np.asarray(params, float).ravel()
    P = np.asarray(points, float)
    if P.shape != (s.shape[0], 3) or s.shape[0] < 8 or np.any(np.diff(s) <= 0):
        raise InvalidGeometryError(f"params/points: expected m >= 8 increasing parameters and (m, 3) points, got "
                                   f"{s.shape} and {P.shape}")
    cap = tolerances.FILL_FIT_MAX_SPANS if max_spans is None else int(max_spans)
    lo, hi, p = float(s[0]), float(s[-1]), 3
    inner = np.empty(0)
    w = np.ones_like(s)
    w[[0, -1]] = 1e4
    while True:
        knots = np.r_[np.full(p + 1, lo), inner, np.full(p + 1, hi)]
        coef = _lsq(knots, p, s, P, w)
        coef[0], coef[-1] = P[0], P[-1]  # clamped: the ends interpolated exactly (the sides must meet)
        c = BSplineCurve(p, knots, coef)
        err = np.linalg.norm(c.evaluate(s) - P, axis=1)
        breaks = np.r_[lo, inner, hi]
        if err.max() <= tol or len(breaks) - 1 >= cap:
            break
        span = np.clip(np.searchsorted(breaks, s, side="right") - 1, 0, len(breaks) - 2)
        counts = np.bincount(span, minlength=len(breaks) - 1)
        bad = np.unique(span[err > tol])
        bad = bad[counts[bad] >= 8]
        if bad.size == 0:
            break
        inner = np.unique(np.r_[inner, 0.5 * (breaks[bad] + breaks[bad + 1])])
    return c, float(err.max())


def _second_derivative_kept(curve: BSplineCurve, end: int, i1: int, i2: int, D: Array, d2: Array
                            ) -> tuple[BSplineCurve, Array]:
    """``curve`` with pole ``i1`` moved by ``D`` and pole ``i2`` by the ``E`` that keeps its second
    derivative ``d2`` at the end ``end``; returns the curve and ``E``. Poles and weights enter the
    Cartesian curve as ``sum_i R_i P_i`` with the rational basis ``R_i`` fixed by the weights, so the
    second derivative is affine in ``E`` with the scalar slope ``R_i2''``, found from one trial move."""
    at = np.array([curve.domain[end]])
    P = np.array(curve.control_points, float)
    P[i1] += D
    trial = P.copy()
    trial[i2, 0] += 1.0
    v0 = BSplineCurve(curve.degree, curve.knots, P, curve.weights).derivatives(at, 2)[0, 2]
    v1 = BSplineCurve(curve.degree, curve.knots, trial, curve.weights).derivatives(at, 2)[0, 2]
    E = (d2 - v0) / (v1[0] - v0[0])
    P[i2] += E
    return BSplineCurve(curve.degree, curve.knots, P, curve.weights), E


def turn_end_tangent(curve: BSplineCurve, end: int, normal: ArrayLike, budget: float, *,
                     min_angle: float | None = None) -> tuple[BSplineCurve, float]:
    """Turn a side's end tangent into a plane, moving the side by at most ``budget`` near that end.

    At a hole corner between a side that asks G1 to its neighbour and one that asks only G0 (a
    sharp edge of the original model), a fill regular at the corner has its tangent plane spanned
    by the two side tangents. When the G0 side's tangent ``t`` leaves the G1 neighbour's plane
    (normal ``n``) by ``beta``, the fill misses that neighbour by ``beta`` at the corner, whatever it
    does elsewhere (the screw's faces [22, 23]: 0.767 deg, the original model's own crease there).
    G0 asks position only: the tangent is turned by ``beta`` into the plane (``t`` projected on
    it) within a short end stretch, the side moving by at most ``budget`` (its G0 tolerance).

    Knots are inserted at ``e, 2e, 3e`` from the end (simple: the curve stays C^(p-1)), which
    shortens the end leg ``P1 - P0`` to about ``e |C'| / p``; ``P1`` is rotated into the plane
    about ``P0`` (so the end point stays and the new tangent is the projection of the old), and
    ``P2`` moves by the ``E`` that keeps the second derivative at the end: the twist that the
    fill's two ribbons ask at the corner (Gregory's compatibility) stays what it was (moving ``P1``
    alone bends the side with curvature ``~ beta / e`` at the corner and left a corner twist
    mismatch of 2.1 on the screw, 0.07 deg along the G1 side). Both poles act on ``[0, 3e]`` only
    and ``|C_new - C| = |R_1 D + R_2 E| <= max(|D|, |E|)`` (rational basis, non-negative and at most
    one in sum), which ``e`` is chosen to keep within ``budget``.

    Parameters
    ----------
    curve : BSplineCurve
        The side (3-D, clamped or not, polynomial or rational).
    end : {0, 1}
        The end of the domain at the corner.
    normal : array_like, shape (3,)
        Normal of the plane the end tangent must lie in (the G1 neighbour's at the corner).
    budget : float
        Largest movement of the curve (model units), > 0.
    min_angle : float, optional
        Angles (degrees) up to this are left alone; default a tenth of ``tolerances.FILL_FIT_ANGLE``.

    Returns
    -------
    (BSplineCurve, float)
        The curve (the input itself when nothing is turned; at least cubic otherwise) and the angle
        turned (degrees; 0 when nothing is).

    Raises
    ------
    InvalidGeometryError
        A curve that is not a 3-D BSplineCurve, ``end`` not 0 or 1, a zero or non-finite normal, a
        budget that is not a positive number.
    """
    if not isinstance(curve, BSplineCurve) or curve.dim != 3:
        raise InvalidGeometryError(f"curve: expected a 3-D BSplineCurve, got {type(curve).__name__}")
    if end not in (0, 1):
        raise InvalidGeometryError(f"end: expected 0 or 1, got {end!r}")
    n = np.asarray(normal, float)
    if n.shape != (3,) or not np.all(np.isfinite(n)) or np.linalg.norm(n) == 0:
        raise InvalidGeometryError(f"normal: expected a finite non-zero 3-vector, got {normal!r}")
    if not (np.isfinite(budget) and budget > 0):
        raise InvalidGeometryError(f"budget: expected a positive number, got {budget!r}")
    n = _unit(n)
    least = 0.1 * tolerances.FILL_FIT_ANGLE if min_angle is None else float(min_angle)
    c = curve.clamp()
    P = np.asarray(c.control_points)
    leg = P[1] - P[0] if end == 0 else P[-2] - P[-1]
    if np.linalg.norm(leg) == 0:
        return curve, 0.0
    d = _unit(leg)
    beta = float(np.arctan2(abs(d @ n), np.linalg.norm(d - (d @ n) * n)))
    if np.degrees(beta) <= least:
        return curve, 0.0
    if c.degree < 3:
        c = c.elevate_degree(3 - c.degree)
    p, (lo, hi) = c.degree, c.domain
    at = np.array([(lo, hi)[end]])
    D2 = c.derivatives(at, 2)[0]
    inner = np.unique(c.knots[(c.knots > lo) & (c.knots < hi)])
    room = (hi - lo) if inner.size == 0 else (inner[0] - lo if end == 0 else hi - inner[-1])
    chord = 2.0 * np.sin(0.5 * beta)  # |D| = chord |P1 - P0|
    # |P1 - P0| ~ e |C'| / p and |E| ~ 3 |D| (polynomial, knots e, 2e, 3e): a first guess, then checked
    e = min(0.25 * room, p * budget / (3.0 * chord * max(float(np.linalg.norm(D2[1])), 1e-300)))
    for _ in range(60):
        if e <= 1e-9 * (hi - lo):  # within the knots' round-off of the end: leave the side as it is
            break
        steps = e * np.arange(1.0, 4.0)
        r = c.refine(lo + steps if end == 0 else hi - steps[::-1])
        Q = np.asarray(r.control_points)
        m = len(Q)
        i0, i1, i2 = (0, 1, 2) if end == 0 else (m - 1, m - 2, m - 3)
        L = Q[i1] - Q[i0]
        u = _unit(L)
        D = Q[i0] + np.linalg.norm(L) * _unit(u - (u @ n) * n) - Q[i1]
        out, E = _second_derivative_kept(r, end, i1, i2, D, D2[2])
        moved = max(float(np.linalg.norm(D)), float(np.linalg.norm(E)))
        if moved <= budget:
            return out, float(np.degrees(beta))
        e *= min(0.5, 0.9 * budget / moved)
    return curve, 0.0
